//! Shadow storage and the interface every shadow-generation technique implements.
//!
//! The unit of work is a *shadow view*: a view-projection plus a square tile of one depth
//! atlas ([`manyshadows_scene::light_space::ShadowView`] + [`manyshadows_scene::atlas::Tile`]).
//! Tiles may differ in size per light (the remedy seed 000 §19.6 names for the equal-size
//! limit of texture arrays). A technique fills every view's tile; the lighting pass reads them.

use manyshadows_scene::atlas::{self, AtlasLayout, FitPolicy, Tile};
use manyshadows_scene::light_space::{self, PointShadows, ShadowView, ViewKind};
use manyshadows_scene::Scene;

use crate::gpu_scene::casters::CasterGeometry;
use crate::gpu_scene::instances::GpuScene;
use crate::gpu::types::{LightData, ShadowViewData, ViewUniform, VIEW_UNIFORM_STRIDE};
use crate::gpu::timing::{GpuTimer, Span};
use crate::settings::{ShadowOptions, Technique, IRREGULAR_NO_ATLAS, VIRTUAL_NO_ATLAS};
use crate::{GpuContext, RenderError};

/// Largest atlas side the renderer uses by default (256 MiB of depth), further clamped to the
/// adapter's `max_texture_dimension_2d`.
pub const DEFAULT_MAX_ATLAS_SIZE: u32 = 8192;

/// Every shadow view of a scene and its place in the atlas.
#[derive(Clone, Debug)]
pub struct ShadowPlan {
    /// All views, grouped by light in light order.
    pub views: Vec<ShadowView>,
    /// The atlas layout: one tile per view.
    pub layout: AtlasLayout,
    /// Per light: `(first view, view count)`; count 0 for lights without shadows.
    pub light_views: Vec<(u32, u32)>,
    /// How the maps were fitted into the atlas.
    pub fit: FitReport,
}

/// How the shadow maps of a plan were fitted into the atlas (see [`FitPolicy::Prioritize`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FitReport {
    /// Shadow-casting lights whose maps have the requested resolution.
    pub full: usize,
    /// Shadow-casting lights whose maps were made smaller to fit.
    pub reduced: usize,
    /// Shadow-casting lights left unshadowed for lack of atlas room (the least important).
    pub unshadowed: usize,
    /// Shadow-casting lights that reach nothing the camera sees, so need no maps.
    pub off_screen: usize,
}

/// Importance of a light for the shadow budget: the tangent of the half-angle its reach
/// subtends at the camera (infinite for directional lights and lights around the camera).
pub(crate) fn light_importance(scene: &Scene, light: usize) -> f32 {
    match scene.lights[light].bounding_sphere() {
        None => f32::INFINITY,
        Some((c, r)) => {
            let d = (c - scene.camera.position).length();
            if d <= r {
                f32::INFINITY
            } else {
                r / (d - r)
            }
        }
    }
}

