//! Mesh loader tests: every file is generated here, in a temporary directory.

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec2, Vec3};
use manyshadows_scene::builtin::{
    DIRECTIONAL_CASCADES, DIRECTIONAL_SHADOW_RESOLUTION, DIRECTIONAL_SPLIT_LAMBDA,
    POINT_SHADOW_RESOLUTION, SPOT_SHADOW_RESOLUTION,
};
use manyshadows_scene::loaders::{
    self, load_mesh, load_scene, write_gltf, write_obj, write_ply_ascii, LoadedScene, PHONG_PER_LUX,
};
use manyshadows_scene::{
    AlphaMode, Attenuation, Camera, Instance, Light, LightKind, Material, Mesh, Scene, SceneError,
    Texture, TextureRef, Wrap,
};
use serde_json::{json, Value};

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

/// The mesh has exactly the triangles `indices` over `positions` (corner positions compared
/// exactly): vertices the file shares may have been split for crease-angle normals, but the
/// file's vertices keep their indices.
fn assert_same_triangles(m: &Mesh, positions: &[Vec3], indices: &[u32]) {
    assert_eq!(m.indices.len(), indices.len(), "{}", m.name);
    assert_eq!(&m.positions[..positions.len()], positions, "{}", m.name);
    for (got, want) in m.indices.iter().zip(indices) {
        assert_eq!(
            m.positions[*got as usize], positions[*want as usize],
            "{}",
            m.name
        );
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
        indices: vec![0, 1, 2, 0, 2, 3, 0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0],
        ..Mesh::default()
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
fn obj_cube_without_normals_gets_flat_faces() {
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
    // The eight shared corners meet at 90°, beyond the crease angle: three vertices each.
    assert_eq!(m.positions.len(), 24);
    assert_unit_normals(&m);
    assert_normals_match_winding(&m);
    for n in &m.normals {
        assert!(CUBE_NORMALS.contains(n), "{n} is not a face normal");
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
    // Crease-angle normals: the base's corners split from the steep sides.
    let mut want = m.clone();
    want.compute_normals_with_crease(loaders::CREASE_ANGLE_DEG);
    assert!(want.positions.len() > m.positions.len());
    assert_eq!(back.positions, want.positions);
    assert_eq!(back.indices, want.indices);
    assert_eq!(back.normals, want.normals);
    assert_normals_match_winding(&back);
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
    assert_same_triangles(&m, &positions, &indices);
    assert_unit_normals(&m);
}

#[test]
fn ply_binary_big_endian_loads_exactly() {
    let dir = temp_dir("ply_be");
    let (bytes, positions, indices) = binary_ply(true);
    let m = load_one(&write(&dir, "be.PLY", &bytes));
    assert_same_triangles(&m, &positions, &indices);
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
    assert_same_triangles(&back, &positions, &indices);
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

// ---------------------------------------------------------------------------------------------
// Crease-angle normals
// ---------------------------------------------------------------------------------------------

/// The cube above as a mesh: eight shared corners, twelve triangles, no normals.
fn shared_cube() -> Mesh {
    let positions = CUBE_V
        .lines()
        .map(|l| {
            let c: Vec<f32> = l.trim()[2..]
                .split(' ')
                .map(|s| s.parse().unwrap())
                .collect();
            Vec3::new(c[0], c[1], c[2])
        })
        .collect();
    let mut indices = Vec::new();
    for q in CUBE_QUADS {
        let q = q.map(|i| i - 1);
        indices.extend_from_slice(&[q[0], q[1], q[2], q[0], q[2], q[3]]);
    }
    Mesh {
        name: "cube".into(),
        positions,
        indices,
        ..Mesh::default()
    }
}

#[test]
fn crease_normals_keep_a_box_flat() {
    let mut m = shared_cube();
    // Texture coordinates are carried along when vertices split.
    m.uvs = (0..8).map(|i| Vec2::new(i as f32, 0.5)).collect();
    let before = m.clone();
    m.compute_normals_with_crease(loaders::CREASE_ANGLE_DEG);
    m.validate().unwrap();
    assert_eq!(m.positions.len(), 24);
    assert_eq!(m.triangle_count(), 12);
    for (t0, t1) in before.indices.chunks(3).zip(m.indices.chunks(3)) {
        let [a, b, c] = [0, 1, 2].map(|k| m.positions[t1[k] as usize]);
        let face = (b - a).cross(c - a).normalize();
        for k in 0..3 {
            let (old, new) = (t0[k] as usize, t1[k] as usize);
            assert_eq!(m.positions[new], before.positions[old]);
            assert_eq!(m.uvs[new], before.uvs[old]);
            assert!(
                (m.normals[new] - face).length() < 1e-6,
                "vertex normal {} is not its face's {face}",
                m.normals[new]
            );
        }
    }
}

#[test]
fn crease_normals_keep_a_finely_tessellated_cylinder_smooth() {
    const SEGMENTS: u32 = 64;
    let mut m = Mesh {
        name: "cylinder side".into(),
        ..Mesh::default()
    };
    for y in [0.0, 2.0] {
        for k in 0..SEGMENTS {
            let a = k as f32 / SEGMENTS as f32 * std::f32::consts::TAU;
            m.positions.push(Vec3::new(a.cos(), y, -a.sin()));
        }
    }
    for k in 0..SEGMENTS {
        let (b0, b1) = (k, (k + 1) % SEGMENTS);
        let (t0, t1) = (b0 + SEGMENTS, b1 + SEGMENTS);
        m.indices.extend_from_slice(&[b0, b1, t1, b0, t1, t0]);
    }
    m.compute_normals_with_crease(loaders::CREASE_ANGLE_DEG);
    m.validate().unwrap();
    // No vertex split: every vertex has one smooth normal, close to radial.
    assert_eq!(m.positions.len(), 2 * SEGMENTS as usize);
    assert_normals_match_winding(&m);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let radial = Vec3::new(p.x, 0.0, p.z).normalize();
        assert!(n.y.abs() < 1e-6, "{n}");
        assert!(n.dot(radial) > 2f32.to_radians().cos(), "{n} vs {radial}");
    }
}

// ---------------------------------------------------------------------------------------------
// Whole scenes: helpers
// ---------------------------------------------------------------------------------------------

/// The quad document of [`embedded_gltf`] as JSON, to be extended by a test.
fn quad_doc(nodes: Value) -> Value {
    serde_json::from_str(&embedded_gltf(&nodes.to_string())).unwrap()
}

fn save_json(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    write(dir, name, doc.to_string().as_bytes())
}

fn scene_of(path: &Path) -> LoadedScene {
    load_scene(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn png(t: &Texture) -> Vec<u8> {
    let mut out = Vec::new();
    image::RgbaImage::from_raw(t.width, t.height, t.rgba.to_vec())
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

fn grey_png(width: u32, height: u32, f: impl Fn(u32, u32) -> u8) -> Vec<u8> {
    let mut out = Vec::new();
    image::GrayImage::from_fn(width, height, |x, y| image::Luma([f(x, y)]))
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).length() <= tolerance * (1.0 + a.length().max(b.length()))
}

/// A glTF document of one mesh with one primitive over `positions` (VEC3 floats), with
/// optional u32 `indices` and the given `mode`, embedded.
fn primitive_doc(positions: &[Vec3], indices: Option<&[u32]>, mode: u32) -> Value {
    let mut bin: Vec<u8> = positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let pos_len = bin.len();
    let (lo, hi) = positions
        .iter()
        .fold((positions[0], positions[0]), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let mut accessors = vec![json!({
        "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3",
        "min": lo.to_array(), "max": hi.to_array()
    })];
    let mut views = vec![json!({ "buffer": 0, "byteOffset": 0, "byteLength": pos_len })];
    let mut primitive = json!({ "attributes": { "POSITION": 0 }, "mode": mode });
    if let Some(idx) = indices {
        bin.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
        views.push(json!({ "buffer": 0, "byteOffset": pos_len, "byteLength": 4 * idx.len() }));
        accessors.push(json!({
            "bufferView": 1, "componentType": 5125, "count": idx.len(), "type": "SCALAR"
        }));
        primitive["indices"] = json!(1);
    }
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "name": "m", "primitives": [primitive] }],
        "buffers": [{
            "byteLength": bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64(&bin)),
        }],
        "bufferViews": views,
        "accessors": accessors,
    })
}

// ---------------------------------------------------------------------------------------------
// glTF conformance
// ---------------------------------------------------------------------------------------------

#[test]
fn gltf_strips_and_fans_equal_their_triangle_lists() {
    let dir = temp_dir("gltf_strip_fan");
    // A bent ribbon (so normals are not all equal) and a bent fan.
    let ribbon: Vec<Vec3> = (0..7)
        .map(|i| Vec3::new((i / 2) as f32, (i % 2) as f32, 0.3 * (i as f32).sin()))
        .collect();
    let load = |name: &str, doc: Value| load_one(&save_json(&dir, name, &doc));

    // glTF 2.0 §3.7.2.1: strip triangle i = (v_i, v_{i+1+i%2}, v_{i+2-i%2}).
    let strip_list: Vec<u32> = vec![0, 1, 2, 1, 3, 2, 2, 3, 4, 3, 5, 4, 4, 5, 6];
    let list = load(
        "strip_list.gltf",
        primitive_doc(&ribbon, Some(&strip_list), 4),
    );
    let order: Vec<u32> = (0..7).collect();
    for (name, doc) in [
        ("strip.gltf", primitive_doc(&ribbon, None, 5)),
        (
            "strip_indexed.gltf",
            primitive_doc(&ribbon, Some(&order), 5),
        ),
    ] {
        let strip = load(name, doc);
        assert_eq!(
            strip,
            Mesh {
                name: strip.name.clone(),
                ..list.clone()
            },
            "{name}"
        );
    }
    assert_normals_match_winding(&list);

    // Fan triangle i = (v_{i+1}, v_{i+2}, v_0).
    let mut fan_points = vec![Vec3::new(0.0, 0.0, 0.5)];
    for k in 0..6 {
        let a = k as f32 * 0.6;
        fan_points.push(Vec3::new(a.cos(), a.sin(), 0.0));
    }
    let fan_list: Vec<u32> = vec![1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5, 0, 5, 6, 0];
    let list = load(
        "fan_list.gltf",
        primitive_doc(&fan_points, Some(&fan_list), 4),
    );
    for (name, doc) in [
        ("fan.gltf", primitive_doc(&fan_points, None, 6)),
        (
            "fan_indexed.gltf",
            primitive_doc(&fan_points, Some(&order), 6),
        ),
    ] {
        let fan = load(name, doc);
        assert_eq!(
            fan,
            Mesh {
                name: fan.name.clone(),
                ..list.clone()
            },
            "{name}"
        );
    }
    assert_normals_match_winding(&list);
    assert_eq!(list.triangle_count(), 5);
}

#[test]
fn gltf_lines_and_points_are_skipped_with_a_note() {
    let dir = temp_dir("gltf_lines");
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    let triangle = doc["meshes"][0]["primitives"][0].clone();
    let mut lines = triangle.clone();
    lines["mode"] = json!(1);
    doc["meshes"][0]["primitives"] = json!([triangle, lines]);
    let loaded = scene_of(&save_json(&dir, "lines.gltf", &doc));
    assert_eq!(loaded.scene.meshes.len(), 1);
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("1 point or line primitive(s) skipped")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn gltf_1_0_is_refused_with_a_clear_message() {
    let dir = temp_dir("gltf1");
    let old = json!({
        "asset": { "version": "1.0" },
        "meshes": { "box": { "primitives": [] } },
        "nodes": { "root": { "meshes": ["box"] } },
        "scene": "default",
        "scenes": { "default": { "nodes": ["root"] } }
    });
    // Also a 2.0-looking version with 1.0's dictionaries.
    let mut dictionaries = old.clone();
    dictionaries["asset"]["version"] = json!("2.0");
    let json_text = old.to_string();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&1u32.to_le_bytes());
    glb.extend_from_slice(&(20 + json_text.len() as u32).to_le_bytes());
    glb.extend_from_slice(&(json_text.len() as u32).to_le_bytes());
    glb.extend_from_slice(&0u32.to_le_bytes());
    glb.extend_from_slice(json_text.as_bytes());
    let files = [
        write(&dir, "old.gltf", json_text.as_bytes()),
        save_json(&dir, "dict.gltf", &dictionaries),
        write(&dir, "old.glb", &glb),
    ];
    for p in &files {
        for result in [load_mesh(p).map(|_| ()), load_scene(p).map(|_| ())] {
            match result {
                Err(SceneError::Parse { reason, .. }) => {
                    assert!(reason.contains("glTF 1.0 is not supported"), "{reason}");
                    assert!(reason.contains("convert"), "{reason}");
                }
                other => panic!("{}: {other:?}", p.display()),
            }
        }
    }
}

#[test]
fn gltf_required_extensions_are_named() {
    let dir = temp_dir("gltf_required");
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = load_scene(&save_json(&dir, "draco.gltf", &doc)).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e:?}");
    assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");

    // A required texture transform still loads, with a note.
    doc["extensionsUsed"] = json!(["KHR_texture_transform"]);
    doc["extensionsRequired"] = json!(["KHR_texture_transform"]);
    let loaded = scene_of(&save_json(&dir, "transform.gltf", &doc));
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("requires KHR_texture_transform")),
        "{:?}",
        loaded.notes
    );
}

