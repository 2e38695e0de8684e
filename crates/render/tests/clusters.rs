//! Clustered shading must change the cost of a frame, never its picture: the clustered light
//! loop visits a pixel's lights in the same ascending order as the loop over every light, so
//! the shaded image and the visibility mask must be identical, byte for byte. A pool too small
//! for the occupied clusters must be reported and still give the same image (those clusters
//! fall back to every light).

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::Scene;
use manyshadows::{ClusterOptions, LightLoop};
use manyshadows::{Frame, GpuContext, RenderSettings, Renderer};

fn scene(name: &str, lights: usize) -> Scene {
    builtin::build(
        name,
        &BuiltinOptions {
            lights: Some(lights),
            seed: 3,
            mix: LightMix::All,
            shadow_resolution: Some(128),
            ..Default::default()
        },
    )
    .expect("builtin scene")
}

fn render(ctx: &GpuContext, scene: &Scene, light_loop: LightLoop, pool: Option<u64>) -> Frame {
    let settings = RenderSettings::default()
        .with_width(320)
        .with_height(180)
        .with_visibility(true)
        .with_light_loop(light_loop)
        .with_clusters(ClusterOptions::default().with_pool_bytes(pool));
    Renderer::new(ctx, scene, settings)
        .expect("renderer")
        .render()
        .expect("frame")
}

fn assert_same(name: &str, a: &Frame, b: &Frame) {
    let differing =
        common::differing_pixels(a, b, &format!("clusters_{name}"), ["clustered", "all"]);
    assert_eq!(
        differing, 0,
        "{name}: {differing} pixels differ (images in target/test-artifacts)"
    );
    let (va, vb) = (
        a.visibility.as_ref().unwrap(),
        b.visibility.as_ref().unwrap(),
    );
    assert!(va.words == vb.words, "{name}: the visibility masks differ");
}

#[test]
fn clustered_image_equals_the_loop_over_every_light() {
    let ctx = common::context();
    for (name, n) in [("atrium", 300), ("dragon", 200)] {
        let scene = scene(name, n);
        let clustered = render(&ctx, &scene, LightLoop::Clustered, None);
        let all = render(&ctx, &scene, LightLoop::All, None);
        assert!(all.clusters.is_none());
        let stats = clustered.clusters.expect("cluster stats");
        eprintln!("{name}, {n} lights: {stats:?}");
        assert_eq!(stats.overflowed, 0);
        // The default tile at this size (every cluster of the 16-pixel grid has a slot).
        assert_eq!(stats.tile, 16);
        assert_eq!(stats.tiles, [20, 12]);
        assert!(stats.occupied > 0 && stats.lights_in_view > 0);
        // The point of clustering: a cluster sees a small part of the lights.
        assert!(
            stats.mean_lights < 0.25 * n as f64,
            "{name}: {:.1} lights per cluster of {n}",
            stats.mean_lights
        );
        assert!(stats.max_lights as usize <= n);
        // Some pixels must be lit by some light, or the comparison proves nothing.
        assert!(clustered.rgba.chunks(4).any(|p| p[0] > 60));
        assert_same(name, &clustered, &all);
    }
}

#[test]
fn overflowing_the_list_pool_is_reported_and_changes_nothing() {
    let ctx = common::context();
    let scene = scene("atrium", 300);
    // Room for very few slots: most occupied clusters overflow.
    let tight = render(&ctx, &scene, LightLoop::Clustered, Some(256));
    let stats = tight.clusters.expect("cluster stats");
    assert!(stats.capacity < stats.occupied, "{stats:?}");
    assert_eq!(
        stats.overflowed,
        stats.occupied - stats.capacity,
        "{stats:?}"
    );
    let all = render(&ctx, &scene, LightLoop::All, None);
    assert_same("overflow", &tight, &all);
}

/// The most lights a layout makes render without error: clustered lists, and shadows for as
/// many lights as a deliberately small atlas holds (the rest reported, none silently lost).
#[test]
fn sixteen_thousand_lights_render() {
    let ctx = common::context();
    let n = builtin::MAX_LIGHTS;
    let scene = builtin::build(
        "cubes",
        &BuiltinOptions {
            lights: Some(n),
            seed: 1,
            mix: LightMix::All,
            ..Default::default()
        },
    )
    .expect("builtin scene");
    assert_eq!(scene.lights.len(), 16384);
    let settings = RenderSettings::default()
        .with_width(96)
        .with_height(54)
        .with_max_atlas_size(Some(1024));
    let mut renderer = Renderer::new(&ctx, &scene, settings).expect("renderer");
    let fit = renderer.plan().fit;
    let shadowed = scene.lights.iter().filter(|l| l.casts_shadows).count();
    assert_eq!(
        fit.full + fit.reduced + fit.unshadowed + fit.off_screen,
        shadowed,
        "{fit:?}"
    );
    assert!(
        fit.unshadowed > 0,
        "a 1024² atlas cannot hold {n} lights' maps: {fit:?}"
    );
    let frame = renderer.render().expect("frame");
    let stats = frame.clusters.expect("cluster stats");
    eprintln!("{n} lights: {fit:?}, {stats:?}");
    assert!(
        stats.lights_in_view > 0 && stats.mean_lights < n as f64 / 8.0,
        "{stats:?}"
    );
    assert!(frame.rgba.chunks(4).any(|p| p[0] > 40), "the frame is dark");
}
