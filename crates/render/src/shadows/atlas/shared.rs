//! What the atlas techniques share, so that none imports another: the clear of single cached
//! tiles ([`TileClear`], `tile_clear.wgsl`), bind groups kept across frames ([`CachedGroup`]),
//! per-record uniforms at dynamic offsets ([`UniformRecords`]) and the atlas as a depth
//! attachment. The depth pipelines they draw with are [`crate::shadows::depth`]'s (virtual
//! pages use them too).

use crate::gpu::context::GpuContext;
use crate::gpu::timing::Stage;
use crate::shadows::depth::clear_pipeline;
use crate::shadows::descriptor::Culling;
use crate::shadows::report::{ReportLine, ShadowReport, ShadowText};
use crate::shadows::technique::ShadowInput;

/// Clears only the tiles of the views in [`ShadowInput::draw_list`] (to depth 1), for
/// generations that must keep the other, cached tiles.
pub struct TileClear {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// The atlas side (`vec4<f32>`), rewritten when it changes.
    size: wgpu::Buffer,
    written: Option<u32>,
    group: CachedGroup,
}

impl TileClear {
    /// Builds the clear pipeline.
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let module = crate::gpu::shaders::module(device, "tile_clear.shader", &tile_clear_shader());
        let vs = wgpu::ShaderStages::VERTEX;
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "tile_clear.layout",
            &[
                crate::gpu::pipelines::storage_entry(0, vs),
                crate::gpu::pipelines::storage_entry(1, vs),
                crate::gpu::pipelines::uniform_entry(2, vs),
            ],
        );
        let pipeline_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "tile_clear.pipeline_layout",
            &[&layout],
        );
        let pipeline = clear_pipeline(device, &pipeline_layout, &module, "vs_clear");
        let size = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tile_clear.atlas"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            pipeline,
            layout,
            size,
            written: None,
            group: CachedGroup::default(),
        }
    }

    /// Records the clear of every listed view's tile into `pass` (whose viewport must be the
    /// whole atlas). Does nothing when every view is drawn: that pass clears on load instead.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        input: &ShadowInput<'_>,
        pass: &mut wgpu::RenderPass<'_>,
    ) {
        if input.full() || input.draw_list.is_empty() {
            return;
        }
        if self.written != Some(input.atlas.size) {
            let size = [input.atlas.size as f32, 0.0, 0.0, 0.0];
            ctx.queue
                .write_buffer(&self.size, 0, bytemuck::cast_slice(&size));
            self.written = Some(input.atlas.size);
        }
        let buffers = [
            &input.atlas.views_buffer,
            &input.atlas.draw_list,
            &self.size,
        ];
        let (device, layout) = (&ctx.device, &self.layout);
        let bind_group = self.group.get(&buffers, || {
            crate::gpu::pipelines::buffer_bind_group(
                device,
                "tile_clear.bind_group",
                layout,
                &buffers,
            )
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..6, 0..input.draw_list.len() as u32);
    }
}

impl TileClear {
    /// Leaves `pass` with a pipeline that writes no clip distances. wgpu-hal 30's OpenGL
    /// backend enables `GL_CLIP_DISTANCEi` when a pipeline that writes them is set, but forgets
    /// that at the next command encoder, so the enables outlive the pass and clip later
    /// pipelines (which never write those distances) at random. Setting a pipeline without
    /// clip distances before the pass ends disables them. Harmless elsewhere.
    pub fn reset_clip_distances(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
    }
}

/// A bind group kept across frames: rebuilt only when one of the buffers it binds was replaced
/// (or after [`CachedGroup::invalidate`], for bound textures). Holds handles of the bound
/// buffers, so a replaced buffer is never mistaken for a new one at the same address.
#[derive(Default)]
pub(crate) struct CachedGroup {
    buffers: Vec<wgpu::Buffer>,
    group: Option<wgpu::BindGroup>,
}

impl CachedGroup {
    /// The bind group of `buffers`, made by `make` if they are not the ones last bound.
    pub fn get(
        &mut self,
        buffers: &[&wgpu::Buffer],
        make: impl FnOnce() -> wgpu::BindGroup,
    ) -> &wgpu::BindGroup {
        let same = self.buffers.len() == buffers.len()
            && self.buffers.iter().zip(buffers).all(|(a, b)| a == *b);
        if !same || self.group.is_none() {
            self.buffers = buffers.iter().map(|&b| b.clone()).collect();
            self.group = Some(make());
        }
        self.group.as_ref().expect("bind group just made")
    }

    /// Forgets the bind group (a bound texture was replaced).
    pub fn invalidate(&mut self) {
        self.group = None;
    }
}

/// Uniform records at the device's dynamic-offset alignment in one buffer kept across frames:
/// rewritten with `write_buffer` each generation, replaced (twice the need) only when a
/// generation needs more records than it holds. Techniques record one generation per
/// submission, so a write never overtakes commands that read the previous records.
pub(crate) struct UniformRecords {
    buffer: wgpu::Buffer,
    record: u64,
    stride: u64,
    bytes: Vec<u8>,
    what: &'static str,
}