/// [`FitPolicy::Prioritize`]: the views to keep and their tile sides (powers of two).
fn prioritize(
    scene: &Scene,
    aspect: f32,
    views: Vec<ShadowView>,
    max_atlas: u32,
) -> (Vec<ShadowView>, Vec<u32>, FitReport) {
    let max_side = 1u64 << (31 - max_atlas.max(1).leading_zeros());
    let min = u64::from(atlas::MIN_TILE).min(max_side);
    let cam = &scene.camera;
    let planes = light_space::frustum_planes(cam.projection(aspect) * cam.view());
    let mut report = FitReport::default();
    // Per light with views: (light, first view, end, importance, tile sides).
    struct Group {
        light: usize,
        range: std::ops::Range<usize>,
        importance: f32,
        sides: Vec<u64>,
        kept: bool,
    }
    let mut groups = Vec::new();
    let mut i = 0;
    while i < views.len() {
        let light = views[i].light;
        let n = views[i..].iter().take_while(|v| v.light == light).count();
        let range = i..i + n;
        i += n;
        if let Some((c, r)) = scene.lights[light].bounding_sphere() {
            if !light_space::sphere_in_planes(&planes, c, r * 1.001 + 1e-4) {
                report.off_screen += 1;
                continue;
            }
        }
        let sides = views[range.clone()]
            .iter()
            .map(|v| {
                u64::from(v.resolution.max(atlas::MIN_TILE))
                    .next_power_of_two()
                    .min(max_side)
            })
            .collect();
        groups.push(Group {
            light,
            importance: light_importance(scene, light),
            range,
            sides,
            kept: true,
        });
    }
    let requested: Vec<Vec<u64>> = groups.iter().map(|g| g.sides.clone()).collect();
    let area = |g: &Group| g.sides.iter().map(|s| s * s).sum::<u64>();
    let budget = max_side * max_side;
    let mut total: u64 = groups.iter().map(area).sum();
    // Least important first; among equals the later light gives way.
    let mut order: Vec<usize> = (0..groups.len()).collect();
    order.sort_by(|&a, &b| {
        groups[a]
            .importance
            .total_cmp(&groups[b].importance)
            .then(groups[b].light.cmp(&groups[a].light))
    });
    // Tile sides proportional to importance (as a virtual shadow map gives texels by screen
    // size): side = k · importance rounded down to a power of two, clamped to the floor and the
    // request; k is the largest that fits, found by bisection on its logarithm.
    let sides_for = |k: f64, groups: &mut Vec<Group>| -> u64 {
        let mut total = 0;
        for (g, want) in groups.iter_mut().zip(&requested) {
            let target = k * f64::from(g.importance);
            for (s, &w) in g.sides.iter_mut().zip(want) {
                *s = if target >= w as f64 {
                    w
                } else if target <= min as f64 {
                    min.min(w)
                } else {
                    (1u64 << (63 - (target as u64).leading_zeros())).clamp(min.min(w), w)
                };
                total += *s * *s;
            }
        }
        total
    };
    if total > budget {
        let (mut lo, mut hi) = (-30.0f64, 60.0f64);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if sides_for(mid.exp2(), &mut groups) <= budget {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        total = sides_for(lo.exp2(), &mut groups);
        // Spend what rounding left over on the most important lights.
        for &g in order.iter().rev() {
            for (side, &want) in groups[g].sides.iter_mut().zip(&requested[g]) {
                while *side < want && total + 3 * *side * *side <= budget {
                    total += 3 * *side * *side;
                    *side *= 2;
                }
            }
        }
    }
    // Lights that matter infinitely (directional, or around the camera) may still not fit:
    // halve one light at a time, least important first, until the maps fit or are all at the
    // floor.
    while total > budget {
        let mut progressed = false;
        for &g in &order {
            let group = &mut groups[g];
            if group.sides.iter().all(|&s| s <= min) {
                continue;
            }
            let before = area(group);
            for s in &mut group.sides {
                *s = (*s / 2).max(min);
            }
            total = total - before + area(group);
            progressed = true;
            if total <= budget {
                break;
            }
        }
        if !progressed {
            break;
        }
    }
    // Then leave the least important lights unshadowed.
    for &g in &order {
        if total <= budget {
            break;
        }
        total -= area(&groups[g]);
        groups[g].kept = false;
        report.unshadowed += 1;
    }
    let mut kept_views = Vec::new();
    let mut sides = Vec::new();
    for (g, want) in groups.iter().zip(&requested) {
        if !g.kept {
            continue;
        }
        if g.sides == *want {
            report.full += 1;
        } else {
            report.reduced += 1;
        }
        kept_views.extend_from_slice(&views[g.range.clone()]);
        sides.extend(g.sides.iter().map(|&s| s as u32));
    }
    (kept_views, sides, report)
}

impl ShadowPlan {
    /// Computes the views of every shadow-casting light and packs their tiles.
    pub fn new(
        scene: &Scene,
        aspect: f32,
        max_atlas: u32,
        fit: FitPolicy,
    ) -> Result<Self, RenderError> {
        Self::with_points(scene, aspect, max_atlas, fit, PointShadows::Cube)
    }

    /// [`ShadowPlan::new`] with a choice of point-light shadows (cube or dual paraboloid).
    pub fn with_points(
        scene: &Scene,
        aspect: f32,
        max_atlas: u32,
        fit: FitPolicy,
        points: PointShadows,
    ) -> Result<Self, RenderError> {
        let mut views = light_space::shadow_views_with(scene, aspect, points);
        let mut requests: Vec<u32> = views.iter().map(|v| v.resolution).collect();
        let shadowed = views
            .iter()
            .enumerate()
            .filter(|(i, v)| *i == 0 || views[i - 1].light != v.light)
            .count();
        let mut fit_report = FitReport {
            full: shadowed,
            ..Default::default()
        };
        if fit == FitPolicy::Prioritize
            && !requests.is_empty()
            && atlas::layout(&requests, max_atlas, FitPolicy::Strict).is_err()
        {
            let (kept, sides, report) = prioritize(scene, aspect, views, max_atlas);
            views = kept;
            requests = sides;
            fit_report = report;
            log::info!(
                "shadow maps do not fit a {max_atlas}² atlas: {} lights at full resolution, {} \
                 reduced, {} unshadowed, {} off screen (no maps needed)",
                report.full,
                report.reduced,
                report.unshadowed,
                report.off_screen
            );
        }
        let layout = if requests.is_empty() {
            AtlasLayout {
                size: atlas::MIN_TILE,
                tiles: Vec::new(),
                shrink_steps: 0,
            }
        } else {
            atlas::layout(&requests, max_atlas, fit)?
        };
        if layout.shrink_steps > 0 {
            log::warn!(
                "shadow maps shrunk {}x ({}x smaller per side) to fit a {}² atlas",
                layout.shrink_steps,
                1u32 << layout.shrink_steps,
                layout.size
            );
        }
        let mut light_views = vec![(0u32, 0u32); scene.lights.len()];
        let mut i = 0;
        while i < views.len() {
            let light = views[i].light;
            let n = views[i..].iter().take_while(|v| v.light == light).count();
            light_views[light] = (i as u32, n as u32);
            i += n;
        }
        Ok(Self {
            views,
            layout,
            light_views,
            fit: fit_report,
        })
    }

    /// A plan without shadow views (techniques that plan their own: `virtual`).
    pub fn none(lights: usize) -> Self {
        Self {
            views: Vec::new(),
            layout: AtlasLayout {
                size: atlas::MIN_TILE,
                tiles: Vec::new(),
                shrink_steps: 0,
            },
            light_views: vec![(0, 0); lights],
            fit: FitReport::default(),
        }
    }

    /// GPU records of the views with their tiles.
    pub fn view_data(&self) -> Vec<ShadowViewData> {
        self.views
            .iter()
            .zip(&self.layout.tiles)
            .map(|(v, t)| {
                // The view was planned for `v.resolution` texels; a shrunk tile has fewer, so a
                // texel covers proportionally more of the world.
                let texel_world = v.texel_world * v.resolution as f32 / t.size as f32;
                ShadowViewData {
                    view_proj: v.view_proj.to_cols_array_2d(),
                    tile: [t.x as f32, t.y as f32, t.size as f32, 0.0],
                    params: [
                        v.near,
                        v.far,
                        texel_world,
                        match v.kind {
                            ViewKind::Paraboloid(_) => 2.0,
                            _ if v.orthographic => 1.0,
                            _ => 0.0,
                        },
                    ],
                }
            })
            .collect()
    }

    /// GPU records of the scene's lights.
    pub fn light_data(&self, scene: &Scene) -> Vec<LightData> {
        scene
            .lights
            .iter()
            .zip(&self.light_views)
            .map(|(l, &(first, n))| {
                LightData::new(l, first, &self.views[first as usize..(first + n) as usize])
            })
            .collect()
    }

    /// Texels covered by tiles / texels in the atlas.
    pub fn fill(&self) -> f64 {
        let used: u64 = self
            .layout
            .tiles
            .iter()
            .map(|t| t.size as u64 * t.size as u64)
            .sum();
        used as f64 / (self.layout.size as u64 * self.layout.size as u64) as f64
    }
}

/// The depth atlas and the per-view data techniques read.
pub struct ShadowAtlas {
    /// Depth32Float, `size`².
    pub texture: wgpu::Texture,
    /// Depth view of the whole atlas.
    pub view: wgpu::TextureView,
    /// Side in texels.
    pub size: u32,
    /// `array<ShadowViewData>` (storage; at least one element).
    pub views_buffer: wgpu::Buffer,
    /// One [`ViewUniform`] per view at [`VIEW_UNIFORM_STRIDE`] (dynamic uniform offsets).
    pub view_uniforms: wgpu::Buffer,
    /// Tiles in view order.
    pub tiles: Vec<Tile>,
    /// `array<vec4<f32>>` per view, what back-face culling faces: the light's position
    /// (w = 1) or, for orthographic views, the direction light travels (w = 0).
    pub eyes: wgpu::Buffer,
    /// `array<u32>`: the views a generation draws (see [`ShadowInput::draw_list`]).
    pub draw_list: wgpu::Buffer,
}

/// What back-face culling of `view` faces: `(position, 1)` or `(direction of travel, 0)`.
pub fn view_eye(view: &ShadowView) -> glam::Vec4 {
    let inv = view.view.inverse();
    if view.orthographic {
        inv.transform_vector3(glam::Vec3::NEG_Z)
            .normalize_or_zero()
            .extend(0.0)
    } else {
        inv.w_axis.truncate().extend(1.0)
    }
}

impl ShadowAtlas {
    /// Creates the atlas texture and view buffers for `plan`.
    pub fn new(ctx: &GpuContext, plan: &ShadowPlan) -> Result<Self, RenderError> {
        Self::with_size(ctx, plan, plan.layout.size)
    }

    /// The view buffers of `plan` with a 1×1 placeholder texture: for `irregular`, which
    /// reads the views but fills no tiles.
    pub fn views_only(ctx: &GpuContext, plan: &ShadowPlan) -> Result<Self, RenderError> {
        Self::with_size(ctx, plan, 1)
    }

    fn with_size(ctx: &GpuContext, plan: &ShadowPlan, size: u32) -> Result<Self, RenderError> {
        let (texture, view) = atlas_texture(ctx, size);
        let placeholder = |label: &str, usage: wgpu::BufferUsages| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let mut atlas = Self {
            texture,
            view,
            size,
            views_buffer: placeholder("shadow.views", wgpu::BufferUsages::STORAGE),
            view_uniforms: placeholder("shadow.view_uniforms", wgpu::BufferUsages::UNIFORM),
            tiles: Vec::new(),
            eyes: placeholder("shadow.eyes", wgpu::BufferUsages::STORAGE),
            draw_list: placeholder("shadow.draw_list", wgpu::BufferUsages::STORAGE),
        };
        atlas.write_views(ctx, plan)?;
        Ok(atlas)
    }

    /// Makes the atlas hold `plan` (a new frame's views): view buffers are rewritten in place
    /// (replaced only when the plan has more views than they hold), the texture only when the
    /// atlas side changed. Returns true if a buffer or the texture was replaced, so bind groups
    /// that hold them must be rebuilt.
    pub fn update(&mut self, ctx: &GpuContext, plan: &ShadowPlan) -> Result<bool, RenderError> {
        let mut replaced = false;
        // A views-only atlas keeps its 1×1 placeholder.
        if self.size != 1 && self.size != plan.layout.size {
            (self.texture, self.view) = atlas_texture(ctx, plan.layout.size);
            self.size = plan.layout.size;
            replaced = true;
        }
        Ok(replaced | self.write_views(ctx, plan)?)
    }

    /// Writes the per-view buffers of `plan`, growing them if needed (true if any grew).
    fn write_views(&mut self, ctx: &GpuContext, plan: &ShadowPlan) -> Result<bool, RenderError> {
        let mut data = plan.view_data();
        let uniforms: Vec<ViewUniform> = data
            .iter()
            .map(|d| ViewUniform {
                view_proj: d.view_proj,
                params: d.params,
                _pad: [[0.0; 4]; 11],
            })
            .collect();
        if data.is_empty() {
            data.push(bytemuck::Zeroable::zeroed());
        }
        let mut uniform_bytes: Vec<u8> = bytemuck::cast_slice(&uniforms).to_vec();
        if uniform_bytes.is_empty() {
            uniform_bytes.resize(VIEW_UNIFORM_STRIDE as usize, 0);
        }
        let mut eyes: Vec<[f32; 4]> = plan.views.iter().map(|v| view_eye(v).to_array()).collect();
        eyes.resize(eyes.len().max(1), [0.0; 4]);
        let all: Vec<u32> = (0..plan.views.len().max(1) as u32).collect();
        let mut grew = crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.views_buffer,
            data_bytes(&data),
            "shadow views",
        )?;
        grew |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.view_uniforms,
            uniform_bytes.len() as u64,
            "shadow view uniforms",
        )?;
        grew |= crate::gpu::buffers::grow_buffer(ctx, &mut self.eyes, data_bytes(&eyes), "shadow view eyes")?;
        grew |= crate::gpu::buffers::grow_buffer(
            ctx,
            &mut self.draw_list,
            data_bytes(&all),
            "shadow draw list",
        )?;
        ctx.queue
            .write_buffer(&self.views_buffer, 0, bytemuck::cast_slice(&data));
        ctx.queue
            .write_buffer(&self.view_uniforms, 0, &uniform_bytes);
        ctx.queue
            .write_buffer(&self.eyes, 0, bytemuck::cast_slice(&eyes));
        ctx.queue
            .write_buffer(&self.draw_list, 0, bytemuck::cast_slice(&all));
        self.tiles = plan.layout.tiles.clone();
        Ok(grew)
    }
}

