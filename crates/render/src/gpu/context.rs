//! The GPU context: headless adapter choice, device creation and the optional features the
//! renderer turns on.
//!
//! The development and CI machines have no GPU, so the adapter order matters: a hardware GPU
//! first, then Vulkan on the CPU (lavapipe), then OpenGL on the CPU (llvmpipe through EGL). The
//! user can narrow the choice with `WGPU_BACKEND` (or [`AdapterRequest::backends`]) and
//! `WGPU_ADAPTER_NAME` (a case-insensitive substring of the adapter's name).

use std::sync::{Arc, Mutex};

use crate::error::RenderError;

/// What the caller asks of the adapter choice.
#[derive(Clone, Debug, Default)]
#[non_exhaustive]
pub struct AdapterRequest {
    /// Backends to consider; `None` = `WGPU_BACKEND` if set, otherwise all.
    pub backends: Option<wgpu::Backends>,
    /// Case-insensitive substring the adapter name must contain; `None` = `WGPU_ADAPTER_NAME`.
    pub name: Option<String>,
    /// Limits to create the device with instead of the adapter's own; `None` = the adapter's
    /// full limits. Use it to see how the renderer behaves on a smaller device
    /// ([`webgpu_default_limits`] is what a browser gives). Every limit must be within
    /// the adapter's, otherwise [`GpuContext::new`] fails naming the limits that are not.
    pub limits: Option<wgpu::Limits>,
}

/// WebGPU's default limits (`wgpu::Limits::defaults()`): what a web page gets without asking
/// for more.
pub fn webgpu_default_limits() -> wgpu::Limits {
    wgpu::Limits::defaults()
}

/// The smallest device limits every technique of the renderer runs with: WebGPU's defaults
/// (bind groups, bindings per stage, workgroup sizes) with smaller textures and buffers
/// (2048² textures, 4 MiB storage bindings and buffers). Capacities scale with the device: the
/// shadow atlas and page pool are capped at the texture limit, the priority fit shrinks or
/// drops maps that do not fit, and a scene or frame whose buffers would pass a limit is
/// refused with [`RenderError::TooLarge`] or [`RenderError::ResolutionTooLarge`].
/// [`GpuContext::new`] refuses a device below these, naming each limit
/// (`crates/render/tests/limits.rs` renders every technique on exactly these limits).
pub fn required_limits() -> wgpu::Limits {
    wgpu::Limits {
        max_texture_dimension_1d: 2048,
        max_texture_dimension_2d: 2048,
        max_storage_buffer_binding_size: 4 << 20,
        max_buffer_size: 4 << 20,
        ..webgpu_default_limits()
    }
}

/// The limits in `have` that fall short of `need`, as `name: have < need` lines.
pub fn limit_shortfalls(have: &wgpu::Limits, need: &wgpu::Limits) -> Vec<String> {
    let mut out = Vec::new();
    need.check_limits_with_fail_fn(have, false, |name, need, have| {
        out.push(format!(
            "{name}: the device allows {have}, the renderer needs {need}"
        ));
    });
    out
}

/// Optional adapter features and whether the renderer uses them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FeatureUse {
    /// Feature name as wgpu spells it.
    pub name: &'static str,
    /// The adapter has it.
    pub available: bool,
    /// What the renderer does with it.
    pub purpose: &'static str,
}

/// Optional features the renderer turns on when present, with their purpose.
const OPTIONAL_FEATURES: &[(wgpu::Features, &str, &str)] = &[
    (
        wgpu::Features::TIMESTAMP_QUERY,
        "TIMESTAMP_QUERY",
        "GPU time per pass",
    ),
    (
        wgpu::Features::PIPELINE_STATISTICS_QUERY,
        "PIPELINE_STATISTICS_QUERY",
        "vertex-shader invocation and primitive counts (benchmarks)",
    ),
    (
        wgpu::Features::MULTIVIEW,
        "MULTIVIEW",
        "multiview shadow generation (technique multiview)",
    ),
    (
        wgpu::Features::MULTI_DRAW_INDIRECT_COUNT,
        "MULTI_DRAW_INDIRECT_COUNT",
        "compacted indirect draws of the gpu-driven technique",
    ),
    (
        wgpu::Features::CLIP_DISTANCES,
        "CLIP_DISTANCES",
        "keeping layered and gpu-driven draws inside their atlas tiles",
    ),
    (
        wgpu::Features::EXPERIMENTAL_RAY_QUERY,
        "EXPERIMENTAL_RAY_QUERY",
        "ray-traced shadows (technique raytraced, compare --reference gpu)",
    ),
];

