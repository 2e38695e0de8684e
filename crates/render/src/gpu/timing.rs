//! GPU timing with timestamp queries written at the start and end of passes.
//!
//! A *span* is a named pair of timestamps; a stage made of many passes (one per shadow view)
//! writes the span's start in its first pass and its end in its last. Without the
//! `TIMESTAMP_QUERY` feature every call is a no-op and no GPU times are reported.
//!
//! Benchmarks may also turn on pipeline-statistics queries
//! ([`GpuTimer::enable_statistics`]): techniques bracket each pass they record with
//! `begin_*_stats` / `end_*_stats`, and the counts of all bracketed passes are summed.

use std::cell::Cell;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;

/// Pipeline-statistics counters summed over the passes of one generation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct PipelineCounts {
    /// Vertex-shader invocations.
    pub vertex_shader_invocations: u64,
    /// Primitives that entered the clipper.
    pub clipper_invocations: u64,
    /// Primitives that left the clipper (what is rasterized).
    pub clipper_primitives_out: u64,
    /// Fragment-shader invocations (0 for depth-only pipelines without a fragment stage).
    pub fragment_shader_invocations: u64,
    /// Compute-shader invocations.
    pub compute_shader_invocations: u64,
}

const STAT_TYPES: wgpu::PipelineStatisticsTypes = wgpu::PipelineStatisticsTypes::all();
const STAT_WORDS: u64 = 5;

struct StatQueries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    capacity: u32,
    next: Cell<u32>,
    overflow: Cell<bool>,
}

/// A stage of a frame whose GPU time is measured, in the order a frame runs them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Stage {
    /// Skinned and morphed meshes bent on the GPU (gpu_scene/deform.rs), before anything
    /// draws; only in frames after a new pose.
    Deform,
    /// The camera's G-buffer.
    GBuffer,
    /// Assigning lights to clusters.
    Clusters,
    /// Virtual shadow maps: marking, allocating and clearing pages.
    Pages,
    /// Ray-traced shadows: building the frame's top-level acceleration structure.
    Accel,
    /// Shadow generation: the atlas, the virtual pages, or irregular shadow maps' mask.
    Shadows,
    /// Reflection probes: their faces' G-buffers and lighting.
    Probes,
    /// Deferred lighting.
    Lighting,
    /// The denoiser of shadow rays: its temporal and spatial passes and the composite that
    /// shades their result (`RayOptions::denoise`).
    Denoise,
    /// The hard visibility mask.
    Visibility,
}

impl Stage {
    /// Every stage, in frame order.
    pub const ALL: &'static [Stage] = &[
        Stage::Deform,
        Stage::GBuffer,
        Stage::Clusters,
        Stage::Pages,
        Stage::Accel,
        Stage::Shadows,
        Stage::Probes,
        Stage::Lighting,
        Stage::Denoise,
        Stage::Visibility,
    ];

    /// The stage's name in reports and JSON (`deform`, `gbuffer`, `clusters`, `pages`, `accel`,
    /// `shadows`, `probes`, `lighting`, `denoise`, `visibility`).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Deform => "deform",
            Stage::GBuffer => "gbuffer",
            Stage::Clusters => "clusters",
            Stage::Pages => "pages",
            Stage::Accel => "accel",
            Stage::Shadows => "shadows",
            Stage::Probes => "probes",
            Stage::Lighting => "lighting",
            Stage::Denoise => "denoise",
            Stage::Visibility => "visibility",
        }
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// GPU milliseconds per stage of one frame, in the order the stages ran; empty when the
/// device has no timestamp queries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GpuTimes(Vec<(Stage, f64)>);

impl GpuTimes {
    /// Times from `(stage, milliseconds)` pairs.
    pub fn new(stages: Vec<(Stage, f64)>) -> Self {
        Self(stages)
    }

    /// Milliseconds of `stage` (summed if it ran more than once), `None` if it did not run or
    /// nothing was timed.
    pub fn get(&self, stage: Stage) -> Option<f64> {
        let mut it = self.0.iter().filter(|(s, _)| *s == stage).peekable();
        it.peek()?;
        Some(it.map(|(_, ms)| ms).sum())
    }

