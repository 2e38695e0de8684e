//! `--light-size` and `--sun-size`: they reach the scene of every command that loads one, the
//! `render` summary states the lights' sizes (text and JSON), `--help` teaches them, and a size
//! no light can have is a one-line error with exit code 1 before anything is loaded.

use std::path::PathBuf;
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "manyshadows-cli-size-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(args)
        .output()
        .expect("run manyshadows")
}

/// Renders a 32x32 frame of `scene` with `flags`: the summary's `lights` line and its JSON
/// `lights.sizes`.
fn sizes(dir: &std::path::Path, scene: &str, flags: &[&str]) -> (String, serde_json::Value) {
    let json = dir.join("summary.json");
    let out_png = dir.join("frame.png");
    let mut args = vec![
        "render",
        "--scene",
        scene,
        "--width",
        "32",
        "--height",
        "32",
        "--json",
        json.to_str().unwrap(),
        "--out",
        out_png.to_str().unwrap(),
    ];
    args.extend_from_slice(flags);
    let out = run(&args);
    assert!(
        out.status.success(),
        "{scene} {flags:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("lights "))
        .unwrap_or_else(|| panic!("no lights line:\n{stdout}"))
        .to_string();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    (line, summary["lights"]["sizes"].clone())
}

/// `[lo, hi]` of a JSON size range, as f32 (the sizes are f32).
fn range(v: &serde_json::Value) -> [f32; 2] {
    let a = v.as_array().unwrap_or_else(|| panic!("not a range: {v}"));
    [a[0].as_f64().unwrap() as f32, a[1].as_f64().unwrap() as f32]
}

#[test]
fn render_summary_states_the_sizes_the_flags_set() {
    let dir = tmp("summary");
    // The default scene's lights are sized by the built-in rule: 2 % of the range, suns 0.53°.
    let (line, s) = sizes(&dir, "atrium", &["--lights", "3"]);
    assert!(
        line.ends_with(", sizes: radius 0.18–0.28, sun 0.53°"),
        "{line}"
    );
    assert_eq!(range(&s["radius"]), [0.02 * 9.0, 0.02 * 14.0]);
    assert_eq!(range(&s["sun_deg"]), [0.53, 0.53]);

    // cubes is hard, unless the flags size it.
    let (line, s) = sizes(&dir, "cubes", &[]);
    assert!(line.ends_with(", all hard (size 0)"), "{line}");
    assert_eq!(
        (range(&s["radius"]), range(&s["sun_deg"])),
        ([0.0; 2], [0.0; 2])
    );
    let (line, s) = sizes(
        &dir,
        "cubes",
        &["--light-size", "0.25", "--sun-size", "1.5"],
    );
    assert!(line.ends_with(", sizes: radius 0.25, sun 1.5°"), "{line}");
    assert_eq!(
        (range(&s["radius"]), range(&s["sun_deg"])),
        ([0.25; 2], [1.5; 2])
    );

    // One flag leaves the other kind of light as the scene has it.
    let (line, _) = sizes(&dir, "atrium", &["--lights", "3", "--sun-size", "0"]);
    assert!(
        line.ends_with(", sizes: radius 0.18–0.28, sun 0°"),
        "{line}"
    );
    let (line, _) = sizes(
        &dir,
        "atrium",
        &["--lights", "3", "--light-size", "0", "--sun-size", "0"],
    );
    assert!(line.ends_with(", all hard (size 0)"), "{line}");

    // A scene file: its own sizes, overridden by the flag; no directional light, no sun range.
    let toml = dir.join("sized.toml");
    std::fs::write(
        &toml,
        "[[mesh]]\nname = \"floor\"\nprimitive = \"plane\"\nsize = [8, 8]\n\
         [[mesh]]\nname = \"box\"\nprimitive = \"cube\"\nsize = 1\n\
         [[instance]]\nmesh = \"floor\"\n[[instance]]\nmesh = \"box\"\ntranslate = [0, 1, 0]\n\
         [[light]]\ntype = \"spot\"\nposition = [0, 5, 0]\ndirection = [0, -1, 0]\n\
         cutoff_deg = 40\nrange = 12\nsize = 0.1\n\
         [[light]]\ntype = \"point\"\nposition = [2, 3, 0]\nrange = 8\n",
    )
    .unwrap();
    let toml = toml.to_str().unwrap();
    let (line, s) = sizes(&dir, toml, &[]);
    assert!(line.ends_with(", sizes: radius 0–0.1"), "{line}");
    assert!(s["sun_deg"].is_null(), "{s}");
    assert_eq!(range(&s["radius"]), [0.0, 0.1]);
    let (line, _) = sizes(&dir, toml, &["--light-size", "0"]);
    assert!(line.ends_with(", all hard (size 0)"), "{line}");
    // Seeded lights in place of the file's get the built-in sizes, and still obey the flag.
    let (_, s) = sizes(&dir, toml, &["--lights", "4", "--light-size", "0.05"]);
    assert_eq!(range(&s["radius"]), [0.05, 0.05]);
    assert_eq!(range(&s["sun_deg"]), [0.53, 0.53]);
}

#[test]
fn help_teaches_both_flags() {
    let out = run(&["render", "--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "--light-size <RADIUS>",
        "--sun-size <DEGREES>",
        "world units",
        "below 30",
        "0.53",
        "2% of its range",
    ] {
        assert!(
            help.contains(needle),
            "render --help lacks '{needle}':\n{help}"
        );
    }
    let out = run(&["compare", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(
        help.contains("--light-size <RADIUS>") && help.contains("--sun-size <DEGREES>"),
        "{help}"
    );
}

/// Refused before the scene is loaded (the missing scene file would be the error otherwise),
/// naming the flag, with exit code 1; `compare` too.
#[test]
fn bad_sizes_are_refused_naming_the_flag() {
    let missing = "no-such-scene-file.toml";
    for (cmd, flag, value, needle) in [
        (
            "render",
            "--light-size",
            "-1",
            "--light-size: light radius -1",
        ),
        (
            "render",
            "--light-size",
            "nan",
            "--light-size: light radius NaN",
        ),
        ("render", "--light-size", "inf", "finite number >= 0"),
        ("render", "--sun-size", "-0.5", "--sun-size: sun size -0.5"),
        ("render", "--sun-size", "30", "below 30"),
        ("render", "--sun-size", "nan", "--sun-size: sun size NaN"),
        (
            "compare",
            "--light-size",
            "-2",
            "--light-size: light radius -2",
        ),
        ("compare", "--sun-size", "45", "below 30"),
    ] {
        let out = run(&[cmd, "--scene", missing, flag, value]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{cmd} {flag} {value}: {stderr}");
        assert!(stderr.contains(needle), "{cmd} {flag} {value}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // Not a number at all is clap's usage error (exit code 2).
    let out = run(&["render", "--light-size", "big"]);
    assert_eq!(out.status.code(), Some(2));
}
