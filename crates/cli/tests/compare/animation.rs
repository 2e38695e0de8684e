//! An animated glTF file scored at a time: every technique's hard shadows of the moved box are
//! as right as those of the same scene frozen at that time (the box placed by hand), against
//! the CPU reference of each; the exact techniques stay exact.

use serde_json::Value;

use crate::animated::{animated, frozen};
use crate::helpers::{compare, tmp};

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

/// At 0.5 s and 1.5 s, each technique misclassifies no more pixels outside the band in the
/// animated file's frame than in the frozen file's (the two frames are the same pixels, see
/// the CLI's animation test, so any step a technique missed, a map not redrawn or a caster
/// left at rest, shows as more); ray-traced and irregular maps misclassify none.
#[test]
fn an_animated_file_is_scored_as_its_frozen_frames() {
    let dir = tmp("animated-files");
    let file = animated(&dir);
    let frame = ["--width", "128", "--height", "96", "--soft-samples", "0"];
    for t in [0.5f32, 1.5] {
        let time = t.to_string();
        let (moved, _) = compare(
            &format!("animated-{t}"),
            &[
                &["--scene", file.to_str().unwrap(), "--time", &time][..],
                &frame[..],
            ]
            .concat(),
        );
        let still = frozen(&dir, t);
        let (truth, _) = compare(
            &format!("frozen-{t}"),
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
