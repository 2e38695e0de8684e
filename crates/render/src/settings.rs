//! What a caller chooses for a frame: [`RenderSettings`] and the choices it holds that belong
//! to no one pass (the [`Technique`], culling and caster [`ShadowOptions`], filtering, bias).
//! Knobs of one feature stay with it and are gathered here: the caster options
//! (`CasterOptions::assume_closed`), the light loop and cluster grid ([`crate::frame::clusters`]),
//! irregular and virtual shadow maps ([`crate::shadows::irregular`], [`crate::shadows::vsm`]).
//! Plain data: the sources and the renderer read it; nothing it names reads it.

use manyshadows_scene::atlas::FitPolicy;

use crate::frame::clusters::{ClusterOptions, LightLoop};
use crate::gpu_scene::casters::CasterOptions;
use crate::shadows::irregular::maps::{IrregularOptions, GRID_LIMIT};
use crate::shadows::raytraced::accel::{RayOptions, MAX_LIGHT_SAMPLES};
use crate::shadows::vsm::plan::{VirtualOptions, PAGE_SIZE};
use crate::RenderError;

/// A shadow technique, by its name. Every technique declares itself once, in its own module,
/// with a [`TechniqueInfo`](crate::shadows::descriptor::TechniqueInfo) (name, summary, what it
/// fills, point-shadow modes, the features it needs, its constructor and its WGSL) and a
/// constant here (`Technique::LAYERED`…); the registry ([`Technique::all`]) lists them, and
/// everything that offers a choice of technique (the CLI's `--technique` and its help, the
/// benchmarks' defaults, the viewer's and the web page's menus) reads it.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Technique(&'static str);

impl Technique {
    /// The technique called `name` (its module's constant; only the registry makes them
    /// reachable by name).
    pub(crate) const fn named(name: &'static str) -> Self {
        Technique(name)
    }

    /// The name (`--technique`'s value).
    pub fn name(self) -> &'static str {
        self.0
    }
}

impl std::fmt::Display for Technique {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

impl std::fmt::Debug for Technique {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Technique({})", self.0)
    }
}

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

/// How a frame is rendered.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Shadow generation technique.
    pub technique: Technique,
    /// Culling and caster options of the technique.
    pub shadow: ShadowOptions,
    /// Keep what did not change between frames (default on): the atlas tiles of views that
    /// saw no change, the virtual pages of unchanged faces away from moved casters. Changes
    /// reach the renderer only through its setters, so nothing is kept that a change
    /// touched; the first frame is the same either way. Off draws every map anew each frame
    /// (what a benchmark of a whole frame's shadow work wants).
    pub cache_shadows: bool,
    /// At most this many shadow views drawn per frame (atlas techniques; implies
    /// [`Self::cache_shadows`]): the others wait, served from their older depth where their
    /// tile holds it and unshadowed where it holds nothing of them yet, counted in
    /// [`crate::Frame::shadow_stats`]. `None`: every view that changed is drawn.
    pub shadow_budget: Option<u32>,
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
    /// Knobs of [`Technique::IRREGULAR`] (ignored by the other techniques).
    pub irregular: IrregularOptions,
    /// Knobs of [`Technique::VIRTUAL`] (ignored by the other techniques).
    pub virtual_maps: VirtualOptions,
    /// Knobs of [`Technique::RAYTRACED`] (ignored by the other techniques).
    pub rays: RayOptions,
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
            cache_shadows: true,
            shadow_budget: None,
            point_shadows: Default::default(),
            pcf: Pcf::default(),
            bias: ShadowBias::default(),
            max_atlas_size: None,
            fit: FitPolicy::default(),
            visibility: false,
            irregular: IrregularOptions::default(),
            virtual_maps: VirtualOptions::default(),
            rays: RayOptions::default(),
            light_loop: LightLoop::default(),
            clusters: ClusterOptions::default(),
        }
    }
}

