//! `compute`: a software rasterizer in compute shaders fills every listed view's tile, without
//! the fixed-function pipeline (UE5 Nanite's idea for dense geometry, and a way round GPUs on
//! which few units run graphics work: docs/techniques.md, "A compute rasterizer:
//! `--technique compute`").
//!
//! Per generation ([`compute.wgsl`](compute.wgsl)): the caster transform writes world positions
//! once; then per *round* (below) a storage buffer of one `u32` per texel of the round's tiles
//! is filled with zeros (= far); one thread per (triangle, view) culls (frustum, back-face,
//! zero area, zero coverage), clips against the near plane, applies the viewport transform and
//! snaps to 1/256 texel; a small triangle (≤ [`SMALL_AREA`] texels of bounding box) is
//! rasterized by that thread with exact integer edge functions, a large one is appended as
//! chunks of 32² texels that one 8×8 workgroup each rasterizes (an indirect dispatch). Depth is
//! written as `atomicMax(1.0's bits − depth's bits)`: `atomicMin` on the float's bits (depths in
//! [0, 1] order like their bits) turned around so that far is 0 and a zero fill clears the
//! buffer (far cheaper than a clear shader on a software driver: docs/decisions.md, "Compute
//! rasterizer: a zero fill and a chunk list 16 times the texels").
//! A render pass finally copies the buffer into the atlas tiles with `frag_depth` (GL can
//! neither copy into depth textures nor store to them from compute).
//!
//! **Same depth as the hardware**: the fixed-function viewport transform in the same order, 8
//! sub-pixel bits, texel centres at +0.5, the top-left fill rule, depth from the triangle's
//! clip-space plane (z/w is affine in screen space; the plane from the clip coordinates stays
//! accurate where corners lie far outside the tile or were clipped), near clipping in clip
//! space, far clipping per texel. Large triangles use f32 edge functions evaluated from the
//! edge's lexicographically first end so neighbours agree exactly (no cracks).
//!
//! **No silent drops**: the chunk list is sized from the round's texels (every texel covered by
//! large triangles 16 times over); when it is full anyway, the setup thread rasterizes the
//! chunk itself (correct, slower) and counts it ([`Compute::overflowed`] reads the count).
//!
//! **Memory**: the depth buffer covers only the drawn tiles (an offset per *entry*). When they
//! exceed the adapter's storage-binding limit, the draw list is split into rounds, each cleared,
//! rasterized and copied in turn; a single tile over the limit is split into bands of rows.

use manyshadows_scene::light_space::PointShadows;

use crate::error::Fills;
use crate::error::RenderError;
use crate::error::Technique;
use crate::gpu::context::GpuContext;
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::shadows::atlas::shared::atlas_report;
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::depth::CULL;
use crate::shadows::descriptor::{Build, Culling, TechniqueInfo, Wgsl};
use crate::shadows::lookup::ATLAS_LOOKUP;
use crate::shadows::source::ShadowStats;
use crate::shadows::technique::{Generation, ShadowTechnique};

impl Technique {
    /// A rasterizer in compute shaders (beyond the seeds).
    pub const COMPUTE: Technique = Technique::named("compute");
}

/// `compute`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::COMPUTE,
    summary: "compute-shader rasterizer: per-view culling, clipping and binning in compute, \
              depth by atomicMin into a buffer, then copied into the tiles",
    origin: "beyond the seeds: a software rasterizer as in UE5's Nanite",
    fills: Fills::Atlas,
    culling: Culling::Threads,
    point_shadows: &[PointShadows::Cube],
    needs: &[],
    soft_shadows: true,
    // Milliseconds of its shadow stage per (triangle, view) pair taken on, (instance, view) pair,
    // texel of the tiles, texel of the whole atlas, view, and fixed, on lavapipe
    // (docs/benchmarks.md, "What a frame will cost: `bench estimate`").
    cost: Cost {
        lighting: LightingRead::Maps,
        shadows_ms: |w| {
            price(
                &[1.59e-05, 4.45e-02, 2.90e-06, 4.98e-06, 0.0, 0.0],
                &w.atlas_units(),
            )
        },
    },
    camera_pixels_only: false,
    follows_camera: false,
    report: |r| atlas_report(r, Culling::Threads),
    instead: "",
    lookup: ATLAS_LOOKUP,
    build: Build::Atlas(|ctx| Ok(Box::new(Compute::new(ctx)?))),
    shaders: || {
        vec![
            Wgsl::core("compute", shader()),
            Wgsl::core("compute_copy", copy_shader()),
        ]
    },
};

