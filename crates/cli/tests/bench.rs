//! `manyshadows bench layered` end to end on a tiny configuration: it measures every method it
//! was asked for, writes consistent JSON, a table and plots, and rejects bad arguments cleanly.

use std::path::PathBuf;
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("manyshadows-bench-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn bench(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .arg("bench")
        .arg("layered")
        .args(args)
        .output()
        .expect("run manyshadows")
}

#[test]
fn bench_layered_writes_table_json_and_plots() {
    let dir = tmp("run");
    let out = bench(&[
        "--maps",
        "1,3",
        "--resolutions",
        "128",
        "--variants",
        "skinned,backface",
        "--methods",
        "traditional,layered",
        "--repeats",
        "2",
        "--warmup",
        "0",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "bench failed: {stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
    assert!(
        stdout.contains("adapter:"),
        "every table names the adapter: {stdout}"
    );

    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
    let records = json["records"].as_array().unwrap();
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
    // Ratios: every method's GPU time over traditional's for the same variant and map count,
    // recomputed here from the records' own medians (lavapipe and llvmpipe GL both have
    // timestamp queries, so the times must be there).
    let mut ratios = 0;
    for r in records {
        let gpu = r["gpu_ms"]
            .as_f64()
            .unwrap_or_else(|| panic!("no GPU time on an adapter with timestamps: {r}"));
        let base = records
            .iter()
            .find(|b| {
                b["method"] == "traditional"
                    && b["variant"] == r["variant"]
                    && b["maps"] == r["maps"]
                    && b["resolution"] == r["resolution"]
            })
            .unwrap_or_else(|| panic!("no traditional record beside {r}"));
        let want = gpu / base["gpu_ms"].as_f64().unwrap();
        let got = r["gpu_ratio_vs_traditional"]
            .as_f64()
            .unwrap_or_else(|| panic!("no ratio in {r}"));
        assert!(
            (got - want).abs() <= 1e-9 * want.abs().max(1.0),
            "ratio {got} is not gpu_ms / traditional's ({want}): {r}"
        );
        ratios += usize::from(r["method"] != "traditional");
    }
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
        (vec!["--maps", "0"], "--maps 0"),
        (vec!["--maps", "5000"], "--maps 5000"),
        (vec!["--resolutions", "3"], "--resolutions 3"),
        (vec!["--variants", "nope"], "unknown variant"),
        (vec!["--methods", "raytraced"], "unknown technique"),
        (vec!["--methods", "layered:sideways"], "unknown cull mode"),
        (vec!["--repeats", "0"], "--repeats"),
    ] {
        let out = bench(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(
            stderr.contains(needle),
            "{args:?}: expected '{needle}' in {stderr}"
        );
    }
}

#[test]
fn bench_omni_compares_cube_and_paraboloid_per_light() {
    let dir = tmp("omni");
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "bench",
            "omni",
            "--lights",
            "1,2",
            "--resolution",
            "64",
            "--methods",
            "cube:traditional,dp:traditional,dp:layered",
            "--repeats",
            "1",
            "--warmup",
            "0",
            "--out-dir",
            dir.to_str().unwrap(),
        ])
        .output()
        .expect("run manyshadows");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench omni failed: {stderr}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
    let records = json["records"].as_array().unwrap();
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
    assert!(dir.join("omni-atrium-64.png").exists());
    let bad = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(["bench", "omni", "--methods", "sphere:traditional"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("unknown mode"));
}

#[test]
fn bench_irregular_times_frames_against_traditional() {
    let dir = tmp("irregular");
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "bench",
            "irregular",
            "--scene",
            "cubes",
            "--lights",
            "2",
            "--screens",
            "96x64",
            "--methods",
            "irregular,traditional@512",
            "--repeats",
            "1",
            "--warmup",
            "0",
            "--out-dir",
            dir.to_str().unwrap(),
        ])
        .output()
        .expect("run manyshadows");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench irregular failed: {stderr}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
    let records = json["records"].as_array().unwrap();
    assert_eq!(records.len(), 2, "{json}");
    for r in records {
        assert_eq!(
            r["frame_ms_runs"].as_array().unwrap().len(),
            usize::from(r["frame_gpu_ms"].is_number())
        );
    }
    // Each frame's ratio is its GPU time over traditional@512's at the same light count,
    // recomputed from the records (both CI adapters have timestamps, so the times exist).
    for r in records {
        let gpu = r["frame_gpu_ms"]
            .as_f64()
            .unwrap_or_else(|| panic!("no frame GPU time: {r}"));
        let base = records
            .iter()
            .find(|b| {
                b["method"] == "traditional@512"
                    && b["lights"] == r["lights"]
                    && b["screen"] == r["screen"]
            })
            .unwrap_or_else(|| panic!("no traditional@512 record beside {r}"));
        let want = gpu / base["frame_gpu_ms"].as_f64().unwrap();
        let got = r["ratio_vs_traditional_512"].as_f64().expect("a ratio");
        assert!(
            (got - want).abs() <= 1e-9 * want.max(1.0),
            "{got} vs {want}: {r}"
        );
    }
    assert!(dir.join("irregular-96x64.png").exists());
    let bad = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(["bench", "irregular", "--methods", "traditional@huge"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("bad resolution"));
}

