//! The frame estimate's own count, checked against the frame: the (pixel, light) pairs in reach
//! it finds from a coarse grid of camera rays against instance boxes, before anything is drawn,
//! must be close to the pairs counted exactly from the G-buffer the frame then draws (every
//! pixel's world position against every light's bounding sphere; directional lights reach
//! everything). The other units (pixels, triangles, the plan's (triangle, view) pairs and atlas
//! texels) are counted exactly; the milliseconds they are priced at are measured by
//! `manyshadows bench estimate`, not here (timings are never asserted in tests).

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::LightKind;
use manyshadows::{RenderSettings, Renderer};

/// Pairs counted exactly from the G-buffer of the frame the renderer draws.
fn exact_pairs(r: &mut Renderer) -> u64 {
    r.render().expect("frame");
    let g = r.read_gbuffer().expect("G-buffer");
    let spheres: Vec<Option<(glam::Vec3, f32)>> = r
        .scene()
        .lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Directional { .. } => None,
            _ => l.bounding_sphere(),
        })
        .collect();
    let mut n = 0u64;
    for (p, covered) in g.position.iter().zip(&g.covered) {
        if !covered {
            continue;
        }
        n += spheres
            .iter()
            .filter(|s| s.is_none_or(|(c, rad)| (*p - c).length_squared() <= rad * rad))
            .count() as u64;
    }
    n
}

#[test]
fn estimated_pixel_light_pairs_are_close_to_the_frames_own() {
    let ctx = common::context();
    let mut worst: f64 = 1.0;
    for name in ["atrium", "courtyard", "terrain", "dragon"] {
        for lights in [8, 256] {
            let scene = builtin::build(
                name,
                &BuiltinOptions {
                    lights: Some(lights),
                    seed: 1,
                    mix: LightMix::All,
                    shadow_resolution: Some(64),
                    ..Default::default()
                },
            )
            .expect("builtin scene");
            let settings = RenderSettings::default().with_width(160).with_height(90);
            let mut r = Renderer::new(&ctx, &scene, settings).expect("renderer");
            let estimated = r.estimated_work().pixel_lights;
            let exact = exact_pairs(&mut r);
            let ratio = estimated as f64 / exact.max(1) as f64;
            eprintln!(
                "{name}, {lights} lights: estimated {estimated}, exact {exact}, ratio {ratio:.3}"
            );
            worst = worst.max(ratio.max(1.0 / ratio));
        }
    }
    eprintln!("furthest from the exact count: {worst:.3}x");
    assert!(
        worst <= 1.05,
        "the estimate's (pixel, light) pairs are {worst:.2}x off the frame's (bound 1.05x)"
    );
}

/// The units the frame's stages are priced by follow the settings: rays only for ray-traced
/// shadows (one per (pixel, light) pair in reach, or K per pixel when sampled), taps only
/// where a sized light is filtered, atlas texels only for atlas techniques.
#[test]
fn the_estimate_counts_what_the_technique_does() {
    let ctx = common::context();
    let scene = common::cubes_under_48_lights();
    let work = |s: RenderSettings| {
        Renderer::new(&ctx, &scene, s.with_width(64).with_height(36))
            .expect("renderer")
            .estimate_frame()
    };
    // The estimate counts the views' pairs itself, as `shadow_work` does, for every technique
    // with per-view work.
    for t in manyshadows::Technique::all() {
        let r = match Renderer::new(
            &ctx,
            &scene,
            RenderSettings::default()
                .with_technique(t)
                .with_width(64)
                .with_height(36),
        ) {
            Ok(r) => r,
            Err(e) => {
                common::check_refusal(&ctx, t, &e);
                continue;
            }
        };
        let e = r.estimate_frame().work;
        if let (Some(w), manyshadows::Fills::Atlas | manyshadows::Fills::Mask) =
            (r.shadow_work(), t.info().fills)
        {
            assert_eq!(
                (
                    e.triangle_views,
                    e.after_instance_culling,
                    e.all_pairs,
                    e.views
                ),
                (
                    w.triangle_views,
                    w.after_instance_culling,
                    w.all_pairs,
                    w.views
                ),
                "{t}"
            );
        }
    }
    let atlas = work(RenderSettings::default());
    assert_eq!(atlas.work.pixels, 64 * 36);
    assert_eq!(atlas.work.rays, 0);
    assert!(atlas.work.atlas_texels > 0 && atlas.work.triangle_views > 0);
    assert!(atlas.total_ms() > 0.0 && atlas.shadows_ms > 0.0);
    let virt = work(RenderSettings::default().with_technique(manyshadows::Technique::VIRTUAL));
    assert_eq!(virt.work.atlas_texels, 0);
    let rays = |s: RenderSettings| {
        common::raytraced(&ctx, &scene, s.with_width(64).with_height(36))
            .map(|r| r.estimate_frame())
    };
    let mut one_point = RenderSettings::default();
    one_point.rays.area_samples = 1;
    if let Some(every) = rays(one_point) {
        assert_eq!(every.work.rays, every.work.pixel_lights);
        assert_eq!(every.work.atlas_texels, 0);
        // The cubes' lights are sized: a 3x3 grid over each light's shape.
        let mut s = RenderSettings::default();
        s.rays.area_samples = 3;
        assert!(scene.lights.iter().all(|l| l.size > 0.0));
        assert_eq!(rays(s).expect("same device").work.rays, 9 * every.work.rays);
        let mut s = RenderSettings::default();
        s.rays.light_samples = 2;
        let sampled = rays(s).expect("same device");
        assert_eq!(sampled.work.rays, 2 * 64 * 36);
    }
}
