//! The benches of one technique or feature: omni, irregular, stereo, probes, lights, soft.

use crate::helpers::{assert_ratio, assert_ratios, bench, bench_ok, records, rejects};

#[test]
fn bench_omni_compares_cube_and_paraboloid_per_light() {
    let (dir, json) = bench_ok(
        "omni",
        "--lights 1,2 --resolution 64 --methods cube:traditional,dp:traditional,dp:layered \
         --repeats 1 --warmup 0",
    );
    let records = records(&json);
    assert_eq!(records.len(), 6, "{json}");
    for r in records {
        let lights = r["lights"].as_u64().unwrap();
        let per_light = if r["method"] == "cube:traditional" {
            6
        } else {
            2
        };
        assert_eq!(r["views"].as_u64().unwrap(), per_light * lights, "{r}");
        // Memory per light: six 64² faces or two 128² hemispheres of 4-byte depth.
        let expected = if per_light == 6 {
            6 * 64 * 64 * 4
        } else {
            2 * 128 * 128 * 4
        };
        assert_eq!(
            r["memory_bytes_per_light"].as_f64().unwrap(),
            expected as f64,
            "{r}"
        );
    }
    // Each method's GPU time over six cube passes' at the same light count.
    let ratios = assert_ratios(
        records,
        "gpu_ms",
        "gpu_ratio_vs_cube_traditional",
        "cube:traditional",
        &["lights"],
    );
    assert_eq!(ratios, 2 * 2, "{json}");
    assert!(dir.join("omni-atrium-64.png").exists());
    rejects("omni --methods sphere:traditional", "unknown mode");
}

#[test]
fn bench_irregular_times_frames_against_traditional() {
    let (dir, json) = bench_ok(
        "irregular",
        "--scene cubes --lights 2 --screens 96x64 --methods irregular,traditional@512 \
         --repeats 1 --warmup 0",
    );
    let records = records(&json);
    assert_eq!(records.len(), 2, "{json}");
    for r in records {
        assert_eq!(
            r["frame_ms_runs"].as_array().unwrap().len(),
            usize::from(r["frame_gpu_ms"].is_number())
        );
    }
    // Each frame's ratio is its GPU time over traditional@512's at the same light count and
    // screen.
    let ratios = assert_ratios(
        records,
        "frame_gpu_ms",
        "ratio_vs_traditional_512",
        "traditional@512",
        &["lights", "screen"],
    );
    assert_eq!(ratios, 1, "{json}");
    assert!(dir.join("irregular-96x64.png").exists());
    rejects("irregular --methods traditional@huge", "bad resolution");
}

#[test]
fn bench_stereo_times_one_pass_against_one_per_eye() {
    let (dir, json) = bench_ok(
        "stereo",
        "--scenes cubes --eyes 64x36 --lights 2 --repeats 1 --warmup 0",
    );
    let records = records(&json);
    // A mono eye, per-eye, and each one-pass way the adapter has (layered: Vulkan and GL;
    // multiview: Vulkan); the ones left out are noted by name.
    let methods: Vec<&str> = records
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert!(
        methods.starts_with(&["mono (one eye)", "per-eye"]),
        "{json}"
    );
    assert!(methods.contains(&"layered"), "{json}");
    let notes = json["notes"].to_string();
    assert!(
        methods.contains(&"multiview") || notes.contains("multiview left out"),
        "{json}"
    );
    // The G-buffer's and the frame's ratios are their medians over per-eye's.
    assert_ratios(
        records,
        "gbuffer_gpu_ms",
        "gbuffer_ratio_vs_per_eye",
        "per-eye",
        &["scene", "eye"],
    );
    assert_ratios(
        records,
        "frame_gpu_ms",
        "frame_ratio_vs_per_eye",
        "per-eye",
        &["scene", "eye"],
    );
    assert!(dir.join("stereo-cubes.png").exists());
    rejects("stereo --scenes nowhere", "not a built-in scene");
    rejects("stereo --separation -1", "--separation");
}