/// Experimental features the adapter reports that the renderer does not use (listed by `info`
/// so a user sees what the driver offers).
#[cfg_attr(not(feature = "internals"), allow(dead_code))] // the CLI's `info`
pub const UNUSED_EXPERIMENTAL: &[(wgpu::Features, &str)] = &[(
    wgpu::Features::EXPERIMENTAL_MESH_SHADER,
    "EXPERIMENTAL_MESH_SHADER",
)];

/// The token wgpu asks for before a device may enable a feature named `EXPERIMENTAL_…`:
/// enabled exactly when `features` holds one (ray queries, for technique raytraced).
///
/// wgpu marks the token `unsafe` because its experimental APIs may still contain bugs that
/// cause undefined behaviour; the renderer uses of them only acceleration-structure builds
/// from its own validated buffers and ray queries that read them, and a device without the
/// feature never gets the token. This is the project's one `unsafe` block.
fn experimental_features(features: wgpu::Features) -> wgpu::ExperimentalFeatures {
    if features.intersects(wgpu::Features::EXPERIMENTAL_RAY_QUERY) {
        #[allow(unsafe_code)]
        // SAFETY: see the function's documentation; wgpu's contract is an acknowledgement
        // that experimental features may be buggy, not a precondition the caller must check.
        unsafe {
            wgpu::ExperimentalFeatures::enabled()
        }
    } else {
        wgpu::ExperimentalFeatures::disabled()
    }
}

/// An adapter and the device made on it. Cloning is cheap (wgpu handles are reference
/// counted): a [`crate::Renderer`] keeps its own clone, so it borrows nothing from the caller.
#[derive(Clone)]
pub struct GpuContext {
    /// The wgpu instance.
    pub instance: wgpu::Instance,
    /// The chosen adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's description.
    pub info: wgpu::AdapterInfo,
    /// GPU errors nobody captured in an error scope (they would otherwise panic).
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// The fence every compute pass of a frame begins through (inert but on OpenGL).
    raster_fence: super::raster_fence::RasterFence,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("info", &self.info)
            .finish()
    }
}

/// The longest [`GpuContext::wait_idle`] waits for submitted work before it reports an error
/// (a frame on a CPU adapter can take tens of seconds; a hang must not be endless).
pub const GPU_WAIT_LIMIT: std::time::Duration = std::time::Duration::from_secs(600);

/// A one-line description of an adapter: name, backend, type and driver.
pub fn describe_adapter(info: &wgpu::AdapterInfo) -> String {
    let driver = [info.driver.as_str(), info.driver_info.as_str()]
        .iter()
        .filter(|s| !s.is_empty())
        .copied()
        .collect::<Vec<_>>()
        .join(" ");
    format!(
        "{} ({:?}, {:?}{})",
        info.name,
        info.backend,
        info.device_type,
        if driver.is_empty() {
            String::new()
        } else {
            format!(", {driver}")
        }
    )
}

/// Preference rank of an adapter (lower is better): hardware first, then Vulkan on the CPU,
/// then anything else on the CPU.
fn rank(info: &wgpu::AdapterInfo) -> u32 {
    use wgpu::DeviceType::*;
    let hw = match info.device_type {
        DiscreteGpu => 0,
        IntegratedGpu => 1,
        VirtualGpu => 2,
        Other => 4,
        Cpu => 5,
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan => 0,
        wgpu::Backend::Metal | wgpu::Backend::Dx12 => 1,
        wgpu::Backend::Gl => 2,
        _ => 3,
    };
    hw * 10 + backend
}

impl AdapterRequest {
    /// The backends this request considers: [`AdapterRequest::backends`], else
    /// `WGPU_BACKEND`, else every native backend.
    pub fn resolved_backends(&self) -> wgpu::Backends {
        requested_backends(self)
    }
}

/// Which backends a request considers.
pub fn requested_backends(req: &AdapterRequest) -> wgpu::Backends {
    req.backends.or_else(wgpu::Backends::from_env).unwrap_or(
        wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12 | wgpu::Backends::GL,
    )
}

fn requested_name(req: &AdapterRequest) -> Option<String> {
    req.name
        .clone()
        .or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok())
        .filter(|s| !s.trim().is_empty())
}

