//! `manyshadows bench layered` end to end on a tiny configuration: it measures every method it
//! was asked for, writes consistent JSON, a table and plots, and rejects bad arguments cleanly.

mod shared_gpu;

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("manyshadows-bench-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `manyshadows bench ARGS…` (`args` split at white space), then `extra`.
fn bench(args: &str, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .arg("bench")
        .args(args.split_whitespace())
        .args(extra)
        .output()
        .expect("run manyshadows")
}

/// `manyshadows bench COMMAND ARGS… --out-dir <a fresh directory>`, which must succeed without
/// a validation error and print and write a table naming the adapter; the directory and its
/// results.json.
fn bench_ok(command: &str, args: &str) -> (PathBuf, Value) {
    // A directory per command and arguments: tests of one command run side by side.
    let mut h = std::collections::hash_map::DefaultHasher::new();
    std::hash::Hash::hash(args, &mut h);
    let dir = tmp(&format!("{command}-{:x}", std::hash::Hasher::finish(&h)));
    let out = bench(
        &format!("{command} {args}"),
        &["--out-dir", dir.to_str().unwrap()],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "bench {args:?} failed: {stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
    assert!(
        stdout.contains("adapter:"),
        "every table names the adapter: {stdout}"
    );
    assert!(std::fs::read_to_string(dir.join("results.txt"))
        .unwrap()
        .contains("adapter:"));
    let json: Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
    assert!(json["adapter"].is_string(), "{json}");
    (dir, json)
}

/// results.json's records.
fn records(json: &Value) -> &Vec<Value> {
    json["records"].as_array().unwrap()
}

/// `manyshadows bench ARGS…` must fail cleanly (exit code 1, no panic), saying `needle`.
fn rejects(args: &str, needle: &str) {
    let out = bench(args, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected '{needle}' in {stderr}"
    );
}

/// `ratio` must be `time / base_time`, both GPU medians of `record`'s run (lavapipe and
/// llvmpipe GL both have timestamp queries, so the times must be there).
fn assert_ratio(ratio: &Value, time: &Value, base_time: &Value, record: &Value) {
    let time = time
        .as_f64()
        .unwrap_or_else(|| panic!("no GPU time on an adapter with timestamps: {record}"));
    let base = base_time
        .as_f64()
        .unwrap_or_else(|| panic!("no baseline GPU time beside {record}"));
    let want = time / base;
    let got = ratio
        .as_f64()
        .unwrap_or_else(|| panic!("no ratio in {record}"));
    assert!(
        (got - want).abs() <= 1e-9 * want.abs().max(1.0),
        "ratio {got} is not {time} / {base} ({want}): {record}"
    );
}

/// Every record's `ratio_key` must be its `time_key` over that of the `base_method` record
/// with the same `same` fields, recomputed here from the records' own medians. Returns how
/// many records other than the baseline's have one.
fn assert_ratios(
    records: &[Value],
    time_key: &str,
    ratio_key: &str,
    base_method: &str,
    same: &[&str],
) -> usize {
    let mut ratios = 0;
    for r in records {
        let base = records
            .iter()
            .find(|b| b["method"] == base_method && same.iter().all(|k| b[k] == r[k]))
            .unwrap_or_else(|| panic!("no {base_method} record beside {r}"));
        assert_ratio(&r[ratio_key], &r[time_key], &base[time_key], r);
        ratios += usize::from(r["method"] != base_method);
    }
    ratios
}

#[test]
fn bench_layered_writes_table_json_and_plots() {
    let (dir, json) = bench_ok(
        "layered",
        "--maps 1,3 --resolutions 128 --variants skinned,backface \
         --methods traditional,layered --repeats 2 --warmup 0",
    );
    assert_eq!(
        (json["repeats"].as_u64(), json["warmup"].as_u64()),
        (Some(2), Some(0))
    );
    let records = records(&json);
    // skinned: traditional + layered:none; backface: traditional + layered:none +
    // layered:backface; two map counts each.
    assert_eq!(records.len(), (2 + 3) * 2, "{json}");
    for r in records {
        let maps = r["maps"].as_u64().unwrap();
        assert_eq!(r["cpu_ms_runs"].as_array().unwrap().len(), 2, "repeats");
        assert!(r["cpu_ms"].as_f64().unwrap() > 0.0);
        // Every method generated every map: one view drawn per map.
        assert_eq!(r["stats"]["views_drawn"].as_u64().unwrap(), maps, "{r}");
        if r["method"] == "traditional" {
            assert_eq!(
                r["stats"]["passes"].as_u64().unwrap(),
                maps,
                "one pass per map"
            );
        } else {
            assert_eq!(
                r["stats"]["draws"].as_u64().unwrap(),
                1,
                "one draw for all maps"
            );
        }
    }
    // Ratios: every method's GPU time over traditional's for the same variant, resolution and
    // map count.
    let ratios = assert_ratios(
        records,
        "gpu_ms",
        "gpu_ratio_vs_traditional",
        "traditional",
        &["variant", "maps", "resolution"],
    );
    assert_eq!(ratios, 3 * 2, "one ratio per layered record");
    for variant in ["skinned", "backface"] {
        let png = dir.join(format!("layered-{variant}-128.png"));
        let img = image::open(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert_eq!((img.width(), img.height()), (1400, 1000));
    }
    assert!(std::fs::read_to_string(dir.join("results.txt"))
        .unwrap()
        .contains("traditional"));
}

#[test]
fn bench_layered_rejects_bad_arguments() {
    for (args, needle) in [
        ("--maps 0", "--maps 0"),
        ("--maps 5000", "--maps 5000"),
        ("--resolutions 3", "--resolutions 3"),
        ("--variants nope", "unknown variant"),
        ("--methods nope", "unknown technique"),
        ("--methods layered:sideways", "unknown cull mode"),
        ("--repeats 0", "--repeats"),
    ] {
        rejects(&format!("layered {args}"), needle);
    }
}

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

/// `bench virtual` on a tiny frame: both paths run in the same run, every light count gets a
/// record, the virtual side's pages add up (resident + denied = what the admission rule
/// admits or denies, resident within the pool, quarter pages four to a pool page), and a 1 MiB pool (16 pages) at 200 lights must
/// deny pages and say so.
#[test]
fn bench_virtual_reports_pages_memory_and_both_paths() {
    let (dir, json) = bench_ok(
        "virtual",
        "--scene cubes --lights 4,200 --width 160 --height 90 --page-pool 1 --repeats 1 --warmup 0",
    );
    let records = records(&json);
    assert_eq!(records.len(), 2, "{json}");
    for r in records {
        let s = &r["stats"];
        let needed: u64 = s["needed"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .sum();
        let (resident, denied) = (
            s["resident"].as_u64().unwrap(),
            s["denied"].as_u64().unwrap(),
        );
        // The admission rule (VirtualStats::asked): the finest level A whose marked pages fit
        // the pool with the asked pages of every coarser level is admitted whole, asked pages
        // coarser than A are resident, asked pages finer than A denied; ancestors no sample
        // asked for are drawn only at A. When not even level 0 fits, level 0 is placed (in
        // quarter pages, the rest denied) and every finer asked page is denied.
        let per_level = |key: &str| -> Vec<u64> {
            s[key]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap())
                .collect()
        };
        let (marked, asked) = (per_level("needed"), per_level("asked"));
        let pool = s["pool_pages"].as_u64().unwrap();
        let accounted = if marked[0] > pool {
            marked[0] + asked[1..].iter().sum::<u64>()
        } else {
            let mut coarser = 0;
            let mut a = 0;
            for (level, &m) in marked.iter().enumerate() {
                if coarser + m > pool {
                    break;
                }
                a = level;
                coarser += asked[level];
            }
            asked[..a].iter().sum::<u64>() + marked[a] + asked[a + 1..].iter().sum::<u64>()
        };
        assert_eq!(resident + denied, accounted, "{r}");
        assert!(accounted <= needed, "{r}");
        // Pool pages used: whole pages plus quarter pages four to one.
        let quarters = s["quarter_faces"].as_u64().unwrap();
        assert!(
            resident - quarters + quarters.div_ceil(4) <= s["pool_pages"].as_u64().unwrap(),
            "{r}"
        );
        assert_eq!(
            s["pool_pages"].as_u64().unwrap(),
            16,
            "1 MiB = 512² texels = 16 pages"
        );
        assert!(resident > 0, "{r}");
        // Memory kept: the page pool (1 MiB) plus the table (per entry its page, its farthest
        // receiver's key and the cells its samples reach: 12 bytes) against the atlas; every
        // map drawn anew, so no copy of last frame's table is kept.
        let table = s["fit"]["table_entries"].as_u64().unwrap();
        assert_eq!(s["table_bytes"].as_u64().unwrap(), 12 * table, "{r}");
        assert_eq!(s["prev_table_bytes"].as_u64().unwrap(), 0, "{r}");
        let v_mib = r["virtual_maps"]["shadow_mib"].as_f64().unwrap();
        let want = (s["pool_bytes"].as_u64().unwrap() + 12 * table) as f64 / (1u64 << 20) as f64;
        assert!(
            (v_mib - want).abs() < 1e-6 && (1.0..3.0).contains(&v_mib),
            "{r}"
        );
        assert!(r["atlas"]["shadow_mib"].as_f64().unwrap() > 0.0, "{r}");
        // The frame ratio comes from the two paths' medians in the same run.
        assert_ratio(
            &r["frame_ratio_virtual_vs_atlas"],
            &r["virtual_maps"]["frame_ms"],
            &r["atlas"]["frame_ms"],
            r,
        );
    }
    // 200 lights use hundreds of faces: not even a quarter page each fits, so the pool fills
    // with level-0 quarter pages (four faces to a pool page) and the faces beyond them are
    // counted unshadowed.
    let s = &records[1]["stats"];
    assert!(
        s["denied"].as_u64().unwrap() > 0,
        "200 lights cannot fit 16 pages: {s}"
    );
    assert_eq!(s["resident"].as_u64().unwrap(), 4 * 16, "{s}");
    assert_eq!(s["quarter_faces"].as_u64().unwrap(), 4 * 16, "{s}");
    assert!(s["unshadowed_faces"].as_u64().unwrap() > 0, "{s}");
    assert!(dir.join("virtual-cubes-160x90.png").is_file());
}

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

/// `bench virtual --cache`: both paths keep what did not change while the smallest caster
/// moves, so the measured (post-warm-up) frame of the virtual maps draws only some of its
/// resident pages and keeps the rest; the memory kept then counts last frame's page table
/// too (as large as the table). Without `--page-pool` the pool is as large as the atlas
/// (equal memory); `--page-pool 0` is refused naming the flag.
#[test]
fn bench_virtual_with_cache_measures_frames_that_keep_pages() {
    let (_, json) = bench_ok(
        "virtual",
        "--scene cubes --lights 8 --width 160 --height 90 --repeats 2 --warmup 1 --cache",
    );
    assert_eq!(json["cache"], true, "{json}");
    let records = records(&json);
    let s = &records[0]["stats"];
    let (drawn, kept, resident) = (
        s["drawn"].as_u64().unwrap(),
        s["kept"].as_u64().unwrap(),
        s["resident"].as_u64().unwrap(),
    );
    // A pool below one page is refused naming the flag, before any frame is measured.
    rejects(
        "virtual --scene cubes --lights 4 --width 32 --height 18 --page-pool 0",
        "--page-pool",
    );
    assert!(kept > 0 && drawn < resident, "{s}");
    assert_eq!(drawn + kept, resident, "{s}");
    let table = s["table_bytes"].as_u64().unwrap();
    assert_eq!(s["prev_table_bytes"].as_u64().unwrap(), table, "{s}");
    let atlas_mib = records[0]["atlas"]["shadow_mib"].as_f64().unwrap();
    let pool_mib = s["pool_bytes"].as_u64().unwrap() as f64 / (1u64 << 20) as f64;
    assert!(
        (pool_mib - atlas_mib).abs() < 1e-6,
        "pool {pool_mib} MiB, atlas {atlas_mib} MiB"
    );
    let mib = records[0]["virtual_maps"]["shadow_mib"].as_f64().unwrap();
    let want = (s["pool_bytes"].as_u64().unwrap() + 2 * table) as f64 / (1u64 << 20) as f64;
    assert!((mib - want).abs() < 1e-6, "{mib} MiB kept, want {want}");
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

/// `bench denoise` on a tiny sequence: every frame scored against the exact image of that
/// frame, the denoised frames closer than the plain ones on average (the denoiser's point:
/// measured on cubes with 48 lights, 96x72, 4 frames), the cost ratio from the same
/// sequence's medians; `--reference off` times only. Without ray queries it is refused naming
/// the feature.
#[test]
fn bench_denoise_scores_each_frame_of_a_sequence() {
    let args = "denoise --scene cubes --lights 48 --frames 4 --width 96 --height 72";
    let ctx = shared_gpu::context();
    let rays_here = shared_gpu::rays_here(&ctx);
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