/// `ComputeParams` of `compute.wgsl`, one per round.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ComputeParams {
    /// Triangles, cullable triangles, cull bits, entries in this round.
    pub(crate) counts: [u32; 4],
    /// Texels in this round, chunk capacity, most workgroups along x, flags (1 = discard).
    pub(crate) sizes: [u32; 4],
}

/// Clear, setup and large-triangle rasterization.
fn shader() -> String {
    compose(&[COMMON, CULL, ALPHA_MASK, include_str!("compute.wgsl")])
}

/// The copy of the depth buffer into the atlas tiles.
fn copy_shader() -> String {
    compose(&[COMMON, include_str!("compute_copy.wgsl")])
}

/// Most bounding-box texels a setup thread rasterizes itself (must match compute.wgsl).
#[cfg_attr(not(feature = "internals"), allow(dead_code))] // benchmarks and tests
pub const SMALL_AREA: u32 = 512;
/// Bytes of one chunk record (`Chunk` in compute.wgsl).
const CHUNK_BYTES: u64 = 64;
/// Largest workgroup count per dispatch dimension WebGPU guarantees.
const MAX_GROUPS: u32 = 65535;
/// Most bytes the depth buffer of one round may take, whatever the adapter allows.
const MAX_DEPTH_BYTES: u64 = 256 << 20;
/// Most entries in one round: they are read from a 64 KiB uniform (compute.wgsl), which keeps
/// the pass within WebGPU's 8 storage buffers per shader stage.
pub const MAX_ROUND_ENTRIES: u64 = 4096;
/// Initial and largest chunk-list capacity.
const MIN_CHUNKS: u32 = 1 << 16;
const MAX_CHUNKS: u32 = 1 << 21;

/// One round entry: a band of rows of one view's tile and where it sits in the depth buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Entry {
    /// The view.
    pub view: u32,
    /// First texel of the band in the depth buffer.
    pub base: u32,
    /// First row of the tile in the band.
    pub row: u32,
    /// Rows in the band.
    pub rows: u32,
}

/// Splits the draw list into rounds whose depth buffer holds at most `max_texels` texels and
/// whose setup dispatch has at most `max_threads` threads (`triangles` per entry). A tile
/// larger than `max_texels` becomes bands of rows.
pub fn plan_rounds(
    draw_list: &[u32],
    tile_size: impl Fn(u32) -> u32,
    triangles: u32,
    max_texels: u64,
    max_threads: u64,
) -> Vec<Vec<Entry>> {
    let max_entries = (max_threads / triangles.max(1) as u64).clamp(1, MAX_ROUND_ENTRIES);
    let mut rounds: Vec<Vec<Entry>> = Vec::new();
    let mut current: Vec<Entry> = Vec::new();
    let mut texels = 0u64;
    for &view in draw_list {
        let size = tile_size(view) as u64;
        let rows_per_band = (max_texels / size).clamp(1, size);
        let mut row = 0u64;
        while row < size {
            let rows = rows_per_band.min(size - row);
            let need = rows * size;
            if !current.is_empty()
                && (texels + need > max_texels || current.len() as u64 >= max_entries)
            {
                rounds.push(std::mem::take(&mut current));
                texels = 0;
            }
            current.push(Entry {
                view,
                base: texels as u32,
                row: row as u32,
                rows: rows as u32,
            });
            texels += need;
            row += rows;
        }
    }
    if !current.is_empty() {
        rounds.push(current);
    }
    rounds
}

