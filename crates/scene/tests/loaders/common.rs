//! What the loader tests share: temporary files, mesh assertions and known meshes, and the
//! glTF documents and scene helpers several subjects build on.

use std::path::{Path, PathBuf};

use glam::Vec3;
use manyshadows_scene::loaders::{load_mesh, load_scene, LoadedScene};
use manyshadows_scene::{Mesh, Texture};
use serde_json::Value;

/// A fresh, empty directory for one test.
pub(crate) fn temp_dir(test: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("manyshadows-loaders-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub(crate) fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

pub(crate) fn load_one(path: &Path) -> Mesh {
    let mut meshes = load_mesh(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(meshes.len(), 1, "{}", path.display());
    meshes.pop().unwrap()
}

/// Every triangle's winding agrees with its vertex normals (normals aligned and outward).
pub(crate) fn assert_normals_match_winding(m: &Mesh) {
    for t in m.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
        let g = (b - a).cross(c - a);
        for k in 0..3 {
            assert!(
                g.dot(m.normals[t[k] as usize]) > 0.0,
                "{}: triangle {t:?} disagrees with its normals",
                m.name
            );
        }
    }
}

pub(crate) fn assert_unit_normals(m: &Mesh) {
    assert_eq!(m.normals.len(), m.positions.len());
    for n in &m.normals {
        assert!((n.length() - 1.0).abs() < 1e-5, "normal {n} is not unit");
    }
}

/// A known mesh: a square pyramid (5 vertices, 6 triangles) with non-trivial coordinates.
pub(crate) fn pyramid() -> Mesh {
    let mut m = Mesh {
        name: "pyramid".into(),
        positions: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(0.1, 1.7, -0.3),
        ],
        indices: vec![0, 1, 2, 0, 2, 3, 0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0],
        ..Mesh::default()
    };
    m.compute_normals();
    m
}

pub(crate) const CUBE_V: &str = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n\
                                 v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n";

/// The six faces of the cube above as counter-clockwise (outward) quads, 1-based.
pub(crate) const CUBE_QUADS: [[u32; 4]; 6] = [
    [1, 4, 3, 2], // -Z
    [5, 6, 7, 8], // +Z
    [1, 5, 8, 4], // -X
    [2, 3, 7, 6], // +X
    [1, 2, 6, 5], // -Y
    [4, 8, 7, 3], // +Y
];

pub(crate) const CUBE_NORMALS: [Vec3; 6] = [
    Vec3::NEG_Z,
    Vec3::Z,
    Vec3::NEG_X,
    Vec3::X,
    Vec3::NEG_Y,
    Vec3::Y,
];

/// The inverse of [`base64`] (padding optional).
pub(crate) fn base64_decode(text: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {}", c as char),
    } as u32;
    let bytes: Vec<u8> = text.bytes().filter(|&c| c != b'=').collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let acc = chunk
            .iter()
            .enumerate()
            .fold(0u32, |a, (i, &c)| a | val(c) << (18 - 6 * i));
        out.extend_from_slice(&acc.to_be_bytes()[1..chunk.len()]);
    }
    out
}

pub(crate) fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A unit quad in the XY plane (normal +Z): 4 positions, 4 normals, 6 u16 indices; plus a
/// non-indexed triangle (3 positions, no normals).
pub(crate) fn quad_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for _ in 0..4 {
        for c in [0f32, 0., 1.] {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    // offset 108: the non-indexed triangle.
    for p in [[0f32, 0., 0.], [2., 0., 0.], [0., 0., -2.]] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b
}

/// glTF JSON for the buffer above. `nodes` is the JSON of the node array; node meshes: 0 = quad,
/// 1 = non-indexed triangle. `buffer_uri` is `None` for a GLB's BIN chunk.
pub(crate) fn gltf_json(nodes: &str, buffer_uri: Option<&str>, buffer_len: usize) -> String {
    let uri = buffer_uri
        .map(|u| format!("\"uri\": \"{u}\", "))
        .unwrap_or_default();
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scene": 0,
  "scenes": [ {{ "nodes": [0] }} ],
  "nodes": {nodes},
  "meshes": [
    {{ "name": "quad", "primitives": [ {{ "attributes": {{ "POSITION": 0, "NORMAL": 1 }}, "indices": 2 }} ] }},
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 3 }} }} ] }}
  ],
  "buffers": [ {{ {uri}"byteLength": {buffer_len} }} ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 96 }},
    {{ "buffer": 0, "byteOffset": 96, "byteLength": 12 }},
    {{ "buffer": 0, "byteOffset": 108, "byteLength": 36 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 0, "byteOffset": 48, "componentType": 5126, "count": 4, "type": "VEC3" }},
    {{ "bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR" }},
    {{ "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3",
       "min": [0, 0, -2], "max": [2, 0, 0] }}
  ]
}}"#
    )
}

pub(crate) fn embedded_gltf(nodes: &str) -> String {
    let buf = quad_buffer();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&buf));
    gltf_json(nodes, Some(&uri), buf.len())
}

pub(crate) fn garbage(len: usize, seed: u64) -> Vec<u8> {
    let mut x = seed;
    (0..len)
        .map(|_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 56) as u8
        })
        .collect()
}

/// The quad document of [`embedded_gltf`] as JSON, to be extended by a test.
pub(crate) fn quad_doc(nodes: Value) -> Value {
    serde_json::from_str(&embedded_gltf(&nodes.to_string())).unwrap()
}

pub(crate) fn save_json(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    write(dir, name, doc.to_string().as_bytes())
}

pub(crate) fn scene_of(path: &Path) -> LoadedScene {
    load_scene(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

pub(crate) fn png(t: &Texture) -> Vec<u8> {
    let mut out = Vec::new();
    image::RgbaImage::from_raw(t.width, t.height, t.rgba.to_vec())
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

pub(crate) fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).length() <= tolerance * (1.0 + a.length().max(b.length()))
}

/// The framing camera of a file without one: it looks from (1, 0.6, 1) at the centre of the
/// bounds with a 60° field of view, every corner of the bounds is in view for any frame at
/// least as wide as it is high, and the bounds fill the frame (a corner touches its margin).
pub(crate) fn assert_frames(camera: &manyshadows_scene::Camera, lo: Vec3, hi: Vec3) {
    let centre = (lo + hi) / 2.0;
    assert!(close(camera.target, centre, 1e-6), "{camera:?}");
    let back = (camera.position - camera.target).normalize();
    assert!(
        close(back, Vec3::new(1.0, 0.6, 1.0).normalize(), 1e-5),
        "{camera:?}"
    );
    assert_eq!(camera.fov_y_deg, 60.0);
    let view = glam::Mat4::look_at_rh(camera.position, camera.target, camera.up);
    let tan = 30f32.to_radians().tan();
    let mut widest = 0.0f32;
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let v = view.transform_point3(c);
        assert!(-v.z > camera.near, "corner {c} is behind the near plane");
        let (x, y) = (v.x / (-v.z * tan), v.y / (-v.z * tan));
        assert!(
            x.abs() <= 1.0 + 1e-4 && y.abs() <= 1.0 + 1e-4,
            "corner {c} at ({x}, {y})"
        );
        widest = widest.max(x.abs()).max(y.abs());
    }
    assert!(widest > 0.85, "the bounds fill only {widest} of the frame");
}
