//! The `manyshadows` binary end to end: it renders, writes what it promises, and turns bad
//! input into a one-line error with exit code 1 (2 for argument errors), never a panic.

use std::path::PathBuf;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("manyshadows-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run manyshadows")
}

/// `run`, which must succeed (its stderr is the failure message).
fn run_ok(args: &[&str]) -> Output {
    let out = run(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn assert_clean_failure(out: &Output, code: i32, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "exit code; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert!(
        !stderr.contains("Validation Error"),
        "GPU validation error: {stderr}"
    );
    assert!(
        stderr.to_lowercase().contains(&needle.to_lowercase()),
        "expected '{needle}' in: {stderr}"
    );
}

#[test]
fn renders_frame_atlas_and_visibility() {
    let dir = tmp("render");
    let frame = dir.join("frame.png");
    let atlas = dir.join("atlas.png");
    let vis = dir.join("vis");
    let json = dir.join("summary.json");
    let out = run(&[
        "render",
        "--scene",
        "cubes",
        "--width",
        "96",
        "--height",
        "64",
        "--out",
        frame.to_str().unwrap(),
        "--atlas-out",
        atlas.to_str().unwrap(),
        "--visibility-out",
        vis.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for needle in ["adapter", "10 views", "atlas", "GPU time", "CPU record"] {
        assert!(
            stdout.contains(needle),
            "summary lacks '{needle}':\n{stdout}"
        );
    }
    assert_eq!(image::open(&frame).unwrap().width(), 96);
    assert!(image::open(&atlas).unwrap().width() >= 16);
    let raw = std::fs::read(vis.join("visibility.msvis")).unwrap();
    let mask = manyshadows::VisibilityMask::read_raw(&raw).unwrap();
    assert_eq!((mask.width, mask.height, mask.lights), (96, 64, 3));
    let pngs = std::fs::read_dir(&vis)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "png")
        })
        .count();
    assert_eq!(pngs, 3);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(
        summary["shadow_views"],
        1 + 6 + 3,
        "spot + point + 3 cascades"
    );
}

