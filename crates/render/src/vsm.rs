//! Virtual shadow maps (seed 002: Olsson et al., "Efficient Virtual Shadow Maps for Many
//! Lights", I3D 2014; the page pool and page table as Unreal Engine 5 builds them, since wgpu
//! has no sparse textures).
//!
//! **Faces.** Every shadow view of the plan — a spot's frustum, each of a point light's six
//! cube faces, each cascade — is a *face* with a virtual map of up to 16,384² texels, cut into
//! [`PAGE_SIZE`]² pages. A face is a mip chain of page grids: level `l` has `2^l × 2^l` pages,
//! level 0 covers the whole face with one page, the finest level has `side / PAGE_SIZE` pages
//! per side. The CPU picks each face's virtual side from the light's importance (the largest
//! texel density any visible point in its reach can ask for; directional lights and lights
//! around the camera get the maximum) and lays out one page-table entry per page of every
//! level ([`VirtualPlan`]); lights that reach nothing the camera sees get no faces.
//!
//! **Pages on the GPU, every frame** (`shaders/vsm.wgsl`, after the G-buffer and the light
//! clusters):
//! 1. *mark*: each pixel visits its cluster's lights; for each light that reaches it (and
//!    faces it), the sample asks for the level whose texel matches its pixel footprint
//!    ([`VirtualOptions::lod`] texels per pixel) and marks that page and its ancestors needed;
//! 2. *allocate*: needed pages get pool pages in page-table order (ranks from per-block counts
//!    and a prefix sum, so the frame never depends on thread order), coarsest level first, a
//!    level admitted whole or not at all while the pool lasts; pages of levels that do not fit are *denied*, and
//!    lookups fall back to their nearest resident ancestor — a coarser shadow, never a wrong
//!    or missing one — and the frame's [`VirtualStats`] count them (a pool smaller than one
//!    page per face in use leaves the faces beyond it unshadowed, counted too). With caching
//!    ([`crate::RenderSettings::cache_shadows`]) a page resident last frame in a face whose
//!    view and casters did not change keeps its pool page and its depth; only the other pages
//!    get free pool pages and are drawn;
//! 3. *render*: every page drawn this frame is an ordinary shadow view (the face's projection
//!    cropped to the page, one tile of the pool), drawn the `gpu-driven` way: compute culls caster
//!    clusters against each page's frustum slice (and by normal cone), one indirect multi-draw
//!    per round draws the survivors, clipped to the page's tile (`shaders/vsm_draw.wgsl`).
//!
//! **Lookups** (`shaders/vsm_lookup.wgsl`) repeat the marking's level and page choice with the
//! same code, read the page table and sample the pool; PCF taps are clamped to the page.

use glam::Vec3;
use manyshadows_scene::light_space::{self, PointShadows, ShadowView, ViewKind};
use manyshadows_scene::Scene;

use crate::gpu_scene::casters::CasterGeometry;
use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::GBuffer;
use crate::gpu_scene::instances::GpuScene;
use crate::gpu::types::{LightData, ShadowViewData, VirtualFace, VsmRound, VsmUniforms};
use crate::gpu::pipelines::whole_entry;
use crate::settings::RenderSettings;
use crate::settings::{ShadowOptions, Technique};
use crate::shadow::{ShadowAtlas, ShadowPlan, ShadowStats};
use crate::source::{PagePool, ShadowOutput, ShadowSource, SourceInputs, ViewTable};
use crate::techniques::gpu_driven::{plan_rounds, Round, COMMAND_SIZE};
use crate::gpu::timing::{GpuTimer, Span};
use crate::{GpuContext, RenderError};

/// Side of a page in texels.
pub const PAGE_SIZE: u32 = 128;
/// Levels a face can have (level 7 of 128² pages is 16,384² texels).
pub const MAX_LEVELS: u32 = 8;
/// Largest virtual side of a face.
pub const MAX_SIDE: u32 = PAGE_SIZE << (MAX_LEVELS - 1);
/// Default page-pool budget: 256 MiB of 32-bit depth (an 8192² pool of 4096 pages).
pub const DEFAULT_POOL_BYTES: u64 = 256 << 20;
/// Default cap on page-table entries (4 bytes each).
pub const DEFAULT_TABLE_ENTRIES: u32 = 4 << 20;
/// Largest command buffer of one page-render round.
const MAX_ROUND_BYTES: u64 = 64 << 20;
/// Page-table entries per allocation workgroup (`BLOCK` in `vsm.wgsl`).
const ALLOC_BLOCK: u64 = 32;
/// Words of the counters buffer (see `vsm.wgsl`).
const COUNTERS: usize = 20;

/// Knobs of the virtual shadow maps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VirtualOptions {
    /// Page-pool budget in bytes (rounded down to a square power-of-two pool, within the
    /// adapter's texture limit).
    pub pool_bytes: u64,
    /// Largest virtual side of a face (a power of two, 128 to 16,384).
    pub max_side: u32,
    /// Shadow texels wanted per screen pixel (1 = texel footprint ≈ pixel footprint).
    pub lod: f32,
    /// Cap on page-table entries: when the faces' tables would exceed it, the largest
    /// virtual sides are halved until they fit (reported in [`VirtualFit::capped_side`]).
    pub max_table_entries: u32,
    /// Mark pages for samples that face away from a light too (what the visibility mask
    /// reads; the lighting pass does not need them).
    pub back_facing: bool,
}

