//! The soft reference against a penumbra known in closed form, and size 0 against the hard
//! reference.
//!
//! **The scene.** A spot light of radius R (a disc, facing down) at height H over the floor
//! `y = 0`, and a horizontal half-plane occluder at height h (0 < h < H) covering `x < 0`, its
//! straight edge along z at x = 0. A floor point (x, 0, z) sees the light's point at disc
//! offset u (along x) through the occluder's plane at `x + (u − x)·h/H`, so that sample is
//! blocked when `u < c(x) = −x·(H − h)/h`, and the visible fraction is the share of the disc
//! with `u ≥ c`: with `s = c/R`, `f = (acos s − s·√(1 − s²))/π` for `|s| ≤ 1`, 1 below, 0 above.
//! The rays start `ray_offset` (1e-4) above the floor, which moves c by `c·1e-4/h`: 5·10⁻⁵ of
//! it, far below the bound.
//!
//! **The bound.** The n×n jittered grid is mapped onto the disc by the concentric map, which
//! keeps areas: every cell becomes a piece of area πR²/n². A piece wholly on one side of the
//! line `u = c` contributes exactly its true share (its one sample sees what the whole piece
//! sees). Each of the K pieces the line crosses contributes its sample's 0 or 1 where the
//! truth is its visible share p: an error in `[−p, 1 − p]/n²`, zero-mean over the jitter, and
//! independent of the others (the hash standing in for independent uniform jitter).
//! Hoeffding's inequality bounds the sum: `P(|error| ≥ t) ≤ 2·exp(−2t²n⁴/K)`, so with a
//! failure chance of δ = 10⁻⁹ per point, `t = √(K·ln(2/δ)/2)/n²`. K is counted for every
//! point (the cells whose image reaches both sides of the line, from 64 points along each cell
//! side: a cell's image is a compact region whose extreme u lies on its outline); it is at
//! most 2n here, so the bound is at most 0.072 at N = 256 (n = 16) and 0.026 at N = 1,024
//! (n = 32), each point checked against its own K. Measured (this test prints them): the
//! largest error 0.021 at N = 256 and 0.0097 at N = 1,024; the mean error 0.0048 and 0.0017.
//! Outside the penumbra (|c| > R) every sample
//! agrees, so the fraction is exactly 0 or 1.

use std::sync::atomic::AtomicBool;

use glam::{Vec2, Vec3};
use manyshadows_reference::soft::{concentric_disc, grid_side};
use manyshadows_reference::{
    reference_soft_visibility, reference_visibility, SurfacePoint, Surfaces, Tracer,
};
use manyshadows_scene::builtin::{self, BuiltinOptions};
use manyshadows_scene::{Attenuation, Light, LightKind, Scene};

/// Light height, occluder height, light radius.
const H: f32 = 4.0;
const OCCLUDER_H: f32 = 2.0;
const R: f32 = 0.5;
/// Failure chance per point of the Hoeffding bound.
const DELTA: f64 = 1e-9;
/// Floor points across x: the penumbra is |x| ≤ R·h/(H − h) = 0.5; the row runs ±0.65.
const XS: u32 = 261;
const X_HALF: f32 = 0.65;
/// Rows at these z (any z sees the same penumbra: the edge runs along z).
const ZS: [f32; 4] = [-1.2, 0.0, 0.35, 1.7];

fn spot(size: f32) -> Light {
    Light {
        kind: LightKind::Spot {
            position: Vec3::new(0.0, H, 0.0),
            direction: Vec3::NEG_Y,
            cutoff_deg: 80.0,
            range: 100.0,
        },
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ONE,
        attenuation: Attenuation::NONE,
        casts_shadows: true,
        shadow_resolution: 1024,
        size,
    }
}

/// A square of two triangles at height `y` spanning `[x0, x1] × [−50, 50]`.
fn quad(y: f32, x0: f32, x1: f32) -> [[Vec3; 3]; 2] {
    let (a, b) = (Vec3::new(x0, y, -50.0), Vec3::new(x1, y, -50.0));
    let (c, d) = (Vec3::new(x1, y, 50.0), Vec3::new(x0, y, 50.0));
    [[a, b, c], [a, c, d]]
}

fn floor_row() -> Surfaces {
    let points = ZS
        .iter()
        .flat_map(|&z| {
            (0..XS).map(move |i| {
                let x = -X_HALF + 2.0 * X_HALF * i as f32 / (XS - 1) as f32;
                Some(SurfacePoint {
                    position: Vec3::new(x, 0.0, z),
                    normal: Vec3::Y,
                })
            })
        })
        .collect();
    Surfaces::new(XS, ZS.len() as u32, points).unwrap()
}

