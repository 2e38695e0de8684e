//! The procedural primitives: closed, wound outwards, exact; and every mesh of every scene
//! wound outwards.

use std::collections::HashMap;

use glam::{Mat4, Vec2, Vec3};
use manyshadows_scene::builtin::{dragon, SCENE_NAMES};
use manyshadows_scene::{primitives, Mesh};

use crate::common::build;

/// Every triangle's geometric normal agrees with its vertex normals (CCW seen from outside),
/// and no triangle is degenerate.
fn assert_winding_matches_normals(mesh: &Mesh) {
    mesh.validate().unwrap();
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        let g = (b - a).cross(c - a);
        assert!(
            g.length_squared() > 0.0,
            "{}: triangle {t} is degenerate",
            mesh.name
        );
        let n: Vec3 = [0, 1, 2]
            .map(|k| mesh.normals[tri[k] as usize])
            .iter()
            .sum();
        assert!(
            g.dot(n) > 0.0,
            "{}: triangle {t} is wound against its normals",
            mesh.name
        );
    }
    for n in &mesh.normals {
        assert!(
            (n.length() - 1.0).abs() < 1e-3,
            "{}: normal {n} not unit",
            mesh.name
        );
    }
}

/// For a closed convex-ish mesh: every triangle faces away from the mesh's centre.
fn assert_outward_from_center(mesh: &Mesh) {
    let (lo, hi) = mesh.bounds().unwrap();
    let center = 0.5 * (lo + hi);
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        let g = (b - a).cross(c - a);
        let centroid = (a + b + c) / 3.0;
        assert!(
            g.dot(centroid - center) > 0.0,
            "{}: triangle {t} faces inwards",
            mesh.name
        );
    }
}

/// Closed and consistently wound: every edge (matched by position, since sharp edges split
/// vertices) is used exactly once in each direction.
fn assert_watertight(mesh: &Mesh) {
    let key = |p: Vec3| (p * 1e4).round().as_ivec3().to_array();
    let mut edges: HashMap<([i32; 3], [i32; 3]), i32> = HashMap::new();
    for tri in mesh.indices.chunks_exact(3) {
        for k in 0..3 {
            let a = key(mesh.positions[tri[k] as usize]);
            let b = key(mesh.positions[tri[(k + 1) % 3] as usize]);
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "{}: edge {a:?}->{b:?} used {n} times", mesh.name);
        assert_eq!(
            edges.get(&(b, a)),
            Some(&1),
            "{}: edge {a:?}->{b:?} is open",
            mesh.name
        );
    }
}

#[test]
fn closed_primitives_are_watertight_with_outward_normals() {
    let cuboid = primitives::cuboid(Vec3::new(1.0, 2.0, 3.0));
    assert_eq!((cuboid.positions.len(), cuboid.triangle_count()), (24, 12));
    let sphere = primitives::uv_sphere(1.5, 24, 12);
    assert_eq!(sphere.triangle_count(), 2 * 24 * 11);
    let cylinder = primitives::cylinder(0.5, 2.0, 20);
    assert_eq!(cylinder.triangle_count(), 4 * 20);
    let (lo, hi) = cylinder.bounds().unwrap();
    assert!(
        lo.y.abs() < 1e-6 && (hi.y - 2.0).abs() < 1e-6,
        "base at y = 0"
    );
    let cone = primitives::cone(1.0, 2.0, 16);
    assert_eq!(cone.triangle_count(), 2 * 16);
    for mesh in [&cuboid, &sphere, &cylinder, &cone] {
        assert_winding_matches_normals(mesh);
        assert_outward_from_center(mesh);
        assert_watertight(mesh);
    }
    // Tessellation arguments are clamped, never invalid.
    for mesh in [
        primitives::uv_sphere(1.0, 0, 0),
        primitives::cylinder(1.0, 1.0, 0),
        primitives::plane(1.0, 1.0, 0),
    ] {
        assert_winding_matches_normals(&mesh);
        assert!(mesh.triangle_count() > 0);
    }
}