impl RenderSettings {
    /// Checks every value that has a range of its own, before anything is built: the first
    /// one out of range is [`RenderError::InvalidOption`] naming the field as this struct
    /// does (`irregular.hash`). Limits that depend on the device (the largest image, atlas or
    /// pool) are checked, or clamped with a note in the frame's statistics, by
    /// [`crate::Renderer::new`]. Nothing is clamped silently here.
    pub fn validate(&self) -> Result<(), RenderError> {
        fn bad(
            option: &'static str,
            value: impl std::fmt::Display,
            expected: &'static str,
        ) -> RenderError {
            RenderError::InvalidOption {
                option,
                value: value.to_string(),
                expected,
            }
        }
        if self.width == 0 {
            return Err(bad("width", self.width, "at least 1 pixel"));
        }
        if self.height == 0 {
            return Err(bad("height", self.height, "at least 1 pixel"));
        }
        if self.shadow_budget == Some(0) {
            return Err(bad(
                "shadow_budget",
                0,
                "at least 1 view per frame (or none for no budget)",
            ));
        }
        if let Some(m) = self
            .max_atlas_size
            .filter(|&m| m < manyshadows_scene::atlas::MIN_TILE)
        {
            return Err(bad(
                "max_atlas_size",
                m,
                "the atlas must hold at least one tile of the smallest size (16 texels)",
            ));
        }
        for (option, v) in [
            ("bias.constant", self.bias.constant),
            ("bias.slope", self.bias.slope),
            ("bias.normal_offset", self.bias.normal_offset),
        ] {
            if !v.is_finite() {
                return Err(bad(option, v, "a finite number of texels"));
            }
        }
        if self.clusters.tile == 0 {
            return Err(bad("clusters.tile", self.clusters.tile, "at least 1 pixel"));
        }
        if !(1..=256).contains(&self.clusters.slices) {
            return Err(bad(
                "clusters.slices",
                self.clusters.slices,
                "1 to 256 depth slices",
            ));
        }
        if self.clusters.pool_bytes == Some(0) {
            return Err(bad(
                "clusters.pool_bytes",
                0,
                "at least 1 byte, or None for the default",
            ));
        }
        if let Some(g) = self
            .irregular
            .grid
            .filter(|g| !(1..=GRID_LIMIT).contains(g))
        {
            return Err(bad(
                "irregular.grid",
                g,
                "1 to 1024 texels per side (GRID_LIMIT)",
            ));
        }
        if self.irregular.hash == Some(0) {
            return Err(bad(
                "irregular.hash",
                0,
                "at least 1 (1 = one list per texel, no hashing)",
            ));
        }
        let page_bytes = u64::from(PAGE_SIZE) * u64::from(PAGE_SIZE) * 4;
        if self.virtual_maps.pool_bytes < page_bytes {
            return Err(bad(
                "virtual_maps.pool_bytes",
                self.virtual_maps.pool_bytes,
                "at least one 128x128 page of 32-bit depth (65,536 bytes)",
            ));
        }
        if !(self.virtual_maps.lod.is_finite() && self.virtual_maps.lod > 0.0) {
            return Err(bad(
                "virtual_maps.lod",
                self.virtual_maps.lod,
                "a positive number of shadow texels per pixel",
            ));
        }
        if !(self.virtual_maps.directed_lod.is_finite() && self.virtual_maps.directed_lod > 0.0) {
            return Err(bad(
                "virtual_maps.directed_lod",
                self.virtual_maps.directed_lod,
                "a positive factor on virtual_maps.lod",
            ));
        }
        if !(self.virtual_maps.bias_scale.is_finite()
            && (0.0..=16.0).contains(&self.virtual_maps.bias_scale))
        {
            return Err(bad(
                "virtual_maps.bias_scale",
                self.virtual_maps.bias_scale,
                "a fraction of the shadow bias from 0 to 16",
            ));
        }
        if self.rays.light_samples > MAX_LIGHT_SAMPLES {
            return Err(bad(
                "rays.light_samples",
                self.rays.light_samples,
                "0 (every light) to 16 sampled lights per pixel",
            ));
        }
        if self.virtual_maps.max_side == 0 {
            return Err(bad(
                "virtual_maps.max_side",
                0,
                "a virtual side of 128 to 16,384 texels (rounded to a power of two)",
            ));
        }
        Ok(())
    }
}

with_setters!(RenderSettings {
    with_width: width: u32,
    with_height: height: u32,
    with_technique: technique: Technique,
    with_shadow: shadow: ShadowOptions,
    with_cache_shadows: cache_shadows: bool,
    with_shadow_budget: shadow_budget: Option<u32>,
    with_point_shadows: point_shadows: manyshadows_scene::light_space::PointShadows,
    with_pcf: pcf: Pcf,
    with_bias: bias: ShadowBias,
    with_max_atlas_size: max_atlas_size: Option<u32>,
    with_fit: fit: FitPolicy,
    with_visibility: visibility: bool,
    with_irregular: irregular: IrregularOptions,
    with_virtual_maps: virtual_maps: VirtualOptions,
    with_rays: rays: RayOptions,
    with_light_loop: light_loop: LightLoop,
    with_clusters: clusters: ClusterOptions,
});

impl RenderSettings {
    /// Default settings at `width`×`height`.
    pub fn new(width: u32, height: u32) -> Self {
        Self::default().with_width(width).with_height(height)
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
