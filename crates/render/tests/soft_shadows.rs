//! Soft shadows of sized lights against a penumbra known in closed form, and lights of size 0
//! unchanged by everything soft shadows added.
//!
//! The analytic penumbra: a spot light whose disc (radius `R`, facing straight down) hangs at
//! height `H` over a floor, and a horizontal half-plane occluder at height `h` covering
//! `x < 0`. From a floor point at `x`, the disc's point at offset `u` (along x) is hidden when
//! `u < c = −x·(H − h)/h`, so the visible fraction is the part of the disc with `u ≥ c`:
//! `(acos(c/R) − (c/R)·√(1 − (c/R)²))/π`. The frame looks straight down at the floor; each
//! pixel's world position comes from the G-buffer, so the expected fraction is exact per
//! pixel, independent of the rasterizer.

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::{primitives, Attenuation, Camera, Instance, Light, LightKind};
use manyshadows::scene::{Material, Scene};
use manyshadows::{RenderSettings, Renderer, Technique};

const R: f32 = 0.2;
const H: f32 = 4.0;
const OCCLUDER: f32 = 2.0;
const SIZE: u32 = 192;

/// The visible fraction of the disc light from the floor point at `x`.
fn disc_fraction(x: f32) -> f32 {
    let c = (-x * (H - OCCLUDER) / OCCLUDER / R).clamp(-1.0, 1.0);
    (c.acos() - c * (1.0 - c * c).sqrt()) / std::f32::consts::PI
}

/// The floor, the half-plane occluder (a wide quad over x in [-6, 0]) and the spot light, with
/// a camera looking straight down at the penumbra.
fn penumbra_scene(size: f32) -> Scene {
    let mut occluder = primitives::plane(6.0, 12.0, 1);
    for p in &mut occluder.positions {
        p.x -= 3.0;
    }
    Scene {
        name: "penumbra".into(),
        meshes: vec![primitives::plane(12.0, 12.0, 1), occluder],
        materials: vec![Material::default()],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 0, Mat4::from_translation(Vec3::Y * OCCLUDER)),
        ],
        lights: vec![Light {
            kind: LightKind::Spot {
                position: Vec3::Y * H,
                direction: Vec3::NEG_Y,
                cutoff_deg: 50.0,
                range: 20.0,
            },
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            attenuation: Attenuation::for_range(20.0),
            casts_shadows: true,
            shadow_resolution: 1024,
            size,
        }],
        camera: Camera {
            position: Vec3::new(0.0, 1.5, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            fov_y_deg: 40.0,
            near: 0.05,
            far: 10.0,
        },
        ..Default::default()
    }
}

/// Mean and largest error of light 0's soft visibility against the disc fraction over the
/// floor pixels within the penumbra and a margin around it.
fn penumbra_errors(technique: Technique, size: f32) -> Option<(f32, f32, usize)> {
    let ctx = common::context();
    let scene = penumbra_scene(size);
    let settings = RenderSettings::new(SIZE, SIZE)
        .with_technique(technique)
        .with_soft_visibility(true);
    let mut r = common::renderer_or_refusal(&ctx, &scene, settings)?;
    let frame = r.render().expect("frame");
    let soft = frame.soft_visibility.expect("soft visibility");
    let g = r.read_gbuffer().expect("G-buffer");
    let half = R * OCCLUDER / (H - OCCLUDER);
    let (mut sum, mut max, mut n) = (0.0f32, 0.0f32, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let i = (y * SIZE + x) as usize;
            let p = g.position[i];
            if !g.covered[i] || p.y.abs() > 1e-3 || p.x.abs() > 1.5 * half || p.z.abs() > 0.4 {
                continue;
            }
            let e = (soft.get(x, y, 0) - disc_fraction(p.x)).abs();
            sum += e;
            max = max.max(e);
            n += 1;
        }
    }
    assert!(n > 1000, "{technique}: only {n} penumbra pixels");
    if std::env::var_os("SOFT_PROFILE").is_some() {
        let mut bins = vec![(0.0f32, 0.0f32, 0u32); 24];
        for y in 0..SIZE {
            for x in 0..SIZE {
                let i = (y * SIZE + x) as usize;
                let p = g.position[i];
                if !g.covered[i] || p.y.abs() > 1e-3 || p.x.abs() > 1.5 * half || p.z.abs() > 0.4 {
                    continue;
                }
                let b = (((p.x / (1.5 * half)) * 0.5 + 0.5) * 24.0).clamp(0.0, 23.0) as usize;
                bins[b].0 += soft.get(x, y, 0);
                bins[b].1 += disc_fraction(p.x);
                bins[b].2 += 1;
            }
        }
        for (k, (a, e, c)) in bins.iter().enumerate() {
            eprintln!(
                "{technique} bin {k}: got {:.3} want {:.3}",
                a / *c as f32,
                e / *c as f32
            );
        }
    }
    Some((sum / n as f32, max, n))
}

