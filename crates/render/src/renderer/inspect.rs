//! What callers read of a renderer: its plans and estimates, GPU read-backs, and frames
//! shaded with a given visibility.

use super::state::Renderer;
use crate::error::RenderError;
use crate::frame::gbuffer_readback::GBufferData;
use crate::frame::visibility_mask::SoftVisibility;
use crate::gpu::context::GpuContext;
use crate::report::{ShadowLayout, ShadowWork};
use crate::settings::RenderSettings;
use crate::shading::lighting::LightingPass;
use crate::shadows::image::ShadowPicture;
use manyshadows_scene::Scene;
use wgpu::util::DeviceExt;

impl Renderer {
    /// The shadow views and atlas layout.
    #[cfg(feature = "internals")]
    pub fn plan(&self) -> &crate::shadows::plan::ShadowPlan {
        self.parts.source.plan()
    }

    /// The frame's shadow source as `T`, where the technique's source is one (the facade's
    /// accessors of one technique's own read-backs use it).
    pub(crate) fn source_as<T: 'static>(&self) -> Option<&T> {
        (&*self.parts.source as &dyn std::any::Any).downcast_ref::<T>()
    }

    /// The technique's own counters of the last frame as `T` (its declaration's type of them:
    /// `VirtualStats`, `IrregularStats`), or `None` where the technique keeps none of that type
    /// or reading them failed.
    pub fn technique_stats<T: std::any::Any + Copy>(&self) -> Option<T> {
        self.parts
            .source
            .technique_stats(&self.ctx)
            .ok()
            .flatten()
            .and_then(|s| s.downcast::<T>().ok())
            .map(|s| *s)
    }

    /// Shadow views of the current plan: every atlas tile, or every virtual face (a spot
    /// light's frustum, a cube face, a cascade).
    pub fn shadow_views(&self) -> usize {
        self.parts.source.view_count()
    }

    /// What holds the shadows: the kind, how many views, and the side of the texture they
    /// are read from.
    pub fn shadow_layout(&self) -> ShadowLayout {
        let source = &self.parts.source;
        ShadowLayout {
            fills: self.settings.technique.info().fills,
            views: self.shadow_views(),
            side: source.output().depth_side,
            atlas_fill: source.fills_atlas().then(|| source.plan().fill() as f32),
        }
    }

    /// The per-view shadow work the next frame asks for, from its shadow plan, before anything
    /// is rendered: what a caller checks before starting a frame that could take minutes (a
    /// technique that sends every triangle to every one of 36,499 views takes 9.4 G pairs).
    /// Irregular shadow maps test every caster triangle against every light view's grid (one
    /// thread per pair), so they count every pair too. `None` for techniques whose work is not
    /// per view: rays, and virtual pages made on the GPU.
    pub fn shadow_work(&self) -> Option<ShadowWork> {
        let views = &self.parts.source.plan().views;
        if views.is_empty() {
            return None;
        }
        Some(self.per_view_work(views).0)
    }

    /// The per-view work of `views` as the technique takes it on ([`ShadowWork`]), and the
    /// (caster instance, view) pairs left by culling whole instances (the draws).
    pub(super) fn per_view_work(
        &self,
        views: &[manyshadows_scene::light_space::ShadowView],
    ) -> (ShadowWork, u64) {
        use crate::shadows::descriptor::Culling;
        let per_view: u64 = self
            .parts
            .scene
            .draws
            .iter()
            .filter(|d| d.casts_shadows)
            .map(|d| u64::from(d.mesh.index_count / 3))
            .sum();
        let (culled, draws) = self.instance_pairs(views);
        let all_pairs = per_view * views.len() as u64;
        let work = ShadowWork {
            views: views.len(),
            triangle_views: match self.settings.technique.info().culling {
                Culling::VertexStage | Culling::Threads | Culling::NoViews => all_pairs,
                _ => culled,
            },
            after_instance_culling: culled,
            all_pairs,
        };
        (work, draws)
    }

    /// (caster triangle, view) and (caster instance, view) pairs left after culling whole
    /// instances per view by bounding sphere.
    fn instance_pairs(&self, views: &[manyshadows_scene::light_space::ShadowView]) -> (u64, u64) {
        let casters: Vec<_> = self
            .parts
            .scene
            .draws
            .iter()
            .filter(|d| d.casts_shadows)
            .collect();
        let (mut culled, mut draws) = (0u64, 0u64);
        for v in views {
            let visible = v.sphere_test();
            for d in &casters {
                if visible(d.sphere.0, d.sphere.1) {
                    culled += u64::from(d.mesh.index_count / 3);
                    draws += 1;
                }
            }
        }
        (culled, draws)
    }

    /// A picture of the shadow maps as the last frame left them: the atlas with each view's
    /// tile outlined by light type, or the virtual maps' page pool (pages in use, unused pool
    /// dark blue), at most 2048² (larger ones are shown every n-th texel). A technique that
    /// keeps neither answers [`RenderError::NoAtlas`].
    pub fn shadow_picture(&self) -> Result<ShadowPicture, RenderError> {
        self.parts.source.picture(&self.ctx)
    }

    /// The settings in use.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The widest penumbra radius, in shadow texels, the soft filter reads at one level:
    /// `SoftShadows::max_penumbra`, clamped to what the technique's lookup reaches (virtual
    /// maps: 63 texels, wider penumbrae filtered at coarser levels).
    pub fn max_penumbra(&self) -> f32 {
        self.shadow_side().1.min(self.settings.soft.max_penumbra)
    }

    /// The shading model, exposure and tone map of the next frame: the settings' [`Look`]
    /// decided for the current scene and camera (a metered exposure follows the camera).
    ///
    /// [`Look`]: crate::shading::look::Look
    pub fn look(&self) -> crate::shading::look::ResolvedLook {
        self.settings.look.resolve(&self.current)
    }

    /// Triangles in the scene (over all instances).
    pub fn triangles(&self) -> u64 {
        self.parts.scene.triangles
    }

    /// The GPU context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The world-space shadow-caster geometry (its back-face culling decisions included).
    #[cfg(feature = "internals")]
    pub fn casters(&self) -> &crate::gpu_scene::casters::CasterGeometry {
        self.parts.source.casters()
    }

    /// The shadow atlas.
    #[cfg(feature = "internals")]
    pub fn atlas(&self) -> &crate::shadows::storage::ShadowAtlas {
        self.parts.source.atlas()
    }

    /// The scene as the next frame will render it (camera, lights and instance transforms as
    /// last set).
    pub fn scene(&self) -> &Scene {
        &self.current
    }

    /// The last frame [`Renderer::render`] produced, shaded again with `visibility` instead
    /// of the technique's shadows (the fraction of each light reaching each pixel, as
    /// [`crate::Frame::soft_visibility`] holds it): the image a technique would give if its
    /// visibility were `visibility`, such as the reference's. sRGB RGBA8, as [`crate::Frame::rgba`].
    pub fn shade_with(&self, visibility: &SoftVisibility) -> Result<Vec<u8>, RenderError> {
        let (w, h) = (self.settings.width, self.settings.height);
        let lights = self.current.lights.len() as u32;
        if (visibility.width, visibility.height, visibility.lights) != (w, h, lights) {
            return Err(RenderError::Mismatch {
                what: "the visibility to shade with",
                expected: format!("{w}x{h} pixels of {lights} lights"),
                found: format!(
                    "{}x{} pixels of {} lights",
                    visibility.width, visibility.height, visibility.lights
                ),
            });
        }
        let ctx = &*self.ctx;
        let limit = ctx.limits().max_storage_buffer_binding_size;
        let mut bytes = visibility.values.clone();
        bytes.resize(bytes.len().div_ceil(4).max(1) * 4, 0);
        if bytes.len() as u64 > limit {
            return Err(RenderError::TooLarge {
                what: "the visibility to shade with".into(),
                needed: bytes.len() as u64,
                limit,
                unit: "bytes",
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        ctx.scoped("shading with a given visibility", || {
            let fractions = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("lighting.fractions"),
                    contents: &bytes,
                    usage: wgpu::BufferUsages::STORAGE,
                });
            let mut inputs = self.parts.lighting();
            inputs.frame.shadows.mask = Some(&fractions);
            // A frame shaded with given fractions: no sampled lights, their histories are
            // the frame's own (the probes' reflections stay).
            let probes = inputs.parts.pop().expect("the probes' part is last");
            inputs.parts = crate::sampled::lighting_parts(None, None, None);
            inputs.parts.push(probes);
            let consts = self.parts.shading_consts(&self.current, &self.settings);
            let pass = LightingPass::with_fractions(ctx, &inputs, (w, h), &consts);
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("lighting.fractions.encoder"),
                });
            pass.record(&mut encoder, &self.timer, None);
            ctx.queue.submit([encoder.finish()]);
            crate::gpu::readback::read_texture(ctx, &pass.color, 4)
        })
    }

    /// Reads face `face` (+X, −X, +Y, −Y, +Z, −Z: `Probe::face_cameras`) of probe `probe` as
    /// the last frame left it: linear radiance per texel, rows from the top, `side`² texels
    /// (see [`crate::Frame::probes`]).
    pub fn read_probe_face(&self, probe: usize, face: usize) -> Result<Vec<[f32; 4]>, RenderError> {
        let Some(p) = &self.parts.probes else {
            return Err(RenderError::NotImplemented {
                what: "reading a probe face of a scene without probes",
                instead: "give the scene probes (Scene::probes)",
            });
        };
        if probe >= p.maps.count || face >= 6 {
            return Err(RenderError::InvalidOption {
                option: "probe face",
                value: format!("probe {probe} face {face}"),
                expected: "an existing probe and a face 0..6",
            });
        }
        let layer = crate::probes::maps::ProbeMaps::layer(probe, face);
        let bytes = crate::gpu::readback::read_texture_layer(&self.ctx, &p.maps.faces, 8, layer)?;
        Ok(bytes
            .chunks_exact(8)
            .map(|t| {
                let h = |i: usize| f16_to_f32(u16::from_le_bytes([t[2 * i], t[2 * i + 1]]));
                [h(0), h(1), h(2), h(3)]
            })
            .collect())
    }

    /// With probe faces drawn GPU-driven (`ProbePasses::Clusters`): of the triangle clusters
    /// the last frame that drew the faces offered the GPU's cull (every cluster × every face),
    /// how many it kept, and how many it was offered (`None` when the faces are drawn another
    /// way). A read-back, for tests and inspection.
    pub fn probe_clusters_kept(&self) -> Result<Option<(u64, u64)>, RenderError> {
        match &self.parts.probes {
            Some(p) => p.clusters_kept(&self.ctx),
            None => Ok(None),
        }
    }

    /// With probe faces drawn GPU-driven: the cull + draw rounds the last frame that drew
    /// them ran (`None` when the faces are drawn another way).
    pub fn probe_cluster_rounds(&self) -> Option<usize> {
        Some(self.parts.probes.as_ref()?.face_clusters()?.rounds())
    }

    /// Test only (feature `test-hooks`): caps the indirect commands of one round of
    /// GPU-driven probe faces (more rounds, faces split between them) and redraws the faces
    /// in the next frame; false when the faces are drawn another way.
    #[cfg(feature = "test-hooks")]
    pub fn cap_probe_cluster_rounds(&mut self, commands: u64) -> bool {
        let Some(c) = self
            .parts
            .probes
            .as_mut()
            .and_then(|p| p.face_clusters_mut())
        else {
            return false;
        };
        c.cap_round_commands(commands);
        self.dirty = true;
        self.probes_stale = true;
        true
    }

    /// Reads the G-buffer of the last frame [`Renderer::render`] produced (before the first
    /// frame every pixel reads as uncovered).
    pub fn read_gbuffer(&self) -> Result<GBufferData, RenderError> {
        GBufferData::read(self.context(), &self.parts.gbuffer)
    }

    /// Reads the depth atlas back (`size`² floats, row-major); techniques that fill no atlas
    /// (`irregular`, `virtual`) answer [`RenderError::NoAtlas`].
    pub fn read_atlas(&self) -> Result<Vec<f32>, RenderError> {
        self.parts.source.read_atlas(&self.ctx)
    }
}

/// An IEEE half's value.
fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f32::from(h & 0x3ff);
    sign * match exp {
        0 => frac * 2f32.powi(-24),
        31 if frac == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + frac / 1024.0) * 2f32.powi(e - 15),
    }
}
