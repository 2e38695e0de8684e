//! `gpu-driven`: clusters culled per view in compute, drawn by one indirect multi-draw (seed
//! 002's route, the one meant to scale to thousands of views).
//!
//! After the per-frame caster transform (which also writes each cluster's world bounding sphere,
//! [`crate::gpu_scene::casters`]), a compute pass runs one thread per (cluster, listed view) (views
//! along the dispatch's y). A cluster survives a view unless its sphere is wholly outside the view
//! frustum (frustum culling on) or its normal cone proves that every triangle faces away from the
//! light from every point of the sphere (back-face culling on; only clusters of cullable
//! triangles). Survivors become indexed-indirect commands over the caster corner buffer.
//!
//! The view is not passed through `first_instance` (OpenGL's support for it is shaky): a
//! command for the view in batch slot `s` has `base_vertex = s · V` (V = caster vertices), so
//! the vertex shader sees `vertex_index = vertex + s · V` and recovers both. It then maps the
//! view's clip position into the tile exactly as `layered` does (`tile.wgsl`).
//!
//! With `MULTI_DRAW_INDIRECT_COUNT` the commands are compacted through an atomic counter and
//! drawn with `multi_draw_indexed_indirect_count`; without it (OpenGL) every (cluster, view)
//! slot gets a command, zero indices when culled, drawn by `multi_draw_indexed_indirect`.
//!
//! Views are processed in *rounds*: a round's slots must keep `s · V` below 2³¹ and its
//! command buffer (clusters × views × 20 bytes) within the storage-binding limit, so large
//! scenes with many views run several cull + draw rounds instead of truncating. Clusters are
//! split too if even one view's commands would not fit.

use manyshadows_scene::light_space::PointShadows;

use crate::error::Fills;
use crate::error::RenderError;
use crate::error::Technique;
use crate::gpu::context::GpuContext;
use crate::gpu::pipelines::{dynamic_uniform_entry, whole_entry};
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::shadows::atlas::shared::atlas_report;
use crate::shadows::atlas::shared::{atlas_attachment, CachedGroup, TileClear, UniformRecords};
use crate::shadows::cluster_draw::CLUSTER_CULL;
use crate::shadows::cluster_draw::{plan_rounds, Round, COMMAND_SIZE};
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::depth::{culled_depth_pipeline, depth_pipeline};
use crate::shadows::depth::{CULL, TILE, TILE_MASK};
use crate::shadows::descriptor::{Build, Culling, Need, TechniqueInfo, Wgsl};
use crate::shadows::lookup::ATLAS_LOOKUP;
use crate::shadows::source::ShadowStats;
use crate::shadows::technique::{Generation, ShadowTechnique};

impl Technique {
    /// Clusters culled per view in compute, one indirect multi-draw
    /// (seed 002).
    pub const GPU_DRIVEN: Technique = Technique::named("gpu-driven");
}

/// `gpu-driven`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::GPU_DRIVEN,
    summary: "compute culls triangle clusters per view and writes indirect draws; one \
              multi-draw fills every tile",
    origin: "seed 002 (GPU culling of shadow casters, multi-draw-indirect)",
    fills: Fills::Atlas,
    culling: Culling::Clusters,
    point_shadows: &[PointShadows::Cube],
    needs: &[
        Need::feature(
            wgpu::Features::CLIP_DISTANCES,
            "to keep each view inside its atlas tile",
        ),
        Need::indirect("indirect draws"),
    ],
    soft_shadows: true,
    // Milliseconds of its shadow stage per (triangle, view) pair taken on, (instance, view) pair,
    // texel of the tiles, texel of the whole atlas, view, and fixed, on lavapipe
    // (docs/benchmarks.md, "What a frame will cost: `bench estimate`").
    cost: Cost {
        lighting: LightingRead::Maps,
        shadows_ms: |w| {
            price(
                &[3.83e-06, 5.49e-03, 0.0, 9.67e-07, 0.0, 0.0],
                &w.atlas_units(),
            )
        },
    },
    camera_pixels_only: false,
    follows_camera: false,
    report: |r| atlas_report(r, Culling::Clusters),
    instead: "use technique layered",
    lookup: ATLAS_LOOKUP,
    build: Build::Atlas(|ctx| Ok(Box::new(GpuDriven::new(ctx)?))),
    shaders: || {
        vec![Wgsl::with(
            "gpu_driven",
            shader(),
            wgpu::Features::CLIP_DISTANCES,
        )]
    },
};

