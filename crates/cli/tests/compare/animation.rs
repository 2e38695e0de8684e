//! An animated glTF file scored at a time: every technique's hard shadows of the moved box are
//! as right as those of the same scene frozen at that time (the box placed by hand), against
//! the CPU reference of each; the exact techniques stay exact.

use serde_json::Value;

use crate::animated::{animated, bending, bent, curled, curling, frozen};
use crate::helpers::{compare, run, tmp};
use crate::shared_gpu;

/// Misclassified pixels outside the edge band, per technique label.
fn errors(v: &Value) -> Vec<(String, u64)> {
    v["variants"]
        .as_array()
        .unwrap()
        .iter()
        .map(|var| {
            let all = &var["by_type"]["all"];
            (
                var["label"].as_str().unwrap().to_string(),
                all["false_shadow"].as_u64().unwrap() + all["false_light"].as_u64().unwrap(),
            )
        })
        .collect()
}

/// At 0.5 s and 1.5 s of the sliding box, at 1 s of the bending tube and of the curling card
/// (a morph target), each technique
/// misclassifies no more pixels outside the band in the animated file's frame than in the file
/// frozen by hand (the two frames are the same pixels, see the CLI's animation test, so a
/// caster left at rest or a mesh not bent shows as more); ray-traced and irregular maps
/// misclassify none.
#[test]
fn an_animated_file_is_scored_as_its_frozen_frames() {
    let dir = tmp("animated-files");
    let frame = ["--width", "128", "--height", "96", "--soft-samples", "0"];
    // The sliding box at two times, and the bending tube at its full bend.
    let cases = [
        (animated(&dir), 0.5f32, frozen(&dir, 0.5)),
        (animated(&dir), 1.5, frozen(&dir, 1.5)),
        (bending(&dir), 1.0, bent(&dir, 1.0)),
        (curling(&dir), 1.0, curled(&dir, 1.0)),
    ];
    for (file, t, still) in cases {
        let time = t.to_string();
        let (moved, _) = compare(
            &format!(
                "animated-{}-{t}",
                file.file_stem().unwrap().to_string_lossy()
            ),
            &[
                &["--scene", file.to_str().unwrap(), "--time", &time][..],
                &frame[..],
            ]
            .concat(),
        );
        let (truth, _) = compare(
            &format!("frozen-{}-{t}", file.file_stem().unwrap().to_string_lossy()),
            &[&["--scene", still.to_str().unwrap()][..], &frame[..]].concat(),
        );
        let (moved, truth) = (errors(&moved), errors(&truth));
        assert_eq!(moved.len(), truth.len());
        assert!(moved.len() >= 6, "{moved:?}");
        for ((label, m), (_, f)) in moved.iter().zip(&truth) {
            eprintln!("t = {t} s, {label}: {m} misclassified outside the band (frozen: {f})");
            assert!(m <= f, "t = {t} s, {label}: {m} against {f} frozen");
            if label == "raytraced" || label == "irregular" {
                assert_eq!(*m, 0, "t = {t} s: {label} is exact");
            }
        }
    }
}

/// Ray-traced shadows follow a bending mesh: the bottom-level structure of the skinned tube is
/// built again each frame from its new vertices, so a sequence's last frame is the frame a
/// fresh renderer draws from the mesh bent on the CPU (byte for byte: the same structure built
/// from the same vertices). Without ray queries the refusal is recorded.
#[test]
fn ray_traced_shadows_follow_a_bending_mesh() {
    let ctx = shared_gpu::context();
    if !shared_gpu::rays_here(&ctx) {
        return;
    }
    let dir = tmp("bending-rays");
    let file = bending(&dir);
    let file = file.to_str().unwrap();
    let png = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let o = run(&[
            &[
                "render",
                "--scene",
                file,
                "--technique",
                "raytraced",
                "--width",
                "128",
                "--height",
                "96",
                "--out",
                out.to_str().unwrap(),
            ][..],
            extra,
        ]
        .concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        image::open(&out).unwrap().to_rgb8()
    };
    let seq = png("seq.png", &["--frames", "4", "--fps", "3"]);
    let single = png("single.png", &["--time", "1"]);
    let first = png("first.png", &[]);
    let off = |a: &image::RgbImage, b: &image::RgbImage| {
        a.pixels().zip(b.pixels()).filter(|(x, y)| x != y).count()
    };
    eprintln!(
        "sequence vs single frame at 1 s: {} pixels differ; vs the first frame: {}",
        off(&seq, &single),
        off(&seq, &first)
    );
    assert_eq!(
        off(&seq, &single),
        0,
        "the sequence's last frame is not the frame at 1 s"
    );
    assert!(off(&seq, &first) > 100, "the tube did not bend");
}