fn texels(round: &[Entry], tile_size: impl Fn(u32) -> u32) -> u64 {
    round
        .iter()
        .map(|e| e.rows as u64 * tile_size(e.view) as u64)
        .sum()
}

/// The compute rasterizer's pipelines and buffers.
pub struct Compute {
    setup: wgpu::ComputePipeline,
    /// `cs_setup` and `cs_large` compiled with `ALPHA_TESTED`: the alpha-tested triangles.
    setup_masked: wgpu::ComputePipeline,
    finalize: wgpu::ComputePipeline,
    large: wgpu::ComputePipeline,
    large_masked: wgpu::ComputePipeline,
    copy: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    copy_layout: wgpu::BindGroupLayout,
    depth: Option<(wgpu::Buffer, u64)>,
    chunks: Option<(wgpu::Buffer, u32)>,
    counters: wgpu::Buffer,
    counters_read: wgpu::Buffer,
    args: wgpu::Buffer,
    args_bind_group: wgpu::BindGroup,
    max_texels: u64,
    max_groups: u32,
    chunk_capacity: Option<u32>,
    pending_read: bool,
    /// `[atlas side, 0, 0, 0]` for the copy pass, written each frame.
    copy_params: wgpu::Buffer,
    /// One slot per round, kept across frames and rewritten with `write_buffer`.
    slots: Vec<RoundSlot>,
    /// The buffers the slots' bind groups were made with; a replaced one rebuilds them.
    bound: Vec<wgpu::Buffer>,
}

/// A round's uniforms and bind groups, made once: each round of a frame has its own, so the
/// frame's writes never overwrite what an earlier round of the same submission reads.
struct RoundSlot {
    params: wgpu::Buffer,
    entries: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
    copy_bind_group: Option<wgpu::BindGroup>,
}