/// `GpuParams` of `gpu_driven.wgsl`, one per round.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct GpuParams {
    /// Caster vertices, cullable triangles, cull bits, clusters in this round.
    pub(crate) counts: [u32; 4],
    /// First draw-list entry of the round, views in it, first cluster, 1 = compact commands.
    pub(crate) round: [u32; 4],
    /// Atlas side in texels, its reciprocal, unused, unused.
    pub(crate) atlas: [f32; 4],
}

/// Bytes of one round's parameters (`GpuParams` in gpu_driven.wgsl).
const PARAMS_SIZE: u64 = std::mem::size_of::<GpuParams>() as u64;

/// Cluster culling (compute) and the draw (vertex, fragment for masks).
fn shader() -> String {
    compose(&[
        "enable clip_distances;",
        COMMON,
        CULL,
        TILE,
        CLUSTER_CULL,
        ALPHA_MASK,
        TILE_MASK,
        include_str!("gpu_driven.wgsl"),
    ])
}

/// The gpu-driven technique's pipelines and command buffers.
pub struct GpuDriven {
    cull: wgpu::ComputePipeline,
    draw: wgpu::RenderPipeline,
    /// Rounds of alpha-tested clusters (`fs_alpha`).
    draw_masked: wgpu::RenderPipeline,
    /// Rounds of cullable clusters whose triangles' facing decides what they cast (back
    /// faces culled by the rasterizer).
    draw_culled: wgpu::RenderPipeline,
    cull_layout: wgpu::BindGroupLayout,
    draw_layout: wgpu::BindGroupLayout,
    clear: TileClear,
    compact: bool,
    max_round_commands: u64,
    commands: Option<(wgpu::Buffer, u64)>,
    counter: wgpu::Buffer,
    /// One `GpuParams` per round, rewritten each generation.
    params: UniformRecords,
    cull_group: CachedGroup,
    draw_group: CachedGroup,
}

impl GpuDriven {
    /// Builds the pipelines; needs `CLIP_DISTANCES`. Uses the compacted count draw where the
    /// adapter has `MULTI_DRAW_INDIRECT_COUNT`.
    pub fn new(ctx: &GpuContext) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let module = crate::gpu::shaders::module(device, "gpu_driven.shader", &shader());
        let cs = wgpu::ShaderStages::COMPUTE;
        let cull_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "gpu_driven.cull_layout",
            &[
                dynamic_uniform_entry(0, cs, PARAMS_SIZE),
                crate::gpu::pipelines::storage_entry(1, cs),
                crate::gpu::pipelines::storage_entry(2, cs),
                crate::gpu::pipelines::storage_entry(3, cs),
                crate::gpu::pipelines::storage_entry(4, cs),
                crate::gpu::pipelines::storage_entry(5, cs),
                crate::gpu::pipelines::storage_entry(6, cs),
                crate::gpu::pipelines::storage_rw_entry(7, cs),
                crate::gpu::pipelines::storage_rw_entry(8, cs),
            ],
        );
        let vs = wgpu::ShaderStages::VERTEX;
        let draw_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "gpu_driven.draw_layout",
            &[
                dynamic_uniform_entry(0, vs, PARAMS_SIZE),
                crate::gpu::pipelines::storage_entry(1, vs),
                crate::gpu::pipelines::storage_entry(2, vs),
                crate::gpu::pipelines::storage_entry(9, vs),
                crate::gpu::pipelines::storage_entry(10, wgpu::ShaderStages::VERTEX_FRAGMENT),
            ],
        );
        let cull_pipeline_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "gpu_driven.cull_pipeline_layout",
            &[&cull_layout],
        );
        let draw_pipeline_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "gpu_driven.draw_pipeline_layout",
            &[&draw_layout],
        );
        let cull = crate::gpu::pipelines::compute_pipeline(
            device,
            "gpu_driven.cull",
            &cull_pipeline_layout,
            &module,
            "cs_cull",
        );
        let draw = depth_pipeline(device, &draw_pipeline_layout, &module, "vs_draw", &[]);
        let draw_culled = culled_depth_pipeline(
            device,
            &draw_pipeline_layout,
            &module,
            "vs_draw",
            &[],
            wgpu::FrontFace::Ccw,
        );
        let draw_masked = crate::shadows::depth::masked_depth_pipeline(
            device,
            &draw_pipeline_layout,
            &module,
            "vs_draw_masked",
            &[],
            None,
        );
        let counter = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("gpu_driven.count"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let limits = ctx.limits();
        let max_round_commands = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            / COMMAND_SIZE;
        Ok(Self {
            cull,
            draw,
            draw_masked,
            draw_culled,
            cull_layout,
            draw_layout,
            clear: TileClear::new(ctx),
            compact: ctx.has(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
            max_round_commands,
            commands: None,
            counter,
            params: UniformRecords::new(ctx, "gpu_driven.params", PARAMS_SIZE),
            cull_group: CachedGroup::default(),
            draw_group: CachedGroup::default(),
        })
    }

    /// Test only (feature `test-hooks`): caps the commands of one cull + draw round below
    /// what the adapter allows (smaller command buffers, more rounds), to exercise batching.
    #[cfg(feature = "test-hooks")]
    pub fn with_max_round_commands(mut self, commands: u64) -> Self {
        self.max_round_commands = self.max_round_commands.min(commands.max(1));
        self
    }

    /// The command buffer, holding at least `commands` commands.
    fn command_buffer(&mut self, ctx: &GpuContext, commands: u64) -> &wgpu::Buffer {
        if self.commands.as_ref().is_none_or(|(_, n)| *n < commands) {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gpu_driven.commands"),
                size: commands.max(1) * COMMAND_SIZE,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
                mapped_at_creation: false,
            });
            self.commands = Some((buffer, commands));
        }
        &self.commands.as_ref().expect("command buffer").0
    }
}

