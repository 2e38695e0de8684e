//! Rendering the pages the allocation made resident (step 3 of [`crate::shadows::vsm`]): each
//! drawn page is an ordinary shadow view, the face's projection cropped to the page, filled
//! the `gpu-driven` way. Per round ([`crate::shadows::cluster_draw`]) compute culls caster
//! clusters against each page's frustum slice (and by normal cone) and one indirect multi-draw
//! draws the survivors, clipped to the page's tile of the pool (`vsm_draw.wgsl`). The cull is
//! hierarchical: groups of `CULL_GROUP` consecutive clusters have a merged bounding sphere
//! (written with the clusters' by [`CasterGeometry::record`]), one thread per (group, page)
//! tests it and only then the group's clusters. The
//! page clears and the indirect arguments come from the allocation passes ([`super::alloc`]).

use crate::gpu::buffers::buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::pipelines::whole_entry;
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::caster_layout::{CLUSTER_PARTS, CLUSTER_TRIANGLES};
use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::shadows::cluster_draw::CLUSTER_CULL;
use crate::shadows::cluster_draw::{plan_rounds, Round, COMMAND_SIZE};
use crate::shadows::depth::{CULL, TILE, TILE_MASK};
use crate::shadows::options::ShadowOptions;
use crate::shadows::vsm::types::VsmRound;
use crate::shadows::vsm::types::VSM_TYPES;

/// Consecutive clusters per cull group (one cull thread per group and page).
pub(crate) const CULL_GROUP: u32 = crate::gpu_scene::caster_layout::CLUSTER_GROUP;

/// Flag in the rounds' cull bits: skip the groups' spheres (the flat cull, for measuring).
const FLAT_CULL: u32 = 1 << 8;

/// `VSM_CULL_GROUP` (and the flat-cull flag) for the shaders that dispatch or run the cull.
pub(crate) fn group_decl() -> String {
    format!(
        "const VSM_CULL_GROUP: u32 = {CULL_GROUP}u;\nconst VSM_FLAT_CULL: u32 = {FLAT_CULL}u;\n\
         const VSM_CLUSTER_TRIANGLES: u32 = {CLUSTER_TRIANGLES}u;\nconst VSM_PARTS: u32 = {CLUSTER_PARTS}u;\n\
         const VSM_PART_TRIANGLES: u32 = {}u;",
        CLUSTER_TRIANGLES / CLUSTER_PARTS
    )
}

/// Cull threads' groups along x for a round's clusters `[first, first + count)`.
fn round_groups(first: u32, count: u32) -> u32 {
    (first + count).div_ceil(CULL_GROUP) - first / CULL_GROUP
}

/// Page culling, drawing and clearing.
pub(crate) fn shader() -> String {
    compose(&[
        "enable clip_distances;",
        &group_decl(),
        COMMON,
        VSM_TYPES,
        CULL,
        TILE,
        CLUSTER_CULL,
        ALPHA_MASK,
        TILE_MASK,
        include_str!("vsm_draw.wgsl"),
    ])
}

/// Largest command buffer of one page-render round.
const MAX_ROUND_BYTES: u64 = 64 << 20;

const ROUND_SIZE: u64 = std::mem::size_of::<VsmRound>() as u64;

/// The page tables' buffers the page rendering reads (owned by [`super::pages`]).
pub(crate) struct PageBuffers<'a> {
    /// `VsmUniforms`.
    pub uniforms: &'a wgpu::Buffer,
    /// The shadow view of every pool page drawn this frame.
    pub page_views: &'a wgpu::Buffer,
    /// `array<VirtualFace>`.
    pub faces: &'a wgpu::Buffer,
    /// The frame's counters.
    pub counters: &'a wgpu::Buffer,
    /// World-space caster geometry.
    pub casters: &'a CasterGeometry,
    /// Scene instances (`array<InstanceData>`).
    pub instances: &'a wgpu::Buffer,
}

