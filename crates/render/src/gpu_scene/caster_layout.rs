//! The layout of shadow-caster geometry, decided on the CPU when a scene is uploaded (no
//! GPU here): what [`crate::gpu_scene::casters::CasterGeometry`] puts in its buffers.
//!
//! Layout, built once on the CPU:
//! - *caster vertices*: one per (caster instance, mesh vertex), `sources[i] = (scene vertex,
//!   instance)`;
//! - *corners*: three caster-vertex indices per triangle (also usable as an index buffer);
//!   triangles that may be back-face culled come first ([`CasterGeometry::cullable_triangles`](crate::gpu_scene::casters::CasterGeometry::cullable_triangles)),
//!   so shaders need one comparison instead of a per-triangle flag;
//! - *clusters*: runs of at most [`CLUSTER_TRIANGLES`] triangles of one instance, with an
//!   object-space normal cone; their world bounding spheres and boxes are recomputed per
//!   frame.
//!
//! Alpha-tested casters (materials with a coverage mask, [`manyshadows_scene::masks`]) come
//! last, in their own class: their triangles after every opaque one
//! ([`CasterGeometry::first_masked_triangle`](crate::gpu_scene::casters::CasterGeometry::first_masked_triangle)), their clusters after every opaque cluster
//! (flag [`CLUSTER_MASKED`]) and their caster vertices after every opaque one. So a technique
//! draws the opaque range with its depth-only pipeline exactly as before and the masked range
//! with an alpha-testing one; opaque casters never run an alpha test. What the alpha test
//! needs travels at the end of the corner buffer (the *mask tail*, read by
//! `alpha_mask.wgsl`, so no technique needs another binding): per masked caster vertex its
//! texture coordinate and material, per material its mask record, the coverage bits, and a
//! four-word header in the last four words. Masked casters are never back-face culled (a
//! hole in a closed mesh lets a ray reach its back faces); double-sided ones only where
//! culling is exact, never under [`CasterOptions::assume_closed`].
//!
//! Back-face culling is only exact for closed meshes seen from outside: the nearest surface
//! along a ray entering a closed mesh always faces the ray's origin. So a triangle is
//! *cullable* only if its mesh is closed (checked on welded positions) and no spot or point
//! light lies inside the instance's bounding box; inward-wound closed meshes are flipped.
//! [`CasterOptions::assume_closed`] reproduces the seed instead, which culled every mesh.

use std::collections::HashMap;

use glam::{Mat4, Vec3};
use manyshadows_scene::masks::MaskSet;
use manyshadows_scene::{LightKind, Mesh, Scene, SingleSidedShadows};

use crate::gpu_scene::instances::morton_order;

/// Consecutive caster clusters per group (`CLUSTER_GROUP` in `casters.wgsl`): each group's
/// bounding sphere holds its clusters' spheres, for culling a group before its clusters.
pub const CLUSTER_GROUP: u32 = 16;

/// Parts of a caster cluster with boxes of their own (`CLUSTER_PARTS` in `casters.wgsl`):
/// consecutive runs of a quarter of the cluster's triangles, so that a page cull can tell
/// which parts of a cluster touch a page.
pub const CLUSTER_PARTS: u32 = 4;

/// Most triangles per caster cluster.
pub const CLUSTER_TRIANGLES: u32 = 128;

/// How caster geometry is prepared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct CasterOptions {
    /// Treat every mesh as closed and outward-facing for back-face culling, as seed 000 did.
    /// Faster on open meshes, but their back sides then cast no shadow. Never applied to
    /// double-sided materials.
    pub assume_closed: bool,
    /// Cast shadows as if no material were alpha-tested (the camera still sees the holes):
    /// what a renderer that ignores alpha in its shadow passes draws. For comparisons
    /// (`compare --shadow-alpha off`), not for pictures.
    pub ignore_masks: bool,
    /// What single-sided opaque casters shadow (`Material::casts_front_only`): by default only
    /// where a light sees their front, which every technique applies exactly, as back-face
    /// culling of those triangles for every light and view.
    pub single_sided: SingleSidedShadows,
}