fn data_bytes<T>(v: &[T]) -> u64 {
    std::mem::size_of_val(v) as u64
}

/// A `size`² depth atlas texture and its view.
fn atlas_texture(ctx: &GpuContext, size: u32) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = crate::gpu::pipelines::depth_texture(&ctx.device, "shadow.atlas", size, 1);
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("shadow.atlas.view"),
        dimension: Some(wgpu::TextureViewDimension::D2),
        ..Default::default()
    });
    (texture, view)
}

/// What a technique is given to fill the atlas.
pub struct ShadowInput<'a> {
    /// GPU context.
    pub ctx: &'a GpuContext,
    /// Scene buffers.
    pub scene: &'a GpuScene,
    /// Views to fill (same order as the atlas tiles).
    pub views: &'a [ShadowView],
    /// The atlas to fill.
    pub atlas: &'a ShadowAtlas,
    /// World-space caster geometry (techniques that use it record its transform).
    pub casters: &'a CasterGeometry,
    /// Culling and raster options.
    pub options: &'a ShadowOptions,
    /// The views to draw this time, ascending (all of them unless caching kept some);
    /// also uploaded to [`ShadowAtlas::draw_list`].
    pub draw_list: &'a [u32],
}

impl ShadowInput<'_> {
    /// True if every view is drawn: the whole atlas may be cleared at once. Otherwise only the
    /// listed views' tiles may be touched.
    pub fn full(&self) -> bool {
        self.draw_list.len() == self.views.len()
    }
}