/// The page-render rounds, their command buffers and pipelines.
pub(crate) struct PageDraw {
    fence: crate::gpu::raster_fence::RasterFence,
    shadow: ShadowOptions,
    compact: bool,
    rounds: Vec<Round>,
    rounds_storage: wgpu::Buffer,
    round_uniforms: wgpu::Buffer,
    round_stride: u64,
    commands: wgpu::Buffer,
    command_count: wgpu::Buffer,
    /// Commands per round (with compaction, the pairs drawn whole start there).
    capacity: u64,
    /// With compaction: each round's triangles that touch their page (`cs_expand`).
    expanded: wgpu::Buffer,
    /// The expansion's dispatch and the round's indexed draw.
    round_args: wgpu::Buffer,
    expand: wgpu::ComputePipeline,
    expand_args: wgpu::ComputePipeline,
    draw_args: wgpu::ComputePipeline,
    expand_layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    cull: wgpu::ComputePipeline,
    draw: wgpu::RenderPipeline,
    /// Rounds of alpha-tested clusters (`fs_alpha`).
    draw_masked: wgpu::RenderPipeline,
    /// Rounds of cullable clusters whose triangles' facing decides what they cast (back
    /// faces culled by the rasterizer: a cluster the cull keeps may still hold some).
    draw_culled: wgpu::RenderPipeline,
    clear: wgpu::RenderPipeline,
    cull_layout: wgpu::BindGroupLayout,
    draw_layout: wgpu::BindGroupLayout,
    clear_layout: wgpu::BindGroupLayout,
    groups: Option<Groups>,
    /// The caster layout the rounds were planned for ([`Self::made_for`]).
    layout: [u32; 5],
}

/// What the rounds' records take from the caster layout.
fn caster_layout(casters: &CasterGeometry) -> [u32; 5] {
    [
        casters.clusters.len() as u32,
        casters.first_masked_cluster,
        casters.vertices,
        casters.cullable_triangles,
        culled_clusters(casters),
    ]
}

/// The clusters drawn culled by facing: the cullable ones where single-sided casters cast only
/// where a light sees their front (none otherwise).
fn culled_clusters(casters: &CasterGeometry) -> u32 {
    if casters.front_only {
        casters.cullable_clusters
    } else {
        0
    }
}

struct Groups {
    cull: wgpu::BindGroup,
    expand: wgpu::BindGroup,
    args: wgpu::BindGroup,
    draw: wgpu::BindGroup,
    clear: wgpu::BindGroup,
}

