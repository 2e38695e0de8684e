//! The shadow plan: every shadow view of a frame and its tile of the atlas, and the priority
//! fit that decides which lights keep full-size maps when they do not all fit
//! ([`FitPolicy::Prioritize`]: tile sides by importance, then unshadowed lights).
//!
//! The unit of work is a *shadow view*: a view-projection plus a square tile of one depth
//! atlas ([`manyshadows_scene::light_space::ShadowView`] + [`manyshadows_scene::atlas::Tile`]).
//! Tiles may differ in size per light (the remedy seed 000 §19.6 names for the equal-size
//! limit of texture arrays). A technique fills every view's tile; the lighting pass reads them.

use manyshadows_scene::atlas::{self, AtlasLayout, FitPolicy};
use manyshadows_scene::light_space::{self, PointShadows, ShadowView, ViewKind};
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::gpu::types::{LightData, ShadowViewData};

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
        // Reflection probes see all around them: with probes no light is off screen.
        if let Some((c, r)) = scene.lights[light]
            .bounding_sphere()
            .filter(|_| scene.probes.is_empty())
        {
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
        let views = light_space::shadow_views_with(scene, aspect, points);
        Self::from_views(scene, aspect, views, max_atlas, fit)
    }

    /// [`ShadowPlan::with_points`] over views already computed by
    /// `light_space::shadow_views_with` for the same scene and aspect (virtual maps' plan
    /// has them: it fits the atlas plan only to know each view's tile).
    pub(crate) fn from_views(
        scene: &Scene,
        aspect: f32,
        mut views: Vec<ShadowView>,
        max_atlas: u32,
        fit: FitPolicy,
    ) -> Result<Self, RenderError> {
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
