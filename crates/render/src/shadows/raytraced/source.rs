//! Ray-traced shadows as a frame's shadow source: no shadow map at all. The source keeps the
//! acceleration structures ([`RayAccel`]) and rebuilds the TLAS when an instance moved; the
//! lighting and visibility passes cast the rays themselves (`rays.wgsl` composed into them),
//! from the G-buffer point to each light of the pixel's cluster, or to `K` lights picked by
//! importance ([`crate::RayOptions::light_samples`]).

use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::error::{Fills, RenderError, Technique};
use crate::gpu::bindings::Binding;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Stage};
use crate::gpu::types::LightData;
use crate::gpu_scene::casters::ALPHA_MASK;
use crate::gpu_scene::instances::GpuScene;
use crate::sampled::options::RayOptions;
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::descriptor::{Build, Culling, Need, TechniqueInfo};
use crate::shadows::image::ShadowPicture;
use crate::shadows::lookup::{atlas_coord, LookupWgsl, ATLAS_TAPS};
use crate::shadows::plan::ShadowPlan;
use crate::shadows::raytraced::accel::RayAccel;
use crate::shadows::report::{ReportLine, ShadowReport, ShadowText};
use crate::shadows::source::{
    ShadowOutput, ShadowSource, ShadowStats, SourceInputs, SourceSettings, ViewTable, Views,
};

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
    soft_shadows: true,
    // Milliseconds of its acceleration structure per instance, and fixed, on lavapipe
    // (docs/benchmarks.md, "What a frame will cost: `bench estimate`").
    cost: Cost {
        lighting: LightingRead::Rays,
        shadows_ms: |w| price(&[0.0, 8.13e-02], &[w.instances as f64, 1.0]),
    },
    camera_pixels_only: false,
    follows_camera: false,
    report,
    instead: "use technique irregular for exact shadows without ray queries",
    lookup: RAYS_LOOKUP,
    build: Build::Source(|a| {
        Ok(Box::new(RaytracedSource::new(
            a.ctx, a.scene, a.gpu, a.settings,
        )?))
    }),
    // Its only WGSL is its lookup, composed into the lighting and visibility passes.
    shaders: Vec::new,
};

/// Shadow rays from the passes themselves: the atlas's `shadow_coord` (never reached: no
/// light has views), the alpha-mask tail and `rays.wgsl`. Its declarations: the TLAS, the
/// ray geometry and the sampling parameters.
const RAYS_LOOKUP: LookupWgsl = LookupWgsl {
    enables: "enable wgpu_ray_query;",
    bindings: &[
        Binding::acceleration_structure("scene_tlas"),
        Binding::storage("corners", "array<u32>"),
        Binding::uniform("rays", "RayParams"),
    ],
    source: || {
        format!(
            "{}\n{ATLAS_TAPS}\n{ALPHA_MASK}\n{}",
            atlas_coord(),
            include_str!("rays.wgsl")
        )
    },
    features: wgpu::Features::EXPERIMENTAL_RAY_QUERY,
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
        settings: &SourceSettings<'_>,
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
        let accel = RayAccel::new(
            ctx,
            scene,
            gpu,
            &masks,
            settings.options::<RayOptions>(),
            settings.shadow.casters.single_sided,
        )?;
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

    fn note_deformed(&mut self, ctx: &GpuContext, mesh: usize, positions: &[glam::Vec3]) {
        self.accel.deform(&ctx.queue, mesh, positions);
    }

    fn note_deformed_on_gpu(&mut self, mesh: usize, bytes: (u64, u64)) {
        self.accel.deform_on_gpu(mesh, bytes);
    }

    /// The TLAS build, timed as the `accel` stage between two empty compute passes that
    /// carry its timestamps; the rays themselves are cast by the lighting pass.
    fn record(
        &mut self,
        _ctx: &GpuContext,
        scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> ShadowStats {
        let span = timer.span(Stage::Accel);
        drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("raytraced.accel_begin"),
            timestamp_writes: timer.compute_writes(span, true, false),
        }));
        let built = self.accel.record(encoder, &scene.positions);
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
        ShadowOutput {
            resources: vec![
                self.accel.tlas().as_binding(),
                self.accel.geometry.as_entire_binding(),
                self.accel.params.as_entire_binding(),
            ],
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
}

/// Ray-traced shadows' report: no views and no filter, how sized lights are traced, and the
/// acceleration structure's builds.
fn report(r: &ShadowReport<'_>) -> ShadowText {
    let rays = &r.rays;
    let softness = match rays.light_samples {
        0 => format!(
            "sized lights traced with {0}x{0} samples of their shape per pixel{1}",
            rays.area_samples.max(1),
            if rays.denoise {
                ", new each frame and accumulated over still frames"
            } else {
                ""
            }
        ),
        _ => format!(
            "a sampled sized light is traced at one point of its shape{}{}",
            if rays.reuse {
                ", new each frame, reused across frames"
            } else if rays.denoise {
                ", new each frame"
            } else {
                ""
            },
            if rays.denoise { ", denoised" } else { "" }
        ),
    };
    let mut lines = r.opening("no shadow views", "no filter", &softness);
    lines.push(ReportLine::new(
        "shadow work",
        format!(
            "no shadow map: rays per pixel and light of its cluster (or per sampled light) in \
             the lighting pass; {} top-level structure build(s)",
            r.stats.passes
        ),
    ));
    // No maps: the rays are traced in the lighting pass, and what their histories hold.
    let history = RayOptions::denoise_history(r.frames);
    let plural = if history == 1 { "" } else { "s" };
    let reused = if rays.reuse {
        let m = RayOptions::reuse_confidence(r.frames);
        let spatial = match rays.spatial {
            crate::sampled::options::SpatialReuse::Off => String::new(),
            mode => format!(" and between neighbours ({})", mode.name()),
        };
        format!(", lights reused (reservoirs of up to {m} frames){spatial}")
    } else {
        String::new()
    };
    let kept = if !rays.denoise {
        reused
    } else if rays.light_samples > 0 {
        format!("{reused}, denoised (history up to {history} frame{plural})")
    } else {
        format!(", area samples accumulated (up to {history} frame{plural})")
    };
    ShadowText {
        lines,
        frame: format!(
            "shadow rays in the lighting pass{kept}, lighting GPU time {}",
            r.gpu_time(Stage::Lighting)
        ),
    }
}
