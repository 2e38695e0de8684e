//! An atlas technique as a frame's [`ShadowSource`]: the [`ShadowGenerator`] (plan, atlas,
//! caster geometry, the technique, caching) re-planned when the frame changes.

use glam::Vec3;
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::GpuTimer;
use crate::gpu::types::LightData;
use crate::gpu_scene::instances::GpuScene;
use crate::shadows::atlas::generator::ShadowGenerator;
use crate::shadows::descriptor::{SourceArgs, TechniqueInfo};
use crate::shadows::image::ShadowPicture;
use crate::shadows::source::{
    PlanParams, ShadowOutput, ShadowSource, ShadowStats, SourceInputs, Views,
};

/// An atlas-filling technique ([`ShadowGenerator`]) as a frame's shadow source.
pub struct AtlasSource {
    generator: ShadowGenerator,
    params: PlanParams,
    info: &'static TechniqueInfo,
}

impl AtlasSource {
    /// The source of the atlas technique `info`.
    pub(crate) fn new(
        args: SourceArgs<'_>,
        info: &'static TechniqueInfo,
    ) -> Result<Self, RenderError> {
        let SourceArgs {
            ctx,
            scene,
            gpu,
            params,
            settings,
        } = args;
        let plan = params.plan(scene)?;
        let mut generator = ShadowGenerator::new(ctx, scene, gpu, plan, info, settings.shadow)?;
        generator.set_caching(settings.cache_shadows || settings.shadow_budget.is_some());
        generator.set_budget(settings.shadow_budget);
        Ok(Self {
            generator,
            params,
            info,
        })
    }
}

impl ShadowSource for AtlasSource {
    fn views(&self) -> Views<'_> {
        Views {
            plan: &self.generator.plan,
            atlas: &self.generator.atlas,
            casters: &self.generator.casters,
        }
    }

    fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        self.generator.plan.light_data(scene)
    }

    fn update(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), RenderError> {
        let plan = self.params.plan(scene)?;
        let casters_changed = self.generator.casters.refresh(ctx, scene);
        self.generator.set_plan(ctx, plan, casters_changed)?;
        Ok(())
    }

    fn bind(&mut self, _ctx: &GpuContext, _inputs: &SourceInputs<'_>) -> Result<(), RenderError> {
        // The techniques read only the atlas, the scene and the caster geometry.
        Ok(())
    }

    fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.generator.note_moved(old, new);
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> ShadowStats {
        let span = timer.span(crate::gpu::timing::Stage::Shadows);
        self.generator.generate(ctx, scene, encoder, timer, span)
    }

    fn output(&self) -> ShadowOutput<'_> {
        ShadowOutput::from_views(&self.generator.atlas, self.info.lookup)
    }

    fn fills_atlas(&self) -> bool {
        true
    }

    fn picture(&self, ctx: &GpuContext) -> Result<ShadowPicture, RenderError> {
        ShadowPicture::of_atlas(ctx, &self.generator.atlas, &self.generator.plan)
    }

    fn read_atlas(&self, ctx: &GpuContext) -> Result<Vec<f32>, RenderError> {
        self.generator.read_atlas(ctx)
    }
}
