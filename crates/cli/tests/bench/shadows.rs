//! `bench shadows` and `bench denoise`: maps, pages and rays side by side.

use crate::helpers::{assert_ratio, bench_ok, records, rejects, tmp};
use crate::shared_gpu;

/// `bench shadows` on a tiny frame: the atlas, pages and (where the device has ray queries)
/// rays with every light and with sampled lights, in one run; ratios from the same run's
/// medians; the per-frame acceleration-structure rebuild timed apart.
#[test]
fn bench_shadows_puts_every_kind_of_shadow_side_by_side() {
    let (dir, json) = bench_ok(
        "shadows",
        "--scene cubes --lights 4,40 --width 96 --height 54 --light-samples 2 --repeats 1 --warmup 0",
    );
    let ctx = shared_gpu::context();
    let rays_here = shared_gpu::rays_here(&ctx);
    let records = records(&json);
    assert_eq!(records.len(), 2, "{json}");
    for r in records {
        let sides = r["sides"].as_array().unwrap();
        let labels: Vec<&str> = sides.iter().map(|s| s["label"].as_str().unwrap()).collect();
        let want: &[&str] = if rays_here {
            &["atlas", "pages", "rays", "rays K=2"]
        } else {
            &["atlas", "pages"]
        };
        assert_eq!(labels, want, "{r}");
        let atlas = &sides[0];
        for s in sides {
            assert!(s["setup_ms"].as_f64().unwrap() > 0.0, "{s}");
            assert_ratio(&s["ratio"], &s["frame_ms"], &atlas["frame_ms"], s);
            let rays = s["label"].as_str().unwrap().starts_with("rays");
            // Only the rays rebuild a top-level acceleration structure, every frame.
            assert_eq!(s["accel_ms"].is_number(), rays, "{s}");
        }
    }
    assert!(dir.join("shadows-cubes-96x54.png").exists());
}

/// `bench denoise --technique virtual`: the sampled lights' visibility from the pages, each
/// frame scored against virtual maps with every light (the denoised frames far closer than the
/// plain ones), with the every-light frame's time and pages beside them; the exact frames too
/// where there are ray queries. Irregular maps cannot sample: refused naming the flag.
fn bench_denoise_over_virtual_maps(rays_here: bool) {
    let (dir, json) = bench_ok(
        "denoise",
        "--technique virtual --scene cubes --lights 48 --frames 4 --width 96 --height 72 --still",
    );
    assert_eq!(json["technique"], "virtual", "{json}");
    let r = &records(&json)[0];
    let (plain, denoised) = (
        r["plain_every_mean_rmse"]
            .as_f64()
            .expect("plain against every light"),
        r["denoised_every_mean_rmse"]
            .as_f64()
            .expect("denoised against every light"),
    );
    eprintln!("bench denoise over virtual maps: against every light, plain {plain:.2}, denoised {denoised:.2}");
    assert!(plain > 0.0 && denoised < 0.7 * plain, "{r}");
    let f = &r["frames"][0];
    assert!(
        f["every_ms"].is_number() || f["plain_ms"].is_null(),
        "the every-light frame is timed where frames are: {f}"
    );
    assert!(
        f["denoised_pages"].as_u64().is_some_and(|p| p > 0) && f["every_pages"].is_u64(),
        "{f}"
    );
    assert_eq!(f["plain_rmse"].is_number(), rays_here, "{f}");
    let text = std::fs::read_to_string(dir.join("results.txt")).unwrap();
    assert!(
        text.contains("against every light through the same maps")
            && text.contains("virtual's shadow maps"),
        "{text}"
    );
    rejects(
        "denoise --technique irregular --scene cubes --lights 4 --frames 1",
        "--technique irregular",
    );
}

