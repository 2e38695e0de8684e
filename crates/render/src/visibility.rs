//! The visibility mask: one bit per light and pixel, the hard (unfiltered) shadow test. It is
//! what shadow quality is measured on, so it reads the atlas with the same coordinates and
//! bias as the lighting pass but without filtering.
//!
//! File format written by [`VisibilityMask::write_raw`] (`.msvis`, little-endian):
//! the 8 bytes `MSVIS001`, then `u32` width, height, light count, words per pixel, then
//! `width·height·words` `u32` words row-major from the top-left pixel; bit `b` of word `w` of a
//! pixel is light `32·w + b`; set = lit (within the light's reach and unoccluded).

use std::io::Write;

use crate::gpu::pipelines::texture_entry;
use crate::lighting::LightingInputs;
use crate::gpu::timing::{GpuTimer, Span};
use crate::{GpuContext, RenderError};

/// Per-pixel light bits read back from the GPU.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VisibilityMask {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Number of lights.
    pub lights: u32,
    /// `ceil(lights / 32)` (at least 1).
    pub words_per_pixel: u32,
    /// `width · height · words_per_pixel` words.
    pub words: Vec<u32>,
}

impl VisibilityMask {
    /// Whether `light` reaches pixel `(x, y)` unoccluded.
    pub fn lit(&self, x: u32, y: u32, light: u32) -> bool {
        let pixel = y as usize * self.width as usize + x as usize;
        let i = pixel * self.words_per_pixel as usize + (light / 32) as usize;
        self.words[i] >> (light % 32) & 1 == 1
    }

    /// Writes the `.msvis` format described in the module docs.
    pub fn write_raw(&self, mut w: impl Write) -> std::io::Result<()> {
        w.write_all(b"MSVIS001")?;
        for v in [self.width, self.height, self.lights, self.words_per_pixel] {
            w.write_all(&v.to_le_bytes())?;
        }
        for v in &self.words {
            w.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    }

    /// Reads the `.msvis` format.
    pub fn read_raw(bytes: &[u8]) -> Result<Self, String> {
        if bytes.len() < 24 || &bytes[..8] != b"MSVIS001" {
            return Err("not a .msvis file (bad header)".into());
        }
        let u = |i: usize| u32::from_le_bytes(bytes[8 + 4 * i..12 + 4 * i].try_into().unwrap());
        let (width, height, lights, words_per_pixel) = (u(0), u(1), u(2), u(3));
        if words_per_pixel != lights.div_ceil(32).max(1) {
            return Err(format!(
                "{lights} lights need {} words per pixel, the header says {words_per_pixel}",
                lights.div_ceil(32).max(1)
            ));
        }
        // The header's sizes are checked against the bytes present before anything is
        // allocated: a header claiming 2^32 × 2^32 pixels is an error, not an allocation.
        let n = (width as u64)
            .checked_mul(height as u64)
            .and_then(|p| p.checked_mul(words_per_pixel as u64))
            .and_then(|n| n.checked_mul(4))
            .ok_or_else(|| {
                format!("{width}x{height} pixels of {words_per_pixel} words overflow")
            })?;
        if bytes.len() as u64 - 24 != n {
            return Err(format!(
                "{width}x{height} pixels of {words_per_pixel} words need {n} bytes of words, \
                 found {}",
                bytes.len() - 24
            ));
        }
        let words = bytes[24..]
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        Ok(Self {
            width,
            height,
            lights,
            words_per_pixel,
            words,
        })
    }

    /// A greyscale image of one light's bits (white = lit), 8 bits per pixel.
    pub fn light_image(&self, light: u32) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.width as usize * self.height as usize);
        for y in 0..self.height {
            for x in 0..self.width {
                out.push(if self.lit(x, y, light) { 255 } else { 0 });
            }
        }
        out
    }
}

/// Layout of `VisibilityParams` in `visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct VisibilityParams {
    first_word: u32,
    word_count: u32,
    _pad: [u32; 2],
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
    /// Words computed per dispatch (so one chunk's buffer stays within the binding limit).
    chunk_words: u32,
}

// The virtual maps' page-table declarations start where the lighting pass's do.
use crate::lighting::VSM_FIRST_BINDING;