/// CPU record of a cluster.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct ClusterData {
    /// First triangle (in corner order).
    pub first_triangle: u32,
    /// Triangles in the run.
    pub triangles: u32,
    /// Instance the triangles belong to.
    pub instance: u32,
    /// Unused.
    pub flags: u32,
    /// Object-space normal cone: unit axis, half angle (radians; ≥ π/2 = no cone).
    pub cone: [f32; 4],
}

/// Half angle stored for clusters that must never be back-face culled.
pub const NO_CONE: f32 = 4.0;

/// [`ClusterData::flags`] bit: the cluster's triangles are alpha-tested.
pub const CLUSTER_MASKED: u32 = 1;

with_setters!(CasterOptions {
    with_assume_closed: assume_closed: bool,
    with_ignore_masks: ignore_masks: bool,
    with_single_sided: single_sided: SingleSidedShadows,
});

#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Closure {
    Open,
    Outward,
    Inward,
}

/// Whether a mesh is closed, judged on welded positions (seams with split normals or UVs do not
/// open a mesh); degenerate triangles (e.g. at sphere poles) are ignored.
pub(crate) fn closure(mesh: &Mesh) -> Closure {
    let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
    let ids: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            // `+ 0.0` folds -0.0 into +0.0 so both weld together.
            let key = p.to_array().map(|c| (c + 0.0).to_bits());
            let next = weld.len() as u32;
            *weld.entry(key).or_insert(next)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    let mut volume = 0.0f64;
    let mut any = false;
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [ids[t[0] as usize], ids[t[1] as usize], ids[t[2] as usize]];
        if a == b || b == c || c == a {
            continue;
        }
        any = true;
        for e in [(a, b), (b, c), (c, a)] {
            *edges.entry(e).or_insert(0) += 1;
        }
        let [p0, p1, p2] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize].as_dvec3());
        volume += p0.dot(p1.cross(p2));
    }
    let closed = any
        && edges
            .iter()
            .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1));
    match (closed, volume > 0.0) {
        (false, _) => Closure::Open,
        (true, true) => Closure::Outward,
        (true, false) => Closure::Inward,
    }
}

/// True if the matrix is a rotation times a uniform scale (plus translation): normal cones
/// keep their angle under it.
pub(crate) fn is_similarity(m: Mat4) -> bool {
    let [x, y, z] = [m.x_axis, m.y_axis, m.z_axis].map(|a| a.truncate());
    let s = x.length();
    let tol = 1e-4 * s.max(1e-12);
    (y.length() - s).abs() <= tol
        && (z.length() - s).abs() <= tol
        && x.dot(y).abs() <= tol * s
        && y.dot(z).abs() <= tol * s
        && z.dot(x).abs() <= tol * s
}

/// Unit axis and half angle of the smallest cone (around the mean normal) holding every
/// triangle normal; [`NO_CONE`] if the normals spread over a hemisphere or more.
pub(crate) fn normal_cone(normals: &[Vec3]) -> [f32; 4] {
    let sum: Vec3 = normals.iter().sum();
    let Some(axis) = sum.try_normalize() else {
        return [0.0, 0.0, 1.0, NO_CONE];
    };
    let min_dot = normals.iter().map(|n| n.dot(axis)).fold(1.0f32, f32::min);
    if min_dot <= 0.0 {
        return [axis.x, axis.y, axis.z, NO_CONE];
    }
    // Round the angle up a little: the cone must contain every normal.
    let angle = min_dot.clamp(-1.0, 1.0).acos() + 1e-3;
    [axis.x, axis.y, axis.z, angle]
}

/// How one caster instance's triangles are laid out: what back-face culling may do with them.
/// Recomputed whenever lights or instances move ([`CasterGeometry::refresh`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Decision {
    /// Its triangles may be back-face culled (closed mesh, no spot or point light inside its
    /// box).
    pub(crate) cullable: bool,
    /// Wind its triangles the other way (inward-wound closed mesh).
    pub(crate) flip: bool,
    /// The transform mirrors (negative determinant).
    pub(crate) mirrored: bool,
    /// Normal cones are valid (cullable, rigid, a similarity transform).
    pub(crate) cone_ok: bool,
    /// Its material is alpha-tested.
    pub(crate) masked: bool,
    /// Its material is single-sided and casts only where a light sees its front: its
    /// triangles are culled by their facing for every light (and laid out with the cullable
    /// ones, wound as its mesh is, mirrored transforms turned back).
    pub(crate) front_only: bool,
}

