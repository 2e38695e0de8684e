//! The terrain: its grid, the objects on it, and its surface height.

use std::collections::HashMap;

use manyshadows_scene::builtin::terrain;
use manyshadows_scene::LightKind;

use crate::common::{build, count_types, light_position};

#[test]
fn terrain_is_a_251_square_grid_with_600_objects_on_it() {
    let scene = build("terrain");
    let grid = &scene.meshes[terrain::TERRAIN_MESH];
    assert_eq!(grid.positions.len(), 251 * 251);
    assert_eq!(grid.triangle_count(), 125_000);
    let (lo, hi) = grid.bounds().unwrap();
    assert_eq!((lo.x, lo.z, hi.x, hi.z), (-50.0, -50.0, 50.0, 50.0));
    assert!(
        hi.y - lo.y > 4.0,
        "the ground should not be flat: {lo} {hi}"
    );
    let terrain_instances: Vec<_> = scene
        .instances
        .iter()
        .filter(|i| i.mesh == terrain::TERRAIN_MESH)
        .collect();
    assert_eq!(terrain_instances.len(), 1);

    let objects: Vec<_> = scene
        .instances
        .iter()
        .filter(|i| i.mesh != terrain::TERRAIN_MESH)
        .collect();
    assert_eq!(objects.len(), 600);
    let mut per_mesh: HashMap<usize, usize> = HashMap::new();
    for o in &objects {
        *per_mesh.entry(o.mesh).or_default() += 1;
    }
    let mut counts: Vec<usize> = per_mesh.values().copied().collect();
    counts.sort();
    assert_eq!(counts, vec![50, 150, 200, 200]);
    for o in &objects {
        let t = o.transform.w_axis.truncate();
        assert!(t.x.abs() < 50.0 && t.z.abs() < 50.0);
        let ground = terrain::surface_height(t.x, t.z);
        assert!(
            t.y <= ground && t.y > ground - 0.5,
            "object at {t} floats or sinks (ground {ground})"
        );
    }

    assert_eq!(scene.lights.len(), terrain::DEFAULT_TERRAIN_LIGHTS);
    let (spot, point, directional) = count_types(&scene);
    assert_eq!(directional, 1);
    assert!(spot >= 1 && point >= 1);
    for l in &scene.lights {
        if let LightKind::Directional { cascades, .. } = l.kind {
            assert_eq!(cascades, 3);
        }
        if let Some(p) = light_position(&l.kind) {
            assert!(
                p.y > terrain::surface_height(p.x, p.z) + 1.0,
                "light under ground at {p}"
            );
        }
    }
    // The camera is above the ground it looks across.
    let c = scene.camera.position;
    assert!(c.y > terrain::surface_height(c.x, c.z) + 10.0);
}

#[test]
fn terrain_surface_height_follows_the_triangles() {
    let scene = build("terrain");
    let grid = &scene.meshes[terrain::TERRAIN_MESH];
    // Exact at vertices.
    for &idx in &[0usize, 1, 251, 300, 31_000, 251 * 251 - 1] {
        let p = grid.positions[idx];
        let h = terrain::surface_height(p.x, p.z);
        assert!((h - p.y).abs() < 1e-5, "vertex {idx}: {h} vs {}", p.y);
    }
    // On the triangle's plane at each triangle's centroid.
    for tri in grid.indices.chunks_exact(3).step_by(997) {
        let [a, b, c] = [0, 1, 2].map(|k| grid.positions[tri[k] as usize]);
        let centroid = (a + b + c) / 3.0;
        let h = terrain::surface_height(centroid.x, centroid.z);
        assert!((h - centroid.y).abs() < 1e-3, "{h} vs {}", centroid.y);
    }
}
