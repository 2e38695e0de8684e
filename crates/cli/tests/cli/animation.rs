//! A glTF file's animation: `render --time` puts its instances where the animation has them
//! (checked against the same scene frozen at that time with the box placed by hand), a
//! sequence plays it frame by frame, and flags that cannot apply are refused by name.

use std::path::Path;

use crate::animated::{animated, bending, bent, box_pose, curled, curling, frozen};
use crate::helpers::{assert_clean_failure, run, run_ok, tmp};

const FRAME: [&str; 4] = ["--width", "160", "--height", "120"];

fn render(scene: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["render", "--scene", scene.to_str().unwrap()];
    args.extend(FRAME);
    args.extend(extra);
    args.extend(["--out", out.to_str().unwrap()]);
    let o = run_ok(&args);
    String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr)
}

/// Mean absolute difference of two PNGs' RGB channels (0–255).
fn mean_difference(a: &Path, b: &Path) -> f64 {
    let (a, b) = (
        image::open(a).unwrap().to_rgb8(),
        image::open(b).unwrap().to_rgb8(),
    );
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: u64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(&x, &y)| u64::from(x.abs_diff(y)))
        .sum();
    sum as f64 / a.as_raw().len() as f64
}

/// At 0.5 s and at 1.25 s (the way back, turned past half a circle), the animated file's frame
/// is the frozen file's frame: the same pixels but for rounding (the animated box's vertices
/// are baked at rest and moved by a transform; the frozen box's are baked where it stands),
/// measured below 0.05 of 255 on average, while the box standing anywhere else differs by
/// more than 1. A sequence plays the same times: its last frame at 0.25 s + 2 frames at
/// 4 fps is the single frame at 0.75 s.
#[test]
fn render_at_a_time_places_what_the_file_animates() {
    let dir = tmp("animation-time");
    let file = animated(&dir);
    let rest = dir.join("rest.png");
    render(&file, &rest, &[]);
    for t in [0.5f32, 1.25] {
        let (a, f) = (
            dir.join(format!("a-{t}.png")),
            dir.join(format!("f-{t}.png")),
        );
        let said = render(&file, &a, &["--time", &t.to_string()]);
        assert!(
            said.contains(&format!(
                "animation    'slide' (1 of 1) at {t:.3} s of 2.000 s (1 instance moves)"
            )),
            "{said}"
        );
        render(&frozen(&dir, t), &f, &[]);
        let same = mean_difference(&a, &f);
        let moved = mean_difference(&rest, &f);
        eprintln!(
            "t = {t} s (box at x {:.2}): animated vs frozen {same:.4}, rest vs frozen {moved:.3}",
            box_pose(t).0
        );
        assert!(
            same < 0.05,
            "t = {t}: the animated frame is {same} from the frozen one"
        );
        assert!(moved > 1.0, "t = {t}: the box hardly moved ({moved})");
    }
    // Through the atlas's kept views and virtual maps' kept pages alike: what moved is redrawn.
    // Every frame is written with --out-dir, the last one also to --out.
    for technique in ["traditional", "virtual"] {
        let seq = dir.join(format!("seq-{technique}.png"));
        let frames = dir.join(format!("frames-{technique}"));
        let said = render(
            &file,
            &seq,
            &[
                "--technique",
                technique,
                "--time",
                "0.25",
                "--frames",
                "3",
                "--fps",
                "4",
                "--out-dir",
                frames.to_str().unwrap(),
            ],
        );
        for k in 1..=3 {
            assert!(
                frames.join(format!("frame_{k:04}.png")).is_file(),
                "frame {k} not written"
            );
        }
        assert_eq!(mean_difference(&frames.join("frame_0003.png"), &seq), 0.0);
        assert!(
            mean_difference(&frames.join("frame_0001.png"), &seq) > 0.1,
            "the first frame is the last"
        );
        let lines: Vec<&str> = said.lines().filter(|l| l.starts_with("frame ")).collect();
        assert_eq!(lines.len(), 3, "{said}");
        assert!(said.contains("at 0.750 s of 2.000 s"), "{said}");
        let single = dir.join(format!("single-{technique}.png"));
        render(
            &file,
            &single,
            &["--technique", technique, "--time", "0.75"],
        );
        let d = mean_difference(&seq, &single);
        assert!(
            d < 0.05,
            "{technique}: the sequence's last frame is {d} from the frame at 0.75 s"
        );
    }
}

