//! Where a frame's shadows come from: one [`ShadowSource`] per renderer, whatever the
//! technique.
//!
//! A source is told about the frame's changes ([`ShadowSource::update`] after the camera,
//! lights or instances changed, [`ShadowSource::note_moved`] for a moved caster), is handed the
//! renderer's buffers ([`ShadowSource::bind`]), records its work after the G-buffer and the
//! light clusters ([`ShadowSource::record`]) and checks it after submission
//! ([`ShadowSource::finish`]). What it leaves for the lighting and visibility passes is a
//! [`ShadowOutput`]:
//!
//! - [`ShadowOutput::Atlas`]: a depth atlas with every view's tile and the view table
//!   (`traditional`, `layered`, `multiview`, `gpu-driven`, `compute`:
//!   [`crate::shadows::atlas::source::AtlasSource`]);
//! - [`ShadowOutput::Pages`]: a virtual page pool and its page table (`virtual`:
//!   [`crate::shadows::vsm::source::VirtualSource`]);
//! - [`ShadowOutput::Mask`]: the per-pixel, per-light visibility bits themselves
//!   (`irregular`: [`crate::shadows::irregular::source::IrregularSource`]).
//!
//! `shadows::create` is the one place a [`crate::Technique`] becomes a source.

use glam::Vec3;
use manyshadows_scene::atlas::FitPolicy;
use manyshadows_scene::light_space::PointShadows;
use manyshadows_scene::Scene;

use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::GBuffer;
use crate::frame::visibility_mask::VisibilityMask;
use crate::gpu::timing::GpuTimer;
use crate::gpu::types::LightData;
use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::instances::GpuScene;
use crate::settings::RenderSettings;
use crate::shadows::atlas::storage::ShadowAtlas;
use crate::shadows::plan::ShadowPlan;
use crate::{GpuContext, RenderError};

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
}

/// A virtual page pool and its page table.
#[derive(Clone, Copy)]
pub struct PagePool<'a> {
    /// Depth view of the pool.
    pub pool: &'a wgpu::TextureView,
    /// Side of the pool in texels.
    pub side: u32,
    /// `VsmUniforms`.
    pub uniforms: &'a wgpu::Buffer,
    /// `array<VirtualFace>`.
    pub faces: &'a wgpu::Buffer,
    /// The page table.
    pub table: &'a wgpu::Buffer,
}

/// The ray-traced scene the lighting and visibility passes cast shadow rays into.
#[derive(Clone, Copy)]
pub struct RayScene<'a> {
    /// The top-level acceleration structure of the shadow casters.
    pub tlas: &'a wgpu::Tlas,
    /// Per instance and masked triangle what the alpha test reads, then the mask tail.
    pub geometry: &'a wgpu::Buffer,
    /// `RayParams` (samples per pixel, seed).
    pub params: &'a wgpu::Buffer,
}

/// What a source leaves for the lighting and visibility passes. Every kind carries a view
/// table (`array<ShadowViewData>`, empty for virtual maps, whose faces are in the page table)
/// and a depth texture to bind (a 1×1 placeholder where shadows are not read from one).
#[derive(Clone, Copy)]
pub enum ShadowOutput<'a> {
    /// A depth atlas: every view's tile, found through the atlas's view table.
    Atlas(&'a ShadowAtlas),
    /// Virtual shadow maps: resident pages in a pool; `views` holds the view table.
    Pages {
        /// Pool and page table.
        pages: PagePool<'a>,
        /// View table and placeholder texture.
        views: &'a ShadowAtlas,
    },
    /// Shadow rays through the scene's acceleration structure, cast by the lighting and
    /// visibility passes themselves.
    Rays {
        /// The acceleration structure, its ray geometry and the sampling parameters.
        rays: RayScene<'a>,
        /// View table and placeholder texture.
        views: &'a ShadowAtlas,
    },
    /// The visibility of every (pixel, light) pair: `counts.w` words of light bits per pixel.
    Mask {
        /// The mask.
        mask: &'a wgpu::Buffer,
        /// View table and placeholder texture.
        views: &'a ShadowAtlas,
    },
}

