//! What a frame reports to its caller: the image and its counters ([`Frame`], [`FrameTimings`],
//! [`SubmittedFrame`]), and what the renderer says of its shadows before a frame
//! ([`ShadowLayout`], [`ShadowWork`]).

use crate::error::Fills;
use crate::frame::clusters::ClusterStats;
use crate::frame::visibility_mask::{SoftVisibility, VisibilityMask};
use crate::gpu::timing::GpuTimes;
use crate::probes::maps::ProbeStats;
use crate::shadows::cost::EstimatedWork;
use crate::shadows::report::ShadowText;
use crate::shadows::source::ShadowStats;
use crate::shadows::vsm::plan::VirtualStats;

/// Times of one frame.
#[derive(Clone, Debug, Default)]
#[non_exhaustive]
pub struct FrameTimings {
    /// GPU milliseconds per [`Stage`](crate::gpu::timing::Stage) in the order they ran, empty if the adapter has no
    /// timestamp queries.
    pub gpu_ms: GpuTimes,
    /// CPU milliseconds to record and submit the frame's commands.
    pub cpu_record_ms: f64,
    /// Wall milliseconds from the start of recording until the image is back on the CPU.
    pub wall_ms: f64,
}

/// A rendered frame.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Frame {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// sRGB RGBA8 pixels, row-major from the top-left.
    pub rgba: Vec<u8>,
    /// The hard visibility mask, if asked for (also there when soft visibility is).
    pub visibility: Option<VisibilityMask>,
    /// How much of each light reaches each pixel, if asked for
    /// (`RenderSettings::soft_visibility`).
    pub soft_visibility: Option<SoftVisibility>,
    /// Timings.
    pub timings: FrameTimings,
    /// Shadow-generation work counters.
    pub shadow_stats: ShadowStats,
    /// Light-cluster counters (`None` with [`LightLoop::All`](crate::frame::clusters::LightLoop::All)).
    pub clusters: Option<ClusterStats>,
    /// Virtual shadow map counters (`None` for other techniques).
    pub virtual_maps: Option<VirtualStats>,
    /// Reflection probe counters (`None` for scenes without probes).
    pub probes: Option<ProbeStats>,
    /// The frame's shadows in words, as the technique writes them: a few labelled lines (what
    /// `manyshadows render` prints under its summary) and the frame's line among a sequence's.
    pub report: ShadowText,
}

/// What [`Renderer::render_to`](crate::Renderer::render_to) reports: the frame is submitted, not read back.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct SubmittedFrame {
    /// Shadow-generation work counters.
    pub shadow_stats: ShadowStats,
    /// CPU milliseconds to record and submit the frame's commands.
    pub cpu_record_ms: f64,
}

/// Where a renderer's shadows are ([`Renderer::shadow_layout`](crate::Renderer::shadow_layout)).
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowLayout {
    /// What the technique fills.
    pub fills: Fills,
    /// Shadow views: atlas tiles, or virtual faces.
    pub views: usize,
    /// Side of the depth texture shadows are read from (the atlas or the page pool; 1 for a
    /// mask).
    pub side: u32,
    /// Fraction of the atlas the views' tiles cover (atlas techniques only).
    pub atlas_fill: Option<f32>,
}

/// How much per-view shadow work a frame asks for, known before it is rendered
/// ([`Renderer::shadow_work`](crate::Renderer::shadow_work)).
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadowWork {
    /// Shadow views of the frame.
    pub views: usize,
    /// (caster triangle, view) pairs this technique's per-view stage takes on: every caster
    /// triangle in every view where the technique culls in its vertex stage or per thread,
    /// the pairs left by culling whole instances per view otherwise (clusters only cut that
    /// further).
    pub triangle_views: u64,
    /// The pairs left after culling whole instances per view by bounding sphere.
    pub after_instance_culling: u64,
    /// Every caster triangle in every view.
    pub all_pairs: u64,
}

/// What the next frame is estimated to cost
/// ([`Renderer::estimate_frame`](crate::Renderer::estimate_frame)).
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FrameEstimate {
    /// The work counted.
    pub work: EstimatedWork,
    /// Milliseconds of the camera's G-buffer.
    pub gbuffer_ms: f64,
    /// Milliseconds of the light clusters.
    pub clusters_ms: f64,
    /// Milliseconds of shadows (pages and acceleration structures included).
    pub shadows_ms: f64,
    /// Milliseconds of lighting (shadow rays and lookups included).
    pub lighting_ms: f64,
    /// Milliseconds of the reflection probes' faces when they are drawn (each face's
    /// G-buffer and lighting, every light per texel, at the camera's shadow cost per pair);
    /// 0 without probes.
    pub probes_ms: f64,
    /// Whether the costs were measured on an adapter of this kind (a CPU adapter: they were
    /// fitted on lavapipe); otherwise the figures are lavapipe's, an upper bound for a GPU.
    pub calibrated: bool,
}

impl FrameEstimate {
    /// Milliseconds of the whole frame.
    pub fn total_ms(&self) -> f64 {
        self.gbuffer_ms + self.clusters_ms + self.shadows_ms + self.lighting_ms + self.probes_ms
    }
}