/// Each soft technique against its own hard twin (the same technique with a light of size 0,
/// whose answer across the penumbra is 0 or 1), as `compare` scores soft shadows: the mean
/// error across the penumbra must be a small part of the hard edge's, and below an absolute
/// bound. Measured on lavapipe (Mesa 25.0.7; llvmpipe GL gives the same for the map
/// techniques): mean / largest error with the sized light, the hard twin's mean, and the
/// bounds. PCSS's disc filter over a straight edge is the disc-segment profile itself (binned
/// over x, the atlas's mean matches the formula to 0.003), so what remains is the 16 taps'
/// noise. Virtual maps filter at the level their samples asked for, whose texels are finer
/// here: the penumbra's radius there passes the 32-texel limit and is clamped, so their profile
/// is narrower. The rays' error is the noise of 4 samples per pixel: a pixel's fraction is a
/// multiple of 1/4, so its largest error is that of a hard answer (0.5 at the edge) and no
/// bound on it could fail; their mean is held against the hard twin's. Irregular maps stay
/// hard and are not scored here.
struct Bound {
    technique: &'static str,
    /// Measured: mean and largest error of the sized light, the hard twin's mean.
    measured: &'static str,
    mean: f32,
    /// `None` where no bound could fail (see above).
    max: Option<f32>,
    /// The mean's largest share of the hard twin's mean.
    of_hard: f32,
}

const BOUNDS: &[Bound] = &[
    Bound {
        technique: "traditional",
        measured: "0.0177 / 0.119, hard 0.141",
        mean: 0.03,
        max: Some(0.2),
        of_hard: 0.25,
    },
    Bound {
        technique: "layered",
        measured: "0.0177 / 0.119, hard 0.141",
        mean: 0.03,
        max: Some(0.2),
        of_hard: 0.25,
    },
    Bound {
        technique: "multiview",
        measured: "0.0177 / 0.119, hard 0.141",
        mean: 0.03,
        max: Some(0.2),
        of_hard: 0.25,
    },
    Bound {
        technique: "gpu-driven",
        measured: "0.0177 / 0.119, hard 0.141",
        mean: 0.03,
        max: Some(0.2),
        of_hard: 0.25,
    },
    Bound {
        technique: "compute",
        measured: "0.0177 / 0.119, hard 0.141",
        mean: 0.03,
        max: Some(0.2),
        of_hard: 0.25,
    },
    Bound {
        technique: "virtual",
        measured: "0.0384 / 0.191, hard 0.141",
        mean: 0.055,
        max: Some(0.3),
        of_hard: 0.45,
    },
    Bound {
        technique: "raytraced",
        measured: "0.0947 / 0.491, hard 0.141",
        mean: 0.11,
        max: None,
        of_hard: 0.8,
    },
];

