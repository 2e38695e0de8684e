//! Recording, submitting and reading back a frame: the passes in order (G-buffer, clusters,
//! the source's shadows, probes, lighting, the denoiser), `render` and `render_reporting`
//! (read back, with the parts said as the GPU finishes them), `render_to` (into the caller's
//! texture, timings mapped without waiting) and the GPU times of submitted frames.

// `std::time::Instant` panics in a browser; web-time is std's on native targets.
use web_time::Instant;

use super::state::{Renderer, MAP_DONE, MAP_FAILED, MAP_PENDING, MAX_TIMINGS_IN_FLIGHT};
use crate::error::RenderError;
use crate::frame::visibility_mask::{SoftVisibility, VisibilityMask};
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimes, Stage};
use crate::report::{Frame, FrameTimings, SubmittedFrame};
use crate::shadows::report::{ShadowReport, ShadowText};
use crate::shadows::source::ShadowStats;

impl Renderer {
    /// Records one frame after deriving the GPU state from any change, pass by pass in the
    /// order of the algorithm: the meshes bent on the GPU (after a new pose), the G-buffer, the light clusters, the shadows, the probes'
    /// faces, the lighting (with what follows it), the denoiser and its composite, the
    /// visibility mask; returns the shadow work counters.
    fn record_frame(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        mut boundary: Option<&mut Boundary<'_>>,
    ) -> Result<ShadowStats, RenderError> {
        self.prepare()?;
        self.timer.reset();
        self.begin_histories(ctx);
        self.parts.write_uniforms(ctx);
        let scene = &mut self.parts.scene;
        if let Some(l) = &mut scene.last_positions {
            // Before the bend: what the last frame drew.
            l.record_gpu(encoder, &scene.positions);
        }
        if let Some(d) = self
            .parts
            .deformer
            .as_mut()
            .and_then(Option::as_mut)
            .filter(|d| d.pending())
        {
            let span = self.timer.span(Stage::Deform);
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("deform"),
                timestamp_writes: self.timer.compute_writes(span, true, true),
            });
            d.record(&mut pass);
        }
        let span = self.timer.span(Stage::GBuffer);
        let parts = &mut self.parts;
        parts
            .gbuffer
            .record(encoder, &parts.scene, &self.timer, span);
        if parts.clusters.enabled() {
            let span = self.timer.span(Stage::Clusters);
            parts.clusters.record(encoder, &self.timer, span);
        }
        if let Some(b) = boundary.as_deref_mut() {
            b(encoder, FramePart::Camera)?;
        }
        if self.parts.wants.is_some() {
            // The pairs the sampled lights will ask about, before the shadows are made for
            // them alone (sampled/pages.rs); timed with the pages.
            let span = self.timer.span(Stage::Pages);
            self.lighting.record_own_as(
                crate::sampled::pages::CHOOSE,
                encoder,
                (&self.timer, span),
                (true, true),
            );
        }
        let parts = &mut self.parts;
        let shadow_stats = parts
            .source
            .record(ctx, &parts.scene, encoder, &mut self.timer);
        if let Some(b) = boundary {
            b(encoder, FramePart::Shadows)?;
        }
        let parts = &mut self.parts;
        if let Some(p) = parts.probes.as_mut().filter(|p| p.dirty) {
            let span = self.timer.span(Stage::Probes);
            p.record(encoder, &parts.scene, &self.timer, span);
        } else if let Some(p) = &mut parts.probes {
            p.faces_drawn = 0;
        }
        let span = self.timer.span(Stage::Lighting);
        self.lighting.record(encoder, &self.timer, span);
        if let Some(d) = &mut self.parts.denoiser {
            let span = self.timer.span(Stage::Denoise);
            d.record(
                ctx,
                encoder,
                camera_of(&self.current, &self.settings),
                &self.timer,
                span,
            );
            self.lighting.record_own(
                crate::sampled::denoise::COMPOSITE,
                encoder,
                &self.timer,
                span,
            );
        }
        if let Some(v) = &mut self.visibility {
            let span = self.timer.span(Stage::Visibility);
            v.record(ctx, encoder, &self.timer, span);
        }
        Ok(shadow_stats)
    }

    /// Before a frame's passes: the sampled lights' histories take in what moved (the
    /// instances' motion, the camera the reservoirs reproject from) and the frame's numbers
    /// for their rays (`FrameUniforms::modes.yzw`: the frame's number, new random numbers
    /// each frame, and the denoiser's correction for changed lights, this frame only).
    fn begin_histories(&mut self, ctx: &GpuContext) {
        let parts = &mut self.parts;
        if let Some(l) = &mut parts.scene.last_positions {
            l.begin_frame(&ctx.queue);
        }
        if let Some(d) = &mut parts.denoiser {
            d.upload_moved(&ctx.queue);
        }
        if let Some(m) = &mut parts.motion {
            let instances = &self.current.instances;
            m.upload(&ctx.queue, |i| instances[i].transform);
        }
        if let Some(r) = &mut parts.reuse {
            r.prepare(
                ctx,
                camera_of(&self.current, &self.settings),
                self.current.lights.len(),
            );
        }
        if parts.denoiser.is_some() || parts.reuse.is_some() {
            self.frames_denoised = self.frames_denoised.wrapping_add(1);
            let [first, counts] = parts.denoiser.as_ref().map_or([0, 0], |d| d.light_fix());
            parts.uniforms.modes[1] = self.frames_denoised;
            parts.uniforms.modes[2] = first;
            parts.uniforms.modes[3] = counts;
        }
    }

    /// Starts a frame: a new encoder with the frame recorded up to the lit image.
    fn begin_frame<'p>(
        &mut self,
        ctx: &GpuContext,
        progress: Option<&mut (dyn FnMut(FramePart) + 'p)>,
    ) -> Result<(Instant, wgpu::CommandEncoder, ShadowStats), RenderError> {
        let start = Instant::now();
        let new_encoder = || {
            ctx.device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("frame.encoder"),
                })
        };
        let mut encoder = new_encoder();
        let shadow_stats = match progress {
            None => self.record_frame(ctx, &mut encoder, None)?,
            Some(progress) => {
                // Each part is submitted and waited for before the next is recorded.
                let mut boundary = |enc: &mut wgpu::CommandEncoder, part: FramePart| {
                    let done = std::mem::replace(enc, new_encoder());
                    ctx.queue.submit([done.finish()]);
                    ctx.wait_idle()?;
                    progress(part);
                    Ok(())
                };
                self.record_frame(ctx, &mut encoder, Some(&mut boundary))?
            }
        };
        Ok((start, encoder, shadow_stats))
    }

    /// Resolves the timer queries of the last frame and reads them (waits for it).
    fn resolve_timings(&self, ctx: &GpuContext) -> Result<GpuTimes, RenderError> {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("timer.encoder"),
            });
        self.timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        self.timer.read(ctx)
    }

    /// Renders one frame into `target`, a texture the caller owns (created with
    /// `RENDER_ATTACHMENT` usage; any size — the frame is scaled to it, nearest texel — and
    /// any normalized or float colour format, sRGB or not: a window's surface texture, say),
    /// and submits it without reading anything back. The caller presents or samples the
    /// texture after this returns; [`Renderer::render`] is the same frame read back to the CPU.
    /// A source that checks its frame after submission (irregular maps' node pool) waits for
    /// it here (an overflowed frame is an error, never a wrong image).
    pub fn render_to(&mut self, target: &wgpu::Texture) -> Result<SubmittedFrame, RenderError> {
        let ctx = &*self.ctx.clone();
        ctx.scoped("rendering a frame into the caller's texture", || {
            let (start, mut encoder, shadow_stats) = self.begin_frame(ctx, None)?;
            let blit = self
                .blit
                .get_or_insert_with(|| crate::shading::blit::Blit::new(ctx));
            blit.record(ctx, &mut encoder, &self.lighting.color, target)?;
            // The frame's timestamps go to a staging buffer mapped without waiting
            // (`poll_gpu_timings`); `read_gpu_timings` can still resolve them afterwards.
            let bytes = self.timer.resolved_bytes();
            let staged =
                (bytes > 0 && self.timings.pending.len() < MAX_TIMINGS_IN_FLIGHT).then(|| {
                    let staging = match self.timings.free.iter().position(|b| b.size() >= bytes) {
                        Some(i) => self.timings.free.swap_remove(i),
                        None => ctx.device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some("renderer.timings"),
                            size: bytes.max(256),
                            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                            mapped_at_creation: false,
                        }),
                    };
                    let spans = self.timer.resolve_to(&mut encoder, &staging);
                    (staging, spans)
                });
            ctx.queue.submit([encoder.finish()]);
            if let Some((staging, spans)) = staged {
                let state = std::sync::Arc::new(std::sync::atomic::AtomicU8::new(MAP_PENDING));
                let done = state.clone();
                staging.map_async(wgpu::MapMode::Read, .., move |r| {
                    done.store(
                        if r.is_ok() { MAP_DONE } else { MAP_FAILED },
                        std::sync::atomic::Ordering::Release,
                    );
                });
                self.timings.pending.push_back((staging, spans, state));
            }
            self.parts.source.finish(ctx)?;
            Ok(SubmittedFrame {
                shadow_stats,
                cpu_record_ms: start.elapsed().as_secs_f64() * 1e3,
            })
        })
    }

    /// GPU milliseconds per stage of the last frame [`Renderer::render_to`] submitted (empty
    /// without timestamp queries). Waits for that frame to finish.
    pub fn read_gpu_timings(&mut self) -> Result<GpuTimes, RenderError> {
        let ctx = &*self.ctx.clone();
        ctx.scoped("reading the frame's GPU times", || {
            self.resolve_timings(ctx)
        })
    }

    /// GPU milliseconds per stage of the newest frame [`Renderer::render_to`] submitted whose
    /// GPU work has finished, or `None` while none has since the last call. Never waits for
    /// the GPU (it only polls the device): an interactive loop calls it every frame and shows
    /// times a frame or two old, where [`Renderer::read_gpu_timings`] would wait for the frame
    /// just submitted.
    pub fn poll_gpu_timings(&mut self) -> Option<GpuTimes> {
        use std::sync::atomic::Ordering;
        let _ = self.ctx.device.poll(wgpu::PollType::Poll);
        let mut newest = None;
        while let Some((_, _, state)) = self.timings.pending.front() {
            match state.load(Ordering::Acquire) {
                MAP_PENDING => break,
                s => {
                    let (staging, spans, _) = self.timings.pending.pop_front().expect("front");
                    if s == MAP_DONE {
                        if let Ok(view) = staging.get_mapped_range(..) {
                            let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&view);
                            drop(view);
                            newest = Some(self.timer.decode(&spans, &ticks));
                        }
                        staging.unmap();
                        self.timings.free.push(staging);
                    }
                }
            }
        }
        newest
    }

    /// The last submitted frame's hard visibility mask, one bit per pixel and light, and how
    /// much of each light reaches each pixel, where [`RenderSettings::visibility`] and
    /// [`RenderSettings::soft_visibility`] ask for them (`None` otherwise): from the frame's
    /// visibility pass, or the source's own mask (a hard answer, also as soft visibility).
    /// [`Renderer::render`] reads them into its [`Frame`]; after [`Renderer::render_to`] this
    /// reads them (waiting for that frame).
    ///
    /// [`RenderSettings::visibility`]: crate::RenderSettings::visibility
    /// [`RenderSettings::soft_visibility`]: crate::RenderSettings::soft_visibility
    pub fn read_visibility(
        &self,
    ) -> Result<(Option<VisibilityMask>, Option<SoftVisibility>), RenderError> {
        let ctx = &*self.ctx;
        Ok(match &self.visibility {
            Some(pass) => match pass.read(ctx)? {
                Some((mask, soft)) => (Some(mask), soft),
                None => (None, None),
            },
            None if self.settings.visibility || self.settings.soft_visibility => {
                let mask = self.parts.source.read_mask(ctx)?;
                let soft = mask
                    .as_ref()
                    .filter(|_| self.settings.soft_visibility)
                    .map(SoftVisibility::from_mask);
                (mask, soft)
            }
            None => (None, None),
        })
    }

    /// The frame's shadows in words, as the technique writes them (its declaration's `report`)
    /// from the frame's work, its GPU times and the technique's own counters `own`.
    fn report(
        &self,
        stats: &ShadowStats,
        own: Option<&(dyn std::any::Any + Send + Sync)>,
        gpu_ms: &GpuTimes,
    ) -> ShadowText {
        let s = &self.settings;
        let info = s.technique.info();
        (info.report)(&ShadowReport {
            technique: s.technique,
            views: self.shadow_views(),
            pcf: s.pcf,
            soft: crate::shadows::options::SoftShadows {
                max_penumbra: self.max_penumbra(),
                ..s.soft
            },
            rays: s.rays,
            sized: self
                .current
                .lights
                .iter()
                .any(|l| l.size > 0.0 && l.casts_shadows),
            stats: *stats,
            plan: self.parts.source.plan(),
            own,
            gpu_ms,
            frames: self.frames_read,
            budget: s.shadow_budget.is_some(),
        })
    }

    /// Renders one frame and reads it back.
    pub fn render(&mut self) -> Result<Frame, RenderError> {
        self.render_frame(None)
    }

    /// [`Renderer::render`], telling `progress` each part of the frame as the GPU finishes it
    /// (the camera's G-buffer and light clusters, the shadows, the lighting): each part is
    /// submitted and waited for before the next is recorded, so a frame that takes minutes
    /// says where it is. The image is the one `render` gives, byte for byte; only the CPU
    /// record time and the wall time include the waits.
    pub fn render_reporting(
        &mut self,
        progress: &mut dyn FnMut(FramePart),
    ) -> Result<Frame, RenderError> {
        self.render_frame(Some(progress))
    }

    fn render_frame<'p>(
        &mut self,
        mut progress: Option<&mut (dyn FnMut(FramePart) + 'p)>,
    ) -> Result<Frame, RenderError> {
        let ctx = &*self.ctx.clone();
        ctx.scoped("rendering a frame", || {
            let (start, encoder, shadow_stats) = self.begin_frame(ctx, progress.as_deref_mut())?;
            ctx.queue.submit([encoder.finish()]);
            let cpu_record_ms = start.elapsed().as_secs_f64() * 1e3;
            let rgba = crate::gpu::readback::read_texture(ctx, &self.lighting.color, 4)?;
            if let Some(p) = progress {
                p(FramePart::Lighting);
            }
            let wall_ms = start.elapsed().as_secs_f64() * 1e3;
            let clusters = if self.parts.clusters.enabled() {
                Some(self.parts.clusters.read_stats(ctx)?)
            } else {
                None
            };
            // A source whose frame went wrong (irregular's full node pool) makes it an error,
            // never a wrong image.
            self.parts.source.finish(ctx)?;
            let own = self.parts.source.technique_stats(ctx)?;
            let (visibility, soft_visibility) = self.read_visibility()?;
            let gpu_ms = self.resolve_timings(ctx)?;
            self.frames_read = self.frames_read.saturating_add(1);
            let report = self.report(&shadow_stats, own.as_deref(), &gpu_ms);
            let virtual_maps = own.and_then(|s| s.downcast().ok()).map(|s| *s);
            debug_assert!(visibility
                .as_ref()
                .is_none_or(|v: &VisibilityMask| v.lights as usize == self.current.lights.len()));
            Ok(Frame {
                width: self.settings.width,
                height: self.settings.height,
                rgba,
                visibility,
                soft_visibility,
                timings: FrameTimings {
                    gpu_ms,
                    cpu_record_ms,
                    wall_ms,
                },
                shadow_stats,
                clusters,
                virtual_maps,
                probes: self.parts.probes.as_ref().map(|p| p.stats()),
                report,
            })
        })
    }
}

