//! Ray-traced shadows (`Technique::RAYTRACED`) on the adapter `WGPU_BACKEND` selects. Where the
//! adapter has ray queries (lavapipe from Mesa 25) every test checks the frames; where it has
//! none (OpenGL, older Mesa) each test checks that the technique is refused naming the
//! feature, and nothing else (a device without ray queries cannot trace), except the sampled
//! lights' test, which there takes its visibility from shadow maps (`common::sampler`).

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::{LightLoop, Pcf, RayOptions, RenderSettings};

const SIZE: u32 = 256;
const EDGE_BAND_PX: i32 = 2;

/// The three analytic scenes: nothing but the outline's band may disagree with the exact
/// shadow the test computes itself, and inside the band only sub-pixel placement (measured:
/// 0 outside the band on lavapipe).
#[test]
fn shadows_match_exact_outlines() {
    let ctx = common::context();
    for name in ["plane-spot", "plane-point", "plane-directional"] {
        let scene = builtin::build(name, &BuiltinOptions::default()).expect("scene");
        let settings = RenderSettings::new(SIZE, SIZE)
            .with_pcf(Pcf::Off)
            .with_visibility(true);
        let Some(mut r) = common::raytraced(&ctx, &scene, settings) else {
            return;
        };
        let frame = r.render().expect("frame");
        let vis = frame.visibility.as_ref().expect("mask");
        let truth = common::analytic_truth(&scene, SIZE);
        let path = common::artifacts_dir().join(format!("raytraced-{name}.png"));
        let agreement = common::agree_with_truth(vis, &truth, SIZE, EDGE_BAND_PX, &path);
        eprintln!(
            "{name}: {} of {} pixels away from edges disagree",
            agreement.wrong, agreement.compared
        );
        assert_eq!(agreement.wrong, 0, "{name}: see {}", path.display());
        assert!(
            agreement.compared > 40_000,
            "{name}: too few pixels compared"
        );
    }
}

/// The atrium with 64 lights of every type: the mask against the exact CPU reference from the
/// same G-buffer points. Bound: 0.01 % of the pairs outside the edge band (the bar;
/// measured 0), and inside it only what the two triangle tests' rounding can place
/// differently.
#[test]
fn the_atrium_agrees_with_the_cpu_reference() {
    let ctx = common::context();
    let mut scene = builtin::build(
        "atrium",
        &BuiltinOptions {
            lights: Some(64),
            ..Default::default()
        },
    )
    .expect("scene");
    scene.lights = builtin::scatter_lights(&scene, 64, 7, LightMix::All, None);
    let settings = RenderSettings::new(320, 180).with_visibility(true);
    let Some(mut r) = common::raytraced(&ctx, &scene, settings) else {
        return;
    };
    let frame = r.render().expect("frame");
    let vis = frame.visibility.as_ref().expect("mask");
    let e = common::reference_errors(&r, &scene, vis, 2);
    eprintln!("{e:?}");
    assert!(e.lit > 10_000, "too few lit pairs to judge: {e:?}");
    assert!(
        (e.wrong as f64) <= 1e-4 * e.pairs as f64,
        "{} of {} pairs wrong outside the band",
        e.wrong,
        e.pairs
    );
    assert!(
        (e.wrong_in_band as f64) <= 1e-4 * e.pairs as f64,
        "{} of {} pairs wrong in the band",
        e.wrong_in_band,
        e.pairs
    );
}