#[test]
fn penumbra_of_a_disc_light_matches_the_disc_fraction() {
    let ctx = common::context();
    let mut failures = Vec::new();
    let mut ran = 0;
    for t in Technique::all() {
        if !t.info().soft_shadows {
            continue;
        }
        let b = BOUNDS
            .iter()
            .find(|b| b.technique == t.name())
            .unwrap_or_else(|| panic!("{t} has no bound here: measure it and write it down"));
        let Some((mean, max, n)) = penumbra_errors(t, R) else {
            continue;
        };
        let (hard, ..) = penumbra_errors(t, 0.0).expect("the same technique ran just now");
        ran += 1;
        eprintln!(
            "{t}: mean error {mean:.4}, largest {max:.3} over {n} pixels; hard twin {hard:.4} \
             (measured {})",
            b.measured
        );
        if mean > b.mean || max > b.max.unwrap_or(f32::INFINITY) || mean > b.of_hard * hard {
            failures.push(format!(
                "{t}: mean {mean:.4} (bound {}, and {} of the hard twin's {hard:.4}), largest \
                 {max:.3} (bound {:?})",
                b.mean, b.of_hard, b.max
            ));
        }
    }
    // The atlas techniques and virtual maps everywhere; multiview and rays where the device
    // has them (their refusals are checked and recorded by `renderer_or_refusal`).
    let everywhere = Technique::all()
        .into_iter()
        .filter(|t| t.info().soft_shadows && t.info().unmet(&ctx).is_empty())
        .count();
    assert_eq!(ran, everywhere, "soft techniques scored");
    assert!(ran >= 5, "only {ran} soft techniques ran");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The same frame with a hard light: the penumbra's pixels are all 0 or 1, so the soft
/// technique's error above is its own and not the scene's.
#[test]
fn a_hard_light_gives_a_hard_edge_whose_error_is_far_larger() {
    let (mean_soft, ..) = penumbra_errors(Technique::default(), R).expect("default technique");
    let (mean_hard, max_hard, _) =
        penumbra_errors(Technique::default(), 0.0).expect("default technique");
    eprintln!(
        "hard light: mean error {mean_hard:.4} (largest {max_hard:.3}); sized: {mean_soft:.4}"
    );
    assert!(
        mean_hard > 4.0 * mean_soft,
        "hard {mean_hard} against soft {mean_soft}"
    );
}

/// Lights of size 0 take the hard path whatever the soft-shadow settings: every technique's
/// frame, mask and soft visibility are the same with other taps and penumbra limits, and the
/// soft visibility is the mask's bits.
#[test]
fn size_zero_is_untouched_by_soft_settings() {
    let ctx = common::context();
    let scene = manyshadows::scene::builtin::build("cubes", &Default::default()).expect("cubes");
    assert!(scene.lights.iter().all(|l| l.size == 0.0));
    let mut ran = 0;
    for t in Technique::all() {
        let base = RenderSettings::new(96, 72)
            .with_technique(t)
            .with_soft_visibility(true);
        let other = base.clone().with_soft(
            manyshadows::SoftShadows::default()
                .with_blocker_taps(3)
                .with_filter_taps(5)
                .with_max_penumbra(2.0),
        );
        let render = |s: RenderSettings| {
            common::renderer_or_refusal(&ctx, &scene, s).map(|mut r| r.render().expect("frame"))
        };
        let (Some(a), Some(b)) = (render(base), render(other)) else {
            continue;
        };
        assert!(a.rgba == b.rgba, "{t}: the image changed");
        assert_eq!(a.visibility, b.visibility, "{t}: the mask changed");
        let soft = a.soft_visibility.expect("soft");
        let mask = a.visibility.expect("mask");
        assert_eq!(
            soft,
            manyshadows::SoftVisibility::from_mask(&mask),
            "{t}: hard lights' soft visibility is not their bits"
        );
        ran += 1;
    }
    assert!(ran >= 5, "only {ran} techniques ran");
}

/// Shading the last frame again with its own soft visibility gives its image: exactly for
/// hard lights without filtering (the lighting pass's test is the visibility pass's), within
/// the bytes' rounding for sized lights; and a visibility of another shape is refused.
#[test]
fn shading_with_the_frames_own_visibility_gives_its_image() {
    let ctx = common::context();
    let mut scene = manyshadows::scene::builtin::build("cubes", &Default::default()).unwrap();
    let settings = RenderSettings::new(96, 72)
        .with_pcf(manyshadows::Pcf::Off)
        .with_soft_visibility(true);
    let mut r = Renderer::new(&ctx, &scene, settings.clone()).unwrap();
    let frame = r.render().unwrap();
    let soft = frame.soft_visibility.clone().unwrap();
    assert!(r.shade_with(&soft).unwrap() == frame.rgba, "hard lights");
    let dark = manyshadows::SoftVisibility {
        values: vec![0; soft.values.len()],
        ..soft.clone()
    };
    assert!(
        r.shade_with(&dark).unwrap() != frame.rgba,
        "no light reaching changes it"
    );
    let wrong = manyshadows::SoftVisibility {
        lights: soft.lights + 1,
        ..soft
    };
    assert!(matches!(
        r.shade_with(&wrong),
        Err(manyshadows::RenderError::Mismatch { .. })
    ));

    for l in &mut scene.lights {
        l.size = 0.15;
    }
    let mut r = Renderer::new(&ctx, &scene, settings).unwrap();
    let frame = r.render().unwrap();
    let again = r
        .shade_with(frame.soft_visibility.as_ref().unwrap())
        .unwrap();
    let worst = frame
        .rgba
        .iter()
        .zip(&again)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(worst <= 2, "sized lights: a channel differs by {worst}");
}

/// Virtual maps with sized lights: the soft filter reads up to the largest penumbra from a
/// sample, so its page's receiver bounds and the pages beside it must hold the casters there.
/// Culling casters by the receiver bounds, and marking by tiles, then change no pixel.
#[test]
fn virtual_soft_shadows_keep_what_their_filter_reads() {
    let ctx = common::context();
    let scene = manyshadows::scene::builtin::build(
        "atrium",
        &manyshadows::scene::builtin::BuiltinOptions {
            lights: Some(12),
            ..Default::default()
        },
    )
    .expect("atrium");
    assert!(scene.lights.iter().all(|l| l.size > 0.0));
    let render = |options: manyshadows::VirtualOptions| {
        Renderer::new(
            &ctx,
            &scene,
            RenderSettings::new(240, 135)
                .with_technique(Technique::VIRTUAL)
                .with_virtual_maps(options),
        )
        .expect("renderer")
        .render()
        .expect("frame")
    };
    let base = render(manyshadows::VirtualOptions::default());
    for (what, options) in [
        (
            "without receiver bounds",
            manyshadows::VirtualOptions::default().with_receiver_cull(false),
        ),
        (
            "marking per pixel",
            manyshadows::VirtualOptions::default().with_tile_marking(false),
        ),
    ] {
        let other = render(options);
        let (differing, largest, _) = common::frame_differences(&base, &other);
        eprintln!("{what}: {differing} pixels differ, by up to {largest}");
        assert!(
            differing <= 2 && largest <= 4,
            "{what}: {differing} pixels differ, by up to {largest} levels"
        );
    }
}

/// Virtual maps filter penumbrae up to `MAX_SOFT_PENUMBRA` (63 texels) at a sample's level:
/// the page marking asks for the pages at the corners of the taps' reach, all the pages the
/// reach touches only while it spans at most a page. A wider `max_penumbra` is clamped there
/// (wider penumbrae go to coarser levels), so the frame at 200 is the frame at 63; the atlas,
/// whose taps read one tile, keeps 200 (its frames differ: the clamp is the virtual maps').
#[test]
fn virtual_maps_clamp_the_penumbra_to_what_their_marking_reaches() {
    use manyshadows::shadows::vsm::plan::{MAX_SOFT_PENUMBRA, PAGE_SIZE};
    assert!(2.0 * (MAX_SOFT_PENUMBRA + 1.0) <= PAGE_SIZE as f32);
    let ctx = common::context();
    let mut scene = manyshadows::scene::builtin::build(
        "atrium",
        &manyshadows::scene::builtin::BuiltinOptions {
            lights: Some(8),
            ..Default::default()
        },
    )
    .expect("atrium");
    // Wide lights, so that penumbrae pass 63 texels.
    for l in &mut scene.lights {
        l.size *= 4.0;
    }
    let render = |technique: Technique, max_penumbra: f32| {
        Renderer::new(
            &ctx,
            &scene,
            RenderSettings::new(240, 135)
                .with_technique(technique)
                .with_soft(manyshadows::SoftShadows::default().with_max_penumbra(max_penumbra)),
        )
        .expect("renderer")
        .render()
        .expect("frame")
    };
    let at = |t| (render(t, MAX_SOFT_PENUMBRA), render(t, 200.0));
    let (a, b) = at(Technique::VIRTUAL);
    assert_eq!(common::frame_differences(&a, &b), (0, 0, 0), "virtual maps");
    let (a, b) = at(Technique::TRADITIONAL);
    let (differing, _, _) = common::frame_differences(&a, &b);
    assert!(differing > 100, "the atlas: {differing} pixels differ");
}
