//! Soft shadows scored. The soft reference: the fraction of each sized light that each
//! pixel's point sees, traced once per scene on the CPU (`manyshadows_reference::soft`, from
//! the same G-buffer points as the hard reference). Each variant's soft visibility (a byte per
//! pixel and light, `Frame::soft_visibility`) is scored against it: the mean absolute error by
//! the reference's class (umbra, penumbra, lit), and the variant's frame against the same
//! frame shaded with the reference's fractions (`Renderer::shade_with`): the RMSE of the 8-bit
//! colour channels and the mean ꟻLIP, whose error map is written beside the difference image.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::MultiProgress;
use manyshadows::scene::Light;
use manyshadows::{Frame, Renderer};
use manyshadows_reference::soft_score::SoftScore;
use manyshadows_reference::{Fractions, Surfaces, Tracer};

use crate::compare::images::image_rgb_out;

/// The soft reference of the frame.
pub(super) struct SoftReference {
    /// The fractions with their reach and facing masks.
    pub(super) vis: manyshadows_reference::SoftVisibility,
    /// The fractions as the renderer's bytes (what `Renderer::shade_with` takes).
    pub(super) bytes: manyshadows::SoftVisibility,
    /// Time to trace it, ms.
    pub(super) ms: f64,
    /// Rays traced: n² per in-reach pair of a sized light that casts shadows, one per pair of
    /// a light of size 0 that does.
    pub(super) rays: u64,
}

/// Traces the soft reference of `surfaces` with `samples` samples per (pixel, sized light),
/// with a progress bar of rows on `multi` in the hard reference's style.
pub(super) fn trace(
    multi: &MultiProgress,
    tracer: &Tracer,
    lights: &[Light],
    surfaces: &Surfaces,
    samples: u32,
) -> Result<SoftReference> {
    // At most `samples` rays per pixel and sized light.
    let sized = lights.iter().filter(|l| l.size > 0.0).count();
    let rows = crate::progress::RowProgress::new(
        multi,
        surfaces.height as u64,
        surfaces.width as f64 * sized as f64 * f64::from(samples),
        &format!("soft reference rays ({samples} per pair)"),
    );
    let t = Instant::now();
    let vis = manyshadows_reference::reference_soft_visibility(
        tracer,
        lights,
        surfaces,
        samples,
        &|| rows.row(),
        &AtomicBool::new(false),
    )
    .context("the soft reference was cancelled")?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    rows.finish();
    let rays = soft_rays(&vis, lights);
    let bytes = to_bytes(&vis.visible);
    Ok(SoftReference {
        vis,
        bytes,
        ms,
        rays,
    })
}

/// The soft reference traced on the GPU (`--reference gpu`): the ray-traced technique's soft
/// visibility over every light, `samples` rays per (pixel, sized light), with the hard
/// reference's reach and facing masks; `ms` is the GPU frame that traced both.
pub(super) fn from_gpu(
    hard: &manyshadows_reference::ReferenceVisibility,
    bytes: manyshadows::SoftVisibility,
    samples: u32,
    lights: &[Light],
    ms: f64,
) -> SoftReference {
    let mut visible = to_fractions(&bytes);
    let lights_n = visible.lights as usize;
    for (i, v) in visible.values.iter_mut().enumerate() {
        if !hard.reach.get(i / lights_n, (i % lights_n) as u32) {
            *v = 0.0;
        }
    }
    let side = manyshadows_reference::soft::grid_side(samples);
    let vis = manyshadows_reference::SoftVisibility {
        visible,
        reach: hard.reach.clone(),
        facing: hard.facing.clone(),
        samples: side * side,
    };
    let rays = soft_rays(&vis, lights);
    let bytes = to_bytes(&vis.visible);
    SoftReference {
        vis,
        bytes,
        ms,
        rays,
    }
}

/// The rays the soft reference traced (see [`SoftReference::rays`]).
fn soft_rays(vis: &manyshadows_reference::SoftVisibility, lights: &[Light]) -> u64 {
    let pixels = vis.visible.width as usize * vis.visible.height as usize;
    let mut rays = 0u64;
    for p in 0..pixels {
        for (l, light) in lights.iter().enumerate() {
            if light.casts_shadows && vis.reach.get(p, l as u32) {
                rays += if light.size > 0.0 {
                    u64::from(vis.samples)
                } else {
                    1
                };
            }
        }
    }
    rays
}

