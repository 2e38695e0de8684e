//! The renderer: creation, the frame's state and its setters, and deriving the GPU state
//! from their changes (the frames themselves: `frame_loop`).

use manyshadows_scene::{Camera, Light, Scene, SceneError};

use super::parts::FrameParts;
use super::uniforms::{frame_uniforms, lights_or_placeholder};
use crate::error::RenderError;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::GpuTimer;
use crate::settings::RenderSettings;
use crate::shading::lighting::LightingPass;
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
    /// Everything the frame's passes read (`parts.rs`).
    pub(super) parts: FrameParts,
    pub(super) lighting: LightingPass,
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
    /// Frames the denoiser or the reuse has seen (their rays' random numbers differ by it).
    pub(super) frames_denoised: u32,
    /// Frames rendered and read back (`render`), which the frames' reports count.
    pub(super) frames_read: u32,
    /// A light changed since the last prepared frame (the denoiser's history follows it).
    pub(super) lights_changed: bool,
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
        let info = settings.technique.info();
        if settings.shadow_budget.is_some() && !info.takes_shadow_budget() {
            return Err(RenderError::NotImplemented {
                what: "a shadow budget with a technique that fills no atlas",
                instead: "use an atlas technique, or caching alone (virtual maps redraw only \
                          the pages under a change)",
            });
        }
        scene.validate()?;
        // Shadows of the camera's pixels only: nothing to light a probe's faces with. The
        // probes are left out of everything (the shadow plan gives every light a map only
        // for probes that are drawn).
        let without_probes;
        let scene = if info.camera_pixels_only && !scene.probes.is_empty() {
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
            let parts = FrameParts::new(ctx, scene, &settings, max_atlas)?;
            crate::shading::lighting::check_limits(ctx, &parts.lighting())?;
            let lighting = LightingPass::new(
                ctx,
                &parts.lighting(),
                (settings.width, settings.height),
                &parts.shading_consts(scene, &settings),
            );
            let mut visibility = visibility_pass(ctx, &settings, scene, &*parts.source)?;
            if let Some(v) = &mut visibility {
                v.bind(ctx, &parts.frame_inputs());
            }
            Ok(Self {
                // In a browser wgpu's handles are not Send; the Arc only shares, never crosses
                // threads there.
                #[allow(clippy::arc_with_non_send_sync)]
                ctx: std::sync::Arc::new(ctx.clone()),
                settings,
                parts,
                lighting,
                visibility,
                frames_denoised: 0,
                frames_read: 0,
                lights_changed: false,
                probes_stale: false,
                blit: None,
                timings: TimingsInFlight::default(),
                timer: GpuTimer::new(ctx),
                current: scene.clone(),
                dirty: false,
            })
        })
    }

    /// Test only (feature `test-hooks`): rebuilds the lighting pass with sized lights' soft
    /// shadows compiled out, so a test can check that lights of size 0 give the frame the
    /// pass gives without them, byte for byte, in one run.
    #[cfg(feature = "test-hooks")]
    pub fn compile_out_soft_shadows(&mut self) {
        let consts = crate::shading::look::ShadingConsts {
            soft_shadows: false,
            ..self.parts.shading_consts(&self.current, &self.settings)
        };
        self.lighting = LightingPass::new(
            &self.ctx,
            &self.parts.lighting(),
            (self.settings.width, self.settings.height),
            &consts,
        );
    }

    /// Moves the camera before the next frame. The next [`Renderer::render`] re-plans the
    /// shadows (cascades follow the view; lights that leave the screen give up their maps).
    pub fn set_camera(&mut self, camera: Camera) -> Result<(), RenderError> {
        camera.validate()?;
        self.current.camera = camera;
        self.dirty = true;
        // Probes see the camera's shadows where those follow the camera: cascades, and
        // a technique's own (virtual pages).
        self.probes_stale |= self.settings.technique.info().follows_camera
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
        let Some(old) = self.parts.scene.draws.get(instance).copied() else {
            return Err(bad(format!("no such instance (the scene has {count})")).into());
        };
        if !transform.is_finite() || transform.determinant().abs() < 1e-12 {
            return Err(bad("transform must be finite and invertible".into()).into());
        }
        if let Some(m) = &mut self.parts.motion {
            m.note(instance, self.current.instances[instance].transform);
        }
        self.parts
            .scene
            .set_instance_transform(&self.ctx.queue, instance, transform);
        self.current.instances[instance].transform = transform;
        if old.casts_shadows {
            let new = self.parts.scene.draws[instance].sphere;
            self.parts.source.note_moved(old.sphere, new);
            if let Some(d) = moved_casters_denoiser(&mut self.parts, &self.settings) {
                d.note_moved(old.sphere, new);
            }
        }
        self.dirty = true;
        self.probes_stale = true;
        Ok(())
    }

    /// Gives mesh `mesh` new vertices and normals, as many as it has (a skinned mesh bent:
    /// [`Scene::set_time`](manyshadows_scene::Scene::set_time) computes them, or
    /// `Animations::bent`). Every instance drawing it gets a bounding sphere around the new
    /// vertices, and what its old and new spheres reach is redrawn (kept atlas views, virtual
    /// pages, probe faces); ray tracing builds the mesh's structure again. Errors: no such mesh,
    /// another number of vertices or normals, a value that is not finite.
    pub fn set_mesh_vertices(
        &mut self,
        mesh: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), RenderError> {
        let count = self.current.meshes.len();
        let Some(m) = self.current.meshes.get(mesh) else {
            return Err(SceneError::InvalidMesh {
                mesh: format!("mesh {mesh}"),
                reason: format!("no such mesh (the scene has {count})"),
            }
            .into());
        };
        let bad = |reason: String| SceneError::InvalidMesh {
            mesh: m.name.clone(),
            reason,
        };
        if positions.len() != m.positions.len() || normals.len() != m.positions.len() {
            return Err(bad(format!(
                "{} positions and {} normals for a mesh of {} vertices (a mesh keeps its \
                 vertex count)",
                positions.len(),
                normals.len(),
                m.positions.len()
            ))
            .into());
        }
        if let Some(v) = positions.iter().chain(normals).position(|p| !p.is_finite()) {
            return Err(bad(format!(
                "vertex {} has a position or normal that is not finite",
                v % positions.len().max(1)
            ))
            .into());
        }
        let instances = &self.current.instances;
        let moved =
            self.parts
                .scene
                .set_mesh_vertices(&self.ctx.queue, mesh, positions, normals, |k| {
                    instances
                        .get(k)
                        .map_or(glam::Mat4::IDENTITY, |i| i.transform)
                });
        for (k, old, new) in moved {
            if self.parts.scene.draws[k].casts_shadows {
                self.parts.source.note_moved(old, new);
                if let Some(d) = moved_casters_denoiser(&mut self.parts, &self.settings) {
                    let world = self
                        .current
                        .instances
                        .get(k)
                        .map_or(glam::Mat4::IDENTITY, |i| i.transform);
                    d.note_bent(&self.current.meshes[mesh].positions, positions, world);
                }
            }
        }
        self.parts.source.note_deformed(&self.ctx, mesh, positions);
        self.current.animations.bent_bounds.remove(&mesh);
        let m = &mut self.current.meshes[mesh];
        m.positions = positions.to_vec();
        m.normals = normals.to_vec();
        self.dirty = true;
        self.probes_stale = true;
        Ok(())
    }

    /// Poses the scene's animations at `t` seconds (`playing`: which clips; wrapped as
    /// `Animations::wrap` says): every instance an animated node moves gets its transform
    /// ([`Renderer::set_instance_transform`]), and every skinned or morphed mesh is bent
    /// ([`Renderer::set_bending`]). Errors: a pose that is not finite.
    pub fn set_time(
        &mut self,
        playing: manyshadows_scene::animation::Playing,
        t: f32,
    ) -> Result<(), RenderError> {
        let anim = &self.current.animations;
        let pose = anim.pose(playing, t);
        let bending =
            (!anim.skins.is_empty() || !anim.morphs.is_empty()).then(|| anim.bending(playing, t));
        for (k, m) in pose {
            self.set_instance_transform(k, m)?;
        }
        match bending {
            Some(b) => self.set_bending(&b),
            None => Ok(()),
        }
    }

    /// Bends every skinned and morphed mesh of the scene's animations as `bending` says (its
    /// nodes' world transforms and morph weights: `Animations::bending`). With
    /// [`Deform::Gpu`](crate::settings::Deform) (the default) the CPU evaluates only the joints'
    /// matrices and the bounds drawn from them, and a compute pass bends the vertices before
    /// the next frame draws (gpu_scene/deform.rs); the meshes' vertices in
    /// [`Renderer::scene`] stay as loaded. With `Deform::Cpu`, or for a skin that pass cannot
    /// bound (weights not convex), the CPU bends them ([`Renderer::set_mesh_vertices`]).
    /// Either way, what the meshes' old and new bounds reach is redrawn and the histories
    /// follow. Errors: a matrix or weight that is not finite.
    pub fn set_bending(
        &mut self,
        bending: &manyshadows_scene::animation::Bending,
    ) -> Result<(), RenderError> {
        let finite = bending.worlds.iter().all(|m| m.is_finite())
            && bending
                .weights
                .iter()
                .all(|(_, w)| w.iter().all(|x| x.is_finite()));
        if !finite {
            return Err(SceneError::InvalidMesh {
                mesh: "the animation's pose".into(),
                reason: "a node's transform or a morph weight is not finite".into(),
            }
            .into());
        }
        if self.settings.deform == crate::settings::Deform::Gpu && self.parts.deformer.is_none() {
            self.parts.deformer = Some(crate::gpu_scene::deform::Deformer::new(
                &self.ctx,
                &self.current,
                &self.parts.scene,
            ));
        }
        let deformer = self
            .parts
            .deformer
            .as_mut()
            .and_then(Option::as_mut)
            .filter(|_| self.settings.deform == crate::settings::Deform::Gpu);
        let on_cpu = |mesh: usize| deformer.as_ref().is_none_or(|d| !d.bends(mesh));
        let cpu: Vec<_> = self.current.animations.bend_where(bending, on_cpu);
        let Some(deformer) = deformer else {
            for (mesh, positions, normals) in cpu {
                self.set_mesh_vertices(mesh, &positions, &normals)?;
            }
            return Ok(());
        };
        let bent = deformer.pose(&self.ctx.queue, &self.current.animations, bending);
        let ranges: Vec<(usize, u64, u64)> = deformer.ranges().collect();
        let instances = &self.current.instances;
        let transform = |k: usize| {
            instances
                .get(k)
                .map_or(glam::Mat4::IDENTITY, |i| i.transform)
        };
        for b in bent {
            let (lo, hi) = b.parts.iter().map(|(_, now)| now).fold(
                (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
                |(lo, hi), &(c, r)| (lo.min(c - r), hi.max(c + r)),
            );
            if lo.cmple(hi).all() {
                self.current.animations.bent_bounds.insert(b.mesh, (lo, hi));
            }
            let moved = self
                .parts
                .scene
                .set_mesh_sphere(b.mesh, b.sphere, transform);
            for (k, old, new) in moved {
                if !self.parts.scene.draws[k].casts_shadows {
                    continue;
                }
                self.parts.source.note_moved(old, new);
                if let Some(d) = moved_casters_denoiser(&mut self.parts, &self.settings) {
                    let world = transform(k);
                    let scale = crate::gpu_scene::deform::max_stretch(world);
                    let to_world =
                        |(c, r): (glam::Vec3, f32)| (world.transform_point3(c), r * scale);
                    for &(was, is) in b.parts.iter().filter(|(was, is)| was != is) {
                        d.note_moved(to_world(was), to_world(is));
                    }
                }
            }
            if let Some(&(_, at, len)) = ranges.iter().find(|r| r.0 == b.mesh) {
                if let Some(l) = &mut self.parts.scene.last_positions {
                    l.note_gpu((at, len));
                }
                self.parts.source.note_deformed_on_gpu(b.mesh, (at, len));
            }
        }
        for (mesh, positions, normals) in cpu {
            self.set_mesh_vertices(mesh, &positions, &normals)?;
        }
        self.dirty = true;
        self.probes_stale = true;
        Ok(())
    }

    /// The side of the texture shadows are read from and the widest penumbra its lookup
    /// filters at one level (the frame uniforms').
    pub(super) fn shadow_side(&self) -> (u32, f32) {
        let out = self.parts.source.output();
        (out.depth_side, out.max_penumbra)
    }

    /// Derives this frame's GPU state from [`Renderer::scene`] after a change: a new shadow
    /// plan, re-decided caster culling, the frame's uniforms, and the atlas, light and
    /// cluster buffers rewritten in place (replaced only when they must grow or the atlas
    /// side changed); every pass is bound to what changed.
    pub(super) fn prepare(&mut self) -> Result<(), RenderError> {
        if !self.dirty {
            return Ok(());
        }
        let ctx = &*self.ctx.clone();
        let scene = &self.current;
        let settings = &self.settings;
        let parts = &mut self.parts;
        parts.source.update(ctx, scene)?;
        let records = parts.source.light_data(scene);
        let count = records.len();
        let mut light_data = lights_or_placeholder(records);
        if let Some(d) = parts.denoiser.as_mut().filter(|_| self.lights_changed) {
            // The records of the lights that changed may follow the frame's for the
            // denoiser's correction of its history.
            d.follow_lights(
                &mut light_data,
                count,
                settings.technique.info().fills == crate::error::Fills::Rays,
            );
        }
        let bytes: &[u8] = bytemuck::cast_slice(&light_data);
        crate::gpu::buffers::grow_buffer(ctx, &mut parts.lights, bytes.len() as u64, "lights")?;
        ctx.queue.write_buffer(&parts.lights, 0, bytes);
        parts.clusters.update(ctx, scene)?;
        parts
            .clusters
            .bind(ctx, &parts.frame_buffer, &parts.lights, &parts.gbuffer);
        parts.source.bind(
            ctx,
            &SourceInputs {
                scene,
                frame: &parts.frame_buffer,
                lights: &parts.lights,
                gbuffer: &parts.gbuffer,
                clusters: &parts.clusters,
                instances: &parts.scene.instances,
                page_wants: parts.wants.as_ref().map(|w| &w.buffer),
            },
        )?;
        let out = parts.source.output();
        parts.uniforms = frame_uniforms(scene, settings, (out.depth_side, out.max_penumbra));
        if let Some(p) = &mut parts.probes {
            let redraw = std::mem::take(&mut self.probes_stale);
            let sources = (&parts.lights, &*parts.source);
            p.update(ctx, scene, &parts.scene, sources, &parts.uniforms, redraw)?;
        }
        self.lighting.rebind(ctx, &parts.lighting());
        let lights = scene.lights.len() as u32;
        if self
            .visibility
            .as_ref()
            .is_some_and(|v| v.lights() != lights)
        {
            self.visibility = visibility_pass(ctx, settings, scene, &*parts.source)?;
        }
        if let Some(v) = &mut self.visibility {
            v.bind(ctx, &parts.frame_inputs());
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
        (settings.width, settings.height),
        scene.lights.len() as u32,
        &shadows.lookup,
        settings.soft_visibility,
    )
    .map(Some)
}

/// The denoiser, where it follows moved casters (`RayOptions::moved_shadows`): what a moved
/// or bent caster is noted to.
fn moved_casters_denoiser<'p>(
    parts: &'p mut FrameParts,
    settings: &RenderSettings,
) -> Option<&'p mut crate::sampled::denoise::Denoiser> {
    parts
        .denoiser
        .as_mut()
        .filter(|_| settings.rays.moved_shadows)
}
