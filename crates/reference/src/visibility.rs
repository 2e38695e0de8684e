//! Exact hard-shadow visibility per pixel and light.
//!
//! The bit means what the renderer's visibility mask bit means
//! (`crates/render/src/shading/visibility.wgsl`): the surface point is **within the light's
//! reach** and **unoccluded**. Reach is decided by [`in_reach`], a line-for-line copy of the
//! shader's `in_reach` (range for spot and point lights, the cone for spots, everywhere for
//! directional lights), evaluated at the G-buffer point itself, as the shader does.
//!
//! Occlusion is one ray per pixel and light, from the G-buffer point moved [`ray_offset`] along
//! its normal (so the ray cannot hit the triangle it starts on through rounding), towards the
//! light position (spot, point; the segment ends at the light) or against the light's direction
//! (directional; unbounded). Every shadow-casting triangle counts, from either side.
//!
//! The reference applies **no shadow-map bias**: the renderer's receiver bias (a few shadow
//! texels along the normal and towards the light) exists to hide the shadow map's sampling
//! error, and the reference has none to hide. Where the bias itself changes the answer (contact
//! shadows, thin walls) the difference is the technique's error; most of it lies at shadow
//! edges, inside the tolerance band that [`crate::score`] reports separately.
//!
//! Lights with `casts_shadows = false` have no shadow in any technique: their bit is set
//! wherever they reach, without a ray.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use manyshadows_scene::{Light, LightKind};
use rayon::prelude::*;

use crate::frame::{Mask, Surfaces};
use crate::tracer::Tracer;

/// The ray-start offset along the normal, relative to the point's largest coordinate: about
/// 100 ulps of an `f32`, far above the rounding of G-buffer positions (which the GPU
/// interpolates across the triangle) and far below any shadow texel.
pub const RAY_OFFSET_RELATIVE: f32 = 1e-4;

/// How far (world units) the ray from `p` starts off the surface along its normal:
/// `RAY_OFFSET_RELATIVE · max(1, |p|∞)`, so 0.1 mm near the origin and 3 mm at 30 m.
pub fn ray_offset(p: Vec3) -> f32 {
    RAY_OFFSET_RELATIVE * p.abs().max_element().max(1.0)
}

/// Whether `p` lies within the light's range and cone. Keep in sync with `in_reach` in
/// `crates/render/src/shadows/shadow_lookup.wgsl` (and the packing in `gpu/types.rs`: the cone
/// is `cos(cutoff)` of the normalised axis).
pub fn in_reach(light: &Light, p: Vec3) -> bool {
    match light.kind {
        LightKind::Directional { .. } => true,
        LightKind::Spot {
            position,
            direction,
            cutoff_deg,
            range,
        } => {
            let d = p - position;
            let dist = d.length();
            dist <= range
                && (d / dist.max(1e-6)).dot(direction.normalize()) >= cutoff_deg.to_radians().cos()
        }
        LightKind::Point { position, range } => (p - position).length() <= range,
    }
}

/// Exact visibility of one point: in reach and nothing between its offset start and the light.
pub fn point_visible(tracer: &Tracer, light: &Light, position: Vec3, normal: Vec3) -> bool {
    if !in_reach(light, position) {
        return false;
    }
    if !light.casts_shadows {
        return true;
    }
    let origin = position + normal.normalize_or_zero() * ray_offset(position);
    match light.kind {
        LightKind::Directional { direction, .. } => {
            !tracer.occluded(origin, -direction.normalize(), f32::INFINITY)
        }
        LightKind::Spot { position: l, .. } | LightKind::Point { position: l, .. } => {
            let to = l - origin;
            let dist = to.length();
            dist <= 0.0 || !tracer.occluded(origin, to / dist, dist)
        }
    }
}

/// Unit vector from `p` towards the light.
pub fn to_light(light: &Light, p: Vec3) -> Vec3 {
    match light.kind {
        LightKind::Directional { direction, .. } => -direction.normalize(),
        LightKind::Spot { position, .. } | LightKind::Point { position, .. } => {
            (position - p).normalize_or_zero()
        }
    }
}

/// The reference for a frame: which lights reach each pixel, and which of those are unoccluded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReferenceVisibility {
    /// Set = within the light's reach and unoccluded (the visibility-mask bit).
    pub lit: Mask,
    /// Set = within the light's reach (whatever the occlusion).
    pub reach: Mask,
    /// Set = the pixel's normal faces the light (`n · l > 0`), whether or not in reach. Where it
    /// does not, the light adds nothing to the pixel (the lighting pass's `max(n · l, 0)`), so
    /// a wrong bit there cannot be seen; [`crate::score`] reports those pixels apart.
    pub facing: Mask,
}

/// Computes the reference for every covered pixel of `surfaces` and every light, in parallel
/// over rows; `on_row` is called once per finished row (for a progress display). Returns
/// `None` when `cancel` is raised before the end.
pub fn reference_visibility(
    tracer: &Tracer,
    lights: &[Light],
    surfaces: &Surfaces,
    on_row: &(dyn Fn() + Sync),
    cancel: &AtomicBool,
) -> Option<ReferenceVisibility> {
    visibility_with(lights, surfaces, on_row, cancel, &|light, p, n| {
        point_visible(tracer, light, p, n)
    })
}

/// Which lights reach each pixel and which the pixel faces, without casting a ray (`lit` is
/// left empty): the part of the reference another tracer (the GPU's, `compare --reference
/// gpu`) completes.
pub fn reach_and_facing(lights: &[Light], surfaces: &Surfaces) -> ReferenceVisibility {
    visibility_with(
        lights,
        surfaces,
        &|| {},
        &AtomicBool::new(false),
        &|_, _, _| false,
    )
    .expect("never cancelled")
}

fn visibility_with(
    lights: &[Light],
    surfaces: &Surfaces,
    on_row: &(dyn Fn() + Sync),
    cancel: &AtomicBool,
    visible: &(dyn Fn(&Light, Vec3, Vec3) -> bool + Sync),
) -> Option<ReferenceVisibility> {
    let (w, h) = (surfaces.width, surfaces.height);
    let mut lit = Mask::zeros(w, h, lights.len() as u32);
    let mut reach = Mask::zeros(w, h, lights.len() as u32);
    let mut facing = Mask::zeros(w, h, lights.len() as u32);
    let words = lit.words_per_pixel as usize;
    let row_words = w as usize * words;
    if row_words == 0 {
        return Some(ReferenceVisibility { lit, reach, facing });
    }
    lit.words
        .par_chunks_mut(row_words)
        .zip(reach.words.par_chunks_mut(row_words))
        .zip(facing.words.par_chunks_mut(row_words))
        .enumerate()
        .for_each(|(y, ((lit_row, reach_row), facing_row))| {
            if cancel.load(Ordering::Relaxed) {
                return;
            }
            for x in 0..w as usize {
                let Some(sp) = surfaces.points[y * w as usize + x] else {
                    continue;
                };
                for (li, light) in lights.iter().enumerate() {
                    let word = x * words + li / 32;
                    let bit = 1u32 << (li % 32);
                    if sp.normal.dot(to_light(light, sp.position)) > 0.0 {
                        facing_row[word] |= bit;
                    }
                    if in_reach(light, sp.position) {
                        reach_row[word] |= bit;
                        if visible(light, sp.position, sp.normal) {
                            lit_row[word] |= bit;
                        }
                    }
                }
            }
            on_row();
        });
    (!cancel.load(Ordering::Relaxed)).then_some(ReferenceVisibility { lit, reach, facing })
}
