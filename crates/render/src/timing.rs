//! GPU timing with timestamp queries written at the start and end of passes.
//!
//! A *span* is a named pair of timestamps; a stage made of many passes (one per shadow view)
//! writes the span's start in its first pass and its end in its last. Without the
//! `TIMESTAMP_QUERY` feature every call is a no-op and no GPU times are reported.

use crate::{GpuContext, RenderError};

/// Most spans per frame.
const MAX_SPANS: u32 = 32;

/// A span handle: indices of its two timestamps.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    begin: u32,
    end: u32,
}

/// Timestamp queries for one frame.
pub struct GpuTimer {
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    labels: Vec<(String, Span)>,
    period_ns: f32,
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
            period_ns: ctx.queue.get_timestamp_period(),
        }
    }

    /// True if GPU times will be measured.
    pub fn enabled(&self) -> bool {
        self.queries.is_some()
    }

    /// Forgets the spans of the previous frame.
    pub fn reset(&mut self) {
        self.labels.clear();
    }

    /// Starts a named span; `None` if timing is off or the span budget is spent.
    pub fn span(&mut self, label: &str) -> Option<Span> {
        self.queries.as_ref()?;
        let n = self.labels.len() as u32;
        if n >= MAX_SPANS {
            return None;
        }
        let span = Span {
            begin: 2 * n,
            end: 2 * n + 1,
        };
        self.labels.push((label.to_string(), span));
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
        Some(wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: first.then_some(span.begin),
            end_of_pass_write_index: last.then_some(span.end),
        })
    }

    /// Records the resolve of this frame's queries; call once after the last timed pass.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
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

    /// Reads the resolved spans back (after the frame's submission): `(label, milliseconds)`.
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<(String, f64)>, RenderError> {
        let Some((_, _, readback)) = self.queries.as_ref() else {
            return Ok(Vec::new());
        };
        let n = self.labels.len() as u64 * 2;
        if n == 0 {
            return Ok(Vec::new());
        }
        let bytes = crate::readback::map_read(ctx, readback, 0..n * 8)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        Ok(self
            .labels
            .iter()
            .map(|(label, s)| {
                let dt = ticks[s.end as usize].saturating_sub(ticks[s.begin as usize]);
                (label.clone(), dt as f64 * self.period_ns as f64 / 1e6)
            })
            .collect())
    }
}
