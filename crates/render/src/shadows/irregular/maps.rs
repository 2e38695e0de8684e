//! Irregular (alias-free) shadow maps, seed 001, as `--technique irregular`.
//!
//! Shadow maps sample occluders at light-space texels and compare depths there, so a texel's
//! answer is smeared over every camera pixel that lands in it (aliasing). Irregular shadow
//! maps turn that around: the camera's own samples are put into a light-space grid and every
//! caster triangle is tested against exactly the samples under it, so each pixel gets the
//! exact answer for its own point. No depth atlas is filled; the result is the per-pixel
//! visibility mask itself, which the lighting pass reads instead of a shadow map.
//!
//! One frame, after the G-buffer (all compute, `irregular.wgsl` beside this module):
//!
//! 1. the caster transform ([`crate::gpu_scene::casters`]) writes every caster vertex in world
//!    space;
//! 2. `cs_init`: every pixel's mask word gets the bits of the lights that reach it;
//! 3. per batch of lights (see **Memory**): the batch's grids are emptied; `cs_insert` projects each
//!    pixel's ray origin (the G-buffer point moved `1e-4·max(1, |p|∞)` along its normal, the
//!    CPU reference's convention) into the light view that covers it and pushes it on that
//!    grid texel's list (node cursor by `atomicAdd`, list head by `atomicExchange`; nodes are
//!    struct-of-arrays: a `next` array, then origin + pixel); `cs_triangles` runs one thread
//!    per (caster triangle, view), bounds the triangle's projection conservatively in texels
//!    (see below) and tests every listed sample exactly (two-sided watertight segment test to
//!    the light, or along the light direction, as the reference); a hit clears the sample's
//!    light bit with `atomicAnd`.
//!
//! **Conservative coverage in compute, not the rasterizer.** wgpu has no conservative
//! rasterization and no geometry shader (the seed needed one to see a triangle's vertices
//! per fragment). A compute thread pulls the triangle's three corners from the caster buffers
//! (indexed geometry stays indexed: `corners` are indices into shared world positions), clips
//! it at the light's plane (`w = ε`, perspective views; a sample's segment to the light lies
//! wholly at `w > 0`), takes the bounding box of the projected polygon grown by
//! `MARGIN` = 0.05 texel, and — when nothing was clipped — skips texels whose square (also
//! grown by the margin) lies outside one of the three edge half-planes. Footprints of at most
//! 16 texels are walked by that thread; of larger ones, the 8×8-texel tiles that hold samples
//! (an occupancy flag per tile, set by `cs_insert`) are appended to a queue that an indirect
//! dispatch walks with one workgroup per tile and one thread per texel, so one floor quad
//! covering a whole grid does not serialize on one thread, and empty parts of a light's view
//! cost one flag read per tile. A full queue is an error ([`crate::error::RenderError::TileQueueFull`]), never
//! a dropped tile.
//!
//! **llvmpipe's loop budget.** Mesa's software driver (GL and Vulkan) ends every loop of an
//! invocation once that invocation has run 65535 loop iterations in all; a thread that walked
//! a large footprint lost tests silently (docs/decisions.md, "llvmpipe's loop budget"). So every
//! invocation walks little: one list per `cs_tiles` thread, at most 16 lists per
//! `cs_triangles` thread, at most `(1024/8)²` tile flags ([`GRID_LIMIT`]); a walk that still
//! ends early (a list longer than the budget, e.g. `--irregular-grid 1`) is counted and the
//! frame becomes an error.
//!
//! **Views.** The grid of a view is the view's own projection, so a segment from a sample to
//! the light (a ray through the light's centre of projection, or parallel rays for an
//! orthographic view) projects to the sample's own grid point, and any triangle crossing it
//! covers that point: the traversal is exact, only the grid's resolution changes the cost.
//! Spot lights use their one view. Point lights use the plan's six cube faces, the sample's
//! face chosen by the major axis of `origin − light`: faces are perspective projections, so
//! triangle edges stay straight (the dual-paraboloid warp would bend them and break the
//! conservative bound; irregular refuses paraboloid views). Directional lights use the plan's
//! cascades: the sample goes to the cascade the lighting pass would pick (or any cascade whose
//! square holds it), and triangles are tested against every cascade they touch; cascades
//! split the samples, so each (sample, triangle) pair is still tested at most once. Depth
//! ranges play no part (a caster beyond a cascade's far plane still shadows).
//!
//! **Grid resolution** is a knob ([`IrregularOptions::grid`], `--irregular-grid`): the view's
//! tile size capped at 512 by default, at most [`GRID_LIMIT`]. It changes speed (list lengths
//! versus texels visited), never the answer. The paper's sample-equalising multimap hash is
//! an option ([`IrregularOptions::hash`], `--irregular-hash`), off by default: it keeps the
//! answer exact but lengthens the lists each texel visit walks (docs/techniques.md,
//! "Alias-free shadows: `--technique irregular`").
//!
//! **Memory.** Each pixel lands in at most one view per light, so a batch of `k` shadowed
//! lights needs at most `k · width · height` nodes (20 bytes each). Lights are split into
//! batches so that this worst case fits the node pool (at most the storage-binding limit)
//! and the batch's grids fit one binding. A frame that still runs out (only with a pool forced
//! smaller than one light's worst case, as a test does, or frames above
//! ~6.7 M pixels, where one light's worst case exceeds a 128 MiB binding) is reported as
//! [`RenderError::NodePoolOverflow`] after the frame, never used.
//!
//! **Approximation.** Triangles are clipped `ε = 10⁻³·near` in front of the light's plane: an
//! occluder closer to a spot or point light than that (0.1 mm for a 0.1 m near plane) is
//! missed. Edge cases of the watertight test are decided in single precision (the reference
//! re-decides exact zeros in double precision), so a sample exactly on a shared edge can differ.

