//! What a caller chooses for a frame: [`RenderSettings`] and the choices it holds that belong
//! to no one pass (the [`Technique`], culling and caster [`ShadowOptions`], filtering, bias).
//! Knobs of one feature stay with it and are gathered here: the caster options
//! ([`crate::gpu_scene::casters`]), the light loop and cluster grid ([`crate::frame::clusters`]),
//! irregular and virtual shadow maps ([`crate::shadows::irregular`], [`crate::shadows::vsm`]).
//! Plain data: the sources and the renderer read it; nothing it names reads it.

use manyshadows_scene::atlas::FitPolicy;

use crate::frame::clusters::{ClusterOptions, LightLoop};
use crate::gpu_scene::casters::CasterOptions;
use crate::shadows::irregular::maps::IrregularOptions;
use crate::shadows::vsm::plan::VirtualOptions;

/// Why `irregular` cannot stand where an atlas-filling technique is expected.
pub const IRREGULAR_NO_ATLAS: &str = "technique irregular computes the visibility mask \
     directly and fills no shadow atlas, so it runs in frames (render, compare) but not where \
     atlas tiles are generated or benchmarked on their own (bench layered, bench omni, atlas \
     read-back)";

/// Why `virtual` cannot stand where an atlas-filling technique is expected.
pub const VIRTUAL_NO_ATLAS: &str = "technique virtual renders only the pages the camera's \
     samples need, into a page pool instead of an atlas, so it runs in frames (render, \
     compare, bench virtual) but not where atlas tiles are generated or benchmarked on their \
     own (bench layered, bench omni, atlas read-back)";

/// The techniques that exist, by CLI name.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Technique {
    /// One depth-only pass per shadow view (seed 004, seed 000 §19.2).
    #[default]
    Traditional,
    /// One instanced draw fills every view's tile (seed 000 §19.3).
    Layered,
    /// One multiview pass per group of equal-size views (seed 000 §19.5); needs `MULTIVIEW`.
    Multiview,
    /// Clusters culled per view in compute, one indirect multi-draw (seed 002).
    GpuDriven,
    /// A compute-shader rasterizer: every view in one set of dispatches, depth by atomicMin.
    Compute,
    /// Irregular shadow maps (seed 001): camera samples in per-texel lists of each light
    /// view, exact tests per triangle; produces the visibility mask, not atlas tiles
    /// ([`crate::shadows::irregular`]), so it runs in the [`crate::Renderer`] only.
    Irregular,
    /// Virtual shadow maps (seed 002): a paged virtual map per light face, only the pages visible
    /// samples need, rendered into a page pool ([`crate::shadows::vsm`]); fills no atlas, so it
    /// runs in the [`crate::Renderer`] only.
    Virtual,
}

impl Technique {
    /// Every technique.
    pub const ALL: &'static [Technique] = &[
        Technique::Traditional,
        Technique::Layered,
        Technique::Multiview,
        Technique::GpuDriven,
        Technique::Compute,
        Technique::Irregular,
        Technique::Virtual,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Technique::Traditional => "traditional",
            Technique::Layered => "layered",
            Technique::Multiview => "multiview",
            Technique::GpuDriven => "gpu-driven",
            Technique::Compute => "compute",
            Technique::Irregular => "irregular",
            Technique::Virtual => "virtual",
        }
    }

    /// One line for `--help` and tables.
    pub fn summary(self) -> &'static str {
        match self {
            Technique::Traditional => "one depth pass per shadow view, instances culled on the CPU",
            Technique::Layered => {
                "one instanced draw into every tile; per-view triangle culling in the vertex shader"
            }
            Technique::Multiview => {
                "one multiview pass per group of equal-size views (cube faces, cascades), then \
                 a copy into the tiles; needs MULTIVIEW"
            }
            Technique::GpuDriven => {
                "compute culls triangle clusters per view and writes indirect draws; one \
                 multi-draw fills every tile"
            }
            Technique::Compute => {
                "compute-shader rasterizer: per-view culling, clipping and binning in compute, \
                 depth by atomicMin into a buffer, then copied into the tiles"
            }
            Technique::Irregular => {
                "irregular shadow maps: camera samples in per-texel lists of each light view, \
                 every caster triangle tested exactly against the samples under it; \
                 alias-free, fills no atlas"
            }
            Technique::Virtual => {
                "virtual shadow maps: a 16k² paged map per light face, only the pages the \
                 camera's samples need, at the resolution they need, rendered into a page pool"
            }
        }
    }
}

impl std::str::FromStr for Technique {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Technique::ALL
            .iter()
            .copied()
            .find(|t| t.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown technique '{s}' (techniques: {})",
                    Technique::ALL
                        .iter()
                        .map(|t| t.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }
}

impl std::fmt::Display for Technique {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which triangles single-pass techniques drop per view before rasterization (seed 000
/// Listings 19.9 and 19.10).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CullMode {
    /// Every triangle goes to every view.
    None,
    /// Triangles wholly outside a view's frustum are dropped for that view.
    Frustum,
    /// Triangles facing away from the light are dropped (closed meshes only; see
    /// [`crate::gpu_scene::casters`]).
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
}

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

/// How a frame is rendered.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Shadow generation technique.
    pub technique: Technique,
    /// Culling and caster options of the technique.
    pub shadow: ShadowOptions,
    /// Keep the tiles of unchanged views between frames (see [`crate::shadows::atlas::generator`]).
    pub cache_shadows: bool,
    /// Point-light shadows: six cube faces or two paraboloid hemispheres.
    pub point_shadows: manyshadows_scene::light_space::PointShadows,
    /// Shadow filtering.
    pub pcf: Pcf,
    /// Receiver bias.
    pub bias: ShadowBias,
    /// Largest atlas side (clamped to the adapter's limit); `None` =
    /// [`DEFAULT_MAX_ATLAS_SIZE`](crate::shadows::plan::DEFAULT_MAX_ATLAS_SIZE).
    pub max_atlas_size: Option<u32>,
    /// What to do when the shadow maps do not fit the atlas.
    pub fit: FitPolicy,
    /// Also compute the hard visibility mask.
    pub visibility: bool,
    /// Knobs of [`Technique::Irregular`] (ignored by the other techniques).
    pub irregular: IrregularOptions,
    /// Knobs of [`Technique::Virtual`] (ignored by the other techniques).
    pub virtual_maps: VirtualOptions,
    /// Which lights each pixel visits: its cluster's (default) or every light (reference).
    pub light_loop: LightLoop,
    /// The cluster grid.
    pub clusters: ClusterOptions,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            technique: Technique::default(),
            shadow: ShadowOptions::default(),
            cache_shadows: false,
            point_shadows: Default::default(),
            pcf: Pcf::default(),
            bias: ShadowBias::default(),
            max_atlas_size: None,
            fit: FitPolicy::default(),
            visibility: false,
            irregular: IrregularOptions::default(),
            virtual_maps: VirtualOptions::default(),
            light_loop: LightLoop::default(),
            clusters: ClusterOptions::default(),
        }
    }
}