fn new_instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
    desc.backends = backends;
    wgpu::Instance::new(desc)
}

/// Every adapter the request's backends expose, best first (the first is the one
/// [`GpuContext::new`] picks when no name filter is given).
pub fn list_adapters(req: &AdapterRequest) -> Vec<wgpu::AdapterInfo> {
    let instance = new_instance(requested_backends(req));
    let mut infos: Vec<_> = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .into_iter()
        .map(|a| a.get_info())
        .collect();
    infos.sort_by_key(rank);
    infos
}

/// The optional features of an adapter and what the renderer does with each.
pub fn feature_use(features: wgpu::Features) -> Vec<FeatureUse> {
    OPTIONAL_FEATURES
        .iter()
        .map(|&(f, name, purpose)| FeatureUse {
            name,
            available: features.contains(f),
            purpose,
        })
        .collect()
}

/// The environment variable naming optional features the device is made without
/// (comma-separated, as wgpu spells them: `EXPERIMENTAL_RAY_QUERY,MULTIVIEW`): to see how the
/// renderer and its tests behave on a device that lacks them, on one that has them.
pub const WITHOUT_FEATURES_VAR: &str = "MANYSHADOWS_WITHOUT_FEATURES";

/// The features [`WITHOUT_FEATURES_VAR`] names (none when unset); a name wgpu does not know
/// is an error naming it.
fn masked_features() -> Result<wgpu::Features, RenderError> {
    let Ok(list) = std::env::var(WITHOUT_FEATURES_VAR) else {
        return Ok(wgpu::Features::empty());
    };
    let mut out = wgpu::Features::empty();
    for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        out |= wgpu::Features::from_name(name).ok_or_else(|| RenderError::InvalidOption {
            option: "MANYSHADOWS_WITHOUT_FEATURES",
            value: name.to_string(),
            expected: "wgpu feature names, comma-separated (EXPERIMENTAL_RAY_QUERY, MULTIVIEW, \
                       CLIP_DISTANCES, ...)",
        })?;
    }
    Ok(out)
}

impl GpuContext {
    /// Picks the best adapter for `req` and creates a device with the adapter's full limits and
    /// the optional features the renderer uses (but those [`WITHOUT_FEATURES_VAR`] names).
    /// Fails with an error that says what to install when there is no adapter at all.
    pub fn new(req: &AdapterRequest) -> Result<Self, RenderError> {
        let instance = new_instance(requested_backends(req));
        Self::with_instance(instance, req, None)
    }

