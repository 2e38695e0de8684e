//! Shared pieces of the seeded light layouts: the random source, how a count splits into
//! types, colours, brightness, and the generic [`scatter`] layout.
//!
//! Why one place: every scene must follow the same rules (type split, default shadow
//! resolutions, ambient fraction, brightness at a key distance, size) so that light counts and
//! mixes mean the same thing in every scene and benchmark. Every light made here has the
//! default size of [`crate::light_size`]: a radius of 2 % of its range for a spot or point
//! light, the sun's 0.53° for a directional one (scenes that must stay hard set 0 after).

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::options::LightMix;
use crate::light_size::default_size;
use crate::model::{Attenuation, Light, LightKind, Scene};

/// Default shadow-map resolution of spot lights (texels per side).
pub const SPOT_SHADOW_RESOLUTION: u32 = 512;
/// Default shadow-map resolution of point lights (texels per cube face).
pub const POINT_SHADOW_RESOLUTION: u32 = 256;
/// Default shadow-map resolution of directional lights (texels per cascade).
pub const DIRECTIONAL_SHADOW_RESOLUTION: u32 = 1024;
/// Default cascade count of directional lights.
pub const DIRECTIONAL_CASCADES: u32 = 3;
/// Default cascade split blend of directional lights.
pub const DIRECTIONAL_SPLIT_LAMBDA: f32 = 0.75;

/// Seeded random numbers for layouts: PCG32 with our own float mapping (24 random bits, so
/// every value is exact and the same on every platform).
pub(crate) struct Rand(Pcg32);

impl Rand {
    /// A generator for `seed`; `stream` separates independent uses of one seed (geometry,
    /// lights of one scene, ...).
    pub(crate) fn new(seed: u64, stream: u64) -> Self {
        Self(Pcg32::seed_from_u64(
            seed ^ stream.wrapping_mul(0x9e37_79b9_7f4a_7c15),
        ))
    }