/// Per technique, each frame's misclassified pairs outside the band (`compare --frames
/// --misclassified`).
fn per_frame(v: &Value) -> Vec<(String, Vec<u64>)> {
    v["techniques"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            let frames = t["misclassified"]["outside_band"]
                .as_array()
                .unwrap_or_else(|| panic!("no per-frame score: {t}"))
                .iter()
                .map(|x| x.as_u64().unwrap())
                .collect();
            (t["technique"].as_str().unwrap().to_string(), frames)
        })
        .collect()
}

/// `compare --frames N --misclassified` on the generated files (the sliding box, 8 frames at 4
/// a second: 0 to 1.75 s; the bending tube and the curling card, 4 at 2 a second), each
/// frame's hard masks scored against the CPU reference traced through the scene as it stands
/// at that frame: every technique, carrying its kept views, pages and rebuilt structures from
/// frame to frame, misclassifies on no frame more than it does on the file frozen by hand at
/// that frame's time, scored alone; ray-traced and irregular maps misclassify none on any
/// frame. Measured (lavapipe, 96 x 72): 0 on every frame and every frozen file. A reference
/// traced through the scene at rest instead (the box left where it was) counts the moved
/// box's shadow as wrong, 49 to 145 pairs a frame: seen failing.
#[test]
fn every_frame_of_an_animated_sequence_is_scored_as_its_frozen_frame() {
    let dir = tmp("animated-sequence");
    let frame = ["--width", "96", "--height", "72"];
    type Frozen = fn(&std::path::Path, f32) -> std::path::PathBuf;
    let cases: [(std::path::PathBuf, Frozen, u32, u32); 3] = [
        (animated(&dir), frozen, 8, 4),
        (bending(&dir), bent, 4, 2),
        (curling(&dir), curled, 4, 2),
    ];
    for (file, still_at, frames, fps) in cases {
        let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
        let (seq, _) = compare(
            &format!("sequence-{stem}"),
            &[
                &[
                    "--scene",
                    file.to_str().unwrap(),
                    "--frames",
                    &frames.to_string(),
                    "--fps",
                    &fps.to_string(),
                    "--misclassified",
                ][..],
                &frame[..],
            ]
            .concat(),
        );
        let moving = per_frame(&seq);
        let mut truths = Vec::new();
        for k in 0..frames {
            let still = still_at(&dir, k as f32 / fps as f32);
            let (truth, _) = compare(
                &format!("sequence-{stem}-frozen-{k}"),
                &[
                    &["--scene", still.to_str().unwrap(), "--soft-samples", "0"][..],
                    &frame[..],
                ]
                .concat(),
            );
            truths.push(errors(&truth));
        }
        eprintln!("{stem}: per frame {moving:?}; frozen {truths:?}");
        for (technique, errs) in &moving {
            assert_eq!(errs.len(), frames as usize, "{stem}, {technique}: {errs:?}");
            for (k, &wrong) in errs.iter().enumerate() {
                let truth = truths[k]
                    .iter()
                    .find(|(label, _)| label == technique)
                    .map(|(_, n)| *n)
                    .unwrap_or_else(|| panic!("{technique} not scored on frozen frame {k}"));
                if technique == "raytraced" || technique == "irregular" {
                    assert_eq!(
                        wrong,
                        0,
                        "{stem}: {technique} misclassifies on frame {}",
                        k + 1
                    );
                }
                assert!(
                    wrong <= truth,
                    "{stem}, {technique}, frame {}: {wrong} misclassified in the sequence, \
                     {truth} on the frozen file",
                    k + 1
                );
            }
        }
    }
}