impl<'a> ShadowOutput<'a> {
    /// The atlas, or the view table with its placeholder texture.
    fn views(&self) -> &'a ShadowAtlas {
        match *self {
            ShadowOutput::Atlas(a) => a,
            ShadowOutput::Pages { views, .. }
            | ShadowOutput::Mask { views, .. }
            | ShadowOutput::Rays { views, .. } => views,
        }
    }

    /// `array<ShadowViewData>`.
    pub fn view_table(&self) -> &'a wgpu::Buffer {
        &self.views().views_buffer
    }

    /// The depth texture shadows are read from: the atlas or the page pool (a placeholder for
    /// a mask).
    pub fn depth(&self) -> &'a wgpu::TextureView {
        match *self {
            ShadowOutput::Pages { pages, .. } => pages.pool,
            _ => &self.views().view,
        }
    }

    /// Side of [`ShadowOutput::depth`] in texels (the frame uniforms' `counts.z`).
    pub fn depth_side(&self) -> u32 {
        match *self {
            ShadowOutput::Pages { pages, .. } => pages.side,
            _ => self.views().size,
        }
    }

    /// How the lighting and visibility shaders find shadows, their extra declarations from
    /// binding `first` on.
    pub(crate) fn shader_source(&self, first: u32) -> crate::gpu::shaders::ShadowSource {
        match self {
            ShadowOutput::Pages { .. } => crate::gpu::shaders::ShadowSource::Virtual { first },
            ShadowOutput::Rays { .. } => crate::gpu::shaders::ShadowSource::Rays { first },
            _ => crate::gpu::shaders::ShadowSource::Atlas,
        }
    }

    /// Layout entries of the extra declarations at `first` .. (the page table, or the rays).
    pub(crate) fn extra_layout(
        &self,
        first: u32,
        visibility: wgpu::ShaderStages,
    ) -> Vec<wgpu::BindGroupLayoutEntry> {
        use crate::gpu::pipelines::{storage_entry, uniform_entry};
        match self {
            ShadowOutput::Pages { .. } => vec![
                uniform_entry(first, visibility),
                storage_entry(first + 1, visibility),
                storage_entry(first + 2, visibility),
            ],
            ShadowOutput::Rays { .. } => vec![
                wgpu::BindGroupLayoutEntry {
                    binding: first,
                    visibility,
                    ty: wgpu::BindingType::AccelerationStructure {
                        vertex_return: false,
                    },
                    count: None,
                },
                storage_entry(first + 1, visibility),
                uniform_entry(first + 2, visibility),
            ],
            _ => Vec::new(),
        }
    }

    /// Bind-group entries of the extra declarations at `first` ...
    pub(crate) fn extra_entries(&self, first: u32) -> Vec<wgpu::BindGroupEntry<'a>> {
        match *self {
            ShadowOutput::Pages { pages, .. } => vec![
                wgpu::BindGroupEntry {
                    binding: first,
                    resource: pages.uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: first + 1,
                    resource: pages.faces.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: first + 2,
                    resource: pages.table.as_entire_binding(),
                },
            ],
            ShadowOutput::Rays { rays, .. } => vec![
                wgpu::BindGroupEntry {
                    binding: first,
                    resource: rays.tlas.as_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: first + 1,
                    resource: rays.geometry.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: first + 2,
                    resource: rays.params.as_entire_binding(),
                },
            ],
            _ => Vec::new(),
        }
    }

    /// The visibility mask, if the source computed it.
    pub fn mask(&self) -> Option<&'a wgpu::Buffer> {
        match *self {
            ShadowOutput::Mask { mask, .. } => Some(mask),
            _ => None,
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
pub trait ShadowSource {
    /// The plan, the atlas (or view table) and the caster geometry the source keeps.
    fn views(&self) -> Views<'_>;

    /// The shadow views and atlas layout (no views for virtual maps, whose faces are in
    /// [`ShadowSource::virtual_plan`]).
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

    /// Takes the renderer's buffers (after creation and after every update, since the
    /// renderer may have replaced one).
    fn bind(&mut self, ctx: &GpuContext, inputs: &SourceInputs<'_>) -> Result<(), RenderError>;

    /// A shadow caster's bounding sphere went from `old` to `new` (centre, radius): what it
    /// shadowed must be redrawn by the next frame (sources that keep work between frames).
    fn note_moved(&mut self, _old: (Vec3, f32), _new: (Vec3, f32)) {}

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

    /// Counters of the last finished frame of irregular shadow maps.
    fn irregular_stats(&self) -> Option<crate::shadows::irregular::maps::IrregularStats> {
        None
    }

    /// The faces of virtual shadow maps.
    fn virtual_plan(&self) -> Option<&crate::shadows::vsm::plan::VirtualPlan> {
        None
    }

    /// Reads the counters of the last submitted frame of virtual shadow maps.
    fn read_virtual_stats(
        &self,
        _ctx: &GpuContext,
    ) -> Result<Option<crate::shadows::vsm::plan::VirtualStats>, RenderError> {
        Ok(None)
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
    pub fn new(settings: &RenderSettings, max_atlas: u32) -> Self {
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
        settings: &RenderSettings,
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
