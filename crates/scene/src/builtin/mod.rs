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

pub mod analytic;
pub mod atrium;
pub mod courtyard;
pub mod cubes;
pub mod dragon;
mod lights;
pub mod terrain;

use std::fmt;
use std::str::FromStr;

use crate::{Light, Mesh, Scene, SceneError};

pub use analytic::*;
pub use lights::{
    local_range, LightCounts, AMBIENT_FRACTION, DIRECTIONAL_CASCADES,
    DIRECTIONAL_SHADOW_RESOLUTION, DIRECTIONAL_SPLIT_LAMBDA, LOCAL_BRIGHTNESS, LOCAL_LAYOUT_ABOVE,
    LOCAL_OVERLAP, LOCAL_RANGE, POINT_SHADOW_RESOLUTION, SPOT_SHADOW_RESOLUTION,
};

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
];

/// The most lights a built-in scene or [`scatter_lights`] layout may ask for; more is a
/// [`SceneError::InvalidRequest`]. Layouts above [`LOCAL_LAYOUT_ABOVE`] lights are local
/// lights of bounded range, so a frame stays readable at any count up to this one.
pub const MAX_LIGHTS: usize = 16384;

/// Which light types a seeded layout uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightMix {
    /// Mostly spots (≈ 60 %), some points (≈ 30 %) and one directional light per 64 lights
    /// (at least one when there are 3 or more lights, at most two); see [`LightCounts::split`].
    #[default]
    All,
    /// Spot lights only.
    Spot,
    /// Point lights only.
    Point,
    /// Directional lights only (expensive: each has cascades).
    Directional,
}

impl LightMix {
    /// The names [`FromStr`] accepts (besides the alias `"mixed"` for `"all"`).
    pub const NAMES: &'static [&'static str] = &["all", "spot", "point", "directional"];

    /// The canonical name, as [`FromStr`] parses it.
    pub fn as_str(self) -> &'static str {
        match self {
            LightMix::All => "all",
            LightMix::Spot => "spot",
            LightMix::Point => "point",
            LightMix::Directional => "directional",
        }
    }
}

impl fmt::Display for LightMix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for LightMix {
    type Err = SceneError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "all" | "mixed" => Ok(LightMix::All),
            "spot" => Ok(LightMix::Spot),
            "point" => Ok(LightMix::Point),
            "directional" => Ok(LightMix::Directional),
            _ => Err(SceneError::InvalidRequest(format!(
                "unknown light mix '{s}' (expected one of: all (or mixed), spot, point, directional)"
            ))),
        }
    }
}

/// What to build: light count, seed, light types, a mesh for the dragon scene and a shadow-map
/// resolution override.
#[derive(Clone, Debug)]
pub struct BuiltinOptions {
    /// Number of lights; `None` means the scene's default (atrium 32, terrain 8, dragon 8,
    /// `plane-*` 1, cubes 3, courtyard 8). The `plane-*` scenes always have exactly their one light.
    pub lights: Option<usize>,
    /// Seed of the light layout (positions, directions, colours).
    pub seed: u64,
    /// Light types of the layout.
    pub mix: LightMix,
    /// The model for the `dragon` scene (normalised to stand 2 m tall at the origin); `None`
    /// uses a procedural stand-in. Other scenes ignore it.
    pub mesh: Option<Mesh>,
    /// Shadow-map resolution (texels per side, per cube face, per cascade) for every light;
    /// `None` uses the defaults: spot 512, point 256, directional 1024 (the analytic scenes
    /// use 1024 for all).
    pub shadow_resolution: Option<u32>,
}

impl Default for BuiltinOptions {
    fn default() -> Self {
        Self {
            lights: None,
            seed: 1,
            mix: LightMix::All,
            mesh: None,
            shadow_resolution: None,
        }
    }
}

/// Builds the built-in scene `name` (one of [`SCENE_NAMES`]).
///
/// Errors: [`SceneError::UnknownScene`] listing the names; [`SceneError::InvalidRequest`] for
/// more than [`MAX_LIGHTS`] lights or a shadow resolution outside `1..=16384`; whatever
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
    let scene = match name {
        "atrium" => atrium::build(opts),
        "terrain" => terrain::build(opts),
        "dragon" => dragon::build(opts)?,
        "plane-spot" => analytic::build(analytic::AnalyticLight::Spot, opts),
        "plane-point" => analytic::build(analytic::AnalyticLight::Point, opts),
        "plane-directional" => analytic::build(analytic::AnalyticLight::Directional, opts),
        "cubes" => cubes::build(opts),
        "courtyard" => courtyard::build(opts, true),
        "courtyard-opaque" => courtyard::build(opts, false),
        _ => unreachable!("checked against SCENE_NAMES above"),
    };
    scene.validate()?;
    Ok(scene)
}

/// Checks a requested light count against [`MAX_LIGHTS`].
pub fn check_light_count(n: usize) -> Result<(), SceneError> {
    if n > MAX_LIGHTS {
        return Err(SceneError::InvalidRequest(format!(
            "{n} lights requested, but at most {MAX_LIGHTS} are supported"
        )));
    }
    Ok(())
}

/// A generic seeded layout of `n` lights inside `scene`'s world bounds, for scenes that have no
/// layout of their own (TOML scenes given `--lights N`).
///
/// Spots hang in the upper part of the bounds pointing roughly down, points float in the lower
/// half, directional lights slant in at 35–65° elevation; positions follow a jittered
/// low-discrepancy sequence so any `n` covers the area evenly. Ranges shrink as `n` grows so
/// each light affects a neighbourhood, not the whole scene. A scene with no geometry gets a
/// layout over a 10 m square. The caller checks `n` against [`MAX_LIGHTS`] (see
/// [`check_light_count`]); this function produces whatever it is asked for.
pub fn scatter_lights(
    scene: &Scene,
    n: usize,
    seed: u64,
    mix: LightMix,
    shadow_resolution: Option<u32>,
) -> Vec<Light> {
    lights::scatter(scene, n, seed, mix, shadow_resolution)
}