// ---------------------------------------------------------------------------------------------
// glTF materials, images, lights, camera
// ---------------------------------------------------------------------------------------------

#[test]
fn gltf_materials_map_to_phong() {
    let dir = temp_dir("gltf_materials");
    let image = Texture::from_fn("checker", 4, 2, |x, y| {
        [x as u8 * 60, y as u8 * 120, 33, 100 + 20 * x as u8]
    });
    let uri = format!("data:image/png;base64,{}", base64(&png(&image)));
    let mut doc = quad_doc(json!([{ "mesh": 0 }, { "mesh": 2 }]));
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    let mut second = doc["meshes"][0].clone();
    second["primitives"][0]["material"] = json!(1);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    doc["meshes"].as_array_mut().unwrap().push(second);
    doc["images"] = json!([{ "uri": uri }]);
    doc["samplers"] = json!([{ "wrapS": 33071, "wrapT": 33648 }]);
    doc["textures"] = json!([{ "source": 0, "sampler": 0 }, { "source": 0 }]);
    doc["materials"] = json!([
        {
            "name": "leaves",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.4, 0.2, 0.5],
                "metallicFactor": 0.5,
                "roughnessFactor": 0.5,
                "baseColorTexture": { "index": 0, "texCoord": 1 }
            },
            "normalTexture": { "index": 1 },
            "alphaMode": "MASK",
            "alphaCutoff": 0.3,
            "doubleSided": true
        },
        {
            "name": "glass",
            "pbrMetallicRoughness": {
                "baseColorTexture": {
                    "index": 1,
                    "extensions": { "KHR_texture_transform": { "scale": [2, 2] } }
                }
            },
            "alphaMode": "BLEND",
            "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 } }
        }
    ]);
    let loaded = scene_of(&save_json(&dir, "materials.gltf", &doc));
    let scene = &loaded.scene;
    assert_eq!(scene.meshes.len(), 2);
    // One image, decoded once for three uses.
    assert_eq!(scene.textures.len(), 1);
    assert_eq!(scene.textures[0].rgba, image.rgba);

    let leaves = scene.materials[scene.instances[0].material];
    let base = Vec3::new(0.8, 0.4, 0.2);
    assert_eq!(leaves.diffuse, base);
    assert_eq!(leaves.ambient, base);
    assert!(close(
        leaves.specular,
        Vec3::splat(0.04).lerp(base, 0.5),
        1e-6
    ));
    // α = 0.5² = 0.25: 2/α² − 2 = 30.
    assert!(
        (leaves.shininess - 30.0).abs() < 1e-4,
        "{}",
        leaves.shininess
    );
    assert_eq!(leaves.base_alpha, 0.5);
    assert_eq!(leaves.alpha_mode, AlphaMode::Mask);
    assert_eq!(leaves.alpha_cutoff, 0.3);
    assert!(leaves.double_sided);
    assert_eq!(
        leaves.base_color_texture,
        Some(TextureRef {
            texture: 0,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::MirroredRepeat
        })
    );
    assert_eq!(leaves.normal_texture, Some(TextureRef::repeat(0)));

    // glTF defaults: white, metallic 1, roughness 1.
    let glass = scene.materials[scene.instances[1].material];
    assert_eq!(glass.diffuse, Vec3::ONE);
    assert_eq!(glass.specular, Vec3::ONE);
    assert_eq!(glass.shininess, 1.0);
    assert_eq!(glass.alpha_mode, AlphaMode::Blend);
    assert!(!glass.double_sided);
    assert_eq!(glass.base_color_texture, Some(TextureRef::repeat(0)));

    let notes = loaded.notes.join("\n");
    assert!(
        notes.contains("material 'leaves': its base-colour texture uses texture-coordinate set 1"),
        "{notes}"
    );
    assert!(
        notes.contains(
            "material 'glass': KHR_materials_transmission, KHR_texture_transform ignored"
        ),
        "{notes}"
    );
    // Texture coordinates: none in this file.
    assert!(scene.meshes[0].uvs.is_empty());
}