impl VisibilityPass {
    /// Plans the pass; fails if even one word per pixel exceeds the storage-binding limit.
    /// Shadows are read from `shadows` (an atlas, or a page pool through its page table).
    pub fn new(
        ctx: &GpuContext,
        w: u32,
        h: u32,
        lights: u32,
        shadows: &crate::source::ShadowOutput<'_>,
    ) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let limit = ctx.limits().max_storage_buffer_binding_size;
        let words = lights.div_ceil(32).max(1);
        let per_word = w as u64 * h as u64 * 4;
        if per_word > limit {
            return Err(RenderError::ResolutionTooLarge {
                width: w,
                height: h,
                reason: format!("the visibility mask needs {per_word} bytes per 32 lights, over this adapter's storage-buffer binding limit of {limit} bytes"),
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
        ];
        let source = if shadows.pages().is_some() {
            entries.extend(crate::lighting::vsm_layout_entries(VSM_FIRST_BINDING, comp));
            crate::gpu::shaders::ShadowSource::Virtual {
                first: VSM_FIRST_BINDING,
            }
        } else {
            crate::gpu::shaders::ShadowSource::Atlas
        };
        let layout = crate::gpu::pipelines::bind_group_layout(device, "visibility.layout", &entries);
        let module = crate::gpu::shaders::module(
            device,
            "visibility.shader",
            &crate::gpu::shaders::visibility(source),
        );
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "visibility.pipeline_layout", &[&layout]);
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
        })
    }

    /// Lights the mask holds.
    pub fn lights(&self) -> u32 {
        self.lights
    }

    /// Computes and reads back the mask (its own submissions, after the frame's).
    pub fn run(
        &self,
        ctx: &GpuContext,
        inputs: &LightingInputs<'_>,
        timer: &GpuTimer,
        span: Option<Span>,
    ) -> Result<VisibilityMask, RenderError> {
        let device = &ctx.device;
        let pixels = self.width as u64 * self.height as u64;
        let mut words = vec![0u32; (pixels * self.words as u64) as usize];
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
            let params = wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("visibility.params"),
                    contents: bytemuck::bytes_of(&VisibilityParams {
                        first_word: first,
                        word_count: count,
                        _pad: [0; 2],
                    }),
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            );
            let mut entries = inputs.shared_entries(&pv, &nv, &mask);
            entries.push(crate::gpu::pipelines::whole_entry(7, &params));
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("visibility.bind_group"),
                layout: &self.layout,
                entries: &entries,
            });
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("visibility.encoder"),
            });
            {
                let last = first + count >= self.words;
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("visibility.pass"),
                    timestamp_writes: timer.compute_writes(span, first == 0, last),
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
            }
            encoder.copy_buffer_to_buffer(&mask, 0, &readback, 0, size);
            ctx.queue.submit([encoder.finish()]);
            let bytes = crate::gpu::readback::map_read(ctx, &readback, 0..size)?;
            let chunk: &[u32] = bytemuck::cast_slice(&bytes);
            for px in 0..pixels as usize {
                let dst = px * self.words as usize + first as usize;
                words[dst..dst + count as usize]
                    .copy_from_slice(&chunk[px * count as usize..(px + 1) * count as usize]);
            }
            first += count;
        }
        Ok(VisibilityMask {
            width: self.width,
            height: self.height,
            lights: self.lights,
            words_per_pixel: self.words,
            words,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::VisibilityMask;

    fn header(w: u32, h: u32, lights: u32, words: u32) -> Vec<u8> {
        let mut b = b"MSVIS001".to_vec();
        for v in [w, h, lights, words] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b
    }

    #[test]
    fn round_trip() {
        let m = VisibilityMask {
            width: 3,
            height: 2,
            lights: 40,
            words_per_pixel: 2,
            words: (0..12).map(|i| i * 0x0101_0101).collect(),
        };
        let mut bytes = Vec::new();
        m.write_raw(&mut bytes).unwrap();
        assert_eq!(VisibilityMask::read_raw(&bytes).unwrap(), m);
    }

    #[test]
    fn lying_headers_are_errors_not_allocations() {
        // Sizes whose product overflows u64, and ones that merely exceed the bytes present.
        for (w, h, lights, words) in [
            (u32::MAX, u32::MAX, u32::MAX, u32::MAX.div_ceil(32)),
            (1 << 20, 1 << 20, 64, 2),
            (2, 2, 1, 1),
        ] {
            let err = VisibilityMask::read_raw(&header(w, h, lights, words)).unwrap_err();
            assert!(err.contains("overflow") || err.contains("need"), "{err}");
        }
        // Words per pixel that do not match the light count (lit() would read out of range).
        let mut b = header(1, 1, 64, 1);
        b.extend_from_slice(&[0; 4]);
        let err = VisibilityMask::read_raw(&b).unwrap_err();
        assert!(err.contains("64 lights need 2 words"), "{err}");
        assert!(VisibilityMask::read_raw(b"MSVIS00").is_err());
        assert!(VisibilityMask::read_raw(b"NOTMSVIS0000000000000000").is_err());
    }
}
