//! # manyshadows
//!
//! Scenes lit by many shadow-casting lights, on wgpu: spot, point and directional lights,
//! deferred Phong lighting with PCF, and a choice of shadow techniques — shadow maps in one
//! depth atlas (five ways to fill it), virtual shadow maps in a page pool, and exact irregular
//! shadow maps — that all answer the same question, per pixel and light: lit or not.
//!
//! ## A frame in five lines
//!
//! ```
//! use manyshadows::{AdapterRequest, GpuContext, RenderSettings, Renderer, Technique};
//!
//! // Any adapter: a GPU, or Vulkan/OpenGL on the CPU (Mesa lavapipe, llvmpipe).
//! let ctx = GpuContext::new(&AdapterRequest::default())?;
//! // A built-in scene (or `scene::loaders::load_scene` for a glTF/OBJ/PLY file).
//! let scene = manyshadows::scene::builtin::build("plane-spot", &Default::default())?;
//! let settings = RenderSettings::new(64, 48)
//!     .with_technique(Technique::LAYERED)
//!     .with_visibility(true);
//! let mut renderer = Renderer::new(&ctx, &scene, settings)?;
//! let frame = renderer.render()?;
//! assert_eq!(frame.rgba.len(), 64 * 48 * 4);
//! // One bit per pixel and light: the hard shadow test, what quality is measured on.
//! let mask = frame.visibility.expect("asked for");
//! let lit = (0..64).filter(|&x| mask.lit(x, 24, 0)).count();
//! assert!(lit > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## What to read
//!
//! - [`Renderer`]: a scene on the GPU. [`Renderer::render`] reads a [`Frame`] back (image,
//!   optional [`VisibilityMask`], [`FrameTimings`] with [`GpuTimes`] per [`Stage`], work
//!   counters); [`Renderer::render_to`] draws into a texture you own (a window's surface)
//!   without a read-back. Between frames, [`Renderer::set_camera`], [`Renderer::set_lights`]
//!   and [`Renderer::set_instance_transform`] change the scene; the next frame re-plans.
//! - [`RenderSettings`]: size, [`Technique`], culling ([`ShadowOptions`], [`CullMode`]),
//!   filtering ([`Pcf`]), [`ShadowBias`], and each technique's own knobs
//!   ([`IrregularOptions`], [`VirtualOptions`], [`ClusterOptions`]). Build it with the
//!   `with_*` setters; [`RenderSettings::validate`] names any value out of range.
//! - [`Technique`]: every technique declares itself once ([`TechniqueInfo`]: what it fills,
//!   the point-light shadows it renders, the device features it [`Need`]s);
//!   [`Technique::all`] lists them. A technique the device cannot run is refused by name
//!   ([`RenderError::MissingFeature`]; [`RenderError::is_unsupported`] groups such refusals).
//! - [`GpuContext`]: the adapter and device. [`GpuContext::new`] picks one;
//!   [`GpuContext::from_parts`] wraps a device your application made (it must reach
//!   [`required_limits`]: WebGPU's defaults with 2048² textures).
//! - [`RenderError`]: every failure, with typed fields; nothing panics on bad input.
//! - [`scene`]: the scene model, loaders and built-in scenes (`manyshadows-scene`, no GPU).
//!
//! The crate's inside — the GPU plumbing, the per-technique passes, the shadow plan — is
//! public only with the `internals` feature, for the project's own CLI, benchmarks and tests,
//! with no stability promise.

/// Builder-style setters for a `#[non_exhaustive]` options struct, one per field:
/// `RenderSettings::default().with_width(640).with_technique(Technique::VIRTUAL)`. Declared
/// before the modules so every floor's options use it without importing anything.
macro_rules! with_setters {
    ($ty:ident { $($setter:ident: $field:ident: $fty:ty),+ $(,)? }) => {
        impl $ty {
            $(
                #[doc = concat!("Sets [`", stringify!($ty), "::", stringify!($field), "`].")]
                #[must_use]
                pub fn $setter(mut self, $field: $fty) -> Self {
                    self.$field = $field;
                    self
                }
            )+
        }
    };
}

// The floors (ARCHITECTURE.md; `tests/import_floors/` holds them to it). They are
// the crate's inside: public only with the `internals` feature, which the project's own CLI,
// benchmarks and tests turn on and which promises no stability. An embedder uses the facade
// below.
pub mod error;
#[cfg(feature = "internals")]
pub mod frame;
#[cfg(not(feature = "internals"))]
pub(crate) mod frame;
#[cfg(feature = "internals")]
pub mod gpu;
#[cfg(not(feature = "internals"))]
pub(crate) mod gpu;
#[cfg(feature = "internals")]
pub mod gpu_scene;
#[cfg(not(feature = "internals"))]
pub(crate) mod gpu_scene;
#[cfg(feature = "internals")]
pub mod probes;
#[cfg(not(feature = "internals"))]
pub(crate) mod probes;
#[cfg(feature = "internals")]
pub mod registry;
#[cfg(not(feature = "internals"))]
pub(crate) mod registry;
mod renderer;
mod report;
#[cfg(feature = "internals")]
pub mod sampled;
#[cfg(not(feature = "internals"))]
pub(crate) mod sampled;
mod settings;
#[cfg(feature = "internals")]
pub mod shading;
#[cfg(not(feature = "internals"))]
pub(crate) mod shading;
#[cfg(feature = "internals")]
pub mod shadows;
#[cfg(not(feature = "internals"))]
pub(crate) mod shadows;