#[test]
fn gltf_bad_images_leave_materials_untextured_with_a_note() {
    let dir = temp_dir("gltf_bad_image");
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let garbage_png = base64(b"\x89PNG\r\n\x1a\n this is not really a PNG file");
    let cases = [
        json!({ "uri": format!("data:image/png;base64,{garbage_png}") }),
        json!({ "uri": format!("data:image/png;base64,{}", base64(&garbage(300, 9))) }),
        json!({ "uri": "data:image/png;base64,@@not base64@@" }),
        json!({ "uri": "missing.png" }),
        json!({ "uri": "https://example.com/remote.png" }),
        json!({ "uri": "data:image/png,plain" }),
        json!({ "bufferView": 0, "mimeType": "image/png" }),
        json!({ "bufferView": 0 }),
    ];
    for (i, image) in cases.into_iter().enumerate() {
        doc["images"] = json!([image]);
        doc["textures"] = json!([{ "source": 0 }]);
        doc["materials"] = json!([{
            "name": "broken",
            "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } }
        }]);
        let path = save_json(&dir, &format!("bad{i}.gltf"), &doc);
        let loaded = scene_of(&path);
        let m = loaded.scene.materials[loaded.scene.instances[0].material];
        assert_eq!(m.base_color_texture, None, "case {i}");
        assert!(loaded.scene.textures.is_empty(), "case {i}");
        assert!(
            loaded
                .notes
                .iter()
                .any(|n| n.contains("material 'broken'") && n.contains("could not be used")),
            "case {i}: {:?}",
            loaded.notes
        );
        // Geometry alone does not look at images.
        load_one(&path);
    }
}

