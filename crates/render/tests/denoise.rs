//! The denoiser of sampled lights (`RayOptions::denoise`): against the exact image (every
//! cluster light), one light sampled per pixel denoised must be far closer than one sampled
//! plainly, and come closer frame after frame on a still camera. The sampled lights' visibility
//! is traced where the adapter has ray queries and read from shadow maps where it has none
//! (OpenGL: `common::sampler`); accumulating area samples of every light needs shadow rays, and
//! options that cannot be denoised are refused everywhere.

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::{RayOptions, RenderError, RenderSettings, Renderer, Technique};

/// The cubes under 48 lights, 160 × 120: plain K = 1 against denoised K = 1 over eight still frames.
#[test]
fn denoised_samples_are_close_to_every_light_and_converge() {
    let ctx = common::context();
    let scene = common::cubes_under_48_lights();
    let base = RenderSettings::new(160, 120);
    let mut exact = common::sampler(&ctx, &scene, base.clone());
    let exact = exact.render().expect("frame");
    let one = RayOptions::default().with_light_samples(1);
    let plain = common::sampler(&ctx, &scene, base.clone().with_rays(one))
        .render()
        .expect("frame");
    let plain = common::rmse(&plain, &exact);
    let mut denoised = common::sampler(&ctx, &scene, base.with_rays(one.with_denoise(true)));
    let errors: Vec<f64> = (0..8)
        .map(|_| common::rmse(&denoised.render().expect("frame"), &exact))
        .collect();
    eprintln!(
        "RMSE against every light: K = 1 plain {plain:.2}; denoised, frames 1 to 8: {errors:.2?}"
    );
    let artifacts = common::artifacts_dir();
    let last = denoised.render().expect("frame");
    image::RgbaImage::from_raw(160, 120, last.rgba.clone())
        .expect("frame size")
        .save(artifacts.join("denoise-cubes-9-frames.png"))
        .expect("write");
    assert!(
        errors[0] < 0.5 * plain,
        "the first denoised frame is not much closer than plain sampling: {} vs {plain}",
        errors[0]
    );
    // Stratified light samples converge about as 1 / frames, and the filter narrows with
    // them (lavapipe: 3.00 on the first frame, 1.09 on the eighth, 0.36x; with independent
    // samples and the filter narrowing as 1 / sqrt(frames), as before: 2.98 and 1.96, 0.66x).
    assert!(
        errors[7] < 0.5 * errors[0],
        "eight still frames do not converge: {errors:?}"
    );
    assert!(errors[7] < 0.3 * plain, "{} vs {plain}", errors[7]);
    // Pixels with a settled history skip the wide à-trous passes (denoise.rs SETTLED_FRAMES;
    // lavapipe: the eighth frame 0.98, 0.070x plain, since the samples' van der Corput points
    // start in fifths (0.88, 0.063x, before: docs/bench/denoise-order-lavapipe.txt); with
    // every pass 1.47, 0.105x, which fails this (seen failing); before the points changed, every pass read 1.45,
    // 0.10x, and with the ratio's earlier Laplacian weight 1.06, 0.076x).
    assert!(
        errors[7] < 0.08 * plain,
        "the eighth still frame keeps the wide passes' blur: {} vs plain {plain}",
        errors[7]
    );
}

/// Every light traced, one area sample per sized light and pixel: still frames accumulate
/// (new points on the lights each frame, no spatial filter) towards the image traced with 64
/// samples per light, and without bias: 16 frames must more than halve the first frame's
/// error (one sample per frame averages to 1/4 of it, down to the 64-sample image's own
/// noise), where the same frame without accumulation does not improve at all.
#[test]
fn every_light_traced_accumulates_area_samples_over_still_frames() {
    let ctx = common::context();
    let mut scene = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    scene.lights = builtin::scatter_lights(&scene, 8, 5, LightMix::All, None);
    // Wide penumbrae: four times the default radii (suns keep theirs).
    for l in &mut scene.lights {
        if l.type_name() != "directional" {
            l.size *= 4.0;
        }
    }
    assert!(scene.lights.iter().all(|l| l.size > 0.0));
    let base = RenderSettings::new(160, 120);
    let rays = |area: u32| RayOptions::default().with_area_samples(area);
    let Some(mut exact) = common::raytraced(&ctx, &scene, base.clone().with_rays(rays(8))) else {
        return;
    };
    let exact = exact.render().expect("frame");
    let mut plain =
        common::raytraced(&ctx, &scene, base.clone().with_rays(rays(1))).expect("same device");
    let plain: Vec<f64> = (0..2)
        .map(|_| common::rmse(&plain.render().expect("frame"), &exact))
        .collect();
    let mut acc = common::raytraced(&ctx, &scene, base.with_rays(rays(1).with_denoise(true)))
        .expect("same device");
    let errors: Vec<f64> = (0..16)
        .map(|_| common::rmse(&acc.render().expect("frame"), &exact))
        .collect();
    eprintln!(
        "RMSE against 64 area samples: one sample, two frames without accumulating {plain:.2?}; \
         accumulated, frames 1 to 16: {errors:.2?}"
    );
    assert!(
        plain[0] > 1.0,
        "the penumbrae are too small to test: {plain:?}"
    );
    assert!(
        (errors[0] - plain[0]).abs() < 0.25 * plain[0],
        "the first accumulated frame is not the plain frame: {} vs {}",
        errors[0],
        plain[0]
    );
    assert!(
        (plain[1] - plain[0]).abs() < 0.1 * plain[0],
        "frames without accumulation should not converge: {plain:?}"
    );
    assert!(
        errors[15] < 0.5 * errors[0],
        "16 still frames do not converge: {errors:?}"
    );
}