/// Animation flags where they cannot apply, and bad values, are refused by name.
#[test]
fn animation_flags_that_cannot_apply_are_refused() {
    let dir = tmp("animation-refused");
    let file = animated(&dir);
    let out = dir.join("x.png");
    let file = file.to_str().unwrap();
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["--scene", "cubes", "--time", "1"],
            "--time: scene cubes has no animation",
        ),
        (
            vec!["--scene", "cubes", "--animation", "0"],
            "--animation: scene cubes",
        ),
        (
            vec!["--scene", file, "--animation", "walk"],
            "0 'slide' (2.00 s)",
        ),
        (
            vec!["--scene", file, "--animation", "3"],
            "no animation named or numbered '3'",
        ),
        (
            vec!["--scene", file, "--fps", "10"],
            "--fps 10: applies to a sequence",
        ),
        (
            vec!["--scene", file, "--frames", "2", "--fps", "0"],
            "--fps 0",
        ),
        (vec!["--scene", file, "--time", "-1"], "--time -1"),
        (vec!["--scene", file, "--time", "NaN"], "--time NaN"),
        (
            vec!["--scene", file, "--frames", "2", "--move-instance", "1"],
            "--move-instance 1: the file's animation moves that instance",
        ),
    ] {
        let mut a = vec!["render"];
        a.extend(FRAME);
        a.extend(&args);
        a.extend(["--out", o]);
        assert_clean_failure(&run(&a), 1, needle);
    }
    // `all` and a name play.
    for which in ["all", "slide"] {
        run_ok(
            &[
                &["render", "--scene", file, "--animation", which, "--out", o][..],
                &FRAME[..],
            ]
            .concat(),
        );
    }
}

/// A skinned tube bending at its upper joint: at 0.5 s (30°) and 1 s (60°) the frame is the
/// frame of the same tube bent by hand (each vertex blended between itself and its turn about
/// the joint, tests/common/animated.rs), while the straight tube differs; a sequence through
/// kept views and kept pages ends on the single frame of its time (the bent mesh's shadows
/// redrawn where its old and new bounds reach).
#[test]
fn a_skinned_mesh_bends_as_its_joints_turn() {
    let dir = tmp("animation-skin");
    deforms_as_by_hand(&dir, &bending(&dir), "bend", |t| bent(&dir, t));
}

/// A card whose morph target curls its top: at 0.5 s (half the target) and 1 s (all of it) the
/// frame is the frame of the card curled by hand, and a sequence ends on the single frame of
/// its time, as for the skin above.
#[test]
fn a_morph_target_shapes_its_mesh_as_its_weight_says() {
    let dir = tmp("animation-morph");
    deforms_as_by_hand(&dir, &curling(&dir), "curl", |t| curled(&dir, t));
}

/// `file`, whose clip `clip` deforms a mesh, against the same scene deformed by hand at 0.5 s
/// and 1 s (`by_hand(t)` writes it), and through a sequence.
fn deforms_as_by_hand(
    dir: &Path,
    file: &Path,
    clip: &str,
    by_hand: impl Fn(f32) -> std::path::PathBuf,
) {
    let straight = dir.join("straight.png");
    // One exposure for all: the meter aims at the centre of the file's bounds as loaded, and
    // the straight tube's bounds are taller than the bent one's (1 level over the ground).
    let render = |scene: &Path, out: &Path, extra: &[&str]| {
        render(scene, out, &[&["--exposure", "x2"][..], extra].concat())
    };
    let said = render(file, &straight, &[]);
    assert!(
        said.contains(&format!("animation    '{clip}' (1 of 1) at 0.000 s")),
        "{said}"
    );
    for t in [0.5f32, 1.0] {
        let (a, f) = (
            dir.join(format!("a-{t}.png")),
            dir.join(format!("f-{t}.png")),
        );
        render(file, &a, &["--time", &t.to_string()]);
        render(&by_hand(t), &f, &[]);
        let same = mean_difference(&a, &f);
        let moved = mean_difference(&straight, &f);
        eprintln!("{clip}, t = {t} s: file vs by hand {same:.4}, at rest vs by hand {moved:.3}");
        assert!(
            same < 0.05,
            "{clip}, t = {t}: the file's frame is {same} from the one by hand"
        );
        assert!(
            moved > 0.2,
            "{clip}, t = {t}: the mesh hardly moved ({moved})"
        );
    }
    for technique in ["traditional", "virtual"] {
        let seq = dir.join(format!("seq-{technique}.png"));
        let said = render(
            file,
            &seq,
            &[
                "--technique",
                technique,
                "--time",
                "0.25",
                "--frames",
                "3",
                "--fps",
                "4",
            ],
        );
        assert!(said.contains("at 0.750 s of 2.000 s"), "{said}");
        let single = dir.join(format!("single-{technique}.png"));
        render(file, &single, &["--technique", technique, "--time", "0.75"]);
        let d = mean_difference(&seq, &single);
        assert!(
            d < 0.05,
            "{technique}: the sequence's last frame is {d} from the frame at 0.75 s"
        );
    }
}