    /// [`GpuContext::new`] on an instance the caller made (a windowed application makes it
    /// with its display handle), choosing among the adapters that can present to
    /// `compatible_surface` when one is given.
    pub fn with_instance(
        instance: wgpu::Instance,
        req: &AdapterRequest,
        compatible_surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, RenderError> {
        let backends = requested_backends(req);
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        if let Some(surface) = compatible_surface {
            adapters.retain(|a| a.is_surface_supported(surface));
        }
        let all_names: Vec<String> = adapters
            .iter()
            .map(|a| describe_adapter(&a.get_info()))
            .collect();
        if let Some(name) = requested_name(req) {
            let needle = name.to_lowercase();
            adapters.retain(|a| a.get_info().name.to_lowercase().contains(&needle));
            if adapters.is_empty() {
                return Err(RenderError::NoAdapter {
                    backends: format!("{backends:?}"),
                    detail: format!(
                        "no adapter's name contains '{name}' (WGPU_ADAPTER_NAME / AdapterRequest::name); adapters found: {}",
                        if all_names.is_empty() { "none".to_string() } else { all_names.join("; ") }
                    ),
                });
            }
        }
        adapters.sort_by_key(|a| rank(&a.get_info()));
        let Some(adapter) = adapters.into_iter().next() else {
            return Err(RenderError::NoAdapter {
                backends: format!("{backends:?}"),
                detail: "no graphics adapter was found. Install a driver: on Debian/Ubuntu \
                         `apt-get install -y mesa-vulkan-drivers` gives Vulkan on the CPU \
                         (lavapipe), and `libegl1 libgl1-mesa-dri` give OpenGL on the CPU \
                         (llvmpipe). If WGPU_BACKEND is set, check that it names an installed \
                         backend (vulkan, gl)."
                    .to_string(),
            });
        };
        let info = adapter.get_info();
        let wanted = OPTIONAL_FEATURES
            .iter()
            .fold(wgpu::Features::empty(), |acc, &(f, _, _)| acc | f);
        let features = adapter.features() & wanted & !masked_features()?;
        let adapter_limits = adapter.limits();
        let limits = match &req.limits {
            None => adapter_limits.clone(),
            Some(wanted) => {
                let over = limit_shortfalls(&adapter_limits, wanted);
                if !over.is_empty() {
                    return Err(RenderError::LimitsUnavailable {
                        adapter: describe_adapter(&info),
                        over,
                    });
                }
                wanted.clone()
            }
        };
        let short = limit_shortfalls(&limits, &required_limits());
        if !short.is_empty() {
            return Err(RenderError::LimitsTooSmall {
                adapter: describe_adapter(&info),
                needs: "manyshadows (WebGPU's defaults)".into(),
                shortfalls: short,
            });
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("manyshadows.device"),
            required_features: features,
            required_limits: limits,
            experimental_features: experimental_features(features),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|reason| RenderError::Device {
            adapter: describe_adapter(&info),
            reason,
        })?;
        log::info!("adapter: {}", describe_adapter(&info));
        let ctx = Self::from_parts(instance, adapter, device, queue)?;
        // The device is ours: its errors outside every error scope are recorded, not thrown.
        ctx.capture_uncaptured_errors();
        Ok(ctx)
    }

    /// Wraps a device the caller made (to render into the caller's own textures, beside the
    /// caller's own passes). The renderer uses the optional features the device has
    /// ([`feature_use`]) and its limits, which must reach [`required_limits`]; techniques that
    /// need a feature the device lacks are refused when chosen.
    ///
    /// The device's uncaptured-error handler stays the host's: the renderer catches the errors
    /// of its own calls in error scopes (natively; a browser cannot wait for scopes). A host
    /// that wants errors outside every scope reported by the renderer's calls instead calls
    /// [`GpuContext::capture_uncaptured_errors`].
    pub fn from_parts(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Self, RenderError> {
        let info = adapter.get_info();
        let short = limit_shortfalls(&device.limits(), &required_limits());
        if !short.is_empty() {
            return Err(RenderError::LimitsTooSmall {
                adapter: format!("the device on {}", describe_adapter(&info)),
                needs: "manyshadows".into(),
                shortfalls: short,
            });
        }
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let raster_fence = super::raster_fence::RasterFence::new(&device, info.backend);
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            info,
            uncaptured,
            raster_fence,
        })
    }

    /// What every compute pass of a frame begins through, so that the draws recorded before
    /// it are finished (OpenGL: llvmpipe runs a dispatch before the draws before it; see
    /// `gpu::raster_fence`); inert on other backends.
    pub(crate) fn raster_fence(&self) -> &super::raster_fence::RasterFence {
        &self.raster_fence
    }

    /// One line naming the adapter: name, backend, type and driver.
    pub fn describe(&self) -> String {
        describe_adapter(&self.info)
    }

    /// True if the device has every feature in `f`.
    pub fn has(&self, f: wgpu::Features) -> bool {
        self.device.features().contains(f)
    }

    /// Views one multiview pass renders on this device: the device's limit, at most
    /// `MAX_MULTIVIEW_VIEWS`, one where the driver loses clipped primitives' view index
    /// (`clips_into_layer_zero`); 0 without multiview.
    pub fn multiview_views_per_pass(&self) -> u32 {
        if !self.has(wgpu::Features::MULTIVIEW) {
            return 0;
        }
        let limit = self
            .limits()
            .max_multiview_view_count
            .min(MAX_MULTIVIEW_VIEWS);
        if clips_into_layer_zero(&self.info) {
            limit.min(1)
        } else {
            limit
        }
    }