/// `bench denoise` on a tiny sequence: every frame scored against the exact image of that
/// frame, the denoised frames closer than the plain ones on average (the denoiser's point:
/// measured on cubes with 48 lights, 96x72, 4 frames), the cost ratio from the same
/// sequence's medians; `--reference off` times only. Without ray queries the ray-traced run is
/// refused naming the feature; sampled lights over virtual maps run on any backend.
#[test]
fn bench_denoise_scores_each_frame_of_a_sequence() {
    let args = "denoise --scene cubes --lights 48 --frames 4 --width 96 --height 72";
    let ctx = shared_gpu::context();
    let rays_here = shared_gpu::rays_here(&ctx);
    bench_denoise_over_virtual_maps(rays_here);
    if !rays_here {
        rejects(args, "EXPERIMENTAL_RAY_QUERY");
        return;
    }
    let (dir, json) = bench_ok("denoise", &args["denoise ".len()..]);
    // The exact image's grid over each sized light is said (its own noise is in every score).
    assert_eq!(
        json["reference_area_samples"].as_u64(),
        Some(u64::from(manyshadows::DEFAULT_AREA_SAMPLES)),
        "{json}"
    );
    let rows = records(&json);
    assert_eq!(rows.len(), 1, "{json}");
    let r = &rows[0];
    let frames = r["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 4, "{r}");
    for f in frames {
        for key in ["plain_rmse", "denoised_rmse", "plain_ms", "denoised_ms"] {
            assert!(f[key].as_f64().is_some_and(|v| v >= 0.0), "{key}: {f}");
        }
    }
    let (plain, denoised) = (
        r["plain_mean_rmse"].as_f64().unwrap(),
        r["denoised_mean_rmse"].as_f64().unwrap(),
    );
    eprintln!("bench denoise: mean RMSE plain {plain:.2}, denoised {denoised:.2}");
    assert!(denoised < 0.7 * plain, "{r}");
    assert_ratio(
        &r["cost_ratio"],
        &r["denoised_median_ms"],
        &r["plain_median_ms"],
        r,
    );
    // The paired ratio is the median of the frames' own ratios: within their range.
    let own: Vec<f64> = frames
        .iter()
        .map(|f| f["denoised_ms"].as_f64().unwrap() / f["plain_ms"].as_f64().unwrap())
        .collect();
    let paired = r["cost_ratio_paired"].as_f64().expect("paired ratio");
    let (lo, hi) = own
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(
        lo - 1e-9 <= paired && paired <= hi + 1e-9,
        "{paired} outside {own:?}"
    );
    assert!(dir.join("frames.png").exists());
    // Two light counts, their frames alternating: each keeps its own sequence, and the
    // growth between them is given both ways with what the denoiser adds.
    let (off_dir, json) = bench_ok(
        "denoise",
        "--scene cubes --lights 8,16 --frames 2 --width 64 --height 48 --reference off",
    );
    let rows = records(&json);
    assert_eq!(rows.len(), 2, "{json}");
    for (r, n) in rows.iter().zip([8, 16]) {
        assert_eq!(r["lights"].as_u64(), Some(n), "{r}");
        let frames: Vec<u64> = r["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["frame"].as_u64().unwrap())
            .collect();
        assert_eq!(frames, [1, 2], "{r}");
    }
    let f = &rows[0]["frames"][0];
    assert!(
        f["plain_rmse"].is_null() && f["denoised_ms"].is_number(),
        "{f}"
    );
    let text = std::fs::read_to_string(off_dir.join("results.txt")).unwrap();
    assert!(
        text.contains("growth from 8 to 16 lights")
            && text.contains("frame by frame")
            && text.contains("what the denoiser adds"),
        "{text}"
    );
    // A still camera and a moving caster: the bench picks a caster whose move shows, says
    // which, and measures how far the denoised shadow trails (issue 39: at most 2 frames).
    let (_, json) = bench_ok(
        "denoise",
        "--scene cubes --lights 48 --frames 8 --orbit 0 --width 96 --height 72",
    );
    let notes = json["notes"].to_string();
    assert!(notes.contains("circles"), "{notes}");
    let r = &records(&json)[0];
    let trails: Vec<u64> = r["frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|f| f["trail_frames"].as_u64())
        .collect();
    eprintln!("bench denoise: trail per frame {trails:?}");
    assert!(trails.len() >= 3, "{r}");
    let trail = r["mean_trail_frames"].as_f64().unwrap();
    assert!(
        trail <= 2.0,
        "the denoised shadow trails by {trail} frames: {r}"
    );
    // A fly path instead of an orbit: three cameras, the last kept.
    let path = tmp("denoise-path").join("path.txt");
    std::fs::write(&path, "0 4 9 0 1 0\n1 3.5 8 0 1 0\n2 3 7 0 0.5 0\n").unwrap();
    let (path_dir, json) = bench_ok(
        "denoise",
        &format!(
            "--scene cubes --lights 8 --frames 4 --width 64 --height 48 --camera-path {}",
            path.display()
        ),
    );
    let r = &records(&json)[0];
    assert_eq!(r["frames"].as_array().unwrap().len(), 4, "{r}");
    let text = std::fs::read_to_string(path_dir.join("results.txt")).unwrap();
    assert!(text.contains("camera along"), "{text}");
    std::fs::write(&path, "0 4 9\n").unwrap();
    rejects(
        &format!(
            "denoise --scene cubes --lights 4 --camera-path {}",
            path.display()
        ),
        "line 1",
    );
    rejects("denoise --frames 0", "--frames");
    rejects(
        "denoise --scene cubes --lights 4 --frames 1 --width 32 --height 32 --move-instance 100000",
        "--move-instance",
    );
}

/// `bench denoise --animation`: the built-in `walker` plays its walk beside a twin frozen at
/// 0 s, same run, each a record of its own (labelled), and the table sets the moving error
/// against the frozen one. Both start from the same pose, so their first frames score alike to
/// the bit; later ones differ (the figure walks in one only). Over virtual maps, so on every
/// backend. A scene without animations, or an animation it lacks, is refused by name.
#[test]
fn bench_denoise_plays_an_animation_beside_its_frozen_twin() {
    let (dir, json) = bench_ok(
        "denoise",
        "--technique virtual --scene walker --animation walk --lights 16 --frames 3 --width 96 \
         --height 72 --orbit 0 --reference off",
    );
    let rows = records(&json);
    assert_eq!(rows.len(), 2, "{json}");
    assert_eq!(rows[0]["animation"], "moving", "{json}");
    assert_eq!(rows[1]["animation"], "frozen", "{json}");
    let series = |r: &serde_json::Value| -> Vec<f64> {
        r["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                f["plain_every_rmse"]
                    .as_f64()
                    .expect("scored against every light")
            })
            .collect()
    };
    let (moving, frozen) = (series(&rows[0]), series(&rows[1]));
    eprintln!("bench denoise --animation: moving {moving:.3?}, frozen {frozen:.3?}");
    assert_eq!(moving[0], frozen[0], "both start at 0 s");
    assert!(
        moving[1..] != frozen[1..],
        "the moving sequence scores as the frozen one: {moving:?}"
    );
    let text = std::fs::read_to_string(dir.join("results.txt")).unwrap();
    assert!(
        text.contains("16 moving") && text.contains("16 lights, moving against frozen"),
        "{text}"
    );
    rejects(
        "denoise --scene cubes --animation walk --lights 4 --frames 2",
        "--animation",
    );
    rejects(
        "denoise --scene walker --animation run --lights 4 --frames 2",
        "walk",
    );
}
