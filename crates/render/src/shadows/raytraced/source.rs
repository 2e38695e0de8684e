//! Ray-traced shadows as a frame's shadow source: no shadow map at all. The source keeps the
//! acceleration structures ([`RayAccel`]) and rebuilds the TLAS when an instance moved; the
//! lighting and visibility passes cast the rays themselves (`rays.wgsl` composed into them),
//! from the G-buffer point to each light of the pixel's cluster, or to `K` lights picked by
//! importance ([`crate::RayOptions::light_samples`]).

use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::gpu::shaders::{lighting, visibility, ShadowSource as ShaderSource};
use crate::gpu::timing::{GpuTimer, Stage};
use crate::gpu::types::LightData;
use crate::gpu_scene::instances::GpuScene;
use crate::settings::{RenderSettings, Technique};
use crate::shadows::descriptor::{Build, Culling, Fills, Need, TechniqueInfo, Wgsl};
use crate::shadows::plan::ShadowPlan;
use crate::shadows::raytraced::accel::RayAccel;
use crate::shadows::source::{
    RayScene, ShadowOutput, ShadowSource, ShadowStats, SourceInputs, ViewTable, Views,
};
use crate::{GpuContext, RenderError};

impl Technique {
    /// Shadow rays through an acceleration structure (ray queries).
    pub const RAYTRACED: Technique = Technique::named("raytraced");
}

/// `raytraced`'s declaration.
pub const INFO: TechniqueInfo = TechniqueInfo {
    technique: Technique::RAYTRACED,
    summary: "ray-traced shadows: one shadow ray per pixel and cluster light through a \
              BLAS per mesh and a TLAS of the casters (or K lights per pixel picked by \
              importance); exact, no shadow map",
    origin: "beyond the seeds: what Unreal's MegaLights and ReSTIR do for many lights",
    fills: Fills::Rays,
    culling: Culling::NoViews,
    point_shadows: &[PointShadows::Cube, PointShadows::DualParaboloid],
    needs: &[Need::feature(
        wgpu::Features::EXPERIMENTAL_RAY_QUERY,
        "ray queries in the lighting and visibility passes",
    )],
    instead: "use technique irregular for exact shadows without ray queries",
    build: Build::Source(|a| {
        Ok(Box::new(RaytracedSource::new(
            a.ctx, a.scene, a.gpu, a.settings,
        )?))
    }),
    shaders: || {
        let rays = ShaderSource::Rays { first: 12 };
        vec![
            Wgsl::with(
                "lighting_rays",
                lighting(rays),
                wgpu::Features::EXPERIMENTAL_RAY_QUERY,
            ),
            Wgsl::with(
                "visibility_rays",
                visibility(rays),
                wgpu::Features::EXPERIMENTAL_RAY_QUERY,
            ),
        ]
    },
};

/// Ray-traced shadows as a frame's [`ShadowSource`].
pub struct RaytracedSource {
    table: ViewTable,
    accel: RayAccel,
}

impl RaytracedSource {
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
        let masks = if settings.shadow.casters.ignore_masks {
            Default::default()
        } else {
            gpu.masks.clone()
        };
        let accel = RayAccel::new(ctx, scene, gpu, &masks, settings.rays)?;
        Ok(Self { table, accel })
    }
}

impl ShadowSource for RaytracedSource {
    fn views(&self) -> Views<'_> {
        self.table.views()
    }

    /// No views: a light's `shadow.y` is 1 when it casts shadows (the rays test it), else 0.
    fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        let mut data = self.table.plan.light_data(scene);
        for (d, l) in data.iter_mut().zip(&scene.lights) {
            d.shadow[1] = u32::from(l.casts_shadows);
        }
        data
    }

    fn update(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), RenderError> {
        self.table
            .update(ctx, scene, ShadowPlan::none(scene.lights.len()))?;
        self.accel.update(scene);
        Ok(())
    }

    fn bind(&mut self, _ctx: &GpuContext, _inputs: &SourceInputs<'_>) -> Result<(), RenderError> {
        Ok(())
    }

    fn note_moved(&mut self, _old: (glam::Vec3, f32), _new: (glam::Vec3, f32)) {}

    /// The TLAS build, timed as the `accel` stage between two empty compute passes that
    /// carry its timestamps; the rays themselves are cast by the lighting pass.
    fn record(
        &mut self,
        _ctx: &GpuContext,
        _scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> ShadowStats {
        let span = timer.span(Stage::Accel);
        drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("raytraced.accel_begin"),
            timestamp_writes: timer.compute_writes(span, true, false),
        }));
        let built = self.accel.record(encoder);
        drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("raytraced.accel_end"),
            timestamp_writes: timer.compute_writes(span, false, true),
        }));
        ShadowStats {
            passes: u32::from(built),
            views_drawn: 0,
            ..Default::default()
        }
    }

    fn output(&self) -> ShadowOutput<'_> {
        ShadowOutput::Rays {
            rays: RayScene {
                tlas: self.accel.tlas(),
                geometry: &self.accel.geometry,
                params: &self.accel.params,
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
}