impl Compute {
    /// Builds the pipelines (core WebGPU only: compute, storage buffers, atomics).
    pub fn new(ctx: &GpuContext) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let limits = ctx.limits();
        let max_texels = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            .min(MAX_DEPTH_BYTES)
            / 4;
        if max_texels < 64 * 64 {
            return Err(RenderError::LimitsTooSmall {
                adapter: crate::gpu::context::describe_adapter(&ctx.info),
                needs: "technique compute".into(),
                shortfalls: vec![format!(
                    "max_storage_buffer_binding_size: the device allows {}, the technique \
                     needs 16384",
                    limits.max_storage_buffer_binding_size
                )],
            });
        }
        let module = crate::gpu::shaders::module(device, "compute.shader", &shader());
        let cs = wgpu::ShaderStages::COMPUTE;
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "compute.layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, cs),
                crate::gpu::pipelines::storage_entry(1, cs),
                crate::gpu::pipelines::storage_entry(2, cs),
                crate::gpu::pipelines::storage_entry(3, cs),
                crate::gpu::pipelines::storage_entry(4, cs),
                crate::gpu::pipelines::uniform_entry(5, cs),
                crate::gpu::pipelines::storage_rw_entry(6, cs),
                crate::gpu::pipelines::storage_rw_entry(7, cs),
                crate::gpu::pipelines::storage_rw_entry(8, cs),
            ],
        );
        let args_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "compute.args_layout",
            &[crate::gpu::pipelines::storage_rw_entry(0, cs)],
        );
        let main_layout =
            crate::gpu::pipelines::pipeline_layout(device, "compute.pipeline_layout", &[&layout]);
        let finalize_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "compute.finalize_layout",
            &[&layout, &args_layout],
        );
        let pipeline = |entry: &str, layout: &wgpu::PipelineLayout| {
            crate::gpu::pipelines::compute_pipeline(device, entry, layout, &module, entry)
        };
        let alpha_tested = |entry: &str, layout: &wgpu::PipelineLayout| {
            crate::gpu::pipelines::compute_pipeline_with(
                device,
                entry,
                Some(layout),
                &module,
                entry,
                &[("ALPHA_TESTED", 1.0)],
            )
        };

        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let copy_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "compute.copy_layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, vf),
                crate::gpu::pipelines::storage_entry(1, vf),
                crate::gpu::pipelines::uniform_entry(2, vf),
                crate::gpu::pipelines::storage_entry(3, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let copy_module =
            crate::gpu::shaders::module(device, "compute_copy.shader", &copy_shader());
        let copy_pipeline_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "compute.copy_pipeline_layout",
            &[&copy_layout],
        );
        // A copy: every texel of the band or tile is replaced.
        let copy = crate::shadows::depth::overwrite_pipeline(
            device,
            &copy_pipeline_layout,
            &copy_module,
            "vs_copy",
            Some("fs_copy"),
        );

        let counters = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("compute.counters"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let counters_read = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("compute.counters_read"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let args = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("compute.args"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let args_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("compute.args_bind_group"),
            layout: &args_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: args.as_entire_binding(),
            }],
        });
        Ok(Self {
            setup: pipeline("cs_setup", &main_layout),
            setup_masked: alpha_tested("cs_setup", &main_layout),
            finalize: pipeline("cs_finalize", &finalize_layout),
            large: pipeline("cs_large", &main_layout),
            large_masked: alpha_tested("cs_large", &main_layout),
            copy,
            layout,
            copy_layout,
            depth: None,
            chunks: None,
            counters,
            counters_read,
            args,
            args_bind_group,
            max_texels,
            max_groups: limits.max_compute_workgroups_per_dimension.min(MAX_GROUPS),
            chunk_capacity: None,
            pending_read: false,
            copy_params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("compute.copy_params"),
                size: 16,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            slots: Vec::new(),
            bound: Vec::new(),
        })
    }

    /// Slot `r`, made on first use; its bind groups are (re)made when missing.
    fn slot(&mut self, ctx: &GpuContext, r: usize, bound: &[&wgpu::Buffer]) -> &RoundSlot {
        let device = &ctx.device;
        while self.slots.len() <= r {
            self.slots.push(RoundSlot {
                params: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("compute.params"),
                    size: std::mem::size_of::<ComputeParams>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                // The uniform binding is the whole fixed-size array (the raster and copy
                // passes read it as a uniform).
                entries: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("compute.entries"),
                    size: MAX_ROUND_ENTRIES * std::mem::size_of::<Entry>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                bind_group: None,
                copy_bind_group: None,
            });
        }
        let slot = &mut self.slots[r];
        if slot.bind_group.is_none() {
            // params, views, eyes, world, corners, entries, depth, chunks, counters
            let [views, eyes, world, corners, depth, chunks] = bound else {
                unreachable!("six bound buffers")
            };
            let buffers = [
                &slot.params,
                *views,
                *eyes,
                *world,
                *corners,
                &slot.entries,
                *depth,
                *chunks,
                &self.counters,
            ];
            slot.bind_group = Some(crate::gpu::pipelines::buffer_bind_group(
                device,
                "compute.bind_group",
                &self.layout,
                &buffers,
            ));
            slot.copy_bind_group = Some(crate::gpu::pipelines::buffer_bind_group(
                device,
                "compute.copy_bind_group",
                &self.copy_layout,
                &[&self.copy_params, *views, &slot.entries, *depth],
            ));
        }
        &self.slots[r]
    }

    /// Test knobs: at most `max_texels` texels per round, exactly `chunks` chunk records, at
    /// most `max_groups` workgroups along x of a dispatch (the rest goes along y).
    #[cfg(feature = "test-hooks")]
    pub fn with_limits(mut self, max_texels: u64, chunks: u32, max_groups: u32) -> Self {
        self.max_texels = max_texels.clamp(1, self.max_texels);
        self.chunk_capacity = Some(chunks.max(1));
        self.max_groups = max_groups.clamp(1, self.max_groups);
        self
    }

    /// `(chunks requested, chunks that did not fit the list and were rasterized by their setup
    /// thread)` in the last generation's final round (waits for the GPU; call after submitting
    /// it). `None` before the first generation or when already read.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // benchmarks and tests
    pub fn overflowed(&mut self, ctx: &GpuContext) -> Result<Option<(u32, u32)>, RenderError> {
        if !self.pending_read {
            return Ok(None);
        }
        self.pending_read = false;
        let bytes = crate::gpu::readback::map_read(ctx, &self.counters_read, 0..16)?;
        let words: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(Some((words[0], words[1])))
    }

    fn ensure_buffers(&mut self, ctx: &GpuContext, texels: u64, chunks_wanted: u32) {
        if self.depth.as_ref().is_none_or(|(_, n)| *n < texels) {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("compute.depth"),
                size: texels.max(1) * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.depth = Some((buffer, texels));
        }
        let max_chunks =
            ((ctx.limits().max_storage_buffer_binding_size / CHUNK_BYTES) as u32).min(MAX_CHUNKS);
        let want = self
            .chunk_capacity
            .unwrap_or(chunks_wanted)
            .clamp(1, max_chunks);
        if self.chunks.as_ref().is_none_or(|(_, n)| *n < want) {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("compute.chunks"),
                size: want as u64 * CHUNK_BYTES,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            self.chunks = Some((buffer, want));
        }
    }
}

