//! The page table and pool of virtual shadow maps and their per-frame passes (steps 1 and 2 of
//! [`crate::shadows::vsm`], `vsm.wgsl`): marking the pages the samples need, allocating pool
//! pages (keeping last frame's where the face did not change), writing the indirect arguments,
//! then the page rendering of [`super::draw`].

use glam::{Mat4, Vec3};
use manyshadows_scene::light_space::ViewKind;
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::GBuffer;
use crate::gpu::buffers::buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::pipelines::whole_entry;
use crate::gpu::shaders::{compose, COMMON};
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu::types::{LightData, ShadowViewData, VirtualFace, VsmUniforms};
use crate::gpu_scene::casters::CasterGeometry;
use crate::shadows::lookup::{PARABOLOID, SHADOW_LOOKUP};
use crate::shadows::options::ShadowOptions;
use crate::shadows::vsm::draw::{PageBuffers, PageDraw};
use crate::shadows::vsm::plan::VSM_COMMON;
use crate::shadows::vsm::plan::{
    pool_side, TileMarking, VirtualOptions, VirtualPlan, VirtualStats, MAX_LEVELS, NOTHING_MOVED,
    PAGE_SIZE,
};

/// Page marking, allocation and indirect arguments.
pub(crate) fn shader() -> String {
    compose(&[
        COMMON,
        PARABOLOID,
        SHADOW_LOOKUP,
        VSM_COMMON,
        &super::draw::group_decl(),
        include_str!("vsm.wgsl"),
    ])
}

/// Page-table entries per allocation thread (`BLOCK` in `vsm.wgsl`).
const ALLOC_BLOCK: u64 = 32;
/// Words of the page table per entry: the entry, its receiver depth key and its cell mask.
const TABLE_WORDS: u64 = 3;
/// Pixels per side of a tile of the tile marking (`MARK_TILE` in `vsm.wgsl`).
const MARK_TILE: u32 = 4;
/// Room for the tile marking's jobs, in words per tile of the screen (a job is 2 words and 3
/// per light handed on; a tile whose job does not fit does it in its own thread: the same
/// pages, slower).
const JOB_WORDS_PER_TILE: u64 = 12;

/// Bytes of the tile marking's hand-off list for a `width` x `height` screen (`mark_list` in
/// `vsm.wgsl`): counts, a word per tile for tiles handed on whole and one for jobs' offsets,
/// then room for the jobs, as much of it as `limit` (the device's binding limit) leaves. The
/// fixed part, 8 bytes per 4x4-pixel tile, fits every device the renderer accepts (2 MiB at
/// its 2048² texture limit against 4 MiB bindings).
fn mark_list_bytes(width: u32, height: u32, limit: u64) -> u64 {
    let tiles = width.div_ceil(MARK_TILE) as u64 * height.div_ceil(MARK_TILE) as u64;
    let fixed = 4 * (8 + 2 * tiles);
    // (16 bytes spare: the buffer is rounded up to a multiple of 16.)
    let room = (4 * tiles * JOB_WORDS_PER_TILE).min(limit.saturating_sub(fixed + 16) / 16 * 16);
    fixed + room
}