/// The CPU side of the caster buffers.
pub(crate) struct Layout {
    pub(crate) sources: Vec<[u32; 2]>,
    pub(crate) corners: Vec<u32>,
    pub(crate) clusters: Vec<ClusterData>,
    pub(crate) cullable_triangles: u32,
    /// Clusters from here on are not cullable (the cullable ones come first).
    pub(crate) cullable_clusters: u32,
    pub(crate) first_masked_triangle: u32,
    pub(crate) first_masked_cluster: u32,
    pub(crate) first_masked_vertex: u32,
    /// Some cullable triangles are single-sided ones that cast only where a light sees their
    /// front: the cullable class must then be culled by facing in every view.
    pub(crate) front_only: bool,
}

/// Per-mesh facts that never change: closure and Morton order, computed on first use.
#[derive(Default)]
pub(crate) struct MeshCache {
    pub(crate) closures: Vec<Option<Closure>>,
    pub(crate) orders: Vec<Option<Vec<u32>>>,
}

/// World-space position of every spot and point light that casts shadows.
pub(crate) fn light_points(scene: &Scene) -> Vec<Vec3> {
    scene
        .lights
        .iter()
        .filter(|l| l.casts_shadows)
        .filter_map(|l| match l.kind {
            LightKind::Spot { position, .. } | LightKind::Point { position, .. } => Some(position),
            LightKind::Directional { .. } => None,
        })
        .collect()
}

/// True if any of `points` lies in the world box of a mesh (its box `bounds`) placed by
/// `transform`.
pub(crate) fn light_inside(bounds: Option<(Vec3, Vec3)>, transform: Mat4, points: &[Vec3]) -> bool {
    bounds.is_some_and(|(lo, hi)| {
        let corners = (0..8).map(|k| {
            transform.transform_point3(Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ))
        });
        let (wlo, whi) = corners.fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(a, b), p| (a.min(p), b.max(p)),
        );
        points
            .iter()
            .any(|p| p.cmpge(wlo).all() && p.cmple(whi).all())
    })
}

impl MeshCache {
    pub(crate) fn new(meshes: usize) -> Self {
        Self {
            closures: vec![None; meshes],
            orders: vec![None; meshes],
        }
    }

    /// The decision of every instance of `scene` (non-casters get the default).
    pub(crate) fn decisions(
        &mut self,
        scene: &Scene,
        masks: &MaskSet,
        options: CasterOptions,
        skinned: bool,
    ) -> Vec<Decision> {
        let points = light_points(scene);
        // A skinned or morphed mesh bends: normal cones taken at load would not hold.
        let bends = |mesh: usize| {
            let a = &scene.animations;
            a.skins.iter().any(|s| s.mesh == mesh) || a.morphs.iter().any(|m| m.mesh == mesh)
        };
        scene
            .instances
            .iter()
            .map(|inst| {
                if !inst.casts_shadows {
                    return Decision::default();
                }
                let mesh = &scene.meshes[inst.mesh];
                let masked = masks.is_masked(inst.material);
                let front_only = !masked
                    && scene
                        .materials
                        .get(inst.material)
                        .is_some_and(|m| m.casts_front_only(options.single_sided));
                if front_only {
                    return Decision {
                        cullable: true,
                        flip: false,
                        mirrored: inst.transform.determinant() < 0.0,
                        cone_ok: !skinned && !bends(inst.mesh) && is_similarity(inst.transform),
                        masked: false,
                        front_only: true,
                    };
                }
                // Seed 000's "every mesh is closed" never applies to double-sided materials:
                // they are culled only where culling is exact.
                let assume_closed = options.assume_closed
                    && !scene
                        .materials
                        .get(inst.material)
                        .is_some_and(|m| m.double_sided);
                let closure = if assume_closed {
                    Closure::Outward
                } else {
                    *self.closures[inst.mesh].get_or_insert_with(|| closure(mesh))
                };
                let cullable = !masked
                    && closure != Closure::Open
                    && (assume_closed
                        || !light_inside(scene.mesh_bounds(inst.mesh), inst.transform, &points));
                Decision {
                    cullable,
                    flip: cullable && closure == Closure::Inward,
                    mirrored: inst.transform.determinant() < 0.0,
                    cone_ok: cullable
                        && !skinned
                        && !bends(inst.mesh)
                        && is_similarity(inst.transform),
                    masked,
                    front_only: false,
                }
            })
            .collect()
    }

