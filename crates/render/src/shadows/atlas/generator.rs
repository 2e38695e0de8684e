//! Shadow generation on its own: the plan, the atlas, the caster geometry and a technique,
//! with optional caching of unchanged views across frames. [`crate::Renderer`] uses it for
//! frames; benchmarks and equivalence tests use it without the rest of the frame.
//!
//! Caching (seed 004's remark that static lights over static geometry need not be redrawn):
//! a view is redrawn when it has never been drawn, or when a shadow caster moved
//! ([`ShadowGenerator::note_moved`]) and its old or new bounding sphere touches the view's
//! frustum. Other tiles keep their depth; the technique clears and redraws only the listed
//! tiles. Skinned scenes redraw everything (every vertex may move).
//!
//! A shadow budget ([`ShadowGenerator::set_budget`]) caps the views drawn per frame. Views
//! wait their turn by priority: a view whose tile holds nothing of it (new, or moved to
//! another tile) before one whose tile holds its own older depth, larger tiles (the plan's
//! nearer and more important views) first, then the longest waiting. A waiting view with its
//! own older depth is served from it (stale, its age counted); one with none gets no shadow
//! until drawn (its tile is marked empty for the lookups, counted as waiting). Once nothing
//! changes, every view is drawn within `ceil(views / budget)` frames and the frame equals an
//! unbudgeted one.

use glam::Vec3;
use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::error::Technique;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::instances::GpuScene;
use crate::shadows::descriptor::TechniqueInfo;
use crate::shadows::options::ShadowOptions;
use crate::shadows::plan::ShadowPlan;
use crate::shadows::source::ShadowStats;
use crate::shadows::storage::ShadowAtlas;
use crate::shadows::technique::{ShadowInput, ShadowTechnique};

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
    /// Per view of the plan: what its tile holds.
    state: Vec<TileState>,
    moves: Vec<[(Vec3, f32); 2]>,
    budget: Option<u32>,
    /// Generations so far (the clock of [`TileState::Stale`]).
    frame: u64,
    /// Views whose tiles were marked empty for the lookups at the last generation.
    waiting: Vec<u32>,
}

/// What a view's tile holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TileState {
    /// The view's current depth.
    Current,
    /// The view's depth from before a change, out of date since generation `since`.
    Stale { since: u64 },
    /// Nothing of this view (never drawn here).
    Empty,
}

