//! How a technique declares itself: one [`TechniqueInfo`] in its own module says its name,
//! what it is, what it fills, which point-shadow modes it renders, what it needs of the
//! device, how it is built and which WGSL it compiles. The registry
//! ([`crate::registry`]) is the list of them; nothing else names a technique.

use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::error::{Fills, RenderError, Technique};
use crate::gpu::context::GpuContext;
use crate::gpu_scene::instances::GpuScene;
use crate::shadows::cost::Cost;
use crate::shadows::lookup::LookupWgsl;
use crate::shadows::report::{ShadowReport, ShadowText};
use crate::shadows::source::{PlanParams, ShadowSource, SourceSettings};
use crate::shadows::technique::ShadowTechnique;

/// Where a technique drops the caster triangles a shadow view cannot see, which decides how its
/// work grows with views × triangles.
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Culling {
    /// Whole instances per view by bounding sphere on the CPU; per-triangle culling is not
    /// applied (`ShadowOptions::cull` is ignored).
    Instances,
    /// Clusters of triangles per view in a compute pass before drawing.
    Clusters,
    /// Every caster triangle reaches every view's vertex stage, which drops the culled ones.
    VertexStage,
    /// One compute thread per (caster triangle, view) sets up, culls and rasterizes.
    Threads,
    /// No per-view triangle work: the technique tests samples or casts rays.
    NoViews,
}

impl Culling {
    /// True if the technique applies `ShadowOptions::cull` to triangles.
    pub fn honours_cull_mode(self) -> bool {
        matches!(
            self,
            Culling::Clusters | Culling::VertexStage | Culling::Threads
        )
    }
}

/// Something a technique needs of the device.
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Requirement {
    /// An optional wgpu feature.
    Feature(wgpu::Features),
    /// Indirect draws and dispatches (a downlevel flag: OpenGL ES and WebGL may lack it).
    IndirectExecution,
    /// The `MULTIVIEW` feature with at least one view per pass (Mesa 25's OpenGL reports
    /// the feature with a `max_multiview_view_count` of 0).
    Multiview,
}

/// A [`Requirement`] and what the technique uses it for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Need {
    /// What the device must have.
    pub requirement: Requirement,
    /// What the technique does with it ("to keep each view inside its atlas tile").
    pub purpose: &'static str,
}

impl Need {
    /// Needs `feature` for `purpose`.
    pub const fn feature(feature: wgpu::Features, purpose: &'static str) -> Self {
        Need {
            requirement: Requirement::Feature(feature),
            purpose,
        }
    }

    /// Needs multiview passes of at least one view for `purpose`.
    pub const fn multiview(purpose: &'static str) -> Self {
        Need {
            requirement: Requirement::Multiview,
            purpose,
        }
    }

    /// Needs indirect execution for `purpose`.
    pub const fn indirect(purpose: &'static str) -> Self {
        Need {
            requirement: Requirement::IndirectExecution,
            purpose,
        }
    }

    /// The requirement's name as wgpu spells it.
    pub fn name(&self) -> String {
        match self.requirement {
            Requirement::Feature(f) => f.to_string(),
            Requirement::IndirectExecution => "INDIRECT_EXECUTION".into(),
            Requirement::Multiview => "MULTIVIEW".into(),
        }
    }

    /// True if `ctx`'s device meets it.
    pub fn met(&self, ctx: &GpuContext) -> bool {
        match self.requirement {
            Requirement::Feature(f) => ctx.has(f),
            Requirement::IndirectExecution => ctx
                .adapter
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION),
            Requirement::Multiview => {
                ctx.has(wgpu::Features::MULTIVIEW) && ctx.limits().max_multiview_view_count > 0
            }
        }
    }
}

/// Builds an atlas technique's pipelines (after its needs were checked).
pub(crate) type BuildAtlas = fn(&GpuContext) -> Result<Box<dyn ShadowTechnique>, RenderError>;

/// What a technique that fills no atlas is built from.
pub(crate) struct SourceArgs<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a Scene,
    pub gpu: &'a GpuScene,
    pub params: PlanParams,
    pub settings: &'a SourceSettings<'a>,
}

