//! The files a comparison writes beside its numbers: the lit frame (PNG), the reference's
//! lit bits (`.msvis`, the renderer's raw visibility-mask format), the difference images
//! (each pixel's error class over the dimmed frame) and ꟻLIP's error maps (RGB PNG).

use std::path::Path;

use anyhow::{Context, Result};
use manyshadows_reference::score::class_colour;
use manyshadows_reference::Mask;

/// Brightness the frame keeps under the difference colours.
const DIM: f32 = 0.35;

/// An RGBA8 image (the lit frame) as PNG.
pub(super) fn image_out(path: &Path, w: u32, h: u32, rgba: &[u8]) -> Result<()> {
    image::save_buffer(path, rgba, w, h, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("writing {}", path.display()))
}

/// An RGB8 image (a ꟻLIP error map) as PNG.
pub(super) fn image_rgb_out(path: &Path, w: u32, h: u32, rgb: &[u8]) -> Result<()> {
    image::save_buffer(path, rgb, w, h, image::ExtendedColorType::Rgb8)
        .with_context(|| format!("writing {}", path.display()))
}

/// `m` in the renderer's raw visibility-mask format (`VisibilityMask::write_raw`).
pub(super) fn write_msvis(path: &Path, m: &Mask) -> Result<()> {
    let vis = manyshadows::VisibilityMask {
        width: m.width,
        height: m.height,
        lights: m.lights,
        words_per_pixel: m.words_per_pixel,
        words: m.words.clone(),
    };
    let file =
        std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
    vis.write_raw(std::io::BufWriter::new(file))
        .with_context(|| format!("writing {}", path.display()))
}

/// The frame dimmed to grey, with each pixel's error class on top.
pub(super) fn write_diff(path: &Path, rgba: &[u8], classes: &[u8], w: u32, h: u32) -> Result<()> {
    let mut rgb = Vec::with_capacity(classes.len() * 3);
    for (px, &c) in rgba.chunks_exact(4).zip(classes) {
        let grey = (0.3 * px[0] as f32 + 0.59 * px[1] as f32 + 0.11 * px[2] as f32) * DIM;
        let g = grey as u8;
        let out = class_colour(c).unwrap_or([g, g, g]);
        rgb.extend_from_slice(&out);
    }
    image::save_buffer(path, &rgb, w, h, image::ExtendedColorType::Rgb8)
        .with_context(|| format!("writing {}", path.display()))
}
