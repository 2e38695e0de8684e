//! Bad input reaches the renderer as a clear error, never a panic or a GPU validation error.

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::scene::{Attenuation, Instance, Light, LightKind, Material, Mesh, Scene};
use manyshadows::{RenderError, RenderSettings, Renderer};

fn small() -> RenderSettings {
    RenderSettings {
        width: 64,
        height: 48,
        visibility: true,
        ..Default::default()
    }
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
    }
}

fn triangle_scene(p: [Vec3; 3]) -> Scene {
    let mut mesh = Mesh {
        name: "tri".into(),
        positions: p.to_vec(),
        normals: vec![Vec3::Y; 3],
        indices: vec![0, 1, 2],
    };
    if mesh.positions.iter().all(|p| p.is_finite()) {
        mesh.compute_normals();
    }
    Scene {
        name: "tri".into(),
        meshes: vec![mesh],
        materials: vec![Material::default()],
        instances: vec![Instance {
            mesh: 0,
            material: 0,
            transform: Mat4::IDENTITY,
            casts_shadows: true,
        }],
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

#[test]
fn too_many_shadow_views_is_a_clear_error() {
    let ctx = common::context();
    let mut scene = triangle_scene([Vec3::ZERO, Vec3::X, Vec3::Z]);
    scene.lights = (0..5000).map(spot).collect();
    match Renderer::new(&ctx, &scene, small()) {
        Err(e @ RenderError::TooManyShadowViews { .. }) => assert!(e.to_string().contains("5000")),
        Err(e) => panic!("wrong error: {e}"),
        Ok(_) => panic!("5000 shadow views accepted"),
    }
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
    for (w, h) in [(max + 1, 16), (16, max + 1), (0, 16)] {
        let err = Renderer::new(
            &ctx,
            &scene,
            RenderSettings {
                width: w,
                height: h,
                ..Default::default()
            },
        )
        .err();
        assert!(
            matches!(err, Some(RenderError::ResolutionTooLarge { .. })),
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
    let ctx = common::context();
    let scene = triangle_scene([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]);
    Renderer::new(&ctx, &scene, small())
        .unwrap()
        .render()
        .unwrap();
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
    let strict = RenderSettings {
        max_atlas_size: Some(2048),
        fit: FitPolicy::Strict,
        ..small()
    };
    let err = Renderer::new(&ctx, &scene, strict)
        .err()
        .expect("8 maps of 2048² in a 2048² atlas");
    assert!(matches!(err, RenderError::Atlas(_)), "{err}");
    let shrink = RenderSettings {
        max_atlas_size: Some(2048),
        ..small()
    };
    let r = Renderer::new(&ctx, &scene, shrink).unwrap();
    assert!(r.plan().layout.shrink_steps >= 1);
    assert_eq!(r.plan().layout.size, 2048);
}
