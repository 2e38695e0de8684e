//! Occlusion rays against every shadow-casting triangle of a scene.
//!
//! The BVH comes from obvhs (a PLOC-built BVH2 collapsed to an 8-wide compressed BVH, the
//! layout of Ylitie et al. 2017, traversed on the CPU with SIMD node tests). The triangle test
//! is ours: obvhs' own Möller–Trumbore test documents small gaps at shared edges, and a gap in
//! the reference is a pixel of false light. The watertight test of Woop, Benthin and Wald
//! (JCGT 2013) shears the triangle into ray space so that a ray through a shared edge or vertex
//! hits at least one of the triangles that meet there.

use glam::{Vec2, Vec3, Vec3A};
use manyshadows_scene::masks::MaskSet;
use manyshadows_scene::{Scene, SingleSidedShadows};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray;
use obvhs::BvhBuildParams;

use crate::error::ReferenceError;

/// Padding of each triangle's bounding box in the BVH, relative to its largest coordinate
/// (about 10 ulps of an `f32`).
const BOX_PAD_RELATIVE: f32 = 1e-6;

/// Marks a triangle without an alpha test in [`Tracer`]'s per-triangle table.
const OPAQUE: u32 = u32::MAX;

/// An alpha-tested triangle: its corners' texture coordinates and its material.
#[derive(Clone, Copy)]
struct MaskedTriangle {
    uvs: [Vec2; 3],
    material: usize,
}

/// World-space triangles of the shadow casters in a BVH.
///
/// Alpha-tested casters (materials with a coverage mask, `manyshadows_scene::masks`) block a
/// ray only where their mask is solid at the hit: the hit's barycentric weights interpolate
/// the corners' texture coordinates and [`MaskSet::covered`] answers, with the same nearest-
/// texel rule the renderer's shadow passes use. A rejected hit lets the ray go on.
///
/// Single-sided opaque casters follow the scene's rule ([`SingleSidedShadows`]): under the
/// default one a triangle blocks a ray towards a light only where the light sees its front
/// (its front, counter-clockwise in the mesh as the camera takes it, faces along the ray).
pub struct Tracer {
    /// `None` when the scene casts no shadow at all.
    bvh: Option<CwBvh>,
    /// Triangles in BVH primitive order (so a leaf's primitive id indexes this directly).
    triangles: Vec<[Vec3; 3]>,
    /// Per triangle (BVH order): an index into `masked`, or [`OPAQUE`].
    alpha: Vec<u32>,
    /// Per triangle (BVH order): 0 where it blocks from both sides; +1 or −1 where it blocks
    /// only rays along its front, the sign turning its world winding's normal into the front
    /// (−1 under a mirroring transform).
    facing: Vec<f32>,
    masked: Vec<MaskedTriangle>,
    masks: MaskSet,
}

impl Tracer {
    /// Gathers every triangle of every instance with `casts_shadows` (the instances the shadow
    /// passes draw), transformed to world space, and builds the BVH. Zero-area triangles are
    /// left out: they rasterize to nothing, so they cast no shadow in any technique either.
    pub fn new(scene: &Scene) -> Result<Self, ReferenceError> {
        Self::with_rule(scene, SingleSidedShadows::default())
    }

