//! What the summary says of each technique, and what it announces.

use crate::helpers::{run, tmp};

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

/// The summary reports the run's peak resident memory (`memory` line, `peak_resident_bytes`
/// in --json), and it is measured, not guessed: a 2048x2048 frame holds at least its 16 MiB
/// of read-back pixels (and its G-buffer and image besides) more than a 64x64 one, so its
/// peak must be at least 16 MiB higher.
#[test]
fn the_summary_reports_the_peak_resident_memory() {
    let dir = tmp("peak-memory");
    let peak = |side: &str| {
        let json = dir.join(format!("s{side}.json"));
        let png = dir.join(format!("f{side}.png"));
        let out = run(&[
            "render",
            "--scene",
            "cubes",
            "--width",
            side,
            "--height",
            side,
            "--out",
            png.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(stdout.contains("memory       peak resident"), "{stdout}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        v["peak_resident_bytes"]
            .as_u64()
            .unwrap_or_else(|| panic!("no peak_resident_bytes in {v}"))
    };
    let small = peak("64");
    let large = peak("2048");
    eprintln!("peak resident: 64x64 {small} bytes, 2048x2048 {large} bytes");
    assert!(
        small > 1 << 20,
        "{small} bytes: not a process's resident memory"
    );
    assert!(
        large >= small + (16 << 20),
        "2048x2048 peaked at {large} bytes, 64x64 at {small}: under 16 MiB apart"
    );
}