/// Work counters of one shadow generation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
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
}

/// One generation as a technique records it: what to draw and where to record it.
pub struct Generation<'a> {
    /// The views, atlas and geometry; `input.draw_list` is never empty here.
    pub input: &'a ShadowInput<'a>,
    /// The encoder the passes are recorded into.
    pub encoder: &'a mut wgpu::CommandEncoder,
    /// Timestamp and pipeline-statistics queries.
    pub timer: &'a GpuTimer,
    /// The timer span of the generation's passes.
    pub span: Option<Span>,
}

/// A shadow-generation technique: fills every view's tile of the atlas with depth. Its name
/// is [`Technique::name`] of the [`Technique`] that created it.
pub trait ShadowTechnique {
    /// Records the generation of a non-empty draw list (see [`ShadowTechnique::generate`],
    /// which calls it).
    fn record(&mut self, generation: Generation<'_>) -> ShadowStats;

    /// Records the generation into `encoder`; `span` is the timer span for its passes. An
    /// empty draw list records nothing. Techniques keep their uniform buffers and bind groups
    /// across generations and rewrite the uniforms with `Queue::write_buffer`, so submit each
    /// generation before recording the next one.
    fn generate(
        &mut self,
        input: &ShadowInput<'_>,
        encoder: &mut wgpu::CommandEncoder,
        timer: &GpuTimer,
        span: Option<Span>,
    ) -> ShadowStats {
        if input.draw_list.is_empty() {
            return ShadowStats::default();
        }
        self.record(Generation {
            input,
            encoder,
            timer,
            span,
        })
    }
}

/// Per-view CPU culling shared by techniques that draw instance by instance: the shadow
/// casters whose bounding sphere touches the view's frustum.
pub fn visible_casters<'a>(
    scene: &'a GpuScene,
    view: &ShadowView,
) -> impl Iterator<Item = &'a crate::gpu_scene::instances::DrawItem> + 'a {
    let view = *view;
    scene
        .draws
        .iter()
        .filter(move |d| d.casts_shadows && view.sphere_visible(d.sphere.0, d.sphere.1))
}

impl Technique {
    /// Builds the technique's pipelines; fails with a clear message where the adapter lacks
    /// a feature the technique needs.
    pub fn create(
        self,
        ctx: &GpuContext,
        options: &ShadowOptions,
    ) -> Result<Box<dyn ShadowTechnique>, RenderError> {
        let _ = options;
        Ok(match self {
            Technique::Traditional => {
                Box::new(crate::techniques::traditional::Traditional::new(ctx))
            }
            Technique::Layered => Box::new(crate::techniques::layered::Layered::new(ctx)?),
            Technique::Multiview => Box::new(crate::techniques::multiview::Multiview::new(ctx)?),
            Technique::GpuDriven => Box::new(crate::techniques::gpu_driven::GpuDriven::new(ctx)?),
            Technique::Compute => Box::new(crate::techniques::compute::Compute::new(ctx)?),
            Technique::Irregular => {
                return Err(RenderError::NoAtlas {
                    technique: Technique::Irregular,
                    detail: IRREGULAR_NO_ATLAS.into(),
                })
            }
            Technique::Virtual => {
                return Err(RenderError::NoAtlas {
                    technique: Technique::Virtual,
                    detail: VIRTUAL_NO_ATLAS.into(),
                })
            }
        })
    }
}
