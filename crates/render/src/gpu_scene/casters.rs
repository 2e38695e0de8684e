//! Shadow-caster geometry shared by the single-pass techniques.
//!
//! Seed 000 §19.4.1 locates layered rendering's saving in the per-vertex work (model
//! transform, skinning) that a one-pass-per-map renderer repeats for every map. Here that work
//! runs **once per frame**: a compute pass writes the world position of every vertex of every
//! shadow-casting instance into [`CasterGeometry::world`], and every shadow view then only
//! applies its view-projection. The same buffers feed `layered` (vertex pulling),
//! `multiview`, and `gpu-driven` (triangle clusters).
//!
//!
//! What is on the GPU and how it is recorded is here; what is decided on the CPU (the layout
//! of caster vertices, corners and clusters, closure, normal cones, the mask tail) is in
//! [`crate::gpu_scene::caster_layout`].

use glam::Mat4;
use manyshadows_scene::masks::MaskSet;
use manyshadows_scene::Scene;
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;
use crate::gpu_scene::caster_layout::*;
use crate::gpu_scene::instances::GpuScene;
use crate::gpu_scene::skinning::{MAX_BONES, SKIN_VERTEX_STRIDE};

/// Alpha-tested casters: the mask tail of the corner buffer, for any shader that tests a
/// caster's mask (it needs a `corners` binding).
pub const ALPHA_MASK: &str = include_str!("alpha_mask.wgsl");

/// The per-frame world transform of shadow casters: its WGSL, with the cluster constants.
pub fn shader() -> String {
    let group = format!(
        "const CLUSTER_GROUP: u32 = {CLUSTER_GROUP}u;\nconst CLUSTER_PARTS: u32 = {CLUSTER_PARTS}u;\n\
         const PART_TRIANGLES: u32 = {}u;",
        CLUSTER_TRIANGLES / CLUSTER_PARTS
    );
    crate::gpu::shaders::compose(&[
        crate::gpu::shaders::COMMON,
        &group,
        include_str!("casters.wgsl"),
    ])
}

