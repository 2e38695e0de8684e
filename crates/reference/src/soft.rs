//! Exact soft-shadow visibility: the fraction of a sized light each surface point sees.
//!
//! This module is **the one definition of the light shapes and of their sampling** that every
//! soft-shadow technique is scored against, and that the GPU's rays copy. Each piece below is
//! a small pure function so a shader can port it line for line.
//!
//! # The shapes (`Light::size`)
//!
//! - **Spot light**, size R: a disc of radius R centred at the light's position, its normal the
//!   spot's direction. Points uniform by area on the disc.
//! - **Point light**, size R: a sphere of radius R. Seen from the receiving point p (the
//!   G-buffer point, not the offset ray start) it is replaced by its silhouette to first order
//!   in R/d: the disc of radius R through the centre, perpendicular to `centre − p`. Points
//!   uniform by area on that disc.
//! - **Directional light**, size S (degrees, the angular diameter): directions in the cone of
//!   half-angle S/2 around `−direction`, uniform in solid angle: `cos θ` uniform in
//!   `[cos(S/2), 1]`, `φ` uniform in `[0, 2π)`.
//! - **Size 0**: exactly one sample, the centre (the position, or `−direction`); the result is
//!   the hard reference ([`point_visible`]) bit for bit, 1 or 0.
//!
//! # Sampling
//!
//! N requested samples become an **n×n jittered grid** in the unit square, `n = ⌈√N⌉`: N is
//! rounded **up** to a square ([`grid_side`]; 200 → 15² = 225), and at most [`MAX_SAMPLES`].
//! Sample k (`0 ≤ k < n²`) lies in cell `(i, j) = (k mod n, k div n)` at
//! `((i + ξ₁) / n, (j + ξ₂) / n)` ([`stratum_point`]), its jitter ξ from a hash: nothing is
//! random, the same (pixel, light, k) gives the same point on every run and every machine.
//!
//! - The hash is Jarzynski and Olano's `pcg_hash` ("Hash Functions for GPU Rendering", JCGT
//!   2020; [`pcg_hash`]), all arithmetic wrapping on `u32`.
//! - The seed of pixel (x, y) and light l: `pcg(l + pcg(y + pcg(x)))` ([`seed`]).
//! - The jitter of sample k: `ξ₁ = unit(pcg(seed + 2k))`, `ξ₂ = unit(pcg(seed + 2k + 1))`,
//!   `unit(h) = (h >> 8) · 2⁻²⁴` in `[0, 1)`.
//!
//! The unit square goes to the unit disc by the **concentric map** of Shirley and Chiu
//! ([`concentric_disc`]), which keeps areas in proportion (every grid cell becomes a piece of
//! the disc of area π/n²) and keeps cells compact, so stratification survives the mapping. A
//! disc in space uses the tangent frame of its normal from Duff et al., "Building an
//! Orthonormal Basis, Revisited" (JCGT 2017; [`tangent_frame`], the sign taken as
//! `z ≥ 0 ? 1 : −1` so that `−0` and `0` agree with a shader's `select`). For the cone the
//! square's x gives `cos θ` and its y gives φ ([`cone_direction`]).
//!
//! # The visibility of one (pixel, light)
//!
//! **Reach** ([`in_reach`]) and **facing** (`n · l > 0`,
//! [`to_light`](crate::visibility::to_light)) are decided at the light's centre, exactly as
//! for hard shadows. Out of reach (or without a surface) the
//! fraction is **0**, as the hard bit is. A light that casts no shadow gives 1 wherever it
//! reaches. Otherwise each sample is one ray from the G-buffer point moved [`ray_offset`] along
//! its normal (the hard reference's start) to the sample point (spot, point: the segment ends
//! there) or along the sample direction (directional: unbounded), through the same
//! [`Tracer`] (watertight, two-sided, alpha masks honoured). The fraction is the unoccluded
//! samples k over n², in `[0, 1]`: one `f32` division `k / n²` (exact when n² is a power of
//! two, as for 256 and 1,024).
//!
//! Storage is one `f32` per (pixel, light) ([`Fractions`]), with the reach and facing masks
//! beside it, so scoring ([`crate::soft_score`](mod@crate::soft_score)) skips what the hard
//! score skips.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, TAU};
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec2, Vec3};
use manyshadows_scene::{Light, LightKind};
use rayon::prelude::*;

use crate::frame::{Fractions, Mask, Surfaces};
use crate::tracer::Tracer;
use crate::visibility::{in_reach, point_visible, ray_offset, reach_and_facing};