/// Denoising asks for sampled lights, and accumulating every light's area samples for shadow
/// rays: a shadow-map technique without sampled lights, or irregular maps, are refused naming
/// the option, on any device.
#[test]
fn denoising_without_shadow_rays_is_refused_by_name() {
    let scene = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    common::refused_naming(
        &scene,
        &[
            RenderSettings::new(32, 32)
                .with_technique(Technique::default())
                .with_rays(RayOptions::default().with_denoise(true)),
            // Irregular maps answer every light in one mask: nothing to sample or denoise.
            RenderSettings::new(32, 32)
                .with_technique(Technique::IRREGULAR)
                .with_rays(RayOptions::default().with_denoise(true)),
        ],
        "rays.denoise",
    );
}

/// A sun switched off: its light leaves the frame at once (the unshadowed light is exact
/// every frame) and the shadow ratio's history is corrected for it in the frame of the switch
/// (denoise.rs: the sun's unshadowed light and its visibility, traced once, taken out of the
/// history's means; the history's frame count cut to its samples of the lights that stay,
/// and that frame drawing the lost share of a full history's samples again,
/// lighting.wgsl `catch_up_samples`). Measured (cubes, 48 lights, lavapipe): the exact image
/// changes by 17.0; the denoised error after the switch 0.830, 0.817, 0.801, 0.787, where a
/// denoiser started without the sun is at 1.375 after four frames and 0.787 after 16 (1.05x,
/// 1.04x, 1.02x, 1.00x; issue 39 asks 1.1x within four frames); without the catch-up 0.985,
/// 1.017, 0.975, 0.908 (1.25x first),
/// which fails. With the ratio's Laplacian weight before (denoise.rs `RATIO_SIGMAS`): 0.829,
/// 0.811, 0.795, 0.780 against 1.37 and 0.768; without the catch-up 0.977, 0.992, 0.956,
/// 0.898 (1.27x first), which failed. Before settled pixels skipped the wide
/// à-trous passes (denoise.rs `SETTLED_FRAMES`): 0.927, 0.901, 0.895, 0.879 against 1.90
/// and 0.869. Without the catch-up then (K
/// samples in that frame too) 1.12, 1.12, 1.08, 1.01 (1.29x ... 1.16x), which fails;
/// drawing the lost share of 16 frames again 1.02, 1.00, 0.98, 0.96 (1.18x ... 1.10x).
/// Without the correction (the fallback for more lights than `MAX_LIGHT_FIXES`, the history
/// cut by the change of each pixel's unshadowed light): 2.11, 1.95, 1.81, 1.66 (1.91x).
/// (Before the light samples were stratified over frames: 2.00, 1.86, 1.71, 1.63 against a
/// steady 1.39.)
#[test]
fn a_light_switched_off_leaves_the_frame_within_four_frames() {
    // A sun goes dark (it lights every pixel).
    let s = switch_off(|scene| vec![sun_of(scene)], 16);
    let (fresh4, steady) = (s.fresh[3], s.fresh[15]);
    eprintln!(
        "switching the sun off changes the exact image by {:.2}; denoised after the switch: \
         {:.3?}; a denoiser started without it: {fresh4:.3} after 4 frames, steady {steady:.3} \
         after 16 ({:.3}x)",
        s.moved,
        s.after,
        s.after[3] / steady
    );
    assert!(
        s.moved > 4.0 * steady,
        "the switch must matter: {} vs {steady}",
        s.moved
    );
    // Four frames after the switch the history from before it helps rather than hurts: the
    // frame is closer to the exact one than a denoiser that never saw the light, four frames
    // in (lavapipe: 0.879 against 1.90), and every frame after the switch is within 10 % of
    // the steady error after 16 frames (lavapipe: at most 1.07x). Without the catch-up the
    // first frame after is 1.29x; without the correction 1.91x four frames after.
    assert!(
        s.after[3] <= fresh4,
        "four frames after the switch: {} vs {fresh4} for a denoiser started without the light",
        s.after[3]
    );
    for (k, e) in s.after.iter().enumerate() {
        assert!(
            *e <= 1.10 * steady,
            "frame {} after the switch: {e} vs a steady {steady} ({:.3}x, at most 1.10x)",
            k + 1,
            e / steady
        );
    }
}