#[test]
fn bench_probes_times_every_way_of_drawing_the_faces() {
    let (dir, json) = bench_ok(
        "probes",
        "--scene cubes --probes 1,2 --sides 16 --lights 2 --screen 48x27 --repeats 1 --warmup 0",
    );
    let records = records(&json);
    // Per probe count: per-face, layered (CLIP_DISTANCES: Vulkan and GL here), multiview
    // where six views fit one pass (Vulkan here), or a note that says why not, and
    // gpu-driven (CLIP_DISTANCES and indirect draws: Vulkan and GL here).
    let methods: Vec<&str> = records
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert!(methods.starts_with(&["per-face", "layered"]), "{json}");
    assert!(methods.contains(&"gpu-driven"), "{json}");
    let multiview = methods.contains(&"multiview");
    assert!(
        multiview || json["notes"].to_string().contains("multiview left out"),
        "{json}"
    );
    assert_eq!(records.len(), if multiview { 8 } else { 6 }, "{json}");
    for r in records {
        // A caster moves every frame, so every face is drawn: the probes stage is timed.
        assert!(r["probes_gpu_ms"].as_f64().is_some_and(|t| t > 0.0), "{r}");
    }
    assert_ratios(
        records,
        "probes_gpu_ms",
        "probes_ratio_vs_per_face",
        "per-face",
        &["probes", "side"],
    );
    assert!(dir.join("probes-16x16.png").exists());
    rejects("probes --sides 4", "8 to 1024");
    rejects("probes --probes 65", "--probes");
}

#[test]
fn bench_lights_reports_stages_clusters_and_fit_per_count() {
    let (dir, json) = bench_ok(
        "lights",
        "--scenes dragon --lights 16,200 --screens 96x54 --repeats 1 --warmup 0 \
         --reference-up-to 16 --shadow-resolution 64",
    );
    let records = records(&json);
    assert_eq!(records.len(), 2, "{json}");
    for r in records {
        let n = r["lights"].as_u64().unwrap();
        let fit = &r["fit"];
        let accounted: u64 = ["full", "reduced", "unshadowed", "off_screen"]
            .iter()
            .map(|k| fit[k].as_u64().unwrap())
            .sum();
        assert_eq!(accounted, n, "every shadowed light is accounted for: {r}");
        assert!(r["mean_lights_per_cluster"].as_f64().unwrap() <= n as f64);
        assert!(r["max_lights_per_cluster"].as_u64().unwrap() <= n);
        // The reference loop is timed only up to --reference-up-to.
        assert_eq!(r["lighting_all_ms"].is_null(), n > 16, "{r}");
        assert!(r["wall_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
    assert!(dir.join("lights-dragon-96x54.png").is_file());
}

/// `bench soft` on a tiny frame: per technique and light count the hard frame and one PCSS
/// frame per `--taps` entry (N of each, or B/F), in one run, with ratios from the same run's medians; sizes from
/// the flags (`cubes` is hard of its own); bad tap counts are refused naming the flag.
#[test]
fn bench_soft_times_pcss_against_hard_frames() {
    let (_, json) = bench_ok(
        "soft",
        "--scene cubes --lights 3,12 --width 96 --height 54 --light-size 0.1 --sun-size 1 \
         --taps 4,16/8 --repeats 1 --warmup 0",
    );
    let records = records(&json);
    let cells: Vec<(String, u64)> = records
        .iter()
        .map(|r| {
            (
                r["technique"].as_str().unwrap().to_string(),
                r["lights"].as_u64().unwrap(),
            )
        })
        .collect();
    let want: Vec<(String, u64)> = [3, 12]
        .iter()
        .flat_map(|&n| ["traditional", "virtual"].map(|t| (t.to_string(), n)))
        .collect();
    assert_eq!(cells, want, "{json}");
    for r in records {
        assert_eq!(r["sized_lights"], r["lights"], "every light sized: {r}");
        let sides = r["sides"].as_array().unwrap();
        let methods: Vec<&str> = sides
            .iter()
            .map(|s| s["method"].as_str().unwrap())
            .collect();
        assert_eq!(methods, ["hard", "pcss-4", "pcss-16/8"], "{r}");
        let taps: Vec<(u64, u64)> = sides
            .iter()
            .map(|s| {
                let t = |k: &str| s[k].as_u64().unwrap();
                (t("blocker_taps"), t("filter_taps"))
            })
            .collect();
        assert_eq!(taps, [(0, 0), (4, 4), (16, 8)], "{r}");
        for s in sides {
            assert_ratio(&s["ratio"], &s["frame_ms"], &sides[0]["frame_ms"], s);
            assert_ratio(
                &s["lighting_ratio"],
                &s["lighting_ms"],
                &sides[0]["lighting_ms"],
                s,
            );
        }
    }
    rejects("soft --taps 0", "--taps 0");
    rejects("soft --taps 65", "--taps 65");
    rejects("soft --taps 16/65", "--taps 16/65");
    // Not a count or a pair: clap's usage error (exit 2), naming the value.
    let out = bench("soft --taps 16/8/4", &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("'16/8/4'") && stderr.contains("B/F"),
        "{stderr}"
    );
    rejects("soft --max-penumbra 0.5", "--max-penumbra");
}
