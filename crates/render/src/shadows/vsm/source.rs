//! Virtual shadow maps as a frame's shadow source: an empty shadow plan, a view table, the
//! caster geometry and [`VirtualShadows`]; the output is the page pool with its table.

use glam::Vec3;
use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::gpu::timing::GpuTimer;
use crate::gpu::types::LightData;
use crate::gpu_scene::instances::GpuScene;
use crate::settings::{RenderSettings, Technique};
use crate::shadows::descriptor::{Build, Culling, Fills, Need, TechniqueInfo, Wgsl};
use crate::shadows::plan::ShadowPlan;
use crate::shadows::source::{
    PagePool, ShadowOutput, ShadowSource, ShadowStats, SourceInputs, ViewTable, Views,
};
use crate::shadows::vsm::pages::{VirtualShadows, VsmInputs};
use crate::shadows::vsm::plan::{VirtualOptions, VirtualPlan, VirtualStats};
use crate::{GpuContext, RenderError};

impl Technique {
    /// Virtual shadow maps (seed 002).
    pub const VIRTUAL: Technique = Technique::named("virtual");
}

/// `virtual`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::VIRTUAL,
    summary: "virtual shadow maps: a 16k² paged map per light face, only the pages the \
              camera's samples need, at the resolution they need, rendered into a page pool",
    origin: "seed 002 (Olsson et al., virtual shadow maps for many lights)",
    fills: Fills::Pages,
    culling: Culling::Clusters,
    point_shadows: &[PointShadows::Cube],
    needs: &[
        Need::feature(
            wgpu::Features::CLIP_DISTANCES,
            "to keep each page's draw inside its pool tile",
        ),
        Need::indirect("indirect dispatches and draws (to allocate and draw its pages)"),
    ],
    instead: "use technique traditional",
    build: Build::Source(|a| {
        Ok(Box::new(VirtualSource::new(
            a.ctx, a.scene, a.gpu, a.settings,
        )?))
    }),
    shaders: || {
        vec![
            Wgsl::core("vsm", crate::shadows::vsm::pages::shader()),
            Wgsl::with(
                "vsm_draw",
                crate::shadows::vsm::draw::shader(),
                wgpu::Features::CLIP_DISTANCES,
            ),
        ]
    },
};

/// Virtual shadow maps as a frame's [`ShadowSource`]: an empty shadow plan (the faces are in
/// [`VirtualPlan`]), the caster geometry and the page pool, which is the output.
pub struct VirtualSource {
    table: ViewTable,
    maps: VirtualShadows,
    size: (u32, u32),
    /// Keep the pages of unchanged faces between frames.
    cache: bool,
}

impl VirtualSource {
    pub(crate) fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        settings: &RenderSettings,
    ) -> Result<Self, RenderError> {
        let table = ViewTable::new(
            ctx,
            scene,
            gpu,
            ShadowPlan::none(scene.lights.len()),
            settings,
        )?;
        let options = VirtualOptions {
            back_facing: settings.visibility,
            ..settings.virtual_maps
        };
        let size = (settings.width, settings.height);
        let maps = VirtualShadows::new(
            ctx,
            scene,
            size,
            options,
            settings.shadow,
            &table.casters,
            settings.cache_shadows,
        )?;
        Ok(Self {
            table,
            maps,
            size,
            cache: settings.cache_shadows,
        })
    }
}

impl ShadowSource for VirtualSource {
    fn views(&self) -> Views<'_> {
        self.table.views()
    }

    fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        self.maps.light_data(scene)
    }

    fn update(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), RenderError> {
        let plan = ShadowPlan::none(scene.lights.len());
        if self.table.update(ctx, scene, plan)? {
            self.maps.forget_pages();
        }
        self.maps
            .update(ctx, scene, self.size, &self.table.casters)?;
        Ok(())
    }

    fn bind(&mut self, ctx: &GpuContext, inputs: &SourceInputs<'_>) -> Result<(), RenderError> {
        self.maps.bind(
            ctx,
            &VsmInputs {
                frame: inputs.frame,
                lights: inputs.lights,
                gbuffer: inputs.gbuffer,
                clusters: inputs.clusters,
                instances: inputs.instances,
                casters: &self.table.casters,
            },
        );
        Ok(())
    }

    fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.maps.note_moved(old, new);
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        _scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> ShadowStats {
        let pages_span = timer.span(crate::gpu::timing::Stage::Pages);
        let span = timer.span(crate::gpu::timing::Stage::Shadows);
        self.maps.record(
            ctx,
            encoder,
            &self.table.casters,
            timer,
            pages_span,
            span,
            self.cache,
        );
        ShadowStats::default()
    }

    fn output(&self) -> ShadowOutput<'_> {
        ShadowOutput::Pages {
            pages: PagePool {
                pool: &self.maps.pool_view,
                side: self.maps.pool_side(),
                uniforms: self.maps.uniforms(),
                faces: self.maps.faces(),
                table: self.maps.table(),
            },
            views: &self.table.views,
        }
    }

    fn read_atlas(&self, _ctx: &GpuContext) -> Result<Vec<f32>, RenderError> {
        Err(RenderError::NoAtlas {
            technique: INFO.technique,
            fills: INFO.fills,
        })
    }

    fn virtual_plan(&self) -> Option<&VirtualPlan> {
        Some(&self.maps.plan)
    }

    fn read_virtual_stats(&self, ctx: &GpuContext) -> Result<Option<VirtualStats>, RenderError> {
        self.maps.read_stats(ctx).map(Some)
    }
}