/// World-space caster geometry, recomputed once per frame by [`CasterGeometry::record`].
pub struct CasterGeometry {
    /// Caster vertices.
    pub vertices: u32,
    /// Caster triangles.
    pub triangles: u32,
    /// The first `cullable_triangles` triangles may be back-face culled.
    pub cullable_triangles: u32,
    /// The first `cullable_clusters` clusters hold the cullable triangles.
    pub cullable_clusters: u32,
    /// Some of the cullable triangles are single-sided and cast only where a light sees
    /// their front (`CasterOptions::single_sided`): every technique then culls the cullable
    /// triangles by facing, for every light and in every kind of view (exact for the closed
    /// meshes among them too).
    pub front_only: bool,
    /// Triangles from here on are alpha-tested (`triangles` when none are).
    pub first_masked_triangle: u32,
    /// Clusters from here on are alpha-tested (`clusters.len()` when none are).
    pub first_masked_cluster: u32,
    /// Clusters.
    pub clusters: Vec<ClusterData>,
    /// `array<vec4<f32>>` world positions (w = 1), one per caster vertex.
    pub world: wgpu::Buffer,
    /// `u32` caster-vertex indices, three per triangle (STORAGE | INDEX), followed by the mask
    /// tail (see the module docs).
    pub corners: wgpu::Buffer,
    /// `array<Cluster>`.
    pub cluster_buffer: wgpu::Buffer,
    /// `array<vec4<f32>>` world bounding sphere per cluster, then one per group of
    /// [`CLUSTER_GROUP`] clusters at `clusters.len() + g`, then per cluster its axis-aligned
    /// box as two corners (low, high) at `clusters.len() + groups + 2c`, then per cluster the
    /// boxes of its [`CLUSTER_PARTS`] parts at `3 clusters.len() + groups + 2 (parts c + k)`
    /// (all written each frame).
    pub cluster_bounds: wgpu::Buffer,
    skinned: bool,
    options: CasterOptions,
    masks: MaskSet,
    cache: MeshCache,
    decisions: Vec<Decision>,
    transform: wgpu::ComputePipeline,
    bounds: wgpu::ComputePipeline,
    groups: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl CasterGeometry {
    /// Builds the caster buffers of `scene` (already uploaded as `gpu`).
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        options: CasterOptions,
    ) -> Result<Self, RenderError> {
        let skinned = gpu.skin.is_some();
        let masks = if options.ignore_masks {
            MaskSet::default()
        } else {
            gpu.masks.clone()
        };
        let mut cache = MeshCache::new(scene.meshes.len());
        let decisions = cache.decisions(scene, &masks, options, skinned);
        let layout = cache.layout(scene, &decisions);
        if gpu.skin.is_some() && layout.first_masked_vertex < layout.sources.len() as u32 {
            return Err(RenderError::NotImplemented {
                what: "skinning alpha-tested shadow casters",
                instead: "skinning is a benchmark workload for opaque meshes: turn the masks \
                          off or leave the skin out",
            });
        }
        let tail = mask_tail(scene, &masks, &layout);
        let Layout {
            mut sources,
            corners: mut all_corners,
            clusters: mut all_clusters,
            cullable_triangles,
            cullable_clusters,
            front_only,
            first_masked_triangle,
            first_masked_cluster,
            ..
        } = layout;
        let vertices = sources.len() as u32;
        let triangles = (all_corners.len() / 3) as u32;
        all_corners.extend(tail);

        let limits = ctx.limits();
        for (what, bytes) in [
            ("caster world-position", vertices as u64 * 16),
            ("caster corner", all_corners.len() as u64 * 4),
        ] {
            if bytes > limits.max_storage_buffer_binding_size {
                return Err(RenderError::TooLarge {
                    what: format!("the {what} buffer"),
                    needed: bytes,
                    limit: limits.max_storage_buffer_binding_size,
                    unit: "bytes",
                    limit_name: "max_storage_buffer_binding_size",
                });
            }
        }

        // Zero-sized buffers are invalid: keep one dummy element (the corner buffer always
        // holds at least the mask tail's header).
        if sources.is_empty() {
            sources.push([0, 0]);
        }
        let cluster_list = all_clusters.clone();
        if all_clusters.is_empty() {
            all_clusters.push(bytemuck::Zeroable::zeroed());
        }
        let device = &ctx.device;
        let init = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let world = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("casters.world"),
            size: sources.len() as u64 * 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let corners_buf = init(
            "casters.corners",
            bytemuck::cast_slice(&all_corners),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
        );
        let sources_buf = init(
            "casters.sources",
            bytemuck::cast_slice(&sources),
            wgpu::BufferUsages::STORAGE,
        );
        let cluster_buffer = init(
            "casters.clusters",
            bytemuck::cast_slice(&all_clusters),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let cluster_bounds = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("casters.cluster_bounds"),
            // Per cluster a sphere, per group a sphere, then per cluster a box (two corners),
            // then per cluster its parts' boxes.
            size: ((3 + 2 * u64::from(CLUSTER_PARTS)) * all_clusters.len() as u64
                + u64::from(groups_of(all_clusters.len())))
                * 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let params = init(
            "casters.params",
            bytemuck::cast_slice(&[vertices, cluster_list.len() as u32, u32::from(skinned), 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        // A bound but unused skin when the scene has none.
        let dummy_skin;
        let (skin_vertices, bones) = match &gpu.skin {
            Some(s) => (&s.vertices, &s.bones),
            None => {
                dummy_skin = (
                    init(
                        "casters.no_skin",
                        &[0u8; SKIN_VERTEX_STRIDE as usize],
                        wgpu::BufferUsages::STORAGE,
                    ),
                    init(
                        "casters.no_bones",
                        bytemuck::cast_slice(&[Mat4::IDENTITY.to_cols_array(); MAX_BONES]),
                        wgpu::BufferUsages::UNIFORM,
                    ),
                );
                (&dummy_skin.0, &dummy_skin.1)
            }
        };

        let module = crate::gpu::shaders::module(device, "casters.shader", &shader());
        let cs = wgpu::ShaderStages::COMPUTE;
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "casters.layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, cs),
                crate::gpu::pipelines::storage_entry(1, cs),
                crate::gpu::pipelines::storage_entry(2, cs),
                crate::gpu::pipelines::storage_entry(3, cs),
                crate::gpu::pipelines::storage_rw_entry(4, cs),
                crate::gpu::pipelines::uniform_entry(5, cs),
                crate::gpu::pipelines::storage_entry(6, cs),
                crate::gpu::pipelines::storage_entry(7, cs),
                crate::gpu::pipelines::storage_entry(8, cs),
                crate::gpu::pipelines::storage_rw_entry(9, cs),
            ],
        );
        let buffers = [
            &params,
            &gpu.positions,
            &gpu.instances,
            &sources_buf,
            &world,
            bones,
            skin_vertices,
            &cluster_buffer,
            &corners_buf,
            &cluster_bounds,
        ];
        let bind_group = crate::gpu::pipelines::buffer_bind_group(
            device,
            "casters.bind_group",
            &layout,
            &buffers,
        );
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "casters.pipeline_layout", &[&layout]);
        let pipeline = |entry: &str| {
            crate::gpu::pipelines::compute_pipeline(device, entry, &pipeline_layout, &module, entry)
        };
        Ok(Self {
            vertices,
            triangles,
            cullable_triangles,
            cullable_clusters,
            front_only,
            first_masked_triangle,
            first_masked_cluster,
            masks,
            clusters: cluster_list,
            transform: pipeline("cs_transform"),
            bounds: pipeline("cs_bounds"),
            groups: pipeline("cs_groups"),
            world,
            corners: corners_buf,
            cluster_buffer,
            cluster_bounds,
            skinned,
            options,
            cache,
            decisions,
            bind_group,
        })
    }

    /// Re-decides which instances may be back-face culled for `scene`'s current lights and
    /// instance transforms (a light that moved into a closed caster's box, a caster that moved
    /// over a light, a transform that became mirrored or non-uniform), and rewrites the corner
    /// and cluster buffers in place when a decision changed: the same triangles and clusters,
    /// regrouped. Returns true if anything was rewritten.
    pub fn refresh(&mut self, ctx: &GpuContext, scene: &Scene) -> bool {
        let decisions = self
            .cache
            .decisions(scene, &self.masks, self.options, self.skinned);
        if decisions == self.decisions {
            return false;
        }
        let layout = self.cache.layout(scene, &decisions);
        debug_assert_eq!(layout.corners.len() as u32, 3 * self.triangles);
        // Masked instances keep their class, so the mask tail after the corners stays valid.
        debug_assert_eq!(layout.first_masked_triangle, self.first_masked_triangle);
        debug_assert_eq!(layout.clusters.len(), self.clusters.len());
        if !layout.corners.is_empty() {
            ctx.queue
                .write_buffer(&self.corners, 0, bytemuck::cast_slice(&layout.corners));
        }
        if !layout.clusters.is_empty() {
            ctx.queue.write_buffer(
                &self.cluster_buffer,
                0,
                bytemuck::cast_slice(&layout.clusters),
            );
        }
        self.cullable_triangles = layout.cullable_triangles;
        self.cullable_clusters = layout.cullable_clusters;
        self.front_only = layout.front_only;
        self.clusters = layout.clusters;
        self.decisions = decisions;
        true
    }

    /// True if `material`'s casters are alpha-tested in the shadow passes.
    pub fn is_masked(&self, material: u32) -> bool {
        self.masks.is_masked(material as usize)
    }

    /// True if scene instance `instance` is a single-sided caster that casts only where a light
    /// sees its front (`CasterOptions::single_sided`).
    pub fn casts_front_only(&self, instance: u32) -> bool {
        self.decisions
            .get(instance as usize)
            .is_some_and(|d| d.front_only)
    }

    /// True if world positions come from the skin.
    pub fn skinned(&self) -> bool {
        self.skinned
    }

    /// Records the per-frame world transform (and, with `bounds`, the cluster spheres) into a
    /// compute pass.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>, bounds: bool) {
        if self.vertices == 0 {
            return;
        }
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_pipeline(&self.transform);
        let (x, y) = crate::gpu::pipelines::dispatch_2d(u64::from(self.vertices), 65535);
        pass.dispatch_workgroups(x, y, 1);
        if bounds && !self.clusters.is_empty() {
            pass.set_pipeline(&self.bounds);
            pass.dispatch_workgroups((self.clusters.len() as u32).div_ceil(64), 1, 1);
            pass.set_pipeline(&self.groups);
            pass.dispatch_workgroups(groups_of(self.clusters.len()).div_ceil(64), 1, 1);
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn cluster_record_matches_the_wgsl() {
        use crate::gpu::types::layout::same_layout;
        same_layout!(in super::shader(), super::ClusterData as "Cluster", first_triangle, triangles, instance, flags, cone);
    }
}

#[cfg(test)]
mod shader_tests {
    /// What this module composes is WGSL a WebGPU device accepts.
    #[test]
    fn shader_validates_for_webgpu() {
        crate::gpu::shaders::validate_for_webgpu(
            "casters",
            &super::shader(),
            wgpu::Features::empty(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}
