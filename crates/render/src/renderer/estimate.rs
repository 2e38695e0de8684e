//! What the next frame will cost, before it is drawn: the work each stage takes on (counted
//! from the scene, the shadow plan and a coarse look at what the camera sees), and milliseconds
//! from costs per unit of that work measured on lavapipe (`manyshadows bench estimate` measures
//! them against real frames; docs/benchmarks.md, "What a frame will cost: `bench estimate`",
//! has its table).
//!
//! The units per stage:
//! - **G-buffer**: pixels, and every triangle of every instance (the camera's draw culls
//!   nothing on the CPU).
//! - **Lighting**: a 64×36 grid of camera rays is cast against every triangle of the scene
//!   (a BVH from obvhs, built for the estimate) and, at each surface point, lights are
//!   counted: those whose bounding sphere holds the point (directional lights hold
//!   everything) are the (pixel, light) pairs in reach, each paying its shadow lookup (a PCF
//!   comparison, a sized light's blocker search and filter, a virtual page read, a mask bit,
//!   or shadow rays); those whose sphere meets the point's cluster are the pairs the
//!   clustered loop visits. For ray-traced shadows, rays to a few lights in reach of each
//!   point count the triangles a shadow ray tests.
//! - **Shadows**: (caster triangle, view) pairs as the technique takes them
//!   ([`ShadowWork`]) and atlas texels filled, for the atlas techniques; every pair and the
//!   (pixel, light) samples put in lists, for irregular maps; the pairs after culling whole
//!   instances per face and the samples marking pages, for virtual maps; the instances of the
//!   acceleration structure, for rays.

use super::state::Renderer;
use crate::frame::clusters::ClusterOptions;
use crate::frame::eyes::Eyes;
use crate::report::FrameEstimate;
use crate::sampled::options::SpatialReuse;
use crate::settings::RenderSettings;
use crate::shadows::cost::{price, EstimatedWork, LightingRead};
use glam::{Vec3, Vec3A};
use manyshadows_scene::{LightKind, Scene};
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

/// Columns and rows of the camera rays that find what the camera sees.
const GRID: (u32, u32) = (64, 36);

/// Milliseconds per unit of work of the stages every technique shares, on llvmpipe (LLVM 15,
/// Mesa 25.0.7) through Vulkan with 2 cores: least squares on the relative error of each stage
/// over frames of every technique (`manyshadows bench estimate`; docs/benchmarks.md, "What a
/// frame will cost: `bench estimate`"). Each technique's shadow stage is priced by its own
/// declaration (`TechniqueInfo::cost`). Each row lists its units in order; a 0 is a unit the
/// fit found no cost in.
struct Costs {
    /// G-buffer: pixels, camera triangles, fixed.
    gbuffer: [f64; 3],
    /// Clusters: pixels, lights, fixed.
    clusters: [f64; 3],
    /// Lighting with maps (atlas, pages): pixels, (pixel, light) pairs of the cluster loop,
    /// fixed, pairs in reach, pairs in reach × extra depth taps.
    lighting_maps: [f64; 5],
    /// Lighting from a mask: pixels, loop pairs, fixed, pairs in reach.
    lighting_mask: [f64; 4],
    /// Lighting with shadow rays: pixels, loop pairs, fixed, rays, rays × triangles a ray
    /// tests, rays × (triangles a ray tests)² (the fit found no cost in the linear term; a
    /// term for the instance boxes a ray crosses found none either and was dropped).
    lighting_rays: [f64; 6],
}

const LAVAPIPE: Costs = Costs {
    gbuffer: [3.51e-05, 1.42e-04, 4.19e-01],
    clusters: [1.01e-05, 4.26e-04, 2.33e-01],
    lighting_maps: [5.91e-05, 8.49e-06, 0.0, 6.19e-06, 2.41e-06],
    lighting_mask: [7.92e-07, 5.32e-06, 2.63, 1.46e-06],
    lighting_rays: [1.52e-04, 8.27e-06, 0.0, 1.14e-05, 0.0, 4.43e-05],
};

impl Costs {
    /// The lighting pass over `pixels` with `loop_pairs` visited, `pairs` in reach paying
    /// `tap_pairs` extra taps, or `rays` testing `ray_weight` triangles each, as `read` says.
    fn lighting(
        &self,
        read: LightingRead,
        (pixels, loop_pairs, fixed): (f64, f64, f64),
        (pairs, tap_pairs): (f64, f64),
        (rays, ray_weight): (f64, f64),
    ) -> f64 {
        match read {
            LightingRead::Rays => price(
                &self.lighting_rays,
                &[
                    pixels,
                    loop_pairs,
                    fixed,
                    rays,
                    rays * ray_weight,
                    rays * ray_weight * ray_weight,
                ],
            ),
            LightingRead::Mask => price(&self.lighting_mask, &[pixels, loop_pairs, fixed, pairs]),
            LightingRead::Maps => price(
                &self.lighting_maps,
                &[pixels, loop_pairs, fixed, pairs, tap_pairs],
            ),
        }
    }
}