#[test]
fn bench_lights_reports_stages_clusters_and_fit_per_count() {
    let dir = tmp("lights");
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "bench", "lights", "--scenes", "dragon", "--lights", "16,200",
        ])
        .args(["--screens", "96x54", "--repeats", "1", "--warmup", "0"])
        .args(["--reference-up-to", "16", "--shadow-resolution", "64"])
        .args(["--out-dir", dir.to_str().unwrap()])
        .output()
        .expect("run manyshadows");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench failed: {stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
    let records = json["records"].as_array().unwrap();
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
    }
    assert!(dir.join("lights-dragon-96x54.png").is_file());
    assert!(std::fs::read_to_string(dir.join("results.txt"))
        .unwrap()
        .contains("adapter:"));
}

/// `bench virtual` on a tiny frame: both paths run in the same run, every light count gets a
/// record, the virtual side's pages add up (rendered + denied = needed, rendered within the
/// pool), and a 1 MiB pool (16 pages) at 200 lights must deny pages and say so.
#[test]
fn bench_virtual_reports_pages_memory_and_both_paths() {
    let dir = tmp("virtual");
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(["bench", "virtual", "--scene", "cubes", "--lights", "4,200"])
        .args(["--width", "160", "--height", "90", "--page-pool", "1"])
        .args(["--repeats", "1", "--warmup", "0"])
        .args(["--out-dir", dir.to_str().unwrap()])
        .output()
        .expect("run manyshadows");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench failed: {stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
    let records = json["records"].as_array().unwrap();
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
        assert_eq!(resident + denied, needed, "{r}");
        assert!(resident <= s["pool_pages"].as_u64().unwrap(), "{r}");
        assert_eq!(
            s["pool_pages"].as_u64().unwrap(),
            16,
            "1 MiB = 512² texels = 16 pages"
        );
        assert!(resident > 0, "{r}");
        // Memory kept: the page pool (1 MiB) plus the table against the atlas.
        let v_mib = r["virtual_maps"]["shadow_mib"].as_f64().unwrap();
        assert!((1.0..2.0).contains(&v_mib), "{r}");
        assert!(r["atlas"]["shadow_mib"].as_f64().unwrap() > 0.0, "{r}");
    }
    // 200 lights use hundreds of faces: not even one page each fits, so the pool fills with
    // level-0 pages and the faces beyond it are counted unshadowed.
    let s = &records[1]["stats"];
    assert!(
        s["denied"].as_u64().unwrap() > 0,
        "200 lights cannot fit 16 pages: {s}"
    );
    assert_eq!(s["resident"].as_u64().unwrap(), 16, "{s}");
    assert!(s["unshadowed_faces"].as_u64().unwrap() > 0, "{s}");
    assert!(dir.join("virtual-cubes-160x90.png").is_file());
    assert!(std::fs::read_to_string(dir.join("results.txt"))
        .unwrap()
        .contains("adapter:"));
}

/// `bench soak` on a tiny frame: every frame renders while the camera, a caster, a light and
/// the light count change (the count halves at frame 200 of each 250, so 260 frames cover a
/// drop and a return), samples are written, and resident memory stays within the bound.
#[test]
fn bench_soak_runs_changing_frames_and_samples_memory() {
    let dir = tmp("soak");
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "bench", "soak", "--frames", "260", "--warmup", "20", "--lights", "8",
        ])
        .args(["--width", "32", "--height", "18", "--cache"])
        .args(["--out-dir", dir.to_str().unwrap()])
        .output()
        .expect("run manyshadows");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "soak failed: {stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
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
    assert!(json["growth_mib"].as_f64().unwrap() < 64.0, "{json}");
    let bad = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(["bench", "soak", "--frames", "10", "--warmup", "20"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--frames must be larger"));
}