/// The most samples per (pixel, light): a 256×256 grid. Requests above are clamped to it.
pub const MAX_SAMPLES: u32 = 256 * 256;

/// Side n of the sampling grid for `requested` samples: `⌈√requested⌉`, between 1 and 256
/// (so n² is the request rounded up to a square, at most [`MAX_SAMPLES`]).
pub fn grid_side(requested: u32) -> u32 {
    let r = requested.clamp(1, MAX_SAMPLES);
    let n = r.isqrt();
    if n * n < r {
        n + 1
    } else {
        n
    }
}

/// Jarzynski and Olano's `pcg_hash` (JCGT 2020): one round of a PCG generator and its output
/// permutation, a good 32-bit hash for a shader.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The seed of pixel (x, y) and light `light`: `pcg(light + pcg(y + pcg(x)))`.
pub fn seed(x: u32, y: u32, light: u32) -> u32 {
    pcg_hash(light.wrapping_add(pcg_hash(y.wrapping_add(pcg_hash(x)))))
}

/// A hash's top 24 bits as a number in `[0, 1)` (exact in `f32`).
fn unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Sample `k` of the n×n jittered grid of `seed`, in the unit square: cell
/// `(k mod n, k div n)`, jittered by `unit(pcg(seed + 2k))` and `unit(pcg(seed + 2k + 1))`.
pub fn stratum_point(seed: u32, k: u32, n: u32) -> Vec2 {
    let (i, j) = (k % n, k / n);
    let jx = unit(pcg_hash(seed.wrapping_add(k.wrapping_mul(2))));
    let jy = unit(pcg_hash(
        seed.wrapping_add(k.wrapping_mul(2)).wrapping_add(1),
    ));
    Vec2::new((i as f32 + jx) / n as f32, (j as f32 + jy) / n as f32)
}

/// Shirley and Chiu's concentric map from the unit square onto the unit disc: the square's
/// concentric squares go to concentric circles, areas in proportion.
pub fn concentric_disc(u: Vec2) -> Vec2 {
    let a = 2.0 * u.x - 1.0;
    let b = 2.0 * u.y - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Two unit tangents `(t₁, t₂)` completing the unit vector `n` to a right-handed orthonormal
/// frame (Duff et al., JCGT 2017), with the sign `z ≥ 0 ? 1 : −1`.
pub fn tangent_frame(n: Vec3) -> (Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        Vec3::new(b, s + n.y * n.y * a, -n.y),
    )
}

/// The point of the disc (`centre`, unit `normal`, `radius`) that the unit-square point `u`
/// maps to: `centre + radius · (d.x · t₁ + d.y · t₂)` with `d` = [`concentric_disc`]`(u)`.
pub fn disc_point(centre: Vec3, normal: Vec3, radius: f32, u: Vec2) -> Vec3 {
    let d = concentric_disc(u);
    let (t1, t2) = tangent_frame(normal);
    centre + radius * (d.x * t1 + d.y * t2)
}

/// The unit direction of the cone (unit `axis`, half-angle `half_angle` radians) that the
/// unit-square point `u` maps to: `cos θ = 1 − u.x · (1 − cos α)`, `φ = 2π · u.y`, uniform in
/// solid angle. `1 − cos α` is computed as `2 sin²(α/2)` and `sin θ` from it, which keeps
/// their precision for the sun's quarter degree (`1 − cos` of it is 10⁻⁵).
pub fn cone_direction(axis: Vec3, half_angle: f32, u: Vec2) -> Vec3 {
    let s = (0.5 * half_angle).sin();
    let one_minus_cos_max = 2.0 * s * s;
    let one_minus_cos = u.x * one_minus_cos_max;
    let cos_theta = 1.0 - one_minus_cos;
    let sin_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let phi = TAU * u.y;
    let (t1, t2) = tangent_frame(axis);
    (sin_theta * phi.cos() * t1 + sin_theta * phi.sin() * t2 + cos_theta * axis).normalize()
}

/// Where one sample of a light lies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSample {
    /// A point on the light (spot, point): the ray's segment ends there.
    Point(Vec3),
    /// A unit direction towards the light (directional): the ray is unbounded.
    Direction(Vec3),
}

