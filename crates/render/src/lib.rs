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

// The floors, bottom up (ARCHITECTURE.md; `tests/import_floors.rs` holds them to it). They are
// the crate's inside: public only with the `internals` feature, which the project's own CLI,
// benchmarks and tests turn on and which promises no stability. An embedder uses the facade
// below.
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
mod renderer;
mod settings;
#[cfg(feature = "internals")]
pub mod shadows;
#[cfg(not(feature = "internals"))]
pub(crate) mod shadows;

pub use manyshadows_scene as scene;
pub use wgpu;

// ------------------------------------------------------------------------------------------
// The facade: what an application embedding the renderer uses.
// ------------------------------------------------------------------------------------------
pub use frame::clusters::{ClusterOptions, ClusterStats, LightLoop};
pub use frame::gbuffer_readback::GBufferData;
pub use frame::visibility_mask::{MaskFileError, VisibilityMask};
pub use gpu::context::{
    feature_use, list_adapters, required_limits, webgpu_default_limits, AdapterRequest, FeatureUse,
    GpuContext,
};
pub use gpu::timing::{GpuTimes, Stage};
pub use gpu_scene::casters::CasterOptions;
pub use renderer::{
    Frame, FrameTimings, Renderer, ShadowLayout, ShadowPicture, ShadowWork, SubmittedFrame,
};
pub use settings::{CullMode, Pcf, RenderSettings, ShadowBias, ShadowOptions, Technique};
pub use shadows::descriptor::{Culling, Fills, Need, Requirement, TechniqueInfo};
pub use shadows::irregular::maps::{IrregularOptions, IrregularStats};
pub use shadows::plan::DEFAULT_MAX_ATLAS_SIZE;
pub use shadows::raytraced::accel::RayOptions;
pub use shadows::source::ShadowStats;
pub use shadows::vsm::plan::{TileMarking, VirtualOptions, VirtualStats};

