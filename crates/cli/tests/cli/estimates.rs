//! Frames estimated before they are drawn, and refused when they would take minutes.

use crate::helpers::{assert_clean_failure, run, run_ok, tmp};

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
