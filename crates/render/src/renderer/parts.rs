//! The frame's parts, made in one place and handed to the passes from one place: the scene on
//! the GPU, the shadow source, the frame's uniforms and lights, the G-buffer, the light
//! clusters, the sampled lights' histories (motion, reservoirs, denoiser) and the reflection
//! probes. [`FrameParts::new`] makes them for a scene and settings; [`FrameParts::lighting`]
//! is the one list of what the lighting pass reads and of the parts plugged into it.

use manyshadows_scene::Scene;
use wgpu::util::DeviceExt;

use super::uniforms::{frame_uniforms, lights_or_placeholder};
use crate::error::RenderError;
use crate::frame::clusters::{LightClusters, LightLoop};
use crate::frame::gbuffer::{GBuffer, GBufferViews};
use crate::gpu::context::GpuContext;
use crate::gpu::types::FrameUniforms;
use crate::gpu_scene::instances::GpuScene;
use crate::probes::faces::ProbeFrame;
use crate::sampled::denoise::Denoiser;
use crate::sampled::motion::InstanceMotion;
use crate::sampled::pages::PageWants;
use crate::sampled::reuse::Reuse;
use crate::settings::RenderSettings;
use crate::shading::inputs::FrameInputs;
use crate::shading::lighting::LightingInputs;
use crate::shading::look::ShadingConsts;
use crate::shadows::source::{ShadowSource, SourceInputs};

/// Everything a frame's passes read.
pub(super) struct FrameParts {
    /// The scene's meshes, materials and instances on the GPU.
    pub scene: GpuScene,
    /// Where the frame's shadows come from (atlas, page pool, visibility mask or rays).
    pub source: Box<dyn ShadowSource>,
    /// The frame's uniforms as last derived (`FrameParts::write_uniforms` sends them).
    pub uniforms: FrameUniforms,
    /// `FrameUniforms` on the GPU.
    pub frame_buffer: wgpu::Buffer,
    /// `array<LightData>`: the source's light records (and the denoiser's changed ones).
    pub lights: wgpu::Buffer,
    /// What the camera sees.
    pub gbuffer: GBuffer,
    /// The clustered light lists.
    pub clusters: LightClusters,
    /// Moving instances' motion between frames, which the denoiser's and the reservoirs'
    /// histories follow (only with either).
    pub motion: Option<InstanceMotion>,
    /// The denoiser of sampled shadow rays (`RayOptions::denoise`).
    pub denoiser: Option<Denoiser>,
    /// The reservoirs of reused light samples (`RayOptions::reuse`).
    pub reuse: Option<Reuse>,
    /// The (pixel, light) pairs the sampled lights ask about, for a source that makes only
    /// their shadows (`ShadowSource::marks_sampled_pairs`).
    pub wants: Option<PageWants>,
    /// The reflection probes' faces and passes (scenes with probes).
    pub probes: Option<ProbeFrame>,
    /// Skinned and morphed meshes bent on the GPU: made by the first pose
    /// (`Renderer::set_bending`); `Some(None)` where the scene has none it can bend.
    pub deformer: Option<Option<crate::gpu_scene::deform::Deformer>>,
}

