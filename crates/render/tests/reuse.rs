//! Temporal reuse of sampled lights (`RayOptions::reuse`): on a still camera one light per
//! pixel and frame, reused, must come ever closer to the exact image (every cluster light)
//! where plain sampling stays as noisy as its first frame, and its mean over seeds must be the
//! exact image (no bias). The sampled lights' visibility is traced where the adapter has ray
//! queries and read from shadow maps where it has none (OpenGL: `common::sampler`); reuse
//! without sampled lights is refused everywhere.

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::shading::look::{Exposure, Look, ToneMap};
use manyshadows::{RayOptions, RenderSettings, SpatialReuse, Technique};

/// Still frames, 160 × 120: plain K = 1 stays at its first frame's error, reused K = 1
/// falls frame by frame (the reservoirs stand for up to 20 frames: a moving average of
/// about that many draws, whose error is a fraction of one draw's).
#[test]
fn reused_samples_converge_on_a_still_camera() {
    let ctx = common::context();
    let scene = common::cubes_under_48_lights();
    let base = RenderSettings::new(160, 120);
    let mut exact = common::sampler(&ctx, &scene, base.clone());
    let exact = exact.render().expect("frame");
    let one = RayOptions::default().with_light_samples(1);
    let mut plain = common::sampler(&ctx, &scene, base.clone().with_rays(one));
    let plain: Vec<f64> = (0..2)
        .map(|_| common::rmse(&plain.render().expect("frame"), &exact))
        .collect();
    let mut reused = common::sampler(&ctx, &scene, base.with_rays(one.with_reuse(true)));
    let errors: Vec<f64> = (0..16)
        .map(|_| common::rmse(&reused.render().expect("frame"), &exact))
        .collect();
    eprintln!(
        "RMSE against every light: K = 1 plain {plain:.2?}; reused, frames 1 to 16: {errors:.2?}"
    );
    assert!(
        (errors[0] - plain[0]).abs() < 0.25 * plain[0],
        "the first reused frame (nothing to reuse yet) is not plain sampling: {} vs {}",
        errors[0],
        plain[0]
    );
    assert!(
        errors[15] < 0.5 * plain[0],
        "sixteen still frames of reuse do not halve the error: {errors:?} (plain {plain:?})"
    );
    assert!(
        errors[15] < errors[3] && errors[3] < errors[0],
        "the error does not fall frame by frame: {errors:?}"
    );
}

/// Spatial reuse on still frames, 160 × 120: with neighbours' samples resampled the first frame
/// (nothing to reuse in time yet) is already far closer than temporal reuse's, and later
/// frames stay closer too, biased or unbiased.
#[test]
fn spatial_reuse_lowers_the_error_from_the_first_frame() {
    let ctx = common::context();
    let scene = common::cubes_under_48_lights();
    let base = RenderSettings::new(160, 120);
    let mut exact = common::sampler(&ctx, &scene, base.clone());
    let exact = exact.render().expect("frame");
    let reuse = RayOptions::default().with_light_samples(1).with_reuse(true);
    let errors = |spatial: SpatialReuse| -> Vec<f64> {
        let mut r = common::sampler(
            &ctx,
            &scene,
            base.clone().with_rays(reuse.with_spatial(spatial)),
        );
        (0..8)
            .map(|_| common::rmse(&r.render().expect("frame"), &exact))
            .collect()
    };
    let temporal = errors(SpatialReuse::Off);
    let biased = errors(SpatialReuse::Biased);
    let unbiased = errors(SpatialReuse::Unbiased);
    eprintln!(
        "RMSE against every light, frames 1 to 8: temporal {temporal:.2?}; + spatial biased \
         {biased:.2?}; + spatial unbiased {unbiased:.2?}"
    );
    for (name, e) in [("biased", &biased), ("unbiased", &unbiased)] {
        assert!(
            e[0] < 0.8 * temporal[0],
            "{name}: the first frame is not much closer than temporal reuse's: {} vs {}",
            e[0],
            temporal[0]
        );
        assert!(
            e[7] < temporal[7],
            "{name}: the eighth frame is not closer than temporal reuse's: {} vs {}",
            e[7],
            temporal[7]
        );
    }
}

