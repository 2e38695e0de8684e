//! Bad input, announced values, refused estimates and the reference's progress.

use crate::helpers::{assert_clean_failure_compare, run, tmp};

#[test]
fn bad_input_is_a_clear_error() {
    let cases: &[(&[&str], i32, &str)] = &[
        (&["--edge-band", "1000"], 1, "edge-band"),
        (&["--shadow-resolutions", "0"], 1, "between 1 and 16384"),
        (&["--bias-constant", "NaN"], 1, "finite"),
        (&["--scene", "nope"], 1, "unknown built-in scene"),
        (&["--techniques", "nope"], 2, "unknown technique"),
        (&["--atlas-max", "8"], 1, "--atlas-max 8"),
        (
            &["--techniques", "virtual", "--virtual-bias", "NaN"],
            1,
            "--virtual-bias",
        ),
        (
            &["--techniques", "virtual", "--virtual-lod", "0"],
            1,
            "--virtual-lod",
        ),
        (
            &["--lights", "4096", "--width", "8192", "--height", "8192"],
            1,
            "reference rays",
        ),
        (&["--soft", "maybe"], 2, "neither on nor off"),
        // Out of range for every technique, not only where rays read it.
        (
            &[
                "--techniques",
                "traditional",
                "--frames",
                "2",
                "--light-samples",
                "99",
            ],
            1,
            "--light-samples",
        ),
        (&["--probes", "65"], 1, "--probes 65"),
        (
            &[
                "--soft-samples",
                "65536",
                "--width",
                "2000",
                "--height",
                "2000",
            ],
            1,
            "soft reference rays",
        ),
    ];
    for (extra, code, needle) in cases {
        let dir = tmp("bad");
        let mut args = vec!["compare", "--out-dir", dir.to_str().unwrap()];
        args.extend_from_slice(extra);
        let out = run(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(*code), "{extra:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{extra:?}: {stderr}");
        assert!(
            stderr.to_lowercase().contains(&needle.to_lowercase()),
            "{extra:?}: expected '{needle}' in {stderr}"
        );
    }
}

/// `--atlas-max` that is not a power of two is announced, not changed silently.
#[test]
fn a_rounded_atlas_max_is_announced() {
    let dir = tmp("atlas-note");
    let out = run(&[
        "compare",
        "--out-dir",
        dir.to_str().unwrap(),
        "--scene",
        "plane-spot",
        "--width",
        "32",
        "--height",
        "32",
        "--techniques",
        "traditional",
        "--atlas-max",
        "3000",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--atlas-max 3000 is used as 2048"),
        "no note: {stderr}"
    );
}

/// A technique whose frame would take minutes is estimated before it is drawn, as `render`
/// does: named, it is refused with its estimate (irregular at 16,384 lights: every caster
/// triangle against each of 43,693 light views).
#[test]
fn a_technique_of_minutes_is_refused_with_its_estimate() {
    let dir = tmp("minutes");
    let out = run(&[
        "compare",
        "--lights",
        "16384",
        "--techniques",
        "irregular",
        "--soft-samples",
        "0",
        "--width",
        "64",
        "--height",
        "36",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert_clean_failure_compare(&out, "technique irregular would take");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--insist"), "{stderr}");
}

/// The CPU reference shows its progress: in a log (stderr no terminal) a line at every tenth
/// of its rows with the rays so far, rays per second and the time left (issue 42).
#[test]
fn the_reference_shows_its_progress_in_a_log() {
    let dir = tmp("progress");
    let out = run(&[
        "compare",
        "--scene",
        "plane-spot",
        "--techniques",
        "traditional",
        "--width",
        "80",
        "--height",
        "60",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("reference rays: "))
        .collect();
    // Rows finish on several threads: the lines may come in any order, each tenth once.
    let mut rows: Vec<u32> = lines
        .iter()
        .map(|l| {
            l["reference rays: ".len()..]
                .split('/')
                .next()
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("{l}"))
        })
        .collect();
    rows.sort_unstable();
    assert_eq!(
        rows,
        (1..=10).map(|k| k * 6).collect::<Vec<u32>>(),
        "a line per tenth of 60 rows: {stderr}"
    );
    for l in &lines {
        assert!(l.contains("/s") && l.ends_with("s left"), "{l}");
    }
}