impl ShadowTechnique for GpuDriven {
    fn record(&mut self, g: Generation<'_>) -> ShadowStats {
        let input = g.input;
        let mut stats = ShadowStats::default();
        let views = input.draw_list.len() as u32;
        let ctx = input.ctx;
        let casters = input.casters;
        // Single-sided casters cast only where a light sees their front: a cluster kept by the
        // cull may still hold triangles facing away, which the rasterizer then culls.
        let culled = if casters.front_only {
            casters.cullable_clusters
        } else {
            0
        };
        let rounds = plan_rounds(
            views,
            casters.clusters.len() as u32,
            (culled, casters.first_masked_cluster),
            casters.vertices,
            self.max_round_commands,
        );
        let capacity = rounds.iter().map(Round::commands).max().unwrap_or(1);
        self.command_buffer(ctx, capacity);
        let commands = &self.commands.as_ref().expect("command buffer").0;

        let atlas = input.atlas.size as f32;
        let records: Vec<GpuParams> = rounds
            .iter()
            .map(|r| GpuParams {
                counts: [
                    casters.vertices,
                    casters.cullable_triangles,
                    input.options.cull.bits_for(casters),
                    r.clusters,
                ],
                round: [
                    r.first_view,
                    r.views,
                    r.first_cluster,
                    u32::from(self.compact),
                ],
                atlas: [atlas, 1.0 / atlas, 0.0, 0.0],
            })
            .collect();
        self.params.write(ctx, &records);
        let params = &self.params;
        let device = &ctx.device;
        let cull_buffers = [
            params.buffer(),
            &input.atlas.views_buffer,
            &input.atlas.draw_list,
            &input.atlas.eyes,
            &casters.cluster_buffer,
            &casters.cluster_bounds,
            &input.scene.instances,
            commands,
            &self.counter,
        ];
        let cull_layout = &self.cull_layout;
        let cull_group = self.cull_group.get(&cull_buffers, || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("gpu_driven.cull_group"),
                layout: cull_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.binding(),
                    },
                    whole_entry(1, &input.atlas.views_buffer),
                    whole_entry(2, &input.atlas.draw_list),
                    whole_entry(3, &input.atlas.eyes),
                    whole_entry(4, &casters.cluster_buffer),
                    whole_entry(5, &casters.cluster_bounds),
                    whole_entry(6, &input.scene.instances),
                    whole_entry(7, commands),
                    whole_entry(8, &self.counter),
                ],
            })
        });
        let draw_buffers = [
            params.buffer(),
            &input.atlas.views_buffer,
            &input.atlas.draw_list,
            &casters.world,
            &casters.corners,
        ];
        let draw_layout = &self.draw_layout;
        let draw_group = self.draw_group.get(&draw_buffers, || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("gpu_driven.draw_group"),
                layout: draw_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.binding(),
                    },
                    whole_entry(1, &input.atlas.views_buffer),
                    whole_entry(2, &input.atlas.draw_list),
                    whole_entry(9, &casters.world),
                    whole_entry(10, &casters.corners),
                ],
            })
        });

        g.encoder.push_debug_group("gpu-driven");
        if rounds.is_empty() {
            // No casters: the transform (a no-op) and a pass that clears the listed tiles.
            {
                let mut pass = g.input.ctx.raster_fence().begin_compute_pass(
                    g.encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("gpu_driven.transform"),
                        timestamp_writes: g.timer.compute_writes(g.span, true, false),
                    },
                );
                let s = g.timer.begin_compute_stats(&mut pass);
                casters.record(&mut pass, true);
                g.timer.end_compute_stats(&mut pass, s);
            }
            let mut pass = g.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gpu_driven.draw"),
                color_attachments: &[],
                depth_stencil_attachment: Some(atlas_attachment(input, input.full())),
                timestamp_writes: g.timer.render_writes(g.span, false, true),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let s = g.timer.begin_render_stats(&mut pass);
            self.clear.record(ctx, input, &mut pass);
            g.timer.end_render_stats(&mut pass, s);
            drop(pass);
            g.encoder.pop_debug_group();
            stats.passes += 2;
            return stats;
        }
        let corners = casters.corners.slice(..);
        for (k, r) in rounds.iter().enumerate() {
            let offset = [params.offset(k)];
            let first = k == 0;
            let last = k + 1 == rounds.len();
            if self.compact {
                g.encoder.clear_buffer(&self.counter, 0, None);
            }
            {
                let mut pass = g.input.ctx.raster_fence().begin_compute_pass(
                    g.encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("gpu_driven.cull"),
                        timestamp_writes: g.timer.compute_writes(g.span, first, false),
                    },
                );
                let s = g.timer.begin_compute_stats(&mut pass);
                if first {
                    // The per-frame transform and cluster spheres, once for every round.
                    casters.record(&mut pass, true);
                }
                pass.set_pipeline(&self.cull);
                pass.set_bind_group(0, cull_group, &offset);
                pass.dispatch_workgroups(r.clusters.div_ceil(64), r.views, 1);
                g.timer.end_compute_stats(&mut pass, s);
                stats.passes += 1;
            }
            let mut pass = g.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gpu_driven.draw"),
                color_attachments: &[],
                depth_stencil_attachment: Some(atlas_attachment(input, first && input.full())),
                timestamp_writes: g.timer.render_writes(g.span, false, last),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let s = g.timer.begin_render_stats(&mut pass);
            if first {
                self.clear.record(ctx, input, &mut pass);
            }
            if input.options.discard_raster {
                pass.set_scissor_rect(0, 0, 0, 0);
            }
            pass.set_pipeline(if r.masked {
                &self.draw_masked
            } else if r.culled {
                &self.draw_culled
            } else {
                &self.draw
            });
            pass.set_bind_group(0, draw_group, &offset);
            pass.set_index_buffer(corners, wgpu::IndexFormat::Uint32);
            let max = r.commands() as u32;
            if self.compact {
                pass.multi_draw_indexed_indirect_count(commands, 0, &self.counter, 0, max);
            } else {
                pass.multi_draw_indexed_indirect(commands, 0, max);
            }
            self.clear.reset_clip_distances(&mut pass);
            g.timer.end_render_stats(&mut pass, s);
            stats.passes += 1;
            stats.draws += r.commands();
        }
        g.encoder.pop_debug_group();
        // Triangles offered to culling (what a draw without culling would submit); how many
        // survive is known only on the GPU.
        stats.triangles += casters.triangles as u64 * views as u64;
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::types::layout::same_layout;

    #[test]
    fn params_match_the_wgsl() {
        same_layout!(in shader(), GpuParams, counts, round, atlas);
    }
}
