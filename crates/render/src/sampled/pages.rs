//! Sampled lights over shadow pages made on demand (virtual maps): the shadows are made only
//! for the (pixel, light) pairs the frame's sampled lights ask about, not for every light that
//! reaches a pixel. The lighting pass's choose pass (`lights.wgsl`, `fs_choose`), drawn after
//! the G-buffer and the clusters and before the shadows, runs each pixel's light loop as the
//! lighting pass will (the same draws: they depend on the unshadowed terms, the random
//! numbers and last frame's reservoirs, never on visibility) and notes in [`PageWants`] the
//! lights whose visibility the pass will ask for; the source marks the pages of those pairs
//! alone (`ShadowSource::marks_sampled_pairs`, `SourceInputs::page_wants`). Where the draws
//! do not follow the shadows (all but the denoiser without reuse) it also hands them to the
//! lighting pass in the same buffer ([`PageWants::carry`]), which then skips the light loop:
//! the same image, byte for byte, at a lower lighting cost (docs/techniques.md, "Pages for the
//! sampled pairs").
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

/// Words per pixel of the draws the choose pass hands the lighting pass (`carry_store` in
/// `lights.wgsl`): the colour so far, the unshadowed light, the weights' sum, the count of
/// lights weighed and the random state (9), then per sample its light, weight and point.
const CARRY_WORDS: u64 = 9;
const CARRY_PER_SAMPLE: u64 = 3;

/// The notes' layout in WGSL, for the pass that writes them (`lights.wgsl`) and those that
/// read them (virtual maps' marking): `wants_per_pixel(k)` words per pixel with `k` samples;
/// after every pixel's notes, where `CARRY`, `carry_per_pixel(k)` words per pixel of draws.
pub fn wants_wgsl() -> String {
    format!(
        "const NO_WANT: u32 = 0xffffffffu;\n\
         fn wants_per_pixel(k: u32) -> u32 {{ return {WANTS_PER_SAMPLE}u * k + {WANTS_EXTRA}u; }}\n\
         fn carry_per_pixel(k: u32) -> u32 {{ return {CARRY_PER_SAMPLE}u * k + {CARRY_WORDS}u; }}\n"
    )
}

/// Per pixel, the lights the choose pass noted (`2K + 2` words, unused ones `0xffffffff`),
/// and with `carry`, after them, the draws it hands the lighting pass.
pub struct PageWants {
    /// `array<u32>`, row-major pixels.
    pub buffer: wgpu::Buffer,
    /// Whether the choose pass hands its draws to the lighting pass, which then does not run
    /// the light loop again: where the draws do not depend on what the lighting pass looks
    /// up (not with the denoiser without reuse, whose catch-up samples follow the shadows of
    /// changed lights), and where they fit the storage binding.
    pub carry: bool,
}

impl PageWants {
    /// The notes of a `width` × `height` frame with `samples` lights per pixel; `None` where
    /// they would pass the device's largest storage binding (the source then makes the shadows
    /// of every light: the same image, more pages; at the default limit of 128 MiB, more than
    /// 7 samples at 1920 × 1080).
    /// With `carry`, the draws are handed over where they fit too (else not: the lighting
    /// pass runs the loop again).
    pub fn new(
        ctx: &GpuContext,
        (width, height): (u32, u32),
        samples: u32,
        carry: bool,
    ) -> Option<Self> {
        let limits = ctx.limits();
        let fits = |bytes: u64| {
            bytes <= limits.max_storage_buffer_binding_size && bytes <= limits.max_buffer_size
        };
        let mut bytes = Self::bytes((width, height), samples);
        if !fits(bytes) {
            log::info!(
                "sampled lights mark every light's pages: their notes ({bytes} bytes) pass the \
                 device's storage binding limit"
            );
            return None;
        }
        let with_draws = bytes + Self::carry_bytes((width, height), samples);
        let carry = carry && fits(with_draws);
        if carry {
            bytes = with_draws;
        }
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sampled.page_wants"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Some(Self { buffer, carry })
    }

    /// Bytes of the notes of a `width` × `height` frame with `samples` lights per pixel.
    pub fn bytes((width, height): (u32, u32), samples: u32) -> u64 {
        u64::from(width)
            * u64::from(height)
            * (WANTS_PER_SAMPLE * u64::from(samples) + WANTS_EXTRA)
            * 4
    }

    /// Bytes of the draws handed over, after the notes.
    pub fn carry_bytes((width, height): (u32, u32), samples: u32) -> u64 {
        u64::from(width)
            * u64::from(height)
            * (CARRY_PER_SAMPLE * u64::from(samples) + CARRY_WORDS)
            * 4
    }
}