/// The sample of `light` at unit-square point `u`, seen from the receiving point `p` (which
/// orients a point light's disc). Size 0 gives the centre whatever `u` is.
pub fn light_sample(light: &Light, p: Vec3, u: Vec2) -> LightSample {
    let size = light.size;
    match light.kind {
        LightKind::Directional { direction, .. } => {
            let axis = -direction.normalize();
            if size == 0.0 {
                LightSample::Direction(axis)
            } else {
                LightSample::Direction(cone_direction(axis, 0.5 * size.to_radians(), u))
            }
        }
        LightKind::Spot {
            position,
            direction,
            ..
        } => {
            if size == 0.0 {
                LightSample::Point(position)
            } else {
                LightSample::Point(disc_point(position, direction.normalize(), size, u))
            }
        }
        LightKind::Point { position, .. } => {
            if size == 0.0 {
                LightSample::Point(position)
            } else {
                // The silhouette disc faces p; a p at the centre has no direction, any will do.
                let normal = (position - p).normalize_or(Vec3::Y);
                LightSample::Point(disc_point(position, normal, size, u))
            }
        }
    }
}

/// Whether nothing lies between `origin` and the sample.
fn sample_unoccluded(tracer: &Tracer, origin: Vec3, sample: LightSample) -> bool {
    match sample {
        LightSample::Direction(d) => !tracer.occluded(origin, d, f32::INFINITY),
        LightSample::Point(s) => {
            let to = s - origin;
            let dist = to.length();
            dist <= 0.0 || !tracer.occluded(origin, to / dist, dist)
        }
    }
}

/// The visible fraction of `light` from the surface point (`position`, `normal`), with the
/// n×n grid of `seed` (see the module docs): 0 out of reach, 1 for a light that casts no
/// shadow, the hard bit for size 0, else the unoccluded share of the n² samples.
pub fn point_soft_visibility(
    tracer: &Tracer,
    light: &Light,
    position: Vec3,
    normal: Vec3,
    n: u32,
    seed: u32,
) -> f32 {
    if light.size == 0.0 {
        // One sample at the centre is the hard reference's own ray.
        return if point_visible(tracer, light, position, normal) {
            1.0
        } else {
            0.0
        };
    }
    if !in_reach(light, position) {
        return 0.0;
    }
    if !light.casts_shadows {
        return 1.0;
    }
    let origin = position + normal.normalize_or_zero() * ray_offset(position);
    let seen = (0..n * n)
        .filter(|&k| {
            let u = stratum_point(seed, k, n);
            sample_unoccluded(tracer, origin, light_sample(light, position, u))
        })
        .count();
    seen as f32 / (n * n) as f32
}

/// The soft reference for a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct SoftVisibility {
    /// The visible fraction per pixel and light; 0 out of reach and where no surface is.
    pub visible: Fractions,
    /// Set = within the light's reach (decided at the light's centre, as the hard reference).
    pub reach: Mask,
    /// Set = the pixel's normal faces the light's centre (`n · l > 0`).
    pub facing: Mask,
    /// Samples per (pixel, light) of a sized light that casts shadows: the request rounded up
    /// to a square. Lights of size 0 take one.
    pub samples: u32,
}

/// Computes the soft reference for every covered pixel of `surfaces` and every light with
/// `samples` samples per (pixel, light) (rounded up to n², see the module docs), in parallel
/// over rows; `on_row` is called once per finished row (for a progress display). Returns
/// `None` when `cancel` is raised before the end.
pub fn reference_soft_visibility(
    tracer: &Tracer,
    lights: &[Light],
    surfaces: &Surfaces,
    samples: u32,
    on_row: &(dyn Fn() + Sync),
    cancel: &AtomicBool,
) -> Option<SoftVisibility> {
    let n = grid_side(samples);
    let hard = reach_and_facing(lights, surfaces);
    let (w, h) = (surfaces.width, surfaces.height);
    let mut visible = Fractions::zeros(w, h, lights.len() as u32);
    let row_len = w as usize * lights.len();
    if row_len == 0 {
        // Nothing to trace; the progress display still sees every row.
        (0..h).for_each(|_| on_row());
    } else {
        visible
            .values
            .par_chunks_mut(row_len)
            .enumerate()
            .for_each(|(y, row)| {
                if cancel.load(Ordering::Relaxed) {
                    return;
                }
                for x in 0..w as usize {
                    let pixel = y * w as usize + x;
                    let Some(sp) = surfaces.points[pixel] else {
                        continue;
                    };
                    for (li, light) in lights.iter().enumerate() {
                        if !hard.reach.get(pixel, li as u32) {
                            continue;
                        }
                        let s = seed(x as u32, y as u32, li as u32);
                        row[x * lights.len() + li] =
                            point_soft_visibility(tracer, light, sp.position, sp.normal, n, s);
                    }
                }
                on_row();
            });
    }
    (!cancel.load(Ordering::Relaxed)).then_some(SoftVisibility {
        visible,
        reach: hard.reach,
        facing: hard.facing,
        samples: n * n,
    })
}

