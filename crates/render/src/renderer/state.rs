//! The renderer: creation, the frame's state and its setters, and deriving the GPU state
//! from their changes (the frames themselves: `frame_loop`).

use super::uniforms::{frame_uniforms, lights_or_placeholder};
use crate::shading::look::ShadingConsts;

use manyshadows_scene::{Camera, Light, Scene, SceneError};
use wgpu::util::DeviceExt;

use super::probes::ProbeFrame;
use crate::error::RenderError;
use crate::frame::clusters::{LightClusters, LightLoop};
use crate::frame::gbuffer::{GBuffer, GBufferViews};
use crate::gpu::context::GpuContext;
use crate::gpu::timing::GpuTimer;
use crate::gpu::types::FrameUniforms;
use crate::gpu_scene::instances::GpuScene;
use crate::settings::RenderSettings;
use crate::shading::lighting::{LightingInputs, LightingPass};
use crate::shading::visibility::VisibilityPass;
use crate::shadows::plan::DEFAULT_MAX_ATLAS_SIZE;
use crate::shadows::source::{ShadowSource, SourceInputs};

/// Timestamp copies of submitted frames on their way back: mapped asynchronously, decoded
/// when the GPU has finished them, never waited for.
#[derive(Default)]
pub(super) struct TimingsInFlight {
    /// Oldest first.
    pub(super) pending: std::collections::VecDeque<StagedTimes>,
    /// Unmapped staging buffers to reuse.
    pub(super) free: Vec<wgpu::Buffer>,
}

/// One frame's timestamps on their way back: the staging buffer, the spans to decode it with,
/// and the state of its mapping (`MAP_PENDING`, `MAP_DONE`, `MAP_FAILED`).
type StagedTimes = (
    wgpu::Buffer,
    Vec<(crate::gpu::timing::Stage, crate::gpu::timing::Span)>,
    std::sync::Arc<std::sync::atomic::AtomicU8>,
);

/// Most frames whose timings may be in flight; a frame beyond them is not timed.
pub(super) const MAX_TIMINGS_IN_FLIGHT: usize = 3;
pub(super) const MAP_PENDING: u8 = 0;
pub(super) const MAP_DONE: u8 = 1;
pub(super) const MAP_FAILED: u8 = 2;

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
    pub(super) timings: TimingsInFlight,
    pub(super) timer: GpuTimer,
    /// The frame's state (camera, lights, instance transforms) as last set.
    pub(super) current: Scene,
    /// True when `current` changed since the GPU state was last derived from it.
    pub(super) dirty: bool,
    /// The denoiser of sampled shadow rays (`RayOptions::denoise`).
    pub(super) denoiser: Option<crate::shading::denoise::Denoiser>,
    /// The reservoirs of reused light samples (`RayOptions::reuse`).
    pub(super) reuse: Option<crate::shading::reuse::Reuse>,
    /// Moving instances' motion between frames, which the denoiser's and the reservoirs'
    /// histories follow (only with either).
    pub(super) motion: Option<crate::frame::motion::InstanceMotion>,
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
            // Histories of surface points (the denoiser's, the reservoirs') follow moving
            // instances by the instance each pixel sees (stereo refuses both).
            let histories = settings.rays.denoise || settings.rays.reuse;
            let mono = if histories {
                GBufferViews::MonoMoving
            } else {
                GBufferViews::Mono
            };
            let gbuffer = GBuffer::new(
                ctx,
                &gpu_scene,
                &frame_buffer,
                (settings.width, settings.height),
                settings
                    .stereo
                    .map_or(mono, |s| GBufferViews::Stereo(s.passes)),
            );
            let motion = histories
                .then(|| crate::frame::motion::InstanceMotion::new(ctx, gpu_scene.draws.len()));
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
                        motion.as_ref().expect("made with the denoiser"),
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
                        (&gbuffer, motion.as_ref().expect("made with the reuse")),
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
                motion,
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
        if let Some(m) = &mut self.motion {
            m.note(instance, self.current.instances[instance].transform);
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
    pub(super) fn prepare(&mut self) -> Result<(), RenderError> {
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
