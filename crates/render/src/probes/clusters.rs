//! Probe faces drawn GPU-driven (`ProbePasses::Clusters`, seed 002's route on colour
//! targets): every instance's mesh is cut into clusters of at most [`CLUSTER_TRIANGLES`]
//! consecutive triangles (the scene's Morton-ordered index buffer, so a cluster is compact);
//! a compute pass tests each (cluster, face) pair against the face's frustum (the cluster's
//! bounding sphere) and, where the material shows only front faces, against the face's eye
//! (the cluster's normal cone), and writes an indexed-indirect command for each survivor; one
//! multi-draw per round then draws them into the faces' tiles of the atlas G-buffer
//! (`GBufferViews::FaceClusters`), whose tiles are lit exactly as the layered way's are.
//!
//! Rounds: a command's base vertex carries its face slot and instance
//! (`slot · S + instance · V + vertex`, S = V × instances, `gbuffer_face_clusters.wgsl`), so a
//! round holds as many faces as keep that below 2³¹ and its commands within a storage binding
//! ([`plan_rounds`], shared with the shadow maps' cluster draws). A round never mixes
//! clusters drawn with different pipelines (alpha test, which faces the material shows).

use std::collections::HashMap;

use glam::Vec3;
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::frame::gbuffer::GBuffer;
use crate::frame::gbuffer_pull::{FaceDrawParams, FACE_DRAW_PARAMS_STRIDE, PARAMS_WGSL};
use crate::gpu::context::GpuContext;
use crate::gpu::pipelines::{dynamic_uniform_entry, storage_entry, storage_rw_entry, whole_entry};
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::caster_layout::{is_similarity, normal_cone, NO_CONE};
use crate::gpu_scene::instances::{morton_order, CameraCull, GpuScene};
use crate::shadows::cluster_draw::{plan_rounds, Round, CLUSTER_CULL, COMMAND_SIZE};

/// Most triangles per cluster: small enough that a 90° face leaves many of an instance's
/// clusters out, large enough that the commands stay few. Chosen by measurement (lavapipe
/// pays for every indirect command as for a draw, and 256 was the fastest of 64 to 512;
/// docs/techniques.md, "Reflection probes (`--probes`)").
pub(crate) const CLUSTER_TRIANGLES: usize = 256;

/// `ProbeCluster` of `clusters.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct ProbeCluster {
    first_index: u32,
    index_count: u32,
    base_vertex: u32,
    instance: u32,
    sphere: [f32; 4],
    cone: [f32; 4],
}

/// A run of one mesh's triangles: where its indices start (relative to the mesh's), how many,
/// its object-space bounding sphere and normal cone.
#[derive(Clone, Copy, Debug)]
struct MeshCluster {
    first_index: u32,
    index_count: u32,
    sphere: [f32; 4],
    cone: [f32; 4],
}

/// The cull's WGSL.
fn shader() -> String {
    compose(&[
        COMMON,
        PARAMS_WGSL,
        include_str!("../frame/gbuffer_face_views.wgsl"),
        CLUSTER_CULL,
        include_str!("clusters.wgsl"),
    ])
}

/// The clusters of every instance, the cull and the buffers its rounds use.
pub(crate) struct FaceClusters {
    fence: crate::gpu::raster_fence::RasterFence,
    cull: wgpu::ComputePipeline,
    cull_layout: wgpu::BindGroupLayout,
    /// The G-buffer's second bind group's layout (`gbuffer_pull`).
    pub(crate) pull_layout: wgpu::BindGroupLayout,
    compact: bool,
    max_round_commands: u64,
    /// Each mesh's clusters, made on first use.
    meshes: HashMap<usize, Vec<MeshCluster>>,
    /// Rounds and the pipeline each is drawn with (alpha-tested, faces shown).
    rounds: Vec<(Round, (bool, CameraCull))>,
    /// Bound by `prepare`: params, clusters, commands, counter, and both groups.
    bound: Option<Bound>,
    /// Cluster-face pairs offered to the cull per frame.
    pub(crate) offered: u64,
    /// What the bound buffers were made from: the clusters, the faces, and the views and
    /// instance buffers (a frame that changes none of them, a caster moving say, keeps them).
    made_from: Option<(Vec<ProbeCluster>, u32, [wgpu::Buffer; 2])>,
}

