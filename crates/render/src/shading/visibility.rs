//! The visibility mask: one bit per light and pixel, the hard (unfiltered) shadow test. It is
//! what shadow quality is measured on, so it reads the atlas with the same coordinates and
//! bias as the lighting pass but without filtering. It is recorded into the frame after the
//! lighting pass ([`VisibilityPass::record`]) and read back once the frame is submitted
//! ([`VisibilityPass::read`]); its result is a [`VisibilityMask`]
//! ([`crate::frame::visibility_mask`]).

use crate::error::RenderError;
use crate::frame::visibility_mask::{SoftVisibility, VisibilityMask};
use crate::gpu::bindings::{Binding, BindingList};
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::shading::inputs::{pass_bindings, FrameInputs, CLUSTERS, FRAME, GBUFFER};
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

/// The pass's own bindings after the G-buffer: the shadow texture read as plain floats
/// (compute shaders on OpenGL cannot load depth textures), the chunk's parameters and its
/// mask.
const VISIBILITY: &[Binding] = &[
    Binding::texture_f32("atlas"),
    Binding::uniform("params", "VisibilityParams"),
    Binding::storage_rw("mask", "array<u32>"),
];

/// After the clusters: the fraction of each light reaching each pixel, one byte per light
/// (0..255), four lights per word: per pixel, 8 words per 32-light word of the chunk (a 4-byte
/// dummy without soft visibility).
const VISIBILITY_SOFT: &[Binding] = &[Binding::storage_rw("soft_out", "array<u32>")];

fn bindings(lookup: &LookupWgsl) -> BindingList {
    pass_bindings(
        &[FRAME, GBUFFER, VISIBILITY, CLUSTERS, VISIBILITY_SOFT],
        lookup.bindings,
        &[],
    )
}

/// The visibility pass's WGSL, shadows found through `lookup`.
pub fn shader(lookup: &LookupWgsl) -> String {
    compose_reader(lookup, &bindings(lookup), include_str!("visibility.wgsl"))
}

/// One dispatch's words of the mask and their buffers (a chunk keeps each buffer within the
/// storage-binding limit).
struct Chunk {
    first: u32,
    count: u32,
    params: wgpu::Buffer,
    mask: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// One byte per light of the chunk's words (4 bytes where soft visibility is not asked).
    soft: wgpu::Buffer,
    soft_readback: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
}

/// The visibility compute pass.
pub struct VisibilityPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    bindings: BindingList,
    width: u32,
    height: u32,
    lights: u32,
    /// 32-light words per pixel in total.
    words: u32,
    chunks: Vec<Chunk>,
    /// Also the fraction of each light reaching each pixel (`SoftVisibility`).
    soft: bool,
    /// Whether the last frame recorded the pass (what [`VisibilityPass::read`] reads).
    recorded: bool,
}

/// Bytes of soft visibility per pixel and 32-light word (one byte per light).
const SOFT_BYTES_PER_WORD: u64 = 32;