impl Renderer {
    /// What the next frame is estimated to cost, per stage, before it is drawn: its work
    /// (see [`EstimatedWork`]) and milliseconds on lavapipe. On another adapter the milliseconds
    /// are lavapipe's (a GPU is typically 10–100× faster); `calibrated` says which.
    pub fn estimate_frame(&self) -> FrameEstimate {
        let work = self.estimated_work();
        let c = &LAVAPIPE;
        let cost = self.settings.technique.info().cost;
        let w = &work;
        let (px, pairs, rays) = (w.pixels as f64, w.pixel_lights as f64, w.rays as f64);
        let gbuffer_ms = price(&c.gbuffer, &[px, w.triangles as f64, 1.0]);
        let clusters_ms = price(&c.clusters, &[px, w.lights as f64, 1.0]);
        let lighting_ms = c.lighting(
            cost.lighting,
            (px, w.cluster_lights as f64, 1.0),
            (pairs, w.tap_pairs()),
            (rays, w.ray_weight),
        );
        let shadows_ms = (cost.shadows_ms)(w);
        // Probe faces: a G-buffer and a lighting pass each, over every light per texel (no
        // clusters), the pairs in reach and rays at the camera's density per pixel.
        let probes_ms = self.parts.probes.as_ref().map_or(0.0, |p| {
            let stats = p.stats();
            let faces = 6.0 * f64::from(stats.probes);
            let texels = faces * f64::from(stats.side).powi(2);
            let k = texels / px.max(1.0);
            let mono_triangles = w.triangles as f64
                / if self.settings.stereo.is_some() {
                    2.0
                } else {
                    1.0
                };
            let gbuffer = price(&c.gbuffer, &[texels, faces * mono_triangles, faces]);
            // A face's shadows are read as the camera's are (a mask source draws no faces).
            let read = match cost.lighting {
                LightingRead::Mask => LightingRead::Maps,
                read => read,
            };
            let lighting = c.lighting(
                read,
                (texels, texels * w.lights as f64, faces),
                (pairs * k, w.tap_pairs() * k),
                (rays * k, w.ray_weight),
            );
            gbuffer + lighting
        });
        let calibrated = self.ctx.info.device_type == wgpu::DeviceType::Cpu;
        FrameEstimate {
            work,
            gbuffer_ms,
            clusters_ms,
            shadows_ms,
            lighting_ms,
            probes_ms,
            calibrated,
        }
    }

    /// The units [`Renderer::estimate_frame`] prices.
    pub fn estimated_work(&self) -> EstimatedWork {
        let s = &self.settings;
        let scene = &self.current;
        let info = s.technique.info();
        let pixels = u64::from(s.width) * u64::from(s.height);
        let t0 = web_time::Instant::now();
        let sight = sight(scene, s, &s.clusters);
        let pixel_lights = sight.pixel_lights;
        let sized = scene.lights.iter().any(|l| l.size > 0.0 && l.casts_shadows);
        let source = &self.parts.source;
        // The views the technique fills: the atlas plan's, a virtual map's faces, irregular
        // maps' light views; none for rays. One count of the views' casters (at 36,499 views
        // and 481 casters it is most of the estimate's time).
        let faces = source.views_filled();
        let (per_view, instance_views) = self.per_view_work(faces);
        let (atlas_texels, atlas_area) = if source.fills_atlas() {
            let layout = &source.plan().layout;
            (
                layout
                    .tiles
                    .iter()
                    .map(|t| u64::from(t.size) * u64::from(t.size))
                    .sum(),
                u64::from(layout.size) * u64::from(layout.size),
            )
        } else {
            (0, 0)
        };
        let taps = if sized && info.soft_shadows {
            s.soft.blocker_taps + s.soft.filter_taps
        } else if s.pcf == crate::shadows::options::Pcf::Pcf3x3 {
            9
        } else {
            0
        };
        let rays = if info.cost.lighting != LightingRead::Rays {
            0
        } else if s.rays.light_samples > 0 {
            // One point of each sampled light; reuse traces the kept sample too, spatial
            // reuse each neighbour's light from here (unbiased: from every pixel involved).
            let n = u64::from(crate::sampled::reuse::SPATIAL_NEIGHBOURS);
            let spatial = match s.rays.spatial {
                SpatialReuse::Off => 0,
                SpatialReuse::Biased => n,
                SpatialReuse::Unbiased => n + n * n,
            };
            let reuse = if s.rays.reuse { 2 + spatial } else { 1 };
            pixels * u64::from(s.rays.light_samples) * reuse
        } else if sized {
            // A stratified grid over each sized light's shape.
            pixel_lights * u64::from(s.rays.area_samples.max(1).pow(2))
        } else {
            pixel_lights
        };
        log::debug!(
            "frame estimate counted in {:.0} ms",
            t0.elapsed().as_secs_f64() * 1e3
        );
        EstimatedWork {
            pixels,
            // A stereo frame draws every triangle once per eye.
            triangles: self.parts.scene.triangles * if s.stereo.is_some() { 2 } else { 1 },
            caster_triangles: self
                .parts
                .scene
                .draws
                .iter()
                .filter(|d| d.casts_shadows)
                .map(|d| u64::from(d.mesh.index_count / 3))
                .sum(),
            instances: scene.instances.len(),
            lights: scene.lights.len(),
            pixel_lights,
            cluster_lights: sight.cluster_lights,
            triangle_views: per_view.triangle_views,
            after_instance_culling: per_view.after_instance_culling,
            all_pairs: per_view.all_pairs,
            instance_views,
            views: faces.len(),
            atlas_texels,
            atlas_area,
            taps,
            rays,
            ray_weight: sight.ray_weight,
        }
    }
}