impl Default for VirtualOptions {
    fn default() -> Self {
        Self {
            pool_bytes: DEFAULT_POOL_BYTES,
            max_side: MAX_SIDE,
            lod: 1.0,
            max_table_entries: DEFAULT_TABLE_ENTRIES,
            back_facing: false,
        }
    }
}

/// How the faces of a [`VirtualPlan`] were laid out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct VirtualFit {
    /// Shadow-casting lights with faces.
    pub lights: usize,
    /// Faces (spot views, cube faces, cascades).
    pub faces: usize,
    /// Shadow-casting lights that reach nothing the camera sees (no faces).
    pub off_screen: usize,
    /// Page-table entries over all faces.
    pub table_entries: u32,
    /// The virtual side every face was capped to so the page table fits
    /// [`VirtualOptions::max_table_entries`]; 0 if none was.
    pub capped_side: u32,
}

/// The faces of a frame and their page-table layout.
#[derive(Clone, Debug)]
pub struct VirtualPlan {
    /// Every face's shadow view, grouped by light in light order.
    pub views: Vec<ShadowView>,
    /// Per light: `(first face, face count)`; count 0 without shadows or off screen.
    pub light_views: Vec<(u32, u32)>,
    /// GPU records of the faces.
    pub faces: Vec<VirtualFace>,
    /// Layout summary.
    pub fit: VirtualFit,
}

/// Page-table entries of a face of virtual side `side`: `(4^(L+1) − 1) / 3` for
/// `L = log2(side / PAGE_SIZE)`.
pub fn table_entries(side: u32) -> u32 {
    let levels = (side / PAGE_SIZE).max(1).trailing_zeros() + 1;
    ((1u32 << (2 * levels)) - 1) / 3
}

impl VirtualPlan {
    /// Faces for every shadow-casting light that reaches the camera's view of `scene`
    /// (`aspect` = width / height, `height` in pixels).
    pub fn new(scene: &Scene, aspect: f32, height: u32, options: &VirtualOptions) -> Self {
        let max_side = options
            .max_side
            .clamp(PAGE_SIZE, MAX_SIDE)
            .next_power_of_two()
            .min(MAX_SIDE);
        let all = light_space::shadow_views_with(scene, aspect, PointShadows::Cube);
        let cam = &scene.camera;
        let proj = cam.projection(aspect);
        let planes = light_space::frustum_planes(proj * cam.view());
        let p11 = proj.y_axis.y;
        let mut fit = VirtualFit::default();
        let mut views = Vec::new();
        let mut sides = Vec::new();
        let mut light_views = vec![(0u32, 0u32); scene.lights.len()];
        let mut i = 0;
        while i < all.len() {
            let light = all[i].light;
            let n = all[i..].iter().take_while(|v| v.light == light).count();
            let group = &all[i..i + n];
            i += n;
            if let Some((c, r)) = scene.lights[light].bounding_sphere() {
                if !light_space::sphere_in_planes(&planes, c, r * 1.001 + 1e-4) {
                    fit.off_screen += 1;
                    continue;
                }
            }
            let importance = crate::shadow::light_importance(scene, light);
            light_views[light] = (views.len() as u32, n as u32);
            fit.lights += 1;
            for v in group {
                // A texel at distance r from the light spans 2·tan(half angle)·r / side; a
                // pixel at camera distance D spans 2·D / (P11·height). Points in reach have
                // r / D <= importance, so this side gives every one a texel no larger than
                // its pixel (times the level-of-detail scale).
                let side = if v.orthographic || !importance.is_finite() {
                    max_side
                } else {
                    let tan_half = 1.0 / v.proj.x_axis.x.abs().max(1e-6);
                    let want = tan_half * p11 * height as f32 * options.lod * importance;
                    if want.is_finite() && want < max_side as f32 {
                        (want.ceil().max(1.0) as u32)
                            .next_power_of_two()
                            .clamp(PAGE_SIZE, max_side)
                    } else {
                        max_side
                    }
                };
                views.push(*v);
                sides.push(side);
            }
        }
        // Keep the page table within its cap: halve the largest sides first.
        let mut total: u64 = sides.iter().map(|&s| table_entries(s) as u64).sum();
        while total > options.max_table_entries as u64 {
            let cap = sides.iter().copied().max().unwrap_or(PAGE_SIZE);
            if cap <= PAGE_SIZE {
                break;
            }
            for s in sides.iter_mut().filter(|s| **s == cap) {
                *s = cap / 2;
            }
            fit.capped_side = cap / 2;
            total = sides.iter().map(|&s| table_entries(s) as u64).sum();
        }
        let mut faces = Vec::with_capacity(views.len());
        let mut first = 0u32;
        for (v, &side) in views.iter().zip(&sides) {
            let finest = (side / PAGE_SIZE).trailing_zeros();
            faces.push(VirtualFace {
                view_proj: v.view_proj.to_cols_array_2d(),
                eye: crate::shadow::view_eye(v).to_array(),
                params: [
                    v.near,
                    v.far,
                    v.texel_world * v.resolution as f32 / side as f32,
                    if v.orthographic { 1.0 } else { 0.0 },
                ],
                // w: last frame's first entry + 1 when its pages may be kept (set per frame).
                table: [first, finest, side, 0],
            });
            first = first.saturating_add(table_entries(side));
        }
        fit.faces = faces.len();
        fit.table_entries = first;
        Self {
            views,
            light_views,
            faces,
            fit,
        }
    }

