//! Sampled lights over shadow pages made on demand (virtual maps): the shadows are made only
//! for the (pixel, light) pairs the frame's sampled lights ask about, not for every light that
//! reaches a pixel. The lighting pass's choose pass (`lights.wgsl`, `fs_choose`), drawn after
//! the G-buffer and the clusters and before the shadows, runs each pixel's light loop as the
//! lighting pass will (the same draws: they depend on the unshadowed terms, the random
//! numbers and last frame's reservoirs, never on visibility) and notes in [`PageWants`] the
//! lights whose visibility the pass will ask for; the source marks the pages of those pairs
//! alone (`ShadowSource::marks_sampled_pairs`, `SourceInputs::page_wants`).
//!
//! Spatial reuse (`--spatial`) also asks, after the lighting pass, about neighbours' lights at
//! each pixel; those pairs are not noted, and their lookups fall back to the coarser pages that
//! are resident (or to none: lit).

use crate::gpu::context::GpuContext;

/// The choose pass's entry point (a lighting pass entry point of the sampled draws' part).
pub const CHOOSE: &str = "fs_choose";

/// Lights noted per sample (the one drawn and the one last frame's reservoir kept) and per
/// pixel besides (the denoiser's corrections).
const WANTS_PER_SAMPLE: u64 = 2;
const WANTS_EXTRA: u64 = 2;

/// The notes' layout in WGSL, for the pass that writes them (`lights.wgsl`) and those that
/// read them (virtual maps' marking): `wants_per_pixel(k)` words per pixel with `k` samples.
pub fn wants_wgsl() -> String {
    format!(
        "const NO_WANT: u32 = 0xffffffffu;\n\
         fn wants_per_pixel(k: u32) -> u32 {{ return {WANTS_PER_SAMPLE}u * k + {WANTS_EXTRA}u; }}\n"
    )
}

/// Per pixel, the lights the choose pass noted (`2K + 2` words, unused ones `0xffffffff`).
pub struct PageWants {
    /// `array<u32>`, row-major pixels.
    pub buffer: wgpu::Buffer,
}

impl PageWants {
    /// The notes of a `width` × `height` frame with `samples` lights per pixel; `None` where
    /// they would pass the device's largest storage binding (the source then makes the shadows
    /// of every light: the same image, more pages; at the default limit of 128 MiB, more than
    /// 7 samples at 1920 × 1080).
    pub fn new(ctx: &GpuContext, (width, height): (u32, u32), samples: u32) -> Option<Self> {
        let bytes = Self::bytes((width, height), samples);
        let limits = ctx.limits();
        if bytes > limits.max_storage_buffer_binding_size || bytes > limits.max_buffer_size {
            log::info!(
                "sampled lights mark every light's pages: their notes ({bytes} bytes) pass the \
                 device's storage binding limit"
            );
            return None;
        }
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sampled.page_wants"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Some(Self { buffer })
    }

    /// Bytes of the notes of a `width` × `height` frame with `samples` lights per pixel.
    pub fn bytes((width, height): (u32, u32), samples: u32) -> u64 {
        u64::from(width)
            * u64::from(height)
            * (WANTS_PER_SAMPLE * u64::from(samples) + WANTS_EXTRA)
            * 4
    }
}
