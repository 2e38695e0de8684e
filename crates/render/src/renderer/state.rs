//! The renderer: creation, the frame's state and its setters, and the frame loop.

// `std::time::Instant` panics in a browser; web-time is std's on native targets.
use super::uniforms::{frame_uniforms, lights_or_placeholder};
use crate::shading::look::ShadingConsts;
use web_time::Instant;

use manyshadows_scene::{Camera, Light, Scene, SceneError};
use wgpu::util::DeviceExt;

use super::probes::ProbeFrame;
use crate::error::RenderError;
use crate::frame::clusters::{LightClusters, LightLoop};
use crate::frame::gbuffer::{GBuffer, GBufferViews};
use crate::frame::visibility_mask::{SoftVisibility, VisibilityMask};
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, GpuTimes, Stage};
use crate::gpu::types::FrameUniforms;
use crate::gpu_scene::instances::GpuScene;
use crate::report::{Frame, FrameTimings, SubmittedFrame};
use crate::settings::RenderSettings;
use crate::shading::lighting::{LightingInputs, LightingPass};
use crate::shading::visibility::VisibilityPass;
use crate::shadows::plan::DEFAULT_MAX_ATLAS_SIZE;
use crate::shadows::source::{ShadowSource, ShadowStats, SourceInputs};
use crate::shadows::vsm::plan::VirtualStats;

/// Timestamp copies of submitted frames on their way back: mapped asynchronously, decoded
/// when the GPU has finished them, never waited for.
#[derive(Default)]
struct TimingsInFlight {
    /// Oldest first.
    pending: std::collections::VecDeque<StagedTimes>,
    /// Unmapped staging buffers to reuse.
    free: Vec<wgpu::Buffer>,
}

/// One frame's timestamps on their way back: the staging buffer, the spans to decode it with,
/// and the state of its mapping (`MAP_PENDING`, `MAP_DONE`, `MAP_FAILED`).
type StagedTimes = (
    wgpu::Buffer,
    Vec<(crate::gpu::timing::Stage, crate::gpu::timing::Span)>,
    std::sync::Arc<std::sync::atomic::AtomicU8>,
);

/// Most frames whose timings may be in flight; a frame beyond them is not timed.
const MAX_TIMINGS_IN_FLIGHT: usize = 3;
const MAP_PENDING: u8 = 0;
const MAP_DONE: u8 = 1;
const MAP_FAILED: u8 = 2;

/// A scene uploaded and ready to render frames.
pub struct Renderer {
    /// Shared so a frame can hold it while it mutates the renderer (one reference-count
    /// increment per frame, no copy of the adapter's description).
    pub(super) ctx: std::sync::Arc<GpuContext>,
    pub(super) settings: RenderSettings,
    pub(super) scene: GpuScene,
    /// Where the frame's shadows come from (atlas, page pool or visibility mask).
    pub(super) source: Box<dyn ShadowSource>,
    pub(super) frame_buffer: wgpu::Buffer,
    pub(super) lights: wgpu::Buffer,
    pub(super) gbuffer: GBuffer,
    pub(super) lighting: LightingPass,
    pub(super) clusters: LightClusters,
    /// The visibility pass, when asked for and the source's output is not the mask itself.
    pub(super) visibility: Option<VisibilityPass>,
    /// Copies frames into callers' textures ([`Renderer::render_to`]); built on first use.
    pub(super) blit: Option<crate::shading::blit::Blit>,
    /// GPU times of frames drawn by `render_to`, read back without waiting (oldest first).
    timings: TimingsInFlight,
    pub(super) timer: GpuTimer,
    /// The frame's state (camera, lights, instance transforms) as last set.
    pub(super) current: Scene,
    /// True when `current` changed since the GPU state was last derived from it.
    pub(super) dirty: bool,
    /// The denoiser of sampled shadow rays (`RayOptions::denoise`).
    pub(super) denoiser: Option<crate::shading::denoise::Denoiser>,
    /// The reservoirs of reused light samples (`RayOptions::reuse`).
    pub(super) reuse: Option<crate::shading::reuse::Reuse>,
    /// Frames the denoiser or the reuse has seen (their rays' random numbers differ by it).
    pub(super) frames_denoised: u32,
    /// A light changed since the last prepared frame (the denoiser's history follows it).
    pub(super) lights_changed: bool,
    /// The reflection probes' faces and passes (scenes with probes).
    pub(super) probes: Option<ProbeFrame>,
    /// Something the probes see changed since their faces were drawn.
    pub(super) probes_stale: bool,
}

