//! Bad input reaches the renderer as a clear error, never a panic or a GPU validation error.

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::scene::{Attenuation, Instance, Light, LightKind, Material, Mesh, Scene};
use manyshadows::{RenderError, RenderSettings, Renderer};

fn small() -> RenderSettings {
    RenderSettings::default()
        .with_width(64)
        .with_height(48)
        .with_visibility(true)
}

fn spot(i: usize) -> Light {
    Light {
        kind: LightKind::Spot {
            position: Vec3::new(i as f32 * 0.01, 5.0, 0.0),
            direction: Vec3::NEG_Y,
            cutoff_deg: 30.0,
            range: 10.0,
        },
        ambient: Vec3::splat(0.01),
        diffuse: Vec3::ONE,
        specular: Vec3::ONE,
        attenuation: Attenuation::for_range(10.0),
        casts_shadows: true,
        shadow_resolution: 64,
        size: 0.0,
    }
}

fn triangle_scene(p: [Vec3; 3]) -> Scene {
    let mut mesh = Mesh {
        name: "tri".into(),
        positions: p.to_vec(),
        normals: vec![Vec3::Y; 3],
        uvs: Vec::new(),
        indices: vec![0, 1, 2],
    };
    if mesh.positions.iter().all(|p| p.is_finite()) {
        mesh.compute_normals();
    }
    Scene {
        name: "tri".into(),
        meshes: vec![mesh],
        materials: vec![Material::default()],
        instances: vec![Instance::caster(0, 0, Mat4::IDENTITY)],
        lights: vec![spot(0)],
        ..Default::default()
    }
}

#[test]
fn zero_lights_render_a_dark_frame() {
    let ctx = common::context();
    let mut scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    scene.lights.clear();
    let frame = Renderer::new(&ctx, &scene, small())
        .unwrap()
        .render()
        .unwrap();
    assert_eq!(frame.visibility.unwrap().words_per_pixel, 1);
    // With no light only the sky colour and black remain: nothing is brighter than the sky.
    assert!(frame
        .rgba
        .chunks_exact(4)
        .all(|p| p[0] < 40 && p[1] < 40 && p[2] < 60));
}

/// More maps than the atlas holds is no error: the plan halves the least important lights'
/// maps first, then leaves the least important unshadowed, and says how many of each.
#[test]
fn maps_that_do_not_fit_degrade_by_importance_and_are_counted() {
    let ctx = common::context();
    let mut scene = triangle_scene([Vec3::ZERO, Vec3::X, Vec3::Z]);
    // 5000 spots in a row going away from the camera: the nearest matter most.
    scene.lights = (0..5000).map(spot).collect();
    scene.camera.position = Vec3::new(-5.0, 5.0, 0.0);
    scene.camera.target = Vec3::new(10.0, 0.0, 0.0);
    let settings = small().with_max_atlas_size(Some(512));
    let mut renderer = Renderer::new(&ctx, &scene, settings).expect("5000 lights plan");
    let plan = renderer.plan();
    let fit = plan.fit;
    assert_eq!(
        fit.full + fit.reduced + fit.unshadowed + fit.off_screen,
        5000,
        "{fit:?}"
    );
    assert!(fit.unshadowed > 0 && fit.reduced > 0, "{fit:?}");
    // 512² texels hold at most 1024 tiles of the 16-texel floor.
    assert!(plan.views.len() <= 1024);
    // Importance order: the lights that kept shadows are nearer the camera than the rest.
    let shadowed: Vec<usize> = (0..5000).filter(|&l| plan.light_views[l].1 > 0).collect();
    let last_shadowed = *shadowed.iter().max().unwrap();
    assert_eq!(
        shadowed.len(),
        last_shadowed + 1,
        "a nearer light went unshadowed"
    );
    let tile = |l: usize| plan.layout.tiles[plan.light_views[l].0 as usize].size;
    assert!(tile(0) >= tile(last_shadowed));
    let frame = renderer.render().expect("frame");
    assert_eq!(frame.visibility.unwrap().lights, 5000);
}

#[test]
fn thousands_of_lights_render() {
    let ctx = common::context();
    let mut scene = triangle_scene([
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(0.0, 0.0, 1.0),
    ]);
    scene.lights = (0..1000).map(spot).collect();
    let frame = Renderer::new(&ctx, &scene, small())
        .unwrap()
        .render()
        .unwrap();
    let vis = frame.visibility.unwrap();
    assert_eq!((vis.lights, vis.words_per_pixel), (1000, 32));
}

#[test]
fn resolution_over_the_adapter_limit_is_refused() {
    let ctx = common::context();
    let scene = triangle_scene([Vec3::ZERO, Vec3::X, Vec3::Z]);
    let max = ctx.limits().max_texture_dimension_2d;
    for (w, h) in [(max + 1, 16), (16, max + 1)] {
        let err = Renderer::new(&ctx, &scene, RenderSettings::new(w, h)).err();
        assert!(
            matches!(err, Some(RenderError::ResolutionTooLarge { max: m, .. }) if m == max),
            "{w}x{h}: {err:?}"
        );
    }
    // A zero side is out of every device's range: the settings' own check names it.
    for (w, h, option) in [(0, 16, "width"), (16, 0, "height")] {
        let err = Renderer::new(&ctx, &scene, RenderSettings::new(w, h)).err();
        assert!(
            matches!(&err, Some(RenderError::InvalidOption { option: o, .. }) if *o == option),
            "{w}x{h}: {err:?}"
        );
    }
}

#[test]
fn nan_vertices_are_refused() {
    let ctx = common::context();
    let scene = triangle_scene([Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, Vec3::Z]);
    let err = Renderer::new(&ctx, &scene, small())
        .err()
        .expect("NaN accepted");
    assert!(err.to_string().contains("non-finite"), "{err}");
}