impl ShadowGenerator {
    /// Creates the atlas, caster buffers and the technique's pipelines for `plan`.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        plan: ShadowPlan,
        technique: &'static TechniqueInfo,
        options: ShadowOptions,
    ) -> Result<Self, RenderError> {
        let paraboloid = plan.views.iter().any(|v| {
            matches!(
                v.kind,
                manyshadows_scene::light_space::ViewKind::Paraboloid(_)
            )
        });
        if paraboloid {
            technique.check_point_shadows(PointShadows::DualParaboloid)?;
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
        let state = vec![TileState::Empty; plan.views.len()];
        Ok(Self {
            technique: technique.create_atlas(ctx)?,
            kind: technique.technique,
            plan,
            atlas,
            casters,
            options,
            caching: false,
            state,
            moves: Vec::new(),
            budget: None,
            frame: 0,
            waiting: Vec::new(),
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

    /// Draws at most `budget` views per generation (with caching; `None`: every changed view).
    pub fn set_budget(&mut self, budget: Option<u32>) {
        self.budget = budget.map(|b| b.max(1));
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
        // The old tiles' contents by view; a changed view on the same tile still holds its
        // own older depth (stale), another tile holds nothing of it.
        let old: std::collections::HashMap<_, _> = self
            .plan
            .views
            .iter()
            .zip(&self.plan.layout.tiles)
            .zip(&self.state)
            .filter(|(_, &state)| state != TileState::Empty)
            .map(|((v, t), &state)| ((v.light, v.kind), (v.view_proj, *t, state)))
            .collect();
        let now = self.frame;
        self.state = plan
            .views
            .iter()
            .zip(&plan.layout.tiles)
            .map(|(v, t)| match old.get(&(v.light, v.kind)) {
                Some(&(view_proj, tile, state)) if !replaced && tile == *t => {
                    if view_proj == v.view_proj && !casters_changed {
                        state
                    } else if let TileState::Stale { since } = state {
                        TileState::Stale { since }
                    } else {
                        TileState::Stale { since: now }
                    }
                }
                _ => TileState::Empty,
            })
            .collect();
        self.plan = plan;
        // The views buffer was rewritten whole: no tile is marked empty any more.
        self.waiting.clear();
        Ok(replaced)
    }

    /// The views the next generation draws (ascending), and the counts of the views left
    /// waiting.
    fn draw_list(&mut self, gpu: &GpuScene) -> (Vec<u32>, Waiting) {
        let n = self.plan.views.len();
        self.frame += 1;
        if !self.caching || gpu.skin.is_some() {
            self.moves.clear();
            self.state.iter_mut().for_each(|v| *v = TileState::Current);
            return ((0..n as u32).collect(), Waiting::default());
        }
        let moves = std::mem::take(&mut self.moves);
        let now = self.frame;
        for (view, state) in self.plan.views.iter().zip(&mut self.state) {
            if *state == TileState::Current
                && moves
                    .iter()
                    .any(|m| m.iter().any(|&(c, r)| view.sphere_visible(c, r)))
            {
                *state = TileState::Stale { since: now };
            }
        }
        let mut list: Vec<u32> = (0..n as u32)
            .filter(|&i| self.state[i as usize] != TileState::Current)
            .collect();
        if let Some(budget) = self.budget.filter(|&b| list.len() > b as usize) {
            let tiles = &self.plan.layout.tiles;
            let state = &self.state;
            // Empty tiles first, larger tiles first, the longest waiting first, view order.
            list.sort_by_key(|&i| {
                let (empty, since) = match state[i as usize] {
                    TileState::Empty => (0, 0),
                    TileState::Stale { since } => (1, since),
                    TileState::Current => (2, 0),
                };
                (empty, std::cmp::Reverse(tiles[i as usize].size), since, i)
            });
            list.truncate(budget as usize);
            list.sort_unstable();
        }
        for &i in &list {
            self.state[i as usize] = TileState::Current;
        }
        let mut waiting = Waiting::default();
        for (i, state) in self.state.iter().enumerate() {
            match *state {
                TileState::Current => {}
                TileState::Stale { since } => {
                    waiting.stale += 1;
                    waiting.oldest = waiting.oldest.max((now - since) as u32);
                }
                TileState::Empty => waiting.empty.push(i as u32),
            }
        }
        (list, waiting)
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
        let (list, waiting) = self.draw_list(gpu);
        if !list.is_empty() {
            ctx.queue
                .write_buffer(&self.atlas.draw_list, 0, bytemuck::cast_slice(&list));
        }
        if waiting.empty != self.waiting {
            // Tiles that hold nothing of their view yet read as "no shadow information".
            self.atlas.write_view_data(ctx, &self.plan, &waiting.empty);
            self.waiting = waiting.empty.clone();
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
        stats.views_stale = waiting.stale;
        stats.stale_frames = waiting.oldest;
        stats.views_waiting = waiting.empty.len() as u32;
        stats
    }

    /// Reads the depth atlas back (`size`² floats, row-major).
    pub fn read_atlas(&self, ctx: &GpuContext) -> Result<Vec<f32>, RenderError> {
        ctx.scoped("reading the shadow atlas", || {
            crate::shadows::image::read_depth(ctx, &self.atlas)
        })
    }
}

/// The views a budgeted generation left for later.
#[derive(Debug, Default)]
struct Waiting {
    /// Views served from their own older depth.
    stale: u32,
    /// Generations since the oldest of them went out of date.
    oldest: u32,
    /// Views whose tiles hold nothing of them yet (no shadow until drawn).
    empty: Vec<u32>,
}
