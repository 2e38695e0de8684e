//! The visibility mask: one bit per light and pixel, the hard (unfiltered) shadow test. It is
//! what shadow quality is measured on, so it reads the atlas with the same coordinates and
//! bias as the lighting pass but without filtering. Its result is a
//! [`VisibilityMask`] ([`crate::frame::visibility_mask`]).

use crate::error::RenderError;
use crate::frame::visibility_mask::{SoftVisibility, VisibilityMask};
use crate::gpu::context::GpuContext;
use crate::gpu::pipelines::texture_entry;
use crate::gpu::timing::{GpuTimer, Span};
use crate::shading::lighting::{LightingInputs, SOURCE_FIRST_BINDING};
use crate::shadows::lookup::{compose_reader, LookupWgsl};

/// Layout of `VisibilityParams` in `visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct VisibilityParams {
    first_word: u32,
    word_count: u32,
    soft: u32,
    _pad1: u32,
}

/// The visibility pass's WGSL, shadows found through `lookup` (its declarations from
/// `SOURCE_FIRST_BINDING`, as in the lighting pass).
pub fn shader(lookup: &LookupWgsl) -> String {
    compose_reader(
        lookup,
        SOURCE_FIRST_BINDING,
        include_str!("visibility.wgsl"),
    )
}

/// The visibility compute pass.
pub struct VisibilityPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    width: u32,
    height: u32,
    lights: u32,
    /// 32-light words per pixel in total.
    words: u32,
    /// Words computed per dispatch (so one chunk's buffers stay within the binding limit).
    chunk_words: u32,
    /// Also the fraction of each light reaching each pixel (`SoftVisibility`).
    soft: bool,
}

/// Bytes of soft visibility per pixel and 32-light word (one byte per light).
const SOFT_BYTES_PER_WORD: u64 = 32;