    /// The caster buffers' contents for `decisions`.
    pub(crate) fn layout(&mut self, scene: &Scene, decisions: &[Decision]) -> Layout {
        let mut base_vertex = Vec::with_capacity(scene.meshes.len());
        let mut acc = 0u32;
        for m in &scene.meshes {
            base_vertex.push(acc);
            acc += m.positions.len() as u32;
        }
        let mut sources: Vec<[u32; 2]> = Vec::new();
        // (corners, cluster cones) per class: 0 = cullable, 1 = opaque and not cullable,
        // 2 = alpha-tested.
        let mut corners: [Vec<u32>; 3] = Default::default();
        let mut clusters: [Vec<ClusterData>; 3] = Default::default();
        // Opaque instances' caster vertices first, then the alpha-tested ones'.
        let casters = |masked: bool| {
            scene
                .instances
                .iter()
                .enumerate()
                .filter(move |(i, inst)| inst.casts_shadows && decisions[*i].masked == masked)
        };
        let mut first_masked_vertex = 0;
        for (i, inst) in casters(false).chain(casters(true)) {
            let mesh = &scene.meshes[inst.mesh];
            let Decision {
                cullable,
                flip,
                mirrored,
                cone_ok,
                masked,
                front_only: _,
            } = decisions[i];
            if !masked {
                first_masked_vertex = sources.len() as u32 + mesh.positions.len() as u32;
            }
            let class = if masked { 2 } else { usize::from(!cullable) };
            let first_vertex = sources.len() as u32;
            let bv = base_vertex[inst.mesh];
            sources.extend((0..mesh.positions.len() as u32).map(|v| [bv + v, i as u32]));
            let ordered = self.orders[inst.mesh].get_or_insert_with(|| morton_order(mesh));
            for chunk in ordered.chunks(3 * CLUSTER_TRIANGLES as usize) {
                let first_triangle = (corners[class].len() / 3) as u32;
                let mut normals = Vec::with_capacity(chunk.len() / 3);
                for t in chunk.chunks_exact(3) {
                    // A mirroring transform turns the winding around as well.
                    let (b, c) = if flip != mirrored {
                        (t[2], t[1])
                    } else {
                        (t[1], t[2])
                    };
                    corners[class].extend([t[0], b, c].map(|v| first_vertex + v));
                    if cone_ok {
                        let [p0, p1, p2] = [t[0], b, c].map(|v| mesh.positions[v as usize]);
                        if let Some(n) = (p1 - p0).cross(p2 - p0).try_normalize() {
                            // A mirroring transform flips normals relative to the winding.
                            normals.push(if mirrored { -n } else { n });
                        }
                    }
                }
                let cone = if cone_ok {
                    normal_cone(&normals)
                } else {
                    [0.0, 0.0, 1.0, NO_CONE]
                };
                clusters[class].push(ClusterData {
                    first_triangle,
                    triangles: (chunk.len() / 3) as u32,
                    instance: i as u32,
                    flags: if masked { CLUSTER_MASKED } else { 0 },
                    cone,
                });
            }
        }
        let cullable_triangles = (corners[0].len() / 3) as u32;
        let cullable_clusters = clusters[0].len() as u32;
        let front_only = scene
            .instances
            .iter()
            .zip(decisions)
            .any(|(inst, d)| inst.casts_shadows && d.front_only);
        let first_masked_triangle = cullable_triangles + (corners[1].len() / 3) as u32;
        let [mut all_corners, open, masked] = corners;
        let [mut all_clusters, open_clusters, masked_clusters] = clusters;
        all_corners.extend(open);
        all_corners.extend(masked);
        all_clusters.extend(open_clusters.into_iter().map(|mut c| {
            c.first_triangle += cullable_triangles;
            c
        }));
        let first_masked_cluster = all_clusters.len() as u32;
        all_clusters.extend(masked_clusters.into_iter().map(|mut c| {
            c.first_triangle += first_masked_triangle;
            c
        }));
        Layout {
            sources,
            corners: all_corners,
            clusters: all_clusters,
            cullable_triangles,
            cullable_clusters,
            front_only,
            first_masked_triangle,
            first_masked_cluster,
            first_masked_vertex,
        }
    }
}