    /// Uniform in `[0, 1)`.
    pub(crate) fn unit(&mut self) -> f32 {
        (self.0.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in `[lo, hi)`.
    pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform integer in `0..n` (`n > 0`).
    pub(crate) fn below(&mut self, n: usize) -> usize {
        ((self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64) as usize % n.max(1)
    }
}

/// How many lights of each type a layout of `n` lights gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightCounts {
    /// Spot lights.
    pub spot: usize,
    /// Point lights.
    pub point: usize,
    /// Directional lights.
    pub directional: usize,
}

impl LightCounts {
    /// Splits `n` lights by `mix`. For [`LightMix::All`]: one directional light when `n ≥ 3`
    /// and a second from 64 lights on (they are the most expensive: cascades), then a third of
    /// the rest points (at least one when `n ≥ 2`) and the remainder spots. E.g. 32 → 21 spots,
    /// 10 points, 1 directional; 3 → one of each.
    pub fn split(n: usize, mix: LightMix) -> Self {
        match mix {
            LightMix::Spot => Self {
                spot: n,
                point: 0,
                directional: 0,
            },
            LightMix::Point => Self {
                spot: 0,
                point: n,
                directional: 0,
            },
            LightMix::Directional => Self {
                spot: 0,
                point: 0,
                directional: n,
            },
            LightMix::All => {
                let directional = match n {
                    0..=2 => 0,
                    3..=63 => 1,
                    _ => 2,
                };
                let rest = n - directional;
                let mut point = (rest + 1) / 3;
                if n >= 2 {
                    point = point.max(1);
                }
                Self {
                    spot: rest - point,
                    point,
                    directional,
                }
            }
        }
    }

    /// Total number of lights.
    pub fn total(&self) -> usize {
        self.spot + self.point + self.directional
    }
}

/// Each light's ambient colour as a fraction of its diffuse colour.
///
/// Why a fraction and not a fixed small colour: the lighting pass (seed 004's Phong) attenuates
/// a light's ambient term with distance and applies it only within the light's reach, like its
/// diffuse term. A fixed `0.02·colour` would therefore vanish a few metres from any light whose
/// diffuse colour is scaled up to fight [`Attenuation::for_range`]'s steep fall-off. As a
/// fraction of the diffuse colour, a shadowed point receives 5 % of what the same lights give
/// it when lit, at any light count and density: shadows stay dark but not black, and ambient
/// grows with light density exactly as direct light does instead of washing shadows out.
pub const AMBIENT_FRACTION: f32 = 0.05;

/// A light colour with a varied tint: warm (tungsten, torch), cool (sky, moon) or near white,
/// jittered, brightest channel 1.
pub(crate) fn tint(rng: &mut Rand) -> Vec3 {
    let base = match rng.below(20) {
        0..=8 => Vec3::new(1.0, 0.78, 0.55),
        9..=14 => Vec3::new(0.68, 0.8, 1.0),
        _ => Vec3::new(1.0, 0.96, 0.9),
    };
    let c = base
        * Vec3::new(
            rng.range(0.9, 1.1),
            rng.range(0.9, 1.1),
            rng.range(0.9, 1.1),
        );
    c / c.max_element()
}

/// Colours and brightness shared by the light constructors.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tone {
    /// Tint, brightest channel 1.
    pub color: Vec3,
    /// Diffuse brightness (after attenuation, at the key distance).
    pub brightness: f32,
}

impl Tone {
    fn light(
        &self,
        kind: LightKind,
        attenuation: Attenuation,
        gain: f32,
        resolution: u32,
    ) -> Light {
        Light {
            kind,
            ambient: self.color * (AMBIENT_FRACTION * gain),
            diffuse: self.color * gain,
            specular: self.color * (0.5 * gain),
            attenuation,
            casts_shadows: true,
            shadow_resolution: resolution,
            size: default_size(&kind),
        }
    }
}

/// A shadow-casting spot light at `position` aimed at `target`, bright `tone.brightness` at
/// `key_distance`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn spot(
    position: Vec3,
    direction: Vec3,
    cutoff_deg: f32,
    range: f32,
    key_distance: f32,
    tone: Tone,
    resolution: Option<u32>,
) -> Light {
    let attenuation = Attenuation::for_range(range);
    let gain = tone.brightness / attenuation.factor(key_distance);
    tone.light(
        LightKind::Spot {
            position,
            direction: direction.normalize_or(Vec3::NEG_Y),
            cutoff_deg,
            range,
        },
        attenuation,
        gain,
        resolution.unwrap_or(SPOT_SHADOW_RESOLUTION),
    )
}

/// A shadow-casting point light, bright `tone.brightness` at `key_distance`.
pub(crate) fn point(
    position: Vec3,
    range: f32,
    key_distance: f32,
    tone: Tone,
    resolution: Option<u32>,
) -> Light {
    let attenuation = Attenuation::for_range(range);
    let gain = tone.brightness / attenuation.factor(key_distance);
    tone.light(
        LightKind::Point { position, range },
        attenuation,
        gain,
        resolution.unwrap_or(POINT_SHADOW_RESOLUTION),
    )
}

/// A shadow-casting directional light with the default cascades.
pub(crate) fn directional(direction: Vec3, tone: Tone, resolution: Option<u32>) -> Light {
    tone.light(
        LightKind::Directional {
            direction: direction.normalize_or(Vec3::NEG_Y),
            cascades: DIRECTIONAL_CASCADES,
            split_lambda: DIRECTIONAL_SPLIT_LAMBDA,
            cascade_resolution_scale: 1.0,
        },
        Attenuation::NONE,
        tone.brightness,
        resolution.unwrap_or(DIRECTIONAL_SHADOW_RESOLUTION),
    )
}

/// Brightness factor for `count` local lights sharing an area that `capacity` lights light
/// well: 1 up to `capacity`, then `capacity / count`. Dense layouts keep roughly the same total
/// light instead of washing out to white, so `--lights 1000` still shows shadows.
pub(crate) fn density_dim(count: usize, capacity: usize) -> f32 {
    if count <= capacity {
        1.0
    } else {
        capacity as f32 / count as f32
    }
}

