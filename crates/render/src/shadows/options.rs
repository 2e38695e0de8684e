//! The shadow choices that belong to no one technique and that every source may read: per-view
//! culling and caster preparation ([`ShadowOptions`], [`CullMode`]), filtering ([`Pcf`]) and
//! the receiver [`ShadowBias`]. Plain data on the shadows' lowest floor; `RenderSettings`
//! (above every technique) holds them.

use crate::error::RenderError;
use crate::gpu_scene::caster_layout::CasterOptions;
use crate::gpu_scene::casters::CasterGeometry;

/// Which triangles single-pass techniques drop per view before rasterization (seed 000
/// Listings 19.9 and 19.10).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum CullMode {
    /// Every triangle goes to every view.
    None,
    /// Triangles wholly outside a view's frustum are dropped for that view.
    Frustum,
    /// Triangles facing away from the light are dropped (closed meshes only; see
    /// `CasterOptions::assume_closed`).
    Backface,
    /// Both.
    #[default]
    All,
}

impl CullMode {
    /// Every mode.
    pub const ALL: &'static [CullMode] = &[
        CullMode::None,
        CullMode::Frustum,
        CullMode::Backface,
        CullMode::All,
    ];

    /// CLI name.
    pub fn name(self) -> &'static str {
        match self {
            CullMode::None => "none",
            CullMode::Frustum => "frustum",
            CullMode::Backface => "backface",
            CullMode::All => "all",
        }
    }

    /// Frustum culling on.
    pub fn frustum(self) -> bool {
        matches!(self, CullMode::Frustum | CullMode::All)
    }

    /// Back-face culling on.
    pub fn backface(self) -> bool {
        matches!(self, CullMode::Backface | CullMode::All)
    }

    /// Bit flags for shaders: 1 = frustum, 2 = back-face.
    pub fn bits(self) -> u32 {
        u32::from(self.frustum()) | (u32::from(self.backface()) << 1)
    }

    /// The bits of a pass that culls `casters` per view as this mode asks: back-face culling
    /// forced on, with [`CULL_ALWAYS`] (in every kind of view, dual-paraboloid ones too), where
    /// single-sided casters cast only where a light sees their front
    /// (`CasterGeometry::front_only`): then culling the cullable triangles by facing is the
    /// rule, not a choice.
    pub fn bits_for(self, casters: &CasterGeometry) -> u32 {
        if casters.front_only {
            self.bits() | CullMode::Backface.bits() | CULL_ALWAYS
        } else {
            self.bits()
        }
    }
}

/// Cull bit (`CULL_ALWAYS` in `cull.wgsl`): back-face culling of the cullable triangles is the
/// rule for single-sided casters, applied in every kind of view.
pub const CULL_ALWAYS: u32 = 4;

impl std::str::FromStr for CullMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        CullMode::ALL
            .iter()
            .copied()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!("unknown cull mode '{s}' (expected none, frustum, backface or all)")
            })
    }
}

/// Options every technique honours.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct ShadowOptions {
    /// Per-view triangle culling of the single-pass techniques (`traditional` always culls
    /// whole instances by their bounding sphere on the CPU, and nothing else).
    pub cull: CullMode,
    /// How caster geometry is prepared.
    pub casters: CasterOptions,
    /// Benchmark only: a zero-sized scissor rectangle, so geometry is transformed, culled,
    /// clipped and set up but no fragment is produced. The closest wgpu gets to seed 000's
    /// `GL_RASTERIZER_DISCARD`; the atlas is left cleared.
    pub discard_raster: bool,
}

/// Percentage-closer filtering of the shadow test.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Pcf {
    /// One comparison at the nearest texel: hard edges.
    Off,
    /// Bilinearly weighted comparison of the 2×2 nearest texels (one hardware lookup).
    #[default]
    Pcf2x2,
    /// Mean of the 3×3 texels around the nearest one.
    Pcf3x3,
}

