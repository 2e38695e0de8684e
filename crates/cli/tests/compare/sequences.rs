//! `compare --stages` and `compare --frames`.

use serde_json::Value;

use crate::helpers::{assert_clean_failure_compare, compare, run, tmp};
use crate::shared_gpu;

/// `compare --stages` says each part of every technique's frame as the GPU finishes it, in
/// order (as `render --stages`, whose frames are checked byte for byte in cli/frames.rs).
#[test]
fn compare_tells_each_frame_in_stages() {
    let dir = tmp("stages");
    let out = run(&[
        "compare",
        "--scene",
        "cubes",
        "--techniques",
        "traditional,virtual",
        "--width",
        "96",
        "--height",
        "72",
        "--soft-samples",
        "0",
        "--stages",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{err}");
    for t in ["traditional", "virtual"] {
        let lines: Vec<&str> = err
            .lines()
            .filter(|l| l.starts_with(&format!("{t}: ")) && l.contains(" done after "))
            .collect();
        assert_eq!(lines.len(), 3, "{t}: {err}");
        for (l, part) in lines
            .iter()
            .zip(["G-buffer and light clusters", "shadows", "lighting"])
        {
            assert!(l.contains(part), "{t}: {l}");
        }
    }
}

/// `compare --frames N` scores every frame of a sequence against the exact image of that same
/// frame: the ray-traced technique with every light is that exact image (RMSE 0 in every frame
/// of a turning camera and a moving caster, which fails if any renderer misses a step of the
/// sequence), shadow maps differ from it a little, and sampled rays denoised over still frames
/// come closer to it frame by frame. Without ray queries it is refused by name, but for
/// sampled lights over shadow maps (below).
#[test]
fn compare_over_a_sequence_scores_each_frame_against_its_exact_image() {
    let ctx = shared_gpu::context();
    let rays_here = shared_gpu::rays_here(&ctx);
    let frame = ["--scene", "cubes", "--width", "160", "--height", "90"];
    sampled_lights_over_maps_are_scored_against_every_light(&frame, rays_here);
    if !rays_here {
        let dir = tmp("sequence-refused");
        let out = run(&[
            &[
                "compare",
                "--out-dir",
                dir.to_str().unwrap(),
                "--frames",
                "3",
            ],
            &frame[..],
        ]
        .concat());
        assert_clean_failure_compare(&out, "EXPERIMENTAL_RAY_QUERY");
        return;
    }
    let dir = tmp("sequence-moving");
    let json = dir.join("score.json");
    let out = run(&[
        &[
            "compare",
            "--out-dir",
            dir.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ],
        &frame[..],
        &[
            "--frames",
            "4",
            "--orbit",
            "3",
            "--techniques",
            "raytraced,traditional",
            "--probes",
            "2",
        ],
    ]
    .concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // Progress in a log (stderr is no terminal here): a line per tenth of the frames.
    assert!(stderr.contains("frame 4/4 scored after"), "{stderr}");
    let moving: Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(moving["frames"], 4);
    // Two seeded probes, lit (and reflected) alike by the exact renderer and the technique.
    assert_eq!(moving["probes"], 2);
    assert!(moving["moving_instance"].is_u64(), "{moving}");
    let rows = moving["techniques"].as_array().expect("techniques");
    let rmse = |name: &str| -> Vec<f64> {
        let row = rows
            .iter()
            .find(|r| r["technique"] == name)
            .unwrap_or_else(|| panic!("no {name} row: {moving}"));
        row["rmse"]
            .as_array()
            .expect("rmse per frame")
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    assert_eq!(
        rmse("raytraced"),
        vec![0.0; 4],
        "every light traced is the exact frame"
    );
    let maps = rmse("traditional");
    assert_eq!(maps.len(), 4);
    assert!(
        maps.iter().all(|&e| e > 0.0 && e < 10.0),
        "shadow maps a little off the exact frames: {maps:?}"
    );
    for f in ["sequence.png", "exact-last.png", "traditional-last.png"] {
        assert!(dir.join(f).exists(), "{f} not written");
    }
    let (still, _) = compare(
        "sequence-denoised",
        &[
            &frame[..],
            &[
                "--lights",
                "64",
                "--frames",
                "6",
                "--still",
                "--techniques",
                "raytraced",
                "--light-samples",
                "1",
                "--denoise",
            ],
        ]
        .concat(),
    );
    let row = &still["techniques"][0];
    assert_eq!(row["technique"], "raytraced-k1-denoise");
    let e: Vec<f64> = row["rmse"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    eprintln!("K = 1 denoised over still frames: RMSE {e:?}");
    still_frames_converge(&e);
    // Sequence flags without a sequence, and a sequence of no frames.
    for (bad, needle) in [
        (vec!["--light-samples", "1"], "--light-samples"),
        (vec!["--orbit", "2"], "--orbit"),
        (vec!["--frames", "0"], "--frames"),
        (vec!["--misclassified"], "--misclassified"),
        (
            vec!["--frames", "2", "--misclassified", "--light-samples", "1"],
            "--misclassified",
        ),
    ] {
        let dir = tmp("sequence-bad");
        let out = run(&[
            &["compare", "--out-dir", dir.to_str().unwrap()],
            &frame[..],
            &bad[..],
        ]
        .concat());
        assert_clean_failure_compare(&out, needle);
    }
}

/// Sampled lights over virtual maps, denoised over still frames (any backend: their visibility
/// comes from the pages): scored against the same technique with every light, which they come
/// closer to frame by frame, and against the exact frame where rays exist. Sampling with only
/// techniques that cannot sample is refused naming the flag.
fn sampled_lights_over_maps_are_scored_against_every_light(frame: &[&str], rays_here: bool) {
    let (json, _) = compare(
        "sequence-sampled-maps",
        &[
            frame,
            &[
                "--lights",
                "64",
                "--frames",
                "6",
                "--still",
                "--techniques",
                "virtual",
                "--light-samples",
                "1",
                "--denoise",
            ],
        ]
        .concat(),
    );
    let row = &json["techniques"][0];
    assert_eq!(row["technique"], "virtual-k1-denoise", "{json}");
    let series = |v: &Value| -> Vec<f64> {
        v.as_array()
            .unwrap_or_else(|| panic!("no series: {json}"))
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let every = series(&row["every_light"]["rmse"]);
    eprintln!("virtual K = 1 denoised against every light through the same pages: {every:?}");
    assert_eq!(every.len(), 6);
    still_frames_converge(&every);
    if rays_here {
        let exact = series(&row["rmse"]);
        eprintln!("and against the exact frames: {exact:?}");
        assert_eq!(exact.len(), 6);
        assert!(exact[5] < exact[0], "{exact:?}");
    } else {
        assert!(
            row.get("rmse").is_none() && json["exact"].is_null(),
            "{json}"
        );
    }
    let dir = tmp("sequence-sampled-refused");
    let out = run(&[
        &["compare", "--out-dir", dir.to_str().unwrap()],
        frame,
        &[
            "--frames",
            "3",
            "--techniques",
            "irregular",
            "--light-samples",
            "1",
        ],
    ]
    .concat());
    assert_clean_failure_compare(&out, "--light-samples");
}

/// Six denoised still frames' errors: none exact (they are sampled), and the history brings
/// the sixth well below the first.
fn still_frames_converge(e: &[f64]) {
    assert!(
        e.iter().all(|&x| x > 0.0),
        "sampled frames are not exact: {e:?}"
    );
    assert!(
        e[5] < 0.85 * e[0],
        "the denoiser's history brings the still frames closer: {e:?}"
    );
}