/// sRGB-encoded byte to linear.
fn linear(v: u8) -> f64 {
    let c = f64::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The mean over seeds of the fourth still frame, in linear colour (a tone map that only
/// clamps, an exposure under which nothing clips): the exact image within the seeds' noise,
/// for plain sampling (unbiased by construction: the check of this test's own method) and for
/// reuse. Returns the mean signed difference and the mean absolute difference of the average
/// and of one frame, as fractions of the exact image's mean.
fn mean_over_seeds(rays: RayOptions, seeds: u32) -> (f64, f64, f64) {
    let ctx = common::context();
    let scene = common::cubes_under_48_lights();
    let look = Look {
        tone_map: Some(ToneMap::Clamp),
        exposure: Some(Exposure::Scale(0.1)),
        ..Look::default()
    };
    let base = RenderSettings::new(96, 72).with_look(look);
    let exact = common::sampler(&ctx, &scene, base.clone())
        .render()
        .expect("frame");
    // Colour channels only (every fourth byte is alpha), linear.
    let channels = |rgba: &[u8]| -> Vec<f64> {
        rgba.chunks_exact(4)
            .flat_map(|p| p[..3].iter().map(|&v| linear(v)))
            .collect()
    };
    let exact = channels(&exact.rgba);
    let brightest = exact.iter().cloned().fold(0.0, f64::max);
    assert!(
        brightest < 0.95,
        "the exact image clips (brightest {brightest:.3}): choose a lower exposure"
    );
    let mut sum = vec![0.0f64; exact.len()];
    let mut one = Vec::new();
    for seed in 0..seeds {
        let mut r = common::sampler(&ctx, &scene, base.clone().with_rays(rays.with_seed(seed)));
        for _ in 0..3 {
            r.render().expect("frame");
        }
        let f = channels(&r.render().expect("frame").rgba);
        for (s, v) in sum.iter_mut().zip(&f) {
            *s += v;
        }
        if seed == 0 {
            one = f;
        }
    }
    let mean: Vec<f64> = sum.iter().map(|s| s / f64::from(seeds)).collect();
    let total: f64 = exact.iter().sum();
    let signed = mean.iter().zip(&exact).map(|(a, b)| a - b).sum::<f64>() / total;
    let abs = |v: &[f64]| {
        v.iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>()
            / total
    };
    (signed, abs(&mean), abs(&one))
}

/// The mean of reused frames over 24 seeds is the exact image: its signed difference is
/// within the seeds' noise, and its absolute difference falls well below one frame's as the
/// seeds average out. Measured on lavapipe (fractions of the exact image's mean): plain
/// signed +0.0009, mean 0.025 against one frame's 0.107; reused +0.0012, 0.030 against 0.082.
/// Plain sampling, unbiased by construction, passes the same bounds (the method's own check).
/// Confidence weights that do not sum to 1 fail them: without the new draw's `1 / (1 + M)`
/// the reused mean is +1.12 of the image (seen).
#[test]
fn reuse_is_unbiased_on_a_still_camera() {
    let one = RayOptions::default().with_light_samples(1);
    let plain = mean_over_seeds(one, 24);
    let reused = mean_over_seeds(one.with_reuse(true), 24);
    eprintln!(
        "mean over 24 seeds against exact (fractions of its mean): plain signed {:+.4} abs {:.4} \
         (one frame {:.4}); reused signed {:+.4} abs {:.4} (one frame {:.4})",
        plain.0, plain.1, plain.2, reused.0, reused.1, reused.2
    );
    for (name, (signed, mean_abs, one_abs)) in [("plain", plain), ("reused", reused)] {
        assert!(
            signed.abs() < 0.01,
            "{name}: biased by {signed:+.4} of the image"
        );
        assert!(
            mean_abs < 0.5 * one_abs,
            "{name}: the mean over seeds ({mean_abs:.4}) is not far closer than one frame \
             ({one_abs:.4})"
        );
    }
}

/// Spatial reuse's unbiased mode keeps reuse unbiased: the mean of its frames over 24 seeds is
/// the exact image, as plain sampling's and temporal reuse's are (the bounds of
/// `reuse_is_unbiased_on_a_still_camera`). Measured on lavapipe: signed +0.0011, mean 0.027
/// against one frame's 0.089. The biased mode, measured beside it, darkens by 0.0156 of the
/// image (0.030, one frame 0.087): outside the bound, which the test checks it sees.
#[test]
fn unbiased_spatial_reuse_is_unbiased_on_a_still_camera() {
    let reuse = RayOptions::default().with_light_samples(1).with_reuse(true);
    let unbiased = mean_over_seeds(reuse.with_spatial(SpatialReuse::Unbiased), 24);
    let biased = mean_over_seeds(reuse.with_spatial(SpatialReuse::Biased), 24);
    eprintln!(
        "mean over 24 seeds against exact (fractions of its mean): spatial unbiased signed {:+.4} \
         abs {:.4} (one frame {:.4}); spatial biased signed {:+.4} abs {:.4} (one frame {:.4})",
        unbiased.0, unbiased.1, unbiased.2, biased.0, biased.1, biased.2
    );
    let (signed, mean_abs, one_abs) = unbiased;
    assert!(signed.abs() < 0.01, "biased by {signed:+.4} of the image");
    // The method sees a bias of the biased mode's size (measured −0.0156: it darkens).
    assert!(
        biased.0 < -0.005,
        "the biased mode's darkening ({:+.4}) is not seen: the test could not tell",
        biased.0
    );
    assert!(
        mean_abs < 0.5 * one_abs,
        "the mean over seeds ({mean_abs:.4}) is not far closer than one frame ({one_abs:.4})"
    );
}

/// Reuse asks for sampled lights: irregular maps (every light in one mask), or every light
/// traced, are refused naming the option, on any device.
#[test]
fn reuse_without_sampled_rays_is_refused_by_name() {
    let scene = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    common::refused_naming(
        &scene,
        &[
            RenderSettings::new(32, 32)
                .with_technique(Technique::IRREGULAR)
                .with_rays(RayOptions::default().with_reuse(true)),
            RenderSettings::new(32, 32)
                .with_technique(Technique::RAYTRACED)
                .with_rays(RayOptions::default().with_reuse(true)),
        ],
        "rays.reuse",
    );
}

/// Spatial reuse resamples what temporal reuse keeps: asked for without it, it is refused
/// naming the option, on any device.
#[test]
fn spatial_reuse_without_temporal_reuse_is_refused_by_name() {
    let scene = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    common::refused_naming(
        &scene,
        &[SpatialReuse::Biased, SpatialReuse::Unbiased].map(|mode| {
            RenderSettings::new(32, 32)
                .with_technique(Technique::RAYTRACED)
                .with_rays(
                    RayOptions::default()
                        .with_light_samples(1)
                        .with_spatial(mode),
                )
        }),
        "rays.spatial",
    );
}
