//! The ground floor: every failure of the renderer ([`RenderError`]) and the small name types
//! its variants carry ([`Technique`], [`Fills`]). Every module may import this one; it imports
//! nothing of the crate.

/// A shadow technique, by its name. Every technique declares itself once, in its own module,
/// with a `TechniqueInfo` (`shadows::descriptor`) (name, summary, what it
/// fills, point-shadow modes, the features it needs, its constructor and its WGSL) and a
/// constant here (`Technique::LAYERED`…); the registry (`Technique::all`) lists them, and
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

/// What a technique leaves for the lighting pass.
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fills {
    /// A depth atlas: one tile per shadow view (the shadow-map techniques).
    Atlas,
    /// A pool of depth pages behind a page table (virtual shadow maps).
    Pages,
    /// The per-pixel, per-light visibility bits themselves (exact techniques).
    Mask,
    /// Nothing: the lighting pass casts shadow rays through an acceleration structure.
    Rays,
}

impl Fills {
    /// A few words for messages and menus.
    pub fn describe(self) -> &'static str {
        match self {
            Fills::Atlas => "a shadow atlas",
            Fills::Pages => "a virtual page pool",
            Fills::Mask => "the visibility mask directly",
            Fills::Rays => "no map (shadow rays through an acceleration structure)",
        }
    }
}

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
        /// The adapter ([`GpuContext::describe`](crate::GpuContext::describe)).
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
    /// A texture [`Renderer::render_to`](crate::Renderer::render_to) cannot draw into.
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
        /// The adapter ([`GpuContext::describe`](crate::GpuContext::describe)).
        adapter: String,
        /// What to use instead.
        instead: String,
    },
    /// The device's limits are below what the renderer or a technique needs.
    #[error("{adapter} has smaller limits than {needs} needs: {}", shortfalls.join("; "))]
    LimitsTooSmall {
        /// The adapter ([`GpuContext::describe`](crate::GpuContext::describe)).
        adapter: String,
        /// Who needs more ("manyshadows (WebGPU's defaults)", "technique compute").
        needs: String,
        /// One line per limit: "max_storage_buffers_per_shader_stage: the device allows 4,
        /// the renderer needs 8".
        shortfalls: Vec<String>,
    },
    /// The technique keeps no shadow atlas to read back or to generate on its own: it fills
    /// something else (`fills`) and runs only in whole frames ([`Renderer`](crate::Renderer)).
    #[error("technique {technique} fills {} instead of a shadow atlas, so it renders whole frames (Renderer) but has no atlas to generate or read on its own", fills.describe())]
    NoAtlas {
        /// The technique.
        technique: Technique,
        /// What it fills instead.
        fills: Fills,
    },
    /// A technique has no page pool to read ([`Renderer::read_page_pool`](crate::Renderer::read_page_pool)).
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
        /// The option, as [`RenderSettings`](crate::RenderSettings) names it ("irregular.grid").
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
    /// Two things that must describe the same frame do not.
    #[error("{what} does not fit this renderer: expected {expected}, found {found}")]
    Mismatch {
        /// What was given.
        what: &'static str,
        /// What the renderer has.
        expected: String,
        /// What was given.
        found: String,
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
    /// [`RenderError::InvalidOption`]: the option (named as `RenderSettings` names the field)
    /// is `value`, and must be `expected`.
    pub fn invalid_option(
        option: &'static str,
        value: impl std::fmt::Display,
        expected: &'static str,
    ) -> Self {
        RenderError::InvalidOption {
            option,
            value: value.to_string(),
            expected,
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
