//! Skinned and morphed meshes bent on the GPU: a file's skins and morph targets
//! (`Animations::skins`, `Animations::morphs`) are uploaded once, with their bind vertices;
//! each frame the CPU evaluates only what bends them (the joints' matrices and the morph
//! weights, a [`Bending`]) and a compute pass (deform.wgsl) writes the bent positions and
//! normals into the scene's own buffers, before anything draws. Every pass then reads them
//! where it reads any vertex: the G-buffer, the casters' transform, the virtual and
//! irregular maps, the probes, and the ray-traced shadows' bottom-level structures, which
//! copy them from there ([`crate::shadows::raytraced`]).
//!
//! The CPU never sees the bent vertices, so the bounds that culling, caching and the
//! denoiser's moved casters need are drawn from the joints: per joint, a sphere around the
//! bind vertices it weighs (in the mesh's coordinates), taken through the joint's matrix of
//! the frame. A vertex's weights are 0 or more and sum to 1 (the loader normalizes them), so
//! a bent vertex is a weighted mean of its joints' images of it, and lies inside the spheres
//! of its joints' images, so inside any sphere that encloses them: the bounds are
//! conservative. A morph target's displacement widens each sphere by its weight times its
//! longest displacement (through the joint's largest scale). A skin whose weights are not
//! so, or that names a joint it lacks (built by hand, not loaded: the loader refuses it), is
//! bent on the CPU instead (`Renderer::set_bending`).

use glam::{Mat4, Vec3};
use manyshadows_scene::animation::{Animations, Bending};
use manyshadows_scene::Scene;
use wgpu::util::DeviceExt;

use crate::gpu::context::GpuContext;
use crate::gpu_scene::instances::{GpuScene, POSITION_STRIDE};

/// Its WGSL.
pub const SHADER: &str = include_str!("deform.wgsl");

/// A record's "not skinned".
const NO_SKIN: u32 = u32::MAX;

/// A sphere: centre and radius.
pub type Sphere = (Vec3, f32);

/// The bounds of a mesh its skin or morph targets bend, drawn from what bends it (the CPU
/// never sees its bent vertices).
pub struct MeshBounds {
    /// Its skin (index into `Animations::skins`).
    skin: Option<usize>,
    /// Its morph targets (index into `Animations::morphs`).
    morph: Option<usize>,
    /// Per joint, the sphere around the bind vertices it weighs (`None`: it weighs none), in
    /// the mesh's coordinates; one sphere around every bind vertex when it has no skin.
    parts: Vec<Option<Sphere>>,
    /// Per morph target, its longest position displacement.
    reach: Vec<f32>,
}

impl MeshBounds {
    /// The bounds of mesh `mesh` of `anim` (`None`: nothing bends it). Its skin's weights
    /// must be convex ([`manyshadows_scene::animation::Skin::is_convex`]) for them to hold.
    pub fn new(anim: &Animations, mesh: usize) -> Option<Self> {
        let skin = anim.skins.iter().position(|s| s.mesh == mesh);
        let morph = anim.morphs.iter().position(|m| m.mesh == mesh);
        let bind = match (morph, skin) {
            (Some(k), _) => &anim.morphs[k].base_positions,
            (None, Some(s)) => &anim.skins[s].bind_positions,
            (None, None) => return None,
        };
        let reach = morph.map_or(Vec::new(), |k| {
            let m = &anim.morphs[k];
            m.position_deltas
                .iter()
                .map(|d| d.iter().map(|d| d.length()).fold(0.0, f32::max))
                .collect()
        });
        let parts = match skin {
            Some(s) => joint_parts(&anim.skins[s], bind),
            None => vec![Some(enclosing_points(bind))],
        };
        Some(Self {
            skin,
            morph,
            parts,
            reach,
        })
    }

    /// The parts' spheres around `positions`, the mesh's vertices as they stand (the same
    /// parts, in the same order, as [`MeshBounds::spheres`] gives).
    pub fn parts_around(&self, anim: &Animations, positions: &[Vec3]) -> Vec<Sphere> {
        match self.skin {
            Some(s) => joint_parts(&anim.skins[s], positions)
                .into_iter()
                .zip(&self.parts)
                .filter(|(_, p)| p.is_some())
                .map(|(now, _)| now.unwrap_or((Vec3::ZERO, 0.0)))
                .collect(),
            None => vec![enclosing_points(positions)],
        }
    }