#[test]
fn tubes_and_columns_are_closed_and_wound_outwards() {
    let torus = primitives::torus(2.0, 0.5, 32, 12);
    assert_eq!(torus.triangle_count(), 2 * 32 * 12);
    let knot = primitives::torus_knot(2, 3, 2.0, 0.3, 200, 12);
    assert_eq!(knot.triangle_count(), 2 * 200 * 12);
    let column = primitives::column(0.3, 4.4, 16);
    let stand_in = dragon::dragon_stand_in();
    for mesh in [&torus, &knot, &column, &stand_in] {
        assert_winding_matches_normals(mesh);
        assert_watertight(mesh);
    }
    // The torus's tube normals point away from its core circle.
    for (p, n) in torus.positions.iter().zip(&torus.normals) {
        let core = Vec3::new(p.x, 0.0, p.z).normalize() * 2.0;
        assert!(n.dot(*p - core) > 0.0);
    }
    let (lo, hi) = column.bounds().unwrap();
    assert!(lo.y.abs() < 1e-6 && (hi.y - 4.4).abs() < 1e-5);
    assert!((hi.x - 0.48).abs() < 1e-5, "plinth 3.2 r wide: {hi}");
}

#[test]
fn plane_and_heightfield_face_up_and_interpolate_exactly() {
    let plane = primitives::plane(4.0, 2.0, 3);
    assert_eq!(plane.positions.len(), 16);
    assert_eq!(plane.triangle_count(), 18);
    assert_winding_matches_normals(&plane);
    assert!(plane.normals.iter().all(|&n| n == Vec3::Y));
    assert_eq!(
        plane.bounds().unwrap(),
        (Vec3::new(-2.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 1.0))
    );
    let f = |x: f32, z: f32| 0.3 * x * x - 0.2 * z + 0.1 * x * z;
    let field = primitives::heightfield(4.0, 4.0, 8, f);
    assert_winding_matches_normals(&field);
    let grid = |i: u32, j: u32| field.positions[(i * 9 + j) as usize].y;
    for tri in field.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| field.positions[tri[k] as usize]);
        let p = 0.2 * a + 0.3 * b + 0.5 * c;
        let h = primitives::heightfield_height(4.0, 4.0, 8, grid, p.x, p.z);
        assert!((h - p.y).abs() < 1e-5, "{h} vs {}", p.y);
    }
}

#[test]
fn arch_has_a_clear_round_opening_and_outward_faces() {
    let (w, h, r, d) = (4.0, 1.9, 1.6, 0.7);
    let arch = primitives::arch(w, h, r, d, 48);
    assert_winding_matches_normals(&arch);
    let (lo, hi) = arch.bounds().unwrap();
    assert!(
        (lo - Vec3::new(-2.0, 0.0, -0.35)).abs().max_element() < 1e-5,
        "{lo}"
    );
    assert!(
        (hi - Vec3::new(2.0, 1.9, 0.35)).abs().max_element() < 1e-5,
        "{hi}"
    );
    for p in &arch.positions {
        assert!(
            Vec2::new(p.x, p.y).length() > r - 1e-4,
            "vertex {p} inside the opening"
        );
    }
    // Every triangle faces away from the block's interior: its centroid pushed a little along
    // the normal leaves the solid (outside the box or inside the opening).
    let inside = |p: Vec3| {
        p.x.abs() < 0.5 * w
            && p.y > 0.0
            && p.y < h
            && p.z.abs() < 0.5 * d
            && Vec2::new(p.x, p.y).length() > r
    };
    for tri in arch.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| arch.positions[tri[k] as usize]);
        let n = (b - a).cross(c - a).normalize();
        let centroid = (a + b + c) / 3.0;
        assert!(inside(centroid - 1e-3 * n), "behind the face is solid");
        assert!(
            !inside(centroid + 1e-3 * n),
            "in front of the face is empty"
        );
    }
}

#[test]
fn merge_bakes_transforms_and_keeps_mirrored_meshes_outward() {
    let cube = primitives::cuboid(Vec3::ONE);
    let mirrored = Mat4::from_scale(Vec3::new(-2.0, 1.0, 1.0));
    let moved = Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0));
    let merged = primitives::merge(&[(cube.clone(), mirrored), (cube.clone(), moved)]);
    assert_eq!(merged.positions.len(), 48);
    assert_eq!(merged.triangle_count(), 24);
    assert_winding_matches_normals(&merged);
    let (lo, hi) = merged.bounds().unwrap();
    assert_eq!((lo.x, hi.x), (-1.0, 5.5));
    let first = primitives::merge(&[(cube, mirrored)]);
    assert_outward_from_center(&first);
}

#[test]
fn every_mesh_of_every_scene_is_wound_outwards() {
    for &name in SCENE_NAMES {
        let scene = build(name);
        for mesh in &scene.meshes {
            assert_winding_matches_normals(mesh);
        }
    }
}
