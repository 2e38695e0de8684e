//! Irregular shadow maps as a frame's shadow source: the plan's views in a view table (no
//! atlas) and the passes of [`crate::shadows::irregular::maps`]; the output is the mask.

use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::error::{Fills, RenderError, Technique};
use crate::frame::visibility_mask::VisibilityMask;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Stage};
use crate::gpu::types::LightData;
use crate::gpu_scene::instances::GpuScene;
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::descriptor::{Build, Culling, TechniqueInfo, Wgsl};
use crate::shadows::image::ShadowPicture;
use crate::shadows::irregular::maps::{
    IrregularInputs, IrregularOptions, IrregularShadows, IrregularStats,
};
use crate::shadows::lookup::ATLAS_LOOKUP;
use crate::shadows::report::{ReportLine, ShadowReport, ShadowText};
use crate::shadows::source::{
    PlanParams, ShadowOutput, ShadowSource, ShadowStats, SourceInputs, SourceSettings,
    TechniqueStats, ViewTable, Views,
};

impl Technique {
    /// Irregular (alias-free) shadow maps (seed 001).
    pub const IRREGULAR: Technique = Technique::named("irregular");
}

/// `irregular`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::IRREGULAR,
    summary: "irregular shadow maps: camera samples in per-texel lists of each light view, \
              every caster triangle tested exactly against the samples under it; alias-free",
    origin: "seed 001 (irregular shadow mapping)",
    fills: Fills::Mask,
    culling: Culling::NoViews,
    point_shadows: &[PointShadows::Cube],
    needs: &[],
    soft_shadows: false,
    // Milliseconds of its lists per (triangle, view) pair, (instance, view) pair, (pixel, light)
    // sample, and fixed, on lavapipe (docs/benchmarks.md, "What a frame will cost: `bench
    // estimate`").
    cost: Cost {
        lighting: LightingRead::Mask,
        shadows_ms: |w| {
            price(
                &[2.60e-05, 5.06e-02, 3.29e-04, 1.58e+02],
                &[
                    w.triangle_views as f64,
                    w.instance_views as f64,
                    w.pixel_lights as f64,
                    1.0,
                ],
            )
        },
    },
    camera_pixels_only: true,
    follows_camera: false,
    report,
    instead: "",
    // The passes shade with the mask and never call `shadow_coord`.
    lookup: ATLAS_LOOKUP,
    build: Build::Source(|a| {
        Ok(Box::new(IrregularSource::new(
            a.ctx, a.scene, a.gpu, a.params, a.settings,
        )?))
    }),
    shaders: || {
        vec![Wgsl::core(
            "irregular",
            crate::shadows::irregular::maps::shader(),
        )]
    },
};

/// Irregular shadow maps as a frame's [`ShadowSource`]: the plan's views (a view table, no
/// atlas) and the passes, rebuilt at every [`ShadowSource::bind`] (their light-space grids
/// and batches are sized by the plan). Its output is the visibility mask itself.
pub struct IrregularSource {
    table: ViewTable,
    params: PlanParams,
    size: (u32, u32),
    options: IrregularOptions,
    /// Built by the first [`ShadowSource::bind`].
    passes: Option<IrregularShadows>,
}

impl IrregularSource {
    pub(crate) fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        params: PlanParams,
        settings: &SourceSettings<'_>,
    ) -> Result<Self, RenderError> {
        let plan = params.plan(scene)?;
        Ok(Self {
            table: ViewTable::new(ctx, scene, gpu, plan, settings)?,
            params,
            size: (settings.width, settings.height),
            options: settings.options::<IrregularOptions>(),
            passes: None,
        })
    }

    fn passes(&self) -> &IrregularShadows {
        self.passes
            .as_ref()
            .expect("the renderer binds a shadow source before using it")
    }
}

impl ShadowSource for IrregularSource {
    fn views(&self) -> Views<'_> {
        self.table.views()
    }

    fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        self.table.plan.light_data(scene)
    }

    fn update(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), RenderError> {
        let plan = self.params.plan(scene)?;
        self.table.update(ctx, scene, plan)?;
        Ok(())
    }

    fn bind(&mut self, ctx: &GpuContext, inputs: &SourceInputs<'_>) -> Result<(), RenderError> {
        // The grids are sized by the plan: rebuild the passes.
        self.passes = Some(IrregularShadows::new(
            ctx,
            inputs.scene,
            &self.table.plan,
            &IrregularInputs {
                frame: inputs.frame,
                lights: inputs.lights,
                views: &self.table.views.views_buffer,
                gbuffer: inputs.gbuffer,
                casters: &self.table.casters,
            },
            self.size,
            self.options,
        )?);
        Ok(())
    }

    fn record(
        &mut self,
        _ctx: &GpuContext,
        _scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> ShadowStats {
        let span = timer.span(crate::gpu::timing::Stage::Shadows);
        self.passes()
            .record(encoder, &self.table.casters, timer, span);
        ShadowStats::default()
    }

    fn finish(&mut self, ctx: &GpuContext) -> Result<(), RenderError> {
        // A full node pool makes the frame an error, never a wrong image.
        match self.passes.as_mut() {
            Some(p) => p.finish(ctx).map(|_| ()),
            None => Ok(()),
        }
    }

    fn output(&self) -> ShadowOutput<'_> {
        ShadowOutput {
            mask: Some(self.passes().mask()),
            ..ShadowOutput::from_views(&self.table.views, INFO.lookup)
        }
    }

    fn picture(&self, _ctx: &GpuContext) -> Result<ShadowPicture, RenderError> {
        Err(RenderError::NoAtlas {
            technique: INFO.technique,
            fills: INFO.fills,
        })
    }

    fn read_atlas(&self, _ctx: &GpuContext) -> Result<Vec<f32>, RenderError> {
        Err(RenderError::NoAtlas {
            technique: INFO.technique,
            fills: INFO.fills,
        })
    }

    fn read_mask(&self, ctx: &GpuContext) -> Result<Option<VisibilityMask>, RenderError> {
        self.passes().read_mask(ctx).map(Some)
    }

    /// `IrregularStats` of the last finished frame.
    fn technique_stats(&self, _ctx: &GpuContext) -> Result<Option<TechniqueStats>, RenderError> {
        Ok(self
            .passes
            .as_ref()
            .map(|p| Box::new(p.stats()) as TechniqueStats))
    }
}

/// Irregular maps' report: exact samples in lists, their own work (no atlas, no passes of
/// shadow maps).
fn report(r: &ShadowReport<'_>) -> ShadowText {
    let mut lines = r.opening(
        "exact samples in per-light lists",
        "no filter (exact, hard)",
        "hard: answers at each light's centre, sizes ignored",
    );
    if let Some(i) = r.own::<IrregularStats>() {
        lines.push(ReportLine::new(
            "lists",
            format!(
                "{} batch(es) of lights, the largest holding {} of {} list nodes (camera \
                 samples in light-space lists); up to {} 8x8-texel tiles queued for the triangle \
                 tests{}",
                i.batches,
                i.peak_nodes,
                i.node_capacity,
                i.peak_tiles,
                match i.unmapped {
                    0 => String::new(),
                    n => format!("; {n} samples outside every view of their light (counted lit)"),
                }
            ),
        ));
    }
    // Sample lists: every view's are built anew each frame (nothing is kept).
    ShadowText {
        lines,
        frame: format!(
            "sample lists of all {} light views built anew, shadow GPU time {}",
            r.plan.views.len(),
            r.gpu_time(Stage::Shadows)
        ),
    }
}
