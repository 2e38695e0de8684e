//! Built-in scenes and seeded light layouts.
//!
//! Why they exist: a renderer for *many* shadow-casting lights needs scenes where many lights
//! matter, with no asset files to download, that anyone can rebuild bit for bit. Every scene
//! here is generated from code and a seed:
//!
//! | name | what | default lights | why |
//! |---|---|---|---|
//! | `atrium` | a Sponza-like two-storey arcaded hall, ≥ 200k triangles in many instances | 32 | the many-lights workload: lights along the arcades, each affecting a neighbourhood |
//! | `terrain` | seed 004's 251×251 height field with 600 trees, rocks and grass tufts | 8 | a sun with cascades over a large area plus local lights |
//! | `dragon` | seed 000's benchmark: a ~35k-triangle model on a floor ringed by spots | 8 | the seed's layered-rendering measurements |
//! | `plane-spot`, `plane-point`, `plane-directional` | a square occluder over a floor, one light | 1 | analytic tests: the shadow's outline is known exactly ([`analytic`]) |
//! | `cubes` | a floor, a few boxes and a sphere, one light of each type | 3 | small golden images |
//! | `courtyard` | textured floor and walls, a lattice roof, banners, shrubs and a wire fence (alpha-masked cards), a few solids | 8 | real-content features: textures and alpha-masked casters in every technique ([`courtyard`]) |
//! | `courtyard-opaque` | `courtyard` with every material opaque | 8 | the same geometry without masks: what masks change |
//! | `crowd` | 64 tubes over a floor, each skinned to two joints and swaying (one 2 s clip) | 16 | animation: moving, deforming casters that caching, pages and rays must follow ([`crowd`]) |
//! | `walker` | one figure skinned to eight joints walking across a floor (one 2 s clip, "walk") | 16 | animation: a bent surface the denoiser's and reservoirs' histories must follow ([`walker`]) |
//!
//! Light layouts are **seeded and deterministic**: the same [`BuiltinOptions`] always give the
//! same scene. Geometry does not depend on the seed (so benchmarks with different light
//! layouts compare the same triangles). [`LightMix::All`] mixes types the way a real scene
//! would, mostly spots, some points and very few directional lights (the most expensive:
//! cascades); see [`LightCounts::split`].
//!
//! Brightness: the lights use [`Attenuation::for_range`](crate::Attenuation::for_range), which
//! falls to about 1/10 a third of the way to the range, so each light's colour is scaled up to
//! reach a useful brightness at the distance it is meant to light (its "key distance").
//! Each light's ambient colour is a small fraction of its diffuse colour ([`AMBIENT_FRACTION`]),
//! so shadowed areas stay dark but not black whatever the count.
//!
//! Sizes: every light has the default size of [`crate::light_size`] (a spot or point light's
//! radius 2 % of its range, a directional light the sun's 0.53°), so the default pictures show
//! soft shadows; `cubes` and the `plane-*` scenes keep hard lights (size 0), because golden
//! images and exact-outline tests compare them. [`BuiltinOptions::light_sizes`] overrides
//! every light's size in any scene.

pub mod analytic;
pub mod atrium;
pub mod courtyard;
pub mod crowd;
pub mod cubes;
pub mod dragon;
pub(crate) mod lights;
mod options;
pub mod terrain;
pub mod walker;

use crate::error::SceneError;
use crate::model::{Light, Scene};

pub use analytic::*;
pub use lights::{
    local_range, LightCounts, AMBIENT_FRACTION, DIRECTIONAL_CASCADES,
    DIRECTIONAL_SHADOW_RESOLUTION, DIRECTIONAL_SPLIT_LAMBDA, LOCAL_BRIGHTNESS, LOCAL_LAYOUT_ABOVE,
    LOCAL_OVERLAP, LOCAL_RANGE, POINT_SHADOW_RESOLUTION, SPOT_SHADOW_RESOLUTION,
};
pub use options::{check_light_count, BuiltinOptions, LightMix, MAX_LIGHTS};