    /// Milliseconds of every stage together, `None` if nothing was timed.
    pub fn total(&self) -> Option<f64> {
        (!self.0.is_empty()).then(|| self.0.iter().map(|(_, ms)| ms).sum())
    }

    /// `(stage, milliseconds)` in the order the stages ran.
    pub fn iter(&self) -> impl Iterator<Item = (Stage, f64)> + '_ {
        self.0.iter().copied()
    }

    /// True when nothing was timed (no timestamp queries on the device).
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A map from stage name to milliseconds (`{"gbuffer": 1.2, "shadows": 3.4, …}`).
impl serde::Serialize for GpuTimes {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (stage, ms) in &self.0 {
            map.serialize_entry(stage.name(), ms)?;
        }
        map.end()
    }
}

/// Most spans per frame.
const MAX_SPANS: u32 = 32;

const BEGUN: u8 = 1;
const ENDED: u8 = 2;

/// A span handle: indices of its two timestamps.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    begin: u32,
    end: u32,
}

/// Timestamp queries for one frame.
pub struct GpuTimer {
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    labels: Vec<(Stage, Span)>,
    /// Per span, which of its timestamps a pass of this frame writes (`BEGUN`, `ENDED`): a
    /// span no pass wrote (a stage that drew nothing, such as cached shadows that redrew no
    /// view) times 0, never the ticks its queries kept from an earlier frame.
    written: [Cell<u8>; MAX_SPANS as usize],
    period_ns: f32,
    stats: Option<StatQueries>,
}