/// Words of the counters buffer (see `vsm.wgsl`).
const COUNTERS: usize = 33;

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
    /// Depth view of the pool.
    pub pool_view: wgpu::TextureView,
    pool_side: u32,
    pool_pages: u32,
    /// Pages the draw can take per frame ([`page_slots`]).
    slots: u32,
    shadow: ShadowOptions,
    viewport: (u32, u32),
    uniforms: wgpu::Buffer,
    faces: wgpu::Buffer,
    table: wgpu::Buffer,
    /// Last frame's table, for the pages a frame keeps: allocated only with caching
    /// ([`Self::new`]'s `keep_pages`), otherwise a 16-byte stand-in for its binding.
    prev_table: wgpu::Buffer,
    keep_pages: bool,
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
    /// What the marking depends on besides the G-buffer under moved casters: the camera, the
    /// lights and the non-casting instances, as of the last [`Self::update`].
    key: SceneKey,
    /// Bumped whenever `key` changes.
    key_gen: u64,
    /// `key_gen` of the last recorded frame (its table holds that state's needs).
    marked_gen: u64,
    /// Camera world → clip, for the screen rectangle of moved casters.
    camera: Mat4,
    args: wgpu::Buffer,
    /// The (tile, light) pairs the tile marking hands on to per-pixel marking, and their
    /// dispatch arguments (`mark_list`, `mark_args` in `vsm.wgsl`).
    mark_list: wgpu::Buffer,
    mark_args: wgpu::Buffer,
    /// [`VirtualOptions::tile_marking`], unless the device cannot hold the hand-off list.
    tile_marking: bool,
    mark: wgpu::ComputePipeline,
    mark_tiles: wgpu::ComputePipeline,
    mark_pixels: wgpu::ComputePipeline,
    mark_args_pipeline: wgpu::ComputePipeline,
    carry: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
    retain: wgpu::ComputePipeline,
    free: wgpu::ComputePipeline,
    count_new: wgpu::ComputePipeline,
    scan_new: wgpu::ComputePipeline,
    alloc_new: wgpu::ComputePipeline,
    args_pipeline: wgpu::ComputePipeline,
    mark_layout: wgpu::BindGroupLayout,
    alloc_layout: wgpu::BindGroupLayout,
    mark_args_layout: wgpu::BindGroupLayout,
    groups: Option<Groups>,
    /// The page rendering: rounds, command buffers, pipelines.
    draw: PageDraw,
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
    mark_args: wgpu::BindGroup,
}