/// Builds a technique's shadow source (after its needs were checked).
pub(crate) type BuildSource = fn(SourceArgs<'_>) -> Result<Box<dyn ShadowSource>, RenderError>;

/// How a technique is built: an atlas technique is driven by the shadow generator (caching,
/// the atlas); any other kind is a whole shadow source of its own.
#[derive(Clone, Copy)]
pub(crate) enum Build {
    Atlas(BuildAtlas),
    Source(BuildSource),
}

/// One composed shader of a technique.
#[derive(Clone, Debug)]
pub struct Wgsl {
    /// Its name (the module's label).
    pub name: &'static str,
    /// The composed source.
    pub source: String,
    /// The device features it is compiled only with (`enable clip_distances;`, multiview):
    /// on a WebGPU device without them the technique, or this part of it, is not used.
    pub features: wgpu::Features,
}

impl Wgsl {
    /// A shader that needs no optional feature.
    pub fn core(name: &'static str, source: String) -> Self {
        Wgsl {
            name,
            source,
            features: wgpu::Features::empty(),
        }
    }

    /// A shader compiled only where the device has `features`.
    pub fn with(name: &'static str, source: String, features: wgpu::Features) -> Self {
        Wgsl {
            name,
            source,
            features,
        }
    }
}

/// One technique, declared once in its module.
pub struct TechniqueInfo {
    /// The technique (its name is `--technique`'s value).
    pub technique: Technique,
    /// One line for `--help`, menus and tables.
    pub summary: &'static str,
    /// The seed or paper it implements.
    pub origin: &'static str,
    /// What it fills.
    pub fills: Fills,
    /// Where it culls casters per view (which also says whether it applies
    /// [`crate::ShadowOptions::cull`]: [`Culling::honours_cull_mode`]).
    pub culling: Culling,
    /// The point-light shadow modes it renders.
    pub point_shadows: &'static [PointShadows],
    /// What it needs of the device beyond the renderer's own minimum.
    pub needs: &'static [Need],
    /// Whether sized lights soften its shadows (false: it answers lit or not at the light's
    /// centre, whatever the light's size, and says so).
    pub soft_shadows: bool,
    /// Its price list for the frame estimate (`Renderer::estimate_frame`): how its lighting
    /// pass reads shadows and what its shadow stage costs.
    pub cost: Cost,
    /// Whether its shadows answer for the camera's pixels only (a visibility mask): no other
    /// view can be lit with them, so a scene's reflection probes are left out, with a note.
    pub camera_pixels_only: bool,
    /// Whether what it keeps of the shadows follows the camera (virtual pages): views lit
    /// with them (the probes' faces) are redrawn when the camera moves.
    pub follows_camera: bool,
    /// What a frame says of its shadows in words (`Frame::report`: the lines `render` prints
    /// under its summary, and its line per frame of a sequence): the atlas techniques share
    /// `atlas/shared.rs`'s `atlas_report`.
    pub report: fn(&ShadowReport<'_>) -> ShadowText,
    /// What to use where it cannot run.
    pub instead: &'static str,
    /// How the lighting and visibility passes read its shadows (the atlas techniques share
    /// `shadows::lookup::ATLAS_LOOKUP`).
    pub(crate) lookup: LookupWgsl,
    pub(crate) build: Build,
    /// Its composed WGSL (validated by naga in the tests).
    pub(crate) shaders: fn() -> Vec<Wgsl>,
}

impl TechniqueInfo {
    /// The needs `ctx`'s device does not meet.
    pub fn unmet(&self, ctx: &GpuContext) -> Vec<Need> {
        self.needs.iter().filter(|n| !n.met(ctx)).copied().collect()
    }

    /// Refuses the technique on `ctx`'s device with [`RenderError::MissingFeature`] when a
    /// need is unmet.
    pub fn check(&self, ctx: &GpuContext) -> Result<(), RenderError> {
        match self.unmet(ctx).first() {
            None => Ok(()),
            Some(need) => Err(RenderError::missing_feature(
                ctx,
                format!("technique {}", self.technique),
                format!("the {} feature ({})", need.name(), need.purpose),
                self.instead,
            )),
        }
    }

    /// Refuses a point-shadow mode the technique does not render.
    pub fn check_point_shadows(&self, mode: PointShadows) -> Result<(), RenderError> {
        if self.point_shadows.contains(&mode) {
            Ok(())
        } else {
            Err(RenderError::UnsupportedCombination {
                technique: self.technique,
                option: "point shadows",
                value: mode.name(),
                supported: self.point_shadows.iter().map(|m| m.name()).collect(),
            })
        }
    }

    /// Builds an atlas technique's pipelines, after checking its needs against the device;
    /// [`RenderError::NoAtlas`] for a technique that fills no atlas.
    pub fn create_atlas(&self, ctx: &GpuContext) -> Result<Box<dyn ShadowTechnique>, RenderError> {
        match self.build {
            Build::Atlas(build) => {
                self.check(ctx)?;
                build(ctx)
            }
            Build::Source(_) => Err(RenderError::NoAtlas {
                technique: self.technique,
                fills: self.fills,
            }),
        }
    }

    /// Whether a shadow budget applies to it (`RenderSettings::shadow_budget`): the atlas
    /// techniques, whose views the caching generator draws.
    pub fn takes_shadow_budget(&self) -> bool {
        matches!(self.build, Build::Atlas(_))
    }

    /// The technique's composed WGSL.
    pub fn shaders(&self) -> Vec<Wgsl> {
        (self.shaders)()
    }

    /// The features its shaders may use (those of its needs).
    pub fn features(&self) -> wgpu::Features {
        self.needs
            .iter()
            .fold(wgpu::Features::empty(), |f, n| match n.requirement {
                Requirement::Feature(x) => f | x,
                Requirement::Multiview => f | wgpu::Features::MULTIVIEW,
                Requirement::IndirectExecution => f,
            })
    }
}

impl std::fmt::Debug for TechniqueInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TechniqueInfo")
            .field("technique", &self.technique)
            .field("fills", &self.fills)
            .field("point_shadows", &self.point_shadows)
            .field("needs", &self.needs)
            .finish_non_exhaustive()
    }
}