/// The mask tail appended to `corners` (whose length is its own start): per masked caster
/// vertex (u bits, v bits, material), per material its [`MaskRecord`] with `first_word` made
/// absolute, the coverage bits, and the header `[first masked triangle, first masked caster
/// vertex, start of the vertex table, start of the record table]` in the last four words.
///
/// [`MaskRecord`]: manyshadows_scene::masks::MaskRecord
pub(crate) fn mask_tail(scene: &Scene, masks: &MaskSet, layout: &Layout) -> Vec<u32> {
    let start = layout.corners.len() as u32;
    let mut base_vertex = Vec::with_capacity(scene.meshes.len());
    let mut acc = 0u32;
    for m in &scene.meshes {
        base_vertex.push(acc);
        acc += m.positions.len() as u32;
    }
    let mut tail = Vec::new();
    for &[vertex, instance] in &layout.sources[layout.first_masked_vertex as usize..] {
        let inst = &scene.instances[instance as usize];
        let mesh = &scene.meshes[inst.mesh];
        let uv = mesh
            .uvs
            .get((vertex - base_vertex[inst.mesh]) as usize)
            .copied()
            .unwrap_or_default();
        tail.extend([uv.x.to_bits(), uv.y.to_bits(), inst.material as u32]);
    }
    let records = start + tail.len() as u32;
    let bits = records + 4 * masks.records.len().max(1) as u32;
    for r in &masks.records {
        tail.extend([r.first_word + bits, r.width, r.height, r.flags]);
    }
    if masks.records.is_empty() {
        tail.extend([0; 4]);
    }
    tail.extend_from_slice(&masks.bits);
    tail.extend([
        layout.first_masked_triangle,
        layout.first_masked_vertex,
        start,
        records,
    ]);
    tail
}
/// Groups of [`CLUSTER_GROUP`] clusters covering `clusters`.
pub(crate) fn groups_of(clusters: usize) -> u32 {
    (clusters as u32).div_ceil(CLUSTER_GROUP)
}

#[cfg(test)]
mod tests {
    use super::*;
    use manyshadows_scene::primitives;

    #[test]
    pub(crate) fn closed_primitives_are_recognised_and_planes_are_not() {
        assert!(closure(&primitives::cuboid(Vec3::ONE)) == Closure::Outward);
        assert!(closure(&primitives::uv_sphere(1.0, 16, 8)) == Closure::Outward);
        assert!(closure(&primitives::plane(2.0, 2.0, 1)) == Closure::Open);
        let mut inside_out = primitives::cuboid(Vec3::ONE);
        for t in inside_out.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        assert!(closure(&inside_out) == Closure::Inward);
    }

    #[test]
    pub(crate) fn normal_cones_contain_their_normals() {
        let ns = [
            Vec3::Z,
            Vec3::new(0.1, 0.0, 1.0).normalize(),
            Vec3::new(0.0, -0.2, 1.0).normalize(),
        ];
        let c = normal_cone(&ns);
        let axis = Vec3::new(c[0], c[1], c[2]);
        for n in ns {
            assert!(n.dot(axis).acos() <= c[3], "{n} outside the cone");
        }
        assert_eq!(normal_cone(&[Vec3::Z, -Vec3::Z])[3], NO_CONE);
    }

    #[test]
    pub(crate) fn similarity_detection() {
        assert!(is_similarity(Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::from_rotation_y(0.7),
            Vec3::new(1.0, 2.0, 3.0)
        )));
        assert!(!is_similarity(Mat4::from_scale(Vec3::new(1.0, 2.0, 1.0))));
    }
}