struct Bound {
    commands: wgpu::Buffer,
    counter: wgpu::Buffer,
    /// Pairs kept over the frame's rounds.
    kept: wgpu::Buffer,
    cull_group: wgpu::BindGroup,
    pull_group: wgpu::BindGroup,
}

impl FaceClusters {
    /// The cull's pipeline; needs indirect execution.
    pub(crate) fn new(ctx: &GpuContext) -> Result<Self, RenderError> {
        let downlevel = ctx.adapter.get_downlevel_capabilities().flags;
        if !downlevel.contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION) {
            return Err(RenderError::missing_feature(
                ctx,
                "probe faces drawn GPU-driven",
                "INDIRECT_EXECUTION (the faces are drawn by indirect multi-draws)",
                "draw the probes' faces one pass per face, or layered",
            ));
        }
        let device = &ctx.device;
        let module = crate::gpu::shaders::module(device, "probes.cull_faces", &shader());
        let cs = wgpu::ShaderStages::COMPUTE;
        let cull_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "probes.cull_layout",
            &[
                dynamic_uniform_entry(0, cs, std::mem::size_of::<FaceDrawParams>() as u64),
                storage_entry(1, cs),
                storage_entry(2, cs),
                storage_rw_entry(3, cs),
                storage_rw_entry(4, cs),
                storage_rw_entry(5, cs),
                storage_entry(6, cs),
            ],
        );
        let layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "probes.cull_pipeline_layout",
            &[&cull_layout],
        );
        let cull = crate::gpu::pipelines::compute_pipeline(
            device,
            "probes.cull_faces",
            &layout,
            &module,
            "cs_cull_faces",
        );
        let limits = ctx.limits();
        Ok(Self {
            fence: ctx.raster_fence().clone(),
            cull,
            cull_layout,
            pull_layout: crate::frame::gbuffer_pull::layout(device),
            compact: ctx.has(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
            max_round_commands: limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size)
                / COMMAND_SIZE,
            meshes: HashMap::new(),
            rounds: Vec::new(),
            bound: None,
            offered: 0,
            made_from: None,
        })
    }

    /// Lays out `scene`'s clusters for `faces` faces whose views are `views`, plans the
    /// rounds and binds their buffers. Fails if a face's commands cannot carry every
    /// instance's vertices (scene vertices × instances of 2³¹ or more).
    pub(crate) fn prepare(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
        (faces, views): (u32, &wgpu::Buffer),
    ) -> Result<(), RenderError> {
        let vertices: u64 = scene.meshes.iter().map(|m| m.positions.len() as u64).sum();
        let stride = vertices * gpu_scene.draws.len() as u64;
        if stride >= 1 << 31 {
            return Err(RenderError::TooLarge {
                what: "probe faces drawn GPU-driven (each command's base vertex carries its \
                       instance: scene vertices × instances)"
                    .into(),
                needed: stride,
                limit: (1 << 31) - 1,
                unit: "vertices",
                limit_name: "i32 base vertex",
            });
        }
        // Clusters grouped by the pipeline that draws them.
        let mut groups: Vec<((bool, CameraCull), Vec<ProbeCluster>)> = Vec::new();
        for d in &gpu_scene.draws {
            let instance = &scene.instances[d.instance as usize];
            let mesh = self
                .meshes
                .entry(instance.mesh)
                .or_insert_with(|| mesh_clusters(&scene.meshes[instance.mesh]));
            // The cone holds for the G-buffer's face culling only where the material shows
            // front faces and the transform keeps angles.
            let cones = d.camera_cull != CameraCull::None && is_similarity(instance.transform);
            let key = (d.masked, d.camera_cull);
            let at = match groups.iter().position(|(k, _)| *k == key) {
                Some(at) => at,
                None => {
                    groups.push((key, Vec::new()));
                    groups.len() - 1
                }
            };
            groups[at].1.extend(mesh.iter().map(|c| ProbeCluster {
                first_index: d.mesh.first_index + c.first_index,
                index_count: c.index_count,
                base_vertex: (d.instance as u64 * vertices) as u32 + d.mesh.base_vertex as u32,
                instance: d.instance,
                sphere: c.sphere,
                cone: if cones {
                    c.cone
                } else {
                    [0.0, 0.0, 1.0, NO_CONE]
                },
            }));
        }
        let mut clusters = Vec::new();
        let mut rounds = Vec::new();
        for (key, group) in groups {
            let first = clusters.len() as u32;
            let n = group.len() as u32;
            for mut r in plan_rounds(faces, n, (0, n), stride as u32, self.max_round_commands) {
                r.first_cluster += first;
                rounds.push((r, key));
            }
            clusters.extend(group);
        }
        let buffers = [views.clone(), gpu_scene.instances.clone()];
        if self.bound.is_some()
            && self.made_from.as_ref().is_some_and(|(c, f, b)| {
                *f == faces
                    && *b == buffers
                    && bytemuck::cast_slice::<_, u8>(c) == bytemuck::cast_slice::<_, u8>(&clusters)
            })
        {
            return Ok(());
        }
        self.rounds = rounds;
        self.offered = clusters.len() as u64 * u64::from(faces);
        let records: Vec<u8> = self
            .rounds
            .iter()
            .flat_map(|(r, _)| {
                let p = FaceDrawParams {
                    round: [r.first_view, r.views, r.first_cluster, r.clusters],
                    stride: [stride as u32, vertices as u32, u32::from(self.compact), 0],
                };
                let mut bytes = bytemuck::bytes_of(&p).to_vec();
                bytes.resize(FACE_DRAW_PARAMS_STRIDE as usize, 0);
                bytes
            })
            .collect();
        let device = &ctx.device;
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(FACE_DRAW_PARAMS_STRIDE),
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as B;
        let params = buffer(
            "probes.cull_params",
            records.len() as u64,
            B::UNIFORM | B::COPY_DST,
        );
        ctx.queue.write_buffer(&params, 0, &records);
        let cluster_buffer = buffer(
            "probes.clusters",
            std::mem::size_of_val(clusters.as_slice()) as u64,
            B::STORAGE | B::COPY_DST,
        );
        ctx.queue
            .write_buffer(&cluster_buffer, 0, bytemuck::cast_slice(&clusters));
        let capacity = self.rounds.iter().map(|(r, _)| r.commands()).max();
        let commands = buffer(
            "probes.commands",
            capacity.unwrap_or(1) * COMMAND_SIZE,
            B::STORAGE | B::INDIRECT | B::COPY_SRC,
        );
        let counter = buffer("probes.count", 4, B::STORAGE | B::INDIRECT | B::COPY_DST);
        let kept = buffer("probes.kept", 4, B::STORAGE | B::COPY_DST | B::COPY_SRC);
        let cull_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probes.cull_group"),
            layout: &self.cull_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &params,
                        offset: 0,
                        size: wgpu::BufferSize::new(std::mem::size_of::<FaceDrawParams>() as u64),
                    }),
                },
                whole_entry(1, &cluster_buffer),
                whole_entry(2, &gpu_scene.instances),
                whole_entry(3, &commands),
                whole_entry(4, &counter),
                whole_entry(5, &kept),
                whole_entry(6, views),
            ],
        });
        let pull_group =
            crate::frame::gbuffer_pull::bind_group(device, &self.pull_layout, gpu_scene, &params);
        self.made_from = Some((clusters, faces, buffers));
        self.bound = Some(Bound {
            commands,
            counter,
            kept,
            cull_group,
            pull_group,
        });
        Ok(())
    }

    /// Culls and draws every round of `gpu_scene`'s clusters into `atlas` (the first
    /// round's pass clears it; with no clusters one pass only clears), beginning the span
    /// `span`; passes recorded after it end the span.
    pub(crate) fn record_begin(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        gpu_scene: &GpuScene,
        atlas: &GBuffer,
        (timer, span): (&GpuTimer, Option<Span>),
    ) {
        let Some(b) = &self.bound else {
            debug_assert!(false, "prepare binds the clusters before they are drawn");
            return;
        };
        encoder.push_debug_group("probes.gpu_driven");
        encoder.clear_buffer(&b.kept, 0, None);
        if self.rounds.is_empty() {
            let writes = (timer, span, true, false);
            atlas.record_face_clusters(
                encoder,
                writes,
                true,
                (&b.pull_group, 0),
                (false, CameraCull::None),
                |_| {},
            );
        }
        for (k, &(r, key)) in self.rounds.iter().enumerate() {
            let offset = (k as u64 * FACE_DRAW_PARAMS_STRIDE) as u32;
            let first = k == 0;
            if self.compact {
                encoder.clear_buffer(&b.counter, 0, None);
            }
            // The cull rewrites the commands the last round's draws read.
            {
                let mut pass = self.fence.begin_compute_pass(
                    encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("probes.cull_faces"),
                        timestamp_writes: timer.compute_writes(span, first, false),
                    },
                );
                pass.set_pipeline(&self.cull);
                pass.set_bind_group(0, &b.cull_group, &[offset]);
                pass.dispatch_workgroups(r.clusters.div_ceil(64), r.views, 1);
            }
            let max = r.commands() as u32;
            let compact = self.compact;
            atlas.record_face_clusters(
                encoder,
                (timer, span, false, false),
                first,
                (&b.pull_group, offset),
                key,
                |pass| {
                    pass.set_index_buffer(gpu_scene.indices.slice(..), wgpu::IndexFormat::Uint32);
                    if compact {
                        pass.multi_draw_indexed_indirect_count(&b.commands, 0, &b.counter, 0, max);
                    } else {
                        pass.multi_draw_indexed_indirect(&b.commands, 0, max);
                    }
                },
            );
        }
        encoder.pop_debug_group();
    }
}