impl Renderer {
    /// Validates the scene and settings, uploads the scene, plans and creates the shadow atlas
    /// and builds every pipeline.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Self, RenderError> {
        settings.validate()?;
        if settings.shadow_budget.is_some()
            && settings.technique.info().fills != crate::error::Fills::Atlas
        {
            return Err(RenderError::NotImplemented {
                what: "a shadow budget with a technique that fills no atlas",
                instead: "use an atlas technique, or caching alone (virtual maps redraw only \
                          the pages under a change)",
            });
        }
        scene.validate()?;
        let info = settings.technique.info();
        // A mask holds the camera's pixels only: nothing to light a probe's faces with. The
        // probes are left out of everything (the shadow plan gives every light a map only
        // for probes that are drawn).
        let without_probes;
        let scene = if info.fills == crate::error::Fills::Mask && !scene.probes.is_empty() {
            log::warn!(
                "technique {} draws no reflection probes (its shadows are a mask of the camera's \
                 pixels): the scene's {} probes are left out",
                info.technique,
                scene.probes.len()
            );
            without_probes = Scene {
                probes: Vec::new(),
                ..scene.clone()
            };
            &without_probes
        } else {
            scene
        };
        if !info.soft_shadows && scene.lights.iter().any(|l| l.size > 0.0) {
            log::warn!(
                "technique {} renders hard shadows: the lights' sizes do not soften them",
                info.technique
            );
        }
        let limits = ctx.limits();
        let max_dim = limits.max_texture_dimension_2d;
        if settings.width > max_dim || settings.height > max_dim {
            return Err(RenderError::ResolutionTooLarge {
                width: settings.width,
                height: settings.height,
                max: max_dim,
            });
        }
        if let Some(stereo) = settings.stereo {
            if let Some(feature) = Self::stereo_unmet(ctx, stereo.passes) {
                return Err(RenderError::missing_feature(
                    ctx,
                    format!("stereo drawn {}", stereo.passes),
                    feature,
                    "draw the eyes per-eye, or layered where the adapter has CLIP_DISTANCES",
                ));
            }
        }
        let max_atlas = settings
            .max_atlas_size
            .unwrap_or(DEFAULT_MAX_ATLAS_SIZE)
            .min(max_dim);
        ctx.scoped("creating the renderer", || {
            let gpu_scene = GpuScene::new(ctx, scene)?;
            let mut source = crate::registry::create(ctx, scene, &gpu_scene, &settings, max_atlas)?;
            let light_data = lights_or_placeholder(source.light_data(scene));
            let lights = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("scene.lights"),
                    contents: bytemuck::cast_slice(&light_data),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                });
            // Written once the source is bound and its output (the shadow texture's side) known.
            let frame_buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame.uniforms"),
                size: std::mem::size_of::<FrameUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let gbuffer = GBuffer::new(
                ctx,
                &gpu_scene,
                &frame_buffer,
                (settings.width, settings.height),
                settings
                    .stereo
                    .map_or(GBufferViews::Mono, |s| GBufferViews::Stereo(s.passes)),
            );
            let mut clusters = LightClusters::new(
                ctx,
                (settings.width, settings.height),
                scene.lights.len(),
                settings.clusters,
                settings.light_loop == LightLoop::Clustered,
                settings.stereo,
            )?;
            clusters.update(ctx, scene)?;
            clusters.bind(ctx, &frame_buffer, &lights, &gbuffer);
            source.bind(
                ctx,
                &SourceInputs {
                    scene,
                    frame: &frame_buffer,
                    lights: &lights,
                    gbuffer: &gbuffer,
                    clusters: &clusters,
                    instances: &gpu_scene.instances,
                },
            )?;
            let shadow_side = (source.output().depth_side, source.output().max_penumbra);
            ctx.queue.write_buffer(
                &frame_buffer,
                0,
                bytemuck::bytes_of(&frame_uniforms(scene, &settings, shadow_side)),
            );
            let denoiser = settings
                .rays
                .denoise
                .then(|| {
                    crate::shading::denoise::Denoiser::new(
                        ctx,
                        &gbuffer,
                        settings.width,
                        settings.height,
                        settings.rays.light_samples > 0,
                        source.light_data(scene),
                    )
                })
                .transpose()?;
            let reuse = settings
                .rays
                .reuse
                .then(|| {
                    crate::shading::reuse::Reuse::new(
                        ctx,
                        settings.width,
                        settings.height,
                        settings.rays.light_samples,
                        settings.rays.spatial
                            != crate::shadows::raytraced::accel::SpatialReuse::Off,
                    )
                })
                .transpose()?;
            let look_consts = settings.look.resolve(scene).consts();
            let mut probes = if scene.probes.is_empty() {
                None
            } else {
                Some(ProbeFrame::new(
                    ctx,
                    scene,
                    &gpu_scene,
                    &lights,
                    &*source,
                    look_consts,
                    settings.probe_passes,
                )?)
            };
            if let Some(p) = &mut probes {
                let frame = frame_uniforms(scene, &settings, shadow_side);
                p.update(ctx, scene, &gpu_scene, (&lights, &*source), &frame, true)?;
            }
            let inputs = LightingInputs {
                frame: &frame_buffer,
                lights: &lights,
                materials: &gpu_scene.materials,
                gbuffer: &gbuffer,
                clusters: &clusters,
                shadows: source.output(),
                denoise: denoiser.as_ref().map(|d| &d.buffers),
                reuse: reuse.as_ref().map(|r| &r.buffers),
                probes: probes.as_ref().map(|p| &p.maps),
            };
            let lighting = LightingPass::new(
                ctx,
                &inputs,
                (settings.width, settings.height),
                &ShadingConsts {
                    emission_texture: gbuffer.emission.is_some(),
                    denoise: denoiser.is_some(),
                    reuse: reuse.is_some(),
                    spatial: if reuse.is_some() {
                        settings.rays.spatial.code()
                    } else {
                        0
                    },
                    probes: probes.is_some(),
                    ..look_consts
                },
            );
            let visibility = visibility_pass(ctx, &settings, scene, &*source)?;
            Ok(Self {
                // In a browser wgpu's handles are not Send; the Arc only shares, never crosses
                // threads there.
                #[allow(clippy::arc_with_non_send_sync)]
                ctx: std::sync::Arc::new(ctx.clone()),
                settings,
                scene: gpu_scene,
                source,
                frame_buffer,
                lights,
                gbuffer,
                lighting,
                denoiser,
                reuse,
                frames_denoised: 0,
                lights_changed: false,
                probes,
                probes_stale: false,
                clusters,
                visibility,
                blit: None,
                timings: TimingsInFlight::default(),
                timer: GpuTimer::new(ctx),
                current: scene.clone(),
                dirty: false,
            })
        })
    }

    /// Moves the camera before the next frame. The next [`Renderer::render`] re-plans the
    /// shadows (cascades follow the view; lights that leave the screen give up their maps).
    pub fn set_camera(&mut self, camera: Camera) -> Result<(), RenderError> {
        camera.validate()?;
        self.current.camera = camera;
        self.dirty = true;
        // Probes see the camera's shadows where those follow the camera: cascades, and
        // virtual pages.
        self.probes_stale |= self.settings.technique.info().fills == crate::error::Fills::Pages
            || self
                .current
                .lights
                .iter()
                .any(|l| matches!(l.kind, manyshadows_scene::LightKind::Directional { .. }));
        Ok(())
    }

    /// Replaces light `index` before the next frame; an index past the last light is an
    /// error (use [`Renderer::set_lights`] to change the number of lights).
    pub fn set_light(&mut self, index: usize, light: Light) -> Result<(), RenderError> {
        let count = self.current.lights.len();
        let slot = self
            .current
            .lights
            .get_mut(index)
            .ok_or_else(|| SceneError::InvalidLight {
                index,
                reason: format!("no such light (the scene has {count})"),
            })?;
        light
            .validate()
            .map_err(|reason| SceneError::InvalidLight { index, reason })?;
        *slot = light;
        self.dirty = true;
        self.probes_stale = true;
        self.lights_changed = true;
        Ok(())
    }

    /// Replaces every light (any number, zero included) before the next frame.
    pub fn set_lights(&mut self, lights: Vec<Light>) -> Result<(), RenderError> {
        for (index, light) in lights.iter().enumerate() {
            light
                .validate()
                .map_err(|reason| SceneError::InvalidLight { index, reason })?;
        }
        self.current.lights = lights;
        self.dirty = true;
        self.probes_stale = true;
        self.lights_changed = true;
        Ok(())
    }

    /// Moves instance `instance` (a new model matrix) before the next frame; with
    /// [`RenderSettings::cache_shadows`] only the views that see it are redrawn. The next
    /// frame re-checks which casters may be back-face culled for which lights (a caster moved
    /// over a light may no longer be). An unknown instance or a singular or non-finite matrix
    /// is an error.
    pub fn set_instance_transform(
        &mut self,
        instance: usize,
        transform: glam::Mat4,
    ) -> Result<(), RenderError> {
        let count = self.current.instances.len();
        let bad = |reason: String| SceneError::InvalidInstance {
            index: instance,
            reason,
        };
        let Some(old) = self.scene.draws.get(instance).copied() else {
            return Err(bad(format!("no such instance (the scene has {count})")).into());
        };
        if !transform.is_finite() || transform.determinant().abs() < 1e-12 {
            return Err(bad("transform must be finite and invertible".into()).into());
        }
        self.scene
            .set_instance_transform(&self.ctx.queue, instance, transform);
        self.current.instances[instance].transform = transform;
        if old.casts_shadows {
            let new = self.scene.draws[instance].sphere;
            self.source.note_moved(old.sphere, new);
        }
        self.dirty = true;
        self.probes_stale = true;
        Ok(())
    }

    /// The side of the texture shadows are read from and the widest penumbra its lookup
    /// filters at one level (the frame uniforms').
    pub(super) fn shadow_side(&self) -> (u32, f32) {
        let out = self.source.output();
        (out.depth_side, out.max_penumbra)
    }

    /// Derives this frame's GPU state from [`Renderer::scene`] after a change: a new shadow
    /// plan, re-decided caster culling, and the atlas, light, frame and cluster buffers
    /// rewritten in place (replaced only when they must grow or the atlas side changed).
    fn prepare(&mut self) -> Result<(), RenderError> {
        if !self.dirty {
            return Ok(());
        }
        let ctx = &*self.ctx.clone();
        let scene = &self.current;
        let settings = &self.settings;
        self.source.update(ctx, scene)?;
        let records = self.source.light_data(scene);
        let count = records.len();
        let mut light_data = lights_or_placeholder(records);
        if let Some(d) = self.denoiser.as_mut().filter(|_| self.lights_changed) {
            // The records of the lights that changed may follow the frame's for the
            // denoiser's correction of its history.
            d.follow_lights(&mut light_data, count);
        }
        let bytes: &[u8] = bytemuck::cast_slice(&light_data);
        crate::gpu::buffers::grow_buffer(ctx, &mut self.lights, bytes.len() as u64, "lights")?;
        ctx.queue.write_buffer(&self.lights, 0, bytes);
        self.clusters.update(ctx, scene)?;
        self.clusters
            .bind(ctx, &self.frame_buffer, &self.lights, &self.gbuffer);
        self.source.bind(
            ctx,
            &SourceInputs {
                scene,
                frame: &self.frame_buffer,
                lights: &self.lights,
                gbuffer: &self.gbuffer,
                clusters: &self.clusters,
                instances: &self.scene.instances,
            },
        )?;
        let frame = frame_uniforms(scene, settings, self.shadow_side());
        ctx.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&frame));
        if let Some(p) = &mut self.probes {
            let redraw = std::mem::take(&mut self.probes_stale);
            let sources = (&self.lights, &*self.source);
            p.update(ctx, scene, &self.scene, sources, &frame, redraw)?;
        }
        self.lighting.rebind(
            ctx,
            &LightingInputs {
                frame: &self.frame_buffer,
                lights: &self.lights,
                materials: &self.scene.materials,
                gbuffer: &self.gbuffer,
                clusters: &self.clusters,
                shadows: self.source.output(),
                denoise: self.denoiser.as_ref().map(|d| &d.buffers),
                reuse: self.reuse.as_ref().map(|r| &r.buffers),
                probes: self.probes.as_ref().map(|p| &p.maps),
            },
        );
        let lights = scene.lights.len() as u32;
        if self
            .visibility
            .as_ref()
            .is_some_and(|v| v.lights() != lights)
        {
            self.visibility = visibility_pass(ctx, settings, scene, &*self.source)?;
        }
        self.dirty = false;
        self.lights_changed = false;
        Ok(())
    }

    /// Records one frame up to the lit image (G-buffer, clusters, shadows, lighting) after
    /// deriving the GPU state from any change; returns the shadow work counters.
    fn record_frame(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        mut boundary: Option<&mut Boundary<'_>>,
    ) -> Result<ShadowStats, RenderError> {
        self.prepare()?;
        self.timer.reset();
        let span = self.timer.span(Stage::GBuffer);
        self.gbuffer.record(encoder, &self.scene, &self.timer, span);
        if self.clusters.enabled() {
            let span = self.timer.span(Stage::Clusters);
            self.clusters.record(encoder, &self.timer, span);
        }
        if let Some(r) = &mut self.reuse {
            let cam = self.current.camera;
            let aspect = self.settings.width as f32 / self.settings.height as f32;
            r.prepare(
                ctx,
                (
                    cam.projection(aspect) * cam.view(),
                    cam.position,
                    cam.fov_y_deg,
                ),
                self.current.lights.len(),
            );
        }
        if self.denoiser.is_some() || self.reuse.is_some() {
            // New random numbers for the rays every frame (FrameUniforms::modes.y).
            self.frames_denoised = self.frames_denoised.wrapping_add(1);
            // modes.zw: the denoiser's correction for changed lights, this frame only.
            let [first, counts] = self.denoiser.as_ref().map_or([0, 0], |d| d.light_fix());
            ctx.queue.write_buffer(
                &self.frame_buffer,
                (std::mem::offset_of!(FrameUniforms, modes) + 4) as u64,
                bytemuck::cast_slice(&[self.frames_denoised, first, counts]),
            );
        }
        if let Some(b) = boundary.as_deref_mut() {
            b(encoder, FramePart::Camera)?;
        }
        let shadow_stats = self
            .source
            .record(ctx, &self.scene, encoder, &mut self.timer);
        if let Some(b) = boundary {
            b(encoder, FramePart::Shadows)?;
        }
        if let Some(p) = self.probes.as_mut().filter(|p| p.dirty) {
            let span = self.timer.span(Stage::Probes);
            p.record(encoder, &self.scene, &self.timer, span);
        } else if let Some(p) = &mut self.probes {
            p.faces_drawn = 0;
        }
        let span = self.timer.span(Stage::Lighting);
        self.lighting.record(encoder, &self.timer, span);
        if let Some(d) = &mut self.denoiser {
            let cam = self.current.camera;
            let aspect = self.settings.width as f32 / self.settings.height as f32;
            let view_proj = cam.projection(aspect) * cam.view();
            let span = self.timer.span(Stage::Denoise);
            d.record(
                ctx,
                encoder,
                (view_proj, cam.position, cam.fov_y_deg),
                &self.timer,
                span,
            );
            self.lighting.record_composite(encoder, &self.timer, span);
        }
        Ok(shadow_stats)
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
    /// With [`Technique::IRREGULAR`](crate::error::Technique::IRREGULAR) this waits for the
    /// frame's overflow check (an overflowed frame is an error, never a wrong image).
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
            self.source.finish(ctx)?;
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
            let clusters = if self.clusters.enabled() {
                Some(self.clusters.read_stats(ctx)?)
            } else {
                None
            };
            // A source whose frame went wrong (irregular's full node pool) makes it an error,
            // never a wrong image.
            self.source.finish(ctx)?;
            let virtual_maps = self
                .source
                .technique_stats(ctx)?
                .and_then(|s| s.downcast::<VirtualStats>().ok())
                .map(|s| *s);
            let (visibility, soft_visibility) = match &self.visibility {
                Some(pass) => {
                    let span = self.timer.span(Stage::Visibility);
                    let inputs = LightingInputs {
                        frame: &self.frame_buffer,
                        lights: &self.lights,
                        materials: &self.scene.materials,
                        gbuffer: &self.gbuffer,
                        clusters: &self.clusters,
                        shadows: self.source.output(),
                        denoise: None,
                        reuse: None,
                        probes: None,
                    };
                    let (mask, soft) = pass.run(ctx, &inputs, &self.timer, span)?;
                    (Some(mask), soft)
                }
                // The source's output is the mask itself: a hard answer, also as soft
                // visibility.
                None if self.settings.visibility || self.settings.soft_visibility => {
                    let mask = self.source.read_mask(ctx)?;
                    let soft = mask
                        .as_ref()
                        .filter(|_| self.settings.soft_visibility)
                        .map(SoftVisibility::from_mask);
                    (mask, soft)
                }
                None => (None, None),
            };
            let gpu_ms = self.resolve_timings(ctx)?;
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
                probes: self.probes.as_ref().map(|p| p.stats()),
            })
        })
    }
}

/// The visibility pass of `scene`'s lights when the settings ask for the mask and the source
/// does not produce it itself.
fn visibility_pass(
    ctx: &GpuContext,
    settings: &RenderSettings,
    scene: &Scene,
    source: &dyn ShadowSource,
) -> Result<Option<VisibilityPass>, RenderError> {
    let shadows = source.output();
    if !(settings.visibility || settings.soft_visibility) || shadows.mask.is_some() {
        return Ok(None);
    }
    VisibilityPass::new(
        ctx,
        settings.width,
        settings.height,
        scene.lights.len() as u32,
        &shadows,
        settings.soft_visibility,
    )
    .map(Some)
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

/// Submits the frame recorded so far and starts a new encoder at a part's end.
type Boundary<'a> = dyn FnMut(&mut wgpu::CommandEncoder, FramePart) -> Result<(), RenderError> + 'a;