    /// The bounds under `bending`: a sphere around the whole bent mesh, and its parts'
    /// spheres (per joint that weighs a vertex, or the whole morphed mesh), in the mesh's
    /// coordinates.
    pub fn spheres(&self, anim: &Animations, bending: &Bending) -> (Sphere, Vec<Sphere>) {
        // How far the morph targets can take a vertex.
        let widen: f32 = self.morph.map_or(0.0, |m| {
            let w = anim.morphs[m].weights_in(bending);
            w.iter().zip(&self.reach).map(|(w, r)| w.abs() * r).sum()
        });
        let parts: Vec<Sphere> = match self.skin.map(|s| &anim.skins[s]) {
            Some(s) => s
                .matrices(&bending.worlds)
                .iter()
                .zip(&self.parts)
                .filter_map(|(m, part)| {
                    let (c, r) = (*part)?;
                    Some((m.transform_point3(c), (r + widen) * max_stretch(*m)))
                })
                .collect(),
            None => self
                .parts
                .iter()
                .flatten()
                .map(|&(c, r)| (c, r + widen))
                .collect(),
        };
        (enclosing_spheres(&parts), parts)
    }
}

/// One mesh the GPU bends.
struct Deformed {
    /// The scene mesh.
    mesh: usize,
    /// Its bounds.
    bounds: MeshBounds,
    /// Where its joints' matrices begin in the frame buffer (in matrices).
    joint_base: u32,
    /// Where its morph weights begin (in weights).
    weight_base: u32,
    /// Its parts' spheres as the last pose left them (the mesh's coordinates; at first,
    /// around the vertices as uploaded).
    last: Vec<Sphere>,
    /// Where it lies in the scene's position buffer, in bytes, and how many.
    bytes: (u64, u64),
}

/// A mesh bent by a pose: its whole sphere and its parts' spheres before and after (the
/// mesh's coordinates; the instances drawing it take them to the world).
pub struct Bent {
    /// The scene mesh.
    pub mesh: usize,
    /// A sphere around the whole bent mesh.
    pub sphere: Sphere,
    /// Per part (a joint, or the whole morphed mesh): where it was and where it is.
    pub parts: Vec<(Sphere, Sphere)>,
}

/// The skins and morph targets on the GPU, and the pass that bends them.
pub struct Deformer {
    meshes: Vec<Deformed>,
    frame: wgpu::Buffer,
    /// Joint matrices in all (the morph weights follow them in `frame`).
    joints: u32,
    /// Morph weights in all.
    weights: u32,
    /// Deformed vertices in all.
    vertices: u32,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// A pose was set since the pass last ran.
    pending: bool,
}