impl GpuTimer {
    /// A timer; inert if the device lacks `TIMESTAMP_QUERY`.
    pub fn new(ctx: &GpuContext) -> Self {
        let queries = ctx.has(wgpu::Features::TIMESTAMP_QUERY).then(|| {
            let count = MAX_SPANS * 2;
            let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timer.queries"),
                ty: wgpu::QueryType::Timestamp,
                count,
            });
            let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timer.resolve"),
                size: count as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timer.readback"),
                size: count as u64 * 8,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (set, resolve, readback)
        });
        Self {
            queries,
            labels: Vec::new(),
            written: std::array::from_fn(|_| Cell::new(0)),
            period_ns: ctx.queue.get_timestamp_period(),
            stats: None,
        }
    }

    /// Turns on pipeline-statistics queries for up to `passes` bracketed passes per frame.
    /// Returns false (and stays off) if the adapter lacks `PIPELINE_STATISTICS_QUERY`.
    pub fn enable_statistics(&mut self, ctx: &GpuContext, passes: u32) -> bool {
        if !ctx.has(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
            return false;
        }
        let capacity = passes.clamp(1, 4096);
        let bytes = capacity as u64 * STAT_WORDS * 8;
        self.stats = Some(StatQueries {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timer.statistics"),
                ty: wgpu::QueryType::PipelineStatistics(STAT_TYPES),
                count: capacity,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timer.statistics.resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timer.statistics.readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            capacity,
            next: Cell::new(0),
            overflow: Cell::new(false),
        });
        true
    }

    fn stat_slot(&self) -> Option<(&wgpu::QuerySet, u32)> {
        let q = self.stats.as_ref()?;
        let i = q.next.get();
        if i >= q.capacity {
            q.overflow.set(true);
            return None;
        }
        q.next.set(i + 1);
        Some((&q.set, i))
    }

    /// Starts counting a render pass; pass the result to [`GpuTimer::end_render_stats`].
    pub fn begin_render_stats(&self, pass: &mut wgpu::RenderPass<'_>) -> bool {
        match self.stat_slot() {
            Some((set, i)) => {
                pass.begin_pipeline_statistics_query(set, i);
                true
            }
            None => false,
        }
    }

    /// Ends counting a render pass.
    pub fn end_render_stats(&self, pass: &mut wgpu::RenderPass<'_>, began: bool) {
        if began {
            pass.end_pipeline_statistics_query();
        }
    }

    /// Starts counting a compute pass; pass the result to [`GpuTimer::end_compute_stats`].
    pub fn begin_compute_stats(&self, pass: &mut wgpu::ComputePass<'_>) -> bool {
        match self.stat_slot() {
            Some((set, i)) => {
                pass.begin_pipeline_statistics_query(set, i);
                true
            }
            None => false,
        }
    }

    /// Ends counting a compute pass.
    pub fn end_compute_stats(&self, pass: &mut wgpu::ComputePass<'_>, began: bool) {
        if began {
            pass.end_pipeline_statistics_query();
        }
    }

    /// Sums the statistics of this frame's bracketed passes (after submission); `None` if
    /// statistics are off, or if more passes were bracketed than the capacity allows.
    pub fn read_statistics(&self, ctx: &GpuContext) -> Result<Option<PipelineCounts>, RenderError> {
        let Some(q) = self.stats.as_ref() else {
            return Ok(None);
        };
        if q.overflow.get() {
            return Ok(None);
        }
        let n = q.next.get() as u64;
        if n == 0 {
            return Ok(Some(PipelineCounts::default()));
        }
        let bytes = crate::gpu::readback::map_read(ctx, &q.readback, 0..n * STAT_WORDS * 8)?;
        let words: &[u64] = bytemuck::cast_slice(&bytes);
        let mut c = PipelineCounts::default();
        for q in words.chunks_exact(STAT_WORDS as usize) {
            c.vertex_shader_invocations += q[0];
            c.clipper_invocations += q[1];
            c.clipper_primitives_out += q[2];
            c.fragment_shader_invocations += q[3];
            c.compute_shader_invocations += q[4];
        }
        Ok(Some(c))
    }

    /// True if GPU times will be measured.
    pub fn enabled(&self) -> bool {
        self.queries.is_some()
    }

    /// Forgets the spans of the previous frame.
    pub fn reset(&mut self) {
        self.labels.clear();
        for w in &self.written {
            w.set(0);
        }
        if let Some(q) = &self.stats {
            q.next.set(0);
            q.overflow.set(false);
        }
    }

    /// Starts a span timing `stage`; `None` if timing is off or the span budget is spent.
    pub fn span(&mut self, stage: Stage) -> Option<Span> {
        self.queries.as_ref()?;
        let n = self.labels.len() as u32;
        if n >= MAX_SPANS {
            return None;
        }
        let span = Span {
            begin: 2 * n,
            end: 2 * n + 1,
        };
        self.labels.push((stage, span));
        Some(span)
    }

    /// Timestamp writes for a render pass that is the `first` and/or `last` of a span.
    pub fn render_writes(
        &self,
        span: Option<Span>,
        first: bool,
        last: bool,
    ) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let (set, _, _) = self.queries.as_ref()?;
        let span = span?;
        if !first && !last {
            return None;
        }
        self.note_written(span, first, last);
        Some(wgpu::RenderPassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: first.then_some(span.begin),
            end_of_pass_write_index: last.then_some(span.end),
        })
    }

    /// Timestamp writes for a compute pass that is the `first` and/or `last` of a span.
    pub fn compute_writes(
        &self,
        span: Option<Span>,
        first: bool,
        last: bool,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let (set, _, _) = self.queries.as_ref()?;
        let span = span?;
        if !first && !last {
            return None;
        }
        self.note_written(span, first, last);
        Some(wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: first.then_some(span.begin),
            end_of_pass_write_index: last.then_some(span.end),
        })
    }

    fn note_written(&self, span: Span, first: bool, last: bool) {
        let w = &self.written[(span.begin / 2) as usize];
        w.set(w.get() | if first { BEGUN } else { 0 } | if last { ENDED } else { 0 });
    }

    /// This frame's spans, those whose passes did not write both timestamps made empty (their
    /// end read at their beginning: 0 ms).
    fn spans(&self) -> Vec<(Stage, Span)> {
        self.labels
            .iter()
            .map(|&(stage, s)| {
                if self.written[(s.begin / 2) as usize].get() == BEGUN | ENDED {
                    (stage, s)
                } else {
                    (
                        stage,
                        Span {
                            begin: s.begin,
                            end: s.begin,
                        },
                    )
                }
            })
            .collect()
    }

    /// Records the resolve of this frame's queries; call once after the last timed pass.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(q) = &self.stats {
            let n = q.next.get().min(q.capacity);
            if n > 0 {
                encoder.resolve_query_set(&q.set, 0..n, &q.resolve, 0);
                encoder.copy_buffer_to_buffer(
                    &q.resolve,
                    0,
                    &q.readback,
                    0,
                    n as u64 * STAT_WORDS * 8,
                );
            }
        }
        let Some((set, resolve, readback)) = self.queries.as_ref() else {
            return;
        };
        let n = self.labels.len() as u32 * 2;
        if n == 0 {
            return;
        }
        encoder.resolve_query_set(set, 0..n, resolve, 0);
        encoder.copy_buffer_to_buffer(resolve, 0, readback, 0, n as u64 * 8);
    }

    /// Bytes a copy of this frame's resolved timestamps takes (0 without timestamps or spans).
    pub fn resolved_bytes(&self) -> u64 {
        if self.queries.is_none() {
            return 0;
        }
        self.labels.len() as u64 * 2 * 8
    }

    /// Records the resolve of this frame's queries and a copy of the timestamps into
    /// `staging` (a `MAP_READ | COPY_DST` buffer of at least [`GpuTimer::resolved_bytes`]),
    /// and returns the spans to decode them with once `staging` is mapped
    /// ([`GpuTimer::decode`]): a read-back that never waits for the GPU.
    pub fn resolve_to(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        staging: &wgpu::Buffer,
    ) -> Vec<(Stage, Span)> {
        let Some((set, resolve, _)) = self.queries.as_ref() else {
            return Vec::new();
        };
        let n = self.labels.len() as u32 * 2;
        if n == 0 {
            return Vec::new();
        }
        encoder.resolve_query_set(set, 0..n, resolve, 0);
        encoder.copy_buffer_to_buffer(resolve, 0, staging, 0, n as u64 * 8);
        self.spans()
    }

    /// GPU milliseconds of `spans` from their resolved `ticks`.
    pub fn decode(&self, spans: &[(Stage, Span)], ticks: &[u64]) -> GpuTimes {
        GpuTimes(
            spans
                .iter()
                .map(|&(stage, s)| {
                    let dt = ticks[s.end as usize].saturating_sub(ticks[s.begin as usize]);
                    (stage, dt as f64 * self.period_ns as f64 / 1e6)
                })
                .collect(),
        )
    }

    /// Reads the resolved spans back (after the frame's submission).
    pub fn read(&self, ctx: &GpuContext) -> Result<GpuTimes, RenderError> {
        let Some((_, _, readback)) = self.queries.as_ref() else {
            return Ok(GpuTimes::default());
        };
        let n = self.labels.len() as u64 * 2;
        if n == 0 {
            return Ok(GpuTimes::default());
        }
        let bytes = crate::gpu::readback::map_read(ctx, readback, 0..n * 8)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        Ok(GpuTimes(
            self.spans()
                .into_iter()
                .map(|(stage, s)| {
                    let dt = ticks[s.end as usize].saturating_sub(ticks[s.begin as usize]);
                    (stage, dt as f64 * self.period_ns as f64 / 1e6)
                })
                .collect(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_times_by_stage_total_and_json() {
        let t = GpuTimes::new(vec![
            (Stage::GBuffer, 1.0),
            (Stage::Shadows, 2.0),
            (Stage::Lighting, 4.0),
            (Stage::Shadows, 0.5),
        ]);
        assert_eq!(t.get(Stage::Shadows), Some(2.5));
        assert_eq!(t.get(Stage::Pages), None);
        assert_eq!(t.total(), Some(7.5));
        let json = serde_json::to_value(GpuTimes::new(vec![(Stage::Clusters, 1.5)])).unwrap();
        assert_eq!(json, serde_json::json!({"clusters": 1.5}));
        let none = GpuTimes::default();
        assert!(none.is_empty() && none.total().is_none() && none.get(Stage::GBuffer).is_none());
        let names: Vec<_> = Stage::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(
            names,
            [
                "deform",
                "gbuffer",
                "clusters",
                "pages",
                "accel",
                "shadows",
                "probes",
                "lighting",
                "denoise",
                "visibility"
            ]
        );
    }
}