    /// GPU records of the scene's lights, their shadow views pointing at the faces.
    pub fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        scene
            .lights
            .iter()
            .zip(&self.light_views)
            .map(|(l, &(first, n))| {
                LightData::new(l, first, &self.views[first as usize..(first + n) as usize])
            })
            .collect()
    }
}

/// Counters of one frame of virtual shadow maps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct VirtualStats {
    /// The plan's layout.
    pub fit: VirtualFit,
    /// Pages needed per level (level 0 = one page per face).
    pub needed: [u32; MAX_LEVELS as usize],
    /// Pages resident this frame (kept + drawn).
    pub resident: u32,
    /// Resident pages kept, with their depth, from the last frame (caching).
    pub kept: u32,
    /// Pages drawn this frame.
    pub drawn: u32,
    /// Needed pages that did not fit the pool (their samples used a coarser level).
    pub denied: u32,
    /// Faces left without shadows because not even their level-0 page fitted (only when the
    /// pool has fewer pages than faces in use; the faces of the lowest-numbered lights get
    /// the pool's pages).
    pub unshadowed_faces: u32,
    /// Pages the pool holds.
    pub pool_pages: u32,
    /// Pool side in texels.
    pub pool_side: u32,
    /// Bytes of the pool texture.
    pub pool_bytes: u64,
    /// Bytes of the page table.
    pub table_bytes: u64,
}

impl VirtualStats {
    /// Pages needed over all levels.
    pub fn needed_total(&self) -> u32 {
        self.needed.iter().sum()
    }
}

/// The pool side for a byte budget: the largest power of two whose square of 4-byte texels
/// fits, at least one page, at most `max_dim`.
pub fn pool_side(bytes: u64, max_dim: u32) -> u32 {
    let texels = (bytes / 4).max(PAGE_SIZE as u64 * PAGE_SIZE as u64);
    let side = 1u64 << ((64 - texels.leading_zeros() - 1) / 2);
    let max = 1u64 << (31 - max_dim.max(PAGE_SIZE).leading_zeros());
    side.clamp(PAGE_SIZE as u64, max) as u32
}

/// What the virtual shadow maps read from the rest of the frame.
pub struct VsmInputs<'a> {
    /// `FrameUniforms`.
    pub frame: &'a wgpu::Buffer,
    /// `array<LightData>`.
    pub lights: &'a wgpu::Buffer,
    /// G-buffer.
    pub gbuffer: &'a GBuffer,
    /// Light clusters.
    pub clusters: &'a LightClusters,
    /// Scene instances (`array<InstanceData>`).
    pub instances: &'a wgpu::Buffer,
    /// World-space caster geometry.
    pub casters: &'a CasterGeometry,
}

/// The virtual shadow maps' plan, pool, page table and pipelines.
pub struct VirtualShadows {
    /// This frame's faces.
    pub plan: VirtualPlan,
    options: VirtualOptions,
    shadow: ShadowOptions,
    /// The page pool: `Depth32Float`, `pool_side`².
    pub pool: wgpu::Texture,
    /// Depth view of the pool.
    pub pool_view: wgpu::TextureView,
    pool_side: u32,
    pool_pages: u32,
    viewport: (u32, u32),
    compact: bool,
    uniforms: wgpu::Buffer,
    faces: wgpu::Buffer,
    table: wgpu::Buffer,
    prev_table: wgpu::Buffer,
    scratch: wgpu::Buffer,
    counters: wgpu::Buffer,
    readback: wgpu::Buffer,
    page_views: wgpu::Buffer,
    /// Page-table entries of the last recorded frame (what `prev_table` receives).
    prev_entries: u32,
    /// The faces of the last recorded frame; empty when nothing may be kept.
    last: std::collections::HashMap<(usize, ViewKind), LastFace>,
    /// Caster bounding spheres moved since the last frame (old and new).
    moves: Vec<[(Vec3, f32); 2]>,
    rounds: Vec<Round>,
    rounds_storage: wgpu::Buffer,
    round_uniforms: wgpu::Buffer,
    round_stride: u64,
    args: wgpu::Buffer,
    commands: wgpu::Buffer,
    command_count: wgpu::Buffer,
    mark: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    retain: wgpu::ComputePipeline,
    free: wgpu::ComputePipeline,
    count_new: wgpu::ComputePipeline,
    scan_new: wgpu::ComputePipeline,
    alloc_new: wgpu::ComputePipeline,
    args_pipeline: wgpu::ComputePipeline,
    cull: wgpu::ComputePipeline,
    draw: wgpu::RenderPipeline,
    /// Rounds of alpha-tested clusters (`fs_alpha`).
    draw_masked: wgpu::RenderPipeline,
    clear: wgpu::RenderPipeline,
    mark_layout: wgpu::BindGroupLayout,
    alloc_layout: wgpu::BindGroupLayout,
    cull_layout: wgpu::BindGroupLayout,
    draw_layout: wgpu::BindGroupLayout,
    clear_layout: wgpu::BindGroupLayout,
    groups: Option<Groups>,
}

/// A face of the last recorded frame, by (light, view kind).
#[derive(Clone, Copy, Debug)]
struct LastFace {
    view_proj: [[f32; 4]; 4],
    side: u32,
    first: u32,
}

struct Groups {
    mark: wgpu::BindGroup,
    alloc: wgpu::BindGroup,
    cull: wgpu::BindGroup,
    draw: wgpu::BindGroup,
    clear: wgpu::BindGroup,
}

const ROUND_SIZE: u64 = std::mem::size_of::<VsmRound>() as u64;

