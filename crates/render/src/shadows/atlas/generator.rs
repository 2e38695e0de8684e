//! Shadow generation on its own: the plan, the atlas, the caster geometry and a technique,
//! with optional caching of unchanged views across frames. [`crate::Renderer`] uses it for
//! frames; benchmarks and equivalence tests use it without the rest of the frame.
//!
//! Caching (seed 004's remark that static lights over static geometry need not be redrawn):
//! a view is redrawn when it has never been drawn, or when a shadow caster moved
//! ([`ShadowGenerator::note_moved`]) and its old or new bounding sphere touches the view's
//! frustum. Other tiles keep their depth; the technique clears and redraws only the listed
//! tiles. Skinned scenes redraw everything (every vertex may move).

use glam::Vec3;
use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::instances::GpuScene;
use crate::settings::{ShadowOptions, Technique};
use crate::shadows::atlas::storage::ShadowAtlas;
use crate::shadows::atlas::technique::{ShadowInput, ShadowTechnique};
use crate::shadows::plan::ShadowPlan;
use crate::shadows::source::ShadowStats;
use crate::{GpuContext, RenderError};

/// Everything needed to fill the atlas, frame after frame.
pub struct ShadowGenerator {
    /// Views and atlas layout.
    pub plan: ShadowPlan,
    /// The atlas.
    pub atlas: ShadowAtlas,
    /// World-space caster geometry.
    pub casters: CasterGeometry,
    /// Options in use.
    pub options: ShadowOptions,
    technique: Box<dyn ShadowTechnique>,
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // benchmarks and tests
    kind: Technique,
    caching: bool,
    valid: Vec<bool>,
    moves: Vec<[(Vec3, f32); 2]>,
}

impl ShadowGenerator {
    /// Creates the atlas, caster buffers and the technique's pipelines for `plan`.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        plan: ShadowPlan,
        technique: Technique,
        options: ShadowOptions,
    ) -> Result<Self, RenderError> {
        let paraboloid = plan.views.iter().any(|v| {
            matches!(
                v.kind,
                manyshadows_scene::light_space::ViewKind::Paraboloid(_)
            )
        });
        if paraboloid {
            technique
                .info()
                .check_point_shadows(PointShadows::DualParaboloid)?;
        }
        if paraboloid && !ctx.has(wgpu::Features::CLIP_DISTANCES) {
            return Err(RenderError::missing_feature(
                ctx,
                "dual-paraboloid shadows",
                "the CLIP_DISTANCES feature (to clip triangles at the hemisphere's base)",
                "use cube point shadows",
            ));
        }
        if paraboloid && gpu.skin.is_some() {
            return Err(RenderError::NotImplemented {
                what: "dual-paraboloid shadows of skinned scenes",
                instead: "use cube point shadows",
            });
        }
        let atlas = ShadowAtlas::new(ctx, &plan)?;
        let casters = CasterGeometry::new(ctx, scene, gpu, options.casters)?;
        let valid = vec![false; plan.views.len()];
        Ok(Self {
            technique: technique.create(ctx)?,
            kind: technique,
            plan,
            atlas,
            casters,
            options,
            caching: false,
            valid,
            moves: Vec::new(),
        })
    }

    /// The technique.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // benchmarks and tests
    pub fn technique(&self) -> Technique {
        self.kind
    }

    /// Keeps tiles of unchanged views from one generation to the next (off by default).
    pub fn set_caching(&mut self, on: bool) {
        self.caching = on;
    }

    /// Records that a shadow caster's bounding sphere went from `old` to `new` (centre,
    /// radius); views that see either are redrawn by the next generation.
    pub fn note_moved(&mut self, old: (Vec3, f32), new: (Vec3, f32)) {
        self.moves.push([old, new]);
    }

    /// Replaces the plan with a new frame's (camera or lights changed). The atlas buffers are
    /// rewritten in place; with caching, a view keeps its tile's depth only if the same view
    /// of the same light (same view-projection) lands on the same tile and the caster geometry
    /// did not change (`casters_changed`). Returns true if an atlas buffer or the texture was
    /// replaced (bind groups holding them must be rebuilt).
    pub fn set_plan(
        &mut self,
        ctx: &GpuContext,
        plan: ShadowPlan,
        casters_changed: bool,
    ) -> Result<bool, RenderError> {
        let replaced = self.atlas.update(ctx, &plan)?;
        let old: std::collections::HashMap<_, _> = self
            .plan
            .views
            .iter()
            .zip(&self.plan.layout.tiles)
            .zip(&self.valid)
            .filter(|(_, &valid)| valid)
            .map(|((v, t), _)| ((v.light, v.kind), (v.view_proj, *t)))
            .collect();
        self.valid = plan
            .views
            .iter()
            .zip(&plan.layout.tiles)
            .map(|(v, t)| {
                !casters_changed
                    && !replaced
                    && old.get(&(v.light, v.kind)) == Some(&(v.view_proj, *t))
            })
            .collect();
        self.plan = plan;
        Ok(replaced)
    }

    /// The views the next generation draws.
    fn draw_list(&mut self, gpu: &GpuScene) -> Vec<u32> {
        let n = self.plan.views.len();
        if !self.caching || gpu.skin.is_some() {
            self.moves.clear();
            self.valid.iter_mut().for_each(|v| *v = true);
            return (0..n as u32).collect();
        }
        let moves = std::mem::take(&mut self.moves);
        let mut list = Vec::new();
        for (i, view) in self.plan.views.iter().enumerate() {
            let dirty = !self.valid[i]
                || moves
                    .iter()
                    .any(|m| m.iter().any(|&(c, r)| view.sphere_visible(c, r)));
            if dirty {
                list.push(i as u32);
                self.valid[i] = true;
            }
        }
        list
    }

    /// Records one generation into `encoder`; `span` times it.
    pub fn generate(
        &mut self,
        ctx: &GpuContext,
        gpu: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &GpuTimer,
        span: Option<Span>,
    ) -> ShadowStats {
        let list = self.draw_list(gpu);
        if !list.is_empty() {
            ctx.queue
                .write_buffer(&self.atlas.draw_list, 0, bytemuck::cast_slice(&list));
        }
        let input = ShadowInput {
            ctx,
            scene: gpu,
            views: &self.plan.views,
            atlas: &self.atlas,
            casters: &self.casters,
            options: &self.options,
            draw_list: &list,
        };
        let mut stats = self.technique.generate(&input, encoder, timer, span);
        stats.views_drawn = list.len() as u32;
        stats
    }

    /// Reads the depth atlas back (`size`² floats, row-major).
    pub fn read_atlas(&self, ctx: &GpuContext) -> Result<Vec<f32>, RenderError> {
        ctx.scoped("reading the shadow atlas", || {
            crate::shadows::image::read_depth(ctx, &self.atlas)
        })
    }
}
