//! Whole runs: `bench soak`, `bench suite`, progress in a log, `bench estimate`.

use serde_json::Value;

use crate::helpers::{bench, bench_ok, records, rejects, tmp};

/// `bench soak` on a tiny frame: every frame renders while the camera, a caster, a light and
/// the light count change (the count halves at frame 200 of each 250, so 260 frames cover a
/// drop and a return), samples are written, and resident memory stays within the bound.
#[test]
fn bench_soak_runs_changing_frames_and_samples_memory() {
    let (_, json) = bench_ok(
        "soak",
        "--frames 260 --warmup 20 --lights 8 --width 32 --height 18 --cache",
    );
    let samples = json["samples"].as_array().unwrap();
    assert!(samples.len() >= 10, "{json}");
    assert_eq!(samples.last().unwrap()["frame"], 260);
    let lights: Vec<u64> = samples
        .iter()
        .map(|s| s["lights"].as_u64().unwrap())
        .collect();
    assert!(
        lights.contains(&4) && lights.contains(&8),
        "the count must change: {lights:?}"
    );
    // Measured over the 240 frames after warm-up: 0.0 MiB on lavapipe, 0.41 and 0.46 MiB on
    // llvmpipe GL (two runs each). Bound 2 MiB: a frame's G-buffer and targets leaked every
    // frame (about 23 KB at 32x18) would grow 5.5 MB over those frames and fail it.
    assert!(json["growth_mib"].as_f64().unwrap() < 2.0, "{json}");
    rejects("soak --frames 10 --warmup 20", "--frames must be larger");
}