impl UniformRecords {
    /// Room for one record of `record` bytes.
    pub fn new(ctx: &GpuContext, what: &'static str, record: u64) -> Self {
        let stride =
            record.next_multiple_of(ctx.limits().min_uniform_buffer_offset_alignment as u64);
        Self {
            buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(what),
                size: stride,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            record,
            stride,
            bytes: Vec::new(),
            what,
        }
    }

    /// Writes `records`, record `k` at [`UniformRecords::offset`]`(k)`.
    pub fn write<T: bytemuck::Pod>(&mut self, ctx: &GpuContext, records: &[T]) {
        debug_assert_eq!(std::mem::size_of::<T>() as u64, self.record);
        let stride = self.stride as usize;
        self.bytes.clear();
        self.bytes.resize(stride * records.len().max(1), 0);
        for (k, r) in records.iter().enumerate() {
            self.bytes[k * stride..k * stride + self.record as usize]
                .copy_from_slice(bytemuck::bytes_of(r));
        }
        let needed = self.bytes.len() as u64;
        if let Err(e) = crate::gpu::buffers::grow_buffer(ctx, &mut self.buffer, needed, self.what) {
            // Over the device's buffer limit: a buffer of the full size anyway, so the frame
            // reports a GPU error rather than silently truncating the records.
            log::error!("{e}");
            self.buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.what),
                size: needed,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
        ctx.queue.write_buffer(&self.buffer, 0, &self.bytes);
    }

    /// The buffer (compare it to see whether bind groups must be rebuilt).
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// One record's binding at offset 0 (the dynamic offset selects the record).
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: 0,
            size: wgpu::BufferSize::new(self.record),
        })
    }

    /// The dynamic offset of record `k`.
    pub fn offset(&self, k: usize) -> u32 {
        (k as u64 * self.stride) as u32
    }
}

/// The atlas as a depth attachment, cleared on load when every view is redrawn.
pub(crate) fn atlas_attachment<'a>(
    input: &'a ShadowInput<'_>,
    clear: bool,
) -> wgpu::RenderPassDepthStencilAttachment<'a> {
    wgpu::RenderPassDepthStencilAttachment {
        view: &input.atlas.view,
        depth_ops: Some(wgpu::Operations {
            load: if clear {
                wgpu::LoadOp::Clear(1.0)
            } else {
                wgpu::LoadOp::Load
            },
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}

/// Clearing single tiles of the atlas: the WGSL.
fn tile_clear_shader() -> String {
    crate::gpu::shaders::compose(&[crate::gpu::shaders::COMMON, include_str!("tile_clear.wgsl")])
}

/// The report of a technique that fills the atlas and culls casters where `culling` says: the
/// opening, the atlas, how the maps were fitted where they did not all fit at full size, and
/// the passes that filled it.
pub fn atlas_report(r: &ShadowReport<'_>, culling: Culling) -> ShadowText {
    let mut lines = r.maps_opening();
    let layout = &r.plan.layout;
    let shrink = layout.shrink_steps;
    lines.push(ReportLine::new(
        "atlas",
        format!(
            "{0}x{0}, {1:.0}% filled{2}",
            layout.size,
            r.plan.fill() * 100.0,
            if shrink > 0 {
                format!(", maps shrunk {}x per side to fit", 1u64 << shrink)
            } else {
                String::new()
            }
        ),
    ));
    let fit = &r.plan.fit;
    if fit.reduced + fit.unshadowed + fit.off_screen > 0 {
        lines.push(ReportLine::new(
            "shadow fit",
            format!(
                "{} lights at full resolution, {} with smaller maps, {} unshadowed (no room), {} off screen (no maps needed)",
                fit.full, fit.reduced, fit.unshadowed, fit.off_screen
            ),
        ));
    }
    // What the triangle count is: drawn (after instance culling), or handed to a stage that
    // culls each (triangle, view) itself.
    let what = match culling {
        Culling::VertexStage => {
            "triangle-views submitted (each culled per view in the vertex stage)"
        }
        Culling::Threads => "triangle-views submitted (each culled per view by its setup thread)",
        Culling::Clusters => {
            "triangle-views submitted (clusters culled per view in compute before drawing)"
        }
        _ => "triangles drawn",
    };
    let s = &r.stats;
    lines.push(ReportLine::new(
        "shadow work",
        format!(
            "{} passes, {} draws ({} instance-views culled on the CPU), {} {what}",
            s.passes, s.draws, s.culled, s.triangles
        ),
    ));
    let waiting = if r.budget {
        format!(
            " ({} stale, oldest {} frames; {} waiting, unshadowed)",
            s.views_stale, s.stale_frames, s.views_waiting
        )
    } else {
        String::new()
    };
    ShadowText {
        lines,
        frame: format!(
            "{:>4} of {} shadow views redrawn{waiting}, shadow GPU time {}",
            s.views_drawn,
            r.plan.views.len(),
            r.gpu_time(Stage::Shadows)
        ),
    }
}

#[cfg(test)]
mod shader_tests {
    /// What this module composes is WGSL a WebGPU device accepts.
    #[test]
    fn shader_validates_for_webgpu() {
        crate::gpu::shaders::validate_for_webgpu(
            "tile_clear",
            &super::tile_clear_shader(),
            wgpu::Features::empty(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}
