//! Bad input of every kind: an error, never a panic.

use manyshadows_scene::loaders::{self, load_mesh};
use manyshadows_scene::SceneError;

use crate::common::{garbage, temp_dir, write};

#[test]
fn empty_files_are_errors() {
    let dir = temp_dir("empty");
    for ext in ["obj", "ply", "ply.gz", "gltf", "glb"] {
        let e = load_mesh(&write(&dir, &format!("empty.{ext}"), b"")).unwrap_err();
        assert!(e.to_string().contains("empty."), "{ext}: {e}");
    }
}

#[test]
fn garbage_files_are_errors() {
    let dir = temp_dir("garbage");
    for (seed, ext) in ["obj", "ply", "ply.gz", "gltf", "glb"].iter().enumerate() {
        for len in [1, 7, 100, 5000] {
            let p = write(
                &dir,
                &format!("g{len}.{ext}"),
                &garbage(len, seed as u64 + len as u64),
            );
            assert!(load_mesh(&p).is_err(), "{}", p.display());
        }
    }
    // Plausible-looking garbage.
    let cases: [(&str, &[u8]); 6] = [
        ("text.obj", b"hello world\nthis is not an obj\n"),
        (
            "text.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n",
        ),
        ("json.gltf", b"{\"asset\": {}}"),
        ("magic.glb", b"glTF\x02\x00\x00\x00\x05\x00\x00\x00"),
        ("short.glb", b"glTF"),
        ("notgzip.ply.gz", b"ply\nformat ascii 1.0\nend_header\n"),
    ];
    for (name, bytes) in cases {
        let e = load_mesh(&write(&dir, name, bytes)).unwrap_err();
        assert!(matches!(e, SceneError::Parse { .. }), "{name}: {e:?}");
    }
}

#[test]
fn missing_file_is_io_error() {
    let dir = temp_dir("missing");
    for name in ["nope.obj", "nope.ply", "nope.ply.gz", "nope.glb"] {
        let e = load_mesh(&dir.join(name)).unwrap_err();
        assert!(matches!(e, SceneError::Io { .. }), "{name}: {e:?}");
    }
}

#[test]
fn unsupported_extension_is_reported() {
    let dir = temp_dir("unsupported");
    for name in ["cube.stl", "cube.gz", "cube", "cube.obj.txt"] {
        let p = write(&dir, name, b"solid cube\n");
        let e = load_mesh(&p).unwrap_err();
        assert!(
            matches!(e, SceneError::UnsupportedFormat { .. }),
            "{name}: {e:?}"
        );
    }
}

#[test]
fn oversized_file_is_refused_from_metadata() {
    let dir = temp_dir("oversized");
    let p = dir.join("huge.ply");
    // A sparse file: takes no disk space, but its metadata says 3 GiB.
    let f = std::fs::File::create(&p).unwrap();
    f.set_len(loaders::MAX_FILE_BYTES + (1 << 30)).unwrap();
    drop(f);
    let e = load_mesh(&p).unwrap_err();
    let _ = std::fs::remove_file(&p);
    assert!(matches!(e, SceneError::TooLarge { .. }), "{e:?}");
}
