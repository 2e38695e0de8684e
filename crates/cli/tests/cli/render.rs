//! The frame and what it writes, the adapter `info` names, limits a browser gives.

use crate::helpers::{run, tmp};

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
