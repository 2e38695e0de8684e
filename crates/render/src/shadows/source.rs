//! Where a frame's shadows come from: one [`ShadowSource`] per renderer, whatever the
//! technique.
//!
//! A source is told about the frame's changes ([`ShadowSource::update`] after the camera,
//! lights or instances changed, [`ShadowSource::note_moved`] for a moved caster), is handed the
//! renderer's buffers ([`ShadowSource::bind`]), records its work after the G-buffer and the
//! light clusters ([`ShadowSource::record`]) and checks it after submission
//! ([`ShadowSource::finish`]). What it leaves for the lighting and visibility passes is a
//! [`ShadowOutput`]: the view table, the depth texture to sample, the mask where the source
//! computed it, and the source's own lookup WGSL with its bindings. Nothing here names a
//! technique: what one counts of its own work is a [`TechniqueStats`] value of its type, and
//! what it reads of the settings beside the shared choices it finds by type in
//! [`SourceSettings`]. The registry (`crate::registry`) is the one place a technique becomes
//! a source.

use glam::Vec3;
use manyshadows_scene::atlas::FitPolicy;
use manyshadows_scene::light_space::{PointShadows, ShadowView};
use manyshadows_scene::Scene;

use crate::error::{RenderError, Technique};
use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::GBuffer;
use crate::frame::visibility_mask::VisibilityMask;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::GpuTimer;
use crate::gpu::types::LightData;
use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::instances::GpuScene;
use crate::shadows::image::ShadowPicture;
use crate::shadows::lookup::LookupWgsl;
use crate::shadows::options::ShadowOptions;
use crate::shadows::plan::ShadowPlan;
use crate::shadows::storage::ShadowAtlas;

/// Work counters of one shadow generation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub struct ShadowStats {
    /// Render or compute passes recorded.
    pub passes: u32,
    /// Draw calls recorded.
    pub draws: u64,
    /// (view, instance) pairs skipped by CPU frustum culling.
    pub culled: u64,
    /// Triangles submitted over all draws.
    pub triangles: u64,
    /// Views drawn (fewer than all when caching kept some tiles).
    pub views_drawn: u32,
    /// Views out of date but served from their older depth (a shadow budget left them).
    pub views_stale: u32,
    /// Frames since the oldest stale view went out of date (0 when none is).
    pub stale_frames: u32,
    /// Views with no depth yet, unshadowed until drawn (a shadow budget left them).
    pub views_waiting: u32,
}

/// The renderer's buffers a source may read (bound by [`ShadowSource::bind`]).
pub struct SourceInputs<'a> {
    /// The scene as this frame renders it.
    pub scene: &'a Scene,
    /// `FrameUniforms`.
    pub frame: &'a wgpu::Buffer,
    /// `array<LightData>` (what [`ShadowSource::light_data`] returned).
    pub lights: &'a wgpu::Buffer,
    /// The G-buffer (the camera's samples: irregular inserts them, virtual maps mark pages).
    pub gbuffer: &'a GBuffer,
    /// The light clusters (virtual maps mark pages of the lights a pixel's cluster lists).
    pub clusters: &'a LightClusters,
    /// Scene instances (`array<InstanceData>`).
    pub instances: &'a wgpu::Buffer,
    /// Where the sampled lights' choose pass notes the (pixel, light) pairs the frame asks
    /// about (`sampled::pages`), for a source that [marks only
    /// those](ShadowSource::marks_sampled_pairs).
    pub page_wants: Option<&'a wgpu::Buffer>,
}

/// What a source leaves for the lighting and visibility passes: the view table, the depth
/// texture they sample (the atlas, a page pool, or a 1×1 placeholder), the mask where the
/// source computed it, and its lookup: the WGSL that finds a point's shadow ([`LookupWgsl`],
/// which declares its bindings) and those bindings' resources.
#[derive(Clone)]
pub struct ShadowOutput<'a> {
    /// `array<ShadowViewData>`.
    pub view_table: &'a wgpu::Buffer,
    /// The depth texture shadows are read from.
    pub depth: &'a wgpu::TextureView,
    /// Side of [`ShadowOutput::depth`] in texels (the frame uniforms' `counts.z`).
    pub depth_side: u32,
    /// The visibility of every (pixel, light) pair, `counts.w` words of light bits per pixel,
    /// where the source computed it itself (the passes then shade with it directly).
    pub mask: Option<&'a wgpu::Buffer>,
    /// The source's WGSL for the passes.
    pub lookup: LookupWgsl,
    /// The resources of [`LookupWgsl::bindings`], in their order.
    pub resources: Vec<wgpu::BindingResource<'a>>,
    /// The widest penumbra radius, in texels, the lookup's soft filter reads at one level
    /// (what `SoftShadows::max_penumbra` is clamped to for it; unbounded for the atlas).
    pub max_penumbra: f32,
}