/// Everything that can go wrong in the renderer. Each message says what to do; each variant
/// carries what a caller may act on as typed fields.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No graphics adapter matched.
    #[error("no graphics adapter (backends {backends}): {detail}")]
    NoAdapter {
        /// The backends searched.
        backends: String,
        /// What was found and what to install or change.
        detail: String,
    },
    /// The adapter refused to create a device.
    #[error("could not create a device on {adapter}: {reason}")]
    Device {
        /// The adapter ([`GpuContext::describe`]).
        adapter: String,
        /// wgpu's reason.
        reason: wgpu::RequestDeviceError,
    },
    /// Limits asked of the adapter exceed what it has.
    #[error("{adapter} cannot give the requested limits: {}", over.join("; "))]
    LimitsUnavailable {
        /// The adapter.
        adapter: String,
        /// One line per limit asked above the adapter's.
        over: Vec<String>,
    },
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] manyshadows_scene::SceneError),
    /// The shadow maps do not fit the atlas.
    #[error(transparent)]
    Atlas(#[from] manyshadows_scene::atlas::AtlasError),
    /// The image size is not possible on this adapter.
    #[error("resolution {width}x{height} is not possible: width and height must be 1..={max} on this adapter")]
    ResolutionTooLarge {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// The adapter's largest 2D texture side.
        max: u32,
    },
    /// Something the scene needs would exceed one of the adapter's limits.
    #[error("too large for this adapter: {what} would need {needed} {unit}, over its {limit_name} of {limit}")]
    TooLarge {
        /// What would not fit ("the caster world-position buffer").
        what: String,
        /// How much it needs.
        needed: u64,
        /// The limit.
        limit: u64,
        /// Unit of both ("bytes", "texture layers", "texels").
        unit: &'static str,
        /// The limit's name ("max_storage_buffer_binding_size").
        limit_name: &'static str,
    },
    /// The skin's per-vertex data does not match the scene's vertices.
    #[error("the skin has {joints} joint and {weights} weight entries but the scene has {vertices} vertices")]
    SkinMismatch {
        /// Joint entries.
        joints: usize,
        /// Weight entries.
        weights: usize,
        /// Vertices in the scene.
        vertices: usize,
    },
    /// A skin joint index past the bones the shaders hold.
    #[error("joint index {joint} is out of range (at most {bones} bones)")]
    SkinJointOutOfRange {
        /// The index.
        joint: u32,
        /// The most bones.
        bones: u32,
    },
    /// The GPU reported a validation or out-of-memory error, or stopped answering.
    #[error("GPU error while {during}: {message}")]
    Gpu {
        /// What the renderer was doing.
        during: String,
        /// wgpu's message.
        message: String,
    },
    /// A technique does not render this value of an option; `supported` lists what it does.
    #[error("technique {technique} does not render {option} {value}; it renders {}", supported.join(", "))]
    UnsupportedCombination {
        /// The technique.
        technique: Technique,
        /// The option ("point shadows").
        option: &'static str,
        /// The value asked for.
        value: &'static str,
        /// The values it renders.
        supported: Vec<&'static str>,
    },
    /// A combination no device can render (yet).
    #[error("{what} is not implemented; {instead}")]
    NotImplemented {
        /// The combination.
        what: &'static str,
        /// What to do instead.
        instead: &'static str,
    },
    /// A texture [`Renderer::render_to`] cannot draw into.
    #[error("render_to cannot draw into this {format:?} texture: it needs {needs}")]
    UnsupportedTarget {
        /// The texture's format.
        format: wgpu::TextureFormat,
        /// What the target must be.
        needs: &'static str,
    },
    /// The device lacks a feature a technique or mode needs; `instead` says what works.
    #[error("{needs} needs {feature}, which {adapter} lacks; {instead}")]
    MissingFeature {
        /// What needs it ("technique multiview").
        needs: String,
        /// The feature, and what it is used for.
        feature: String,
        /// The adapter ([`GpuContext::describe`]).
        adapter: String,
        /// What to use instead.
        instead: String,
    },
    /// The device's limits are below what the renderer or a technique needs.
    #[error("{adapter} has smaller limits than {needs} needs: {}", shortfalls.join("; "))]
    LimitsTooSmall {
        /// The adapter ([`GpuContext::describe`]).
        adapter: String,
        /// Who needs more ("manyshadows (WebGPU's defaults)", "technique compute").
        needs: String,
        /// One line per limit: "max_storage_buffers_per_shader_stage: the device allows 4,
        /// the renderer needs 8".
        shortfalls: Vec<String>,
    },
    /// The technique keeps no shadow atlas to read back or to generate on its own: it fills
    /// something else (`fills`) and runs only in whole frames ([`Renderer`]).
    #[error("technique {technique} fills {} instead of a shadow atlas, so it renders whole frames (Renderer) but has no atlas to generate or read on its own", fills.describe())]
    NoAtlas {
        /// The technique.
        technique: Technique,
        /// What it fills instead.
        fills: shadows::descriptor::Fills,
    },
    /// A technique has no page pool to read ([`Renderer::read_page_pool`]).
    #[error("technique {technique} has no page pool (techniques that fill one: {})", with_pool.join(", "))]
    NoPagePool {
        /// The technique.
        technique: Technique,
        /// The techniques that do.
        with_pool: Vec<&'static str>,
    },
    /// An option's value is out of its range.
    #[error("{option} {value} is out of range: {expected}")]
    InvalidOption {
        /// The option, as [`RenderSettings`] names it ("irregular.grid").
        option: &'static str,
        /// The value given.
        value: String,
        /// What it must be.
        expected: &'static str,
    },
    /// Irregular shadow maps ran out of list nodes; the frame's visibility would be wrong.
    #[error("irregular shadow maps: the node pool of {capacity} samples overflowed ({dropped} samples dropped, {needed} needed by one batch of lights); the frame was discarded. Lower the resolution or use fewer lights")]
    NodePoolOverflow {
        /// Samples that found no node.
        dropped: u64,
        /// Nodes one batch asked for.
        needed: u64,
        /// The pool's capacity.
        capacity: u64,
    },
    /// Irregular shadow maps' tile queue was full; the frame was discarded.
    #[error("irregular shadow maps: {tiles} tiles of samples found the tile queue ({capacity} tiles) full; the frame was discarded. Use a coarser grid or fewer lights")]
    TileQueueFull {
        /// Tiles that found the queue full.
        tiles: u32,
        /// The queue's capacity.
        capacity: u64,
    },
    /// Shader loops were cut short by the driver (llvmpipe ends a loop after 65,535
    /// iterations); the frame was discarded.
    #[error("irregular shadow maps: {walks} sample-list walks hit the driver's loop limit (llvmpipe ends loops after 65535 iterations per invocation); the frame was discarded. Use a finer grid (IrregularOptions::grid) so lists are shorter")]
    LoopLimit {
        /// Walks cut short.
        walks: u32,
    },
    /// Reading results back failed.
    #[error("reading {what} back from the GPU failed: {reason}")]
    Readback {
        /// What was read.
        what: &'static str,
        /// Why.
        reason: String,
    },
}

impl RenderError {
    /// [`RenderError::MissingFeature`] for `ctx`'s adapter.
    pub(crate) fn missing_feature(
        ctx: &GpuContext,
        needs: impl Into<String>,
        feature: impl Into<String>,
        instead: impl Into<String>,
    ) -> Self {
        RenderError::MissingFeature {
            needs: needs.into(),
            feature: feature.into(),
            adapter: gpu::context::describe_adapter(&ctx.info),
            instead: instead.into(),
        }
    }

    /// True when the error says this technique, mode or option cannot run here (on this
    /// device, or at all) rather than that something failed: callers that try every
    /// technique skip these.
    pub fn is_unsupported(&self) -> bool {
        matches!(
            self,
            RenderError::UnsupportedCombination { .. }
                | RenderError::NotImplemented { .. }
                | RenderError::UnsupportedTarget { .. }
                | RenderError::MissingFeature { .. }
                | RenderError::LimitsTooSmall { .. }
                | RenderError::NoAtlas { .. }
                | RenderError::NoPagePool { .. }
        )
    }
}