fn buffer(ctx: &GpuContext, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(16),
        usage,
        mapped_at_creation: false,
    })
}

impl VirtualShadows {
    /// Plans the faces of `scene` and builds the pool and pipelines. Needs `CLIP_DISTANCES`
    /// and indirect execution (every adapter the project targets has both); compacts the
    /// page-render commands where `MULTI_DRAW_INDIRECT_COUNT` exists.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        (width, height): (u32, u32),
        options: VirtualOptions,
        shadow: ShadowOptions,
        casters: &CasterGeometry,
    ) -> Result<Self, RenderError> {
        crate::techniques::require_clip_distances(ctx, "virtual")?;
        crate::techniques::require_indirect(
            ctx,
            "virtual",
            "indirect dispatches and draws (to allocate and draw its pages)",
            "use technique traditional",
        )?;
        if !(options.lod.is_finite() && options.lod > 0.0) {
            return Err(RenderError::InvalidOption(format!(
                "the virtual maps' level-of-detail scale must be a positive number, not {}",
                options.lod
            )));
        }
        let device = &ctx.device;
        let limits = ctx.limits();
        let plan = VirtualPlan::new(scene, width as f32 / height as f32, height, &options);
        let pool_side = pool_side(options.pool_bytes, limits.max_texture_dimension_2d);
        let per_row = pool_side / PAGE_SIZE;
        let pool_pages = per_row * per_row;
        let pool = crate::gpu::pipelines::depth_texture(device, "vsm.pool", pool_side, 1);
        let pool_view = pool.create_view(&wgpu::TextureViewDescriptor {
            label: Some("vsm.pool.view"),
            dimension: Some(wgpu::TextureViewDimension::D2),
            ..Default::default()
        });
        let compact = ctx.has(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT);
        let max_commands = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            .min(MAX_ROUND_BYTES)
            / COMMAND_SIZE;
        let rounds = plan_rounds(
            pool_pages,
            casters.clusters.len() as u32,
            casters.first_masked_cluster,
            casters.vertices,
            max_commands,
        );
        let round_stride = (std::mem::size_of::<VsmRound>() as u64)
            .next_multiple_of(limits.min_uniform_buffer_offset_alignment as u64);
        let capacity = rounds.iter().map(Round::commands).max().unwrap_or(1);
        use wgpu::BufferUsages as U;
        let storage = U::STORAGE | U::COPY_DST;
        let uniforms = buffer(ctx, "vsm.uniforms", 48, U::UNIFORM | U::COPY_DST);
        let counters = buffer(
            ctx,
            "vsm.counters",
            COUNTERS as u64 * 4,
            storage | U::COPY_SRC,
        );
        let readback = buffer(
            ctx,
            "vsm.counters.readback",
            COUNTERS as u64 * 4,
            U::MAP_READ | U::COPY_DST,
        );
        let page_views = buffer(
            ctx,
            "vsm.page_views",
            pool_pages as u64 * std::mem::size_of::<ShadowViewData>() as u64,
            storage,
        );
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
        let args = buffer(
            ctx,
            "vsm.args",
            (3 * rounds.len() as u64 + 4) * 4,
            storage | U::INDIRECT,
        );
        let commands = buffer(
            ctx,
            "vsm.commands",
            capacity * COMMAND_SIZE,
            U::STORAGE | U::INDIRECT,
        );
        let command_count = buffer(ctx, "vsm.command_count", 4, storage | U::INDIRECT);
        // Round records (the same for every frame: rounds cover every pool page).
        let records: Vec<VsmRound> = rounds
            .iter()
            .map(|r| VsmRound {
                round: [r.first_view, r.views, r.first_cluster, r.clusters],
                counts: [
                    casters.vertices,
                    casters.cullable_triangles,
                    shadow.cull.bits(),
                    u32::from(compact),
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
        let tex =
            |binding| crate::gpu::pipelines::texture_entry(binding, wgpu::TextureSampleType::Uint, cs);
        let mark_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.mark_layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, cs),
                crate::gpu::pipelines::storage_entry(1, cs),
                tex(2),
                tex(3),
                crate::gpu::pipelines::uniform_entry(4, cs),
                crate::gpu::pipelines::storage_entry(5, cs),
                crate::gpu::pipelines::storage_entry(6, cs),
                crate::gpu::pipelines::uniform_entry(7, cs),
                crate::gpu::pipelines::storage_entry(8, cs),
                crate::gpu::pipelines::storage_rw_entry(9, cs),
            ],
        );
        // The allocation passes: eight storage buffers, WebGPU's default per-stage limit.
        let alloc_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.alloc_layout",
            &[
                crate::gpu::pipelines::uniform_entry(7, cs),
                crate::gpu::pipelines::storage_entry(8, cs),
                crate::gpu::pipelines::storage_rw_entry(9, cs),
                crate::gpu::pipelines::storage_rw_entry(10, cs),
                crate::gpu::pipelines::storage_rw_entry(11, cs),
                crate::gpu::pipelines::storage_entry(12, cs),
                crate::gpu::pipelines::storage_rw_entry(13, cs),
                crate::gpu::pipelines::storage_entry(14, cs),
                crate::gpu::pipelines::storage_rw_entry(15, cs),
            ],
        );
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
                crate::gpu::pipelines::storage_entry(10, cs),
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
            &[crate::gpu::pipelines::uniform_entry(1, vs), crate::gpu::pipelines::storage_entry(2, vs)],
        );
        let pipeline_layout = |label: &str, layout: &wgpu::BindGroupLayout| {
            crate::gpu::pipelines::pipeline_layout(device, label, &[layout])
        };
        let mark_module = crate::gpu::shaders::module(device, "vsm.shader", &crate::gpu::shaders::vsm());
        let draw_module =
            crate::gpu::shaders::module(device, "vsm_draw.shader", &crate::gpu::shaders::vsm_draw());
        let mark_pl = pipeline_layout("vsm.mark_pipeline_layout", &mark_layout);
        let compute =
            |label: &str, module: &wgpu::ShaderModule, pl: &wgpu::PipelineLayout, entry| {
                crate::gpu::pipelines::compute_pipeline(device, label, pl, module, entry)
            };
        let mark = compute("vsm.mark", &mark_module, &mark_pl, "cs_mark");
        let alloc_pl = pipeline_layout("vsm.alloc_pipeline_layout", &alloc_layout);
        let count = compute("vsm.count", &mark_module, &alloc_pl, "cs_count");
        let scan = compute("vsm.scan", &mark_module, &alloc_pl, "cs_scan");
        let retain = compute("vsm.retain", &mark_module, &alloc_pl, "cs_retain");
        let free = compute("vsm.free", &mark_module, &alloc_pl, "cs_free");
        let count_new = compute("vsm.count_new", &mark_module, &alloc_pl, "cs_count_new");
        let scan_new = compute("vsm.scan_new", &mark_module, &alloc_pl, "cs_scan_new");
        let alloc_new = compute("vsm.alloc_new", &mark_module, &alloc_pl, "cs_alloc_new");
        let args_pipeline = compute("vsm.args", &mark_module, &alloc_pl, "cs_args");
        let cull_pl = pipeline_layout("vsm.cull_pipeline_layout", &cull_layout);
        let cull = compute("vsm.cull", &draw_module, &cull_pl, "cs_cull");
        let draw_pl = pipeline_layout("vsm.draw_pipeline_layout", &draw_layout);
        let draw =
            crate::techniques::depth_pipeline(device, &draw_pl, &draw_module, "vs_draw", &[]);
        let draw_masked = crate::techniques::masked_depth_pipeline(
            device,
            &draw_pl,
            &draw_module,
            "vs_draw_masked",
            &[],
            None,
        );
        let clear_pl = pipeline_layout("vsm.clear_pipeline_layout", &clear_layout);
        let clear = crate::techniques::clear_pipeline(device, &clear_pl, &draw_module, "vs_clear");
        let mut this = Self {
            plan,
            options,
            shadow,
            pool,
            pool_view,
            pool_side,
            pool_pages,
            viewport: (width, height),
            compact,
            uniforms,
            faces: buffer(
                ctx,
                "vsm.faces",
                std::mem::size_of::<VirtualFace>() as u64,
                storage,
            ),
            table: buffer(ctx, "vsm.table", 16, storage | U::COPY_SRC),
            prev_table: buffer(ctx, "vsm.prev_table", 16, storage),
            scratch: buffer(ctx, "vsm.scratch", 16, storage),
            counters,
            readback,
            page_views,
            prev_entries: 0,
            last: Default::default(),
            moves: Vec::new(),
            rounds,
            rounds_storage,
            round_uniforms,
            round_stride,
            args,
            commands,
            command_count,
            mark,
            count,
            scan,
            retain,
            free,
            count_new,
            scan_new,
            alloc_new,
            args_pipeline,
            cull,
            draw,
            draw_masked,
            clear,
            mark_layout,
            alloc_layout,
            cull_layout,
            draw_layout,
            clear_layout,
            groups: None,
        };
        this.write_plan(ctx)?;
        Ok(this)
    }

    /// Side of the pool texture in texels.
    pub fn pool_side(&self) -> u32 {
        self.pool_side
    }

    /// The options in use.
    pub fn options(&self) -> &VirtualOptions {
        &self.options
    }

    /// The uniform buffer (`VsmUniforms`) the lookups bind.
    pub fn uniforms(&self) -> &wgpu::Buffer {
        &self.uniforms
    }

    /// The faces (`array<VirtualFace>`) the lookups bind.
    pub fn faces(&self) -> &wgpu::Buffer {
        &self.faces
    }

    /// The page table (`array<u32>`) the lookups bind.
    pub fn table(&self) -> &wgpu::Buffer {
        &self.table
    }

    /// Re-plans the faces for a changed frame (camera, lights); buffers are rewritten in
    /// place and replaced only when they must grow. Returns true if a buffer the lookups bind
    /// was replaced.
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        (width, height): (u32, u32),
    ) -> Result<bool, RenderError> {
        self.plan = VirtualPlan::new(scene, width as f32 / height as f32, height, &self.options);
        let replaced = self.write_plan(ctx)?;
        if replaced {
            self.groups = None;
        }
        Ok(replaced)
    }

    fn write_plan(&mut self, ctx: &GpuContext) -> Result<bool, RenderError> {
        let face_bytes: &[u8] = bytemuck::cast_slice(&self.plan.faces);
        // At least one record: shaders declare the array with a minimum of one element.
        let face_size = std::mem::size_of::<VirtualFace>() as u64;
        let mut replaced = crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.faces,
            (face_bytes.len() as u64).max(face_size),
            "virtual faces",
        )?;
        let entries = self.plan.fit.table_entries.max(1) as u64;
        if crate::gpu::buffers::grow_buffer(ctx, &mut self.table, entries * 4, "virtual page table")? {
            // Last frame's table went with the old buffer: keep no pages this time.
            self.last.clear();
            replaced = true;
        }
        let table_size = self.table.size();
        replaced |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.prev_table,
            table_size,
            "virtual previous page table",
        )?;
        let blocks = entries.div_ceil(ALLOC_BLOCK);
        replaced |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.scratch,
            (2 * self.pool_pages as u64 + (1 + MAX_LEVELS as u64) * blocks) * 4,
            "virtual allocation scratch",
        )?;
        if !face_bytes.is_empty() {
            ctx.queue.write_buffer(&self.faces, 0, face_bytes);
        }
        let data = VsmUniforms {
            pool: [
                self.pool_side,
                self.pool_side / PAGE_SIZE,
                PAGE_SIZE,
                self.pool_pages,
            ],
            counts: [
                self.plan.faces.len() as u32,
                self.plan.fit.table_entries,
                u32::from(self.options.back_facing),
                0,
            ],
            lod: [self.options.lod, 0.0, 0.0, 0.0],
        };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&data));
        Ok(replaced)
    }

    /// Builds the bind groups for `inputs` (after creation or whenever a buffer they hold was
    /// replaced).
    pub fn bind(&mut self, ctx: &GpuContext, inputs: &VsmInputs<'_>) {
        let device = &ctx.device;
        let round = |binding: u32| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &self.round_uniforms,
                offset: 0,
                size: wgpu::BufferSize::new(std::mem::size_of::<VsmRound>() as u64),
            }),
        };
        let pv = inputs.gbuffer.position.create_view(&Default::default());
        let nv = inputs.gbuffer.normal.create_view(&Default::default());
        let mark = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.mark_group"),
            layout: &self.mark_layout,
            entries: &[
                whole_entry(0, inputs.frame),
                whole_entry(1, inputs.lights),
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&pv),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&nv),
                },
                whole_entry(4, &inputs.clusters.uniforms),
                whole_entry(5, &inputs.clusters.slots),
                whole_entry(6, &inputs.clusters.masks),
                whole_entry(7, &self.uniforms),
                whole_entry(8, &self.faces),
                whole_entry(9, &self.table),
            ],
        });
        let alloc = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.alloc_group"),
            layout: &self.alloc_layout,
            entries: &[
                whole_entry(7, &self.uniforms),
                whole_entry(8, &self.faces),
                whole_entry(9, &self.table),
                whole_entry(10, &self.counters),
                whole_entry(11, &self.page_views),
                whole_entry(12, &self.rounds_storage),
                whole_entry(13, &self.args),
                whole_entry(14, &self.prev_table),
                whole_entry(15, &self.scratch),
            ],
        });
        let casters = inputs.casters;
        let cull = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.cull_group"),
            layout: &self.cull_layout,
            entries: &[
                round(0),
                whole_entry(1, &self.uniforms),
                whole_entry(2, &self.page_views),
                whole_entry(4, &self.faces),
                whole_entry(5, &casters.cluster_buffer),
                whole_entry(6, &casters.cluster_bounds),
                whole_entry(7, inputs.instances),
                whole_entry(8, &self.commands),
                whole_entry(9, &self.command_count),
                whole_entry(10, &self.counters),
            ],
        });
        let draw = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.draw_group"),
            layout: &self.draw_layout,
            entries: &[
                round(0),
                whole_entry(1, &self.uniforms),
                whole_entry(2, &self.page_views),
                whole_entry(11, &casters.world),
                whole_entry(13, &casters.corners),
            ],
        });
        let clear = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.clear_group"),
            layout: &self.clear_layout,
            entries: &[
                whole_entry(1, &self.uniforms),
                whole_entry(2, &self.page_views),
            ],
        });
        self.groups = Some(Groups {
            mark,
            alloc,
            cull,
            draw,
            clear,
        });
    }

    /// True once [`VirtualShadows::bind`] has run since the last buffer replacement.
    pub fn bound(&self) -> bool {
        self.groups.is_some()
    }

    /// Notes that a shadow caster's bounding sphere moved from `old` to `new`: pages of faces
    /// that see either are not kept at the next frame.
    pub fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.moves.push([old, new]);
    }

    /// Keeps no page at the next frame (caster geometry or culling decisions changed).
    pub fn forget_pages(&mut self) {
        self.last.clear();
    }

    /// Records one frame: the caster transform, page marking and allocation (`pages_span`),
    /// then the page clear and render rounds (`span`). Needs the G-buffer and the clusters of
    /// this frame recorded before it. With `keep`, pages resident last frame in faces whose
    /// view, virtual side and casters did not change keep their depth and are not redrawn.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        casters: &CasterGeometry,
        timer: &GpuTimer,
        pages_span: Option<Span>,
        span: Option<Span>,
        keep: bool,
    ) {
        if self.groups.is_none() {
            return;
        }
        // Which faces may keep last frame's pages: `table.w` = their first entry then + 1.
        let keep = keep && !casters.skinned();
        let mut faces = self.plan.faces.clone();
        for (face, view) in faces.iter_mut().zip(&self.plan.views) {
            face.table[3] = 0;
            let Some(last) = self.last.get(&(view.light, view.kind)) else {
                continue;
            };
            let touched = self
                .moves
                .iter()
                .flatten()
                .any(|&(c, r)| view.sphere_visible(c, r));
            if keep && last.view_proj == face.view_proj && last.side == face.table[2] && !touched {
                face.table[3] = last.first + 1;
            }
        }
        if !faces.is_empty() {
            ctx.queue
                .write_buffer(&self.faces, 0, bytemuck::cast_slice(&faces));
        }
        self.last = faces
            .iter()
            .zip(&self.plan.views)
            .map(|(f, v)| {
                let last = LastFace {
                    view_proj: f.view_proj,
                    side: f.table[2],
                    first: f.table[0],
                };
                ((v.light, v.kind), last)
            })
            .collect();
        self.moves.clear();
        self.record_passes(encoder, casters, timer, pages_span, span);
        self.prev_entries = self.plan.fit.table_entries;
    }

    fn record_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        casters: &CasterGeometry,
        timer: &GpuTimer,
        pages_span: Option<Span>,
        span: Option<Span>,
    ) {
        let Some(g) = &self.groups else {
            return;
        };
        let (w, h) = self.viewport;
        encoder.push_debug_group("virtual shadow maps");
        if self.prev_entries > 0 {
            // Last frame's table, for the pages this frame keeps.
            encoder.copy_buffer_to_buffer(
                &self.table,
                0,
                &self.prev_table,
                0,
                self.prev_entries as u64 * 4,
            );
        }
        encoder.clear_buffer(&self.table, 0, None);
        encoder.clear_buffer(&self.counters, 0, None);
        encoder.clear_buffer(&self.scratch, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vsm.pages"),
                timestamp_writes: timer.compute_writes(pages_span, true, true),
            });
            casters.record(&mut pass, true);
            // One workgroup per block of page-table entries (2D past 65,535 blocks).
            let groups_2d = |n: u64| (n.min(65535) as u32, n.div_ceil(65535) as u32);
            let entries = self.plan.fit.table_entries as u64;
            let (bx, by) = groups_2d(entries.div_ceil(ALLOC_BLOCK));
            let (ex, ey) = groups_2d(entries.div_ceil(64));
            if !self.plan.faces.is_empty() {
                pass.set_bind_group(0, &g.mark, &[]);
                pass.set_pipeline(&self.mark);
                pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
                pass.set_bind_group(0, &g.alloc, &[]);
                for (pipeline, (x, y)) in [
                    (&self.count, (bx, by)),
                    (&self.scan, (1, 1)),
                    (&self.retain, (ex, ey)),
                    (&self.free, (1, 1)),
                    (&self.count_new, (bx, by)),
                    (&self.scan_new, (1, 1)),
                    (&self.alloc_new, (bx, by)),
                ] {
                    pass.set_pipeline(pipeline);
                    pass.dispatch_workgroups(x, y, 1);
                }
            }
            pass.set_bind_group(0, &g.alloc, &[]);
            pass.set_pipeline(&self.args_pipeline);
            pass.dispatch_workgroups(1, 1, 1);
        }
        let clear_args = 3 * self.rounds.len() as u64 * 4;
        if self.rounds.is_empty() {
            // No casters: the drawn pages are cleared and stay empty.
            let mut pass = self.pool_pass(encoder, timer.render_writes(span, true, true));
            pass.set_pipeline(&self.clear);
            pass.set_bind_group(0, &g.clear, &[]);
            pass.draw_indirect(&self.args, clear_args);
        }
        let corners = casters.corners.slice(..);
        for (k, r) in self.rounds.iter().enumerate() {
            let offset = [(k as u64 * self.round_stride) as u32];
            let first = k == 0;
            let last = k + 1 == self.rounds.len();
            if self.compact {
                encoder.clear_buffer(&self.command_count, 0, None);
            }
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("vsm.cull"),
                    timestamp_writes: timer.compute_writes(span, first, false),
                });
                pass.set_pipeline(&self.cull);
                pass.set_bind_group(0, &g.cull, &offset);
                if self.compact {
                    pass.dispatch_workgroups_indirect(&self.args, 3 * k as u64 * 4);
                } else {
                    // Every slot's command is written (zero for slots past the last page).
                    pass.dispatch_workgroups(r.clusters.div_ceil(64), r.views, 1);
                }
            }
            let mut pass = self.pool_pass(encoder, timer.render_writes(span, false, last));
            if first {
                pass.set_pipeline(&self.clear);
                pass.set_bind_group(0, &g.clear, &[]);
                pass.draw_indirect(&self.args, clear_args);
            }
            if self.shadow.discard_raster {
                pass.set_scissor_rect(0, 0, 0, 0);
            }
            pass.set_pipeline(if r.masked {
                &self.draw_masked
            } else {
                &self.draw
            });
            pass.set_bind_group(0, &g.draw, &offset);
            pass.set_index_buffer(corners, wgpu::IndexFormat::Uint32);
            let max = r.commands() as u32;
            if self.compact {
                pass.multi_draw_indexed_indirect_count(
                    &self.commands,
                    0,
                    &self.command_count,
                    0,
                    max,
                );
            } else {
                pass.multi_draw_indexed_indirect(&self.commands, 0, max);
            }
            // See TileClear::reset_clip_distances: the OpenGL backend leaks clip-distance
            // enables past the pass unless a pipeline without them is set last.
            pass.set_pipeline(&self.clear);
        }
        encoder.copy_buffer_to_buffer(&self.counters, 0, &self.readback, 0, COUNTERS as u64 * 4);
        encoder.pop_debug_group();
    }

    fn pool_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("vsm.draw"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.pool_view,
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

    /// The counters of the last recorded frame (after its submission).
    pub fn read_stats(&self, ctx: &GpuContext) -> Result<VirtualStats, RenderError> {
        let bytes = crate::gpu::readback::map_read(ctx, &self.readback, 0..COUNTERS as u64 * 4)?;
        let c: &[u32] = bytemuck::cast_slice(&bytes);
        let mut needed = [0u32; MAX_LEVELS as usize];
        needed.copy_from_slice(&c[..MAX_LEVELS as usize]);
        Ok(VirtualStats {
            fit: self.plan.fit,
            needed,
            resident: c[9] + c[17],
            kept: c[9],
            drawn: c[17],
            denied: c[16],
            unshadowed_faces: c[18],
            pool_pages: self.pool_pages,
            pool_side: self.pool_side,
            pool_bytes: self.pool_side as u64 * self.pool_side as u64 * 4,
            table_bytes: self.plan.fit.table_entries as u64 * 4,
        })
    }

    /// The plan's per-light records for the lights buffer.
    pub fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        self.plan.light_data(scene)
    }
}