/// Fractions as the renderer's bytes: `round(f · 255)`, as the visibility pass writes them.
fn to_bytes(f: &Fractions) -> manyshadows::SoftVisibility {
    manyshadows::SoftVisibility {
        width: f.width,
        height: f.height,
        lights: f.lights,
        values: f
            .values
            .iter()
            .map(|&v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect(),
    }
}

/// The renderer's bytes as fractions (`b / 255`).
fn to_fractions(s: &manyshadows::SoftVisibility) -> Fractions {
    Fractions {
        width: s.width,
        height: s.height,
        lights: s.lights,
        values: s.values.iter().map(|&b| f32::from(b) / 255.0).collect(),
    }
}

/// One variant's soft-shadow numbers.
pub(super) struct SoftResult {
    /// Its fractions against the reference's, per light.
    pub(super) score: SoftScore,
    /// Root mean square difference of the 8-bit RGB channels between its frame and the frame
    /// shaded with the reference's fractions.
    pub(super) image_rmse: f64,
    /// Mean ꟻLIP of the same pair.
    pub(super) flip: f64,
    /// ꟻLIP's error map (`flip-<label>.png`).
    pub(super) flip_image: PathBuf,
}

/// The frame `renderer` last rendered, shaded with the reference's fractions (the image the
/// technique would give with exact soft shadows).
pub(super) fn reference_image(renderer: &Renderer, r: &SoftReference) -> Result<Vec<u8>> {
    renderer
        .shade_with(&r.bytes)
        .context("shading the frame with the soft reference")
}

/// Scores the soft visibility of `frame` (the last frame of `renderer`, variant `label`)
/// against `r`, and writes its ꟻLIP error map to `out_dir`.
pub(super) fn score(
    out_dir: &Path,
    label: &str,
    renderer: &Renderer,
    frame: &Frame,
    r: &SoftReference,
) -> Result<SoftResult> {
    let soft = frame
        .soft_visibility
        .as_ref()
        .context("the renderer returned no soft visibility")?;
    let score = manyshadows_reference::soft_score(&r.vis, &to_fractions(soft))?;
    let reference = reference_image(renderer, r)?;
    let image_rmse = rmse_rgb(&reference, &frame.rgba);
    let flip =
        manyshadows_reference::flip_rgba8(&reference, &frame.rgba, frame.width, frame.height)?;
    let flip_image = out_dir.join(format!("flip-{label}.png"));
    image_rgb_out(&flip_image, frame.width, frame.height, &flip.error_map)?;
    Ok(SoftResult {
        score,
        image_rmse,
        flip: flip.mean,
        flip_image,
    })
}

/// Root mean square difference of the R, G and B bytes of two RGBA8 images (alpha ignored).
pub(super) fn rmse_rgb(a: &[u8], b: &[u8]) -> f64 {
    let mut sum = 0.0f64;
    let mut n = 0u64;
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = f64::from(pa[c]) - f64::from(pb[c]);
            sum += d * d;
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_and_fractions_round_trip_as_the_shader_rounds() {
        let f = Fractions {
            width: 2,
            height: 1,
            lights: 2,
            values: vec![0.0, 1.0, 0.5, 0.25],
        };
        let b = to_bytes(&f);
        assert_eq!(b.values, vec![0, 255, 128, 64]);
        let back = to_fractions(&b);
        for (x, y) in f.values.iter().zip(&back.values) {
            assert!((x - y).abs() <= 0.5 / 255.0 + 1e-7, "{x} {y}");
        }
    }

    #[test]
    fn rmse_counts_colour_not_alpha() {
        let a = [10, 20, 30, 255, 0, 0, 0, 0];
        let mut b = a;
        assert_eq!(rmse_rgb(&a, &b), 0.0);
        b[3] = 0;
        assert_eq!(rmse_rgb(&a, &b), 0.0);
        b[0] = 16; // one channel of six off by 6: sqrt(36 / 6)
        assert!((rmse_rgb(&a, &b) - 6f64.sqrt()).abs() < 1e-12);
    }
}
