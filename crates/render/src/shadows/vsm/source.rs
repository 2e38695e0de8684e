//! Virtual shadow maps as a frame's shadow source: an empty shadow plan, a view table, the
//! caster geometry and [`VirtualShadows`]; the output is the page pool with its table.

use glam::Vec3;
use manyshadows_scene::light_space::{PointShadows, ShadowView};
use manyshadows_scene::Scene;

use crate::error::{Fills, RenderError, Technique};
use crate::gpu::bindings::Binding;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Stage};
use crate::gpu::types::LightData;
use crate::gpu_scene::instances::GpuScene;
use crate::shadows::cost::{price, Cost, LightingRead};
use crate::shadows::descriptor::{Build, Culling, Need, TechniqueInfo, Wgsl};
use crate::shadows::image::{read_depth_view, ShadowPicture};
use crate::shadows::lookup::{LookupWgsl, NO_RAYS};
use crate::shadows::plan::ShadowPlan;
use crate::shadows::report::{ReportLine, ShadowReport, ShadowText};
use crate::shadows::source::{
    ShadowOutput, ShadowSource, ShadowStats, SourceInputs, SourceSettings, TechniqueStats,
    ViewTable, Views,
};
use crate::shadows::vsm::pages::{VirtualShadows, VsmInputs};
use crate::shadows::vsm::plan::{VirtualOptions, VirtualPlan, VirtualStats, PAGE_SIZE, VSM_COMMON};
use crate::shadows::vsm::types::VSM_TYPES;

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
    soft_shadows: true,
    // Milliseconds of its pages and drawing per (triangle, face) pair after culling whole
    // instances, (instance, face) pair, (pixel, light) pair marked, those times extra taps
    // (penumbrae ask coarser pages), and fixed, on lavapipe (docs/benchmarks.md, "What a frame
    // will cost: `bench estimate`").
    cost: Cost {
        lighting: LightingRead::Maps,
        shadows_ms: |w| {
            price(
                &[1.13e-06, 4.49e-03, 3.03e-05, 9.82e-07, 1.41e+01],
                &[
                    w.triangle_views as f64,
                    w.instance_views as f64,
                    w.pixel_lights as f64,
                    w.tap_pairs(),
                    1.0,
                ],
            )
        },
    },
    camera_pixels_only: false,
    follows_camera: true,
    report,
    instead: "use technique traditional",
    lookup: VSM_LOOKUP,
    build: Build::Source(|a| {
        Ok(Box::new(VirtualSource::new(
            a.ctx, a.scene, a.gpu, a.settings,
        )?))
    }),
    shaders: || {
        vec![
            Wgsl::core("vsm_carry", crate::shadows::vsm::carry::shader()),
            Wgsl::core("vsm_mark", crate::shadows::vsm::mark::shader()),
            Wgsl::core("vsm_tiles", crate::shadows::vsm::tiles::shader()),
            Wgsl::core("vsm_alloc", crate::shadows::vsm::alloc::shader()),
            Wgsl::with(
                "vsm_draw",
                crate::shadows::vsm::draw::shader(),
                wgpu::Features::CLIP_DISTANCES,
            ),
        ]
    },
};

/// Shadows through the page table: the face's level, the resident page or a coarser one.
/// Its declarations: the uniforms, the faces and the page table.
const VSM_LOOKUP: LookupWgsl = LookupWgsl {
    enables: "",
    bindings: &[
        Binding::uniform("vsm", "VsmUniforms"),
        Binding::storage("vsm_faces", "array<VirtualFace>"),
        Binding::storage("vsm_table", "array<u32>"),
    ],
    source: || {
        format!(
            "{NO_RAYS}\n{VSM_TYPES}\n{VSM_COMMON}\n{}",
            include_str!("vsm_lookup.wgsl")
        )
    },
    features: wgpu::Features::empty(),
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
        settings: &SourceSettings<'_>,
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
            ..settings.options::<VirtualOptions>()
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

    fn marks_sampled_pairs(&self) -> bool {
        self.maps.sampled_pages()
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
                page_wants: inputs.page_wants,
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
        ShadowOutput {
            depth: &self.maps.pool_view,
            depth_side: self.maps.pool_side(),
            resources: vec![
                self.maps.uniforms().as_entire_binding(),
                self.maps.faces().as_entire_binding(),
                self.maps.table().as_entire_binding(),
            ],
            max_penumbra: super::plan::MAX_SOFT_PENUMBRA,
            ..ShadowOutput::from_views(&self.table.views, INFO.lookup)
        }
    }

    fn views_filled(&self) -> &[ShadowView] {
        &self.maps.plan.views
    }

    fn picture(&self, ctx: &GpuContext) -> Result<ShadowPicture, RenderError> {
        let (side, depth) = self.read_pool(ctx)?;
        Ok(ShadowPicture::of_pool(&depth, side, PAGE_SIZE))
    }

    fn read_atlas(&self, _ctx: &GpuContext) -> Result<Vec<f32>, RenderError> {
        Err(RenderError::NoAtlas {
            technique: INFO.technique,
            fills: INFO.fills,
        })
    }

    /// `VirtualStats` of the last submitted frame, read back.
    fn technique_stats(&self, ctx: &GpuContext) -> Result<Option<TechniqueStats>, RenderError> {
        Ok(Some(Box::new(self.maps.read_stats(ctx)?)))
    }
}