    /// The device's limits.
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// Runs `f` inside a validation + out-of-memory error scope; a GPU error becomes
    /// [`RenderError::Gpu`] with `what` in its message instead of a panic.
    pub fn scoped<T>(
        &self,
        what: &str,
        f: impl FnOnce() -> Result<T, RenderError>,
    ) -> Result<T, RenderError> {
        // In a browser the scopes' promises settle only after control returns to its event
        // loop, so they could not be waited for here: there no scope is pushed, and errors
        // reach the uncaptured-error handler (logged, and reported by a later call).
        #[cfg(not(target_arch = "wasm32"))]
        let (oom, validation) = (
            self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory),
            self.device.push_error_scope(wgpu::ErrorFilter::Validation),
        );
        let out = f();
        #[cfg(not(target_arch = "wasm32"))]
        {
            let v = pollster::block_on(validation.pop());
            let o = pollster::block_on(oom.pop());
            if let Some(e) = v.or(o) {
                return Err(RenderError::Gpu {
                    during: what.into(),
                    message: e.to_string(),
                });
            }
        }
        if let Some(message) = self.take_uncaptured() {
            return Err(RenderError::Gpu {
                during: what.into(),
                message,
            });
        }
        out
    }

    /// Replaces the device's uncaptured-error handler with one that logs errors and records
    /// them, so [`GpuContext::take_uncaptured`] and the renderer's next call report them
    /// (as [`RenderError::Gpu`]) instead of wgpu's default handler panicking.
    /// [`GpuContext::new`] does this for the device it creates; a device from
    /// [`GpuContext::from_parts`] keeps its host's handler unless the host calls this.
    pub fn capture_uncaptured_errors(&self) {
        let sink = self.uncaptured.clone();
        self.device
            .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                log::error!("uncaptured GPU error: {e}");
                if let Ok(mut v) = sink.lock() {
                    v.push(e.to_string());
                }
            }));
    }

    /// The first GPU error that escaped every error scope since the last call, if any (only
    /// recorded after [`GpuContext::capture_uncaptured_errors`]).
    pub fn take_uncaptured(&self) -> Option<String> {
        let mut v = self.uncaptured.lock().ok()?;
        let first = v.first().cloned();
        v.clear();
        first
    }

    /// Blocks until the GPU has finished all submitted work, at most 600 s.
    ///
    /// One wait of wgpu's OpenGL backend ends after about 2.1 s whatever timeout is asked for
    /// (`glClientWaitSync` takes a 32-bit count of nanoseconds), and a frame of thousands of
    /// lights on llvmpipe under load takes longer; so the wait is repeated while it times out,
    /// up to the limit, and only then becomes an error.
    pub fn wait_idle(&self) -> Result<(), RenderError> {
        let start = web_time::Instant::now();
        loop {
            match self.device.poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(GPU_WAIT_LIMIT),
            }) {
                Ok(_) => return Ok(()),
                Err(wgpu::PollError::Timeout) if start.elapsed() < GPU_WAIT_LIMIT => continue,
                Err(e) => {
                    return Err(RenderError::Gpu {
                        during: format!(
                            "waiting for the GPU ({:.0} s)",
                            start.elapsed().as_secs_f64()
                        ),
                        message: e.to_string(),
                    })
                }
            }
        }
    }
}

with_setters!(AdapterRequest {
    with_backends: backends: Option<wgpu::Backends>,
    with_name: name: Option<String>,
    with_limits: limits: Option<wgpu::Limits>,
});

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
            adapter: describe_adapter(&ctx.info),
            instead: instead.into(),
        }
    }
}

/// True for drivers whose multiview loses the view index of primitives that go through the
/// clipper (they all land in layer 0): Mesa's lavapipe before Mesa 25, which then gets one
/// view per multiview pass. A lavapipe whose Mesa version cannot be read counts as affected
/// (docs/decisions.md, "Multiview: lavapipe's clipper and at most 31 views").
pub fn clips_into_layer_zero(info: &wgpu::AdapterInfo) -> bool {
    info.backend == wgpu::Backend::Vulkan
        && info.name.to_lowercase().contains("llvmpipe")
        && mesa_major(&info.driver_info).is_none_or(|major| major < 25)
}

/// The major version of a Mesa driver's description ("Mesa 25.0.7-2~bpo12+1" → 25).
pub(crate) fn mesa_major(driver_info: &str) -> Option<u32> {
    let rest = &driver_info[driver_info.find("Mesa ")? + 5..];
    rest.split('.').next()?.trim().parse().ok()
}

/// Most views of one pass. wgpu 30 takes a pipeline's view mask as "views 0..n" only when
/// `mask + 1` is a power of two, which wraps to 0 for all 32 views and then asks for
/// `SELECTIVE_MULTIVIEW`, which the renderer does not enable: 31 is the most views a mask of
/// the plain `MULTIVIEW` feature can name (docs/decisions.md, "Multiview: lavapipe's clipper
/// and at most 31 views").
pub const MAX_MULTIVIEW_VIEWS: u32 = 31;
