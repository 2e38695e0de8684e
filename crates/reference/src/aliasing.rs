//! Perspective aliasing in numbers: how many screen pixels one shadow texel covers.
//!
//! For each pixel and each light that reaches it, the shadow view the renderer would read is
//! selected exactly as `select_shadow_view` in `crates/render/src/shadows/shadow_lookup.wgsl`
//! does (the spot's one view; the point light's cube face by the major axis; the first cascade
//! whose far split lies beyond the pixel's camera depth). The **footprint** is then
//!
//! ```text
//! footprint = texel_world(p) / pixel_world(p)
//! texel_world(p) = world width of one texel of that view at p (orthographic: constant;
//!                  perspective: the texel width at distance 1 times p's depth in the view)
//! pixel_world(p) = 2 · depth_camera(p) · tan(fov_y / 2) / image height
//! ```
//!
//! both measured across their own rays, so surface orientation (projective aliasing) is left
//! out: this isolates the perspective term that resolution and cascade choices control. A
//! footprint of 4 means one shadow texel spans about 4×4 pixels (blocky edges); below 1 the
//! map is finer than the screen. Pixels outside every view (beyond the last cascade, outside a
//! spot's frustum) have no texel and are not counted.

use glam::Vec3;
use manyshadows_scene::light_space::ShadowView;
use manyshadows_scene::{LightKind, Scene};
use serde::Serialize;

use crate::error::ReferenceError;
use crate::frame::{Mask, Surfaces};

/// Histogram bins per octave (factor of 2) of footprint.
const BINS_PER_OCTAVE: i32 = 8;
/// Smallest octave kept: footprints below 2^-12 fall in the first bin.
const MIN_OCTAVE: i32 = -12;
/// Number of octaves kept: footprints above 2^12 fall in the last bin.
const OCTAVES: i32 = 24;

/// A log-scale histogram of footprints (1/8-octave bins, so percentiles are exact to ±4.4 %).
#[derive(Clone, Debug, PartialEq)]
pub struct Footprints {
    bins: Vec<u64>,
    count: u64,
    max: f32,
}

impl Default for Footprints {
    fn default() -> Self {
        Self {
            bins: vec![0; (OCTAVES * BINS_PER_OCTAVE) as usize],
            count: 0,
            max: 0.0,
        }
    }
}

impl Footprints {
    /// Adds one footprint.
    pub fn add(&mut self, f: f32) {
        if !(f.is_finite() && f > 0.0) {
            return;
        }
        let b = ((f.log2() - MIN_OCTAVE as f32) * BINS_PER_OCTAVE as f32).floor() as i64;
        let b = b.clamp(0, self.bins.len() as i64 - 1) as usize;
        self.bins[b] += 1;
        self.count += 1;
        self.max = self.max.max(f);
    }

    /// Adds another histogram.
    pub fn merge(&mut self, o: &Footprints) {
        for (a, b) in self.bins.iter_mut().zip(&o.bins) {
            *a += b;
        }
        self.count += o.count;
        self.max = self.max.max(o.max);
    }

    /// Number of (pixel, light) samples.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The largest footprint.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// The `q`-quantile (0..=1): the geometric centre of the bin that holds it, capped at the
    /// maximum; 0 when empty.
    pub fn percentile(&self, q: f64) -> f32 {
        if self.count == 0 {
            return 0.0;
        }
        let target = ((q.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, &n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= target {
                let octave = MIN_OCTAVE as f32 + (i as f32 + 0.5) / BINS_PER_OCTAVE as f32;
                return octave.exp2().min(self.max);
            }
        }
        self.max
    }

    /// Fraction of samples whose footprint exceeds `x` pixels (by bin: exact to one bin).
    pub fn fraction_above(&self, x: f32) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let first = ((x.log2() - MIN_OCTAVE as f32) * BINS_PER_OCTAVE as f32).ceil() as i64;
        let first = first.clamp(0, self.bins.len() as i64) as usize;
        self.bins[first..].iter().sum::<u64>() as f64 / self.count as f64
    }