pub use manyshadows_scene as scene;
pub use wgpu;

// ------------------------------------------------------------------------------------------
// The facade: what an application embedding the renderer uses.
// ------------------------------------------------------------------------------------------
pub use error::{Fills, RenderError, Technique};
pub use frame::clusters::{ClusterOptions, ClusterStats, LightLoop};
pub use frame::eyes::{EyePasses, Eyes, Stereo};
pub use frame::gbuffer_readback::GBufferData;
pub use frame::visibility_mask::{MaskFileError, SoftVisibility, VisibilityMask};
pub use gpu::context::{
    feature_use, list_adapters, required_limits, webgpu_default_limits, AdapterRequest, FeatureUse,
    GpuContext,
};
pub use gpu::readback::read_deferred;
pub use gpu::timing::{GpuTimes, Stage};
pub use gpu_scene::caster_layout::CasterOptions;
pub use manyshadows_scene::SingleSidedShadows;
pub use probes::maps::{ProbeMaps, ProbePasses, ProbeStats};
pub use renderer::{FramePart, Renderer};
pub use report::{Frame, FrameEstimate, FrameTimings, ShadowLayout, ShadowWork, SubmittedFrame};
pub use sampled::options::{RayOptions, SpatialReuse, DEFAULT_AREA_SAMPLES};
pub use settings::{Deform, RenderSettings};
pub use shading::look::{Exposure, Look, ResolvedLook, Shading, ToneMap};
pub use shadows::cost::{Cost, EstimatedWork, LightingRead};
pub use shadows::descriptor::{Culling, Need, Requirement, TechniqueInfo};
pub use shadows::image::ShadowPicture;
pub use shadows::irregular::maps::{IrregularOptions, IrregularStats};
pub use shadows::options::{CullMode, Pcf, ShadowBias, ShadowOptions, SoftShadows};
pub use shadows::plan::DEFAULT_MAX_ATLAS_SIZE;
pub use shadows::report::{ReportLine, ShadowText};
pub use shadows::source::ShadowStats;
pub use shadows::vsm::plan::{TileMarking, VirtualOptions, VirtualStats};

// ------------------------------------------------------------------------------------------
// What one technique alone keeps, read through the renderer (the renderer itself names no
// technique: it drives every source through `ShadowSource`).
// ------------------------------------------------------------------------------------------
impl Renderer {
    /// Counters of the last frame of irregular shadow maps
    /// ([`Technique::IRREGULAR`]; `None` for other techniques).
    pub fn irregular_stats(&self) -> Option<IrregularStats> {
        self.technique_stats::<IrregularStats>()
    }

    /// The faces of [`Technique::VIRTUAL`] (`None` for other techniques).
    #[cfg(feature = "internals")]
    pub fn virtual_plan(&self) -> Option<&shadows::vsm::plan::VirtualPlan> {
        self.source_as::<shadows::vsm::source::VirtualSource>()
            .map(shadows::vsm::source::VirtualSource::plan)
    }

    /// Reads the virtual maps' page pool back: `(side, side² depths)`, row-major from the
    /// top-left texel, as the last frame left it. Only [`Technique::VIRTUAL`] has one.
    pub fn read_page_pool(&self) -> Result<(u32, Vec<f32>), RenderError> {
        match self.source_as::<shadows::vsm::source::VirtualSource>() {
            Some(v) => v.read_pool(self.context()),
            None => Err(self.no_page_pool()),
        }
    }

    /// Reads the virtual maps' page table back as the last frame left it: first, per entry
    /// (`VirtualStats::fit.table_entries` of them), the page it got — a pool page, or a marker
    /// for none or denied — then per entry the farthest receiver's depth key, then the drawn
    /// cells (the buffer may hold more words than that). Equal tables mean the same pages in
    /// the same pool places. Only [`Technique::VIRTUAL`] has one.
    pub fn read_page_table(&self) -> Result<Vec<u32>, RenderError> {
        match self.source_as::<shadows::vsm::source::VirtualSource>() {
            Some(v) => v.read_table(self.context()),
            None => Err(self.no_page_pool()),
        }
    }

    /// [`RenderError::NoPagePool`] for this renderer's technique, naming those with a pool.
    fn no_page_pool(&self) -> RenderError {
        RenderError::NoPagePool {
            technique: self.settings().technique,
            with_pool: registry::TECHNIQUES
                .iter()
                .filter(|i| i.fills == Fills::Pages)
                .map(|i| i.technique.name())
                .collect(),
        }
    }
}