use manyshadows_scene::light_space::ViewKind;
use manyshadows_scene::{LightKind, Scene};
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::frame::gbuffer::GBuffer;
use crate::frame::visibility_mask::VisibilityMask;
use crate::gpu::context::GpuContext;
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::shadows::lookup::{PARABOLOID, SHADOW_LOOKUP};
use crate::shadows::plan::ShadowPlan;

/// Sample lists per light-space texel, exact per-triangle tests.
pub(crate) fn shader() -> String {
    compose(&[
        COMMON,
        PARABOLOID,
        SHADOW_LOOKUP,
        ALPHA_MASK,
        include_str!("irregular.wgsl"),
    ])
}

/// Default cap of the grid side (texels) of one view.
pub const DEFAULT_GRID_MAX: u32 = 512;
/// Largest grid side: `cs_triangles` visits up to `(side / 8)²` tile flags of a footprint in
/// one invocation, which must stay within llvmpipe's 65535 loop iterations per invocation.
pub const GRID_LIMIT: u32 = 1024;
/// Texels per side of a queued tile and of an occupancy flag (`TILE` in the shader).
const TILE: u32 = 8;

/// Words of `heads` one view uses: its grid, then its occupancy flags.
fn view_words(side: u32, hash: u32) -> u64 {
    buckets(side, hash) as u64 + side.div_ceil(TILE) as u64 * side.div_ceil(TILE) as u64
}

/// List heads of a view's grid: one per texel, or with the multimap hash (seed 001: "a small
/// multimap size while hashing point coordinates to equalize the number of points at each
/// multimap cell") `side² / hash` buckets that the texels are hashed into.
fn buckets(side: u32, hash: u32) -> u32 {
    let texels = side * side;
    if hash <= 1 {
        texels
    } else {
        texels.div_ceil(hash).max(1)
    }
}
/// Bytes per node: `next`, ray origin (3 × f32), pixel index.
const NODE_BYTES: u64 = 20;
/// Capacity of the tile queue (16 bytes per 8×8-texel tile): 64 MiB, or what one storage
/// binding of the device holds.
const TILE_QUEUE: u64 = (1 << 22) - 1;
/// Control words (see `irregular.wgsl`): 8 counters, then the indirect dispatch arguments.
const CONTROL_WORDS: u64 = 12;
/// The read-back holds the control words, then the cut-short count.
const READBACK_WORDS: u64 = CONTROL_WORDS + 1;
const ARGS_OFFSET: u64 = 8 * 4;