/// What the grid of camera rays finds: per-frame totals scaled from the grid to the pixels.
struct Sight {
    /// (pixel, light) pairs in reach.
    pixel_lights: u64,
    /// (pixel, light) pairs whose light's reach meets the pixel's cluster.
    cluster_lights: u64,
    /// Mean triangles a shadow ray towards a light in reach tests before it is done.
    ray_weight: f64,
}

/// Lights sampled per grid point for [`Sight::ray_weight`].
const RAY_SAMPLES: usize = 4;

/// Every triangle of the scene in world space, with a BVH over them.
struct Geometry {
    bvh: CwBvh,
    /// In the BVH's primitive order.
    triangles: Vec<Triangle>,
    /// Diagonal of the scene's bounds.
    diag: f32,
}

impl Geometry {
    fn new(scene: &Scene) -> Option<Self> {
        let mut triangles = Vec::new();
        for inst in &scene.instances {
            let Some(mesh) = scene.meshes.get(inst.mesh) else {
                continue;
            };
            // Finite: `Renderer::new` refused any scene with a non-finite position.
            let world: Vec<Vec3A> = mesh
                .positions
                .iter()
                .map(|&p| Vec3A::from(inst.transform.transform_point3(p)))
                .collect();
            for t in mesh.indices.chunks_exact(3) {
                let v = |k: usize| world.get(t[k] as usize).copied();
                if let (Some(v0), Some(v1), Some(v2)) = (v(0), v(1), v(2)) {
                    if (v1 - v0).cross(v2 - v0).length_squared() > 0.0 {
                        triangles.push(Triangle { v0, v1, v2 });
                    }
                }
            }
        }
        if triangles.is_empty() {
            return None;
        }
        let bvh = build_cwbvh_from_tris(
            &triangles,
            BvhBuildParams::fastest_build(),
            &mut std::time::Duration::default(),
        );
        let triangles: Vec<Triangle> = bvh
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        let (lo, hi) = triangles.iter().fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), t| {
                (
                    lo.min(t.v0).min(t.v1).min(t.v2),
                    hi.max(t.v0).max(t.v1).max(t.v2),
                )
            },
        );
        let diag = (hi - lo).length().max(1e-3);
        Some(Self {
            bvh,
            triangles,
            diag,
        })
    }

    /// Distance to the nearest triangle along the ray, `None` past `far`.
    fn nearest(&self, origin: Vec3, dir: Vec3, far: f32) -> Option<f32> {
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, far);
        let mut hit = RayHit::none();
        self.bvh
            .ray_traverse(ray, &mut hit, |r, id| self.triangles[id].intersect(r))
            .then_some(hit.t)
    }

    /// Triangles tested by a shadow ray from `origin` over `len` (stopping at the first
    /// hit, as shadow rays do).
    fn tests(&self, origin: Vec3, dir: Vec3, len: f32) -> u32 {
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, len);
        let mut n = 0;
        self.bvh.ray_traverse_miss(ray, |r, id| {
            n += 1;
            self.triangles[id].intersect(r)
        });
        n
    }
}