/// A sun-like direction: azimuth uniform, elevation between `min_deg` and `max_deg` above the
/// horizon, pointing down.
pub(crate) fn slanted_direction(rng: &mut Rand, min_deg: f32, max_deg: f32) -> Vec3 {
    let az = rng.range(0.0, TAU);
    let el = rng.range(min_deg, max_deg).to_radians();
    Vec3::new(el.cos() * az.cos(), -el.sin(), el.cos() * az.sin())
}

/// The `k`-th point of a seeded R2 low-discrepancy sequence in the unit square: any prefix
/// covers the square evenly, so any light count spreads out.
pub(crate) fn r2(k: usize, offset: Vec2) -> Vec2 {
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_2;
    let x = (offset.x as f64 + A1 * k as f64).fract();
    let y = (offset.y as f64 + A2 * k as f64).fract();
    Vec2::new(x as f32, y as f32)
}

/// See [`super::scatter_lights`].
pub(crate) fn scatter(
    scene: &Scene,
    n: usize,
    seed: u64,
    mix: LightMix,
    resolution: Option<u32>,
) -> Vec<Light> {
    let (lo, hi) = scene
        .world_bounds(false)
        .unwrap_or((Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 2.0, 5.0)));
    let size = hi - lo;
    let diag = Vec2::new(size.x, size.z).length().max(1.0);
    let height = size.y.max(0.3 * diag);
    let counts = LightCounts::split(n, mix);
    let mut rng = Rand::new(seed, 0x5ca7);
    let offset = Vec2::new(rng.unit(), rng.unit());
    let reach = diag * (0.75 / (n.max(1) as f32).sqrt()).max(0.15);
    let inset = |u: Vec2| {
        Vec2::new(
            lo.x + size.x * (0.1 + 0.8 * u.x),
            lo.z + size.z * (0.1 + 0.8 * u.y),
        )
    };
    let dim = density_dim(counts.spot + counts.point, 16);
    let mut out = Vec::with_capacity(n);
    let local_layout = n > LOCAL_LAYOUT_ABOVE;
    for _ in 0..counts.directional {
        let tone = Tone {
            color: tint(&mut rng),
            brightness: 0.8 / counts.directional as f32,
        };
        out.push(directional(
            slanted_direction(&mut rng, 35.0, 65.0),
            tone,
            resolution,
        ));
    }
    if local_layout {
        // Local lights over the bounds' floor: the footprint inset by 5 %, standing on the
        // top of any large slab (over a quarter of the footprint) in the lower half.
        let floor = Floor {
            lo: Vec2::new(lo.x + 0.05 * size.x, lo.z + 0.05 * size.z),
            hi: Vec2::new(hi.x - 0.05 * size.x, hi.z - 0.05 * size.z),
        };
        let boxes = instance_boxes(&scene.meshes, &scene.instances);
        let footprint = (size.x * size.z).max(1e-6);
        let (slabs, obstacles): (Vec<_>, Vec<_>) = boxes.into_iter().partition(|(a, b)| {
            (b.x - a.x) * (b.z - a.z) > 0.25 * footprint && b.y < lo.y + 0.5 * size.y
        });
        let height = |_: usize, xz: Vec2| {
            slabs
                .iter()
                .filter(|(a, b)| xz.x >= a.x && xz.x <= b.x && xz.y >= a.z && xz.y <= b.z)
                .map(|(_, b)| b.y)
                .fold(lo.y, f32::max)
        };
        out.extend(local(
            counts.spot,
            counts.point,
            &[floor],
            &height,
            &obstacles,
            &mut rng,
            LOCAL_BRIGHTNESS,
            resolution,
        ));
        return out;
    }
    let mut k = 0;
    for _ in 0..counts.spot {
        let xz = inset(r2(k, offset));
        k += 1;
        let above = height * rng.range(0.55, 0.9);
        let position = Vec3::new(xz.x, lo.y + above, xz.y);
        let tilt = rng.range(0.0, 25f32.to_radians());
        let az = rng.range(0.0, TAU);
        let direction = Vec3::new(tilt.sin() * az.cos(), -tilt.cos(), tilt.sin() * az.sin());
        let key = above / tilt.cos();
        let tone = Tone {
            color: tint(&mut rng),
            brightness: 0.7 * dim,
        };
        let range = reach.max(2.5 * key);
        out.push(spot(
            position,
            direction,
            rng.range(30.0, 45.0),
            range,
            key,
            tone,
            resolution,
        ));
    }
    for _ in 0..counts.point {
        let xz = inset(r2(k, offset));
        k += 1;
        let above = height * rng.range(0.15, 0.5);
        let position = Vec3::new(xz.x, lo.y + above, xz.y);
        let tone = Tone {
            color: tint(&mut rng),
            brightness: 0.6 * dim,
        };
        let range = (0.7 * reach).max(2.5 * above);
        out.push(point(position, range, above, tone, resolution));
    }
    out
}