/// Tuning knobs of `--technique irregular`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct IrregularOptions {
    /// Grid side per view in texels; `None` = the view's tile size capped at
    /// 512. Changes the cost, not the result.
    pub grid: Option<u32>,
    /// Multimap shrink factor (seed 001's equalising hash): each view keeps `grid² / hash`
    /// list heads and texels are hashed into them, so crowded texels spread over buckets
    /// (lists get longer on average; samples of other texels in a bucket are tested too, which
    /// the exact test makes harmless). `None` or 1: one list per texel.
    pub hash: Option<u32>,
    /// Test only (feature `test-hooks`): force the node pool to this many nodes, to exercise
    /// overflow reporting.
    #[cfg(feature = "test-hooks")]
    pub node_capacity: Option<u32>,
}

impl IrregularOptions {
    /// Checks every value that has a range of its own ([`RenderError::InvalidOption`] names
    /// the first one out of range, as `RenderSettings` names the field).
    pub fn validate(&self) -> Result<(), RenderError> {
        if let Some(g) = self.grid.filter(|g| !(1..=GRID_LIMIT).contains(g)) {
            return Err(RenderError::invalid_option(
                "irregular.grid",
                g,
                "1 to 1024 texels per side (GRID_LIMIT)",
            ));
        }
        if self.hash == Some(0) {
            return Err(RenderError::invalid_option(
                "irregular.hash",
                0,
                "at least 1 (1 = one list per texel, no hashing)",
            ));
        }
        Ok(())
    }
}

/// Work counters of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub struct IrregularStats {
    /// Batches of lights.
    pub batches: u32,
    /// Most nodes one batch used.
    pub peak_nodes: u32,
    /// Node capacity of the pool.
    pub node_capacity: u32,
    /// Samples no view of their light covered (counted as lit; 0 on every scene we know).
    pub unmapped: u32,
    /// Most 8×8-texel tiles one batch queued for `cs_tiles`.
    pub peak_tiles: u32,
}

/// `IView` in `irregular.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct IView {
    view_proj: [[f32; 4]; 4],
    light: [f32; 4],
    grid: [u32; 4],
    params: [f32; 4],
    occ: [u32; 4],
}

/// `Batch` in `irregular.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BatchData {
    lights_views: [u32; 4],
    caps: [u32; 4],
    extra: [u32; 4],
}

/// A run of lights processed together: their samples share the node pool.
struct Batch {
    views: (u32, u32),
    /// Grid texels of the batch's views.
    heads: u64,
    /// Bind groups of `cs_insert`, `cs_triangles`, `cs_args`, `cs_tiles` for this batch.
    groups: [wgpu::BindGroup; 4],
}

/// The irregular-shadow passes of one renderer and their buffers.
pub struct IrregularShadows {
    tile_queue: u64,
    width: u32,
    height: u32,
    lights: u32,
    words: u32,
    triangles: u32,
    capacity: u32,
    /// Word of `heads` that counts walks cut short.
    cut_index: u64,
    mask: wgpu::Buffer,
    heads: wgpu::Buffer,
    control: wgpu::Buffer,
    control_readback: wgpu::Buffer,
    batches: Vec<Batch>,
    init: (wgpu::ComputePipeline, wgpu::BindGroup),
    /// `cs_insert`, `cs_triangles`, `cs_args`, `cs_tiles`.
    pipelines: [wgpu::ComputePipeline; 4],
    last: IrregularStats,
    fence: crate::gpu::raster_fence::RasterFence,
}

/// Everything the passes read that the renderer owns.
pub struct IrregularInputs<'a> {
    /// `FrameUniforms`.
    pub frame: &'a wgpu::Buffer,
    /// `array<LightData>`.
    pub lights: &'a wgpu::Buffer,
    /// `array<ShadowViewData>`.
    pub views: &'a wgpu::Buffer,
    /// G-buffer.
    pub gbuffer: &'a GBuffer,
    /// World-space caster geometry.
    pub casters: &'a CasterGeometry,
}