/// `bench suite --quick`: its three sections run as their own bench commands into their own
/// directories, and suite.txt / suite.json gather them in order, each section naming the
/// adapter; a section that fails stops the suite with its name.
#[test]
fn bench_suite_gathers_its_sections() {
    let dir = tmp("suite");
    let out = bench("suite --quick", &["--out-dir", dir.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
    let txt = std::fs::read_to_string(dir.join("suite.txt")).unwrap();
    let names: Vec<&str> = txt
        .lines()
        .filter_map(|l| l.strip_prefix("## "))
        .map(|l| l.split(' ').next().unwrap())
        .collect();
    assert_eq!(names, ["layered", "omni", "shadows"], "{txt}");
    assert!(txt.matches("adapter:").count() >= 3, "{txt}");
    let json: Value =
        serde_json::from_slice(&std::fs::read(dir.join("suite.json")).unwrap()).unwrap();
    let sections = json["sections"].as_array().unwrap();
    assert_eq!(sections.len(), 3, "{json}");
    for s in sections {
        assert!(s["results"]["adapter"].is_string(), "{s}");
        let name = s["name"].as_str().unwrap();
        assert!(dir.join(name).join("results.json").is_file(), "{name}");
    }
    let bad = bench(
        "suite --quick --backend no-such-backend",
        &["--out-dir", tmp("suite-bad").to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success(), "{err}");
    assert!(err.contains("section layered"), "{err}");
}

/// Where stderr is no terminal (a log, CI, a remote runner) the progress bar draws nothing,
/// so each configuration and each technique being built is a line with the time so far: a
/// GPU run of `bench layered` was silent for 470 s (issue 42).
#[test]
fn bench_progress_is_printed_as_lines_in_a_log() {
    let dir = tmp("layered-lines");
    let out = bench(
        "layered --maps 1 --resolutions 64 --variants simple --methods traditional,layered \
         --repeats 1 --warmup 0",
        &["--out-dir", dir.to_str().unwrap()],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    for needle in [
        "] simple 64² ×1",
        "simple 64² ×1: building traditional",
        "simple 64² ×1: building layered",
    ] {
        assert!(stderr.contains(needle), "{needle}: {stderr}");
    }
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with('[') && l.contains(" s, ") && l.contains("%]")),
        "{stderr}"
    );
}

/// `bench estimate`: every configuration asked for is estimated before it is rendered and
/// then measured, its estimate's stages adding up to its frame; `--estimate-only` renders
/// nothing; a frame estimated past `--max-seconds` is skipped and said to be.
#[test]
fn bench_estimate_sets_each_estimate_beside_its_frame() {
    let total = |e: &Value| {
        ["gbuffer_ms", "clusters_ms", "shadows_ms", "lighting_ms"]
            .iter()
            .map(|k| e[k].as_f64().unwrap())
            .sum::<f64>()
    };
    let (dir, json) = bench_ok(
        "estimate",
        "--scenes courtyard --lights 3,12 --screens 64x36 --sizes soft,hard \
         --methods traditional,virtual --repeats 1 --warmup 0",
    );
    let records = records(&json);
    assert_eq!(records.len(), 2 * 2 * 2, "{json}");
    for r in records {
        let e = &r["estimate"];
        assert!(total(e) > 0.0, "{r}");
        assert_eq!(r["estimate"]["work"]["pixels"], 64 * 36, "{r}");
        assert!(
            r["estimate"]["work"]["pixel_lights"].as_u64().unwrap() > 0,
            "{r}"
        );
        let m = r["measured"].as_array().expect("measured stages");
        assert_eq!(m.len(), 4, "{r}");
        assert!(m.iter().all(|v| v.as_f64().unwrap() >= 0.0), "{r}");
        assert!(
            m.iter().map(|v| v.as_f64().unwrap()).sum::<f64>() > 0.0,
            "{r}"
        );
    }
    // Hard lights read no taps; the courtyard's sized lights read the blocker search and filter.
    let taps = |sizes: &str| {
        records
            .iter()
            .filter(|r| r["sizes"] == sizes && r["method"] == "traditional")
            .map(|r| r["estimate"]["work"]["taps"].as_u64().unwrap())
            .collect::<Vec<_>>()
    };
    assert!(taps("hard").iter().all(|&t| t == 0), "{json}");
    assert!(taps("soft").iter().all(|&t| t > 0), "{json}");
    let table = std::fs::read_to_string(dir.join("results.txt")).unwrap();
    assert!(
        table.contains("measured / estimated frame") || table.contains("x: measured"),
        "{table}"
    );

    let (_, only) = bench_ok(
        "estimate",
        "--scenes cubes --lights 3 --screens 64x36 --methods traditional --estimate-only",
    );
    let r = &records_of(&only)[0];
    assert!(
        r["measured"].is_null() && total(&r["estimate"]) > 0.0,
        "{r}"
    );

    let (_, skipped) = bench_ok(
        "estimate",
        "--scenes cubes --lights 3 --screens 64x36 --methods traditional --max-seconds 0.000001 \
         --repeats 1 --warmup 0",
    );
    assert!(records_of(&skipped)[0]["measured"].is_null(), "{skipped}");
    assert!(
        skipped["notes"].to_string().contains("past --max-seconds"),
        "{skipped}"
    );
    rejects("estimate --sizes medium", "--sizes 'medium'");
    rejects("estimate --methods virtual:k2", "traces none");
    rejects("estimate --methods raytraced:k0", "1 to 64");
    rejects("estimate --max-seconds 0", "--max-seconds");
}

fn records_of(json: &Value) -> Vec<Value> {
    records(json).clone()
}

/// `bench animation` on a small crowd: each technique's animated frames redraw some of their
/// views or pages every frame (the tubes bend), the frozen ones none, and the pose's CPU time
/// is measured for the animated frames only; with `--deform both`, the meshes bent on the GPU
/// (their bending pass timed) and on the CPU (no bending pass) in the same run. A scene where
/// nothing moves is refused, and so is an unknown `--deform`.
#[test]
fn bench_animation_measures_moving_against_frozen() {
    let (_, json) = bench_ok(
        "animation",
        "--crowd 4 --lights 8 --screen 64x36 --repeats 1 --warmup 1 --techniques traditional,virtual \
         --deform both",
    );
    let rows = json["records"].as_array().unwrap();
    assert_eq!(rows.len(), 6, "{json}");
    for r in rows {
        let drawn = r["drawn"].as_u64().unwrap();
        let bending = r["deform_gpu_ms"].as_f64();
        match (r["state"].as_str().unwrap(), r["deform"].as_str()) {
            ("animated", Some("gpu")) => {
                assert!(drawn > 0, "{r}");
                assert!(r["pose_cpu_ms"].as_f64().unwrap() > 0.0, "{r}");
                assert!(bending.is_some_and(|ms| ms > 0.0), "{r}");
            }
            ("animated-cpu", Some("cpu")) => {
                assert!(drawn > 0, "{r}");
                assert!(r["pose_cpu_ms"].as_f64().unwrap() > 0.0, "{r}");
                assert!(bending.is_none(), "{r}");
            }
            ("frozen", None) => assert!(drawn == 0 && bending.is_none(), "{r}"),
            other => panic!("unexpected state {other:?}: {r}"),
        }
    }
    rejects("animation --scene cubes", "nothing in it moves");
    rejects("animation --deform gpus", "--deform");
}
