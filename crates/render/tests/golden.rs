//! Golden images of small scenes, compared with a perceptual tolerance. Re-bless after an
//! intended change with `MANYSHADOWS_BLESS=1 cargo test --release --test golden` and look at
//! the new pictures before committing them; a failure writes the actual image and a diff to
//! `target/test-artifacts/`.

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::{Pcf, RenderError, RenderSettings, Renderer, Technique};

/// A pixel "differs" when its largest channel difference exceeds this (of 255).
const PIXEL_TOLERANCE: u8 = 24;
/// At most this fraction of pixels may differ (edges move by a pixel between rasterizers).
const MAX_DIFFERING_FRACTION: f64 = 0.005;
/// And the mean absolute channel difference must stay under this (of 255).
const MAX_MEAN_DIFF: f64 = 1.5;

fn golden(scene: &str, pcf: Pcf, file: &str) {
    let (differing, mean, _) = golden_with(scene, pcf, file, Technique::default())
        .expect("the default technique runs everywhere");
    assert!(
        differing as f64 <= MAX_DIFFERING_FRACTION * (240.0 * 160.0) && mean <= MAX_MEAN_DIFF,
        "{file}: {differing} pixels differ, mean {mean:.2}"
    );
}

/// Renders `scene` with `technique` and compares it with the golden `file`; returns the pixels
/// that differ by more than [`PIXEL_TOLERANCE`], the mean channel difference and the bytes
/// that differ at all (`Err` when the technique cannot run on this adapter). Blessing writes
/// the default technique's frame.
fn golden_with(
    scene: &str,
    pcf: Pcf,
    file: &str,
    technique: Technique,
) -> Result<(usize, f64, usize), RenderError> {
    let ctx = common::context();
    let scene = builtin::build(scene, &BuiltinOptions::default()).expect("scene");
    let (w, h) = (240, 160);
    let settings = RenderSettings::new(w, h)
        .with_pcf(pcf)
        .with_technique(technique);
    let frame = Renderer::new(&ctx, &scene, settings)?
        .render()
        .expect("frame");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(file);
    if std::env::var_os("MANYSHADOWS_BLESS").is_some() && technique == Technique::default() {
        image::save_buffer(&path, &frame.rgba, w, h, image::ExtendedColorType::Rgba8).unwrap();
        eprintln!("blessed {}", path.display());
        return Ok((0, 0.0, 0));
    }
    let expected = image::open(&path)
        .unwrap_or_else(|e| {
            panic!(
                "missing golden {} ({e}); bless with MANYSHADOWS_BLESS=1",
                path.display()
            )
        })
        .to_rgba8();
    assert_eq!((expected.width(), expected.height()), (w, h), "golden size");
    let (mut differing, mut sum) = (0usize, 0u64);
    let mut diff = vec![0u8; (w * h * 4) as usize];
    for (i, (a, b)) in frame
        .rgba
        .chunks_exact(4)
        .zip(expected.as_raw().chunks_exact(4))
        .enumerate()
    {
        let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap();
        sum += (0..3).map(|c| a[c].abs_diff(b[c]) as u64).sum::<u64>();
        if d > PIXEL_TOLERANCE {
            differing += 1;
        }
        diff[i * 4..i * 4 + 4].copy_from_slice(&[d.saturating_mul(4), 0, 0, 255]);
    }
    let frac = differing as f64 / (w * h) as f64;
    let mean = sum as f64 / (w * h * 3) as f64;
    eprintln!(
        "{file}, technique {technique}: {differing} pixels ({:.3} %) differ by more than \
         {PIXEL_TOLERANCE}, mean difference {mean:.3}",
        frac * 100.0
    );
    if frac > MAX_DIFFERING_FRACTION || mean > MAX_MEAN_DIFF {
        let dir = common::artifacts_dir();
        let actual = dir.join(format!("actual-{technique}-{file}"));
        let diff_path = dir.join(format!("diff-{technique}-{file}"));
        image::save_buffer(&actual, &frame.rgba, w, h, image::ExtendedColorType::Rgba8).unwrap();
        image::save_buffer(&diff_path, &diff, w, h, image::ExtendedColorType::Rgba8).unwrap();
        eprintln!(
            "{file}, {technique}: actual {}, diff {}",
            actual.display(),
            diff_path.display()
        );
    }
    let bytes = frame
        .rgba
        .iter()
        .zip(expected.as_raw())
        .filter(|(a, b)| a != b)
        .count();
    Ok((differing, mean, bytes))
}

#[test]
fn cubes_with_three_light_types_pcf_3x3() {
    golden("cubes", Pcf::Pcf3x3, "cubes-pcf3x3.png");
}

#[test]
fn cubes_hard_shadows() {
    golden("cubes", Pcf::Off, "cubes-pcf-off.png");
}