impl FrameParts {
    /// Uploads `scene`, makes its shadow source and every buffer and target the frame's
    /// passes read, bound together, for `settings` (already validated).
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        settings: &RenderSettings,
        max_atlas: u32,
    ) -> Result<Self, RenderError> {
        let mut gpu_scene = GpuScene::new(ctx, scene)?;
        // Histories of surface points follow bent meshes (any mesh may be bent:
        // `Renderer::set_mesh_vertices`) by the positions the last frame drew.
        if (settings.rays.denoise || settings.rays.reuse) && settings.stereo.is_none() {
            gpu_scene.keep_last_positions(ctx, scene);
        }
        let mut source = crate::registry::create(ctx, scene, &gpu_scene, settings, max_atlas)?;
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
        let motion = histories.then(|| InstanceMotion::new(ctx, gpu_scene.draws.len()));
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
        let samples = settings.rays.light_samples;
        // The choose pass hands its draws over where they do not follow the shadows (the
        // denoiser's catch-up samples without reuse do: sampled/pages.rs).
        let carry = settings.rays.reuse || !settings.rays.denoise;
        let wants = (samples > 0 && source.marks_sampled_pairs())
            .then(|| PageWants::new(ctx, (settings.width, settings.height), samples, carry))
            .flatten();
        source.bind(
            ctx,
            &SourceInputs {
                scene,
                frame: &frame_buffer,
                lights: &lights,
                gbuffer: &gbuffer,
                clusters: &clusters,
                instances: &gpu_scene.instances,
                page_wants: wants.as_ref().map(|w| &w.buffer),
            },
        )?;
        let out = source.output();
        let uniforms = frame_uniforms(scene, settings, (out.depth_side, out.max_penumbra));
        drop(out);
        ctx.queue
            .write_buffer(&frame_buffer, 0, bytemuck::bytes_of(&uniforms));
        let denoiser = settings
            .rays
            .denoise
            .then(|| {
                Denoiser::new(
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
                Reuse::new(
                    ctx,
                    settings.width,
                    settings.height,
                    settings.rays.light_samples,
                    settings.rays.spatial,
                    (&gbuffer, motion.as_ref().expect("made with the reuse")),
                )
            })
            .transpose()?;
        let mut probes = if scene.probes.is_empty() {
            None
        } else {
            Some(ProbeFrame::new(
                ctx,
                scene,
                &gpu_scene,
                &lights,
                &*source,
                settings.look.resolve(scene).consts(),
                settings.probe_passes,
            )?)
        };
        if let Some(p) = &mut probes {
            p.update(ctx, scene, &gpu_scene, (&lights, &*source), &uniforms, true)?;
        }
        Ok(Self {
            scene: gpu_scene,
            source,
            uniforms,
            frame_buffer,
            lights,
            gbuffer,
            clusters,
            motion,
            denoiser,
            reuse,
            wants,
            probes,
            deformer: None,
        })
    }

    /// What the shadow-reading passes read of the frame.
    pub fn frame_inputs(&self) -> FrameInputs<'_> {
        FrameInputs {
            frame: &self.frame_buffer,
            lights: &self.lights,
            materials: &self.scene.materials,
            gbuffer: &self.gbuffer,
            clusters: &self.clusters,
            shadows: self.source.output(),
        }
    }

    /// What the lighting pass reads: the frame's inputs, then the parts plugged into it in
    /// order: the sampled lights with their reservoirs and denoiser, and the probes.
    pub fn lighting(&self) -> LightingInputs<'_> {
        let mut parts = crate::sampled::lighting_parts(
            self.denoiser.as_ref().map(|d| &d.buffers),
            self.reuse.as_ref(),
            self.wants.as_ref().map(|w| w.carry),
        );
        parts.push(crate::probes::maps::lighting_part(
            self.probes.as_ref().map(|p| &p.maps),
        ));
        LightingInputs {
            frame: self.frame_inputs(),
            parts,
            wants: self.wants.as_ref().map(|w| &w.buffer),
        }
    }

    /// How the lighting pass shades `scene` with `settings`: the look's constants and what
    /// the G-buffer keeps.
    pub fn shading_consts(&self, scene: &Scene, settings: &RenderSettings) -> ShadingConsts {
        ShadingConsts {
            emission_texture: self.gbuffer.emission.is_some(),
            ..settings.look.resolve(scene).consts()
        }
    }

    /// Sends the frame's uniforms as last derived (once per frame, whole).
    pub fn write_uniforms(&self, ctx: &GpuContext) {
        ctx.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&self.uniforms));
    }
}

#[cfg(test)]
mod tests {
    use crate::registry::TECHNIQUES;
    use crate::sampled::options::SpatialReuse;
    use crate::shading::look::{Shading, ShadingConsts, ToneMap};

    /// Every technique's lookup composed into the lighting pass with every part plugged in as
    /// the renderer plugs it (each on and off) validates as a WebGPU device with the lookup's
    /// features would: the seeds' Phong scenes, the glTF BRDF with emissive textures, the
    /// denoiser, spatial reuse and probes, physical light shaded by Phong into a probe's
    /// linear faces (every constant away from its default), and soft shadows compiled out.
    #[test]
    fn every_lighting_composition_validates_for_webgpu() {
        let pbr = ShadingConsts {
            shading: Shading::Pbr,
            physical_falloff: true,
            light_scale: 1.0,
            tone_map: ToneMap::Neutral,
            fixed_exposure: None,
            emission: true,
            emission_texture: true,
            linear_out: false,
            soft_shadows: true,
        };
        let phong_physical = ShadingConsts {
            shading: Shading::Phong,
            physical_falloff: true,
            light_scale: std::f32::consts::FRAC_1_PI,
            tone_map: ToneMap::Clamp,
            fixed_exposure: Some(0.5),
            emission: false,
            emission_texture: false,
            linear_out: true,
            soft_shadows: false,
        };
        let compositions = [
            ("lighting", ShadingConsts::default(), false, None, false),
            (
                "lighting (pbr, denoised, spatial reuse, probes)",
                pbr,
                true,
                Some(SpatialReuse::Unbiased),
                true,
            ),
            (
                "lighting (temporal reuse)",
                ShadingConsts::default(),
                false,
                Some(SpatialReuse::Off),
                false,
            ),
            (
                "lighting (phong, physical, linear)",
                phong_physical,
                true,
                None,
                false,
            ),
        ];
        let mut n = 0;
        for info in TECHNIQUES {
            for (name, consts, denoise, reuse, probes) in compositions {
                let mut parts = crate::sampled::lighting_parts_declared(denoise, reuse);
                parts.push(crate::probes::maps::lighting_part_declared(probes));
                let src = crate::shading::lighting::shader(&info.lookup, &consts, &parts);
                crate::gpu::shaders::validate_for_webgpu(name, &src, info.lookup.features)
                    .unwrap_or_else(|e| panic!("technique {}: {e}", info.technique));
                n += 1;
            }
        }
        assert_eq!(n, 4 * TECHNIQUES.len());
    }
}