/// More lights changed at once than the history is corrected for (`MAX_LIGHT_FIXES` records:
/// twelve lights switched off are 24): each pixel's history is cut by how much of its
/// unshadowed light the change kept (to the fourth power, dropped below one frame), and four
/// frames later the frame is no further from the exact one than a denoiser started without
/// those lights. Measured (cubes, the sun and eleven local lights off, lavapipe): 3.19, 2.99,
/// 2.65, 1.33 against 1.45; keeping at least one frame 1.48, which fails. With the ratio's
/// Laplacian weight before (denoise.rs `RATIO_SIGMAS`): 2.97, 2.73, 1.57, 1.45 against 1.47
/// with a frame kept, cubed 1.50 failed (cubed was the rule, 1.96 against 2.03, before settled
/// pixels skipped the wide à-trous passes, `SETTLED_FRAMES`); then the share to the first
/// power 2.17 and the history kept whole 2.42 failed (squared: 1.96). (Twelve local lights without the sun:
/// 1.05 against 2.23; the rule before, each frame weighing at least 0.2 for four frames,
/// 1.46.)
#[test]
fn many_lights_switched_at_once_fall_back_and_still_follow() {
    // The sun (it lights every pixel) and eleven more.
    let pick = |scene: &manyshadows::scene::Scene| {
        let sun = sun_of(scene);
        let off: Vec<usize> = std::iter::once(sun)
            .chain((0..scene.lights.len()).filter(|&i| i != sun).take(11))
            .collect();
        assert!(2 * off.len() > manyshadows::sampled::denoise::MAX_LIGHT_FIXES);
        off
    };
    let s = switch_off(pick, 4);
    eprintln!(
        "switching 12 lights off changes the exact image by {:.2}; denoised after the switch: \
         {:.2?}; a denoiser started without them: {:.2} after 4 frames",
        s.moved, s.after, s.fresh[3]
    );
    assert!(s.moved > 2.0, "the switch must matter: {}", s.moved);
    assert!(
        s.after[3] <= s.fresh[3],
        "four frames after the switch: {} vs {} for a denoiser started without the lights",
        s.after[3],
        s.fresh[3]
    );
}

/// The cubes' directional light.
fn sun_of(scene: &manyshadows::scene::Scene) -> usize {
    scene
        .lights
        .iter()
        .position(|l| l.type_name() == "directional")
        .expect("the layout has a directional light")
}

/// What switching lights off does to the denoised frames (the tests above).
struct Switch {
    /// RMSE between the exact images before and after.
    moved: f64,
    /// A denoiser started without those lights: its first frames' errors.
    fresh: Vec<f64>,
    /// A denoiser that saw 16 frames with them: its four frames' errors after the switch.
    after: Vec<f64>,
}