impl VisibilityPass {
    /// Plans the pass; fails if even one word per pixel exceeds the storage-binding limit.
    /// Shadows are read from `shadows` (an atlas, or a page pool through its page table).
    pub fn new(
        ctx: &GpuContext,
        w: u32,
        h: u32,
        lights: u32,
        shadows: &crate::shadows::source::ShadowOutput<'_>,
        soft: bool,
    ) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let limit = ctx.limits().max_storage_buffer_binding_size;
        let words = lights.div_ceil(32).max(1);
        // The largest buffer one word of a chunk adds: its mask words, or its soft bytes.
        let per_word = w as u64 * h as u64 * if soft { SOFT_BYTES_PER_WORD } else { 4 };
        if per_word > limit {
            return Err(RenderError::TooLarge {
                what: format!("the visibility mask of a {w}x{h} frame, per 32 lights,"),
                needed: per_word,
                limit,
                unit: "bytes",
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let chunk_words = ((limit / per_word) as u32).clamp(1, words);
        let comp = wgpu::ShaderStages::COMPUTE;
        // The lighting pass's bindings (`LightingInputs::shared_entries`); 7 is this pass's
        // parameters, 3 is unused.
        let mut entries = vec![
            crate::gpu::pipelines::uniform_entry(0, comp),
            crate::gpu::pipelines::storage_entry(1, comp),
            crate::gpu::pipelines::storage_entry(2, comp),
            texture_entry(4, wgpu::TextureSampleType::Uint, comp),
            texture_entry(5, wgpu::TextureSampleType::Uint, comp),
            texture_entry(
                6,
                wgpu::TextureSampleType::Float { filterable: false },
                comp,
            ),
            crate::gpu::pipelines::uniform_entry(7, comp),
            crate::gpu::pipelines::storage_rw_entry(8, comp),
            crate::gpu::pipelines::uniform_entry(9, comp),
            crate::gpu::pipelines::storage_entry(10, comp),
            crate::gpu::pipelines::storage_entry(11, comp),
            crate::gpu::pipelines::storage_rw_entry(12, comp),
        ];
        entries.extend(shadows.extra_layout(SOURCE_FIRST_BINDING, comp));
        let layout =
            crate::gpu::pipelines::bind_group_layout(device, "visibility.layout", &entries);
        let module =
            crate::gpu::shaders::module(device, "visibility.shader", &shader(&shadows.lookup));
        let pipeline_layout = crate::gpu::pipelines::pipeline_layout(
            device,
            "visibility.pipeline_layout",
            &[&layout],
        );
        let pipeline = crate::gpu::pipelines::compute_pipeline(
            device,
            "visibility.pipeline",
            &pipeline_layout,
            &module,
            "cs_main",
        );
        Ok(Self {
            pipeline,
            layout,
            width: w,
            height: h,
            lights,
            words,
            chunk_words,
            soft,
        })
    }

    /// Lights the mask holds.
    pub fn lights(&self) -> u32 {
        self.lights
    }

    /// Computes and reads back the mask, and the soft visibility when asked for (its own
    /// submissions, after the frame's).
    pub fn run(
        &self,
        ctx: &GpuContext,
        inputs: &LightingInputs<'_>,
        timer: &GpuTimer,
        span: Option<Span>,
    ) -> Result<(VisibilityMask, Option<SoftVisibility>), RenderError> {
        let device = &ctx.device;
        let pixels = self.width as u64 * self.height as u64;
        let mut words = vec![0u32; (pixels * self.words as u64) as usize];
        let lights = self.lights as usize;
        let mut soft = if self.soft {
            vec![0u8; pixels as usize * lights]
        } else {
            Vec::new()
        };
        let pv = inputs.gbuffer.position.create_view(&Default::default());
        let nv = inputs.gbuffer.normal.create_view(&Default::default());
        let mut first = 0;
        while first < self.words {
            let count = self.chunk_words.min(self.words - first);
            let size = pixels * count as u64 * 4;
            let mask = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("visibility.mask"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("visibility.readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            // One byte per light of the chunk's words (4 bytes where not asked for).
            let soft_size = if self.soft {
                pixels * count as u64 * SOFT_BYTES_PER_WORD
            } else {
                4
            };
            let soft_out = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("visibility.soft"),
                size: soft_size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let soft_readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("visibility.soft_readback"),
                size: soft_size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let params = wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("visibility.params"),
                    contents: bytemuck::bytes_of(&VisibilityParams {
                        first_word: first,
                        word_count: count,
                        soft: u32::from(self.soft),
                        _pad1: 0,
                    }),
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            );
            let mut entries = inputs.shared_entries(&pv, &nv, &mask);
            entries.push(crate::gpu::pipelines::whole_entry(7, &params));
            entries.push(crate::gpu::pipelines::whole_entry(12, &soft_out));
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("visibility.bind_group"),
                layout: &self.layout,
                entries: &entries,
            });
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("visibility.encoder"),
            });
            // The pass reads the G-buffer and the maps the frame drew.
            {
                let last = first + count >= self.words;
                let mut pass = ctx.raster_fence().begin_compute_pass(
                    &mut encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("visibility.pass"),
                        timestamp_writes: timer.compute_writes(span, first == 0, last),
                    },
                );
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
            }
            encoder.copy_buffer_to_buffer(&mask, 0, &readback, 0, size);
            if self.soft {
                encoder.copy_buffer_to_buffer(&soft_out, 0, &soft_readback, 0, soft_size);
            }
            ctx.queue.submit([encoder.finish()]);
            let bytes = crate::gpu::readback::map_read(ctx, &readback, 0..size)?;
            let chunk: &[u32] = bytemuck::cast_slice(&bytes);
            for px in 0..pixels as usize {
                let dst = px * self.words as usize + first as usize;
                words[dst..dst + count as usize]
                    .copy_from_slice(&chunk[px * count as usize..(px + 1) * count as usize]);
            }
            if self.soft {
                let bytes = crate::gpu::readback::map_read(ctx, &soft_readback, 0..soft_size)?;
                // Per pixel the chunk's words, 32 bytes each: light 32·word + b at byte b.
                let per_px = count as usize * 32;
                let first_light = first as usize * 32;
                let n = (lights - first_light).min(per_px);
                for px in 0..pixels as usize {
                    soft[px * lights + first_light..px * lights + first_light + n]
                        .copy_from_slice(&bytes[px * per_px..px * per_px + n]);
                }
            }
            first += count;
        }
        let mask = VisibilityMask {
            width: self.width,
            height: self.height,
            lights: self.lights,
            words_per_pixel: self.words,
            words,
        };
        let soft = self.soft.then_some(SoftVisibility {
            width: self.width,
            height: self.height,
            lights: self.lights,
            values: soft,
        });
        Ok((mask, soft))
    }
}

#[cfg(test)]
mod tests {
    use super::shader;
    use super::VisibilityParams;
    use crate::gpu::types::layout::same_layout;
    use crate::shadows::lookup::ATLAS_LOOKUP;

    #[test]
    fn params_match_the_wgsl() {
        same_layout!(in shader(&ATLAS_LOOKUP), VisibilityParams, first_word, word_count, soft, _pad1);
    }
}