/// Virtual shadow maps as a frame's [`ShadowSource`]: an empty shadow plan (the faces are in
/// [`VirtualPlan`]), the caster geometry and the page pool, which is the output.
pub struct VirtualSource {
    table: ViewTable,
    maps: VirtualShadows,
    size: (u32, u32),
    /// Keep the pages of unchanged faces between frames.
    cache: bool,
}

impl VirtualSource {
    pub(crate) fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        settings: &RenderSettings,
    ) -> Result<Self, RenderError> {
        if settings.point_shadows != PointShadows::default() {
            return Err(RenderError::Unsupported(
                "technique virtual pages cube-map point shadows only; use cube point shadows"
                    .into(),
            ));
        }
        let table = ViewTable::new(
            ctx,
            scene,
            gpu,
            ShadowPlan::none(scene.lights.len()),
            settings,
        )?;
        let options = VirtualOptions {
            back_facing: settings.visibility,
            ..settings.virtual_maps
        };
        let size = (settings.width, settings.height);
        let maps = VirtualShadows::new(ctx, scene, size, options, settings.shadow, &table.casters)?;
        Ok(Self {
            table,
            maps,
            size,
            cache: settings.cache_shadows,
        })
    }
}

impl ShadowSource for VirtualSource {
    fn technique(&self) -> Technique {
        Technique::Virtual
    }