/// The exact visible fraction at floor x.
fn exact(x: f32) -> f64 {
    let c = -(x as f64) * (H - OCCLUDER_H) as f64 / OCCLUDER_H as f64;
    let s = c / R as f64;
    if s <= -1.0 {
        1.0
    } else if s >= 1.0 {
        0.0
    } else {
        (s.acos() - s * (1.0 - s * s).sqrt()) / std::f64::consts::PI
    }
}

/// Cells of the n×n grid whose disc image reaches both sides of `u = s` (unit disc).
fn straddling_cells(n: u32, s: f32) -> u32 {
    const STEPS: u32 = 64;
    let mut k = 0;
    for j in 0..n {
        for i in 0..n {
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for t in 0..=STEPS {
                let f = t as f32 / STEPS as f32;
                for (a, b) in [(f, 0.0), (f, 1.0), (0.0, f), (1.0, f)] {
                    let u = Vec2::new((i as f32 + a) / n as f32, (j as f32 + b) / n as f32);
                    let x = concentric_disc(u).x;
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
            // A hair of margin: the outline is sampled, not traced.
            k += (lo < s + 1e-3 && hi > s - 1e-3) as u32;
        }
    }
    k
}

/// Checks every floor point at `samples` samples; returns (mean error, max error, max bound).
fn penumbra_errors(samples: u32) -> (f64, f64, f64) {
    let mut tris = Vec::new();
    tris.extend(quad(OCCLUDER_H, -50.0, 0.0));
    tris.extend(quad(0.0, -50.0, 50.0));
    let tracer = Tracer::from_triangles(tris);
    let surfaces = floor_row();
    let soft = reference_soft_visibility(
        &tracer,
        &[spot(R)],
        &surfaces,
        samples,
        &|| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    let n = grid_side(samples);
    assert_eq!(soft.samples, n * n, "{samples} is already a square");
    let (mut sum, mut count, mut max_err, mut max_bound) = (0.0, 0, 0.0f64, 0.0f64);
    for (p, sp) in surfaces.points.iter().enumerate() {
        let x = sp.unwrap().position.x;
        let (got, want) = (soft.visible.get(p, 0) as f64, exact(x));
        assert!(soft.reach.get(p, 0) && soft.facing.get(p, 0));
        let s = -x * (H - OCCLUDER_H) / OCCLUDER_H / R;
        if s.abs() > 1.0 + 1e-3 {
            assert_eq!(got, want, "N = {samples}: outside the penumbra at x = {x}");
            continue;
        }
        let k = straddling_cells(n, s) as f64;
        let bound = (k * (2.0 / DELTA).ln() / 2.0).sqrt() / (n as f64 * n as f64);
        let err = (got - want).abs();
        assert!(
            err <= bound,
            "N = {samples}, x = {x}: {got} against exact {want} (error {err}, bound {bound}, \
             {k} cells on the edge)"
        );
        sum += err;
        count += 1;
        max_err = max_err.max(err);
        max_bound = max_bound.max(bound);
    }
    assert!(count > 150 * ZS.len(), "{count} points in the penumbra");
    (sum / count as f64, max_err, max_bound)
}

#[test]
fn spot_penumbra_matches_the_disc_area_formula() {
    let (mean_256, max_256, bound_256) = penumbra_errors(256);
    let (mean_1024, max_1024, bound_1024) = penumbra_errors(1024);
    eprintln!(
        "N = 256: mean error {mean_256:.4}, max {max_256:.4} (bound {bound_256:.4}); \
         N = 1024: mean {mean_1024:.4}, max {max_1024:.4} (bound {bound_1024:.4})"
    );
    assert!(
        mean_1024 < mean_256,
        "more samples must be closer on average: {mean_1024} at 1024, {mean_256} at 256"
    );
}

/// Surface points on every `step`-th triangle of the scene (centroids, both sides):
/// alpha-masked leaves and lattices, walls, the ground; and a grid on the ground.
fn scene_points(scene: &Scene, step: usize) -> Surfaces {
    let mut points = Vec::new();
    for inst in &scene.instances {
        let mesh = &scene.meshes[inst.mesh];
        for t in mesh.indices.chunks_exact(3).step_by(step) {
            let [a, b, c] = [0, 1, 2].map(|k| {
                inst.transform
                    .transform_point3(mesh.positions[t[k] as usize])
            });
            let n = (b - a).cross(c - a).normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            let centre = (a + b + c) / 3.0;
            for normal in [n, -n] {
                points.push(Some(SurfacePoint {
                    position: centre,
                    normal,
                }));
            }
        }
    }
    // The ground plane y = 0 on a 40×40 grid over the casters' extent (the analytic scenes'
    // floor, with its shadow), and a pixel without a surface.
    let (lo, hi) = scene.world_bounds(true).expect("casters");
    for i in 0..40 * 40 {
        let f = |k: u32, a: f32, b: f32| a + (b - a) * (k as f32 + 0.5) / 40.0;
        points.push(Some(SurfacePoint {
            position: Vec3::new(f(i % 40, lo.x, hi.x), 0.0, f(i / 40, lo.z, hi.z)),
            normal: Vec3::Y,
        }));
    }
    points.push(None);
    let width = 64;
    while points.len() % width != 0 {
        points.push(None);
    }
    let height = (points.len() / width) as u32;
    Surfaces::new(width as u32, height, points).unwrap()
}

#[test]
fn size_zero_is_the_hard_reference_bit_for_bit() {
    for name in [
        "courtyard",
        "plane-spot",
        "plane-point",
        "plane-directional",
    ] {
        let mut scene = builtin::build(name, &BuiltinOptions::default()).unwrap();
        // One light that casts no shadow, to cover that rule too.
        let count = scene.lights.len();
        if count > 1 {
            scene.lights[count - 1].casts_shadows = false;
        }
        // The built-in scenes may size their lights: this test is about size 0.
        for l in &mut scene.lights {
            l.size = 0.0;
        }
        let tracer = Tracer::new(&scene).unwrap();
        let step = (scene.triangle_count() / 1500).max(1);
        let surfaces = scene_points(&scene, step);
        let cancel = AtomicBool::new(false);
        let hard =
            reference_visibility(&tracer, &scene.lights, &surfaces, &|| {}, &cancel).unwrap();
        let soft =
            reference_soft_visibility(&tracer, &scene.lights, &surfaces, 1024, &|| {}, &cancel)
                .unwrap();
        assert_eq!(soft.reach, hard.reach, "{name}: reach");
        assert_eq!(soft.facing, hard.facing, "{name}: facing");
        let (mut lit, mut shadowed) = (0, 0);
        for p in 0..surfaces.points.len() {
            for l in 0..scene.lights.len() as u32 {
                let want = if hard.lit.get(p, l) { 1.0 } else { 0.0 };
                let got = soft.visible.get(p, l);
                assert_eq!(
                    got.to_bits(),
                    f32::to_bits(want),
                    "{name}: pixel {p} light {l}"
                );
                if hard.reach.get(p, l) {
                    if got == 1.0 {
                        lit += 1;
                    } else {
                        shadowed += 1;
                    }
                }
            }
        }
        eprintln!("{name}: {lit} lit and {shadowed} shadowed pairs agree");
        assert!(
            lit > 20 && shadowed > 20,
            "{name}: degenerate ({lit} lit, {shadowed} shadowed)"
        );
    }
}

#[test]
fn sized_lights_soften_what_hard_lights_cut() {
    // The courtyard's points with every light given a small size (alpha-masked casters
    // included): every fraction is a count over the n² samples, 0 out of reach, some pairs
    // fall in a penumbra, and over the scene the fractions stay close to the hard bits
    // (measured: 1,166 of 17,487 pairs in penumbra, mean |soft − hard| 0.016).
    let mut scene = builtin::build("courtyard", &BuiltinOptions::default()).unwrap();
    for l in &mut scene.lights {
        l.size = match l.kind {
            LightKind::Directional { .. } => 1.0,
            _ => 0.1,
        };
    }
    let tracer = Tracer::new(&scene).unwrap();
    let surfaces = scene_points(&scene, (scene.triangle_count() / 600).max(1));
    let cancel = AtomicBool::new(false);
    let hard = reference_visibility(&tracer, &scene.lights, &surfaces, &|| {}, &cancel).unwrap();
    let soft =
        reference_soft_visibility(&tracer, &scene.lights, &surfaces, 64, &|| {}, &cancel).unwrap();
    assert_eq!(soft.samples, 64);
    let (mut pairs, mut partial, mut diff) = (0u32, 0u32, 0.0f64);
    for p in 0..surfaces.points.len() {
        for l in 0..scene.lights.len() as u32 {
            let v = soft.visible.get(p, l);
            assert!((0.0..=1.0).contains(&v) && (v * 64.0).fract() == 0.0, "{v}");
            if !hard.reach.get(p, l) {
                assert_eq!(v, 0.0);
                continue;
            }
            pairs += 1;
            partial += (v > 0.0 && v < 1.0) as u32;
            diff += (v as f64 - hard.lit.get(p, l) as u32 as f64).abs();
        }
    }
    let mean = diff / pairs as f64;
    eprintln!("{pairs} pairs in reach, {partial} in penumbra, mean |soft − hard| {mean:.4}");
    assert!(partial > 0, "some penumbra among {pairs} pairs");
    assert!(mean < 0.1, "soft and hard differ by {mean} on average");
}
