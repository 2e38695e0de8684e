//! The page table and pool of virtual shadow maps and their per-frame passes (steps 1 and 2 of
//! [`crate::shadows::vsm`]), recorded in order after the caster transform: with caching,
//! [`super::carry`] (what the frame keeps from the last, and the carrying over of last frame's
//! needs when only casters moved); the marking, by [`super::tiles`] or per pixel
//! ([`super::mark`]); the allocation with the draw's indirect arguments ([`super::alloc`]);
//! then the page rendering of [`super::draw`]. Here live the plan, the pool, the page table
//! and the other buffers the stages share (`vsm_table.wgsl`, `TableBuffers`), and the
//! frame's counters, read back as [`VirtualStats`].

use glam::Vec3;
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::GBuffer;
use crate::gpu::buffers::buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu::types::{LightData, ShadowViewData};
use crate::gpu_scene::casters::CasterGeometry;
use crate::shadows::options::ShadowOptions;
use crate::shadows::vsm::alloc::{AllocBuffers, AllocPass, ALLOC_BLOCK};
use crate::shadows::vsm::carry::{Carried, CarryPass, Marking, PageCache};
use crate::shadows::vsm::draw::{PageBuffers, PageDraw};
use crate::shadows::vsm::mark::{MarkPass, Samples};
use crate::shadows::vsm::plan::{
    pool_side, TileMarking, VirtualOptions, VirtualPlan, VirtualStats, MAX_LEVELS, PAGE_SIZE,
};
use crate::shadows::vsm::sampled::SampledMarking;
use crate::shadows::vsm::table::{TableBuffers, COUNTERS, TABLE_WORDS};
use crate::shadows::vsm::tiles::TilePass;
use crate::shadows::vsm::types::{VirtualFace, VsmUniforms};

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
    /// The (pixel, light) pairs the sampled lights ask about (`sampled::pages`): where given,
    /// only their pages are marked.
    pub page_wants: Option<&'a wgpu::Buffer>,
}