impl IrregularShadows {
    /// Plans the batches and builds buffers and pipelines for frames of `w`×`h` pixels.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        plan: &ShadowPlan,
        inputs: &IrregularInputs<'_>,
        (w, h): (u32, u32),
        options: IrregularOptions,
    ) -> Result<Self, RenderError> {
        // Paraboloid views are refused before (the technique's point-shadow modes): their
        // warp would bend triangle edges and break the conservative bound.
        debug_assert!(!plan
            .views
            .iter()
            .any(|v| matches!(v.kind, ViewKind::Paraboloid(_))));
        // `RenderSettings::validate` checked the options' ranges.
        debug_assert!(options.grid.is_none_or(|g| (1..=GRID_LIMIT).contains(&g)));
        let device = &ctx.device;
        let limit = ctx.limits().max_storage_buffer_binding_size;
        let pixels = w as u64 * h as u64;
        let lights = scene.lights.len() as u32;
        let words = lights.div_ceil(32).max(1);
        let mask_bytes = pixels * words as u64 * 4;
        if mask_bytes > limit {
            return Err(RenderError::TooLarge {
                what: format!("the irregular visibility mask of a {w}x{h} frame"),
                needed: mask_bytes,
                limit,
                unit: "bytes",
                limit_name: "max_storage_buffer_binding_size",
            });
        }

        // Per view: its grid (side, base within its batch) and light.
        let view_data = plan.view_data();
        let grid_max = options.grid.unwrap_or(DEFAULT_GRID_MAX);
        let hash = options.hash.unwrap_or(1).max(1);
        let sides: Vec<u32> = plan
            .layout
            .tiles
            .iter()
            .map(|t| match options.grid {
                Some(g) => g,
                None => t.size.min(grid_max),
            })
            .collect();

        // Batches: runs of lights whose worst-case node count and grids fit one binding.
        let node_limit = (limit / NODE_BYTES).min(u32::MAX as u64 / 4);
        let shadowed = plan.light_views.iter().filter(|v| v.1 > 0).count() as u64;
        #[cfg(feature = "test-hooks")]
        let forced = options.node_capacity;
        #[cfg(not(feature = "test-hooks"))]
        let forced: Option<u32> = None;
        let capacity = match forced {
            Some(c) => c.max(1) as u64,
            None => (shadowed.max(1) * pixels).min(node_limit).max(1),
        };
        let head_limit = limit / 4;
        // ((first light, end light), (first view, end view), grid words) per batch.
        type Range = ((u32, u32), (u32, u32), u64);
        let mut ranges: Vec<Range> = Vec::new();
        let (mut l0, mut k, mut heads) = (0u32, 0u64, 0u64);
        let mut bases = vec![0u32; plan.views.len()];
        for (li, &(first, n)) in plan.light_views.iter().enumerate() {
            let light_heads: u64 = (first..first + n)
                .map(|v| view_words(sides[v as usize], hash))
                .sum();
            if light_heads > head_limit {
                return Err(RenderError::TooLarge {
                    what: format!("light {li}'s irregular grids (lower the grid resolution)"),
                    needed: light_heads,
                    limit: head_limit,
                    unit: "texels",
                    limit_name: "max_storage_buffer_binding_size / 4",
                });
            }
            let needs = u64::from(n > 0);
            if li as u32 > l0
                && ((k + needs) * pixels > capacity || heads + light_heads > head_limit)
            {
                ranges.push(((l0, li as u32), (0, 0), heads));
                l0 = li as u32;
                k = 0;
                heads = 0;
            }
            for v in first..first + n {
                bases[v as usize] = heads as u32;
                heads += view_words(sides[v as usize], hash);
            }
            k += needs;
        }
        ranges.push(((l0, lights), (0, 0), heads));
        for r in &mut ranges {
            let (a, b) = r.0;
            let first = (a..b)
                .map(|l| plan.light_views[l as usize])
                .find(|v| v.1 > 0)
                .map(|v| v.0);
            let end = (a..b)
                .rev()
                .map(|l| plan.light_views[l as usize])
                .find(|v| v.1 > 0)
                .map(|v| v.0 + v.1);
            r.1 = match (first, end) {
                (Some(f), Some(e)) => (f, e),
                _ => (0, 0),
            };
        }

        let iviews: Vec<IView> = plan
            .views
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let light = &scene.lights[v.light];
                let l = match light.kind {
                    LightKind::Directional { direction, .. } => direction.extend(0.0),
                    LightKind::Spot { position, .. } | LightKind::Point { position, .. } => {
                        position.extend(1.0)
                    }
                };
                IView {
                    view_proj: view_data[i].view_proj,
                    light: l.to_array(),
                    grid: [
                        bases[i],
                        sides[i],
                        v.light as u32,
                        u32::from(v.orthographic),
                    ],
                    // Clip triangles 1e-3 of the near distance in front of the light's plane.
                    params: [v.near.max(1e-6) * 1e-3, 0.0, 0.0, 0.0],
                    // The view's occupancy flags follow its heads.
                    // z: bucket count when texels are hashed into a smaller multimap (0: one
                    // list per texel).
                    occ: [
                        bases[i] + buckets(sides[i], hash),
                        sides[i].div_ceil(TILE),
                        if hash > 1 { buckets(sides[i], hash) } else { 0 },
                        0,
                    ],
                }
            })
            .chain(std::iter::once(bytemuck::Zeroable::zeroed()))
            .collect();
        let max_heads = ranges.iter().map(|r| r.2).max().unwrap_or(0);
        let tile_queue = TILE_QUEUE.min(limit / 16 - 1);
        // One more word: the frame's count of walks cut short (`cut_short` in the shader).
        let cut_index = max_heads;
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let storage = wgpu::BufferUsages::STORAGE;
        let iviews_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("irregular.views"),
            contents: bytemuck::cast_slice(&iviews),
            usage: storage,
        });
        let heads_buf = buffer(
            "irregular.heads",
            (max_heads + 1) * 4,
            storage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let nodes = buffer("irregular.nodes", capacity * NODE_BYTES, storage);
        let mask = buffer(
            "irregular.mask",
            mask_bytes,
            storage | wgpu::BufferUsages::COPY_SRC,
        );
        let control = buffer(
            "irregular.control",
            CONTROL_WORDS * 4,
            storage
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        );
        let control_readback = buffer(
            "irregular.control_readback",
            READBACK_WORDS * 4,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let tiles = buffer("irregular.tiles", (tile_queue + 1) * 16, storage);

        let module = crate::gpu::shaders::module(device, "irregular.shader", &shader());
        // A scene without alpha-tested casters gets pipelines compiled without the mask test.
        let masked = inputs.casters.first_masked_triangle < inputs.casters.triangles;
        let constants: &[(&str, f64)] = if masked {
            &[("ALPHA_TESTED", 1.0)]
        } else {
            &[]
        };
        let pipeline = |entry: &str| {
            crate::gpu::pipelines::compute_pipeline_with(
                device, entry, None, &module, entry, constants,
            )
        };
        let pv = inputs.gbuffer.position.create_view(&Default::default());
        let nv = inputs.gbuffer.normal.create_view(&Default::default());
        // Layouts are derived from each entry point, so each binds only what it uses (and
        // stays within the 8 storage buffers per stage of core WebGPU); a derived layout
        // belongs to its pipeline, hence one bind group per pipeline (and batch).
        let bind = |p: &wgpu::ComputePipeline, bindings: &[u32], batch: Option<&wgpu::Buffer>| {
            let entries: Vec<wgpu::BindGroupEntry> = bindings
                .iter()
                .map(|&b| wgpu::BindGroupEntry {
                    binding: b,
                    resource: match b {
                        0 => inputs.frame.as_entire_binding(),
                        1 => inputs.lights.as_entire_binding(),
                        2 => inputs.views.as_entire_binding(),
                        3 => wgpu::BindingResource::TextureView(&pv),
                        4 => wgpu::BindingResource::TextureView(&nv),
                        5 => iviews_buf.as_entire_binding(),
                        6 => inputs.casters.world.as_entire_binding(),
                        7 => inputs.casters.corners.as_entire_binding(),
                        8 => heads_buf.as_entire_binding(),
                        9 => nodes.as_entire_binding(),
                        10 => mask.as_entire_binding(),
                        11 => control.as_entire_binding(),
                        12 => tiles.as_entire_binding(),
                        _ => batch.expect("a batch uniform").as_entire_binding(),
                    },
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("irregular.bind_group"),
                layout: &p.get_bind_group_layout(0),
                entries: &entries,
            })
        };
        let init = pipeline("cs_init");
        let init_group = bind(&init, &[0, 1, 3, 10], None);
        let passes: [(wgpu::ComputePipeline, &[u32]); 4] = [
            (pipeline("cs_insert"), &[0, 1, 3, 4, 5, 8, 9, 11, 13]),
            (pipeline("cs_triangles"), &[5, 6, 7, 8, 9, 10, 11, 12, 13]),
            (pipeline("cs_args"), &[11, 12, 13]),
            (pipeline("cs_tiles"), &[5, 6, 7, 8, 9, 10, 12, 13]),
        ];
        let triangles = inputs.casters.triangles;
        // Single-sided casters cast only where a light sees their front: the walks skip the
        // cullable triangles a light sees from behind (all of them exact for the closed meshes
        // among them too).
        let culled = if inputs.casters.front_only {
            inputs.casters.cullable_triangles
        } else {
            0
        };
        let batches = ranges
            .iter()
            .map(|&((a, b), views, heads)| {
                let data = BatchData {
                    lights_views: [a, b, views.0, views.1],
                    caps: [capacity as u32, tile_queue as u32, triangles, words],
                    extra: [cut_index as u32, culled, 0, 0],
                };
                let buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("irregular.batch"),
                    contents: bytemuck::bytes_of(&data),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                Batch {
                    views,
                    heads,
                    groups: passes
                        .each_ref()
                        .map(|(p, bindings)| bind(p, bindings, Some(&buf))),
                }
            })
            .collect();
        let [insert, triangles_pass, args, tiles_pass] = passes.map(|(p, _)| p);
        Ok(Self {
            fence: ctx.raster_fence().clone(),
            tile_queue,
            width: w,
            height: h,
            lights,
            words,
            triangles,
            capacity: capacity as u32,
            cut_index,
            mask,
            heads: heads_buf,
            control,
            control_readback,
            batches,
            init: (init, init_group),
            pipelines: [insert, triangles_pass, args, tiles_pass],
            last: IrregularStats::default(),
        })
    }

    /// The per-pixel mask the lighting pass reads (`counts.w` words per pixel).
    pub fn mask(&self) -> &wgpu::Buffer {
        &self.mask
    }

    /// Counters of the last frame (after [`IrregularShadows::finish`]).
    pub fn stats(&self) -> IrregularStats {
        self.last
    }

    /// Records the whole visibility computation (after the G-buffer pass).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        casters: &CasterGeometry,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        encoder.clear_buffer(&self.control, 0, None);
        encoder.clear_buffer(&self.heads, self.cut_index * 4, Some(4));
        let pixel_groups =
            crate::gpu::pipelines::dispatch_2d(self.width as u64 * self.height as u64, 65535);
        // The samples come from the G-buffer just drawn.
        {
            let mut pass = self.fence.begin_compute_pass(
                encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some("irregular.init"),
                    timestamp_writes: timer.compute_writes(span, true, false),
                },
            );
            casters.record(&mut pass, false);
            pass.set_pipeline(&self.init.0);
            pass.set_bind_group(0, &self.init.1, &[]);
            pass.dispatch_workgroups(pixel_groups.0, pixel_groups.1, 1);
        }
        let active: Vec<&Batch> = self
            .batches
            .iter()
            .filter(|b| b.views.1 > b.views.0)
            .collect();
        for (i, b) in active.iter().enumerate() {
            let views = (b.views.1 - b.views.0) as u64;
            encoder.clear_buffer(&self.heads, 0, Some(b.heads * 4));
            encoder.clear_buffer(&self.control, 0, Some(8));
            // One compute pass per step: each step reads what the previous one wrote, and only
            // a pass boundary is sure to order storage writes before reads on every backend.
            let [insert, triangles, args, tiles] = &self.pipelines;
            let last = i + 1 == active.len();
            let step = |encoder: &mut wgpu::CommandEncoder,
                        label: &str,
                        pipeline: &wgpu::ComputePipeline,
                        group: &wgpu::BindGroup,
                        end: bool,
                        dispatch: &dyn Fn(&mut wgpu::ComputePass<'_>)| {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(label),
                    timestamp_writes: timer.compute_writes(span, false, end),
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, group, &[]);
                dispatch(&mut pass);
            };
            let has_triangles = self.triangles > 0;
            step(
                encoder,
                "irregular.insert",
                insert,
                &b.groups[0],
                last && !has_triangles,
                &|p| p.dispatch_workgroups(pixel_groups.0, pixel_groups.1, 1),
            );
            if has_triangles {
                let (x, y) =
                    crate::gpu::pipelines::dispatch_2d(self.triangles as u64 * views, 65535);
                step(
                    encoder,
                    "irregular.triangles",
                    triangles,
                    &b.groups[1],
                    false,
                    &|p| p.dispatch_workgroups(x, y, 1),
                );
                step(encoder, "irregular.args", args, &b.groups[2], false, &|p| {
                    p.dispatch_workgroups(1, 1, 1)
                });
                step(
                    encoder,
                    "irregular.tiles",
                    tiles,
                    &b.groups[3],
                    last,
                    &|p| p.dispatch_workgroups_indirect(&self.control, ARGS_OFFSET),
                );
            }
        }
        if active.is_empty() {
            // No shadowed light: close the span with an empty pass.
            let _ = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("irregular.end"),
                timestamp_writes: timer.compute_writes(span, false, true),
            });
        }
        encoder.copy_buffer_to_buffer(
            &self.control,
            0,
            &self.control_readback,
            0,
            CONTROL_WORDS * 4,
        );
        encoder.copy_buffer_to_buffer(
            &self.heads,
            self.cut_index * 4,
            &self.control_readback,
            CONTROL_WORDS * 4,
            4,
        );
    }

    /// After the frame's submission: reads the counters; a full node pool is an error.
    pub fn finish(&mut self, ctx: &GpuContext) -> Result<IrregularStats, RenderError> {
        let bytes =
            crate::gpu::readback::map_read(ctx, &self.control_readback, 0..READBACK_WORDS * 4)?;
        let c: &[u32] = bytemuck::cast_slice(&bytes);
        self.last = IrregularStats {
            batches: self.batches.len() as u32,
            peak_nodes: c[5],
            node_capacity: self.capacity,
            unmapped: c[6],
            peak_tiles: c[2],
        };
        if c[4] > 0 {
            return Err(RenderError::NodePoolOverflow {
                dropped: c[4] as u64,
                needed: c[5] as u64,
                capacity: self.capacity as u64,
            });
        }
        if c[7] > 0 {
            return Err(RenderError::TileQueueFull {
                tiles: c[7],
                capacity: self.tile_queue,
            });
        }
        if c[12] > 0 {
            return Err(RenderError::LoopLimit { walks: c[12] });
        }
        if c[6] > 0 {
            log::warn!(
                "irregular shadows: {} samples lay outside every view of their light and count \
                 as lit",
                c[6]
            );
        }
        Ok(self.last)
    }

    /// Reads the mask back.
    pub fn read_mask(&self, ctx: &GpuContext) -> Result<VisibilityMask, RenderError> {
        let bytes = crate::gpu::readback::read_buffer(ctx, &self.mask)?;
        Ok(VisibilityMask {
            width: self.width,
            height: self.height,
            lights: self.lights,
            words_per_pixel: self.words,
            words: bytemuck::cast_slice(&bytes).to_vec(),
        })
    }
}

with_setters!(IrregularOptions {
    with_grid: grid: Option<u32>,
    with_hash: hash: Option<u32>,
});

#[cfg(feature = "test-hooks")]
impl IrregularOptions {
    /// Test only: forces the node pool to `nodes` nodes ([`IrregularOptions::node_capacity`]).
    #[must_use]
    pub fn with_node_capacity(mut self, nodes: Option<u32>) -> Self {
        self.node_capacity = nodes;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::{shader, BatchData, IView};
    use crate::gpu::types::layout::same_layout;

    #[test]
    fn records_match_the_wgsl() {
        same_layout!(in shader(), IView, view_proj, light, grid, params, occ);
        same_layout!(in shader(), BatchData as "Batch", lights_views, caps, extra);
    }
}
