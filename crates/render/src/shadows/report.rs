//! What a frame says of its shadows in words: a few labelled lines, written by each technique
//! (its declaration's `report`), which `manyshadows render` prints under its summary and
//! [`crate::Frame::report`] carries. What every technique's report opens with (the views,
//! the filter, what sized lights get) is here; the rest is the technique's own: the atlas and
//! its passes (`atlas/shared.rs`), the virtual maps' pages, irregular maps' lists, the rays'
//! builds.

use std::any::Any;

use crate::error::Technique;
use crate::gpu::timing::{GpuTimes, Stage};
use crate::sampled::options::RayOptions;
use crate::shadows::options::{Pcf, SoftShadows};
use crate::shadows::plan::ShadowPlan;
use crate::shadows::source::ShadowStats;

/// One line of a frame's report: a short label (`atlas`, `pages`) and what follows it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ReportLine {
    /// At most 12 characters.
    pub label: &'static str,
    /// The line.
    pub text: String,
}

impl ReportLine {
    /// A line labelled `label`.
    pub fn new(label: &'static str, text: impl Into<String>) -> Self {
        ReportLine {
            label,
            text: text.into(),
        }
    }
}

impl std::fmt::Display for ReportLine {
    /// `label` padded to 12 columns, then the text (as `render` prints its summary).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:<12} {}", self.label, self.text)
    }
}

/// A frame's shadows in words, as its technique writes them: the summary's lines, and one
/// line for the frame among others (what `render --frames` prints per frame, after `frame N:`).
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct ShadowText {
    /// The summary's lines.
    pub lines: Vec<ReportLine>,
    /// The frame's line among a sequence's: what it redrew or built, and its GPU time.
    pub frame: String,
}

/// What a technique's report is written from: the frame's settings as the shadows saw them,
/// its shadow work, its plan, and the technique's own counters.
pub struct ShadowReport<'a> {
    /// The technique.
    pub technique: Technique,
    /// Shadow views (tiles, faces, light views).
    pub views: usize,
    /// The filter of hard shadows.
    pub pcf: Pcf,
    /// The soft-shadow filter's taps and its widest penumbra as the technique's lookup reads
    /// it (clamped to what it reaches).
    pub soft: SoftShadows,
    /// The sampled lights' and rays' options.
    pub rays: RayOptions,
    /// Whether a light that casts shadows has a size.
    pub sized: bool,
    /// The frame's shadow work.
    pub stats: ShadowStats,
    /// The shadow views and atlas layout.
    pub plan: &'a ShadowPlan,
    /// The technique's own counters (`ShadowSource::technique_stats`), if it keeps any.
    pub own: Option<&'a (dyn Any + Send + Sync)>,
    /// The frame's GPU times.
    pub gpu_ms: &'a GpuTimes,
    /// Frames the renderer has drawn, this one included.
    pub frames: u32,
    /// Whether a shadow budget keeps views waiting.
    pub budget: bool,
}

impl ShadowReport<'_> {
    /// `stage`'s GPU time in words (`n/a` without timestamps).
    pub fn gpu_time(&self, stage: Stage) -> String {
        self.gpu_ms
            .get(stage)
            .map_or("n/a".to_string(), |v| format!("{v:.2} ms"))
    }

    /// The technique's own counters as `T`.
    pub fn own<T: Any>(&self) -> Option<&T> {
        self.own.and_then(|o| o.downcast_ref::<T>())
    }

    /// The report's opening: `shadows` (the views, the technique, the filter) and, where a
    /// light has a size, `soft` (what sized lights get).
    pub fn opening(&self, views: &str, filter: &str, softness: &str) -> Vec<ReportLine> {
        let mut lines = vec![ReportLine::new(
            "shadows",
            format!("{views}, technique {}, {filter}", self.technique),
        )];
        if self.sized {
            lines.push(ReportLine::new("soft", softness));
        }
        lines
    }

    /// The opening of a technique that reads shadow maps: its views, PCF, and percentage-
    /// closer soft shadows for sized lights.
    pub fn maps_opening(&self) -> Vec<ReportLine> {
        self.opening(
            &format!("{} views", self.views),
            &format!("PCF {}", self.pcf.name()),
            &format!(
                "sized lights: PCSS, {} blocker and {} filter taps, penumbrae up to {:?} texels",
                self.soft.blocker_taps, self.soft.filter_taps, self.soft.max_penumbra
            ),
        )
    }
}
