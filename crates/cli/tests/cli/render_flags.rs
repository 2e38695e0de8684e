//! `render`'s flags for stereo, spatial reuse and soft-shadow taps.

use crate::helpers::{assert_clean_failure, run, run_ok, tmp};

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

/// `--light-samples K` takes its visibility from shadow rays or shadow maps: with a technique
/// that answers every light in one mask (irregular maps) it is refused naming the flag and the
/// technique, before anything is loaded, instead of being ignored; with an atlas technique it
/// renders.
#[test]
fn light_samples_are_refused_by_name_where_the_technique_cannot_sample() {
    let dir = tmp("light-samples-maps");
    let out_png = dir.join("frame.png");
    let args = |t: &str| {
        run(&[
            "render",
            "--scene",
            "cubes",
            "--technique",
            t,
            "--light-samples",
            "1",
            "--width",
            "64",
            "--height",
            "48",
            "--out",
            out_png.to_str().unwrap(),
        ])
    };
    let mut refused = 0;
    for t in manyshadows::Technique::all() {
        if t.info().fills != manyshadows::Fills::Mask {
            continue;
        }
        let out = args(t.name());
        assert_clean_failure(&out, 1, "--light-samples");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(&format!("technique {}", t.name())),
            "{t}: the refusal names the technique: {stderr}"
        );
        assert!(!out_png.exists(), "{t}: a refused render wrote an image");
        refused += 1;
    }
    assert!(refused >= 1, "irregular maps refuse sampled lights");
    let out = args("traditional");
    assert!(
        out.status.success() && out_png.exists(),
        "sampled lights over the atlas: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}