impl VirtualSource {
    /// The faces of the current frame and their page-table layout.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // Renderer::virtual_plan
    pub fn plan(&self) -> &VirtualPlan {
        &self.maps.plan
    }

    /// The page pool's side and its depth, read back.
    pub fn read_pool(&self, ctx: &GpuContext) -> Result<(u32, Vec<f32>), RenderError> {
        let side = self.maps.pool_side();
        Ok((side, read_depth_view(ctx, &self.maps.pool_view, side)?))
    }

    /// The page table as the last frame left it (one entry per page of every face's levels).
    pub fn read_table(&self, ctx: &GpuContext) -> Result<Vec<u32>, RenderError> {
        Ok(
            bytemuck::cast_slice(&crate::gpu::readback::read_buffer(ctx, self.maps.table())?)
                .to_vec(),
        )
    }
}

/// Virtual maps' report: the opening, the faces and the page table, the pages, how the
/// marking went by tiles, and the pages' drawing.
fn report(r: &ShadowReport<'_>) -> ShadowText {
    let mut lines = r.maps_opening();
    let Some(v) = r.own::<VirtualStats>() else {
        return ShadowText {
            lines,
            frame: format!("shadow GPU time {}", r.gpu_time(Stage::Shadows)),
        };
    };
    let fit = &v.fit;
    let prev = v.prev_table_bytes;
    lines.push(ReportLine::new(
        "virtual",
        format!(
            "{} faces of {} lights ({} off screen, no faces; {} faces needed by a sample, the rest get no pages), page table {} entries ({} KiB{}){}",
            fit.faces,
            fit.lights,
            fit.off_screen,
            v.faces_in_use,
            fit.table_entries,
            v.table_bytes / 1024,
            if prev > 0 {
                format!(", and {} KiB for last frame's, kept for caching", prev / 1024)
            } else {
                String::new()
            },
            if fit.capped_side > 0 {
                format!(", virtual sides capped at {}² to fit it", fit.capped_side)
            } else {
                String::new()
            }
        ),
    ));
    let per_level = |levels: &[u32]| {
        levels
            .iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join("/")
    };
    let mut tail = String::new();
    if v.denied > 0 {
        tail += &format!(
            "; {} pages did not fit the pool, their samples used coarser levels",
            v.denied
        );
    }
    if v.quarter_faces > 0 {
        tail += &format!(
            "; {} faces share pool pages four to one at half resolution (the pool has fewer \
             pages than faces in use)",
            v.quarter_faces
        );
    }
    if v.unshadowed_faces > 0 {
        tail += &format!(
            "; {} faces had no room even for a quarter page: unshadowed; raise --page-pool",
            v.unshadowed_faces
        );
    }
    lines.push(ReportLine::new(
        "pages",
        format!(
            "{} resident in a pool of {} ({} drawn, {} kept from the last frame; {}x{} texels, {} MiB); asked by samples per level (coarsest first) {} (with their ancestors {}){tail}",
            v.resident,
            v.pool_pages,
            v.drawn,
            v.kept,
            v.pool_side,
            v.pool_side,
            v.pool_bytes >> 20,
            per_level(&v.asked),
            per_level(&v.needed),
        ),
    ));
    let t = &v.tiles;
    if t.empty + t.one_page + t.known_page + t.per_pixel > 0 {
        lines.push(ReportLine::new(
            "marking",
            format!(
                "by 4x4-pixel tiles, (tile, light) pairs: {} need no page, {} one page marked once, {} a known page checked per pixel, {} marked per pixel ({} tiles whole)",
                t.empty, t.one_page, t.known_page, t.per_pixel, t.whole_tiles
            ),
        ));
    }
    // Pages are chosen, culled and drawn on the GPU: their counts are the pages line's.
    lines.push(ReportLine::new(
        "shadow work",
        format!(
            "{} pages drawn ({} kept from the last frame): {} (cluster, page) pairs past the \
             cluster cull, {} triangles drawn (culled per page on the GPU: clusters, then \
             triangles where the adapter counts draws)",
            v.drawn, v.kept, v.cluster_draws, v.triangles
        ),
    ));
    ShadowText {
        lines,
        frame: format!(
            "{:>4} of {} resident pages drawn ({} kept), shadow GPU time {}",
            v.drawn,
            v.resident,
            v.kept,
            r.gpu_time(Stage::Shadows)
        ),
    }
}
