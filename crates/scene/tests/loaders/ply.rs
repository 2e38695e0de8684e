//! PLY: ascii and binary (both byte orders), `.ply.gz`, and truncated or lying files.

use std::io::Write;

use glam::Vec3;
use manyshadows_scene::loaders::{self, load_mesh, write_ply_ascii};
use manyshadows_scene::{Mesh, SceneError};

use crate::common::{
    assert_normals_match_winding, assert_unit_normals, load_one, pyramid, temp_dir, write,
};

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