    /// [`Tracer::new`] with single-sided casters shadowing as `rule` says.
    pub fn with_rule(scene: &Scene, rule: SingleSidedShadows) -> Result<Self, ReferenceError> {
        scene.validate()?;
        let masks = MaskSet::new(scene);
        let mut triangles = Vec::with_capacity(scene.triangle_count());
        let mut alpha = Vec::with_capacity(scene.triangle_count());
        let mut facing = Vec::with_capacity(scene.triangle_count());
        let mut masked = Vec::new();
        for inst in scene.instances.iter().filter(|i| i.casts_shadows) {
            let mesh = &scene.meshes[inst.mesh];
            let tested = masks.is_masked(inst.material);
            let front_only = !tested
                && scene
                    .materials
                    .get(inst.material)
                    .is_some_and(|m| m.casts_front_only(rule));
            let sign = match (front_only, inst.transform.determinant() < 0.0) {
                (false, _) => 0.0,
                (true, false) => 1.0,
                (true, true) => -1.0,
            };
            let world: Vec<Vec3> = mesh
                .positions
                .iter()
                .map(|&p| inst.transform.transform_point3(p))
                .collect();
            for t in mesh.indices.chunks_exact(3) {
                let tri = [
                    world[t[0] as usize],
                    world[t[1] as usize],
                    world[t[2] as usize],
                ];
                if (tri[1] - tri[0]).cross(tri[2] - tri[0]).length_squared() > 0.0 {
                    triangles.push(tri);
                    facing.push(sign);
                    if tested {
                        let uv =
                            |k: usize| mesh.uvs.get(t[k] as usize).copied().unwrap_or_default();
                        alpha.push(masked.len() as u32);
                        masked.push(MaskedTriangle {
                            uvs: [uv(0), uv(1), uv(2)],
                            material: inst.material,
                        });
                    } else {
                        alpha.push(OPAQUE);
                    }
                }
            }
        }
        let mut tracer = Self::from_triangles(triangles);
        if let Some(bvh) = &tracer.bvh {
            tracer.alpha = bvh
                .primitive_indices
                .iter()
                .map(|&i| alpha[i as usize])
                .collect();
            tracer.facing = bvh
                .primitive_indices
                .iter()
                .map(|&i| facing[i as usize])
                .collect();
        }
        tracer.masked = masked;
        tracer.masks = masks;
        Ok(tracer)
    }

    /// A tracer over the given world-space triangles (all opaque).
    pub fn from_triangles(triangles: Vec<[Vec3; 3]>) -> Self {
        let alpha = vec![OPAQUE; triangles.len()];
        let facing = vec![0.0; triangles.len()];
        if triangles.is_empty() {
            return Self {
                bvh: None,
                triangles,
                alpha,
                facing,
                masked: Vec::new(),
                masks: MaskSet::default(),
            };
        }
        // Boxes padded a little: the slab test treats a zero direction component as a huge
        // inverse, so a ray lying exactly in a flat box's boundary plane (an axis-aligned ray
        // along an axis-aligned edge) would miss the box of the triangle it touches.
        let boxes: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let lo = t[0].min(t[1]).min(t[2]);
                let hi = t[0].max(t[1]).max(t[2]);
                let pad = BOX_PAD_RELATIVE * lo.abs().max(hi.abs()).max_element().max(1.0);
                Aabb {
                    min: Vec3A::from(lo - pad),
                    max: Vec3A::from(hi + pad),
                }
            })
            .collect();
        let bvh = build_cwbvh(&boxes, BvhBuildParams::medium_build());
        let ordered = bvh
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        Self {
            bvh: Some(bvh),
            triangles: ordered,
            alpha,
            facing,
            masked: Vec::new(),
            masks: MaskSet::default(),
        }
    }

    /// Number of alpha-tested triangles.
    pub fn masked_triangle_count(&self) -> usize {
        self.masked.len()
    }

    /// Number of triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Whether any triangle crosses the open segment `origin + t·dir`, `0 < t < t_max`
    /// (`dir` unit length; `t_max` may be infinite).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        let Some(bvh) = &self.bvh else {
            return false;
        };
        let shear = Shear::new(origin, dir);
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, t_max);
        !bvh.ray_traverse_miss(ray, |r, id| {
            let tri = &self.triangles[id];
            let f = self.facing[id];
            // A front-only triangle is passed where its front faces back along the ray.
            if f != 0.0 && f * (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(dir) <= 0.0 {
                return f32::INFINITY;
            }
            let (t, b) = shear.hit(tri, r.tmax);
            match self.alpha[id] {
                OPAQUE => t,
                _ if t == f32::INFINITY => t,
                k => {
                    let m = &self.masked[k as usize];
                    let uv = m.uvs[0] * b.x + m.uvs[1] * b.y + m.uvs[2] * b.z;
                    if self.masks.covered(m.material, uv) {
                        t
                    } else {
                        f32::INFINITY
                    }
                }
            }
        })
    }
}