#[cfg(test)]
mod tests {
    use manyshadows_scene::Attenuation;

    use super::*;

    fn light(kind: LightKind, size: f32) -> Light {
        Light {
            kind,
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ONE,
            attenuation: Attenuation::NONE,
            casts_shadows: true,
            shadow_resolution: 256,
            size,
        }
    }

    fn spot(size: f32) -> Light {
        let kind = LightKind::Spot {
            position: Vec3::new(1.0, 5.0, -2.0),
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            cutoff_deg: 60.0,
            range: 50.0,
        };
        light(kind, size)
    }

    fn point(size: f32) -> Light {
        let kind = LightKind::Point {
            position: Vec3::new(-1.0, 3.0, 2.0),
            range: 50.0,
        };
        light(kind, size)
    }

    fn directional(size: f32) -> Light {
        let kind = LightKind::Directional {
            direction: Vec3::new(0.3, -1.0, 0.5).normalize(),
            cascades: 1,
            split_lambda: 0.5,
            cascade_resolution_scale: 1.0,
        };
        light(kind, size)
    }

    /// The n×n grid of one seed mapped to the unit disc.
    fn disc_samples(seed: u32, n: u32) -> Vec<Vec2> {
        (0..n * n)
            .map(|k| concentric_disc(stratum_point(seed, k, n)))
            .collect()
    }

    /// Normals that stress the tangent frame: the poles (both signs of zero), axes, diagonals.
    fn normals() -> Vec<Vec3> {
        let mut v = vec![
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::new(-0.0, -0.0, -1.0),
            Vec3::new(0.0, 1.0, -0.0),
            Vec3::X,
            Vec3::NEG_Y,
            Vec3::Y,
        ];
        for k in 0..50u32 {
            let h = |i: u32| unit(pcg_hash(k * 3 + i)) * 2.0 - 1.0;
            v.push(Vec3::new(h(0), h(1), h(2)).normalize_or(Vec3::X));
        }
        v
    }

    #[test]
    fn grid_side_rounds_up_to_a_square() {
        let cases = [
            (0, 1),
            (1, 1),
            (2, 2),
            (4, 2),
            (5, 3),
            (200, 15),
            (256, 16),
            (1024, 32),
            (1025, 33),
            (MAX_SAMPLES, 256),
            (MAX_SAMPLES + 1, 256),
            (u32::MAX, 256),
        ];
        for (requested, n) in cases {
            assert_eq!(grid_side(requested), n, "{requested} samples");
        }
    }

    #[test]
    fn seeds_are_deterministic_and_distinct() {
        assert_eq!(seed(3, 4, 5), seed(3, 4, 5));
        let mut all: Vec<u32> = (0..16)
            .flat_map(|x| (0..16).flat_map(move |y| (0..4).map(move |l| seed(x, y, l))))
            .collect();
        let count = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(
            all.len(),
            count,
            "every (pixel, light) of a 16x16 frame gets its own seed"
        );
        // Swapped coordinates are different pixels.
        assert_ne!(seed(1, 2, 0), seed(2, 1, 0));
    }

    #[test]
    fn each_sample_lies_in_its_own_cell() {
        for n in [1, 2, 7, 16, 32] {
            for k in 0..n * n {
                let u = stratum_point(1234, k, n);
                let (i, j) = ((k % n) as f32, (k / n) as f32);
                let nf = n as f32;
                assert!(u.x >= i / nf && u.x <= (i + 1.0) / nf, "n {n} k {k}: {u}");
                assert!(u.y >= j / nf && u.y <= (j + 1.0) / nf, "n {n} k {k}: {u}");
            }
        }
    }