impl<'a> ShadowOutput<'a> {
    /// The output of a source read through `views`' table and depth texture with `lookup`
    /// and no bindings of its own.
    pub fn from_views(views: &'a ShadowAtlas, lookup: LookupWgsl) -> Self {
        ShadowOutput {
            view_table: &views.views_buffer,
            depth: &views.view,
            depth_side: views.size,
            mask: None,
            lookup,
            resources: Vec::new(),
            max_penumbra: f32::INFINITY,
        }
    }
}

/// What every source keeps of the frame's views: the plan, the atlas (or a view table with a
/// placeholder texture) and the world-space caster geometry.
#[derive(Clone, Copy)]
pub struct Views<'a> {
    /// The shadow views and their layout.
    pub plan: &'a ShadowPlan,
    /// The atlas or view table.
    pub atlas: &'a ShadowAtlas,
    /// The caster geometry.
    pub casters: &'a CasterGeometry,
}

/// Makes a frame's shadows: fills an atlas, a page pool or a visibility mask. The renderer
/// drives every source the same way; see the [module](self) for the order of calls.
pub trait ShadowSource: std::any::Any {
    /// The plan, the atlas (or view table) and the caster geometry the source keeps.
    fn views(&self) -> Views<'_>;

    /// The shadow views and atlas layout (no views for sources that lay out their own, such
    /// as virtual maps' faces; [`ShadowSource::view_count`] counts those).
    fn plan(&self) -> &ShadowPlan {
        self.views().plan
    }

    /// The atlas, or for sources that fill none the view table with a 1×1 placeholder
    /// texture.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // Renderer::atlas, internals only
    fn atlas(&self) -> &ShadowAtlas {
        self.views().atlas
    }

    /// The world-space shadow-caster geometry.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // Renderer::casters, internals only
    fn casters(&self) -> &CasterGeometry {
        self.views().casters
    }

    /// The per-light records of the lights buffer, as this source's shadows are read.
    fn light_data(&self, scene: &Scene) -> Vec<LightData>;

    /// Re-plans for `scene` after its camera, lights or instances changed: new views, caster
    /// culling re-decided, buffers rewritten in place (grown when needed). Followed by
    /// [`ShadowSource::bind`].
    fn update(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), RenderError>;

    /// Whether, given [`SourceInputs::page_wants`], the source makes shadows only for the
    /// (pixel, light) pairs noted there (virtual maps' pages) instead of for every light that
    /// reaches a pixel.
    fn marks_sampled_pairs(&self) -> bool {
        false
    }