impl PageDraw {
    /// Plans the rounds over every page of a pool of `pool_pages` and builds their buffers and
    /// pipelines. Compacts the commands where `MULTI_DRAW_INDIRECT_COUNT` exists; culls by
    /// cluster groups first unless `group_cull` is false.
    pub fn new(
        ctx: &GpuContext,
        pool_pages: u32,
        casters: &CasterGeometry,
        shadow: ShadowOptions,
        group_cull: bool,
        expand_bytes: u64,
    ) -> Self {
        let device = &ctx.device;
        let limits = ctx.limits();
        let compact = ctx.has(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT);
        // With compaction the command buffer holds the pairs, then the pairs drawn whole.
        let max_commands = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            .min(MAX_ROUND_BYTES)
            / COMMAND_SIZE
            / if compact { 2 } else { 1 };
        let rounds = plan_rounds(
            pool_pages,
            casters.clusters.len() as u32,
            (culled_clusters(casters), casters.first_masked_cluster),
            casters.vertices,
            max_commands,
        );
        let round_stride = (std::mem::size_of::<VsmRound>() as u64)
            .next_multiple_of(limits.min_uniform_buffer_offset_alignment as u64);
        let capacity = rounds.iter().map(Round::commands).max().unwrap_or(1);
        use wgpu::BufferUsages as U;
        let storage = U::STORAGE | U::COPY_DST;
        let rounds_storage = buffer(
            ctx,
            "vsm.rounds",
            rounds.len().max(1) as u64 * std::mem::size_of::<VsmRound>() as u64,
            storage,
        );
        let round_uniforms = buffer(
            ctx,
            "vsm.round_uniforms",
            rounds.len().max(1) as u64 * round_stride,
            U::UNIFORM | U::COPY_DST,
        );
        let commands = buffer(
            ctx,
            "vsm.commands",
            capacity * COMMAND_SIZE * if compact { 2 } else { 1 },
            U::STORAGE | U::INDIRECT,
        );
        let command_count = buffer(ctx, "vsm.command_count", 16, storage | U::INDIRECT);
        let expanded = buffer(
            ctx,
            "vsm.expanded",
            if compact {
                // Whole triangles (three u32 corners each).
                let bytes = expand_bytes
                    .min(limits.max_buffer_size)
                    .min(limits.max_storage_buffer_binding_size);
                (bytes / 12).max(1) * 12
            } else {
                4
            },
            U::STORAGE | U::INDEX,
        );
        let round_args = buffer(ctx, "vsm.round_args", 36, U::STORAGE | U::INDIRECT);
        // Round records (the same for every frame: rounds cover every pool page).
        let records: Vec<VsmRound> = rounds
            .iter()
            .map(|r| VsmRound {
                round: [r.first_view, r.views, r.first_cluster, r.clusters],
                counts: [
                    casters.vertices,
                    casters.cullable_triangles,
                    shadow.cull.bits_for(casters) | if group_cull { 0 } else { FLAT_CULL },
                    if compact { capacity as u32 } else { 0 },
                ],
            })
            .collect();
        if !records.is_empty() {
            ctx.queue
                .write_buffer(&rounds_storage, 0, bytemuck::cast_slice(&records));
            let mut bytes = vec![0u8; (records.len() as u64 * round_stride) as usize];
            for (k, r) in records.iter().enumerate() {
                let at = k * round_stride as usize;
                bytes[at..at + std::mem::size_of::<VsmRound>()]
                    .copy_from_slice(bytemuck::bytes_of(r));
            }
            ctx.queue.write_buffer(&round_uniforms, 0, &bytes);
        }

        let cs = wgpu::ShaderStages::COMPUTE;
        let cull_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.cull_layout",
            &[
                crate::gpu::pipelines::dynamic_uniform_entry(0, cs, ROUND_SIZE),
                crate::gpu::pipelines::uniform_entry(1, cs),
                crate::gpu::pipelines::storage_entry(2, cs),
                crate::gpu::pipelines::storage_entry(4, cs),
                crate::gpu::pipelines::storage_entry(5, cs),
                crate::gpu::pipelines::storage_entry(6, cs),
                crate::gpu::pipelines::storage_entry(7, cs),
                crate::gpu::pipelines::storage_rw_entry(8, cs),
                crate::gpu::pipelines::storage_rw_entry(9, cs),
                crate::gpu::pipelines::storage_rw_entry(10, cs),
            ],
        );
        let expand_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.expand_layout",
            &[
                crate::gpu::pipelines::dynamic_uniform_entry(0, cs, ROUND_SIZE),
                crate::gpu::pipelines::uniform_entry(1, cs),
                crate::gpu::pipelines::storage_entry(2, cs),
                crate::gpu::pipelines::storage_entry(4, cs),
                crate::gpu::pipelines::storage_rw_entry(8, cs),
                crate::gpu::pipelines::storage_rw_entry(9, cs),
                crate::gpu::pipelines::storage_rw_entry(10, cs),
                crate::gpu::pipelines::storage_entry(11, cs),
                crate::gpu::pipelines::storage_entry(13, cs),
                crate::gpu::pipelines::storage_rw_entry(15, cs),
            ],
        );
        let args_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.round_args_layout",
            &[
                crate::gpu::pipelines::storage_rw_entry(10, cs),
                crate::gpu::pipelines::storage_rw_entry(15, cs),
                crate::gpu::pipelines::storage_rw_entry(16, cs),
                crate::gpu::pipelines::storage_entry(17, cs),
            ],
        );
        let vs = wgpu::ShaderStages::VERTEX;
        let draw_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.draw_layout",
            &[
                crate::gpu::pipelines::dynamic_uniform_entry(0, vs, ROUND_SIZE),
                crate::gpu::pipelines::uniform_entry(1, vs),
                crate::gpu::pipelines::storage_entry(2, vs),
                crate::gpu::pipelines::storage_entry(11, vs),
                crate::gpu::pipelines::storage_entry(13, wgpu::ShaderStages::VERTEX_FRAGMENT),
            ],
        );
        let clear_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.clear_layout",
            &[
                crate::gpu::pipelines::uniform_entry(1, vs),
                crate::gpu::pipelines::storage_entry(2, vs),
            ],
        );
        let pipeline_layout = |label: &str, layout: &wgpu::BindGroupLayout| {
            crate::gpu::pipelines::pipeline_layout(device, label, &[layout])
        };
        let draw_module = crate::gpu::shaders::module(device, "vsm_draw.shader", &shader());
        let compute = |label: &str, pl: &wgpu::PipelineLayout, entry: &str| {
            crate::gpu::pipelines::compute_pipeline(device, label, pl, &draw_module, entry)
        };
        let cull_pl = pipeline_layout("vsm.cull_pipeline_layout", &cull_layout);
        let cull = compute("vsm.cull", &cull_pl, "cs_cull");
        let expand_pl = pipeline_layout("vsm.expand_pipeline_layout", &expand_layout);
        let expand = compute("vsm.expand", &expand_pl, "cs_expand");
        let args_pl = pipeline_layout("vsm.round_args_pipeline_layout", &args_layout);
        let expand_args = compute("vsm.expand_args", &args_pl, "cs_expand_args");
        let draw_args = compute("vsm.draw_args", &args_pl, "cs_draw_args");
        let draw_pl = pipeline_layout("vsm.draw_pipeline_layout", &draw_layout);
        let draw =
            crate::shadows::depth::depth_pipeline(device, &draw_pl, &draw_module, "vs_draw", &[]);
        let draw_masked = crate::shadows::depth::masked_depth_pipeline(
            device,
            &draw_pl,
            &draw_module,
            "vs_draw_masked",
            &[],
            None,
        );
        let draw_culled = crate::shadows::depth::culled_depth_pipeline(
            device,
            &draw_pl,
            &draw_module,
            "vs_draw",
            &[],
            wgpu::FrontFace::Ccw,
        );
        let clear_pl = pipeline_layout("vsm.clear_pipeline_layout", &clear_layout);
        let clear =
            crate::shadows::depth::clear_pipeline(device, &clear_pl, &draw_module, "vs_clear");
        Self {
            fence: ctx.raster_fence().clone(),
            shadow,
            compact,
            rounds,
            rounds_storage,
            round_uniforms,
            round_stride,
            commands,
            command_count,
            capacity,
            expanded,
            round_args,
            expand,
            expand_args,
            draw_args,
            expand_layout,
            args_layout,
            cull,
            draw,
            draw_masked,
            draw_culled,
            clear,
            cull_layout,
            draw_layout,
            clear_layout,
            groups: None,
            layout: caster_layout(casters),
        }
    }

    /// Whether the rounds were planned for `casters`' layout (a caster moving over a light
    /// changes which triangles may be back-face culled, and the rounds record that).
    pub fn made_for(&self, casters: &CasterGeometry) -> bool {
        self.layout == caster_layout(casters)
    }

    /// The rounds (every frame the same: they cover every pool page).
    pub fn rounds(&self) -> &[Round] {
        &self.rounds
    }

    /// `array<VsmRound>`, which the allocation's argument pass reads.
    pub fn rounds_storage(&self) -> &wgpu::Buffer {
        &self.rounds_storage
    }

    /// Builds the bind groups for `pages` (with the allocation's, whenever a buffer they hold
    /// was replaced).
    pub fn bind(&mut self, ctx: &GpuContext, pages: &PageBuffers<'_>) {
        let device = &ctx.device;
        let round = |binding: u32| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &self.round_uniforms,
                offset: 0,
                size: wgpu::BufferSize::new(std::mem::size_of::<VsmRound>() as u64),
            }),
        };
        let casters = pages.casters;
        let cull = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.cull_group"),
            layout: &self.cull_layout,
            entries: &[
                round(0),
                whole_entry(1, pages.uniforms),
                whole_entry(2, pages.page_views),
                whole_entry(4, pages.faces),
                whole_entry(5, &casters.cluster_buffer),
                whole_entry(6, &casters.cluster_bounds),
                whole_entry(7, pages.instances),
                whole_entry(8, &self.commands),
                whole_entry(9, &self.command_count),
                whole_entry(10, pages.counters),
            ],
        });
        let expand = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.expand_group"),
            layout: &self.expand_layout,
            entries: &[
                round(0),
                whole_entry(1, pages.uniforms),
                whole_entry(2, pages.page_views),
                whole_entry(4, pages.faces),
                whole_entry(8, &self.commands),
                whole_entry(9, &self.command_count),
                whole_entry(10, pages.counters),
                whole_entry(11, &casters.world),
                whole_entry(13, &casters.corners),
                whole_entry(15, &self.expanded),
            ],
        });
        let args = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.round_args_group"),
            layout: &self.args_layout,
            entries: &[
                whole_entry(10, pages.counters),
                whole_entry(15, &self.expanded),
                whole_entry(16, &self.round_args),
                whole_entry(17, &self.command_count),
            ],
        });
        let draw = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.draw_group"),
            layout: &self.draw_layout,
            entries: &[
                round(0),
                whole_entry(1, pages.uniforms),
                whole_entry(2, pages.page_views),
                whole_entry(11, &casters.world),
                whole_entry(13, &casters.corners),
            ],
        });
        let clear = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.clear_group"),
            layout: &self.clear_layout,
            entries: &[
                whole_entry(1, pages.uniforms),
                whole_entry(2, pages.page_views),
            ],
        });
        self.groups = Some(Groups {
            cull,
            expand,
            args,
            draw,
            clear,
        });
    }

    /// Records the page clear and the render rounds into `pool` (`span` times them), with the
    /// indirect arguments the allocation wrote into `args`.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        casters: &CasterGeometry,
        timer: &GpuTimer,
        span: Option<Span>,
        args: &wgpu::Buffer,
        pool: &wgpu::TextureView,
    ) {
        let Some(g) = &self.groups else {
            return;
        };
        let clear_args = 3 * self.rounds.len() as u64 * 4;
        if self.rounds.is_empty() {
            // No casters: the drawn pages are cleared and stay empty.
            let mut pass = pool_pass(encoder, pool, timer.render_writes(span, true, true));
            pass.set_pipeline(&self.clear);
            pass.set_bind_group(0, &g.clear, &[]);
            pass.draw_indirect(args, clear_args);
        }
        let corners = casters.corners.slice(..);
        for (k, r) in self.rounds.iter().enumerate() {
            let offset = [(k as u64 * self.round_stride) as u32];
            let first = k == 0;
            let last = k + 1 == self.rounds.len();
            if self.compact {
                encoder.clear_buffer(&self.command_count, 0, None);
            }
            // The cull rewrites the commands the last round's draws read.
            {
                let mut pass = self.fence.begin_compute_pass(
                    encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("vsm.cull"),
                        timestamp_writes: timer.compute_writes(span, first, false),
                    },
                );
                pass.set_pipeline(&self.cull);
                pass.set_bind_group(0, &g.cull, &offset);
                if self.compact {
                    pass.dispatch_workgroups_indirect(args, 3 * k as u64 * 4);
                    // The pairs' triangles, then the round's draw arguments.
                    pass.set_bind_group(0, &g.args, &[]);
                    pass.set_pipeline(&self.expand_args);
                    pass.dispatch_workgroups(1, 1, 1);
                    pass.set_bind_group(0, &g.expand, &offset);
                    pass.set_pipeline(&self.expand);
                    pass.dispatch_workgroups_indirect(&self.round_args, 0);
                    pass.set_bind_group(0, &g.args, &[]);
                    pass.set_pipeline(&self.draw_args);
                    pass.dispatch_workgroups(1, 1, 1);
                } else {
                    // Every slot's command is written (zero for slots past the last page).
                    let groups = round_groups(r.first_cluster, r.clusters);
                    pass.dispatch_workgroups(groups.div_ceil(64), r.views, 1);
                }
            }
            let mut pass = pool_pass(encoder, pool, timer.render_writes(span, false, last));
            if k == 0 {
                pass.set_pipeline(&self.clear);
                pass.set_bind_group(0, &g.clear, &[]);
                pass.draw_indirect(args, clear_args);
            }
            if self.shadow.discard_raster {
                pass.set_scissor_rect(0, 0, 0, 0);
            }
            pass.set_pipeline(if r.masked {
                &self.draw_masked
            } else if r.culled {
                &self.draw_culled
            } else {
                &self.draw
            });
            pass.set_bind_group(0, &g.draw, &offset);
            pass.set_index_buffer(corners, wgpu::IndexFormat::Uint32);
            let max = r.commands() as u32;
            if self.compact {
                pass.set_index_buffer(self.expanded.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed_indirect(&self.round_args, 12);
                pass.set_index_buffer(corners, wgpu::IndexFormat::Uint32);
                pass.multi_draw_indexed_indirect_count(
                    &self.commands,
                    self.capacity * COMMAND_SIZE,
                    &self.round_args,
                    32,
                    max,
                );
            } else {
                pass.multi_draw_indexed_indirect(&self.commands, 0, max);
            }
            // See TileClear::reset_clip_distances: the OpenGL backend leaks clip-distance
            // enables past the pass unless a pipeline without them is set last.
            pass.set_pipeline(&self.clear);
        }
    }
}

/// A render pass into the page pool, keeping its depth.
fn pool_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    pool: &wgpu::TextureView,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("vsm.draw"),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: pool,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