impl VirtualShadows {
    /// Plans the faces of `scene` and builds the pool and pipelines. Needs `CLIP_DISTANCES`
    /// and indirect execution (every adapter the project targets has both); compacts the
    /// page-render commands where `MULTI_DRAW_INDIRECT_COUNT` exists. With `keep_pages`
    /// (caching) it also keeps last frame's page table, as large as the table, for the
    /// pages a frame keeps; without, frames never keep pages.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        (width, height): (u32, u32),
        options: VirtualOptions,
        shadow: ShadowOptions,
        casters: &CasterGeometry,
        keep_pages: bool,
    ) -> Result<Self, RenderError> {
        // `RenderSettings::validate` checked the options' ranges.
        debug_assert!(options.lod.is_finite() && options.lod > 0.0);
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
        let slots = page_slots(plan.fit.faces, pool_pages);
        // The tile marking's hand-off list, where the device's bindings hold it.
        let binding_limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            / 16
            * 16;
        let mark_list = mark_list_bytes(width, height, binding_limit);
        let tile_marking = options.tile_marking && mark_list <= binding_limit;
        let draw = PageDraw::new(
            ctx,
            slots,
            casters,
            shadow,
            options.group_cull,
            options.expand_bytes,
        );
        use wgpu::BufferUsages as U;
        let storage = U::STORAGE | U::COPY_DST;
        let uniforms = buffer(ctx, "vsm.uniforms", 64, U::UNIFORM | U::COPY_DST);
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
        let (page_views, args) = draw_buffers(ctx, slots, &draw);
        let cs = wgpu::ShaderStages::COMPUTE;
        let tex = |binding| {
            crate::gpu::pipelines::texture_entry(binding, wgpu::TextureSampleType::Uint, cs)
        };
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
                crate::gpu::pipelines::storage_rw_entry(16, cs),
            ],
        );
        let mark_args_layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "vsm.mark_args_layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, cs),
                crate::gpu::pipelines::storage_rw_entry(10, cs),
                crate::gpu::pipelines::storage_rw_entry(16, cs),
                crate::gpu::pipelines::storage_rw_entry(17, cs),
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
        let pipeline_layout = |label: &str, layout: &wgpu::BindGroupLayout| {
            crate::gpu::pipelines::pipeline_layout(device, label, &[layout])
        };
        let mark_module = crate::gpu::shaders::module(device, "vsm.shader", &shader());
        let mark_pl = pipeline_layout("vsm.mark_pipeline_layout", &mark_layout);
        let compute =
            |label: &str, module: &wgpu::ShaderModule, pl: &wgpu::PipelineLayout, entry| {
                crate::gpu::pipelines::compute_pipeline(device, label, pl, module, entry)
            };
        let mark = compute("vsm.mark", &mark_module, &mark_pl, "cs_mark");
        let mark_tiles = compute("vsm.mark_tiles", &mark_module, &mark_pl, "cs_mark_tiles");
        let mark_pixels = compute("vsm.mark_pixels", &mark_module, &mark_pl, "cs_mark_pixels");
        let mark_args_pl = pipeline_layout("vsm.mark_args_pipeline_layout", &mark_args_layout);
        let mark_args_pipeline =
            compute("vsm.mark_args", &mark_module, &mark_args_pl, "cs_mark_args");
        let alloc_pl = pipeline_layout("vsm.alloc_pipeline_layout", &alloc_layout);
        let count = compute("vsm.count", &mark_module, &alloc_pl, "cs_count");
        let carry = compute("vsm.carry", &mark_module, &alloc_pl, "cs_carry");
        let retain = compute("vsm.retain", &mark_module, &alloc_pl, "cs_retain");
        let free = compute("vsm.free", &mark_module, &alloc_pl, "cs_free");
        let count_new = compute("vsm.count_new", &mark_module, &alloc_pl, "cs_count_new");
        let scan_new = compute("vsm.scan_new", &mark_module, &alloc_pl, "cs_scan_new");
        let alloc_new = compute("vsm.alloc_new", &mark_module, &alloc_pl, "cs_alloc_new");
        let args_pipeline = compute("vsm.args", &mark_module, &alloc_pl, "cs_args");
        let mut this = Self {
            plan,
            options,
            pool_view,
            pool_side,
            pool_pages,
            slots,
            shadow,
            viewport: (width, height),
            uniforms,
            faces: buffer(
                ctx,
                "vsm.faces",
                std::mem::size_of::<VirtualFace>() as u64,
                storage,
            ),
            table: buffer(ctx, "vsm.table", 16, storage | U::COPY_SRC),
            prev_table: buffer(ctx, "vsm.prev_table", 16, storage),
            keep_pages,
            scratch: buffer(ctx, "vsm.scratch", 16, storage),
            counters,
            readback,
            page_views,
            prev_entries: 0,
            last: Default::default(),
            moves: Vec::new(),
            key: SceneKey::of(scene),
            key_gen: 1,
            marked_gen: 0,
            camera: camera_matrix(scene, (width, height)),
            args,
            mark_list: buffer(
                ctx,
                "vsm.mark_list",
                if tile_marking { mark_list } else { 16 },
                storage,
            ),
            tile_marking,
            mark_args: buffer(ctx, "vsm.mark_args", 12, U::STORAGE | U::INDIRECT),
            mark,
            mark_tiles,
            mark_pixels,
            mark_args_pipeline,
            carry,
            count,
            retain,
            free,
            count_new,
            scan_new,
            alloc_new,
            args_pipeline,
            mark_layout,
            alloc_layout,
            mark_args_layout,
            groups: None,
            draw,
        };
        this.write_plan(ctx)?;
        Ok(this)
    }

    /// Side of the pool texture in texels.
    pub fn pool_side(&self) -> u32 {
        self.pool_side
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
        casters: &CasterGeometry,
    ) -> Result<bool, RenderError> {
        self.plan = VirtualPlan::new(scene, width as f32 / height as f32, height, &self.options);
        // Compared in place: a caster moving every frame costs no copy of thousands of lights.
        if !self.key.matches(scene) {
            self.key = SceneKey::of(scene);
            self.key_gen += 1;
        }
        self.camera = camera_matrix(scene, (width, height));
        let mut replaced = self.write_plan(ctx)?;
        let slots = page_slots(self.plan.fit.faces, self.pool_pages).max(self.slots);
        if slots > self.slots || !self.draw.made_for(casters) {
            // More faces than the draw has page slots for (quarter pages): larger rounds; or
            // the caster layout changed.
            self.draw = PageDraw::new(
                ctx,
                slots,
                casters,
                self.shadow,
                self.options.group_cull,
                self.options.expand_bytes,
            );
            (self.page_views, self.args) = draw_buffers(ctx, slots, &self.draw);
            self.slots = slots;
            replaced = true;
        }
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
        // The entries, then as many receiver depth keys and as many cell masks (`vsm.wgsl`'s
        // receiver bounds).
        if crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.table,
            entries * TABLE_WORDS * 4,
            "virtual page table",
        )? {
            // Last frame's table went with the old buffer: keep no pages this time.
            self.last.clear();
            replaced = true;
        }
        if self.keep_pages {
            let table_size = self.table.size();
            replaced |= crate::gpu::buffers::grow_buffer(
                ctx,
                &mut self.prev_table,
                table_size,
                "virtual previous page table",
            )?;
        }
        let blocks = entries.div_ceil(ALLOC_BLOCK);
        replaced |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.scratch,
            (2 * self.pool_pages as u64 + blocks) * 4,
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
                u32::from(self.options.receiver_cull),
            ],
            lod: [0.0, 0.0, 0.0, self.options.bias_scale],
            // `record` writes it.
            prev: [0; 4],
        };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&data));
        Ok(replaced)
    }

    /// Builds the bind groups for `inputs` (after creation or whenever a buffer they hold was
    /// replaced).
    pub fn bind(&mut self, ctx: &GpuContext, inputs: &VsmInputs<'_>) {
        let device = &ctx.device;
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
                whole_entry(16, &self.mark_list),
            ],
        });
        let mark_args = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.mark_args_group"),
            layout: &self.mark_args_layout,
            entries: &[
                whole_entry(0, inputs.frame),
                whole_entry(10, &self.counters),
                whole_entry(16, &self.mark_list),
                whole_entry(17, &self.mark_args),
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
                whole_entry(12, self.draw.rounds_storage()),
                whole_entry(13, &self.args),
                whole_entry(14, &self.prev_table),
                whole_entry(15, &self.scratch),
            ],
        });
        self.draw.bind(
            ctx,
            &PageBuffers {
                uniforms: &self.uniforms,
                page_views: &self.page_views,
                faces: &self.faces,
                counters: &self.counters,
                casters: inputs.casters,
                instances: inputs.instances,
            },
        );
        self.groups = Some(Groups {
            mark,
            alloc,
            mark_args,
        });
    }

    /// Notes that a shadow caster's bounding sphere moved from `old` to `new`: the pages
    /// under either, in the faces that see them, are not kept at the next frame.
    pub fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.moves.push([old, new]);
    }

    /// Keeps no page at the next frame (caster geometry or culling decisions changed).
    pub fn forget_pages(&mut self) {
        self.last.clear();
        self.key_gen += 1;
    }

    /// Records one frame: the caster transform, page marking and allocation (`pages_span`),
    /// then the page clear and render rounds (`span`). Needs the G-buffer and the clusters of
    /// this frame recorded before it. With `keep`, pages resident last frame in faces whose
    /// view and virtual side did not change keep their depth and are not redrawn, except those
    /// under the projection of a caster that moved ([`Self::note_moved`]).
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
        // Which faces may keep last frame's pages: `table.w` = their first entry then + 1, and
        // where in them casters moved (`dirty`): only the kept pages there are drawn anew (and
        // those whose samples now reach past the receiver bound they were drawn with).
        let keep = keep && self.keep_pages && !casters.skinned();
        let mut faces = self.plan.faces.clone();
        for (face, view) in faces.iter_mut().zip(&self.plan.views) {
            face.table[3] = 0;
            face.dirty = NOTHING_MOVED;
            let Some(last) = self.last.get(&(view.light, view.kind)) else {
                continue;
            };
            if !(keep && last.view_proj == face.view_proj && last.side == face.table[2]) {
                continue;
            }
            face.table[3] = last.first + 1;
            for &(c, r) in self.moves.iter().flatten() {
                if view.sphere_visible(c, r) {
                    face.dirty = union(face.dirty, moved_rect(view.view_proj, c, r));
                }
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
        // Incremental marking: with the camera, lights and every face as last frame (only
        // casters moved), last frame's needs carry over and only the pixels the moved casters
        // may cover (old and new places) are marked again.
        let incremental = keep
            && self.marked_gen == self.key_gen
            && self.prev_entries == self.plan.fit.table_entries
            && faces.iter().all(|f| f.table[3] != 0);
        let marking = if incremental {
            let rect = self
                .moves
                .iter()
                .flatten()
                .map(|&(c, r)| screen_rect(self.camera, self.viewport, c, r))
                .reduce(|a, b| {
                    [
                        a[0].min(b[0]),
                        a[1].min(b[1]),
                        a[2].max(b[2]),
                        a[3].max(b[3]),
                    ]
                });
            Marking::Carry(rect.filter(|r| r[0] < r[2] && r[1] < r[3]))
        } else {
            Marking::Full
        };
        let origin = match marking {
            Marking::Carry(Some(r)) => [r[0] as f32, r[1] as f32],
            _ => [0.0, 0.0],
        };
        // `VsmUniforms::lod.yz`: the marking pass's first pixel; `prev.x`: where last frame's
        // table (copied by `record_passes`) keeps its receiver bounds.
        ctx.queue
            .write_buffer(&self.uniforms, 36, bytemuck::cast_slice(&origin));
        // `prev.y`: pages drawn now may be kept later, so they get room to spare (not in a
        // renderer's first frame: a single image pays nothing for it). Not when marking
        // incrementally either: carried pages' needs are the bounds they were drawn with,
        // room included, and widening those again would grow a page under a caster that moves
        // every frame until it covers the whole page.
        let spare = keep && self.prev_entries > 0 && !incremental;
        ctx.queue.write_buffer(
            &self.uniforms,
            48,
            bytemuck::cast_slice(&[self.prev_entries, u32::from(spare)]),
        );
        self.moves.clear();
        // Last frame's table is read only where a face may keep its pages.
        let copy_prev = faces.iter().any(|f| f.table[3] != 0);
        self.record_passes(
            encoder,
            casters,
            timer,
            (pages_span, span),
            marking,
            copy_prev,
        );
        self.prev_entries = self.plan.fit.table_entries;
        self.marked_gen = self.key_gen;
    }

    fn record_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        casters: &CasterGeometry,
        timer: &GpuTimer,
        (pages_span, span): (Option<Span>, Option<Span>),
        marking: Marking,
        copy_prev: bool,
    ) {
        let Some(g) = &self.groups else {
            return;
        };
        let (w, h) = self.viewport;
        encoder.push_debug_group("virtual shadow maps");
        if self.prev_entries > 0 && copy_prev {
            // Last frame's table and its pages' receiver bounds, for the pages this frame keeps.
            encoder.copy_buffer_to_buffer(
                &self.table,
                0,
                &self.prev_table,
                0,
                self.prev_entries as u64 * TABLE_WORDS * 4,
            );
        }
        encoder.clear_buffer(&self.table, 0, None);
        encoder.clear_buffer(&self.counters, 0, None);
        encoder.clear_buffer(&self.scratch, 0, None);
        if self.tile_marking {
            // The hand-off count (the entries are written before they are read).
            encoder.clear_buffer(&self.mark_list, 0, Some(32));
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vsm.pages"),
                timestamp_writes: timer.compute_writes(pages_span, true, true),
            });
            casters.record(&mut pass, true);
            // One workgroup per block of page-table entries (2D past 65,535 blocks).
            let groups_2d = |n: u64| (n.min(65535) as u32, n.div_ceil(65535) as u32);
            let entries = self.plan.fit.table_entries as u64;
            // One thread per block (64-thread workgroups).
            let (bx, by) = groups_2d(entries.div_ceil(ALLOC_BLOCK).div_ceil(64));
            let (ex, ey) = groups_2d(entries.div_ceil(64));
            if !self.plan.faces.is_empty() {
                let rect = match marking {
                    Marking::Full => Some([0, 0, w, h]),
                    Marking::Carry(rect) => {
                        pass.set_bind_group(0, &g.alloc, &[]);
                        pass.set_pipeline(&self.carry);
                        pass.dispatch_workgroups(ex, ey, 1);
                        rect
                    }
                };
                if let Some([x0, y0, x1, y1]) = rect {
                    pass.set_bind_group(0, &g.mark, &[]);
                    if self.tile_marking {
                        // One thread per tile of MARK_TILE² pixels (workgroups of 8 x 8
                        // tiles: past the rectangle's end by up to 31 pixels, like the
                        // per-pixel pass's 7), then the jobs the tiles handed on, four per
                        // workgroup.
                        let tiles = |n: u32| n.div_ceil(MARK_TILE).div_ceil(8);
                        pass.set_pipeline(&self.mark_tiles);
                        pass.dispatch_workgroups(tiles(x1 - x0), tiles(y1 - y0), 1);
                        pass.set_bind_group(0, &g.mark_args, &[]);
                        pass.set_pipeline(&self.mark_args_pipeline);
                        pass.dispatch_workgroups(1, 1, 1);
                        pass.set_bind_group(0, &g.mark, &[]);
                        pass.set_pipeline(&self.mark_pixels);
                        pass.dispatch_workgroups_indirect(&self.mark_args, 0);
                    } else {
                        pass.set_pipeline(&self.mark);
                        pass.dispatch_workgroups((x1 - x0).div_ceil(8), (y1 - y0).div_ceil(8), 1);
                    }
                }
                pass.set_bind_group(0, &g.alloc, &[]);
                for (pipeline, (x, y)) in [
                    (&self.count, (bx, by)),
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
        self.draw
            .record(encoder, casters, timer, span, &self.args, &self.pool_view);
        encoder.copy_buffer_to_buffer(&self.counters, 0, &self.readback, 0, COUNTERS as u64 * 4);
        encoder.pop_debug_group();
    }

    /// The counters of the last recorded frame (after its submission).
    pub fn read_stats(&self, ctx: &GpuContext) -> Result<VirtualStats, RenderError> {
        let bytes = crate::gpu::readback::map_read(ctx, &self.readback, 0..COUNTERS as u64 * 4)?;
        let c: &[u32] = bytemuck::cast_slice(&bytes);
        let mut needed = [0u32; MAX_LEVELS as usize];
        needed.copy_from_slice(&c[..MAX_LEVELS as usize]);
        let mut asked = [0u32; MAX_LEVELS as usize];
        asked.copy_from_slice(&c[20..20 + MAX_LEVELS as usize]);
        Ok(VirtualStats {
            fit: self.plan.fit,
            needed,
            asked,
            faces_in_use: needed[0],
            cluster_draws: c[14],
            triangles: c[15],
            resident: c[9] + c[17],
            kept: c[9],
            drawn: c[17],
            denied: c[16],
            unshadowed_faces: c[18],
            quarter_faces: c[12] - c[13],
            pool_pages: self.pool_pages,
            pool_side: self.pool_side,
            pool_bytes: self.pool_side as u64 * self.pool_side as u64 * 4,
            table_bytes: self.plan.fit.table_entries as u64 * TABLE_WORDS * 4,
            prev_table_bytes: if self.keep_pages {
                self.plan.fit.table_entries as u64 * TABLE_WORDS * 4
            } else {
                0
            },
            tiles: TileMarking {
                empty: c[28],
                one_page: c[29],
                known_page: c[30],
                per_pixel: c[31],
                whole_tiles: c[32],
            },
        })
    }

    /// The plan's per-light records for the lights buffer.
    pub fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        self.plan.light_data(scene)
    }
}