/// The virtual shadow maps' plan, pool, page table and page passes.
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
    args: wgpu::Buffer,
    /// What a frame keeps of the last (the caching's CPU side).
    cache: PageCache,
    carry: CarryPass,
    mark: MarkPass,
    /// The marking of sampled pairs, in place of `mark` and `tiles` where the frame notes them.
    sampled: Option<SampledMarking>,
    tiles: TilePass,
    alloc: AllocPass,
    /// Whether the stages' bind groups hold the current buffers ([`Self::bind`]).
    bound: bool,
    /// The page rendering: rounds, command buffers, pipelines.
    draw: PageDraw,
    fence: crate::gpu::raster_fence::RasterFence,
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
        let mut this = Self {
            fence: ctx.raster_fence().clone(),
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
            args,
            cache: PageCache::new(scene, (width, height)),
            carry: CarryPass::new(device),
            mark: MarkPass::new(device),
            sampled: None,
            tiles: TilePass::new(ctx, (width, height), options.tile_marking),
            alloc: AllocPass::new(device),
            bound: false,
            draw,
        };
        this.write_plan(ctx)?;
        Ok(this)
    }

    /// Whether the pages are marked for sampled pairs alone when the frame notes them
    /// ([`VirtualOptions::sampled_pages`]).
    pub fn sampled_pages(&self) -> bool {
        self.options.sampled_pages
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
        self.cache.update(scene, (width, height));
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
            self.bound = false;
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
        // The entries, then as many receiver depth keys and as many cell masks (`vsm_table.wgsl`'s
        // receiver bounds).
        if crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.table,
            entries * TABLE_WORDS * 4,
            "virtual page table",
        )? {
            // Last frame's table went with the old buffer: keep no pages this time.
            self.cache.table_replaced();
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
        let table = TableBuffers {
            uniforms: &self.uniforms,
            faces: &self.faces,
            table: &self.table,
            counters: &self.counters,
            prev_table: &self.prev_table,
        };
        let samples = Samples {
            frame: inputs.frame,
            lights: inputs.lights,
            gbuffer: inputs.gbuffer,
            clusters: inputs.clusters,
        };
        self.carry.bind(device, &table);
        self.mark.bind(device, &samples, &table);
        match inputs.page_wants {
            Some(wants) => self
                .sampled
                .get_or_insert_with(|| {
                    SampledMarking::new(device, self.options.sampled_keep_frames)
                })
                .bind(device, &samples, &table, wants),
            None => self.sampled = None,
        }
        self.tiles.bind(device, &samples, &table);
        self.alloc.bind(
            device,
            &table,
            &AllocBuffers {
                page_views: &self.page_views,
                rounds: self.draw.rounds_storage(),
                args: &self.args,
                scratch: &self.scratch,
            },
        );
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
        self.bound = true;
    }

    /// Notes that a shadow caster's bounding sphere moved from `old` to `new`: the pages
    /// under either, in the faces that see them, are not kept at the next frame.
    pub fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.cache.note_moved(old, new);
    }

    /// Keeps no page at the next frame (caster geometry or culling decisions changed).
    pub fn forget_pages(&mut self) {
        self.cache.forget();
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
        if !self.bound {
            return;
        }
        let keep = keep && self.keep_pages && !casters.skinned();
        let mut carried = self.cache.frame(&self.plan, keep, self.viewport);
        if self.sampled.is_some() {
            // The pairs sampled change every frame: every pixel marks again (the pages it
            // marks that were resident keep their depth all the same).
            if let Marking::Carry(_) = carried.marking {
                carried.marking = Marking::Full;
                carried.spare = keep && carried.prev_entries > 0;
            }
        }
        if !carried.faces.is_empty() {
            ctx.queue
                .write_buffer(&self.faces, 0, bytemuck::cast_slice(&carried.faces));
        }
        let origin = match carried.marking {
            Marking::Carry(Some(r)) => [r[0] as f32, r[1] as f32],
            _ => [0.0, 0.0],
        };
        // `VsmUniforms::lod.yz`: the marking pass's first pixel; `prev.x`: where last frame's
        // table (copied by `record_passes`) keeps its receiver bounds; `prev.y`: whether pages
        // drawn now get room to spare ([`PageCache::frame`]).
        ctx.queue
            .write_buffer(&self.uniforms, 36, bytemuck::cast_slice(&origin));
        ctx.queue.write_buffer(
            &self.uniforms,
            48,
            bytemuck::cast_slice(&[carried.prev_entries, u32::from(carried.spare)]),
        );
        self.record_passes(encoder, casters, timer, (pages_span, span), &carried);
        self.cache.recorded(self.plan.fit.table_entries);
    }

    /// Records the stages in order, then the page rendering.
    fn record_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        casters: &CasterGeometry,
        timer: &GpuTimer,
        (pages_span, span): (Option<Span>, Option<Span>),
        carried: &Carried,
    ) {
        let (w, h) = self.viewport;
        encoder.push_debug_group("virtual shadow maps");
        if carried.prev_entries > 0 && carried.copy_prev {
            // Last frame's table and its pages' receiver bounds, for the pages this frame keeps.
            encoder.copy_buffer_to_buffer(
                &self.table,
                0,
                &self.prev_table,
                0,
                carried.prev_entries as u64 * TABLE_WORDS * 4,
            );
        }
        if let Some(sampled) = &self.sampled {
            sampled.begin(encoder, carried.prev_entries);
        }
        encoder.clear_buffer(&self.table, 0, None);
        encoder.clear_buffer(&self.counters, 0, None);
        encoder.clear_buffer(&self.scratch, 0, None);
        self.tiles.clear(encoder);
        // The marking reads the G-buffer; the allocation rewrites what last frame's page
        // draws read.
        {
            let mut pass = self.fence.begin_compute_pass(
                encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some("vsm.pages"),
                    timestamp_writes: timer.compute_writes(pages_span, true, true),
                },
            );
            casters.record(&mut pass, true);
            let entries = self.plan.fit.table_entries;
            if !self.plan.faces.is_empty() {
                let rect = match carried.marking {
                    Marking::Full => Some([0, 0, w, h]),
                    Marking::Carry(rect) => {
                        self.carry.record(&mut pass, entries);
                        rect
                    }
                };
                if let Some(rect) = rect {
                    if let Some(sampled) = &self.sampled {
                        sampled.record(&mut pass, rect, entries);
                    } else if self.tiles.enabled() {
                        self.tiles.record(&mut pass, rect);
                    } else {
                        self.mark.record(&mut pass, rect);
                    }
                }
                self.alloc.record(&mut pass, entries);
            }
            self.alloc.record_args(&mut pass);
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

/// Page slots of the draw: one per pool page, and up to four per pool page when the plan has
/// more faces than the pool has pages (level-0 quarter pages, see `vsm_alloc.wgsl`).
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
