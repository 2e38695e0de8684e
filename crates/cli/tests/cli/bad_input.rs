//! Bad input: a one-line error naming what is wrong, the right exit code, never a panic.

use crate::helpers::{assert_clean_failure, run, tmp};

#[test]
fn missing_scene_file() {
    assert_clean_failure(
        &run(&["render", "--scene", "/nonexistent/scene.toml"]),
        1,
        "cannot read",
    );
}

#[test]
fn unknown_builtin_scene_lists_the_names() {
    assert_clean_failure(&run(&["render", "--scene", "sponza"]), 1, "atrium");
}

#[test]
fn malformed_toml() {
    let dir = tmp("toml");
    let path = dir.join("bad.toml");
    std::fs::write(&path, "[[light]]\ntype = \"spot\"\nposition = [0, 1\n").unwrap();
    assert_clean_failure(
        &run(&["render", "--scene", path.to_str().unwrap()]),
        1,
        "bad.toml",
    );
}

#[test]
fn malformed_meshes() {
    let dir = tmp("mesh");
    for (name, bytes) in [
        ("bad.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 9\n".as_slice()),
        ("bad.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nend_header\n\x01\x02".as_slice()),
        ("bad.glb", b"glTF\x02\x00\x00\x00garbage".as_slice()),
        ("bad.ply.gz", b"not gzip at all".as_slice()),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = run(&["render", "--scene", "dragon", "--mesh", path.to_str().unwrap(), "--width", "32", "--height", "32"]);
        assert_clean_failure(&out, 1, name);
    }
}

#[test]
fn absurd_numbers() {
    assert_clean_failure(
        &run(&["render", "--scene", "cubes", "--lights", "100000"]),
        1,
        "16384",
    );
    assert_clean_failure(
        &run(&["render", "--scene", "cubes", "--width", "100000"]),
        1,
        "resolution",
    );
    assert_clean_failure(
        &run(&["render", "--scene", "cubes", "--shadow-resolution", "0"]),
        1,
        "resolution",
    );
    assert_clean_failure(&run(&["render", "--pcf", "5x5"]), 2, "pcf");
    assert_clean_failure(&run(&["render", "--technique", "magic"]), 2, "traditional");
    assert_clean_failure(&run(&["render", "--light-types", "laser"]), 1, "laser");
}

/// Values that could only be changed silently are refused before the scene is loaded (a
/// missing scene file would otherwise be the error reported), and an --atlas-max that is not
/// a power of two is used as the next smaller one, with a note saying so.
#[test]
fn silently_changed_values_are_refused_or_announced() {
    let missing = "no-such-scene-file.toml";
    for (flag, value, needle) in [
        ("--frames", "0", "--frames must be at least 1"),
        (
            "--irregular-hash",
            "0",
            "--irregular-hash: irregular.hash 0 is out of range: at least 1",
        ),
        (
            "--page-pool",
            "0",
            "--page-pool (MiB): virtual_maps.pool_bytes 0 is out of range",
        ),
        (
            "--atlas-max",
            "8",
            "--atlas-max: max_atlas_size 8 is out of range",
        ),
        (
            "--shadow-budget",
            "0",
            "--shadow-budget: shadow_budget 0 is out of range",
        ),
    ] {
        assert_clean_failure(
            &run(&["render", "--scene", missing, flag, value]),
            1,
            needle,
        );
    }
    let dir = tmp("atlas-max-note");
    let out = run(&[
        "render",
        "--scene",
        "plane-spot",
        "--width",
        "32",
        "--height",
        "32",
        "--atlas-max",
        "3000",
        "--json",
        dir.join("s.json").to_str().unwrap(),
        "--out",
        dir.join("f.png").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--atlas-max 3000 is used as 2048"),
        "no note: {stderr}"
    );
}

#[test]
fn each_cause_is_printed_once() {
    let out = run(&["render", "--scene", "no-such-scene-file.toml"]);
    assert_clean_failure(&out, 1, "no-such-scene-file.toml");
    let stderr = String::from_utf8_lossy(&out.stderr);
    // The operating system's reason, once (it was printed twice, by the error and its source).
    let reason = std::io::Error::from(std::io::ErrorKind::NotFound).to_string();
    let os = "(os error 2)";
    assert_eq!(
        stderr.matches(os).count(),
        1,
        "the cause '{reason}' should appear once: {stderr}"
    );
}

/// Paths and values that would only fail after the frame (or never, rendering infinities) are
/// refused first, naming the flag and what it wants: a folder or a foreign file as the scene,
/// a folder as the image, a file as a folder, a NaN orbit, a scene whose values are finite
/// one by one but not together, a light past the largest coordinate.
#[test]
fn bad_paths_and_overflowing_scenes_are_refused_by_name() {
    let dir = tmp("bad-paths");
    let picture = dir.join("picture.png");
    std::fs::write(&picture, "not a scene").unwrap();
    let file = dir.join("afile");
    std::fs::write(&file, "").unwrap();
    let huge = dir.join("huge.toml");
    std::fs::write(
        &huge,
        "[[mesh]]\nname = \"b\"\nprimitive = \"cube\"\nsize = 1e30\n\
         [[instance]]\nmesh = \"b\"\nscale = 1e30\n",
    )
    .unwrap();
    let far = dir.join("far.toml");
    std::fs::write(
        &far,
        "[[light]]\ntype = \"point\"\nposition = [0, 1e38, 0]\nrange = 10\n",
    )
    .unwrap();
    let (d, p, f) = (
        dir.to_str().unwrap(),
        picture.to_str().unwrap(),
        file.to_str().unwrap(),
    );
    let out = dir.join("o.png");
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["render", "--scene", d, "-o", o], "that is a folder"),
        (
            vec!["render", "--scene", p, "-o", o],
            "reads no '.png' files",
        ),
        (
            vec![
                "render", "--scene", "cubes", "--frames", "2", "--orbit", "nan", "-o", o,
            ],
            "--orbit NaN",
        ),
        (vec!["render", "--scene", "cubes", "-o", d], "-o "),
        (
            vec!["render", "--scene", "cubes", "--visibility-out", f, "-o", o],
            "--visibility-out",
        ),
        (
            vec!["render", "--scene", huge.to_str().unwrap(), "-o", o],
            "past the largest coordinate",
        ),
        (
            vec!["render", "--scene", far.to_str().unwrap(), "-o", o],
            "at most 1e9 in magnitude",
        ),
        (
            vec!["compare", "--scene", "cubes", "--out-dir", f],
            "--out-dir",
        ),
    ] {
        assert_clean_failure(&run(&args), 1, needle);
        assert!(!out.exists(), "{args:?} wrote an image before refusing");
    }
}
