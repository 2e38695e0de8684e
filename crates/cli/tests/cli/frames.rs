//! Sequences of frames: caching, shadow budgets, frames told in stages, camera paths.

use crate::helpers::{assert_clean_failure, run, run_ok, tmp};

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