/// The normalized-device bounds (x, y) of a sphere seen through `view_proj`: its enclosing
/// cube's eight corners projected; `None` when a corner lies behind the eye.
fn projected_bounds(view_proj: Mat4, c: Vec3, r: f32) -> Option<(glam::Vec2, glam::Vec2)> {
    let mut lo = glam::Vec2::splat(f32::INFINITY);
    let mut hi = glam::Vec2::splat(f32::NEG_INFINITY);
    for k in 0..8 {
        let corner = c + Vec3::new(
            if k & 1 == 0 { -r } else { r },
            if k & 2 == 0 { -r } else { r },
            if k & 4 == 0 { -r } else { r },
        );
        let clip = view_proj * corner.extend(1.0);
        if clip.w.is_nan() || clip.w <= 1e-6 {
            return None;
        }
        let ndc = glam::Vec2::new(clip.x, clip.y) / clip.w;
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    Some((lo, hi))
}

/// The part of a face (uv, y down, as the page table lays pages out) that a sphere may cover:
/// its projected bounds clamped to the face, the whole face when the sphere reaches behind
/// the light's eye.
fn moved_rect(view_proj: Mat4, c: Vec3, r: f32) -> [f32; 4] {
    let Some((lo, hi)) = projected_bounds(view_proj, c, r) else {
        return [0.0, 0.0, 1.0, 1.0];
    };
    // Pages are whole cells of the face: clamp to it.
    [
        (0.5 + 0.5 * lo.x).max(0.0),
        (0.5 - 0.5 * hi.y).max(0.0),
        (0.5 + 0.5 * hi.x).min(1.0),
        (0.5 - 0.5 * lo.y).min(1.0),
    ]
}

/// The smallest rectangle holding both (an empty one, min > max, holds nothing).
fn union(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    let empty = |r: [f32; 4]| r[0] > r[2] || r[1] > r[3];
    match (empty(a), empty(b)) {
        (true, _) => b,
        (_, true) => a,
        _ => [
            a[0].min(b[0]),
            a[1].min(b[1]),
            a[2].max(b[2]),
            a[3].max(b[3]),
        ],
    }
}

/// How a frame marks the pages its samples need.
#[derive(Clone, Copy, Debug)]
enum Marking {
    /// Every pixel marks.
    Full,
    /// Last frame's needs carry over; the pixels of this rectangle (x0, y0, x1, y1; none when
    /// nothing moved) mark again.
    Carry(Option<[u32; 4]>),
}

/// What page marking depends on, besides the G-buffer under moved casters.
#[derive(Clone, Debug)]
struct SceneKey {
    camera: manyshadows_scene::Camera,
    lights: Vec<manyshadows_scene::Light>,
    /// Transforms of the instances that cast no shadow (their moves are not noted as moves).
    others: Vec<Mat4>,
}

impl SceneKey {
    /// True if `scene` has this camera, these lights and these non-casting instances.
    fn matches(&self, scene: &Scene) -> bool {
        self.camera == scene.camera
            && self.lights == scene.lights
            && self.others.iter().copied().eq(scene
                .instances
                .iter()
                .filter(|i| !i.casts_shadows)
                .map(|i| i.transform))
    }

    fn of(scene: &Scene) -> Self {
        Self {
            camera: scene.camera,
            lights: scene.lights.clone(),
            others: scene
                .instances
                .iter()
                .filter(|i| !i.casts_shadows)
                .map(|i| i.transform)
                .collect(),
        }
    }
}

fn camera_matrix(scene: &Scene, (width, height): (u32, u32)) -> Mat4 {
    let cam = &scene.camera;
    cam.projection(width as f32 / height.max(1) as f32) * cam.view()
}

/// The pixels (x0, y0, x1, y1, clamped to the viewport) a sphere may cover on screen: its
/// projected bounds, one pixel wider; the whole screen when it reaches behind the camera.
fn screen_rect(view_proj: Mat4, (w, h): (u32, u32), c: Vec3, r: f32) -> [u32; 4] {
    let Some((lo, hi)) = projected_bounds(view_proj, c, r) else {
        return [0, 0, w, h];
    };
    let (w_f, h_f) = (w as f32, h as f32);
    let clamp = |v: f32, max: u32| v.clamp(0.0, max as f32) as u32;
    [
        clamp(((0.5 + 0.5 * lo.x) * w_f).floor() - 1.0, w),
        clamp(((0.5 - 0.5 * hi.y) * h_f).floor() - 1.0, h),
        clamp(((0.5 + 0.5 * hi.x) * w_f).ceil() + 1.0, w),
        clamp(((0.5 - 0.5 * lo.y) * h_f).ceil() + 1.0, h),
    ]
}

/// Page slots of the draw: one per pool page, and up to four per pool page when the plan has
/// more faces than the pool has pages (level-0 quarter pages, see `vsm.wgsl`).
fn page_slots(faces: usize, pool_pages: u32) -> u32 {
    let faces = u32::try_from(faces).unwrap_or(u32::MAX);
    pool_pages.max(faces.min(pool_pages.saturating_mul(4)))
}

/// The draw list (a view per page slot) and the indirect arguments of `draw`'s rounds.
fn draw_buffers(ctx: &GpuContext, slots: u32, draw: &PageDraw) -> (wgpu::Buffer, wgpu::Buffer) {
    use wgpu::BufferUsages as U;
    let storage = U::STORAGE | U::COPY_DST;
    let page_views = buffer(
        ctx,
        "vsm.page_views",
        slots as u64 * std::mem::size_of::<ShadowViewData>() as u64,
        storage,
    );
    let args = buffer(
        ctx,
        "vsm.args",
        (3 * draw.rounds().len() as u64 + 4) * 4,
        storage | U::INDIRECT,
    );
    (page_views, args)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_moved_sphere_marks_the_part_of_the_face_it_projects_to() {
        // An orthographic face over x, y in [-10, 10] looking down -Z.
        let vp = Mat4::orthographic_rh(-10.0, 10.0, -10.0, 10.0, 0.1, 100.0)
            * Mat4::look_at_rh(Vec3::new(0.0, 0.0, 50.0), Vec3::ZERO, Vec3::Y);
        let r = moved_rect(vp, Vec3::new(5.0, 5.0, 0.0), 1.0);
        // x 4..6 → u 0.7..0.8; y 4..6 → v (down) 0.2..0.3.
        for (got, want) in r.iter().zip([0.7, 0.2, 0.8, 0.3]) {
            assert!((got - want).abs() < 1e-5, "{r:?}");
        }
        // Behind a perspective eye: the whole face.
        let persp = Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0);
        assert_eq!(
            moved_rect(persp, Vec3::new(0.0, 0.0, 0.0), 1.0),
            [0.0, 0.0, 1.0, 1.0]
        );
        assert_eq!(union(NOTHING_MOVED, r), r);
        // The same sphere on a 100 × 100 screen: pixels 70..80 × 20..30, one pixel wider
        // (two where the float bounds round outwards).
        let px = screen_rect(vp, (100, 100), Vec3::new(5.0, 5.0, 0.0), 1.0);
        for (got, want) in px.iter().zip([69, 19, 81, 31]) {
            assert!(got.abs_diff(want) <= 1, "{px:?}");
        }
        assert!(
            px[0] < 70 && px[1] < 20 && px[2] > 80 && px[3] > 30,
            "{px:?}"
        );
        assert_eq!(
            screen_rect(persp, (100, 50), Vec3::ZERO, 1.0),
            [0, 0, 100, 50]
        );
        assert_eq!(
            union([0.0, 0.0, 0.1, 0.1], [0.5, 0.5, 0.6, 0.6]),
            [0.0, 0.0, 0.6, 0.6]
        );
    }

    /// The hand-off list: its fixed part (counts, a word per tile for whole tiles and one for
    /// job offsets) always, the jobs' room up to what the binding limit leaves; on the
    /// smallest device the renderer accepts (2048² textures, 4 MiB bindings) a full-size
    /// screen still fits.
    #[test]
    fn the_mark_list_fits_the_binding_limit() {
        let big = 1u64 << 40;
        // 1280x720: 320 x 180 tiles.
        let tiles = 320 * 180;
        assert_eq!(
            mark_list_bytes(1280, 720, big),
            4 * (8 + 2 * tiles + JOB_WORDS_PER_TILE * tiles)
        );
        let small = 4u64 << 20;
        let bytes = mark_list_bytes(2048, 2048, small);
        let fixed = 4 * (8 + 2 * 512 * 512);
        assert!(
            bytes.next_multiple_of(16) <= small && bytes > fixed,
            "{bytes}"
        );
        assert_eq!((bytes - fixed) % 16, 0);
        // A screen whose fixed part alone passes the limit: the renderer turns tiles off.
        assert!(mark_list_bytes(16384, 16384, small) > small);
    }
}
