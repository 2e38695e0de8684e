//! Crease-angle normals: a box keeps flat faces, a finely tessellated cylinder stays smooth.

use glam::{Vec2, Vec3};
use manyshadows_scene::loaders::{self};
use manyshadows_scene::Mesh;

use crate::common::{assert_normals_match_winding, CUBE_QUADS, CUBE_V};

/// The cube of `CUBE_V` and `CUBE_QUADS` as a mesh: eight shared corners, twelve triangles,
/// no normals.
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
