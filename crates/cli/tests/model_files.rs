//! A user's own model file through the binary: paths that leave the model's folder are
//! refused unless `--allow-outside-paths`, a model without a floor gets a ground plane unless
//! `--ground off`, and each note is printed once (no logged warning beside it).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("manyshadows-models-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn render(model: &Path, extra: &[&str]) -> Output {
    let out = model.with_extension("png");
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "render",
            "--scene",
            model.to_str().unwrap(),
            "--width",
            "48",
            "--height",
            "32",
        ])
        .args(["--out", out.to_str().unwrap()])
        .args(extra)
        .output()
        .expect("run manyshadows")
}

/// A standing quad (in the XY plane) whose buffer is `buffer_uri` and whose one material
/// names a texture file that does not exist.
fn quad_gltf(buffer_uri: &str) -> String {
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scenes": [ {{ "nodes": [0] }} ],
  "nodes": [ {{ "mesh": 0 }} ],
  "meshes": [ {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "indices": 1, "material": 0 }} ] }} ],
  "materials": [ {{ "name": "wall", "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }} }} }} ],
  "textures": [ {{ "source": 0 }} ],
  "images": [ {{ "uri": "missing.png" }} ],
  "buffers": [ {{ "uri": "{buffer_uri}", "byteLength": 60 }} ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 48, "byteLength": 12 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR" }}
  ]
}}"#
    )
}

fn quad_buffer() -> Vec<u8> {
    let mut b: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    b.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    b
}

#[test]
fn outside_paths_are_refused_unless_allowed_and_notes_are_printed_once() {
    let dir = tmp("outside");
    let model = dir.join("model");
    std::fs::create_dir_all(&model).unwrap();
    std::fs::write(dir.join("quad.bin"), quad_buffer()).unwrap();
    let path = model.join("quad.gltf");
    std::fs::write(&path, quad_gltf("../quad.bin")).unwrap();

    let out = render(&path, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains("'../quad.bin'") && stderr.contains("--allow-outside-paths"),
        "{stderr}"
    );

    let out = render(&path, &["--allow-outside-paths"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // The missing texture: one note, no logged warning repeating it.
    let about = stderr.lines().filter(|l| l.contains("missing.png")).count();
    assert_eq!(about, 1, "{stderr}");
    assert!(!stderr.contains("WARN"), "{stderr}");
    // A standing quad has no floor: a ground plane, said once.
    assert_eq!(
        stderr.matches("added a ground plane").count(),
        1,
        "{stderr}"
    );

    let out = render(&path, &["--allow-outside-paths", "--ground", "off"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("ground plane"), "{stderr}");
}

#[test]
fn a_bad_ground_setting_is_an_argument_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(["render", "--ground", "sometimes"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("auto") && stderr.contains("off"),
        "{stderr}"
    );
}