/// Pixels of the 240×160 hard-shadow cubes frame that may differ from the default technique's
/// golden image, per technique: measured on lavapipe / llvmpipe GL (Mesa 25.0.7), then the
/// bound with its margin. The atlas techniques write the same depth (tests/equivalence.rs), so
/// their frames match the golden one exactly here; the bound of 4 allows a few edge texels of
/// another rasterizer. Irregular and ray-traced shadows are exact where the golden frame
/// samples a 512² map, and virtual maps sample pages no coarser than the atlas's tiles (the
/// atlas floor; 25 pixels before it, when they aimed at one texel per pixel): they put a few
/// outline pixels elsewhere; their bounds are the measurement plus about 60 %, far below a
/// shifted or missing shadow (the hard shadows of the cubes cover thousands of pixels of this
/// frame).
/// Every registered technique needs its line here: one without fails the test.
const BOUNDS: &[(&str, &str, usize)] = &[
    ("traditional", "0 / 0", 0),
    ("layered", "0 / 0", 4),
    ("multiview", "0 / refused on GL", 4),
    ("gpu-driven", "0 / 0", 4),
    ("compute", "0 / 0", 4),
    ("irregular", "18 / 18", 30),
    ("virtual", "7 / 7", 12),
    ("raytraced", "18 / refused on GL", 30),
];

/// Every technique of the registry against the golden hard-shadow frame, each with its
/// measured difference beside its bound. A technique the adapter cannot run must be refused
/// naming what it lacks; one the adapter supports must render.
#[test]
fn every_technique_against_the_golden_frame() {
    let ctx = common::context();
    let mut failures = Vec::new();
    for t in Technique::all() {
        let bound = BOUNDS
            .iter()
            .find(|(n, ..)| *n == t.name())
            .map(|&(_, measured, b)| (measured, b))
            .unwrap_or_else(|| {
                panic!(
                    "{t} has no bound in BOUNDS: run this test with --nocapture on Vulkan and \
                     GL, and write its measured difference and a bound beside the others"
                )
            });
        match golden_with("cubes", Pcf::Off, "cubes-pcf-off.png", t) {
            Ok((differing, mean, _)) => {
                eprintln!(
                    "{t}: {differing} pixels differ (measured {}; bound {})",
                    bound.0, bound.1
                );
                if differing > bound.1 || mean > MAX_MEAN_DIFF {
                    failures.push(format!(
                        "{t}: {differing} pixels differ (bound {}), mean {mean:.2}",
                        bound.1
                    ));
                }
            }
            Err(e) => common::check_refusal(&ctx, t, &e),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Lights of size 0 are the hard shadows of before soft shadows existed, byte for byte: every
/// atlas technique's frame of the cubes (whose lights have size 0), PCF off and 3×3, is the
/// frame the same renderer gives with soft shadows compiled out of its lighting pass
/// (`Renderer::compile_out_soft_shadows`), in the same run. A byte comparison with an image
/// stored on another machine would fail wherever llvmpipe rounds differently (its floating
/// point follows the CPU): the stored goldens are compared within tolerances by the tests
/// above. As a control, lights of a small size (sent through the soft filter) must change the
/// bytes, or the comparison could not see the soft path at all. On a hardware rasterizer two
/// compilations of the pass may fuse arithmetic differently: there the perceptual bounds
/// apply.
#[test]
fn size_zero_is_byte_for_byte_the_frame_without_soft_shadows() {
    let ctx = common::context();
    let scene = builtin::build("cubes", &BuiltinOptions::default()).expect("scene");
    assert!(
        scene.lights.iter().all(|l| l.size == 0.0),
        "the cubes' lights must stay hard for this test"
    );
    let exact = common::cpu_rasterizer(&ctx);
    let (w, h) = (240, 160);
    let mut ran = 0;
    let mut failures = Vec::new();
    for t in Technique::all() {
        if t.info().fills != manyshadows::Fills::Atlas {
            continue;
        }
        for pcf in [Pcf::Off, Pcf::Pcf3x3] {
            let settings = RenderSettings::new(w, h).with_pcf(pcf).with_technique(t);
            let Some(mut r) = common::renderer_or_refusal(&ctx, &scene, settings.clone()) else {
                continue;
            };
            let with = r.render().expect("frame");
            r.compile_out_soft_shadows();
            let without = r.render().expect("frame");
            let (pixels, largest, _) = common::frame_differences(&with, &without);
            let bytes = with
                .rgba
                .iter()
                .zip(&without.rgba)
                .filter(|(a, b)| a != b)
                .count();
            eprintln!("{t}, {pcf:?}: {bytes} bytes differ ({pixels} pixels, largest {largest})");
            let fails = if exact {
                bytes != 0
            } else {
                pixels as f64 > MAX_DIFFERING_FRACTION * f64::from(w * h)
                    || largest > PIXEL_TOLERANCE
            };
            if fails {
                common::differing_pixels(
                    &with,
                    &without,
                    &format!("size-zero-{t}-{pcf:?}"),
                    ["with", "without"],
                );
                failures.push(format!(
                    "{t}, {pcf:?}: {bytes} bytes differ with soft shadows compiled out \
                     ({pixels} pixels, largest {largest})"
                ));
            }
            ran += 1;
        }
    }
    assert!(ran >= 8, "only {ran} atlas frames rendered");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The control: small lights go through the soft filter, which the comparison sees.
    let mut sized = scene.clone();
    for l in &mut sized.lights {
        l.size = 0.05;
    }
    let mut r = Renderer::new(&ctx, &sized, RenderSettings::new(w, h)).expect("renderer");
    let soft = r.render().expect("frame");
    r.compile_out_soft_shadows();
    let hard = r.render().expect("frame");
    let (pixels, ..) = common::frame_differences(&soft, &hard);
    assert!(
        pixels > 100,
        "sized lights changed only {pixels} pixels: the soft path is unseen"
    );
}