/// A ray prepared for the watertight test: the axis permutation that makes the ray's largest
/// direction component its z, and the shear that maps the ray onto +z.
struct Shear {
    origin: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl Shear {
    fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding: swapping x and y undoes the mirror of a negative z.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            origin,
            kx,
            ky,
            kz,
            sx: dir[kx] / dir[kz],
            sy: dir[ky] / dir[kz],
            sz: 1.0 / dir[kz],
        }
    }

    /// Distance along the ray to the triangle (either side), or infinity when it misses or
    /// the hit is not in `(0, t_max)`; with the hit's barycentric weights of the corners.
    fn hit(&self, tri: &[Vec3; 3], t_max: f32) -> (f32, Vec3) {
        const MISS: (f32, Vec3) = (f32::INFINITY, Vec3::ZERO);
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = tri[0] - self.origin;
        let b = tri[1] - self.origin;
        let c = tri[2] - self.origin;
        let (ax, ay) = (a[kx] - self.sx * a[kz], a[ky] - self.sy * a[kz]);
        let (bx, by) = (b[kx] - self.sx * b[kz], b[ky] - self.sy * b[kz]);
        let (cx, cy) = (c[kx] - self.sx * c[kz], c[ky] - self.sy * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // On an edge in single precision: decide in double precision, as the paper does.
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let d = |p: f32, q: f32, r: f32, s: f32| p as f64 * q as f64 - r as f64 * s as f64;
            u = d(cx, by, cy, bx) as f32;
            v = d(ax, cy, ay, cx) as f32;
            w = d(bx, ay, by, ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return MISS;
        }
        let det = u + v + w;
        if det == 0.0 {
            return MISS;
        }
        let t = (u * self.sz * a[kz] + v * self.sz * b[kz] + w * self.sz * c[kz]) / det;
        if t > 0.0 && t < t_max {
            (t, Vec3::new(u, v, w) / det)
        } else {
            MISS
        }
    }
}

/// obvhs's `cwbvh::builder::build_cwbvh` (PLOC, reinsertion, conversion to the compressed
/// wide BVH, with the same parameters), less its build timer: `std::time::Instant` panics in a
/// browser, where the web page's score button builds this BVH.
fn build_cwbvh(boxes: &[Aabb], config: BvhBuildParams) -> CwBvh {
    let mut bvh2 = obvhs::ploc::PlocBuilder::with_capacity(boxes.len()).build(
        config.ploc_search_distance,
        boxes,
        (0..boxes.len() as u32).collect::<Vec<_>>(),
        config.sort_precision,
        config.search_depth_threshold,
    );
    obvhs::bvh2::reinsertion::ReinsertionOptimizer::default().run(
        &mut bvh2,
        config.reinsertion_batch_ratio,
        None,
    );
    obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(
        &bvh2,
        config.max_prims_per_leaf.clamp(1, 3),
        true,
        false,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_edges_and_vertices_do_not_leak() {
        // A unit square of two triangles at z = 0; rays straight down through points on the
        // diagonal they share, and through the shared corners, must all hit.
        let tracer = Tracer::from_triangles(vec![
            [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)],
            [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        ]);
        for i in 0..=64 {
            let s = i as f32 / 64.0;
            let o = Vec3::new(s, s, 1.0);
            assert!(tracer.occluded(o, Vec3::NEG_Z, 2.0), "leak at diagonal {s}");
        }
        // Both sides block (casters are two-sided).
        assert!(tracer.occluded(Vec3::new(0.3, 0.6, -1.0), Vec3::Z, 2.0));
        // The segment ends before the square: no hit. Beside the square: no hit.
        assert!(!tracer.occluded(Vec3::new(0.3, 0.6, 1.0), Vec3::NEG_Z, 0.99));
        assert!(!tracer.occluded(Vec3::new(1.3, 0.6, 1.0), Vec3::NEG_Z, 2.0));
    }

    #[test]
    fn empty_scene_occludes_nothing() {
        let tracer = Tracer::from_triangles(Vec::new());
        assert_eq!(tracer.triangle_count(), 0);
        assert!(!tracer.occluded(Vec3::ZERO, Vec3::Y, f32::INFINITY));
    }
}