impl ShadowTechnique for Compute {
    fn record(&mut self, g: Generation<'_>) -> ShadowStats {
        let input = g.input;
        let mut stats = ShadowStats::default();
        let ctx = input.ctx;
        let casters = input.casters;
        let tiles = &input.atlas.tiles;
        let tile_size = |v: u32| tiles[v as usize].size;
        let max_threads = (1u64 << 31).min(self.max_groups as u64 * self.max_groups as u64 * 64);
        let rounds = plan_rounds(
            input.draw_list,
            tile_size,
            casters.triangles,
            self.max_texels,
            max_threads,
        );
        let most_texels = rounds
            .iter()
            .map(|r| texels(r, tile_size))
            .max()
            .unwrap_or(1);
        // Room for every texel of the round to be covered by large triangles 16 times over
        // (chunks are rarely full). With less room a crowded frame's chunks fall back to their
        // setup threads, whose loops over many chunks llvmpipe cuts short (its loop budget per
        // invocation), and large casters lose texels (docs/decisions.md, "Compute rasterizer: a
        // zero fill and a chunk list 16 times the texels").
        let chunks_wanted = ((most_texels / 64) as u32).max(MIN_CHUNKS);
        self.pending_read = false;
        self.ensure_buffers(ctx, most_texels, chunks_wanted);
        let depth = self.depth.as_ref().expect("depth buffer").0.clone();
        let (chunks, capacity) = self.chunks.clone().expect("chunk list");
        let discard = input.options.discard_raster;
        // The slots' bind groups hold these; any replaced (a grown depth buffer, a re-planned
        // atlas) makes them again.
        let bound = [
            &input.atlas.views_buffer,
            &input.atlas.eyes,
            &casters.world,
            &casters.corners,
            &depth,
            &chunks,
        ];
        if self.bound.len() != bound.len() || self.bound.iter().zip(bound).any(|(a, b)| a != b) {
            for slot in &mut self.slots {
                slot.bind_group = None;
                slot.copy_bind_group = None;
            }
            self.bound = bound.iter().map(|b| (*b).clone()).collect();
        }
        ctx.queue.write_buffer(
            &self.copy_params,
            0,
            bytemuck::cast_slice(&[input.atlas.size as f32, 0.0, 0.0, 0.0]),
        );

        g.encoder.push_debug_group("compute");
        let last_round = rounds.len() - 1;
        for (r, round) in rounds.iter().enumerate() {
            let round_texels = texels(round, tile_size);
            let params = ComputeParams {
                counts: [
                    casters.triangles,
                    casters.cullable_triangles,
                    input.options.cull.bits_for(casters),
                    round.len() as u32,
                ],
                sizes: [
                    round_texels as u32,
                    capacity,
                    self.max_groups,
                    u32::from(discard),
                ],
            };
            let slot = self.slot(ctx, r, &bound);
            ctx.queue
                .write_buffer(&slot.params, 0, bytemuck::bytes_of(&params));
            ctx.queue
                .write_buffer(&slot.entries, 0, bytemuck::cast_slice(round));
            let bind_group = slot.bind_group.clone().expect("made by slot()");
            let copy_bind_group = slot.copy_bind_group.clone().expect("made by slot()");
            if r == 0 {
                // The first pass opens the timer span (a fill records no timestamps).
                let mut pass = g.input.ctx.raster_fence().begin_compute_pass(
                    g.encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("compute.transform"),
                        timestamp_writes: g.timer.compute_writes(g.span, true, false),
                    },
                );
                let s = g.timer.begin_compute_stats(&mut pass);
                casters.record(&mut pass, false);
                g.timer.end_compute_stats(&mut pass, s);
                stats.passes += 1;
            }
            g.encoder.clear_buffer(&self.counters, 0, None);
            g.encoder.clear_buffer(&depth, 0, Some(round_texels * 4));
            if casters.triangles > 0 {
                {
                    let mut pass = g.input.ctx.raster_fence().begin_compute_pass(
                        g.encoder,
                        &wgpu::ComputePassDescriptor {
                            label: Some("compute.setup"),
                            timestamp_writes: None,
                        },
                    );
                    let s = g.timer.begin_compute_stats(&mut pass);
                    pass.set_bind_group(0, &bind_group, &[]);
                    // Alpha-tested triangles, then the opaque ones, each with its pipeline (the
                    // few masked ones first: their chunks find room in the list before a
                    // crowded frame fills it, and their texels are the costlier to rasterize
                    // on a setup thread).
                    let opaque = casters.first_masked_triangle;
                    for (pipeline, tris) in [
                        (&self.setup_masked, casters.triangles - opaque),
                        (&self.setup, opaque),
                    ] {
                        if tris == 0 {
                            continue;
                        }
                        pass.set_pipeline(pipeline);
                        let threads = tris as u64 * round.len() as u64;
                        let (x, y) = crate::gpu::pipelines::dispatch_2d(threads, self.max_groups);
                        pass.dispatch_workgroups(x, y, 1);
                    }
                    pass.set_pipeline(&self.finalize);
                    pass.set_bind_group(1, &self.args_bind_group, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                    g.timer.end_compute_stats(&mut pass, s);
                    stats.passes += 1;
                }
                if !discard {
                    let mut pass = g.input.ctx.raster_fence().begin_compute_pass(
                        g.encoder,
                        &wgpu::ComputePassDescriptor {
                            label: Some("compute.large"),
                            timestamp_writes: None,
                        },
                    );
                    let s = g.timer.begin_compute_stats(&mut pass);
                    // Chunks of alpha-tested triangles say so; only a scene with some needs the
                    // pipeline that looks.
                    pass.set_pipeline(if casters.first_masked_triangle < casters.triangles {
                        &self.large_masked
                    } else {
                        &self.large
                    });
                    pass.set_bind_group(0, &bind_group, &[]);
                    pass.dispatch_workgroups_indirect(&self.args, 0);
                    g.timer.end_compute_stats(&mut pass, s);
                    stats.passes += 1;
                }
            }
            if r == last_round {
                g.encoder
                    .copy_buffer_to_buffer(&self.counters, 0, &self.counters_read, 0, 16);
            }

            let mut pass = g.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("compute.copy"),
                color_attachments: &[],
                // Every view redrawn: the first copy may clear the whole atlas; otherwise only
                // the listed tiles are written.
                depth_stencil_attachment: Some(crate::shadows::atlas::shared::atlas_attachment(
                    input,
                    r == 0 && input.full(),
                )),
                timestamp_writes: g.timer.render_writes(g.span, false, r == last_round),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let s = g.timer.begin_render_stats(&mut pass);
            pass.set_pipeline(&self.copy);
            pass.set_bind_group(0, &copy_bind_group, &[]);
            pass.draw(0..6, 0..round.len() as u32);
            g.timer.end_render_stats(&mut pass, s);
            stats.passes += 1;
            stats.draws += 1;
            stats.triangles += casters.triangles as u64 * round.len() as u64;
        }
        g.encoder.pop_debug_group();
        self.pending_read = true;
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_respect_texel_and_thread_limits() {
        let sizes = [256u32, 256, 512, 128];
        let list = [0u32, 1, 2, 3];
        let size = |v: u32| sizes[v as usize];
        // Everything fits one round.
        let r = plan_rounds(&list, size, 10, 1 << 20, 1 << 31);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].len(), 4);
        assert_eq!(r[0][2].base, 2 * 256 * 256);
        // 512² texels per round: the 512 tile alone, the others packed around it.
        let r = plan_rounds(&list, size, 10, 512 * 512, 1 << 31);
        assert!(r.iter().all(|r| texels(r, size) <= 512 * 512));
        assert_eq!(r.iter().map(|r| r.len()).sum::<usize>(), 4);
        // A tile over the limit becomes bands of rows that cover it exactly once.
        let r = plan_rounds(&[2], size, 10, 100 * 512, 1 << 31);
        let rows: Vec<(u32, u32)> = r.iter().flatten().map(|e| (e.row, e.rows)).collect();
        assert_eq!(rows.iter().map(|&(_, n)| n).sum::<u32>(), 512);
        assert!(rows.windows(2).all(|w| w[0].0 + w[0].1 == w[1].0));
        assert!(rows.iter().all(|&(_, n)| n <= 100));
        // Threads: 10 triangles, at most 20 threads → two entries per round.
        let r = plan_rounds(&list, size, 10, 1 << 30, 20);
        assert_eq!(r.len(), 2);
        // Never more entries than the shader's uniform array holds.
        let many: Vec<u32> = (0..10_000).map(|v| v % 4).collect();
        let r = plan_rounds(&many, |_| 16, 1, 1 << 30, 1 << 31);
        assert!(r.iter().all(|r| r.len() as u64 <= MAX_ROUND_ENTRIES));
        assert_eq!(r.iter().map(|r| r.len()).sum::<usize>(), 10_000);
        let wgsl = shader();
        assert!(wgsl.contains(&format!(
            "const MAX_ROUND_ENTRIES: u32 = {MAX_ROUND_ENTRIES}u;"
        )));
    }

    #[test]
    fn records_match_the_wgsl() {
        use crate::gpu::types::layout::{same_layout, wgsl_layout_in};
        same_layout!(in shader(), ComputeParams, counts, sizes);
        // A round entry is one vec4<u32> of the uniform array `RoundEntries`.
        let (size, _) = wgsl_layout_in(&shader(), "RoundEntries");
        assert_eq!(
            size as u64,
            MAX_ROUND_ENTRIES * std::mem::size_of::<Entry>() as u64
        );
        assert_eq!(std::mem::size_of::<Entry>(), 16);
    }

    #[test]
    fn small_area_matches_the_shader() {
        let wgsl = shader();
        assert!(wgsl.contains(&format!("const SMALL_AREA: u32 = {SMALL_AREA}u;")));
    }

    #[test]
    fn dispatches_stay_within_the_dimension_limit() {
        let items = 64 * 65535 * 3 + 1;
        let (x, y) = crate::gpu::pipelines::dispatch_2d(items, 65535);
        assert!(x <= 65535 && y <= 65535);
        assert!(x as u64 * y as u64 * 64 >= items);
        assert_eq!(crate::gpu::pipelines::dispatch_2d(10, 65535), (1, 1));
    }
}
