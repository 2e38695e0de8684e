//! Golden images of small scenes, compared with a perceptual tolerance. Re-bless after an
//! intended change with `MANYSHADOWS_BLESS=1 cargo test --release --test golden` and look at
//! the new pictures before committing them; a failure writes the actual image and a diff to
//! `target/test-artifacts/`.

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::{Pcf, RenderSettings, Renderer};

/// A pixel "differs" when its largest channel difference exceeds this (of 255).
const PIXEL_TOLERANCE: u8 = 24;
/// At most this fraction of pixels may differ (edges move by a pixel between rasterizers).
const MAX_DIFFERING_FRACTION: f64 = 0.005;
/// And the mean absolute channel difference must stay under this (of 255).
const MAX_MEAN_DIFF: f64 = 1.5;

fn golden(scene: &str, pcf: Pcf, file: &str) {
    let ctx = common::context();
    let scene = builtin::build(scene, &BuiltinOptions::default()).expect("scene");
    let (w, h) = (240, 160);
    let settings = RenderSettings::default()
        .with_width(w)
        .with_height(h)
        .with_pcf(pcf);
    let frame = Renderer::new(&ctx, &scene, settings)
        .expect("renderer")
        .render()
        .expect("frame");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(file);
    if std::env::var_os("MANYSHADOWS_BLESS").is_some() {
        image::save_buffer(&path, &frame.rgba, w, h, image::ExtendedColorType::Rgba8).unwrap();
        eprintln!("blessed {}", path.display());
        return;
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
    if frac > MAX_DIFFERING_FRACTION || mean > MAX_MEAN_DIFF {
        let dir = common::artifacts_dir();
        let actual = dir.join(format!("actual-{file}"));
        let diff_path = dir.join(format!("diff-{file}"));
        image::save_buffer(&actual, &frame.rgba, w, h, image::ExtendedColorType::Rgba8).unwrap();
        image::save_buffer(&diff_path, &diff, w, h, image::ExtendedColorType::Rgba8).unwrap();
        panic!(
            "{file}: {:.3}% of pixels differ by more than {PIXEL_TOLERANCE}, mean difference {mean:.2}; actual {}, diff {}",
            frac * 100.0,
            actual.display(),
            diff_path.display()
        );
    }
}

#[test]
fn cubes_with_three_light_types_pcf_3x3() {
    golden("cubes", Pcf::Pcf3x3, "cubes-pcf3x3.png");
}

#[test]
fn cubes_hard_shadows() {
    golden("cubes", Pcf::Off, "cubes-pcf-off.png");
}