    /// A summary for reports.
    pub fn summary(&self) -> FootprintSummary {
        FootprintSummary {
            samples: self.count,
            p50: self.percentile(0.5),
            p90: self.percentile(0.9),
            p99: self.percentile(0.99),
            max: self.max,
            above_1: self.fraction_above(1.0),
            above_4: self.fraction_above(4.0),
        }
    }
}

/// Footprint statistics of a group of lights.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FootprintSummary {
    /// (pixel, light) samples with a shadow texel.
    pub samples: u64,
    /// Median footprint, screen pixels per shadow texel (one axis).
    pub p50: f32,
    /// 90th percentile.
    pub p90: f32,
    /// 99th percentile.
    pub p99: f32,
    /// Largest.
    pub max: f32,
    /// Fraction of samples where a texel is wider than a pixel (the map under-samples).
    pub above_1: f64,
    /// Fraction where a texel is wider than 4 pixels (visibly blocky edges).
    pub above_4: f64,
}

/// The shadow views of a frame as the renderer planned them.
pub struct PlannedViews<'a> {
    /// Every view, grouped by light in light order (`ShadowPlan::views`).
    pub views: &'a [ShadowView],
    /// The atlas tile side each view actually got, in view order (it may be smaller than the
    /// view's requested resolution when the atlas was shrunk to fit). For virtual shadow maps,
    /// each face's virtual side.
    pub tile_sizes: &'a [u32],
    /// Virtual shadow maps with these levels of detail and floors (in view order: texels per
    /// pixel, and the coarsest level the face may use, `VirtualFace::detail`): a pixel reads
    /// the level the lookup picks, the coarsest whose texel is no wider than `pixel / lod` of
    /// its face, between the 128-texel level 0 and the face's virtual side, and no coarser than
    /// the floor (pages denied for lack of pool room, which fall back to coarser levels, are
    /// not modelled).
    pub virtual_lods: Option<&'a [[f32; 2]]>,
}

/// Side of a virtual shadow map page (level 0 spans the face with one page).
const VIRTUAL_PAGE: u32 = 128;

