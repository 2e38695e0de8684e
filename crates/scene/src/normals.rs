//! Crease-angle vertex normals for meshes whose file gives none.
//!
//! Why not plain averaged normals: a file without normals may still describe hard edges (a box
//! whose eight corners are shared by three faces each) or smooth curves (a finely tessellated
//! cylinder). Averaging every triangle around a vertex rounds the box into a blob; giving every
//! triangle its own normal facets the cylinder. The usual compromise (3D packages call it "auto
//! smooth") is a crease angle: a triangle's corner averages only the triangles around it whose
//! normals are within the angle of its own, so edges sharper than the angle stay sharp.
//!
//! The steps, for [`Mesh::compute_normals_with_crease`]:
//!
//! 1. **Weld** vertices by exact position, so that vertices split in the file for other reasons
//!    (texture seams) still share their neighbourhood.
//! 2. For each triangle corner, sum the area-weighted normals of the triangles around the welded
//!    position whose unit normal is within the crease angle of this triangle's (always
//!    including the triangle itself). A zero-area triangle's corners take the sum of all the
//!    triangles around them.
//! 3. **Split**: each distinct (vertex, normal) pair becomes one vertex; the first keeps the
//!    vertex's index, others are appended (texture coordinates copied along), so a mesh that
//!    needs no split keeps its vertex order.
//!
//! Step 2 compares every pair of triangles around a position, which is quadratic in the
//! valence. Around a position with more than [`EXACT_VALENCE`] triangles (the centre of a
//! finely divided disc, a sphere's pole) the triangles are instead grouped greedily into at
//! most [`MAX_GROUPS`] groups of normals within the angle of the group's first one, and each
//! corner takes its group's sum: linear time, the same result for the shapes that occur
//! (all-coplanar fans, smooth poles), and bounded on hostile input.

use std::collections::HashMap;

use glam::Vec3;

use crate::model::Mesh;

impl Mesh {
    /// Replaces the normals with crease-angle normals, splitting vertices where needed:
    /// positions are welded, each triangle corner averages (area-weighted) the triangles
    /// around its position whose normals are within `crease_deg` of its own triangle's, and
    /// each distinct (vertex, normal) pair becomes one vertex (texture coordinates carried
    /// along; the first keeps the vertex's index). Edges sharper than the angle stay sharp (a
    /// box with shared corners gets flat faces), gentler ones smooth (a finely tessellated
    /// cylinder). The loaders use it at
    /// [`CREASE_ANGLE_DEG`](crate::loaders::CREASE_ANGLE_DEG) for files without normals.
    /// Meshes whose indices are out of range get [`Mesh::compute_normals`] instead (and fail
    /// [`Mesh::validate`]).
    pub fn compute_normals_with_crease(&mut self, crease_deg: f32) {
        crease_normals(self, crease_deg);
    }
}

/// Largest number of triangles around one welded position compared pairwise.
const EXACT_VALENCE: usize = 64;

/// Most normal groups formed around one high-valence position.
const MAX_GROUPS: usize = 16;