/// Names accepted by [`build`], in the order the CLI lists them.
pub const SCENE_NAMES: &[&str] = &[
    "atrium",
    "terrain",
    "dragon",
    "plane-spot",
    "plane-point",
    "plane-directional",
    "cubes",
    "courtyard",
    "courtyard-opaque",
    "crowd",
    "walker",
];

/// Builds the built-in scene `name` (one of [`SCENE_NAMES`]). With more than
/// [`LOCAL_LAYOUT_ABOVE`] seeded lights (`opts.lights`) the list follows a Morton curve
/// through their positions, suns first (`lights::spatial_order` says why).
///
/// Errors: [`SceneError::UnknownScene`] listing the names; [`SceneError::InvalidRequest`] for
/// more than [`MAX_LIGHTS`] lights, a shadow resolution outside `1..=16384` or light sizes
/// [`LightSizes::check`](crate::light_size::LightSizes::check) refuses; whatever
/// [`Scene::validate`] finds (e.g. a bad `opts.mesh`). The returned scene has passed
/// [`Scene::validate`].
pub fn build(name: &str, opts: &BuiltinOptions) -> Result<Scene, SceneError> {
    if !SCENE_NAMES.contains(&name) {
        return Err(SceneError::UnknownScene {
            name: name.to_string(),
            known: SCENE_NAMES.join(", "),
        });
    }
    if let Some(n) = opts.lights {
        check_light_count(n)?;
    }
    if let Some(r) = opts.shadow_resolution {
        if !(1..=16384).contains(&r) {
            return Err(SceneError::InvalidRequest(format!(
                "shadow resolution {r} must be between 1 and 16384 texels"
            )));
        }
    }
    opts.light_sizes.check()?;
    let mut scene = match name {
        "atrium" => atrium::build(opts),
        "terrain" => terrain::build(opts),
        "dragon" => dragon::build(opts)?,
        "plane-spot" => analytic::build(analytic::AnalyticLight::Spot, opts),
        "plane-point" => analytic::build(analytic::AnalyticLight::Point, opts),
        "plane-directional" => analytic::build(analytic::AnalyticLight::Directional, opts),
        "cubes" => cubes::build(opts),
        "courtyard" => courtyard::build(opts, true),
        "courtyard-opaque" => courtyard::build(opts, false),
        "crowd" => crowd::build(opts),
        "walker" => walker::build(opts),
        _ => unreachable!("checked against SCENE_NAMES above"),
    };
    if opts.lights.is_some_and(|n| n > LOCAL_LAYOUT_ABOVE) {
        lights::spatial_order(&mut scene.lights);
    }
    opts.light_sizes.apply(&mut scene.lights);
    scene.validate()?;
    Ok(scene)
}

/// A generic seeded layout of `n` lights inside `scene`'s world bounds, for scenes that have no
/// layout of their own (TOML scenes given `--lights N`).
///
/// Spots hang in the upper part of the bounds pointing roughly down, points float in the lower
/// half, directional lights slant in at 35–65° elevation; positions follow a jittered
/// low-discrepancy sequence so any `n` covers the area evenly. Ranges shrink as `n` grows so
/// each light affects a neighbourhood, not the whole scene. A scene with no geometry gets a
/// layout over a 10 m square. Above [`LOCAL_LAYOUT_ABOVE`] lights the list follows a Morton
/// curve through their positions, as every seeded layout's does ([`build`]). The lights have the default sizes ([`crate::light_size`]). The
/// caller checks `n` against [`MAX_LIGHTS`] (see
/// [`check_light_count`]); this function produces whatever it is asked for.
pub fn scatter_lights(
    scene: &Scene,
    n: usize,
    seed: u64,
    mix: LightMix,
    shadow_resolution: Option<u32>,
) -> Vec<Light> {
    let mut out = lights::scatter(scene, n, seed, mix, shadow_resolution);
    if n > LOCAL_LAYOUT_ABOVE {
        lights::spatial_order(&mut out);
    }
    out
}