    /// Takes the renderer's buffers (after creation and after every update, since the
    /// renderer may have replaced one).
    fn bind(&mut self, ctx: &GpuContext, inputs: &SourceInputs<'_>) -> Result<(), RenderError>;

    /// A shadow caster's bounding sphere went from `old` to `new` (centre, radius): what it
    /// shadowed must be redrawn by the next frame (sources that keep work between frames).
    fn note_moved(&mut self, _old: (Vec3, f32), _new: (Vec3, f32)) {}

    /// Mesh `mesh`'s vertices became `positions` (a skinned mesh bent; the renderer also
    /// notes each of its instances' spheres as moved): sources that keep a mesh's geometry of
    /// their own (ray tracing's bottom-level structures) take the new positions.
    fn note_deformed(&mut self, _ctx: &GpuContext, _mesh: usize, _positions: &[Vec3]) {}

    /// Mesh `mesh` is bent on the GPU before the next frame draws, its vertices `bytes`
    /// (first byte, length) into the scene's positions (gpu_scene/deform.rs): sources that
    /// keep a mesh's geometry of their own copy it from there.
    fn note_deformed_on_gpu(&mut self, _mesh: usize, _bytes: (u64, u64)) {}

    /// Records the frame's shadow work after the G-buffer and clusters, opening its own timer
    /// spans (`shadows`, and `pages` before it for virtual maps).
    fn record(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> ShadowStats;

    /// After the frame's submission: checks the work (irregular's node pool; waits for the
    /// frame). A frame whose shadows went wrong is an error here.
    fn finish(&mut self, _ctx: &GpuContext) -> Result<(), RenderError> {
        Ok(())
    }

    /// What the lighting and visibility passes read (valid once the source is bound).
    fn output(&self) -> ShadowOutput<'_>;

    /// Reads the depth atlas back (`size`² floats, row-major);
    /// [`RenderError::NoAtlas`] for sources that fill no atlas.
    fn read_atlas(&self, ctx: &GpuContext) -> Result<Vec<f32>, RenderError>;

    /// Reads the visibility mask back, for a source whose output is the mask (`None`
    /// otherwise: the visibility pass computes it from the output).
    fn read_mask(&self, _ctx: &GpuContext) -> Result<Option<VisibilityMask>, RenderError> {
        Ok(None)
    }

    /// Shadow views of the current plan: every atlas tile, or every face of a source that
    /// lays out views of its own (a spot light's frustum, a cube face, a cascade).
    fn view_count(&self) -> usize {
        self.views_filled().len()
    }

    /// The views whose casters the source draws or lists: the plan's (atlas tiles, irregular
    /// light views), a source's own faces (virtual maps), or none (rays).
    fn views_filled(&self) -> &[ShadowView] {
        &self.plan().views
    }

    /// Whether it fills the plan's atlas tiles (the plan's layout is then the atlas's).
    fn fills_atlas(&self) -> bool {
        false
    }

    /// The technique's own counters of the last frame (virtual maps' pages, irregular maps'
    /// lists), for a caller that knows the technique to downcast (`None` where it keeps
    /// none). Sources that count on the GPU read them back here.
    fn technique_stats(&self, _ctx: &GpuContext) -> Result<Option<TechniqueStats>, RenderError> {
        Ok(None)
    }

    /// A picture of what the source keeps of its shadows (its atlas, its page pool);
    /// [`RenderError::NoAtlas`] for a source that keeps no map.
    fn picture(&self, ctx: &GpuContext) -> Result<ShadowPicture, RenderError>;
}

/// A technique's own counters ([`ShadowSource::technique_stats`]): one value whose type the
/// technique defines (`VirtualStats`, `IrregularStats`).
pub type TechniqueStats = Box<dyn std::any::Any + Send + Sync>;

/// A technique's own options, as `RenderSettings` holds them for it: any type that checks its
/// own ranges. The built-in techniques' have fields of their own in `RenderSettings`
/// (`irregular`, `virtual_maps`, `rays`); a technique added beside them brings its options
/// with `RenderSettings::with_technique_options`, and its source finds them by type
/// ([`SourceSettings::options`]), so the settings are not edited for it.
pub trait TechniqueOptions: std::any::Any + std::fmt::Debug + Send + Sync {
    /// Checks every value that has a range of its own ([`RenderError::InvalidOption`] names
    /// the first one out of range).
    fn validate(&self) -> Result<(), RenderError>;

    /// The options as `Any`, to be found by type.
    fn as_any(&self) -> &(dyn std::any::Any + Send + Sync);
}

/// What a source reads of the frame's settings: the choices every source honours and, for
/// each technique, its own options, found by type ([`SourceSettings::options`]).
/// `RenderSettings::source_settings` makes it.
#[derive(Clone)]
pub struct SourceSettings<'a> {
    /// The technique.
    pub technique: Technique,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Culling and caster options.
    pub shadow: ShadowOptions,
    /// Keep what did not change between frames.
    pub cache_shadows: bool,
    /// Most shadow views drawn per frame (atlas techniques).
    pub shadow_budget: Option<u32>,
    /// The hard visibility mask is asked for too.
    pub visibility: bool,
    /// Point-light shadows: cube faces or paraboloids.
    pub point_shadows: PointShadows,
    /// What to do when the shadow maps do not fit the atlas.
    pub fit: FitPolicy,
    /// Every technique's own options.
    pub options: Vec<&'a (dyn std::any::Any + Send + Sync)>,
}

impl SourceSettings<'_> {
    /// The options of type `T` (a technique's own, such as `VirtualOptions`), or their
    /// defaults where the settings hold none.
    pub fn options<T: std::any::Any + Default + Clone>(&self) -> T {
        self.options
            .iter()
            .find_map(|o| o.downcast_ref::<T>())
            .cloned()
            .unwrap_or_default()
    }
}

/// How shadow views are planned for a frame (what [`ShadowPlan::with_points`] needs beside the
/// scene).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PlanParams {
    pub aspect: f32,
    pub max_atlas: u32,
    pub fit: FitPolicy,
    pub point_shadows: PointShadows,
}

impl PlanParams {
    pub fn new(settings: &SourceSettings<'_>, max_atlas: u32) -> Self {
        Self {
            aspect: settings.width as f32 / settings.height as f32,
            max_atlas,
            fit: settings.fit,
            point_shadows: settings.point_shadows,
        }
    }

    /// The views and atlas layout of `scene`.
    pub fn plan(&self, scene: &Scene) -> Result<ShadowPlan, RenderError> {
        ShadowPlan::with_points(
            scene,
            self.aspect,
            self.max_atlas,
            self.fit,
            self.point_shadows,
        )
    }
}

/// The plan's view table and the caster geometry without an atlas to fill: what the sources
/// that read views but fill no atlas (irregular, virtual) keep.
pub(crate) struct ViewTable {
    pub plan: ShadowPlan,
    pub views: ShadowAtlas,
    pub casters: CasterGeometry,
}

impl ViewTable {
    /// The table as a source's [`Views`].
    pub fn views(&self) -> Views<'_> {
        Views {
            plan: &self.plan,
            atlas: &self.views,
            casters: &self.casters,
        }
    }

    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        plan: ShadowPlan,
        settings: &SourceSettings<'_>,
    ) -> Result<Self, RenderError> {
        Ok(Self {
            views: ShadowAtlas::views_only(ctx, &plan)?,
            casters: CasterGeometry::new(ctx, scene, gpu, settings.shadow.casters)?,
            plan,
        })
    }

    /// Takes a new frame's plan and re-decides caster culling; true if the caster geometry
    /// changed.
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        plan: ShadowPlan,
    ) -> Result<bool, RenderError> {
        let casters_changed = self.casters.refresh(ctx, scene);
        self.views.update(ctx, &plan)?;
        self.plan = plan;
        Ok(casters_changed)
    }
}