/// Three lights under a rotated parent, a camera, the quad: the documented mappings.
fn lights_doc() -> Value {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let mut doc = quad_doc(json!([
        { "mesh": 0 },
        { "name": "spot", "translation": [1, 2, 3], "rotation": [-s, 0, 0, s],
          "extensions": { "KHR_lights_punctual": { "light": 0 } } },
        { "name": "parent", "rotation": [0, s, 0, s], "children": [3, 4] },
        { "name": "sun", "rotation": [-0.38268343, 0, 0, 0.9238795],
          "extensions": { "KHR_lights_punctual": { "light": 1 } } },
        { "name": "bulb", "translation": [-1, 4, 0],
          "extensions": { "KHR_lights_punctual": { "light": 2 } } },
        { "translation": [0, 0, 9], "extensions": { "KHR_lights_punctual": { "light": 3 } } },
        { "translation": [0, 0, -9], "extensions": { "KHR_lights_punctual": { "light": 4 } } },
        { "translation": [2, 0, 0], "rotation": [0, 0, 0, 1],
          "extensions": { "KHR_lights_punctual": { "light": 5 } } }
    ]));
    doc["scenes"][0]["nodes"] = json!([0, 1, 2, 5, 6, 7]);
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "name": "spot", "type": "spot", "color": [1.0, 0.5, 0.25], "intensity": 0.5,
          "spot": { "innerConeAngle": 0.3, "outerConeAngle": 0.5 } },
        { "name": "sun", "type": "directional", "color": [1.0, 0.9, 0.8], "intensity": 30 },
        { "name": "bulb", "type": "point", "intensity": 100, "range": 7.5 },
        { "name": "bright", "type": "point", "intensity": 1000 },
        { "name": "off", "type": "point", "intensity": 0 },
        { "name": "wide", "type": "spot", "spot": { "outerConeAngle": 1.5707964 } }
    ] } });
    doc
}

