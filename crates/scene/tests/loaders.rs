//! Mesh loader tests: every file is generated here, in a temporary directory.

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;
use manyshadows_scene::loaders::{self, load_mesh, write_obj, write_ply_ascii};
use manyshadows_scene::{Mesh, SceneError};

/// A fresh, empty directory for one test.
fn temp_dir(test: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("manyshadows-loaders-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn load_one(path: &Path) -> Mesh {
    let mut meshes = load_mesh(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(meshes.len(), 1, "{}", path.display());
    meshes.pop().unwrap()
}

/// Every triangle's winding agrees with its vertex normals (normals aligned and outward).
fn assert_normals_match_winding(m: &Mesh) {
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

fn assert_unit_normals(m: &Mesh) {
    assert_eq!(m.normals.len(), m.positions.len());
    for n in &m.normals {
        assert!((n.length() - 1.0).abs() < 1e-5, "normal {n} is not unit");
    }
}

/// A known mesh: a square pyramid (5 vertices, 6 triangles) with non-trivial coordinates.
fn pyramid() -> Mesh {
    let mut m = Mesh {
        name: "pyramid".into(),
        positions: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(0.1, 1.7, -0.3),
        ],
        normals: vec![],
        indices: vec![0, 1, 2, 0, 2, 3, 0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0],
    };
    m.compute_normals();
    m
}

const CUBE_V: &str = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n\
                      v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n";

/// The six faces of the cube above as counter-clockwise (outward) quads, 1-based.
const CUBE_QUADS: [[u32; 4]; 6] = [
    [1, 4, 3, 2], // -Z
    [5, 6, 7, 8], // +Z
    [1, 5, 8, 4], // -X
    [2, 3, 7, 6], // +X
    [1, 2, 6, 5], // -Y
    [4, 8, 7, 3], // +Y
];
const CUBE_NORMALS: [Vec3; 6] = [
    Vec3::NEG_Z,
    Vec3::Z,
    Vec3::NEG_X,
    Vec3::X,
    Vec3::NEG_Y,
    Vec3::Y,
];

// ---------------------------------------------------------------------------------------------
// OBJ
// ---------------------------------------------------------------------------------------------

#[test]
fn obj_cube_without_normals_gets_computed_unit_normals() {
    let dir = temp_dir("obj_no_normals");
    let mut text = String::from(CUBE_V);
    for q in CUBE_QUADS {
        text += &format!(
            "f {} {} {}\nf {} {} {}\n",
            q[0], q[1], q[2], q[0], q[2], q[3]
        );
    }
    let m = load_one(&write(&dir, "cube.obj", text.as_bytes()));
    assert_eq!(m.triangle_count(), 12);
    assert_eq!(m.positions.len(), 8);
    assert_unit_normals(&m);
    // Computed corner normals point away from the centre (the faces wind outward).
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(n.dot(*p) > 0.5, "{p} -> {n}");
    }
    m.validate().unwrap();
}

#[test]
fn obj_cube_with_normals_keeps_them_aligned() {
    let dir = temp_dir("obj_normals");
    let mut text = String::from(CUBE_V);
    for n in CUBE_NORMALS {
        text += &format!("vn {} {} {}\n", n.x, n.y, n.z);
    }
    for (f, q) in CUBE_QUADS.iter().enumerate() {
        let n = f + 1;
        text += &format!(
            "f {}//{n} {}//{n} {}//{n}\nf {}//{n} {}//{n} {}//{n}\n",
            q[0], q[1], q[2], q[0], q[2], q[3]
        );
    }
    let m = load_one(&write(&dir, "cube_n.obj", text.as_bytes()));
    assert_eq!(m.triangle_count(), 12);
    assert_unit_normals(&m);
    assert_normals_match_winding(&m);
    // Each vertex's normal is exactly one of the file's face normals (none were recomputed).
    for n in &m.normals {
        assert!(CUBE_NORMALS.contains(n), "{n}");
    }
}

#[test]
fn obj_quads_are_triangulated() {
    let dir = temp_dir("obj_quads");
    let mut text = String::from(CUBE_V);
    for q in CUBE_QUADS {
        text += &format!("f {} {} {} {}\n", q[0], q[1], q[2], q[3]);
    }
    let m = load_one(&write(&dir, "quads.OBJ", text.as_bytes()));
    assert_eq!(m.triangle_count(), 12);
    assert_normals_match_winding(&m);
    // Every quad's four corners appear among the triangles.
    for q in CUBE_QUADS {
        for v in q {
            let p = m.positions.iter().position(|p| {
                let c = CUBE_V.lines().nth(v as usize - 1).unwrap();
                let xyz: Vec<f32> = c[2..].split(' ').map(|s| s.parse().unwrap()).collect();
                *p == Vec3::new(xyz[0], xyz[1], xyz[2])
            });
            assert!(m.indices.contains(&(p.unwrap() as u32)));
        }
    }
}

#[test]
fn obj_objects_become_separate_meshes() {
    let dir = temp_dir("obj_objects");
    let text = "o first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\
                o second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\nf 4 5 7\nf 5 6 7\n";
    let meshes = load_mesh(&write(&dir, "two.obj", text.as_bytes())).unwrap();
    assert_eq!(meshes.len(), 2);
    assert_eq!(meshes[0].triangle_count(), 1);
    assert_eq!(meshes[1].triangle_count(), 2);
    assert!(meshes[1].name.contains("second"), "{}", meshes[1].name);
}

#[test]
fn obj_writer_round_trips() {
    let dir = temp_dir("obj_round_trip");
    let m = pyramid();
    let mut bytes = Vec::new();
    write_obj(&m, &mut bytes).unwrap();
    let back = load_one(&write(&dir, "pyramid.obj", &bytes));
    assert_eq!(back.triangle_count(), m.triangle_count());
    // tobj re-indexes; compare the triangles' corner positions and normals.
    for (t0, t1) in m.indices.chunks(3).zip(back.indices.chunks(3)) {
        for k in 0..3 {
            assert_eq!(m.positions[t0[k] as usize], back.positions[t1[k] as usize]);
            assert_eq!(m.normals[t0[k] as usize], back.normals[t1[k] as usize]);
        }
    }
}

#[test]
fn obj_nan_vertex_is_invalid_mesh() {
    let dir = temp_dir("obj_nan");
    let p = write(&dir, "nan.obj", b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let e = load_mesh(&p).unwrap_err();
    assert!(matches!(e, SceneError::InvalidMesh { .. }), "{e:?}");
    assert!(e.to_string().contains("non-finite"), "{e}");
}

#[test]
fn obj_out_of_range_face_is_an_error() {
    let dir = temp_dir("obj_range");
    let p = write(&dir, "range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    assert!(load_mesh(&p).is_err());
}

// ---------------------------------------------------------------------------------------------
// PLY
// ---------------------------------------------------------------------------------------------

#[test]
fn ply_ascii_round_trip_is_exact() {
    let dir = temp_dir("ply_ascii");
    let m = pyramid();
    let mut bytes = Vec::new();
    write_ply_ascii(&m, &mut bytes).unwrap();
    assert!(bytes.starts_with(b"ply\nformat ascii 1.0\n"));
    let back = load_one(&write(&dir, "pyramid.ply", &bytes));
    assert_eq!(back.positions, m.positions);
    assert_eq!(back.indices, m.indices);
    assert_eq!(back.normals, m.normals);
}

#[test]
fn ply_ascii_without_normals_computes_them() {
    let dir = temp_dir("ply_ascii_nonormals");
    let m = Mesh {
        normals: vec![],
        ..pyramid()
    };
    let mut bytes = Vec::new();
    write_ply_ascii(&m, &mut bytes).unwrap();
    assert!(!String::from_utf8_lossy(&bytes).contains("nx"));
    let back = load_one(&write(&dir, "p.ply", &bytes));
    assert_eq!(back.positions, m.positions);
    assert_eq!(back.normals, pyramid().normals);
}

/// A binary PLY written by hand: `double` coordinates, extra `uchar red` property, a quad and a
/// triangle as `list uchar int vertex_indices`, and an extra trailing element to skip.
fn binary_ply(big_endian: bool) -> (Vec<u8>, Vec<Vec3>, Vec<u32>) {
    let positions = vec![
        Vec3::new(0.5, -1.25, 3.0),
        Vec3::new(2.0, 0.0, 0.1),
        Vec3::new(1.0e-3, 4.0, -7.5),
        Vec3::new(-2.0, 3.0, 1.0),
        Vec3::new(9.0, 9.0, 9.0),
    ];
    let faces: Vec<Vec<i32>> = vec![vec![0, 1, 2, 3], vec![1, 4, 2]];
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\ncomment hand-written\nelement vertex {}\n\
         property double x\nproperty double y\nproperty double z\nproperty uchar red\n\
         element face {}\nproperty list uchar int vertex_indices\n\
         element note 1\nproperty ushort value\nend_header\n",
        positions.len(),
        faces.len()
    )
    .into_bytes();
    let f64b = |v: f64| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let i32b = |v: i32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    for p in &positions {
        for c in p.to_array() {
            out.extend_from_slice(&f64b(c as f64));
        }
        out.push(200); // red
    }
    for f in &faces {
        out.push(f.len() as u8);
        for &i in f {
            out.extend_from_slice(&i32b(i));
        }
    }
    out.extend_from_slice(&if big_endian {
        7u16.to_be_bytes()
    } else {
        7u16.to_le_bytes()
    });
    // The quad is fan-triangulated from its first corner.
    (out, positions, vec![0, 1, 2, 0, 2, 3, 1, 4, 2])
}

#[test]
fn ply_binary_little_endian_loads_exactly() {
    let dir = temp_dir("ply_le");
    let (bytes, positions, indices) = binary_ply(false);
    let m = load_one(&write(&dir, "le.ply", &bytes));
    assert_eq!(m.positions, positions);
    assert_eq!(m.indices, indices);
    assert_unit_normals(&m);
}

#[test]
fn ply_binary_big_endian_loads_exactly() {
    let dir = temp_dir("ply_be");
    let (bytes, positions, indices) = binary_ply(true);
    let m = load_one(&write(&dir, "be.PLY", &bytes));
    assert_eq!(m.positions, positions);
    assert_eq!(m.indices, indices);
}

#[test]
fn ply_binary_float_normals_and_uint_vertex_index() {
    let dir = temp_dir("ply_be_normals");
    let m = pyramid();
    let mut out = format!(
        "ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nproperty float nx\nproperty float ny\n\
         property float nz\nelement face {}\nproperty list uint uint vertex_index\nend_header\n",
        m.positions.len(),
        m.triangle_count()
    )
    .into_bytes();
    for (p, n) in m.positions.iter().zip(&m.normals) {
        for c in p.to_array().into_iter().chain(n.to_array()) {
            out.extend_from_slice(&c.to_be_bytes());
        }
    }
    for t in m.indices.chunks(3) {
        out.extend_from_slice(&3u32.to_be_bytes());
        for i in t {
            out.extend_from_slice(&i.to_be_bytes());
        }
    }
    let back = load_one(&write(&dir, "n.ply", &out));
    assert_eq!(back.positions, m.positions);
    assert_eq!(back.indices, m.indices);
    assert_eq!(back.normals, m.normals);
}

#[test]
fn ply_gz_round_trip_is_exact() {
    let dir = temp_dir("ply_gz");
    let m = pyramid();
    let mut ply = Vec::new();
    write_ply_ascii(&m, &mut ply).unwrap();
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(&ply).unwrap();
    let back = load_one(&write(&dir, "pyramid.ply.gz", &enc.finish().unwrap()));
    assert_eq!(back.positions, m.positions);
    assert_eq!(back.indices, m.indices);
    assert_eq!(back.normals, m.normals);

    // Binary inside gzip too.
    let (bytes, positions, indices) = binary_ply(false);
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(&bytes).unwrap();
    let back = load_one(&write(&dir, "LE.PLY.GZ", &enc.finish().unwrap()));
    assert_eq!((back.positions, back.indices), (positions, indices));
}

#[test]
fn ply_truncated_binary_is_parse_error() {
    let dir = temp_dir("ply_truncated");
    let (bytes, _, _) = binary_ply(false);
    for cut in [bytes.len() - 3, bytes.len() - 30, bytes.len() - 60] {
        let p = write(&dir, "cut.ply", &bytes[..cut]);
        let e = load_mesh(&p).unwrap_err();
        assert!(matches!(e, SceneError::Parse { .. }), "cut at {cut}: {e:?}");
        assert!(e.to_string().contains("cut.ply"), "{e}");
    }
}

#[test]
fn ply_out_of_range_face_index_is_invalid_mesh() {
    let dir = temp_dir("ply_range");
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n";
    let e = load_mesh(&write(&dir, "range.ply", text.as_bytes())).unwrap_err();
    assert!(matches!(e, SceneError::InvalidMesh { .. }), "{e:?}");
    assert!(e.to_string().contains("out of range"), "{e}");

    let negative = text.replace("3 0 1 3\n", "3 0 1 -1\n");
    let e = load_mesh(&write(&dir, "neg.ply", negative.as_bytes())).unwrap_err();
    assert!(matches!(e, SceneError::InvalidMesh { .. }), "{e:?}");
}

#[test]
fn ply_header_promising_too_many_faces_is_too_large() {
    let dir = temp_dir("ply_many_faces");
    let text = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
         property float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        loaders::MAX_TRIANGLES + 1
    );
    let e = load_mesh(&write(&dir, "huge.ply", text.as_bytes())).unwrap_err();
    assert!(matches!(e, SceneError::TooLarge { .. }), "{e:?}");
}

#[test]
fn ply_without_faces_or_coordinates_is_parse_error() {
    let dir = temp_dir("ply_points");
    let points = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                  property float z\nend_header\n0 0 0\n";
    let e = load_mesh(&write(&dir, "points.ply", points.as_bytes())).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e:?}");
    let no_z = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n";
    let e = load_mesh(&write(&dir, "noz.ply", no_z.as_bytes())).unwrap_err();
    assert!(e.to_string().contains("'z'"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// glTF
// ---------------------------------------------------------------------------------------------

fn base64(bytes: &[u8]) -> String {
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
fn quad_buffer() -> Vec<u8> {
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
fn gltf_json(nodes: &str, buffer_uri: Option<&str>, buffer_len: usize) -> String {
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

fn embedded_gltf(nodes: &str) -> String {
    let buf = quad_buffer();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&buf));
    gltf_json(nodes, Some(&uri), buf.len())
}

const QUAD: [Vec3; 4] = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];

#[test]
fn gltf_node_translation_is_baked() {
    let dir = temp_dir("gltf_translation");
    let json = embedded_gltf(r#"[ { "mesh": 0, "translation": [1, 2, 3] } ]"#);
    let m = load_one(&write(&dir, "quad.gltf", json.as_bytes()));
    let expect: Vec<Vec3> = QUAD.iter().map(|p| *p + Vec3::new(1.0, 2.0, 3.0)).collect();
    assert_eq!(m.positions, expect);
    assert_eq!(m.indices, vec![0, 1, 2, 0, 2, 3]);
    assert_eq!(m.normals, vec![Vec3::Z; 4]);
    assert!(m.name.contains("quad"), "{}", m.name);
}

#[test]
fn gltf_hierarchy_is_composed_and_normals_rotated() {
    let dir = temp_dir("gltf_hierarchy");
    // Parent: translate (10, 0, 0) and rotate +90° about X; child: uniform scale 2 with the quad,
    // and a second child with the non-indexed triangle.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let nodes = format!(
        r#"[ {{ "translation": [10, 0, 0], "rotation": [{s}, 0, 0, {s}], "children": [1, 2] }},
            {{ "mesh": 0, "scale": [2, 2, 2] }},
            {{ "mesh": 1 }} ]"#
    );
    let meshes = load_mesh(&write(&dir, "h.gltf", embedded_gltf(&nodes).as_bytes())).unwrap();
    assert_eq!(meshes.len(), 2);
    let rot = |p: Vec3| Vec3::new(p.x, -p.z, p.y); // +90° about X
    for (got, p) in meshes[0].positions.iter().zip(QUAD) {
        let want = Vec3::new(10.0, 0.0, 0.0) + rot(p * 2.0);
        assert!((*got - want).length() < 1e-5, "{got} vs {want}");
    }
    for n in &meshes[0].normals {
        assert!((*n - Vec3::NEG_Y).length() < 1e-5, "normal {n}"); // +Z rotated about X
    }
    // The non-indexed primitive gets 0..n indices and computed normals.
    let tri = &meshes[1];
    assert_eq!(tri.indices, vec![0, 1, 2]);
    assert!((tri.positions[1] - Vec3::new(12.0, 0.0, 0.0)).length() < 1e-5);
    assert_unit_normals(tri);
    assert_normals_match_winding(tri);
}

#[test]
fn gltf_mirroring_transform_keeps_outward_winding() {
    let dir = temp_dir("gltf_mirror");
    let json = embedded_gltf(r#"[ { "mesh": 0, "scale": [1, 1, -1] } ]"#);
    let m = load_one(&write(&dir, "m.gltf", json.as_bytes()));
    for n in &m.normals {
        assert!((*n - Vec3::NEG_Z).length() < 1e-6, "{n}");
    }
    assert_normals_match_winding(&m);
}

#[test]
fn gltf_external_buffer_and_glb() {
    let dir = temp_dir("gltf_external");
    let buf = quad_buffer();
    write(&dir, "quad data.bin", &buf);
    let nodes = r#"[ { "mesh": 0, "translation": [0, 0, 5] } ]"#;
    let json = gltf_json(nodes, Some("quad%20data.bin"), buf.len());
    let ext = load_one(&write(&dir, "ext.gltf", json.as_bytes()));

    // The same document as binary glTF: header, JSON chunk, BIN chunk (each 4-byte aligned).
    let mut json = gltf_json(nodes, None, buf.len()).into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = buf.clone();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    let from_glb = load_one(&write(&dir, "quad.GLB", &glb));
    assert_eq!(
        (&ext.positions, &ext.normals, &ext.indices),
        (&from_glb.positions, &from_glb.normals, &from_glb.indices)
    );
    assert_eq!(ext.positions[2], Vec3::new(1.0, 1.0, 5.0));

    // A truncated GLB fails cleanly.
    let e = load_mesh(&write(&dir, "cut.glb", &glb[..glb.len() - 20])).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e:?}");
}

#[test]
fn gltf_bad_accessor_is_an_error_not_a_panic() {
    let dir = temp_dir("gltf_bad_accessor");
    let good = embedded_gltf(r#"[ { "mesh": 0 } ]"#);
    let cases = [
        // Index accessor reaching past its buffer view.
        good.replace(
            r#""componentType": 5123, "count": 6"#,
            r#""componentType": 5123, "count": 60"#,
        ),
        // Positions declared as unsigned bytes.
        good.replacen(
            r#""componentType": 5126, "count": 4, "type": "VEC3""#,
            r#""componentType": 5121, "count": 4, "type": "VEC3""#,
            1,
        ),
        // A stride smaller than one element.
        good.replace(
            r#""byteLength": 96 }"#,
            r#""byteLength": 96, "byteStride": 4 }"#,
        ),
        // Index referring to a missing vertex.
        good.replace(
            r#""bufferView": 1, "componentType": 5123, "count": 6"#,
            r#""bufferView": 0, "byteOffset": 12, "componentType": 5123, "count": 6"#,
        ),
        // A node that is its own child.
        good.replace(
            r#"[ { "mesh": 0 } ]"#,
            r#"[ { "mesh": 0, "children": [0] } ]"#,
        ),
    ];
    let reasons = [
        "outside its buffer",
        "expected Vec3",
        "stride",
        "out of range",
        "reached twice",
    ];
    for (i, (json, reason)) in cases.iter().zip(reasons).enumerate() {
        assert_ne!(json, &good, "case {i} did not change the document");
        match load_mesh(&write(&dir, &format!("bad{i}.gltf"), json.as_bytes())) {
            Err(e) => assert!(e.to_string().contains(reason), "case {i}: {e}"),
            Ok(m) => panic!("case {i} loaded: {m:?}"),
        }
    }
    // The untouched document loads.
    load_one(&write(&dir, "good.gltf", good.as_bytes()));
}

// ---------------------------------------------------------------------------------------------
// Bad input of every kind: an error, never a panic.
// ---------------------------------------------------------------------------------------------

fn garbage(len: usize, seed: u64) -> Vec<u8> {
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
