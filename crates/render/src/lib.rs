//! # manyshadows
//!
//! Many shadow-casting lights on wgpu. The flow of one frame:
//!
//! `Scene` → [`GpuScene`] (buffers) → the frame's [`ShadowSource`]: an atlas technique
//! ([`ShadowPlan`]: every shadow view and its atlas tile; a [`ShadowTechnique`] fills the
//! [`ShadowAtlas`]), virtual shadow maps (a page pool) or irregular shadow maps (a visibility
//! mask) → the lighting pass reads its [`ShadowOutput`] → image, visibility mask and timings
//! ([`Frame`]).
//!
//! ```no_run
//! use manyshadows::{AdapterRequest, GpuContext, Renderer, RenderSettings};
//! let ctx = GpuContext::new(&AdapterRequest::default())?;
//! let scene = manyshadows_scene::builtin::build("cubes", &Default::default())?;
//! let mut renderer = Renderer::new(&ctx, &scene, RenderSettings::default())?;
//! let frame = renderer.render()?;
//! assert_eq!(frame.rgba.len(), 1280 * 720 * 4);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod frame;
pub mod gpu;
pub mod gpu_scene;
pub mod renderer;
pub mod settings;
pub mod shadows;

pub use manyshadows_scene as scene;
pub use wgpu;

// ------------------------------------------------------------------------------------------
// Paths kept for the CLI, the web crate, examples and tests; the embedding facade (issue 25
// part 3) will replace them. The modules now lie in floors (issue 25 part 1: gpu, gpu_scene,
// frame, shadows, settings, renderer); these re-exports keep the names code outside `src/`
// uses: the crate-root types, and the old module paths (`manyshadows::shadow::…`,
// `manyshadows::vsm::…`). Nothing inside `src/` goes through them; the import check
// (`tests/import_floors.rs`) reads each as the module it re-exports.
// ------------------------------------------------------------------------------------------
pub use frame::gbuffer_readback::GBufferData;
pub use frame::visibility_mask::VisibilityMask;
pub use gpu::context::{AdapterRequest, GpuContext};
pub use gpu_scene::instances::GpuScene;
pub use renderer::{Frame, FrameTimings, Renderer, SubmittedFrame};
pub use settings::{CullMode, Pcf, RenderSettings, ShadowBias, ShadowOptions, Technique};
pub use shadows::atlas::generator::ShadowGenerator;
pub use shadows::atlas::storage::ShadowAtlas;
pub use shadows::atlas::technique::ShadowTechnique;
pub use shadows::plan::ShadowPlan;
pub use shadows::source::{ShadowOutput, ShadowSource, ShadowStats};

pub use frame::clusters;
pub use gpu::{context, readback, timing};

/// Old path of the atlas and page-pool pictures ([`shadows::image`]).
pub mod atlas_image {
    pub use crate::shadows::image::{atlas_picture, pool_picture, read_depth};
}

/// Old path of the caster geometry and skinning ([`gpu_scene::casters`],
/// [`gpu_scene::skinning`]).
pub mod casters {
    pub use crate::gpu_scene::casters::{CasterGeometry, CasterOptions};
    pub use crate::gpu_scene::skinning::{Skin, MAX_BONES};
}

/// Old path of irregular shadow maps' options ([`shadows::irregular`]).
pub mod irregular {
    pub use crate::shadows::irregular::maps::IrregularOptions;
}

/// Old path of the shadow plan and the technique interface ([`shadows::plan`],
/// [`shadows::atlas::technique`], [`settings`]).
pub mod shadow {
    pub use crate::settings::IRREGULAR_NO_ATLAS;
    pub use crate::shadows::atlas::technique::ShadowInput;
    pub use crate::shadows::plan::{FitReport, DEFAULT_MAX_ATLAS_SIZE};
}

/// Old paths of the atlas techniques ([`shadows::atlas`]).
pub mod techniques {
    /// Old path of [`crate::shadows::atlas::compute`].
    pub mod compute {
        pub use crate::shadows::atlas::compute::Compute;
    }
    /// Old path of [`crate::shadows::atlas::gpu_driven`] and the rounds it shares with the
    /// virtual maps ([`crate::shadows::cluster_draw`]).
    pub mod gpu_driven {
        pub use crate::shadows::atlas::gpu_driven::GpuDriven;
        pub use crate::shadows::cluster_draw::plan_rounds;
    }
    /// Old path of [`crate::shadows::atlas::multiview`].
    pub mod multiview {
        pub use crate::shadows::atlas::multiview::Multiview;
    }
}

/// Old path of virtual shadow maps' options, sizes and counters ([`shadows::vsm::plan`]).
pub mod vsm {
    pub use crate::shadows::vsm::plan::{
        pool_side, VirtualOptions, VirtualStats, DEFAULT_POOL_BYTES, MAX_SIDE, PAGE_SIZE,
    };
}
// ------------------------------------------------------------------------------------------

/// Everything that can go wrong in the renderer. Each message says what to do.
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
    #[error("could not create a device on {0}")]
    Device(String),
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] manyshadows_scene::SceneError),
    /// The shadow maps do not fit the atlas.
    #[error(transparent)]
    Atlas(#[from] manyshadows_scene::atlas::AtlasError),
    /// The image size is not possible on this adapter.
    #[error("resolution {width}x{height} is not possible: {reason}")]
    ResolutionTooLarge {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Which limit.
        reason: String,
    },
    /// A scene buffer would exceed the adapter's limits.
    #[error("scene too large for this adapter: {0}")]
    SceneTooLarge(String),
    /// The GPU reported a validation or out-of-memory error.
    #[error("GPU error while {0}")]
    Gpu(String),
    /// The chosen combination is not possible (a point-shadow mode a technique does not
    /// render, a target texture `render_to` cannot draw into).
    #[error("{0}")]
    Unsupported(String),
    /// The device lacks a feature a technique or mode needs; `instead` says what works.
    #[error("{needs} needs {feature}, which {adapter} lacks; {instead}")]
    MissingFeature {
        /// What needs it ("technique multiview").
        needs: String,
        /// The feature, and what it is used for.
        feature: String,
        /// The adapter ([`gpu::context::describe_adapter`]).
        adapter: String,
        /// What to use instead.
        instead: String,
    },
    /// The device's limits are below what the renderer or a technique needs.
    #[error("{adapter} has smaller limits than {needs} needs: {}", shortfalls.join("; "))]
    LimitsTooSmall {
        /// The adapter ([`gpu::context::describe_adapter`]).
        adapter: String,
        /// Who needs more ("manyshadows (WebGPU's defaults)", "technique compute").
        needs: String,
        /// One line per limit: "max_storage_buffers_per_shader_stage: the device allows 4,
        /// the renderer needs 8".
        shortfalls: Vec<String>,
    },
    /// The technique keeps no shadow atlas (or page pool) to read back or to generate on its
    /// own; `detail` says where it does run.
    #[error("{detail}")]
    NoAtlas {
        /// The technique.
        technique: Technique,
        /// Why, and where the technique does run.
        detail: String,
    },
    /// An option's value is out of its range.
    #[error("{0}")]
    InvalidOption(String),
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
    /// Irregular shadow maps could not finish a frame exactly (a work queue or a driver limit);
    /// the frame was discarded.
    #[error("irregular shadow maps: {0}")]
    Irregular(String),
    /// Reading results back failed.
    #[error("reading results back from the GPU failed: {0}")]
    Readback(String),
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
            RenderError::Unsupported(_)
                | RenderError::MissingFeature { .. }
                | RenderError::LimitsTooSmall { .. }
                | RenderError::NoAtlas { .. }
        )
    }
}