#[test]
fn info_lists_the_chosen_adapter() {
    let out = run(&["info"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("chosen:")
            && stdout.contains("max_texture_dimension_2d")
            && stdout.contains("TIMESTAMP_QUERY"),
        "{stdout}"
    );
}

#[test]
fn missing_scene_file() {
    assert_clean_failure(
        &run(&["render", "--scene", "/nonexistent/scene.toml"]),
        1,
        "cannot read",
    );
}

#[test]
fn unknown_builtin_scene_lists_the_names() {
    assert_clean_failure(&run(&["render", "--scene", "sponza"]), 1, "atrium");
}

#[test]
fn malformed_toml() {
    let dir = tmp("toml");
    let path = dir.join("bad.toml");
    std::fs::write(&path, "[[light]]\ntype = \"spot\"\nposition = [0, 1\n").unwrap();
    assert_clean_failure(
        &run(&["render", "--scene", path.to_str().unwrap()]),
        1,
        "bad.toml",
    );
}

#[test]
fn malformed_meshes() {
    let dir = tmp("mesh");
    for (name, bytes) in [
        ("bad.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 9\n".as_slice()),
        ("bad.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nend_header\n\x01\x02".as_slice()),
        ("bad.glb", b"glTF\x02\x00\x00\x00garbage".as_slice()),
        ("bad.ply.gz", b"not gzip at all".as_slice()),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = run(&["render", "--scene", "dragon", "--mesh", path.to_str().unwrap(), "--width", "32", "--height", "32"]);
        assert_clean_failure(&out, 1, name);
    }
}

#[test]
fn absurd_numbers() {
    assert_clean_failure(
        &run(&["render", "--scene", "cubes", "--lights", "100000"]),
        1,
        "16384",
    );
    assert_clean_failure(
        &run(&["render", "--scene", "cubes", "--width", "100000"]),
        1,
        "resolution",
    );
    assert_clean_failure(
        &run(&["render", "--scene", "cubes", "--shadow-resolution", "0"]),
        1,
        "resolution",
    );
    assert_clean_failure(&run(&["render", "--pcf", "5x5"]), 2, "pcf");
    assert_clean_failure(&run(&["render", "--technique", "magic"]), 2, "traditional");
    assert_clean_failure(&run(&["render", "--light-types", "laser"]), 1, "laser");
}

#[test]
fn zero_lights_is_fine() {
    let dir = tmp("zero");
    let out = run(&[
        "render",
        "--scene",
        "cubes",
        "--lights",
        "0",
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        dir.join("f.png").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Values that could only be changed silently are refused before the scene is loaded (a
/// missing scene file would otherwise be the error reported), and an --atlas-max that is not
/// a power of two is used as the next smaller one, with a note saying so.
#[test]
fn silently_changed_values_are_refused_or_announced() {
    let missing = "no-such-scene-file.toml";
    for (flag, value, needle) in [
        ("--frames", "0", "--frames must be at least 1"),
        (
            "--irregular-hash",
            "0",
            "--irregular-hash: irregular.hash 0 is out of range: at least 1",
        ),
        (
            "--page-pool",
            "0",
            "--page-pool (MiB): virtual_maps.pool_bytes 0 is out of range",
        ),
        (
            "--atlas-max",
            "8",
            "--atlas-max: max_atlas_size 8 is out of range",
        ),
        (
            "--shadow-budget",
            "0",
            "--shadow-budget: shadow_budget 0 is out of range",
        ),
    ] {
        assert_clean_failure(
            &run(&["render", "--scene", missing, flag, value]),
            1,
            needle,
        );
    }
    let dir = tmp("atlas-max-note");
    let out = run(&[
        "render",
        "--scene",
        "plane-spot",
        "--width",
        "32",
        "--height",
        "32",
        "--atlas-max",
        "3000",
        "--json",
        dir.join("s.json").to_str().unwrap(),
        "--out",
        dir.join("f.png").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--atlas-max 3000 is used as 2048"),
        "no note: {stderr}"
    );
}

/// `--limits webgpu` creates the device with a browser's default limits: `info` reports them
/// and the compute rasterizer (the pass with the most storage buffers) renders within them.
#[test]
fn webgpu_limits_are_enough_for_every_pass() {
    let out = run(&["info", "--limits", "webgpu"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout
            .lines()
            .any(|l| l.split_whitespace().collect::<Vec<_>>()
                == ["max_storage_buffers_per_stage", "8"]),
        "{stdout}"
    );
    let dir = tmp("webgpu-limits");
    let out = run(&[
        "render",
        "--limits",
        "webgpu",
        "--scene",
        "cubes",
        "--technique",
        "compute",
        "--width",
        "48",
        "--height",
        "32",
        "--out",
        dir.join("f.png").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("GPU error"), "{stderr}");
}

#[test]
fn each_cause_is_printed_once() {
    let out = run(&["render", "--scene", "no-such-scene-file.toml"]);
    assert_clean_failure(&out, 1, "no-such-scene-file.toml");
    let stderr = String::from_utf8_lossy(&out.stderr);
    // The operating system's reason, once (it was printed twice, by the error and its source).
    let reason = std::io::Error::from(std::io::ErrorKind::NotFound).to_string();
    let os = "(os error 2)";
    assert_eq!(
        stderr.matches(os).count(),
        1,
        "the cause '{reason}' should appear once: {stderr}"
    );
}

/// A frame far beyond the rest (every one of 257,596 triangles in each of 36,499 views, 9.4 G
/// pairs) is refused before anything is drawn, with its estimate and the techniques that
/// scale; `--insist` is the way past it (not run here: it takes minutes).
#[test]
fn a_ten_minute_frame_is_refused_with_its_estimate() {
    let out = run(&[
        "render",
        "--lights",
        "16384",
        "--technique",
        "layered",
        "--width",
        "64",
        "--height",
        "36",
        // Without the atrium's probes, which give every light a map (43,693 views).
        "--probes",
        "0",
        "--out",
        "/dev/null",
    ]);
    assert_clean_failure(&out, 1, "would take 9.4 G (caster triangle, view) pairs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    for needle in ["36499 views", "traditional, gpu-driven", "--insist"] {
        assert!(stderr.contains(needle), "{needle}: {stderr}");
    }
}

/// Irregular shadow maps test every caster triangle against every light view (one thread per
/// pair): at 16,384 lights, 320 × 180, they ran for minutes without a word (issue 42). Now
/// the frame is estimated and refused before anything is drawn, and the refusal recommends
/// only techniques that scale (not irregular itself).
#[test]
fn irregular_maps_of_thousands_of_lights_are_estimated_and_refused() {
    let started = std::time::Instant::now();
    let out = run(&[
        "render",
        "--lights",
        "16384",
        "--technique",
        "irregular",
        "--width",
        "320",
        "--height",
        "180",
        "--out",
        "/dev/null",
    ]);
    assert_clean_failure(&out, 1, "technique irregular would take 9.4 G");
    let stderr = String::from_utf8_lossy(&out.stderr);
    for needle in [
        "estimated ~",
        "36499 views",
        "every light view's grid of samples",
        "virtual, raytraced scale",
        "--insist",
    ] {
        assert!(stderr.contains(needle), "{needle}: {stderr}");
    }
    assert!(
        !stderr.contains("irregular, virtual"),
        "the refusal recommends the refused technique: {stderr}"
    );
    eprintln!("refused after {:.1} s", started.elapsed().as_secs_f64());
}

/// A frame whose per-view work is modest but whose time is not (every one of 16,384 lights'
/// pairs in reach traced with 16x16 rays over the light's shape at 3840x2160: some 24 G rays)
/// is refused by its estimated time, naming the stage that costs most and what shrinks it.
/// The costs were measured on lavapipe, so only a CPU adapter refuses by time; on another
/// the summary says the estimate is lavapipe's, and the huge frame is not tried.
#[test]
fn a_frame_estimated_past_ten_minutes_is_refused_with_the_stage_that_costs() {
    let png = tmp("estimate-small").join("cubes.png");
    let small = run_ok(&[
        "render",
        "--scene",
        "cubes",
        "--width",
        "32",
        "--height",
        "18",
        "--out",
        png.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&small.stdout);
    let line = |label: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(label))
            .unwrap_or_else(|| panic!("no '{label}' line in\n{stdout}"))
            .to_string()
    };
    let estimate = line("estimate ");
    assert!(
        estimate.contains(" ms ") && estimate.contains("shadows"),
        "{estimate}"
    );
    if !line("adapter ").contains(", Cpu,") {
        assert!(estimate.contains("lavapipe's costs"), "{estimate}");
        eprintln!("not a CPU adapter: its estimates are lavapipe's and refuse nothing by time");
        return;
    }
    assert!(estimate.contains("on this adapter"), "{estimate}");
    let out = run(&[
        "render",
        "--lights",
        "16384",
        "--technique",
        "raytraced",
        "--area-samples",
        "16",
        "--width",
        "3840",
        "--height",
        "2160",
        "--out",
        "/dev/null",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if stderr.contains("needs the") {
        // No ray queries here: refused by name before any estimate (checked elsewhere).
        assert_clean_failure(&out, 1, "EXPERIMENTAL_RAY_QUERY");
        return;
    }
    assert_clean_failure(&out, 1, "technique raytraced is estimated at ~");
    for needle in [
        "min on this adapter",
        "most of it lighting",
        "--light-samples K",
        "--insist",
    ] {
        assert!(stderr.contains(needle), "{needle}: {stderr}");
    }
}

/// A page pool that is not a square of whole pages is announced with what is used (512 MiB:
/// 11520², 8,100 pages — a power-of-two pool would have kept 4,096); the default is exact.
#[test]
fn a_rounded_page_pool_is_announced() {
    let dir = tmp("page-pool-note");
    let args = |pool: &'static str| {
        [
            "render",
            "--scene",
            "cubes",
            "--technique",
            "virtual",
            "--width",
            "32",
            "--height",
            "32",
            "--page-pool",
            pool,
        ]
    };
    let out_path = dir.join("f.png");
    let mut a = args("512").to_vec();
    a.extend(["--out", out_path.to_str().unwrap()]);
    let out = run(&a);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--page-pool 512 MiB is used as a 11520² pool of 8100 pages"),
        "no note: {stderr}"
    );
    let mut a = args("256").to_vec();
    a.extend(["--out", out_path.to_str().unwrap()]);
    let out = run(&a);
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("--page-pool"));
}

/// `--shadow-budget` with `--frames`: each frame's line says how many views were drawn (at
/// most the budget), how many wait stale and how many wait with no shadow yet.
#[test]
fn a_shadow_budget_reports_each_frames_waiting_views() {
    let dir = tmp("shadow-budget");
    let out = run(&[
        "render",
        "--scene",
        "cubes",
        "--lights",
        "8",
        "--width",
        "64",
        "--height",
        "36",
        "--frames",
        "3",
        "--shadow-budget",
        "4",
        "--out",
        dir.join("f.png").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("frame ")).collect();
    assert_eq!(lines.len(), 3, "{err}");
    assert!(
        lines[0].contains("   4 of ") && lines[0].contains("waiting, unshadowed"),
        "{err}"
    );
}

/// Caching is the default: with `--frames`, a frame after the first redraws only the views
/// that see the moving caster; `--no-cache` redraws every view every frame, and refuses a
/// shadow budget (which needs the kept tiles).
#[test]
fn frames_keep_unchanged_views_unless_no_cache() {
    let dir = tmp("no-cache");
    let out = dir.join("f.png");
    let frames = |extra: &[&str]| -> Vec<(u32, u32)> {
        let mut a = vec![
            "render", "--scene", "cubes", "--width", "64", "--height", "36", "--frames", "3",
        ];
        a.extend(extra);
        a.extend(["--out", out.to_str().unwrap()]);
        let o = run(&a);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(o.status.success(), "{err}");
        // "frame   2:    7 of 10 shadow views redrawn, ..."
        err.lines()
            .filter_map(|l| l.strip_prefix("frame "))
            .map(|l| {
                let w: Vec<&str> = l.split_whitespace().collect();
                (w[1].parse().expect("drawn"), w[3].parse().expect("views"))
            })
            .collect()
    };
    let kept = frames(&[]);
    let anew = frames(&["--no-cache"]);
    eprintln!("default {kept:?}, --no-cache {anew:?}");
    assert_eq!((kept.len(), anew.len()), (3, 3));
    assert_eq!(kept[0].0, kept[0].1, "the first frame draws every view");
    assert!(kept[1..].iter().all(|&(k, v)| k < v), "{kept:?}");
    assert!(anew.iter().all(|&(k, v)| k == v && v > 0), "{anew:?}");
    let refused = run(&[
        "render",
        "--scene",
        "cubes",
        "--no-cache",
        "--shadow-budget",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clean_failure(&refused, 2, "cannot be used with");
}

/// The summary says what each technique did and nothing it did not: an atlas and passes for
/// the map techniques, pages for virtual maps, lists for irregular maps (no atlas, no passes),
/// rays without a map; a soft-shadow line only where lights are sized, saying what the
/// technique makes of them. Every line is checked for every technique the adapter runs.
#[test]
fn the_summary_of_each_technique_is_its_own() {
    let techniques = run(&["render", "--help"]);
    let help = String::from_utf8_lossy(&techniques.stdout).to_string();
    for t in [
        "traditional",
        "layered",
        "multiview",
        "gpu-driven",
        "compute",
        "irregular",
        "virtual",
        "raytraced",
    ] {
        assert!(help.contains(t), "render --help does not list {t}");
        let out = run(&[
            "render",
            "--technique",
            t,
            "--lights",
            "6",
            "--width",
            "96",
            "--height",
            "54",
            "--frames",
            "2",
            "--out",
            tmp(&format!("summary-{t}"))
                .join("frame.png")
                .to_str()
                .unwrap(),
        ]);
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        if !out.status.success() {
            // Refused by name on a device without what the technique needs.
            assert!(err.contains(&format!("technique {t} needs")), "{t}: {err}");
            continue;
        }
        let has = |label: &str| text.lines().any(|l| l.starts_with(label));
        let line = |label: &str| {
            text.lines()
                .find(|l| l.starts_with(label))
                .unwrap_or_else(|| panic!("{t}: no '{label}' line in\n{text}"))
                .to_string()
        };
        for label in [
            "adapter", "scene", "lights", "shadows", "clusters", "GPU time", "wrote",
        ] {
            line(label);
        }
        // Each frame's line says what that technique redid (issue 42: rays and irregular
        // maps once reported "0 of N shadow views redrawn").
        let frames: Vec<&str> = err.lines().filter(|l| l.starts_with("frame ")).collect();
        assert_eq!(frames.len(), 2, "{t}: {err}");
        let per_frame = match t {
            "raytraced" => "shadow rays in the lighting pass",
            "irregular" => "sample lists of all",
            "virtual" => "resident pages drawn",
            _ => "shadow views redrawn",
        };
        for l in &frames {
            assert!(l.contains(per_frame), "{t}: {l}");
        }
        // The atrium's seeded lights are sized: each technique says what it makes of them.
        let soft = line("soft");
        match t {
            "irregular" => {
                assert!(
                    !has("atlas") && !has("shadow work") && !has("pages"),
                    "{t}:\n{text}"
                );
                assert!(line("lists").contains("list nodes"), "{t}:\n{text}");
                assert!(soft.contains("hard") && !line("shadows").contains("PCF"));
            }
            "raytraced" => {
                assert!(!has("atlas") && !has("pages"), "{t}:\n{text}");
                assert!(line("shadow work").contains("no shadow map"));
                assert!(soft.contains("samples of their shape"), "{t}: {soft}");
            }
            "virtual" => {
                assert!(!has("atlas") && !has("lists"), "{t}:\n{text}");
                assert!(line("pages").contains("resident"));
                assert!(line("shadow work").contains("pages drawn"));
                assert!(soft.contains("PCSS"), "{t}: {soft}");
            }
            _ => {
                assert!(!has("pages") && !has("lists"), "{t}:\n{text}");
                assert!(line("atlas").contains("filled"));
                assert!(line("shadow work").contains("passes"));
                assert!(
                    line("shadows").contains("PCF") && soft.contains("PCSS"),
                    "{t}: {soft}"
                );
            }
        }
    }
    // Hard lights get no soft line.
    let out = run(&[
        "render",
        "--scene",
        "cubes",
        "--width",
        "96",
        "--height",
        "54",
        "--out",
        tmp("summary-hard").join("frame.png").to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{text}");
    assert!(!text.lines().any(|l| l.starts_with("soft")), "{text}");
}

/// Every technique's summary says what that technique did and nothing it did not (issue 42:
/// irregular's summary once showed an atlas it does not keep and "0 passes"): the shared
/// lines for all, then per kind of output — an atlas and its passes for the atlas techniques,
/// sample lists for irregular, faces, pages and marking for virtual maps, rays for the
/// ray-traced technique — and no atlas line where there is no atlas. A technique this adapter
/// cannot run must be refused naming the feature it lacks.
#[test]
fn every_technique_summary_is_true_to_the_technique() {
    let dir = tmp("summaries");
    for t in manyshadows::Technique::all() {
        let png = dir.join(format!("{}.png", t.name()));
        let out = run(&[
            "render",
            "--scene",
            "cubes",
            "--technique",
            t.name(),
            "--width",
            "64",
            "--height",
            "48",
            "--out",
            png.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        if !out.status.success() {
            assert!(
                stderr.contains("needs the") && stderr.contains(t.name()),
                "{} failed without naming what it needs: {stderr}",
                t.name()
            );
            continue;
        }
        let has = |label: &str| stdout.lines().any(|l| l.starts_with(label));
        let line = |label: &str| {
            stdout
                .lines()
                .find(|l| l.starts_with(label))
                .unwrap_or_else(|| panic!("{}: no '{label}' line in\n{stdout}", t.name()))
                .to_string()
        };
        for label in [
            "adapter ",
            "scene ",
            "lights ",
            "look ",
            "clusters ",
            "GPU time ",
            "wrote ",
        ] {
            line(label);
        }
        // Every technique estimates its frame, stage by stage, before drawing it.
        let estimate = line("estimate ");
        for part in ["G-buffer", "shadows", "lighting", "before the first frame"] {
            assert!(estimate.contains(part), "{}: {estimate}", t.name());
        }
        assert!(
            line("shadows ").contains(&format!("technique {}", t.name())),
            "{stdout}"
        );
        match t.info().fills {
            manyshadows::Fills::Atlas => {
                assert!(line("atlas ").contains("filled"), "{stdout}");
                assert!(line("shadow work ").contains(" passes"), "{stdout}");
            }
            manyshadows::Fills::Mask => {
                assert!(line("lists ").contains("list nodes"), "{stdout}");
                assert!(!has("atlas ") && !has("shadow work "), "{stdout}");
            }
            manyshadows::Fills::Pages => {
                assert!(line("virtual ").contains("faces of"), "{stdout}");
                assert!(line("pages ").contains("resident in a pool"), "{stdout}");
                line("marking ");
                assert!(line("shadow work ").contains("pages drawn"), "{stdout}");
                assert!(!has("atlas "), "{stdout}");
            }
            manyshadows::Fills::Rays => {
                assert!(
                    line("shadow work ").contains("no shadow map: rays"),
                    "{stdout}"
                );
                assert!(!has("atlas "), "{stdout}");
            }
            other => panic!("a kind of output this test does not know: {other:?}"),
        }
    }
}

/// `render --stages` says each part of the frame as the GPU finishes it, in order, and the
/// image is the one a frame submitted whole gives, byte for byte, for every technique the
/// adapter runs (each part is submitted and waited for before the next is recorded: a
/// technique that wrote a buffer for a later part too early would differ here).
#[test]
fn a_frame_told_in_stages_is_the_same_frame() {
    let mut ran = 0;
    for t in manyshadows::Technique::all() {
        let name = t.name();
        let dir = tmp(&format!("stages-{name}"));
        let frame = |stages: bool| {
            let png = dir.join(if stages { "staged.png" } else { "whole.png" });
            let mut args = vec![
                "render",
                "--technique",
                name,
                "--lights",
                "6",
                "--width",
                "96",
                "--height",
                "54",
                "--out",
                png.to_str().unwrap(),
            ];
            if stages {
                args.push("--stages");
            }
            (run(&args), png)
        };
        let (whole, whole_png) = frame(false);
        if !whole.status.success() {
            let err = String::from_utf8_lossy(&whole.stderr);
            assert!(
                err.contains(&format!("technique {name} needs")),
                "{name}: {err}"
            );
            continue;
        }
        let (staged, staged_png) = frame(true);
        let err = String::from_utf8_lossy(&staged.stderr).to_string();
        assert!(staged.status.success(), "{name}: {err}");
        let parts: Vec<&str> = err
            .lines()
            .filter(|l| l.starts_with("frame ") && l.contains(" done after "))
            .collect();
        assert_eq!(parts.len(), 3, "{name}: {err}");
        for (l, part) in parts
            .iter()
            .zip(["G-buffer and light clusters", "shadows", "lighting"])
        {
            assert!(l.contains(part), "{name}: {l}");
        }
        assert!(
            std::fs::read(&whole_png).unwrap() == std::fs::read(&staged_png).unwrap(),
            "{name}: the staged frame differs"
        );
        ran += 1;
    }
    assert!(ran >= 5, "only {ran} techniques ran");
}

/// `render --frames N --camera-path FILE` flies the path (frame k takes line k, the last
/// stays): its last frame is the frame `render --camera` gives at the path's last camera, byte
/// for byte (maps drawn anew each frame, no caster moving); a bad line is refused naming it.
#[test]
fn a_camera_path_is_flown_frame_by_frame() {
    let dir = tmp("camera-path");
    let path = dir.join("path.txt");
    std::fs::write(
        &path,
        "# fly in\n0 4 9 0 1 0\n1,3.5,8, 0,1,0\n2 3 7 0 0.5 0 # last\n",
    )
    .unwrap();
    let flown = dir.join("flown.png");
    let direct = dir.join("direct.png");
    let common = [
        "render",
        "--scene",
        "cubes",
        "--width",
        "96",
        "--height",
        "72",
        "--no-cache",
    ];
    run_ok(
        &[
            &common[..],
            &[
                "--frames",
                "4",
                "--still",
                "--camera-path",
                path.to_str().unwrap(),
                "--out",
                flown.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    run_ok(
        &[
            &common[..],
            &[
                "--camera",
                "2,3,7,0,0.5,0",
                "--out",
                direct.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(
        std::fs::read(&flown).unwrap() == std::fs::read(&direct).unwrap(),
        "the flown frame is not the frame at the path's last camera"
    );
    // A first frame elsewhere: the path's first camera is not the scene's.
    let first = dir.join("first.png");
    run_ok(
        &[
            &common[..],
            &[
                "--camera-path",
                path.to_str().unwrap(),
                "--out",
                first.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(std::fs::read(&first).unwrap() != std::fs::read(&direct).unwrap());
    std::fs::write(&path, "0 4 9 0 1 0\n1 2 3\n").unwrap();
    let out = run(&[
        &common[..],
        &[
            "--camera-path",
            path.to_str().unwrap(),
            "--out",
            first.to_str().unwrap(),
        ],
    ]
    .concat());
    assert_clean_failure(&out, 1, "line 2");
}

/// `render --stereo`: an image twice as wide as `--width`, whose halves are the two eyes
/// (different pictures), a summary line and JSON naming how the G-buffer was drawn; a negative
/// separation and `--stereo-passes` without `--stereo` refused.
#[test]
fn stereo_writes_both_eyes_side_by_side() {
    let dir = tmp("stereo");
    let frame = dir.join("stereo.png");
    let json = dir.join("stereo.json");
    let out = run_ok(&[
        "render",
        "--scene",
        "cubes",
        "--width",
        "96",
        "--height",
        "54",
        "--stereo",
        "0.5",
        "--stereo-passes",
        "per-eye",
        "-o",
        frame.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("stereo       two eyes 0.5 apart side by side, each 96x54; G-buffer drawn in one pass per eye"),
        "{stdout}"
    );
    let img = image::open(&frame).expect("stereo image").to_rgba8();
    assert_eq!(img.dimensions(), (192, 54));
    let differ = (0..54)
        .flat_map(|y| (0..96).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y) != img.get_pixel(x + 96, y))
        .count();
    assert!(
        differ > 100,
        "the two eyes look the same ({differ} pixels differ)"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(summary["stereo"]["passes"], "per-eye", "{summary}");
    assert_eq!(
        summary["resolution"],
        serde_json::json!([192, 54]),
        "{summary}"
    );
    assert_clean_failure(
        &run(&[
            "render", "--scene", "cubes", "--width", "96", "--height", "54", "--stereo", "-1",
        ]),
        1,
        "--stereo",
    );
    assert_clean_failure(
        &run(&["render", "--scene", "cubes", "--stereo-passes", "layered"]),
        2,
        "--stereo",
    );
}

/// `render --spatial`: with `--reuse` the frames say they reuse between neighbours (where ray
/// queries exist; elsewhere the technique is refused naming the feature); without `--reuse`
/// it is refused naming both flags, and an unknown mode lists the modes.
#[test]
fn spatial_reuse_is_said_and_refused_without_temporal_reuse() {
    let dir = tmp("spatial");
    let out_png = dir.join("spatial.png");
    let common = [
        "render",
        "--scene",
        "cubes",
        "--lights",
        "16",
        "--technique",
        "raytraced",
        "--light-samples",
        "1",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        out_png.to_str().unwrap(),
    ];
    let out = run(&[
        &common[..],
        &["--reuse", "--spatial", "unbiased", "--frames", "2"],
    ]
    .concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    if stderr.contains("EXPERIMENTAL_RAY_QUERY") {
        assert_clean_failure(&out, 1, "EXPERIMENTAL_RAY_QUERY");
    } else {
        assert!(out.status.success(), "{stderr}");
        assert!(
            stderr.contains(
                "lights reused (reservoirs of up to 2 frames) and between neighbours (unbiased)"
            ),
            "{stderr}"
        );
        assert!(std::fs::metadata(&out_png).is_ok());
    }
    let out = run(&[&common[..], &["--spatial", "biased"]].concat());
    assert_clean_failure(&out, 1, "--spatial");
    assert!(String::from_utf8_lossy(&out.stderr).contains("--reuse"));
    let out = run(&[&common[..], &["--reuse", "--spatial", "sideways"]].concat());
    assert_clean_failure(&out, 2, "off, biased, unbiased");
}

/// `--soft-taps B,F` and `--max-penumbra`: the summary says what the shadow maps' soft shadows
/// read; one number sets both counts; out-of-range values are refused naming the flag, a
/// malformed list says the form.
#[test]
fn soft_taps_and_the_largest_penumbra_are_chosen_and_said() {
    let dir = tmp("soft-taps");
    let png = dir.join("soft.png");
    let common = [
        "render",
        "--scene",
        "cubes",
        "--light-size",
        "0.2",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        png.to_str().unwrap(),
    ];
    let said = |extra: &[&str]| {
        let out = run_ok(&[&common[..], extra].concat());
        // The summary, wherever it is printed.
        format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    };
    let stderr = said(&["--soft-taps", "8,16", "--max-penumbra", "24"]);
    assert!(
        stderr.contains("PCSS, 8 blocker and 16 filter taps, penumbrae up to 24.0 texels"),
        "{stderr}"
    );
    let stderr = said(&["--soft-taps", "4"]);
    assert!(
        stderr.contains("PCSS, 4 blocker and 4 filter taps, penumbrae up to 32.0 texels"),
        "{stderr}"
    );
    let out = run(&[&common[..], &["--soft-taps", "8,65"]].concat());
    assert_clean_failure(&out, 1, "--soft-taps (filter)");
    let out = run(&[&common[..], &["--max-penumbra", "0"]].concat());
    assert_clean_failure(&out, 1, "--max-penumbra");
    let out = run(&[&common[..], &["--soft-taps", "8,9,10"]].concat());
    assert_clean_failure(&out, 2, "B,F");
}

/// Paths and values that would only fail after the frame (or never, rendering infinities) are
/// refused first, naming the flag and what it wants: a folder or a foreign file as the scene,
/// a folder as the image, a file as a folder, a NaN orbit, a scene whose values are finite
/// one by one but not together, a light past the largest coordinate.
#[test]
fn bad_paths_and_overflowing_scenes_are_refused_by_name() {
    let dir = tmp("bad-paths");
    let picture = dir.join("picture.png");
    std::fs::write(&picture, "not a scene").unwrap();
    let file = dir.join("afile");
    std::fs::write(&file, "").unwrap();
    let huge = dir.join("huge.toml");
    std::fs::write(
        &huge,
        "[[mesh]]\nname = \"b\"\nprimitive = \"cube\"\nsize = 1e30\n\
         [[instance]]\nmesh = \"b\"\nscale = 1e30\n",
    )
    .unwrap();
    let far = dir.join("far.toml");
    std::fs::write(
        &far,
        "[[light]]\ntype = \"point\"\nposition = [0, 1e38, 0]\nrange = 10\n",
    )
    .unwrap();
    let (d, p, f) = (
        dir.to_str().unwrap(),
        picture.to_str().unwrap(),
        file.to_str().unwrap(),
    );
    let out = dir.join("o.png");
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["render", "--scene", d, "-o", o], "that is a folder"),
        (
            vec!["render", "--scene", p, "-o", o],
            "reads no '.png' files",
        ),
        (
            vec![
                "render", "--scene", "cubes", "--frames", "2", "--orbit", "nan", "-o", o,
            ],
            "--orbit NaN",
        ),
        (vec!["render", "--scene", "cubes", "-o", d], "-o "),
        (
            vec!["render", "--scene", "cubes", "--visibility-out", f, "-o", o],
            "--visibility-out",
        ),
        (
            vec!["render", "--scene", huge.to_str().unwrap(), "-o", o],
            "past the largest coordinate",
        ),
        (
            vec!["render", "--scene", far.to_str().unwrap(), "-o", o],
            "at most 1e9 in magnitude",
        ),
        (
            vec!["compare", "--scene", "cubes", "--out-dir", f],
            "--out-dir",
        ),
    ] {
        assert_clean_failure(&run(&args), 1, needle);
        assert!(!out.exists(), "{args:?} wrote an image before refusing");
    }
}