/// A moved caster and a moved light change the frame exactly as a renderer built on the new
/// state renders it (the TLAS is rebuilt; nothing stale is traced).
#[test]
fn moved_caster_and_light_equal_a_fresh_renderer() {
    let ctx = common::context();
    let scene = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    let settings = RenderSettings::new(160, 120).with_visibility(true);
    let Some(mut r) = common::raytraced(&ctx, &scene, settings.clone()) else {
        return;
    };
    let before = r.render().expect("frame");
    let k = scene.smallest_caster().expect("a caster");
    let mut moved = scene.clone();
    moved.instances[k].transform =
        Mat4::from_translation(Vec3::new(0.5, 0.0, -0.3)) * scene.instances[k].transform;
    let mut light = scene.lights[0];
    match &mut light.kind {
        manyshadows::scene::LightKind::Spot { position, .. }
        | manyshadows::scene::LightKind::Point { position, .. } => {
            *position += Vec3::new(0.4, 0.2, 0.0)
        }
        manyshadows::scene::LightKind::Directional { direction, .. } => {
            *direction = (*direction + Vec3::new(0.1, 0.0, 0.05)).normalize()
        }
    }
    moved.lights[0] = light;
    r.set_instance_transform(k, moved.instances[k].transform)
        .unwrap();
    r.set_light(0, light).unwrap();
    let after = r.render().expect("frame");
    let fresh = common::raytraced(&ctx, &moved, settings)
        .expect("same device")
        .render()
        .expect("frame");
    let changed = common::differing_pixels(&before, &after, "raytraced-move", ["before", "after"]);
    assert!(changed > 100, "the move changed only {changed} pixels");
    assert_eq!(
        common::differing_pixels(&after, &fresh, "raytraced-fresh", ["moved", "fresh"]),
        0
    );
    assert_eq!(after.visibility, fresh.visibility);
}

/// Sampled lights: the error against the all-lights image shrinks as K grows (1, 4, 16), the
/// average of several seeds is closer than one (no bias that averaging cannot remove), and
/// 16,384 lights render.
#[test]
fn sampled_lights_converge_to_every_light() {
    let ctx = common::context();
    let mut scene = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    scene.lights = builtin::scatter_lights(&scene, 48, 3, LightMix::All, None);
    // Every light is a candidate of every pixel (48 > 16 samples), so each K samples.
    let base = RenderSettings::new(128, 96).with_light_loop(LightLoop::All);
    let mut exact = common::sampler(&ctx, &scene, base.clone());
    let exact = exact.render().expect("frame");
    let sampled = |k: u32, seed: u32| {
        common::sampler(
            &ctx,
            &scene,
            base.clone()
                .with_rays(RayOptions::default().with_light_samples(k).with_seed(seed)),
        )
        .render()
        .expect("frame")
    };
    let errors: Vec<f64> = [1, 4, 16]
        .iter()
        .map(|&k| common::rmse(&sampled(k, 1), &exact))
        .collect();
    eprintln!("RMSE against every light, K = 1, 4, 16: {errors:?}");
    assert!(
        errors[0] > errors[1] && errors[1] > errors[2] && errors[2] > 0.0,
        "{errors:?}"
    );
    // Eight seeds of K = 4 averaged: unbiased noise averages away.
    let frames: Vec<_> = (0..8).map(|s| sampled(4, s)).collect();
    let mut mean = frames[0].clone();
    for (i, v) in mean.rgba.iter_mut().enumerate() {
        let sum: u32 = frames.iter().map(|f| u32::from(f.rgba[i])).sum();
        *v = ((sum as f64) / 8.0).round() as u8;
    }
    let averaged = common::rmse(&mean, &exact);
    eprintln!(
        "K = 4: one seed {:.2}, eight seeds averaged {averaged:.2}",
        errors[1]
    );
    assert!(averaged < 0.6 * errors[1], "{averaged} vs {}", errors[1]);

    // 16,384 lights, 4 samples per pixel.
    let mut many = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    many.lights = builtin::scatter_lights(&many, 16_384, 1, LightMix::All, None);
    let frame = common::sampler(
        &ctx,
        &many,
        RenderSettings::new(64, 48).with_rays(RayOptions::default().with_light_samples(4)),
    )
    .render()
    .expect("16,384 lights render");
    assert!(frame.rgba.chunks(4).any(|p| p[0] > 20), "a lit pixel");
}