/// Casts the grid of camera rays (see the module's notes).
fn sight(scene: &Scene, s: &RenderSettings, clusters: &ClusterOptions) -> Sight {
    let (width, height) = (s.width, s.height);
    let none = Sight {
        pixel_lights: 0,
        cluster_lights: 0,
        ray_weight: 0.0,
    };
    let Some(geometry) = Geometry::new(scene) else {
        return none;
    };
    let reach: Vec<Option<(Vec3, f32)>> = scene
        .lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Directional { .. } => None,
            _ => l.bounding_sphere(),
        })
        .collect();
    // Where a shadow ray ends: the light's position, or beyond the scene against a
    // directional light's direction.
    let target = |k: usize, p: Vec3| match scene.lights[k].kind {
        LightKind::Directional { direction, .. } => {
            p - direction.normalize_or(Vec3::NEG_Y) * geometry.diag
        }
        LightKind::Point { position, .. } | LightKind::Spot { position, .. } => position,
    };
    let cam = &scene.camera;
    let forward = (cam.target - cam.position).normalize_or(Vec3::NEG_Z);
    let right = forward.cross(cam.up).normalize_or(Vec3::X);
    let up = right.cross(forward);
    let tan_y = (cam.fov_y_deg.to_radians() * 0.5).tan();
    // With stereo the grid's columns are split between the eyes, each cast from its own eye.
    let eyes = Eyes::new(cam, s.stereo, (width, height));
    let aspect = eyes.aspect();
    let eye_count = eyes.cameras.len() as u32;
    // A cluster at view depth z: `tile` pixels across, one exponential slice deep.
    let slices = clusters.slices.max(1) as f32;
    let slice_growth = ((cam.far / cam.near.max(1e-6)).max(1.0).ln() / slices).exp() - 1.0;
    let pixel_at_1 = 2.0 * tan_y / height.max(1) as f32;
    // The tile the renderer will choose (the pool at its budget: the device's cap is not
    // known here).
    let tile = clusters.tile_for(
        (width, height),
        eye_count,
        scene.lights.len(),
        clusters
            .pool_bytes
            .unwrap_or(crate::frame::clusters::DEFAULT_POOL_BYTES),
    );
    let offset = geometry.diag * 1e-5;
    let (cols, rows) = GRID;
    let (mut in_reach, mut in_cluster) = (0u64, 0u64);
    let (mut tests, mut rays) = (0u64, 0u64);
    let mut near = Vec::new();
    for row in 0..rows {
        for col in 0..cols {
            let per_eye = cols / eye_count;
            let eye = (col / per_eye).min(eye_count - 1);
            let eye_col = col - eye * per_eye;
            let origin = cam.position + right * eyes.offset(eye as usize);
            let x = ((eye_col as f32 + 0.5) / per_eye as f32 * 2.0 - 1.0) * tan_y * aspect;
            let y = (1.0 - (row as f32 + 0.5) / rows as f32 * 2.0) * tan_y;
            let dir = (forward + right * x + up * y).normalize();
            let Some(t) = geometry.nearest(origin, dir, cam.far) else {
                continue;
            };
            let p = origin + dir * t;
            let z = (p - origin).dot(forward).max(cam.near);
            let side = tile as f32 * pixel_at_1 * z;
            let cluster_radius = 0.5 * (2.0 * side * side + (z * slice_growth).powi(2)).sqrt();
            near.clear();
            for (k, r) in reach.iter().enumerate() {
                match r {
                    None => {
                        near.push(k);
                        in_cluster += 1;
                    }
                    Some((c, rad)) => {
                        let d2 = (p - *c).length_squared();
                        if d2 <= rad * rad {
                            near.push(k);
                        }
                        if d2 <= (rad + cluster_radius).powi(2) {
                            in_cluster += 1;
                        }
                    }
                }
            }
            in_reach += near.len() as u64;
            // A few of the lights in reach, evenly spread over the list; the ray leaves the
            // surface on the camera's side.
            let from = p - dir * offset;
            let step = near.len().div_ceil(RAY_SAMPLES).max(1);
            for &k in near.iter().step_by(step) {
                let seg = target(k, p) - from;
                let len = seg.length();
                if len > offset {
                    tests += u64::from(geometry.tests(from, seg / len, len - offset));
                    rays += 1;
                }
            }
        }
    }
    let scale = (u64::from(width) * u64::from(height)) as f64 / f64::from(cols * rows);
    Sight {
        pixel_lights: (in_reach as f64 * scale).round() as u64,
        cluster_lights: (in_cluster as f64 * scale).round() as u64,
        ray_weight: if rays > 0 {
            tests as f64 / rays as f64
        } else {
            0.0
        },
    }
}