/// Switches the lights `pick` names dark (colours zero) on the cubes under 48 lights at
/// 160 x 120, K = 1 denoised, after 16 frames, each frame scored against the exact image
/// without them; a fresh denoiser of the scene without them runs `fresh_frames` frames.
fn switch_off(
    pick: impl Fn(&manyshadows::scene::Scene) -> Vec<usize>,
    fresh_frames: usize,
) -> Switch {
    let ctx = common::context();
    let scene = common::cubes_under_48_lights();
    let base = RenderSettings::new(160, 120);
    let mut exact = common::sampler(&ctx, &scene, base.clone());
    let exact_before = exact.render().expect("frame");
    let mut without = scene.clone();
    for i in pick(&scene) {
        let l = &mut without.lights[i];
        l.diffuse = glam::Vec3::ZERO;
        l.specular = glam::Vec3::ZERO;
        l.ambient = glam::Vec3::ZERO;
    }
    exact.set_lights(without.lights.clone()).expect("lights");
    let exact_after = exact.render().expect("frame");
    let one = RayOptions::default()
        .with_light_samples(1)
        .with_denoise(true);
    let mut fresh = common::sampler(&ctx, &without, base.clone().with_rays(one));
    let fresh = (0..fresh_frames)
        .map(|_| common::rmse(&fresh.render().expect("frame"), &exact_after))
        .collect();
    let mut r = common::sampler(&ctx, &scene, base.with_rays(one));
    for _ in 0..16 {
        r.render().expect("frame");
    }
    r.set_lights(without.lights.clone()).expect("lights");
    let after = (0..4)
        .map(|_| common::rmse(&r.render().expect("frame"), &exact_after))
        .collect();
    Switch {
        moved: common::rmse(&exact_before, &exact_after),
        fresh,
        after,
    }
}

/// A frame whose denoiser buffers (64 bytes a pixel) pass the device's storage-binding limit
/// is refused by name before anything is bound (it was a validation error at 2048 × 2048 on
/// lavapipe's 128 MiB).
#[test]
fn a_frame_too_large_to_denoise_is_refused_by_name() {
    let ctx = common::context();
    let scene = common::cubes_under_48_lights();
    let limits = ctx.limits();
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let w = limits.max_texture_dimension_2d.min(4096);
    let h = ((limit / 64 / u64::from(w)) + 1).min(u64::from(w)) as u32;
    let technique = common::sampling_technique(&ctx);
    let settings = RenderSettings::new(w, h)
        .with_technique(technique)
        .with_rays(
            RayOptions::default()
                .with_light_samples(1)
                .with_denoise(true),
        );
    match Renderer::new(&ctx, &scene, settings) {
        Err(e @ RenderError::TooLarge { .. }) => {
            assert!(e.to_string().contains("denoiser"), "{e}");
        }
        Err(e) => panic!("{technique}: refused for another reason: {e}"),
        Ok(_) => assert!(
            u64::from(w) * u64::from(h) * 64 <= limit,
            "a {w}x{h} denoised frame past the {limit}-byte limit was accepted"
        ),
    }
}

/// The denoised frame keeps what the lighting pass adds besides direct light: with every light
/// traced and every light a point (no noise at all) it is the plain frame, reflections of a
/// probe included (the composite once shaded ambient, emission and the denoised direct light
/// only, and the atrium's marble lost its mirror images).
#[test]
fn the_denoised_frame_keeps_the_probes_reflections() {
    let ctx = common::context();
    let mut scene = builtin::build(
        "atrium",
        &BuiltinOptions {
            lights: Some(8),
            seed: 2,
            mix: LightMix::Point,
            shadow_resolution: Some(256),
            ..Default::default()
        },
    )
    .expect("atrium");
    for l in &mut scene.lights {
        l.size = 0.0;
    }
    scene.probes = vec![manyshadows::scene::Probe {
        resolution: 32,
        ..manyshadows::scene::Probe::new(glam::Vec3::new(6.0, 1.5, 0.0), glam::Vec3::ZERO)
    }];
    let base = RenderSettings::new(160, 90);
    let Some(mut plain) = common::raytraced(&ctx, &scene, base.clone()) else {
        return;
    };
    let plain = plain.render().expect("frame");
    let mut denoised = common::raytraced(
        &ctx,
        &scene,
        base.clone()
            .with_rays(RayOptions::default().with_denoise(true)),
    )
    .expect("same device");
    let denoised = denoised.render().expect("frame");
    let (differing, largest, _) = common::frame_differences(&plain, &denoised);
    // The same frame without the probe, to know the test sees reflections at all.
    let mut bare = scene.clone();
    bare.probes.clear();
    let bare = common::raytraced(&ctx, &bare, base)
        .expect("same device")
        .render()
        .expect("frame");
    let (reflecting, _, _) = common::frame_differences(&plain, &bare);
    eprintln!(
        "denoised against plain: {differing} pixels differ (largest {largest}); the probe changes \
         {reflecting}"
    );
    assert!(
        reflecting > 1000,
        "the probe shows in too few pixels: {reflecting}"
    );
    assert!(
        differing * 200 < reflecting && largest <= 2,
        "the denoised frame is not the plain frame: {differing} pixels differ, by up to {largest}"
    );
}