#[test]
fn gltf_lights_map_to_the_documented_phong_values() {
    let dir = temp_dir("gltf_lights");
    let loaded = scene_of(&save_json(&dir, "lights.gltf", &lights_doc()));
    let lights = &loaded.scene.lights;
    assert_eq!(lights.len(), 6, "{lights:?}");
    assert!(
        !loaded.notes.iter().any(|n| n.contains("no lights")),
        "{:?}",
        loaded.notes
    );
    // The quad spans (0,0,0)..(1,1,0): diagonal √2.
    let diagonal = 2f32.sqrt();
    let inverse_square = Attenuation {
        constant: 1.0,
        linear: 0.0,
        quadratic: 1.0,
    };
    for l in lights {
        assert_eq!(l.ambient, Vec3::ZERO);
        assert_eq!(l.specular, l.diffuse);
        assert!(l.casts_shadows);
        l.validate().unwrap();
    }

    // Spot: −90° about X turns −Z into −Y; colour × intensity × 0.1; range where
    // 0.05 / (1 + d²) = 1/256; cutoff = outer angle.
    let spot = lights[0];
    let LightKind::Spot {
        position,
        direction,
        cutoff_deg,
        range,
    } = spot.kind
    else {
        panic!("{spot:?}")
    };
    assert!(close(position, Vec3::new(1.0, 2.0, 3.0), 1e-6));
    assert!(close(direction, Vec3::NEG_Y, 1e-6), "{direction}");
    assert!((cutoff_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    assert!(close(
        spot.diffuse,
        Vec3::new(1.0, 0.5, 0.25) * 0.5 * PHONG_PER_LUX,
        1e-6
    ));
    assert!(
        (range - (256.0f32 * 0.05 - 1.0).sqrt()).abs() < 1e-4,
        "{range}"
    );
    assert_eq!(spot.attenuation, inverse_square);
    assert_eq!(spot.shadow_resolution, SPOT_SHADOW_RESOLUTION);

    // Directional, under a parent turned +90° about Y: world rotation = parent · child.
    let sun = lights[1];
    let want = Quat::from_xyzw(
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
    ) * Quat::from_xyzw(-0.38268343, 0.0, 0.0, 0.9238795)
        * Vec3::NEG_Z;
    assert_eq!(
        sun.kind,
        LightKind::Directional {
            direction: match sun.kind {
                LightKind::Directional { direction, .. } => direction,
                _ => panic!("{sun:?}"),
            },
            cascades: DIRECTIONAL_CASCADES,
            split_lambda: DIRECTIONAL_SPLIT_LAMBDA,
            cascade_resolution_scale: 1.0,
        }
    );
    if let LightKind::Directional { direction, .. } = sun.kind {
        assert!(close(direction, want, 1e-5), "{direction} vs {want}");
    }
    assert!(close(sun.diffuse, Vec3::new(3.0, 2.7, 2.4), 1e-6));
    assert_eq!(sun.attenuation, Attenuation::NONE);
    assert_eq!(sun.shadow_resolution, DIRECTIONAL_SHADOW_RESOLUTION);

    // Point with a range (its parent's rotation turns its translation).
    let bulb = lights[2];
    let LightKind::Point { position, range } = bulb.kind else {
        panic!("{bulb:?}")
    };
    assert!(
        close(position, Vec3::new(0.0, 4.0, 1.0), 1e-6),
        "{position}"
    );
    assert_eq!(range, 7.5);
    assert!(close(bulb.diffuse, Vec3::splat(10.0), 1e-6));
    assert_eq!(bulb.attenuation, inverse_square);
    assert_eq!(bulb.shadow_resolution, POINT_SHADOW_RESOLUTION);

    // Bright point without a range: clamped to 4 × the diagonal; a dark one: at least 0.1.
    let LightKind::Point { range, .. } = lights[3].kind else {
        panic!()
    };
    assert!((range - 4.0 * diagonal).abs() < 1e-5, "{range}");
    let off = lights[4];
    assert_eq!(off.diffuse, Vec3::ZERO);
    let LightKind::Point { range, .. } = off.kind else {
        panic!()
    };
    assert_eq!(range, 0.1);

    // A 90° glTF cone is clamped just inside this renderer's limit.
    let LightKind::Spot {
        cutoff_deg,
        direction,
        ..
    } = lights[5].kind
    else {
        panic!()
    };
    assert!(cutoff_deg < 89.0 && cutoff_deg > 88.9, "{cutoff_deg}");
    assert_eq!(direction, Vec3::NEG_Z);
}

#[test]
fn gltf_camera_node_maps_to_the_documented_camera() {
    let dir = temp_dir("gltf_camera");
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let mut doc = quad_doc(json!([
        { "mesh": 0 },
        { "name": "ortho", "camera": 1 },
        { "name": "eye", "translation": [0, 2, 10], "rotation": [0, s, 0, s], "camera": 0 }
    ]));
    doc["scenes"][0]["nodes"] = json!([0, 1, 2]);
    doc["cameras"] = json!([
        { "name": "main", "type": "perspective",
          "perspective": { "yfov": 0.8, "znear": 0.05, "zfar": 500, "aspectRatio": 1.5 } },
        { "name": "top", "type": "orthographic",
          "orthographic": { "xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10 } }
    ]);
    let loaded = scene_of(&save_json(&dir, "camera.gltf", &doc));
    let c = loaded.scene.camera;
    let position = Vec3::new(0.0, 2.0, 10.0);
    // +90° about Y turns −Z into −X.
    let centre = Vec3::new(0.5, 0.5, 0.0);
    let distance = (centre - position).length();
    assert!(close(c.position, position, 1e-6));
    assert!(
        close(c.target, position + Vec3::NEG_X * distance, 1e-5),
        "{}",
        c.target
    );
    assert!(close(c.up, Vec3::Y, 1e-6));
    assert!((c.fov_y_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!((c.near, c.far), (0.05, 500.0));
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("camera 'top' is orthographic") && n.contains("'main' is used")),
        "{:?}",
        loaded.notes
    );

    // Infinite projection: far = near + 4 × the diagonal.
    doc["cameras"][0]["perspective"] = json!({ "yfov": 0.8, "znear": 0.05 });
    let c = scene_of(&save_json(&dir, "infinite.gltf", &doc))
        .scene
        .camera;
    assert!(
        (c.far - (0.05 + 4.0 * 2f32.sqrt())).abs() < 1e-5,
        "{}",
        c.far
    );

    // Only an orthographic camera: the default camera, and a note.
    doc["nodes"][2].as_object_mut().unwrap().remove("camera");
    let loaded = scene_of(&save_json(&dir, "ortho.gltf", &doc));
    assert_eq!(loaded.scene.camera, default_camera_for(centre, 2f32.sqrt()));
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("orthographic") && n.contains("the default camera is used")),
        "{:?}",
        loaded.notes
    );
}

/// The documented default camera for bounds of this centre and diagonal.
fn default_camera_for(centre: Vec3, diagonal: f32) -> Camera {
    let distance = 1.1 * (diagonal / 2.0) / 30f32.to_radians().sin();
    Camera {
        position: centre + Vec3::new(1.0, 0.6, 1.0).normalize() * distance,
        target: centre,
        up: Vec3::Y,
        fov_y_deg: 60.0,
        near: diagonal / 1000.0,
        far: 4.0 * diagonal + distance,
    }
}

#[test]
fn files_without_lights_or_camera_get_defaults_and_a_note() {
    let dir = temp_dir("defaults");
    let gltf = save_json(&dir, "plain.gltf", &quad_doc(json!([{ "mesh": 0 }])));
    let mut ply = Vec::new();
    write_ply_ascii(&pyramid(), &mut ply).unwrap();
    let ply = write(&dir, "pyramid.ply", &ply);
    for path in [gltf, ply] {
        let loaded = scene_of(&path);
        let scene = &loaded.scene;
        assert_eq!(scene.lights.len(), 8);
        let count = |t: &str| scene.lights.iter().filter(|l| l.type_name() == t).count();
        assert_eq!(
            (count("spot"), count("point"), count("directional")),
            (5, 2, 1)
        );
        assert!(
            loaded.notes.contains(
                &"the file has no lights: added 8 seeded lights (5 spot, 2 point, 1 directional)"
                    .to_string()
            ),
            "{:?}",
            loaded.notes
        );
        let (lo, hi) = scene.world_bounds(false).unwrap();
        let want = default_camera_for((lo + hi) / 2.0, (hi - lo).length());
        assert!(close(scene.camera.position, want.position, 1e-6));
        assert_eq!(scene.camera.target, want.target);
        assert!((scene.camera.near - want.near).abs() < 1e-7);
        assert!((scene.camera.far - want.far).abs() < 1e-5);
        // One identity instance per mesh, casting shadows.
        for (i, inst) in scene.instances.iter().enumerate() {
            assert_eq!(inst.mesh, i);
            assert_eq!(inst.transform, Mat4::IDENTITY);
            assert!(inst.casts_shadows);
        }
        scene.validate().unwrap();
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ materials
// ---------------------------------------------------------------------------------------------

const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
                            usemtl leaf\nf 1/1/1 2/2/1 3/3/1\n";

#[test]
fn obj_with_missing_or_empty_mtl_gets_default_materials_and_a_note() {
    let dir = temp_dir("obj_mtl_missing");
    let missing = write(
        &dir,
        "missing.obj",
        format!("mtllib nowhere.mtl\n{TRIANGLE_OBJ}").as_bytes(),
    );
    write(&dir, "empty.mtl", b"");
    let empty = write(
        &dir,
        "empty.obj",
        format!("mtllib empty.mtl\n{TRIANGLE_OBJ}").as_bytes(),
    );
    for (path, says) in [(missing, "could not be read"), (empty, "is empty")] {
        let loaded = scene_of(&path);
        let scene = &loaded.scene;
        assert_eq!(scene.meshes.len(), 1);
        assert_eq!(scene.materials, vec![Material::default()]);
        assert!(scene.textures.is_empty());
        assert!(
            loaded
                .notes
                .iter()
                .any(|n| n.contains(says) && n.contains(".mtl") && n.contains("default materials")),
            "{}: {:?}",
            path.display(),
            loaded.notes
        );
        // v is flipped to glTF's convention.
        assert_eq!(
            scene.meshes[0].uvs,
            vec![
                Vec2::new(0.0, 1.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 0.0)
            ]
        );
    }
}

#[test]
fn obj_map_d_becomes_the_alpha_of_a_masked_material() {
    let dir = temp_dir("obj_map_d");
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    let colour = Texture::from_fn("leaf", 4, 4, |x, y| [x as u8 * 50, y as u8 * 60, 200, 255]);
    write(&dir, "textures/leaf.png", &png(&colour));
    let mask = |x: u32, y: u32| (x * 70 + y * 13) as u8;
    write(&dir, "textures/leaf mask.png", &grey_png(4, 4, mask));
    write(
        &dir,
        "scene.mtl",
        b"newmtl leaf\nKa 0 0 0\nKd 0.5 0.6 0.7\nKs 0.1 0.1 0.1\nNs 20\nd 0.5\n\
          map_Kd -bm 1.0 -s 1 1 1 textures\\leaf.png\nmap_d textures/leaf mask.png\n",
    );
    let path = write(
        &dir,
        "scene.obj",
        format!("mtllib scene.mtl\no leaf\n{TRIANGLE_OBJ}").as_bytes(),
    );
    let loaded = scene_of(&path);
    assert!(
        !loaded.notes.iter().any(|n| n.contains("leaf")),
        "{:?}",
        loaded.notes
    );
    let scene = &loaded.scene;
    let m = scene.materials[scene.instances[0].material];
    assert_eq!(m.diffuse, Vec3::new(0.5, 0.6, 0.7));
    assert_eq!(m.ambient, m.diffuse, "black Ka means Kd");
    assert_eq!(m.specular, Vec3::splat(0.1));
    assert_eq!(m.shininess, 20.0);
    assert_eq!(m.alpha_mode, AlphaMode::Mask);
    assert_eq!(m.alpha_cutoff, 0.5);
    assert!(m.double_sided);
    assert_eq!(m.base_alpha, 1.0, "d without map_d is ignored");
    let t = &scene.textures[m.base_color_texture.unwrap().texture];
    assert_eq!((t.width, t.height), (4, 4));
    for y in 0..4 {
        for x in 0..4 {
            let [r, g, b, a] = t.texel(x, y);
            assert_eq!([r, g, b], colour.texel(x, y)[..3], "texel ({x}, {y})");
            assert_eq!(a, mask(x, y), "texel ({x}, {y})");
        }
    }
}

#[test]
fn obj_bump_maps_are_normal_maps_only_in_colour() {
    let dir = temp_dir("obj_bump");
    let normal_map = Texture::from_fn("n", 2, 2, |x, _| [128 + x as u8, 128, 255, 255]);
    write(&dir, "normal.png", &png(&normal_map));
    write(
        &dir,
        "height.png",
        &grey_png(2, 2, |x, y| (x * 100 + y) as u8),
    );
    write(
        &dir,
        "m.mtl",
        b"newmtl leaf\nKd 1 1 1\nnorm normal.png\n\nnewmtl stone\nKd 1 1 1\n\
          map_bump -bm 0.3 height.png\n\nnewmtl lost\nmap_Kd nothere.jpg\n",
    );
    let obj = format!(
        "mtllib m.mtl\no a\n{TRIANGLE_OBJ}o b\nusemtl stone\nf 1/1/1 3/3/1 2/2/1\n\
         o c\nusemtl lost\nf 1/1/1 2/2/1 3/3/1\n"
    );
    let loaded = scene_of(&write(&dir, "m.obj", obj.as_bytes()));
    let scene = &loaded.scene;
    assert_eq!(scene.meshes.len(), 3);
    let material = |i: usize| scene.materials[scene.instances[i].material];
    let leaf = material(0);
    let t = leaf.normal_texture.expect("a colour normal map is used");
    assert_eq!(scene.textures[t.texture].rgba, normal_map.rgba);
    assert_eq!(material(1).normal_texture, None);
    assert_eq!(material(2).base_color_texture, None);
    let notes = loaded.notes.join("\n");
    assert!(
        notes.contains("greyscale bump maps") && notes.contains("'stone'"),
        "{notes}"
    );
    assert!(
        notes.contains("material 'lost': map_Kd 'nothere.jpg' could not be used"),
        "{notes}"
    );
}

// ---------------------------------------------------------------------------------------------
// The glTF writer
// ---------------------------------------------------------------------------------------------

/// A scene with everything the writer writes: textured and masked materials, meshes with and
/// without texture coordinates, a transformed instance, every light type, a camera.
fn writer_scene() -> Scene {
    let card = manyshadows_scene::primitives::card(2.0, 3.0, Vec2::new(2.0, 1.0));
    let cube = manyshadows_scene::primitives::cuboid(Vec3::new(1.0, 2.0, 0.5));
    let mut plain = pyramid();
    plain.name = "plain".into();
    let leaves = Texture::from_fn("leaves", 8, 4, |x, y| {
        [
            x as u8 * 30,
            y as u8 * 60,
            90,
            if (x + y) % 3 == 0 { 0 } else { 255 },
        ]
    });
    let bumps = Texture::from_fn("bumps", 2, 2, |x, y| {
        [128 + x as u8, 127 + y as u8, 250, 255]
    });
    let masked = Material {
        base_color_texture: Some(TextureRef {
            texture: 0,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::MirroredRepeat,
        }),
        base_alpha: 0.8,
        ..Material::matte(Vec3::new(0.3, 0.7, 0.2)).masked(0.3)
    };
    let grey = Material {
        ambient: Vec3::splat(0.6),
        diffuse: Vec3::splat(0.6),
        specular: Vec3::splat(0.25),
        shininess: 32.0,
        normal_texture: Some(TextureRef::repeat(1)),
        ..Material::default()
    };
    let blend = Material {
        alpha_mode: AlphaMode::Blend,
        base_color_texture: Some(TextureRef::repeat(0)),
        ..Material::matte(Vec3::new(0.9, 0.1, 0.1))
    };
    let moved = Mat4::from_scale_rotation_translation(
        Vec3::splat(1.5),
        Quat::from_rotation_y(0.7),
        Vec3::new(3.0, 0.0, -2.0),
    );
    let light = |kind, colour: Vec3| Light {
        kind,
        ambient: Vec3::ZERO,
        diffuse: colour,
        specular: colour,
        attenuation: Attenuation {
            constant: 1.0,
            linear: 0.0,
            quadratic: 1.0,
        },
        casts_shadows: true,
        shadow_resolution: 512,
    };
    Scene {
        name: "writer".into(),
        meshes: vec![card, cube, plain],
        materials: vec![masked, grey, blend],
        textures: vec![leaves, bumps],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 1, Mat4::IDENTITY),
            Instance::caster(2, 2, Mat4::IDENTITY),
            Instance::caster(1, 0, moved),
        ],
        lights: vec![
            light(
                LightKind::Spot {
                    position: Vec3::new(1.0, 5.0, 2.0),
                    direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
                    cutoff_deg: 35.0,
                    range: 12.5,
                },
                Vec3::new(2.0, 1.5, 0.5),
            ),
            light(
                LightKind::Point {
                    position: Vec3::new(-2.0, 3.0, 0.5),
                    range: 6.0,
                },
                Vec3::new(0.3, 0.3, 0.4),
            ),
            light(
                LightKind::Directional {
                    direction: Vec3::new(0.0, 0.0, 1.0),
                    cascades: 3,
                    split_lambda: 0.75,
                    cascade_resolution_scale: 1.0,
                },
                Vec3::new(1.0, 0.95, 0.9),
            ),
            light(
                LightKind::Spot {
                    position: Vec3::new(0.0, 4.0, 0.0),
                    direction: Vec3::NEG_Y,
                    cutoff_deg: 80.0,
                    range: 3.0,
                },
                Vec3::ZERO,
            ),
        ],
        camera: Camera {
            position: Vec3::new(4.0, 3.0, 6.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::new(0.1, 1.0, 0.0),
            fov_y_deg: 50.0,
            near: 0.2,
            far: 300.0,
        },
    }
}

#[test]
fn written_gltf_loads_back_the_same_scene() {
    let dir = temp_dir("write_gltf");
    let original = writer_scene();
    original.validate().unwrap();
    for name in ["scene.gltf", "scene.GLB"] {
        let path = dir.join(name);
        write_gltf(&original, &path).unwrap();
        let loaded = scene_of(&path);
        assert!(
            !loaded.notes.iter().any(|n| n.contains("no lights")),
            "{name}: {:?}",
            loaded.notes
        );
        let scene = &loaded.scene;
        assert_eq!(scene.meshes.len(), original.instances.len(), "{name}");

        for (i, inst) in original.instances.iter().enumerate() {
            let want = &original.meshes[inst.mesh];
            let got = &scene.meshes[scene.instances[i].mesh];
            assert_eq!(got.indices, want.indices, "{name} mesh {i}");
            assert_eq!(got.uvs, want.uvs, "{name} mesh {i}");
            let normal_matrix = glam::Mat3::from_mat4(inst.transform).inverse().transpose();
            for (g, w) in got.positions.iter().zip(&want.positions) {
                assert!(
                    close(*g, inst.transform.transform_point3(*w), 1e-5),
                    "{name} mesh {i}"
                );
            }
            for (g, w) in got.normals.iter().zip(&want.normals) {
                assert!(
                    close(*g, (normal_matrix * *w).normalize(), 1e-5),
                    "{name} mesh {i}"
                );
            }
            assert_eq!(got.positions.len(), want.positions.len());

            // Materials: the fields glTF carries.
            let (a, b) = (
                original.materials[inst.material],
                scene.materials[scene.instances[i].material],
            );
            assert_eq!(b.diffuse, a.diffuse, "{name} mesh {i}");
            assert_eq!(b.base_alpha, a.base_alpha);
            assert_eq!(b.alpha_mode, a.alpha_mode);
            if a.alpha_mode == AlphaMode::Mask {
                assert_eq!(b.alpha_cutoff, a.alpha_cutoff);
            }
            assert_eq!(b.double_sided, a.double_sided);
            assert!(
                (b.shininess - a.shininess).abs() < 1e-5 * a.shininess,
                "{} vs {}",
                b.shininess,
                a.shininess
            );
            for (x, y) in [
                (a.base_color_texture, b.base_color_texture),
                (a.normal_texture, b.normal_texture),
            ] {
                match (x, y) {
                    (None, None) => {}
                    (Some(x), Some(y)) => {
                        assert_eq!((x.wrap_s, x.wrap_t), (y.wrap_s, y.wrap_t));
                        let (tx, ty) = (&original.textures[x.texture], &scene.textures[y.texture]);
                        assert_eq!((tx.width, tx.height), (ty.width, ty.height));
                        assert_eq!(tx.rgba, ty.rgba, "{name}: texture pixels");
                    }
                    other => panic!("{name} mesh {i}: {other:?}"),
                }
            }
        }
        // Grey diffuse with grey specular is representable exactly.
        let grey = scene.materials[scene.instances[1].material];
        assert!(
            close(grey.specular, Vec3::splat(0.25), 1e-5),
            "{}",
            grey.specular
        );

        // Lights.
        assert_eq!(scene.lights.len(), original.lights.len());
        for (a, b) in original.lights.iter().zip(&scene.lights) {
            assert_eq!(a.type_name(), b.type_name());
            assert!(
                close(a.diffuse, b.diffuse, 1e-5),
                "{} vs {}",
                a.diffuse,
                b.diffuse
            );
            assert!(close(a.diffuse, b.specular, 1e-5));
            match (a.kind, b.kind) {
                (
                    LightKind::Spot {
                        position: p0,
                        direction: d0,
                        cutoff_deg: c0,
                        range: r0,
                    },
                    LightKind::Spot {
                        position: p1,
                        direction: d1,
                        cutoff_deg: c1,
                        range: r1,
                    },
                ) => {
                    assert!(close(p0, p1, 1e-5) && close(d0, d1, 1e-5), "{d0} vs {d1}");
                    assert!((c0 - c1).abs() < 1e-5 * c0, "{c0} vs {c1}");
                    assert_eq!(r0, r1);
                }
                (
                    LightKind::Point {
                        position: p0,
                        range: r0,
                    },
                    LightKind::Point {
                        position: p1,
                        range: r1,
                    },
                ) => {
                    assert!(close(p0, p1, 1e-5));
                    assert_eq!(r0, r1);
                }
                (
                    LightKind::Directional { direction: d0, .. },
                    LightKind::Directional { direction: d1, .. },
                ) => assert!(close(d0, d1, 1e-5), "{d0} vs {d1}"),
                other => panic!("{other:?}"),
            }
        }

        // Camera: same eye, direction and view; glTF has no target distance.
        let (a, b) = (original.camera, scene.camera);
        assert!(close(a.position, b.position, 1e-5));
        let dir_a = (a.target - a.position).normalize();
        let dir_b = (b.target - b.position).normalize();
        assert!(close(dir_a, dir_b, 1e-5), "{dir_a} vs {dir_b}");
        assert!((a.fov_y_deg - b.fov_y_deg).abs() < 1e-5 * a.fov_y_deg);
        assert_eq!((a.near, a.far), (b.near, b.far));
        let (va, vb) = (a.view(), b.view());
        for (x, y) in va.to_cols_array().iter().zip(vb.to_cols_array()) {
            assert!((x - y).abs() < 1e-5, "{va} vs {vb}");
        }
    }
}

#[test]
fn written_gltf_of_an_empty_scene_is_refused_on_load() {
    // Nothing to draw is a clear error on load, not a panic on write.
    let dir = temp_dir("write_empty");
    let path = dir.join("empty.gltf");
    write_gltf(&Scene::default(), &path).unwrap();
    let e = load_scene(&path).unwrap_err();
    assert!(e.to_string().contains("no triangles"), "{e}");
}