/// The parts of a frame [`Renderer::render_reporting`] reports as the GPU finishes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FramePart {
    /// The camera's G-buffer and the light clusters.
    Camera,
    /// The shadows: maps, pages, lists or the acceleration structure (the technique's
    /// source).
    Shadows,
    /// The lighting (and the denoiser) and the image read back.
    Lighting,
}

impl FramePart {
    /// A few words for progress lines.
    pub fn describe(self) -> &'static str {
        match self {
            FramePart::Camera => "G-buffer and light clusters",
            FramePart::Shadows => "shadows",
            FramePart::Lighting => "lighting",
        }
    }
}

/// The camera's world → clip, position and vertical field of view (what the histories
/// reproject with).
fn camera_of(
    scene: &manyshadows_scene::Scene,
    s: &crate::settings::RenderSettings,
) -> (glam::Mat4, glam::Vec3, f32) {
    let cam = scene.camera;
    let aspect = s.width as f32 / s.height as f32;
    (
        cam.projection(aspect) * cam.view(),
        cam.position,
        cam.fov_y_deg,
    )
}

/// Submits the frame recorded so far and starts a new encoder at a part's end.
type Boundary<'a> = dyn FnMut(&mut wgpu::CommandEncoder, FramePart) -> Result<(), RenderError> + 'a;