impl VisibilityPass {
    /// Plans the pass and its buffers; fails if even one word per pixel exceeds the
    /// storage-binding limit. Shadows are read through `lookup` (an atlas, or a page pool
    /// through its page table).
    pub fn new(
        ctx: &GpuContext,
        (w, h): (u32, u32),
        lights: u32,
        lookup: &LookupWgsl,
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
        let bindings = bindings(lookup);
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "visibility.layout",
            &bindings.layout(wgpu::ShaderStages::COMPUTE),
        );
        let module = crate::gpu::shaders::module(device, "visibility.shader", &shader(lookup));
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
        let pixels = w as u64 * h as u64;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let read = wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST;
        let mut chunks = Vec::new();
        let mut first = 0;
        while first < words {
            let count = chunk_words.min(words - first);
            let size = pixels * count as u64 * 4;
            let soft_size = if soft {
                pixels * count as u64 * SOFT_BYTES_PER_WORD
            } else {
                4
            };
            let params = wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("visibility.params"),
                    contents: bytemuck::bytes_of(&VisibilityParams {
                        first_word: first,
                        word_count: count,
                        soft: u32::from(soft),
                        _pad1: 0,
                    }),
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            );
            chunks.push(Chunk {
                first,
                count,
                params,
                mask: buffer("visibility.mask", size, storage),
                readback: buffer("visibility.readback", size, read),
                soft: buffer("visibility.soft", soft_size, storage),
                soft_readback: buffer("visibility.soft_readback", soft_size, read),
                bind_group: None,
            });
            first += count;
        }
        Ok(Self {
            pipeline,
            layout,
            bindings,
            width: w,
            height: h,
            lights,
            words,
            chunks,
            soft,
            recorded: false,
        })
    }

    /// Lights the mask holds.
    pub fn lights(&self) -> u32 {
        self.lights
    }

    /// Binds the frame's inputs (after creation and whenever the frame replaced one).
    pub fn bind(&mut self, ctx: &GpuContext, inputs: &FrameInputs<'_>) {
        assert_eq!(
            bindings(&inputs.shadows.lookup),
            self.bindings,
            "the visibility pass rebound with another lookup than it was made with"
        );
        let g = inputs.gbuffer_views();
        for chunk in &mut self.chunks {
            let mut resources = inputs.frame_resources();
            resources.extend([
                wgpu::BindingResource::TextureView(&g.position),
                wgpu::BindingResource::TextureView(&g.normal),
                wgpu::BindingResource::TextureView(inputs.shadows.depth),
                chunk.params.as_entire_binding(),
                chunk.mask.as_entire_binding(),
            ]);
            resources.extend(inputs.cluster_resources());
            resources.push(chunk.soft.as_entire_binding());
            resources.extend(inputs.shadows.resources.iter().cloned());
            chunk.bind_group = Some(ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("visibility.bind_group"),
                layout: &self.layout,
                entries: &self.bindings.entries(resources),
            }));
        }
    }

    /// Records the pass (after the frame's G-buffer, shadows and lighting) and the copies of
    /// its results for [`VisibilityPass::read`], as the span `span`.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        let last = self.chunks.len() - 1;
        for (i, chunk) in self.chunks.iter().enumerate() {
            {
                let mut pass = ctx.raster_fence().begin_compute_pass(
                    encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("visibility.pass"),
                        timestamp_writes: timer.compute_writes(span, i == 0, i == last),
                    },
                );
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, chunk.bind_group.as_ref(), &[]);
                pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
            }
            encoder.copy_buffer_to_buffer(&chunk.mask, 0, &chunk.readback, 0, chunk.mask.size());
            if self.soft {
                encoder.copy_buffer_to_buffer(
                    &chunk.soft,
                    0,
                    &chunk.soft_readback,
                    0,
                    chunk.soft.size(),
                );
            }
        }
        self.recorded = true;
    }

    /// Reads back the mask (and the soft visibility when asked for) of the last frame that
    /// recorded the pass, once that frame is submitted; `None` before any did.
    pub fn read(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<(VisibilityMask, Option<SoftVisibility>)>, RenderError> {
        if !self.recorded {
            return Ok(None);
        }
        let pixels = self.width as u64 * self.height as u64;
        let mut words = vec![0u32; (pixels * self.words as u64) as usize];
        let lights = self.lights as usize;
        let mut soft = if self.soft {
            vec![0u8; pixels as usize * lights]
        } else {
            Vec::new()
        };
        for chunk in &self.chunks {
            let (first, count) = (chunk.first, chunk.count);
            let bytes =
                crate::gpu::readback::map_read(ctx, &chunk.readback, 0..chunk.readback.size())?;
            let got: &[u32] = bytemuck::cast_slice(&bytes);
            for px in 0..pixels as usize {
                let dst = px * self.words as usize + first as usize;
                words[dst..dst + count as usize]
                    .copy_from_slice(&got[px * count as usize..(px + 1) * count as usize]);
            }
            if self.soft {
                let bytes = crate::gpu::readback::map_read(
                    ctx,
                    &chunk.soft_readback,
                    0..chunk.soft_readback.size(),
                )?;
                // Per pixel the chunk's words, 32 bytes each: light 32·word + b at byte b.
                let per_px = count as usize * 32;
                let first_light = first as usize * 32;
                let n = (lights - first_light).min(per_px);
                for px in 0..pixels as usize {
                    soft[px * lights + first_light..px * lights + first_light + n]
                        .copy_from_slice(&bytes[px * per_px..px * per_px + n]);
                }
            }
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
        Ok(Some((mask, soft)))
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