#[test]
fn degenerate_triangles_render() {
    // A zero-area caster (three points on a line) between a spot light and its floor covers
    // no pixel and casts no shadow: with every technique the device runs, the frame and its
    // visibility equal the frame without it, and the floor is lit.
    let ctx = common::context();
    let plain = builtin::build("plane-spot", &BuiltinOptions::default()).unwrap();
    let mut with_line = plain.clone();
    let (lo, hi) = plain.world_bounds(false).expect("the plane");
    let mid = (lo + hi) * 0.5 + Vec3::Y * 0.5;
    with_line.meshes.push(Mesh {
        name: "line".into(),
        positions: vec![mid - Vec3::X, mid, mid + Vec3::X],
        normals: vec![Vec3::Y; 3],
        uvs: Vec::new(),
        indices: vec![0, 1, 2],
    });
    with_line.instances.push(Instance::caster(
        with_line.meshes.len() - 1,
        0,
        Mat4::IDENTITY,
    ));
    let mut ran = 0;
    for technique in manyshadows::Technique::all() {
        let settings = small().with_technique(technique);
        let frame = |scene: &Scene| {
            common::renderer_or_refusal(&ctx, scene, settings.clone())
                .map(|mut r| r.render().unwrap())
        };
        let (Some(a), Some(b)) = (frame(&plain), frame(&with_line)) else {
            continue;
        };
        assert!(
            a.rgba.chunks_exact(4).any(|p| p[0] > 60),
            "{technique}: the spot lights the floor"
        );
        assert!(
            a.rgba == b.rgba,
            "{technique}: the degenerate caster changed the image"
        );
        assert_eq!(
            a.visibility, b.visibility,
            "{technique}: it changed the mask"
        );
        ran += 1;
    }
    assert!(ran >= 5, "only {ran} techniques ran");
}

#[test]
fn full_atlas_in_strict_mode_is_a_clear_error_and_shrinks_otherwise() {
    let ctx = common::context();
    let mut scene = triangle_scene([Vec3::ZERO, Vec3::X, Vec3::Z]);
    scene.lights = (0..8)
        .map(|i| Light {
            shadow_resolution: 2048,
            ..spot(i)
        })
        .collect();
    let strict = small()
        .with_max_atlas_size(Some(2048))
        .with_fit(FitPolicy::Strict);
    let err = Renderer::new(&ctx, &scene, strict)
        .err()
        .expect("8 maps of 2048² in a 2048² atlas");
    assert!(matches!(err, RenderError::Atlas(_)), "{err}");
    let shrink = small()
        .with_max_atlas_size(Some(2048))
        .with_fit(FitPolicy::Shrink);
    let r = Renderer::new(&ctx, &scene, shrink).unwrap();
    assert!(r.plan().layout.shrink_steps >= 1);
    assert_eq!(r.plan().layout.size, 2048);
    // The default gives no light a smaller map than shrinking all would, and fills the atlas
    // at least as well.
    let shrunk: Vec<u32> = r.plan().layout.tiles.iter().map(|t| t.size).collect();
    let r = Renderer::new(&ctx, &scene, small().with_max_atlas_size(Some(2048))).unwrap();
    let fit = r.plan().fit;
    assert_eq!((fit.full + fit.reduced, fit.unshadowed), (8, 0), "{fit:?}");
    let tiles = &r.plan().layout.tiles;
    assert!(
        tiles.iter().zip(&shrunk).all(|(t, &s)| t.size >= s),
        "{tiles:?} vs {shrunk:?}"
    );
    let area = |t: &[u32]| t.iter().map(|&s| u64::from(s).pow(2)).sum::<u64>();
    let sizes: Vec<u32> = tiles.iter().map(|t| t.size).collect();
    assert!(area(&sizes) <= 2048 * 2048 && area(&sizes) >= area(&shrunk));
}

/// The virtual maps' level of detail and bias scale are checked before any GPU work: NaN,
/// infinite, zero or negative texels per pixel, and bias scales outside 0..=16, are refused
/// naming the field (a NaN scale would turn every lookup's position into NaN).
#[test]
fn virtual_options_out_of_range_are_refused() {
    let ctx = common::context();
    let scene = triangle_scene([Vec3::ZERO, Vec3::X, Vec3::Z]);
    let with = |o: manyshadows::VirtualOptions| {
        small()
            .with_technique(manyshadows::Technique::VIRTUAL)
            .with_virtual_maps(o)
    };
    let d = manyshadows::VirtualOptions::default;
    let cases = [
        (d().with_lod(f32::NAN), "virtual_maps.lod"),
        (d().with_lod(0.0), "virtual_maps.lod"),
        (d().with_lod(f32::INFINITY), "virtual_maps.lod"),
        (d().with_directed_lod(f32::NAN), "virtual_maps.directed_lod"),
        (d().with_directed_lod(-1.0), "virtual_maps.directed_lod"),
        (d().with_bias_scale(f32::NAN), "virtual_maps.bias_scale"),
        (d().with_bias_scale(-0.5), "virtual_maps.bias_scale"),
        (d().with_bias_scale(17.0), "virtual_maps.bias_scale"),
    ];
    for (o, option) in cases {
        let err = Renderer::new(&ctx, &scene, with(o)).err();
        assert!(
            matches!(&err, Some(RenderError::InvalidOption { option: f, .. }) if *f == option),
            "{o:?}: {err:?}"
        );
    }
    for scale in [0.0, 0.5, 16.0] {
        let mut r = Renderer::new(&ctx, &scene, with(d().with_bias_scale(scale)))
            .unwrap_or_else(|e| panic!("bias scale {scale}: {e}"));
        r.render().expect("frame");
    }
}
