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

pub mod atlas_image;
mod blit;
pub mod casters;
pub mod clusters;
pub mod context;
pub mod gbuffer;
pub mod gbuffer_readback;
pub mod generator;
pub mod gpu_scene;
pub mod gpu_types;
pub mod irregular;
pub mod lighting;
mod pipelines;
pub mod readback;
pub mod renderer;
pub mod shaders;
pub mod shadow;
pub mod source;
pub mod techniques;
pub mod textures;
pub mod timing;
pub mod visibility;
pub mod vsm;

pub use context::{AdapterRequest, GpuContext};
pub use gbuffer_readback::GBufferData;
pub use generator::ShadowGenerator;
pub use gpu_scene::GpuScene;
pub use renderer::{
    Frame, FrameTimings, Pcf, RenderSettings, Renderer, ShadowBias, SubmittedFrame,
};
pub use shadow::{
    CullMode, ShadowAtlas, ShadowOptions, ShadowPlan, ShadowStats, ShadowTechnique, Technique,
};
pub use source::{ShadowOutput, ShadowSource};
pub use visibility::VisibilityMask;

pub use manyshadows_scene as scene;
pub use wgpu;

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
        /// The adapter ([`context::describe_adapter`]).
        adapter: String,
        /// What to use instead.
        instead: String,
    },
    /// The device's limits are below what the renderer or a technique needs.
    #[error("{adapter} has smaller limits than {needs} needs: {}", shortfalls.join("; "))]
    LimitsTooSmall {
        /// The adapter ([`context::describe_adapter`]).
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
            adapter: context::describe_adapter(&ctx.info),
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

/// A 1D workload of `items` threads, 64 per workgroup, as a 2D dispatch with at most
/// `max_groups` workgroups along x (65535 is every adapter's floor). Shaders recover the item
/// index as `(y · num_workgroups.x + x) · 64 + local`; trailing threads test it against the
/// count.
pub(crate) fn dispatch_2d(items: u64, max_groups: u32) -> (u32, u32) {
    let groups = items.div_ceil(64).max(1);
    let x = groups.min(u64::from(max_groups.max(1)));
    (x as u32, groups.div_ceil(x) as u32)
}

/// Makes `buffer` hold at least `needed` bytes: a buffer too small is replaced by one with room
/// for twice as much (so a growing scene reallocates rarely), capped at the device's limit for
/// its usage (`max_buffer_size`; storage buffers also `max_storage_buffer_binding_size`, since
/// they are bound whole). Returns true if the buffer was replaced; `needed` over the limit is a
/// [`RenderError::SceneTooLarge`] naming `what`, never a GPU error.
pub(crate) fn grow_buffer(
    ctx: &GpuContext,
    buffer: &mut wgpu::Buffer,
    needed: u64,
    what: &str,
) -> Result<bool, RenderError> {
    if buffer.size() >= needed {
        return Ok(false);
    }
    let limits = ctx.limits();
    let usage = buffer.usage();
    let mut limit = limits.max_buffer_size;
    if usage.contains(wgpu::BufferUsages::STORAGE) {
        limit = limit.min(limits.max_storage_buffer_binding_size);
    }
    // Binding sizes must stay multiples of 4 (16 keeps arrays of vec4 whole).
    let limit = limit - limit % 16;
    if needed > limit {
        return Err(RenderError::SceneTooLarge(format!(
            "the {what} buffer would be {needed} bytes, over this device's limit of {limit} bytes"
        )));
    }
    *buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(&format!("manyshadows.{}", what.replace(' ', "_"))),
        size: (2 * needed).next_multiple_of(16).min(limit).max(needed),
        usage,
        mapped_at_creation: false,
    });
    Ok(true)
}

/// A bind group of whole buffers at bindings 0, 1, 2, … in order.
pub(crate) fn buffer_bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// Bind-group layout entry of a read-only storage buffer.
pub(crate) fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(
        binding,
        visibility,
        wgpu::BufferBindingType::Storage { read_only: true },
    )
}

/// Bind-group layout entry of a read-write storage buffer.
pub(crate) fn storage_rw_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(
        binding,
        visibility,
        wgpu::BufferBindingType::Storage { read_only: false },
    )
}

/// Bind-group layout entry of a uniform buffer.
pub(crate) fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, visibility, wgpu::BufferBindingType::Uniform)
}

fn buffer_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}