impl Deformer {
    /// Uploads every skin and morph target of `scene` whose mesh `gpu` holds with the same
    /// vertex count and whose weights are convex; `None` when there are none.
    pub fn new(ctx: &GpuContext, scene: &Scene, gpu: &GpuScene) -> Option<Self> {
        let anim = &scene.animations;
        let mut meshes: Vec<usize> = anim
            .skins
            .iter()
            .map(|s| s.mesh)
            .chain(anim.morphs.iter().map(|m| m.mesh))
            .collect();
        meshes.sort_unstable();
        meshes.dedup();
        let mut deformed = Vec::new();
        let (mut index, mut owner) = (Vec::<u32>::new(), Vec::<u32>::new());
        let mut bind: Vec<[f32; 4]> = Vec::new();
        let mut skin_words: Vec<[u32; 4]> = Vec::new();
        let mut deltas: Vec<[f32; 4]> = Vec::new();
        let (mut joints, mut weights) = (0u32, 0u32);
        for mesh in meshes {
            let skin = anim.skins.iter().position(|s| s.mesh == mesh);
            let morph = anim.morphs.iter().position(|m| m.mesh == mesh);
            let Some((count, base)) = gpu
                .meshes
                .get(mesh)
                .zip(scene.meshes.get(mesh))
                .map(|(r, m)| (m.positions.len(), r.base_vertex as u32))
            else {
                continue;
            };
            let (bind_p, bind_n) = match (morph, skin) {
                (Some(k), _) => (&anim.morphs[k].base_positions, &anim.morphs[k].base_normals),
                (None, Some(s)) => (&anim.skins[s].bind_positions, &anim.skins[s].bind_normals),
                (None, None) => continue,
            };
            let fits = bind_p.len() == count
                && bind_n.len() == count
                && skin.is_none_or(|s| {
                    let s = &anim.skins[s];
                    s.bind_positions.len() == count
                        && s.is_convex()
                        && s.problem(anim.nodes.len()).is_none()
                        && s.joints.len() <= 1 << 16
                })
                && morph.is_none_or(|m| {
                    let m = &anim.morphs[m];
                    m.position_deltas.iter().all(|d| d.len() == count)
                        && m.normal_deltas.iter().all(|d| d.len() == count)
                        && m.normal_deltas.len() == m.position_deltas.len()
                });
            if !fits {
                continue;
            }
            let first = (bind.len() / 2) as u32;
            let record = deformed.len() as u32;
            for (p, n) in bind_p.iter().zip(bind_n) {
                bind.push(p.extend(1.0).to_array());
                bind.push(n.extend(0.0).to_array());
            }
            let (mut targets, mut delta_base) = (0, 0);
            let weight_base = weights;
            if let Some(m) = morph.map(|k| &anim.morphs[k]) {
                targets = m.position_deltas.len() as u32;
                delta_base = (deltas.len() / 2) as u32;
                for (dp, dn) in m.position_deltas.iter().zip(&m.normal_deltas) {
                    for (p, n) in dp.iter().zip(dn) {
                        deltas.push(p.extend(0.0).to_array());
                        deltas.push(n.extend(0.0).to_array());
                    }
                }
                weights += targets;
            }
            let (joint_base, slots) = match skin.map(|k| &anim.skins[k]) {
                Some(s) => {
                    let eight = !s.extra_joints.is_empty();
                    for v in 0..count {
                        let j = s.vertex_joints[v];
                        let e = s.extra_joints.get(v).copied().unwrap_or([0; 4]);
                        let w = s.vertex_weights[v];
                        let we = s.extra_weights.get(v).copied().unwrap_or([0.0; 4]);
                        let half = |a: u16, b: u16| u32::from(a) | (u32::from(b) << 16);
                        skin_words.push([
                            half(j[0], j[1]),
                            half(j[2], j[3]),
                            half(e[0], e[1]),
                            half(e[2], e[3]),
                        ]);
                        skin_words.push(w.map(f32::to_bits));
                        skin_words.push(we.map(f32::to_bits));
                    }
                    let base = joints;
                    joints += s.joints.len() as u32;
                    (base, if eight { 8 } else { 4 })
                }
                None => {
                    skin_words.extend(std::iter::repeat_n([0; 4], 3 * count));
                    (NO_SKIN, 0)
                }
            };
            let Some(bounds) = MeshBounds::new(anim, mesh) else {
                continue;
            };
            let last = bounds.parts_around(anim, &scene.meshes[mesh].positions);
            index.extend([
                first,
                base,
                joint_base,
                slots,
                targets,
                delta_base,
                weight_base,
                count as u32,
            ]);
            owner.extend(std::iter::repeat_n(record, count));
            deformed.push(Deformed {
                mesh,
                bounds,
                joint_base,
                weight_base,
                last,
                bytes: (
                    u64::from(base) * POSITION_STRIDE,
                    count as u64 * POSITION_STRIDE,
                ),
            });
        }
        if deformed.is_empty() {
            return None;
        }
        let vertices = owner.len() as u32;
        let owner_at = index.len() as u32;
        index.extend(owner);
        let device = &ctx.device;
        let init = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if bytes.is_empty() { &[0; 16] } else { bytes },
                usage,
            })
        };
        let storage = wgpu::BufferUsages::STORAGE;
        let params = init(
            "deform.params",
            bytemuck::cast_slice(&[vertices, owner_at, 4 * joints, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let index = init("deform.index", bytemuck::cast_slice(&index), storage);
        let bind = init("deform.bind", bytemuck::cast_slice(&bind), storage);
        let skin = init("deform.skin", bytemuck::cast_slice(&skin_words), storage);
        let deltas = init("deform.deltas", bytemuck::cast_slice(&deltas), storage);
        let frame_bytes = (16 * (4 * joints + weights.div_ceil(4))).max(16);
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("deform.frame"),
            size: u64::from(frame_bytes),
            usage: storage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let module = crate::gpu::shaders::module(device, "deform.shader", SHADER);
        let cs = wgpu::ShaderStages::COMPUTE;
        use crate::gpu::pipelines as p;
        let layout = p::bind_group_layout(
            device,
            "deform.layout",
            &[
                p::uniform_entry(0, cs),
                p::storage_entry(1, cs),
                p::storage_entry(2, cs),
                p::storage_entry(3, cs),
                p::storage_entry(4, cs),
                p::storage_entry(5, cs),
                p::storage_rw_entry(6, cs),
                p::storage_rw_entry(7, cs),
            ],
        );
        let bind_group = p::buffer_bind_group(
            device,
            "deform.bind_group",
            &layout,
            &[
                &params,
                &index,
                &bind,
                &skin,
                &deltas,
                &frame,
                &gpu.positions,
                &gpu.normals,
            ],
        );
        let pipeline_layout = p::pipeline_layout(device, "deform.pipeline_layout", &[&layout]);
        let pipeline =
            p::compute_pipeline(device, "deform", &pipeline_layout, &module, "cs_deform");
        Some(Self {
            meshes: deformed,
            frame,
            joints,
            weights,
            vertices,
            pipeline,
            bind_group,
            pending: false,
        })
    }

    /// Whether this bends mesh `mesh`.
    pub fn bends(&self, mesh: usize) -> bool {
        self.meshes.iter().any(|d| d.mesh == mesh)
    }

    /// Where each mesh it bends lies in the scene's position buffer: `(mesh, first byte,
    /// bytes)`.
    pub fn ranges(&self) -> impl Iterator<Item = (usize, u64, u64)> + '_ {
        self.meshes.iter().map(|d| (d.mesh, d.bytes.0, d.bytes.1))
    }

    /// Takes the pose `bending` (of `anim`, the animations this was made from) for the next
    /// frame: its joint matrices and morph weights are written, and the pass runs before that
    /// frame draws. Returns every mesh it bends, with its bounds.
    pub fn pose(&mut self, queue: &wgpu::Queue, anim: &Animations, bending: &Bending) -> Vec<Bent> {
        let mut data = vec![[0.0f32; 4]; (4 * self.joints + self.weights.div_ceil(4)) as usize];
        let weights_at = 4 * self.joints as usize;
        let mut bent = Vec::with_capacity(self.meshes.len());
        for k in 0..self.meshes.len() {
            let d = &self.meshes[k];
            if let Some(s) = d.bounds.skin.map(|s| &anim.skins[s]) {
                for (j, m) in s.matrices(&bending.worlds).iter().enumerate() {
                    let at = 4 * (d.joint_base as usize + j);
                    for c in 0..4 {
                        data[at + c] = m.col(c).to_array();
                    }
                }
            }
            if let Some(m) = d.bounds.morph.map(|m| &anim.morphs[m]) {
                let targets = m.position_deltas.len();
                for (t, &w) in m.weights_in(bending).iter().take(targets).enumerate() {
                    let at = d.weight_base as usize + t;
                    data[weights_at + at / 4][at % 4] = w;
                }
            }
            let (sphere, parts) = d.bounds.spheres(anim, bending);
            let d = &mut self.meshes[k];
            let last = std::mem::replace(&mut d.last, parts.clone());
            bent.push(Bent {
                mesh: d.mesh,
                sphere,
                parts: last.into_iter().zip(parts).collect(),
            });
        }
        queue.write_buffer(&self.frame, 0, bytemuck::cast_slice(&data));
        self.pending = true;
        bent
    }

    /// Records the pass if a pose was set since it last ran (the scene's positions and
    /// normals of every mesh it bends are then those of the last pose).
    pub fn record(&mut self, pass: &mut wgpu::ComputePass<'_>) {
        if !std::mem::take(&mut self.pending) {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        let (x, y) = crate::gpu::pipelines::dispatch_2d(u64::from(self.vertices), 65535);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// A pose waits for the pass.
    pub fn pending(&self) -> bool {
        self.pending
    }
}

/// Per joint of `skin`, a sphere around the bind vertices (`bind`) it weighs.
fn joint_parts(skin: &manyshadows_scene::animation::Skin, bind: &[Vec3]) -> Vec<Option<Sphere>> {
    let mut boxes: Vec<Option<(Vec3, Vec3)>> = vec![None; skin.joints.len()];
    let mut add = |j: u16, w: f32, p: Vec3| {
        if w > 0.0 {
            if let Some(b) = boxes.get_mut(usize::from(j)) {
                *b = Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
            }
        }
    };
    for (v, &p) in bind.iter().enumerate() {
        for k in 0..4 {
            add(skin.vertex_joints[v][k], skin.vertex_weights[v][k], p);
            if let (Some(j), Some(w)) = (skin.extra_joints.get(v), skin.extra_weights.get(v)) {
                add(j[k], w[k], p);
            }
        }
    }
    let mut radius = vec![0.0f32; skin.joints.len()];
    let centre = |j: usize| boxes[j].map(|(lo, hi)| 0.5 * (lo + hi));
    for (v, &p) in bind.iter().enumerate() {
        for k in 0..4 {
            let sets = [
                Some((skin.vertex_joints[v][k], skin.vertex_weights[v][k])),
                skin.extra_joints
                    .get(v)
                    .zip(skin.extra_weights.get(v))
                    .map(|(j, w)| (j[k], w[k])),
            ];
            for (j, w) in sets.into_iter().flatten() {
                let j = usize::from(j);
                if let (true, Some(c)) = (w > 0.0, centre(j.min(boxes.len().saturating_sub(1)))) {
                    if j < radius.len() {
                        radius[j] = radius[j].max(p.distance(c));
                    }
                }
            }
        }
    }
    (0..skin.joints.len())
        .map(|j| centre(j).map(|c| (c, radius[j] * (1.0 + 1e-5) + 1e-6)))
        .collect()
}

/// A sphere around `points`: their box's centre, the farthest one's distance.
fn enclosing_points(points: &[Vec3]) -> Sphere {
    let Some(&p0) = points.first() else {
        return (Vec3::ZERO, 0.0);
    };
    let (lo, hi) = points
        .iter()
        .fold((p0, p0), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let c = 0.5 * (lo + hi);
    let r = points.iter().map(|p| p.distance(c)).fold(0.0, f32::max);
    (c, r * (1.0 + 1e-5) + 1e-6)
}

/// A sphere around `spheres`: their box's centre, the farthest one's far side.
pub fn enclosing_spheres(spheres: &[Sphere]) -> Sphere {
    let Some(&(c0, r0)) = spheres.first() else {
        return (Vec3::ZERO, 0.0);
    };
    let (lo, hi) = spheres
        .iter()
        .fold((c0 - r0, c0 + r0), |(lo, hi), &(c, r)| {
            (lo.min(c - Vec3::splat(r)), hi.max(c + Vec3::splat(r)))
        });
    let c = 0.5 * (lo + hi);
    let r = spheres
        .iter()
        .map(|&(s, r)| s.distance(c) + r)
        .fold(0.0, f32::max);
    (c, r)
}

/// The largest factor by which `m` stretches a length (its upper 3×3's largest singular
/// value, from the largest eigenvalue of `MᵀM` in closed form), a hair over.
pub fn max_stretch(m: Mat4) -> f32 {
    let m3 = glam::Mat3::from_mat4(m);
    let a = m3.transpose() * m3;
    let (a00, a11, a22) = (a.x_axis.x, a.y_axis.y, a.z_axis.z);
    let (a01, a02, a12) = (a.y_axis.x, a.z_axis.x, a.z_axis.y);
    let p1 = a01 * a01 + a02 * a02 + a12 * a12;
    let q = (a00 + a11 + a22) / 3.0;
    let p2 = (a00 - q).powi(2) + (a11 - q).powi(2) + (a22 - q).powi(2) + 2.0 * p1;
    let largest = if p2 <= f32::EPSILON * q * q {
        a00.max(a11).max(a22)
    } else {
        let p = (p2 / 6.0).sqrt();
        let b = (a - glam::Mat3::from_diagonal(Vec3::splat(q))) * (1.0 / p);
        let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
        q + 2.0 * p * (r.acos() / 3.0).cos()
    };
    // The closed form loses a few ulps; the Frobenius norm bounds it from above.
    let frobenius = (a00 + a11 + a22).max(0.0);
    (largest.max(0.0) * (1.0 + 1e-4)).min(frobenius).sqrt() * (1.0 + 1e-5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use manyshadows_scene::animation::Playing;
    use manyshadows_scene::builtin::{self, BuiltinOptions};

    /// Every vertex the CPU bends lies inside the bounds drawn from the joints, and inside
    /// the sphere around its own joints' parts, at every time of the walker's clip; and the
    /// bounds follow the figure (they are not the rest pose's).
    #[test]
    fn bounds_drawn_from_the_joints_hold_every_bent_vertex() {
        let scene = builtin::build("walker", &BuiltinOptions::default()).expect("walker");
        let anim = &scene.animations;
        let skin = &anim.skins[0];
        assert!(skin.is_convex());
        let bounds = MeshBounds::new(anim, skin.mesh).expect("bounds");
        let rest = bounds.spheres(anim, &anim.bending_at_rest()).0;
        let mut moved = 0.0f32;
        for k in 0..=40 {
            let t = k as f32 * 0.05;
            let bending = anim.bending(Playing::One(0), t);
            let (whole, parts) = bounds.spheres(anim, &bending);
            let (_, bent, _) = anim.bend(&bending).remove(0);
            // The joints that weigh a vertex, by their index among the parts.
            let part_of: Vec<Option<usize>> = bounds
                .parts
                .iter()
                .scan(0, |n, p| {
                    Some(p.map(|_| {
                        *n += 1;
                        *n - 1
                    }))
                })
                .collect();
            for (v, p) in bent.iter().enumerate() {
                assert!(
                    p.distance(whole.0) <= whole.1 * (1.0 + 1e-5),
                    "t {t}: vertex {v} at {p} outside {whole:?}"
                );
                let own: Vec<Sphere> = (0..4)
                    .filter(|&k| skin.vertex_weights[v][k] > 0.0)
                    .filter_map(|k| part_of[usize::from(skin.vertex_joints[v][k])])
                    .map(|i| parts[i])
                    .collect();
                let (c, r) = enclosing_spheres(&own);
                assert!(
                    p.distance(c) <= r * (1.0 + 1e-5),
                    "t {t}: vertex {v} at {p} outside its joints' parts {own:?}"
                );
            }
            moved = moved.max(whole.0.distance(rest.0));
        }
        // The pelvis carries the figure 2.8 m along x over the clip.
        assert!(moved > 2.0, "the bounds stayed at rest: {moved}");
    }

    /// Its WGSL is WebGPU's, within WebGPU's default of 8 storage buffers a stage.
    #[test]
    fn shader_validates_for_webgpu() {
        crate::gpu::shaders::validate_for_webgpu("deform", SHADER, wgpu::Features::empty())
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(SHADER.matches("var<storage").count() <= 8);
    }

    /// The largest stretch of a matrix is its largest singular value: exact for scalings and
    /// rotations, and an upper bound that a sheared matrix's columns underestimate.
    #[test]
    fn max_stretch_is_the_largest_singular_value() {
        let r = Mat4::from_rotation_y(0.7) * Mat4::from_rotation_x(-1.1);
        assert!((max_stretch(r) - 1.0).abs() < 1e-3);
        let s = Mat4::from_scale(Vec3::new(0.5, 3.0, 2.0)) * r;
        assert!((max_stretch(s) - 3.0).abs() < 3e-3);
        // A shear: columns (1,0,0) and (1,1,0); its largest singular value is the golden
        // ratio, above either column's length (1.414).
        let shear = Mat4::from_cols(
            glam::Vec4::X,
            glam::Vec4::new(1.0, 1.0, 0.0, 0.0),
            glam::Vec4::Z,
            glam::Vec4::W,
        );
        let golden = (1.0 + 5f32.sqrt()) / 2.0;
        assert!(max_stretch(shear) >= golden && max_stretch(shear) < golden * 1.001);
    }
}