impl Pcf {
    /// Every mode.
    pub const ALL: &'static [Pcf] = &[Pcf::Off, Pcf::Pcf2x2, Pcf::Pcf3x3];

    /// CLI name: `off`, `2x2`, `3x3`.
    pub fn name(self) -> &'static str {
        match self {
            Pcf::Off => "off",
            Pcf::Pcf2x2 => "2x2",
            Pcf::Pcf3x3 => "3x3",
        }
    }

    pub(crate) fn code(self) -> u32 {
        match self {
            Pcf::Off => 0,
            Pcf::Pcf2x2 => 1,
            Pcf::Pcf3x3 => 2,
        }
    }
}

impl std::str::FromStr for Pcf {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Pcf::ALL
            .iter()
            .copied()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown PCF mode '{s}' (expected off, 2x2 or 3x3)"))
    }
}

/// Receiver-side shadow bias, in shadow-map texels at the receiving point.
///
/// Before the depth comparison the point is moved `normal_offset` texels along its normal and
/// `constant + slope·tan θ` texels towards the light (θ = angle between normal and light
/// direction). Texel-relative bias scales with each view's resolution and distance, so one
/// setting fits spot, point and cascade views alike.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ShadowBias {
    /// Constant offset towards the light, texels.
    pub constant: f32,
    /// Offset towards the light per unit of tan θ, texels (clamped at tan θ = 10).
    pub slope: f32,
    /// Offset along the surface normal, texels.
    pub normal_offset: f32,
}

impl Default for ShadowBias {
    fn default() -> Self {
        Self {
            constant: 1.0,
            slope: 1.0,
            normal_offset: 1.0,
        }
    }
}

with_setters!(ShadowOptions {
    with_cull: cull: CullMode,
    with_casters: casters: CasterOptions,
    with_discard_raster: discard_raster: bool,
});

impl ShadowBias {
    /// A bias of `constant` and `slope` texels towards the light and `normal_offset` texels
    /// along the normal.
    pub fn new(constant: f32, slope: f32, normal_offset: f32) -> Self {
        Self {
            constant,
            slope,
            normal_offset,
        }
    }
}

/// Soft shadows of sized lights in the shadow-map techniques: percentage-closer soft shadows
/// (a blocker search, the penumbra it implies, a filter of that size), both with rotated
/// Vogel-disc taps. Lights of size 0 keep the hard test and its PCF.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct SoftShadows {
    /// Depth taps of the blocker search.
    pub blocker_taps: u32,
    /// Comparison taps of the penumbra filter.
    pub filter_taps: u32,
    /// Largest penumbra radius in shadow texels (the search and the filter stop there).
    pub max_penumbra: f32,
}

impl Default for SoftShadows {
    fn default() -> Self {
        Self {
            blocker_taps: 16,
            filter_taps: 16,
            max_penumbra: 32.0,
        }
    }
}

with_setters!(SoftShadows {
    with_blocker_taps: blocker_taps: u32,
    with_filter_taps: filter_taps: u32,
    with_max_penumbra: max_penumbra: f32,
});

/// Most taps of the blocker search or the filter.
pub const MAX_SOFT_TAPS: u32 = 64;

impl SoftShadows {
    /// Checks the ranges ([`RenderError::InvalidOption`] names the first out of range).
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(1..=MAX_SOFT_TAPS).contains(&self.blocker_taps) {
            return Err(RenderError::invalid_option(
                "soft.blocker_taps",
                self.blocker_taps,
                "1 to 64 taps",
            ));
        }
        if !(1..=MAX_SOFT_TAPS).contains(&self.filter_taps) {
            return Err(RenderError::invalid_option(
                "soft.filter_taps",
                self.filter_taps,
                "1 to 64 taps",
            ));
        }
        if !(self.max_penumbra.is_finite() && (1.0..=256.0).contains(&self.max_penumbra)) {
            return Err(RenderError::invalid_option(
                "soft.max_penumbra",
                self.max_penumbra,
                "1 to 256 shadow texels",
            ));
        }
        Ok(())
    }
}