/// Footprint histograms per light (scene order) for the pixels `reach` marks.
pub fn footprints(
    scene: &Scene,
    planned: &PlannedViews<'_>,
    surfaces: &Surfaces,
    reach: &Mask,
) -> Result<Vec<Footprints>, ReferenceError> {
    if planned.tile_sizes.len() != planned.views.len() {
        return Err(ReferenceError::Mismatch {
            what: "atlas tiles",
            expected: format!("one per shadow view ({})", planned.views.len()),
            found: planned.tile_sizes.len().to_string(),
        });
    }
    if reach.lights as usize != scene.lights.len()
        || reach.width != surfaces.width
        || reach.height != surfaces.height
    {
        return Err(ReferenceError::Mismatch {
            what: "reach mask",
            expected: format!(
                "{}x{}, {} lights",
                surfaces.width,
                surfaces.height,
                scene.lights.len()
            ),
            found: format!("{}x{}, {} lights", reach.width, reach.height, reach.lights),
        });
    }
    let mut first_view = vec![(0usize, 0usize); scene.lights.len()];
    for (i, v) in planned.views.iter().enumerate() {
        let Some(e) = first_view.get_mut(v.light) else {
            continue;
        };
        if e.1 == 0 {
            e.0 = i;
        }
        e.1 += 1;
    }
    let cam = &scene.camera;
    let view = cam.view();
    let pixel_per_depth = 2.0 * (cam.fov_y_deg.to_radians() * 0.5).tan() / surfaces.height as f32;
    let mut out = vec![Footprints::default(); scene.lights.len()];
    for (p, sp) in surfaces.points.iter().enumerate() {
        let Some(sp) = sp else { continue };
        let depth = -(view * sp.position.extend(1.0)).z;
        let pixel_world = depth * pixel_per_depth;
        if pixel_world <= 0.0 {
            continue;
        }
        for (li, light) in scene.lights.iter().enumerate() {
            if !reach.get(p, li as u32) {
                continue;
            }
            let (first, count) = first_view[li];
            if count == 0 {
                continue;
            }
            let vi = match light.kind {
                LightKind::Spot { .. } => Some(first),
                // Dual paraboloid: hemisphere 0 towards +Y, 1 towards −Y (as the shader).
                LightKind::Point { position, .. } if count == 2 => {
                    Some(first + usize::from(sp.position.y < position.y))
                }
                LightKind::Point { position, .. } => {
                    Some(first + cube_face(sp.position - position).min(count - 1))
                }
                LightKind::Directional { .. } => (0..count.min(4))
                    .find(|&i| {
                        let s = planned.views[first + i].split_far;
                        depth <= if s > 0.0 { s } else { f32::MAX }
                    })
                    .map(|i| first + i),
            };
            let Some(vi) = vi else { continue };
            let v = &planned.views[vi];
            if matches!(
                v.kind,
                manyshadows_scene::light_space::ViewKind::Paraboloid(_)
            ) {
                // x = tan(θ/2) on the disk: a texel spans (2/res)·(1 + cos θ) radians, i.e.
                // texel_world·(1 + front)/2 at distance 1 (texel_world is the pole's).
                let lv = v.view.transform_point3(sp.position);
                let dist = lv.length();
                let front = if dist > 0.0 { -lv.z / dist } else { 1.0 };
                let tile = planned.tile_sizes[vi].max(1) as f32;
                let texel = v.texel_world * v.resolution as f32 / tile
                    * 0.5
                    * (1.0 + front.max(0.0))
                    * dist;
                out[li].add(texel / pixel_world);
                continue;
            }
            let clip = v.view_proj * sp.position.extend(1.0);
            if clip.w <= 0.0 {
                continue;
            }
            let outside = (clip.x / clip.w).abs() > 1.0 || (clip.y / clip.w).abs() > 1.0;
            if outside && !matches!(light.kind, LightKind::Point { .. }) {
                continue;
            }
            let tile = planned.tile_sizes[vi].max(1) as f32;
            let mut texel = v.texel_world * v.resolution as f32 / tile;
            if !v.orthographic {
                texel *= clip.w;
            }
            if let Some(lods) = planned.virtual_lods {
                let [lod, floor] = lods[vi];
                // As vsm_level and vsm_floor in vsm_common.wgsl: 2^k finest texels per level
                // texel, the level (finest − k) no coarser than the floor.
                let finest = (planned.tile_sizes[vi] / VIRTUAL_PAGE)
                    .max(1)
                    .trailing_zeros();
                let k = (pixel_world / lod / texel).log2().floor();
                let k = k.clamp(0.0, finest as f32) as u32;
                let level = (finest - k).max((floor as u32).min(finest));
                texel *= 2f32.powi((finest - level) as i32);
            }
            out[li].add(texel / pixel_world);
        }
    }
    Ok(out)
}

/// Cube face of direction `d` in the order +X, −X, +Y, −Y, +Z, −Z (ties as the shader breaks
/// them).
fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x > 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if d.y > 0.0 {
            2
        } else {
            3
        }
    } else if d.z > 0.0 {
        4
    } else {
        5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_land_in_the_right_bins() {
        let mut h = Footprints::default();
        for i in 0..100 {
            h.add(if i < 90 { 0.5 } else { 8.0 });
        }
        let within = |a: f32, b: f32| (a / b - 1.0).abs() < 0.05;
        assert!(within(h.percentile(0.5), 0.5), "{}", h.percentile(0.5));
        assert!(within(h.percentile(0.95), 8.0), "{}", h.percentile(0.95));
        assert_eq!(h.max(), 8.0);
        assert!((h.fraction_above(1.0) - 0.1).abs() < 1e-9);
        assert!((h.fraction_above(4.0) - 0.1).abs() < 1e-9);
        assert_eq!(h.count(), 100);
    }

    #[test]
    fn cube_faces_follow_the_major_axis() {
        assert_eq!(cube_face(Vec3::new(2.0, 1.0, -1.0)), 0);
        assert_eq!(cube_face(Vec3::new(-2.0, 1.0, -1.0)), 1);
        assert_eq!(cube_face(Vec3::new(0.1, 3.0, -1.0)), 2);
        assert_eq!(cube_face(Vec3::new(0.1, -3.0, -1.0)), 3);
        assert_eq!(cube_face(Vec3::new(0.1, 0.2, 1.0)), 4);
        assert_eq!(cube_face(Vec3::new(0.1, 0.2, -1.0)), 5);
    }
}