    #[test]
    fn concentric_map_keeps_the_disc_and_its_areas() {
        assert_eq!(concentric_disc(Vec2::splat(0.5)), Vec2::ZERO);
        for c in [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE, Vec2::new(1.0, 0.3)] {
            let d = concentric_disc(c);
            assert!((d.length() - 1.0).abs() < 1e-6, "{c} -> {d}");
        }
        // Stratification survives the map: with n = 2m, ring k of the square's cells (the
        // cells between the concentric squares k/m and (k+1)/m) becomes the annulus of those
        // radii, area share (2k+1)/m², and holds exactly 8k + 4 samples; each quadrant of the
        // square is a quadrant of the disc and holds n²/4.
        for (seed, n) in [(7, 16u32), (99, 32), (123_456, 8)] {
            let m = n / 2;
            let mut rings = vec![0u32; m as usize];
            let mut quadrants = [0u32; 4];
            for d in disc_samples(seed, n) {
                assert!(d.length() <= 1.0 + 1e-6);
                let ring = ((d.length() * m as f32) as usize).min(m as usize - 1);
                rings[ring] += 1;
                quadrants[(d.x < 0.0) as usize * 2 + (d.y < 0.0) as usize] += 1;
            }
            let expected: Vec<u32> = (0..m).map(|k| 8 * k + 4).collect();
            assert_eq!(rings, expected, "seed {seed}, n {n}");
            assert_eq!(quadrants, [n * n / 4; 4], "seed {seed}, n {n}");
        }
    }

    #[test]
    fn tangent_frames_are_orthonormal_and_right_handed() {
        for n in normals() {
            let (t1, t2) = tangent_frame(n);
            for (what, v) in [("|t1|", t1.length()), ("|t2|", t2.length())] {
                assert!((v - 1.0).abs() < 1e-5, "{n}: {what} = {v}");
            }
            for (what, v) in [
                ("t1·t2", t1.dot(t2)),
                ("t1·n", t1.dot(n)),
                ("t2·n", t2.dot(n)),
            ] {
                assert!(v.abs() < 1e-5, "{n}: {what} = {v}");
            }
            assert!((t1.cross(t2) - n).length() < 1e-5, "{n}: not right-handed");
        }
    }

    #[test]
    fn disc_samples_lie_on_their_disc() {
        let centre = Vec3::new(3.0, -2.0, 0.5);
        for normal in normals() {
            for k in 0..64 {
                let s = disc_point(centre, normal, 0.7, stratum_point(5, k, 8));
                let d = s - centre;
                assert!(d.dot(normal).abs() < 1e-5, "{normal}: off the plane by {d}");
                assert!(
                    d.length() <= 0.7 * (1.0 + 1e-5),
                    "{normal}: outside the disc {d}"
                );
            }
        }
        // A spot's disc faces along its direction; a point light's faces the receiver.
        let p = Vec3::new(4.0, 0.0, 1.0);
        for (l, normal) in [
            (spot(0.5), Vec3::new(0.2, -1.0, 0.1).normalize()),
            (point(0.5), (Vec3::new(-1.0, 3.0, 2.0) - p).normalize()),
        ] {
            let (LightKind::Spot { position, .. } | LightKind::Point { position, .. }) = l.kind
            else {
                unreachable!()
            };
            for k in 0..256 {
                let LightSample::Point(s) = light_sample(&l, p, stratum_point(9, k, 16)) else {
                    panic!("a point on the light")
                };
                assert!((s - position).dot(normal).abs() < 1e-5);
                assert!((s - position).length() <= 0.5 * (1.0 + 1e-5));
            }
        }
    }

    #[test]
    fn cone_samples_lie_in_the_cone_and_cover_it() {
        // A 20° sun: half-angle 10°, wide enough that 1 − cos θ is well resolved in f32.
        let l = directional(20.0);
        let LightKind::Directional { direction, .. } = l.kind else {
            unreachable!()
        };
        let axis = -direction;
        let one_minus_cos_max = 1.0 - 10f32.to_radians().cos();
        let n = 16;
        let mut bands = vec![0u32; n as usize];
        let mut quadrants = [0u32; 4];
        let (t1, t2) = tangent_frame(axis);
        for k in 0..n * n {
            let LightSample::Direction(d) = light_sample(&l, Vec3::ZERO, stratum_point(77, k, n))
            else {
                panic!("a direction")
            };
            assert!((d.length() - 1.0).abs() < 1e-6);
            let angle = d.angle_between(axis).to_degrees();
            assert!(angle <= 10.0 + 1e-3, "{angle}° outside the 10° cone");
            // cos θ is uniform: band j of 1 − cos θ holds exactly one row of the grid.
            let band = ((1.0 - d.dot(axis)) / one_minus_cos_max * n as f32) as usize;
            bands[band.min(n as usize - 1)] += 1;
            quadrants[(d.dot(t1) < 0.0) as usize * 2 + (d.dot(t2) < 0.0) as usize] += 1;
        }
        assert_eq!(bands, vec![n; n as usize]);
        assert_eq!(quadrants, [n * n / 4; 4]);
        // The sun's half degree keeps its precision: the largest angle reaches the rim.
        let sun = directional(0.53);
        let widest = (0..256)
            .map(
                |k| match light_sample(&sun, Vec3::ZERO, stratum_point(3, k, 16)) {
                    LightSample::Direction(d) => d.angle_between(axis).to_degrees(),
                    LightSample::Point(_) => unreachable!(),
                },
            )
            .fold(0.0f32, f32::max);
        assert!(widest <= 0.265 + 1e-3 && widest > 0.24, "{widest}°");
    }