/// Above this many lights a built-in layout keeps a fixed set of large "architectural" lights
/// and turns every further spot and point light into a *local* light (see [`local_range`]):
/// bounded range near a floor, as real many-light scenes use. Up to this count every layout is the
/// scene's hand-made one, unchanged.
pub const LOCAL_LAYOUT_ABOVE: usize = 64;

/// Brightness of a local light at its key distance (its height above the floor).
pub const LOCAL_BRIGHTNESS: f32 = 0.3;

/// Mean number of local lights whose range covers a point of the floors they stand on.
pub const LOCAL_OVERLAP: f32 = 6.0;

/// Shortest and longest range of a local light (metres).
pub const LOCAL_RANGE: (f32, f32) = (0.25, 6.0);

/// A horizontal region that local lights stand over: an XZ rectangle whose height at a point
/// comes from the layout's height function.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Floor {
    /// XZ corner with the smaller coordinates.
    pub lo: Vec2,
    /// XZ corner with the larger coordinates.
    pub hi: Vec2,
}

impl Floor {
    fn area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec2::ZERO);
        d.x * d.y
    }
}

/// The range of each of `n` local lights spread over `area` m² so that about
/// [`LOCAL_OVERLAP`] of them reach any floor point: `π r² n = overlap · area`, clamped to
/// [`LOCAL_RANGE`].
pub fn local_range(n: usize, area: f32) -> f32 {
    let r = (LOCAL_OVERLAP * area.max(1.0) / (std::f32::consts::PI * n.max(1) as f32)).sqrt();
    r.clamp(LOCAL_RANGE.0, LOCAL_RANGE.1)
}

