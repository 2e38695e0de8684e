//! What a built-in scene is built with: the light count and its limit, the seed, the mix of
//! light types. Every scene module and the folder's `mod.rs` import these from here.

use std::fmt;
use std::str::FromStr;

use crate::error::SceneError;
use crate::light_size::LightSizes;
use crate::model::Mesh;

/// The most lights a built-in scene or [`scatter_lights`](super::scatter_lights) layout may
/// ask for; more is a [`SceneError::InvalidRequest`]. Layouts above
/// [`LOCAL_LAYOUT_ABOVE`](super::LOCAL_LAYOUT_ABOVE) lights are local lights of bounded
/// range, so a frame stays readable at any count up to this one.
pub const MAX_LIGHTS: usize = 16384;

/// Which light types a seeded layout uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightMix {
    /// Mostly spots (≈ 60 %), some points (≈ 30 %) and one directional light per 64 lights
    /// (at least one when there are 3 or more lights, at most two); see
    /// [`LightCounts::split`](super::LightCounts::split).
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

/// What to build: light count, seed, light types, a mesh for the dragon scene, and overrides of
/// every light's shadow-map resolution and size.
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
    /// Sizes for every light (radius of spots and points, angular diameter of suns); `None`
    /// parts keep the defaults: [`crate::light_size`]'s rule (2 % of the range, the sun's
    /// 0.53°), except `cubes` and the `plane-*` scenes, whose lights are hard (size 0) for
    /// exact comparisons. [`LightSizes::HARD`] makes every light hard.
    pub light_sizes: LightSizes,
    /// Place the scene's own reflection probes (the atrium: two in the nave, its floor and
    /// fountain reflective; scenes without a set: none). Off by default, so a library caller
    /// pays for probes only when asking; `manyshadows render` asks (`--probes`).
    pub default_probes: bool,
}

impl Default for BuiltinOptions {
    fn default() -> Self {
        Self {
            lights: None,
            seed: 1,
            mix: LightMix::All,
            mesh: None,
            shadow_resolution: None,
            light_sizes: LightSizes::default(),
            default_probes: false,
        }
    }
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