impl FaceClusters {
    /// Test only (feature `test-hooks`): caps the commands of one round below what the
    /// adapter allows (more rounds, faces split between them), from the next `prepare`.
    #[cfg(feature = "test-hooks")]
    pub(crate) fn cap_round_commands(&mut self, commands: u64) {
        self.max_round_commands = self.max_round_commands.min(commands.max(1));
        self.made_from = None;
    }

    /// Cull + draw rounds of the last `prepare`.
    pub(crate) fn rounds(&self) -> usize {
        self.rounds.len()
    }

    /// Of the last frame's rounds: the cluster-face pairs the cull kept, and those it was
    /// offered (a read-back, for tests).
    pub(crate) fn kept(&self, ctx: &GpuContext) -> Result<(u64, u64), RenderError> {
        let Some(b) = &self.bound else {
            return Ok((0, 0));
        };
        let bytes = crate::gpu::readback::read_buffer(ctx, &b.kept)?;
        let kept = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
        Ok((u64::from(kept), self.offered))
    }
}

/// `mesh`'s triangles in the scene's index order ([`morton_order`]) cut into clusters.
fn mesh_clusters(mesh: &manyshadows_scene::Mesh) -> Vec<MeshCluster> {
    let order = morton_order(mesh);
    order
        .chunks(3 * CLUSTER_TRIANGLES)
        .enumerate()
        .map(|(k, tri)| {
            let p = |i: u32| {
                mesh.positions
                    .get(i as usize)
                    .copied()
                    .unwrap_or(Vec3::ZERO)
            };
            let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            for &i in tri {
                lo = lo.min(p(i));
                hi = hi.max(p(i));
            }
            let centre = (lo + hi) * 0.5;
            let radius = tri
                .iter()
                .map(|&i| p(i).distance(centre))
                .fold(0.0f32, f32::max);
            let normals: Vec<Vec3> = tri
                .chunks_exact(3)
                .filter_map(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).try_normalize())
                .collect();
            MeshCluster {
                first_index: (k * 3 * CLUSTER_TRIANGLES) as u32,
                index_count: tri.len() as u32,
                // A little margin: the sphere must hold every vertex after rounding.
                sphere: [centre.x, centre.y, centre.z, radius * 1.0001 + 1e-6],
                cone: normal_cone(&normals),
            }
        })
        .collect()
}