/// `spots` + `points` local lights over `floors`: positions follow a seeded low-discrepancy
/// sequence over the floors' combined area (so any count covers them evenly), each light hangs
/// a fraction of its range above the floor (`height(floor index, xz)` gives the floor's
/// height), spots point down (tilted up to 25°), and a light that would sit inside one of the
/// `obstacles` (world AABBs) moves to the next point of the sequence. The range comes from
/// [`local_range`]; the brightness at the light's key distance (its height) is
/// `brightness`, so the total light on a floor point stays about the same at any count.
#[allow(clippy::too_many_arguments)]
pub(crate) fn local(
    spots: usize,
    points: usize,
    floors: &[Floor],
    height: &dyn Fn(usize, Vec2) -> f32,
    obstacles: &[(Vec3, Vec3)],
    rng: &mut Rand,
    brightness: f32,
    resolution: Option<u32>,
) -> Vec<Light> {
    let n = spots + points;
    let mut out = Vec::with_capacity(n);
    let area: f32 = floors.iter().map(Floor::area).sum();
    if n == 0 || floors.is_empty() || area <= 0.0 {
        return out;
    }
    let range = local_range(n, area);
    let offset = Vec2::new(rng.unit(), rng.unit());
    // Cumulative area fractions: floor i owns u.x in [cum[i], cum[i + 1]).
    let mut cum = Vec::with_capacity(floors.len() + 1);
    cum.push(0.0f32);
    for f in floors {
        cum.push(cum.last().copied().unwrap_or(0.0) + f.area() / area);
    }
    let blocked = |p: Vec3| {
        let pad = Vec3::splat(0.05);
        obstacles
            .iter()
            .any(|&(lo, hi)| p.cmpge(lo - pad).all() && p.cmple(hi + pad).all())
    };
    let mut k = 0usize;
    for i in 0..n {
        let is_spot = i < spots;
        let above = range
            * if is_spot {
                rng.range(0.45, 0.7)
            } else {
                rng.range(0.3, 0.6)
            };
        let jitter = Vec2::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5));
        let mut position = Vec3::ZERO;
        for _attempt in 0..16 {
            let u = r2(k, offset);
            k += 1;
            let f = cum
                .windows(2)
                .position(|w| u.x < w[1])
                .unwrap_or(floors.len() - 1);
            let floor = floors[f];
            let fx = ((u.x - cum[f]) / (cum[f + 1] - cum[f]).max(1e-9)).clamp(0.0, 1.0);
            let size = floor.hi - floor.lo;
            // Jitter by up to half a light's spacing, staying on the floor.
            let spacing = (area / n as f32).sqrt();
            let xz =
                (floor.lo + Vec2::new(fx, u.y) * size + jitter * spacing).clamp(floor.lo, floor.hi);
            position = Vec3::new(xz.x, height(f, xz) + above, xz.y);
            if !blocked(position) {
                break;
            }
        }
        let tone = Tone {
            color: tint(rng),
            brightness,
        };
        if is_spot {
            let tilt = rng.range(0.0, 25f32.to_radians());
            let az = rng.range(0.0, TAU);
            let direction = Vec3::new(tilt.sin() * az.cos(), -tilt.cos(), tilt.sin() * az.sin());
            let cutoff = rng.range(35.0, 50.0);
            out.push(spot(
                position,
                direction,
                cutoff,
                range,
                above / tilt.cos(),
                tone,
                resolution,
            ));
        } else {
            out.push(point(position, range, above, tone, resolution));
        }
    }
    out
}

/// Sorts lights along a Morton (Z-order) curve of their positions, each axis scaled to the
/// lights' bounds: lights near each other come near each other in the list (directional
/// lights, which have no position, first, in their order). The ray-traced technique's
/// sampled lights are stratified over each pixel's lights in list order
/// (`--light-samples K` with `--denoise`), so in this order a pixel's samples over frames
/// spread over the space around it rather than over the list's arbitrary order, which lowers
/// the denoised error of still frames; of the curves tried, a Morton curve over the lights'
/// bounds did best (docs/decisions.md, "Lights listed in space order"). The sequence the
/// positions come from spreads consecutive lights apart, the opposite. Applied to every
/// seeded layout above [`LOCAL_LAYOUT_ABOVE`] lights, once, where the layout leaves the
/// module (`builtin::build`, `builtin::scatter_lights`); the hand-made layouts keep their
/// order.
pub(crate) fn spatial_order(lights: &mut [Light]) {
    let centre = |l: &Light| l.bounding_sphere().map(|(c, _)| c);
    let (lo, hi) = lights.iter().filter_map(centre).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), c| (lo.min(c), hi.max(c)),
    );
    let extent = (hi - lo).max(Vec3::splat(1e-6));
    // Past the 0 of the directional lights.
    let key = |l: &Light| centre(l).map_or(0, |c| 1 + crate::zorder::key3((c - lo) / extent));
    lights.sort_by_cached_key(key);
}

/// World-space bounding boxes of a scene's instances (for [`local`]'s obstacles).
pub(crate) fn instance_boxes(
    meshes: &[crate::model::Mesh],
    instances: &[crate::model::Instance],
) -> Vec<(Vec3, Vec3)> {
    instances
        .iter()
        .filter_map(|inst| {
            let (lo, hi) = meshes.get(inst.mesh)?.bounds()?;
            let corners = (0..8).map(|i| {
                inst.transform.transform_point3(Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                ))
            });
            Some(corners.fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(a, b), p| (a.min(p), b.max(p)),
            ))
        })
        .collect()
}