/// See the module documentation.
pub(crate) fn crease_normals(mesh: &mut Mesh, crease_deg: f32) {
    let n = mesh.positions.len();
    if !mesh.indices.len().is_multiple_of(3) || mesh.indices.iter().any(|&i| i as usize >= n) {
        // Not a triangle list over these vertices: nothing to split safely. Give every vertex
        // a normal so that validation reports the real problem (the indices).
        mesh.compute_normals();
        return;
    }
    let crease = if crease_deg.is_nan() {
        0.0
    } else {
        crease_deg.clamp(0.0, 180.0)
    };
    let cos_crease = crease.to_radians().cos();

    // 1. Weld by exact position (+0.0 and -0.0 are one position).
    let mut weld_of: HashMap<[u32; 3], u32> = HashMap::new();
    let weld: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
            let next = weld_of.len() as u32;
            *weld_of.entry(key).or_insert(next)
        })
        .collect();
    let welds = weld_of.len();
    drop(weld_of);

    // Area-weighted (cross product) and unit normal of every triangle.
    let triangles = mesh.indices.len() / 3;
    let mut area = Vec::with_capacity(triangles);
    let mut unit = Vec::with_capacity(triangles);
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
        let g = (b - a).cross(c - a);
        let g = if g.is_finite() { g } else { Vec3::ZERO };
        area.push(g);
        unit.push(g.try_normalize());
    }

    // Triangles around each welded position (compressed rows).
    let mut start = vec![0u32; welds + 1];
    for &i in &mesh.indices {
        start[weld[i as usize] as usize + 1] += 1;
    }
    for w in 0..welds {
        start[w + 1] += start[w];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; mesh.indices.len()];
    // Where each corner's triangle sits in its position's row.
    let mut slot = vec![0u32; mesh.indices.len()];
    for (corner, &i) in mesh.indices.iter().enumerate() {
        let w = weld[i as usize] as usize;
        around[fill[w] as usize] = (corner / 3) as u32;
        slot[corner] = fill[w] - start[w];
        fill[w] += 1;
    }
    drop(fill);

    // The high-valence positions' groups: for each, the group of every entry of its row and
    // every group's sum. Positions not in the map are compared pairwise.
    let mut groups: HashMap<u32, (Vec<u8>, Vec<Vec3>)> = HashMap::new();
    for w in 0..welds {
        let tris = &around[start[w] as usize..start[w + 1] as usize];
        if tris.len() > EXACT_VALENCE {
            groups.insert(w as u32, group(tris, &area, &unit, cos_crease));
        }
    }

    // 2. The normal of every corner.
    let corner_normal = |corner: usize, i: u32| -> Vec3 {
        let t = corner / 3;
        let w = weld[i as usize] as usize;
        let tris = &around[start[w] as usize..start[w + 1] as usize];
        let sum = if let Some((of, sums)) = groups.get(&(w as u32)) {
            match unit[t] {
                Some(_) => sums[of[slot[corner] as usize] as usize],
                None => tris.iter().map(|&s| area[s as usize]).sum(),
            }
        } else {
            match unit[t] {
                Some(nt) => tris
                    .iter()
                    .filter(|&&s| {
                        s as usize == t
                            || unit[s as usize].is_some_and(|ns| ns.dot(nt) >= cos_crease)
                    })
                    .map(|&s| area[s as usize])
                    .sum(),
                None => tris.iter().map(|&s| area[s as usize]).sum(),
            }
        };
        sum.try_normalize().unwrap_or(Vec3::Y)
    };

    // 3. Split: one vertex per distinct (vertex, normal).
    let has_uvs = mesh.uvs.len() == n;
    let mut first: Vec<Option<Vec3>> = vec![None; n];
    let mut extra: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
    let mut normals = vec![Vec3::Y; n];
    let mut indices = Vec::with_capacity(mesh.indices.len());
    for (corner, &i) in mesh.indices.iter().enumerate() {
        let nrm = corner_normal(corner, i);
        let v = i as usize;
        let out = match first[v] {
            None => {
                first[v] = Some(nrm);
                normals[v] = nrm;
                i
            }
            Some(f) if f.to_array().map(f32::to_bits) == nrm.to_array().map(f32::to_bits) => i,
            Some(_) => *extra
                .entry((i, nrm.to_array().map(f32::to_bits)))
                .or_insert_with(|| {
                    mesh.positions.push(mesh.positions[v]);
                    if has_uvs {
                        mesh.uvs.push(mesh.uvs[v]);
                    }
                    normals.push(nrm);
                    (mesh.positions.len() - 1) as u32
                }),
        };
        indices.push(out);
    }
    mesh.normals = normals;
    mesh.indices = indices;
}

/// Greedy grouping around one high-valence position: each triangle joins the first group whose
/// first normal is within the crease of its own (or, once [`MAX_GROUPS`] exist, the closest
/// group). Zero-area triangles join group 0 and add nothing.
fn group(
    tris: &[u32],
    area: &[Vec3],
    unit: &[Option<Vec3>],
    cos_crease: f32,
) -> (Vec<u8>, Vec<Vec3>) {
    let mut seeds: Vec<Vec3> = Vec::new();
    let mut sums: Vec<Vec3> = Vec::new();
    let mut of = Vec::with_capacity(tris.len());
    for &s in tris {
        let Some(ns) = unit[s as usize] else {
            of.push(0);
            continue;
        };
        let k = match seeds.iter().position(|g| g.dot(ns) >= cos_crease) {
            Some(k) => k,
            None if seeds.len() < MAX_GROUPS => {
                seeds.push(ns);
                sums.push(Vec3::ZERO);
                seeds.len() - 1
            }
            None => seeds
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.dot(ns).total_cmp(&b.1.dot(ns)))
                .map_or(0, |(k, _)| k),
        };
        sums[k] += area[s as usize];
        of.push(k as u8);
    }
    if sums.is_empty() {
        sums.push(Vec3::ZERO);
    }
    (of, sums)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat fan of many triangles around one centre: one group, one normal.
    #[test]
    fn high_valence_fan_stays_one_vertex() {
        let segments = 200u32;
        let mut m = Mesh {
            name: "disc".into(),
            positions: vec![Vec3::ZERO],
            ..Mesh::default()
        };
        for k in 0..segments {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            m.positions.push(Vec3::new(a.cos(), 0.0, -a.sin()));
        }
        for k in 0..segments {
            m.indices
                .extend_from_slice(&[0, 1 + k, 1 + (k + 1) % segments]);
        }
        crease_normals(&mut m, 60.0);
        assert_eq!(m.positions.len(), segments as usize + 1);
        for n in &m.normals {
            assert!((*n - Vec3::Y).length() < 1e-5, "{n}");
        }
    }

    #[test]
    fn out_of_range_indices_are_left_for_validation() {
        let mut m = Mesh {
            name: "bad".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            indices: vec![0, 1, 7],
            ..Mesh::default()
        };
        crease_normals(&mut m, 60.0);
        assert_eq!(m.normals.len(), 3);
        assert!(m.validate().is_err());
    }
}