    fn plan(&self) -> &ShadowPlan {
        &self.table.plan
    }

    fn atlas(&self) -> &ShadowAtlas {
        &self.table.views
    }

    fn casters(&self) -> &CasterGeometry {
        &self.table.casters
    }

    fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        self.maps.light_data(scene)
    }

    fn update(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), RenderError> {
        let plan = ShadowPlan::none(scene.lights.len());
        if self.table.update(ctx, scene, plan)? {
            self.maps.forget_pages();
        }
        self.maps.update(ctx, scene, self.size)?;
        Ok(())
    }

    fn bind(&mut self, ctx: &GpuContext, inputs: &SourceInputs<'_>) -> Result<(), RenderError> {
        self.maps.bind(
            ctx,
            &VsmInputs {
                frame: inputs.frame,
                lights: inputs.lights,
                gbuffer: inputs.gbuffer,
                clusters: inputs.clusters,
                instances: inputs.instances,
                casters: &self.table.casters,
            },
        );
        Ok(())
    }

    fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.maps.note_moved(old, new);
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        _scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> ShadowStats {
        let pages_span = timer.span(crate::gpu::timing::Stage::Pages);
        let span = timer.span(crate::gpu::timing::Stage::Shadows);
        self.maps.record(
            ctx,
            encoder,
            &self.table.casters,
            timer,
            pages_span,
            span,
            self.cache,
        );
        ShadowStats::default()
    }

    fn output(&self) -> ShadowOutput<'_> {
        ShadowOutput::Pages {
            pages: PagePool {
                pool: &self.maps.pool_view,
                side: self.maps.pool_side(),
                uniforms: self.maps.uniforms(),
                faces: self.maps.faces(),
                table: self.maps.table(),
            },
            views: &self.table.views,
        }
    }

    fn read_atlas(&self, _ctx: &GpuContext) -> Result<Vec<f32>, RenderError> {
        Err(RenderError::NoAtlas {
            technique: crate::settings::Technique::Virtual,
            detail: crate::settings::VIRTUAL_NO_ATLAS.into(),
        })
    }

    fn virtual_plan(&self) -> Option<&VirtualPlan> {
        Some(&self.maps.plan)
    }

    fn read_virtual_stats(&self, ctx: &GpuContext) -> Result<Option<VirtualStats>, RenderError> {
        self.maps.read_stats(ctx).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_entries_count_every_level() {
        assert_eq!(table_entries(128), 1);
        assert_eq!(table_entries(256), 1 + 4);
        assert_eq!(table_entries(512), 1 + 4 + 16);
        assert_eq!(
            table_entries(16384),
            (0..8).map(|l| 1u32 << (2 * l)).sum::<u32>()
        );
    }

    #[test]
    fn pool_side_is_the_largest_square_within_budget() {
        assert_eq!(pool_side(256 << 20, 16384), 8192);
        assert_eq!(pool_side((256 << 20) - 1, 16384), 4096);
        assert_eq!(pool_side(1 << 30, 8192), 8192);
        assert_eq!(pool_side(0, 16384), PAGE_SIZE);
        assert_eq!(pool_side(64 << 20, 16384), 4096);
    }
}