    #[test]
    fn size_zero_is_the_centre() {
        let p = Vec3::new(0.5, 0.0, 0.5);
        for u in [Vec2::ZERO, Vec2::splat(0.3), Vec2::ONE] {
            assert_eq!(
                light_sample(&spot(0.0), p, u),
                LightSample::Point(Vec3::new(1.0, 5.0, -2.0))
            );
            assert_eq!(
                light_sample(&point(0.0), p, u),
                LightSample::Point(Vec3::new(-1.0, 3.0, 2.0))
            );
            let d = Vec3::new(0.3, -1.0, 0.5).normalize();
            assert_eq!(
                light_sample(&directional(0.0), p, u),
                LightSample::Direction(-d)
            );
        }
    }

    #[test]
    fn fractions_follow_reach_occlusion_and_casting() {
        // A 2x2 square at y = 1 over the origin.
        let roof = Tracer::from_triangles(vec![
            [
                Vec3::new(-1.0, 1.0, -1.0),
                Vec3::new(1.0, 1.0, -1.0),
                Vec3::new(1.0, 1.0, 1.0),
            ],
            [
                Vec3::new(-1.0, 1.0, -1.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(-1.0, 1.0, 1.0),
            ],
        ]);
        let open = Tracer::from_triangles(Vec::new());
        let overhead = |size: f32| {
            light(
                LightKind::Point {
                    position: Vec3::new(0.0, 3.0, 0.0),
                    range: 10.0,
                },
                size,
            )
        };
        let (p, n) = (Vec3::ZERO, Vec3::Y);
        for size in [0.0, 0.2] {
            let l = overhead(size);
            assert_eq!(point_soft_visibility(&roof, &l, p, n, 8, 1), 0.0);
            assert_eq!(point_soft_visibility(&open, &l, p, n, 8, 1), 1.0);
            let far = Vec3::new(20.0, 0.0, 0.0);
            assert_eq!(point_soft_visibility(&open, &l, far, n, 8, 1), 0.0);
            let mut no_shadow = l;
            no_shadow.casts_shadows = false;
            assert_eq!(point_soft_visibility(&roof, &no_shadow, p, n, 8, 1), 1.0);
        }
        // A point beside the roof's edge under a light wide enough to straddle it: partly lit,
        // and the fraction is a count over the n² samples.
        let l = overhead(1.0);
        let v = point_soft_visibility(&roof, &l, Vec3::new(1.5, 0.0, 0.0), n, 8, 1);
        assert!(v > 0.0 && v < 1.0, "{v}");
        assert_eq!((v * 64.0).fract(), 0.0, "{v} is k/64");
    }

    #[test]
    fn the_frame_pass_fills_reach_and_counts_rows() {
        use std::sync::atomic::AtomicU32;
        let tracer = Tracer::from_triangles(Vec::new());
        let sp = crate::frame::SurfacePoint {
            position: Vec3::ZERO,
            normal: Vec3::Y,
        };
        let surfaces = Surfaces::new(3, 2, vec![Some(sp), None, Some(sp), None, None, None])
            .expect("6 points");
        let lights = [point(0.3), directional(1.0)];
        let rows = AtomicU32::new(0);
        let on_row = || {
            rows.fetch_add(1, Ordering::Relaxed);
        };
        let soft = reference_soft_visibility(
            &tracer,
            &lights,
            &surfaces,
            10,
            &on_row,
            &AtomicBool::new(false),
        )
        .expect("not cancelled");
        assert_eq!(rows.into_inner(), 2);
        assert_eq!(soft.samples, 16);
        assert_eq!(
            soft.visible.values,
            vec![1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        );
        assert!(soft.reach.get(0, 0) && !soft.reach.get(1, 0));
        let cancelled = reference_soft_visibility(
            &tracer,
            &lights,
            &surfaces,
            10,
            &|| {},
            &AtomicBool::new(true),
        );
        assert!(cancelled.is_none());
    }
}
