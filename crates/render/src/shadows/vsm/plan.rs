//! The faces of virtual shadow maps and their page-table layout ([`VirtualPlan`]), the knobs
//! ([`VirtualOptions`]), the pool's size and the counters of a frame ([`VirtualStats`]).

use manyshadows_scene::light_space::{self, PointShadows, ShadowView};
use manyshadows_scene::Scene;

use crate::error::RenderError;
use crate::gpu::types::LightData;
use crate::shadows::vsm::types::VirtualFace;

/// Level and page selection, shared by the page marking and the lookups.
pub const VSM_COMMON: &str = include_str!("vsm_common.wgsl");

/// Side of a page in texels.
pub const PAGE_SIZE: u32 = 128;

/// The widest penumbra radius in texels a sized light's soft filter reads at one level:
/// the page marking asks for the pages at the four corners of the taps' reach (this and a
/// texel around the sample), which are all the pages the reach touches while it spans at most
/// a page (63 + 1 texels each way of 128). `SoftShadows::max_penumbra` is clamped to it here;
/// wider penumbrae are filtered at coarser levels.
pub const MAX_SOFT_PENUMBRA: f32 = (PAGE_SIZE / 2 - 1) as f32;
/// Levels a face can have (level 7 of 128² pages is 16,384² texels).
pub const MAX_LEVELS: u32 = 8;
/// Largest virtual side of a face.
pub const MAX_SIDE: u32 = PAGE_SIZE << (MAX_LEVELS - 1);
/// Default page-pool budget: 256 MiB of 32-bit depth (an 8192² pool of 4096 pages).
pub const DEFAULT_POOL_BYTES: u64 = 256 << 20;
/// [`VirtualFace::dirty`] of a face where no caster moved (min > max).
pub const NOTHING_MOVED: [f32; 4] = [1.0, 1.0, 0.0, 0.0];
/// Default cap on page-table entries (4 bytes each).
pub const DEFAULT_TABLE_ENTRIES: u32 = 4 << 20;
/// Default shadow texels per screen pixel of virtual maps ([`VirtualOptions::lod`]).
pub const DEFAULT_LOD: f32 = 1.0;
/// Default factor on [`DEFAULT_LOD`] for spot and directional lights' faces
/// ([`VirtualOptions::directed_lod`]).
pub const DEFAULT_DIRECTED_LOD: f32 = 0.8;
/// Default receiver-bias scale of virtual maps ([`VirtualOptions::bias_scale`]).
pub const DEFAULT_BIAS_SCALE: f32 = 0.5;
/// Knobs of the virtual shadow maps.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct VirtualOptions {
    /// Page-pool budget in bytes: the pool is the largest square of whole 128² pages of
    /// 32-bit depth that fits it (512 MiB: 11,520², 8,100 pages, 506 MiB), at most the
    /// adapter's largest 2D texture; [`VirtualStats::pool_bytes`] says what was used.
    pub pool_bytes: u64,
    /// Largest virtual side of a face (a power of two, 128 to 16,384).
    pub max_side: u32,
    /// Shadow texels wanted per screen pixel (default 1, `DEFAULT_LOD`: no texel wider
    /// than the pixel footprint) by point lights' cube faces, and, times
    /// [`Self::directed_lod`], by spot and directional lights' faces. Lower values draw fewer
    /// pages and misclassify more where pixels are wide (docs/techniques.md, "Virtual shadow
    /// maps (`--technique virtual`)").
    pub lod: f32,
    /// Factor on [`Self::lod`] for the faces of spot and directional lights (default 0.8,
    /// `DEFAULT_DIRECTED_LOD`: their texels up to 1.25 pixels). Coarser texels cost point
    /// lights' cube faces most of their extra errors (walls near the lights seen through wide
    /// pixels) and spot and directional faces few, so they alone get them; 1 gives every face
    /// `lod`.
    pub directed_lod: f32,
    /// The receiver bias of virtual maps as a fraction of [`crate::ShadowBias`] (which
    /// counts texels; default 0.5, `DEFAULT_BIAS_SCALE`). A page's texels match the screen
    /// pixel, not a fixed atlas tile, so a whole texel of bias per term moves samples further
    /// than the texel's depth steps need and leaks light at contacts (docs/decisions.md,
    /// "Receiver-side bias, not rasterizer depth bias", has the measurements).
    pub bias_scale: f32,
    /// Cap on page-table entries: when the faces' tables would exceed it, the largest
    /// virtual sides are halved until they fit (reported in `VirtualFit::capped_side`).
    pub max_table_entries: u32,
    /// Mark pages for samples that face away from a light too (what the visibility mask
    /// reads; the lighting pass does not need them).
    pub back_facing: bool,
    /// Cull caster clusters against a page by groups of 16 first (a merged bounding sphere
    /// per group, then the group's clusters only where it is inside the page). `false` tests
    /// every cluster against every page: the same clusters are drawn either way; for
    /// measuring what the groups save.
    pub group_cull: bool,
    /// Receiver bounds: the marking pass keeps, per asked page, the largest depth its samples
    /// compare against and the rectangle of the page their filter taps reach (in cells of a
    /// sixteenth of the page side); casters wholly beyond that depth cannot shadow any of them
    /// and are culled, and the page is cleared, culled and drawn over that rectangle only.
    /// With shadow caching a page is kept only while its samples stay within the bounds it was
    /// drawn with (after a renderer's first frame, when the camera or lights changed, they get
    /// room to spare: a cell more on each side, an eighth deeper). The same shadows either
    /// way; `false` for measuring.
    pub receiver_cull: bool,
    /// Bytes of the index buffer one round of page drawing expands its triangles into, where
    /// the adapter counts draws on the GPU (`MULTI_DRAW_INDIRECT_COUNT`): default 24 MiB (2 M
    /// triangles), at most the device's buffer limits and at least one triangle (smaller values, 0
    /// included, are raised to it). When a round's triangles exceed it, the
    /// (cluster, page) pairs past it are drawn whole: the same shadows, more work.
    pub expand_bytes: u64,
    /// Mark pages by tiles of 4 x 4 pixels (default): where the bounds of a tile's samples
    /// (positions, view depths, normals) prove that every sample needing a page of a light
    /// needs the same one, that page is marked once (or, when only some samples may need it,
    /// each pixel checks only whether it does), and the rest is marked per pixel. The pages
    /// asked are exactly those of per-pixel marking, so the shadows are the same; receiver
    /// bounds of pages marked once are their tile's, a little wider. `false` marks every
    /// (pixel, light) pair: for measuring and for tests. Off as well where the device's
    /// storage bindings cannot hold the hand-off list (8 bytes per tile and up).
    pub tile_marking: bool,
    /// No face samples coarser than the tile the atlas techniques give the same view (the
    /// default atlas, fitted by importance): virtual maps are then never coarser than the
    /// atlas where the atlas is finer than the screen asks (few lights, small frames), so they
    /// misclassify no more than it does (docs/techniques.md, "Virtual shadow maps (`--technique
    /// virtual`)", has the table). Default on; off asks only what the screen's level of
    /// detail asks.
    pub atlas_floor: bool,
    /// With sampled lights (`RayOptions::light_samples` > 0): mark only the pages of the
    /// (pixel, light) pairs the frame's samples ask about (the lights drawn, those the
    /// reservoirs keep; `sampled::pages`) instead of every light that reaches a pixel. Default
    /// on; off marks every light's pages (the same shadows where the samples look: for
    /// measuring and tests).
    pub sampled_pages: bool,
    /// With [`Self::sampled_pages`]: frames a page stays resident after the last sample that
    /// asked for it (asked again with no sample asking; 0 to 64, default 8). The samples change
    /// every frame (new draws, stratified over frames where they are denoised), so without
    /// this a page a pixel asks for every few frames is drawn anew each time it is asked
    /// (the churn); lights no pixel sampled in that long draw nothing.
    pub sampled_keep_frames: u32,
}

/// [`VirtualOptions::sampled_keep_frames`]' default: about the frames over which a pixel's
/// denoised samples visit its lights (measured: docs/techniques.md, "Pages for the sampled
/// pairs").
pub const DEFAULT_SAMPLED_KEEP_FRAMES: u32 = 8;

/// The most frames [`VirtualOptions::sampled_keep_frames`] allows.
pub const MAX_SAMPLED_KEEP_FRAMES: u32 = 64;

impl Default for VirtualOptions {
    fn default() -> Self {
        Self {
            pool_bytes: DEFAULT_POOL_BYTES,
            max_side: MAX_SIDE,
            lod: DEFAULT_LOD,
            directed_lod: DEFAULT_DIRECTED_LOD,
            bias_scale: DEFAULT_BIAS_SCALE,
            max_table_entries: DEFAULT_TABLE_ENTRIES,
            back_facing: false,
            group_cull: true,
            receiver_cull: true,
            expand_bytes: 24 << 20,
            tile_marking: true,
            atlas_floor: true,
            sampled_pages: true,
            sampled_keep_frames: DEFAULT_SAMPLED_KEEP_FRAMES,
        }
    }
}

impl VirtualOptions {
    /// Bytes of one page of the pool (32-bit depth): the smallest pool.
    pub const PAGE_BYTES: u64 = PAGE_SIZE as u64 * PAGE_SIZE as u64 * 4;

    /// Checks every value that has a range of its own ([`RenderError::InvalidOption`] names
    /// the first one out of range, as `RenderSettings` names the field).
    pub fn validate(&self) -> Result<(), RenderError> {
        let page_bytes = Self::PAGE_BYTES;
        if self.pool_bytes < page_bytes {
            return Err(RenderError::invalid_option(
                "virtual_maps.pool_bytes",
                self.pool_bytes,
                "at least one 128x128 page of 32-bit depth (65,536 bytes)",
            ));
        }
        if !(self.lod.is_finite() && self.lod > 0.0) {
            return Err(RenderError::invalid_option(
                "virtual_maps.lod",
                self.lod,
                "a positive number of shadow texels per pixel",
            ));
        }
        if !(self.directed_lod.is_finite() && self.directed_lod > 0.0) {
            return Err(RenderError::invalid_option(
                "virtual_maps.directed_lod",
                self.directed_lod,
                "a positive factor on virtual_maps.lod",
            ));
        }
        if !(self.bias_scale.is_finite() && (0.0..=16.0).contains(&self.bias_scale)) {
            return Err(RenderError::invalid_option(
                "virtual_maps.bias_scale",
                self.bias_scale,
                "a fraction of the shadow bias from 0 to 16",
            ));
        }
        if self.sampled_keep_frames > MAX_SAMPLED_KEEP_FRAMES {
            return Err(RenderError::invalid_option(
                "virtual_maps.sampled_keep_frames",
                self.sampled_keep_frames,
                "0 to 64 frames",
            ));
        }
        if self.max_side == 0 {
            return Err(RenderError::invalid_option(
                "virtual_maps.max_side",
                0,
                "a virtual side of 128 to 16,384 texels (rounded to a power of two)",
            ));
        }
        Ok(())
    }
}

/// How the faces of a [`VirtualPlan`] were laid out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct VirtualFit {
    /// Shadow-casting lights with faces.
    pub lights: usize,
    /// Faces (spot views, cube faces, cascades).
    pub faces: usize,
    /// Shadow-casting lights that reach nothing the camera sees (no faces).
    pub off_screen: usize,
    /// Page-table entries over all faces.
    pub table_entries: u32,
    /// The virtual side every face was capped to so the page table fits
    /// [`VirtualOptions::max_table_entries`]; 0 if none was.
    pub capped_side: u32,
}

/// The faces of a frame and their page-table layout.
#[derive(Clone, Debug)]
pub struct VirtualPlan {
    /// Every face's shadow view, grouped by light in light order.
    pub views: Vec<ShadowView>,
    /// Per light: `(first face, face count)`; count 0 without shadows or off screen.
    pub light_views: Vec<(u32, u32)>,
    /// GPU records of the faces.
    pub faces: Vec<VirtualFace>,
    /// Layout summary.
    pub fit: VirtualFit,
}

/// Shadow texels per screen pixel that `light`'s faces aim for (`VirtualFace::detail`).
pub fn face_lod(light: &manyshadows_scene::Light, options: &VirtualOptions) -> f32 {
    match light.kind {
        manyshadows_scene::LightKind::Point { .. } => options.lod,
        _ => options.lod * options.directed_lod,
    }
}

/// Page-table entries of a face of virtual side `side`: `(4^(L+1) − 1) / 3` for
/// `L = log2(side / PAGE_SIZE)`.
pub fn table_entries(side: u32) -> u32 {
    let levels = (side / PAGE_SIZE).max(1).trailing_zeros() + 1;
    ((1u32 << (2 * levels)) - 1) / 3
}

impl VirtualPlan {
    /// Faces for every shadow-casting light that reaches the camera's view of `scene`
    /// (`aspect` = width / height, `height` in pixels).
    pub fn new(scene: &Scene, aspect: f32, height: u32, options: &VirtualOptions) -> Self {
        let max_side = options
            .max_side
            .clamp(PAGE_SIZE, MAX_SIDE)
            .next_power_of_two()
            .min(MAX_SIDE);
        let all = light_space::shadow_views_with(scene, aspect, PointShadows::Cube);
        let cam = &scene.camera;
        let proj = cam.projection(aspect);
        let planes = light_space::frustum_planes(proj * cam.view());
        let p11 = proj.y_axis.y;
        let mut fit = VirtualFit::default();
        let mut views = Vec::new();
        let mut sides = Vec::new();
        let mut lods = Vec::new();
        let mut light_views = vec![(0u32, 0u32); scene.lights.len()];
        let mut floors = Vec::new();
        // Whether each face is a spot light's (their floors take the atlas's whole bias).
        let mut spots = Vec::new();
        // The tiles the atlas techniques give the same views (the default atlas, fitted by
        // importance): no face samples coarser than its tile, so that virtual maps are never
        // coarser than the atlas where the atlas is finer than the screen asks (few lights,
        // small frames: docs/techniques.md, "Virtual shadow maps (`--technique virtual`)",
        // "Never coarser than the atlas").
        let atlas = options
            .atlas_floor
            .then(|| {
                crate::shadows::plan::ShadowPlan::from_views(
                    scene,
                    aspect,
                    all.clone(),
                    crate::shadows::plan::DEFAULT_MAX_ATLAS_SIZE,
                    manyshadows_scene::atlas::FitPolicy::Prioritize,
                )
                .ok()
            })
            .flatten();
        let mut i = 0;
        while i < all.len() {
            let light = all[i].light;
            let n = all[i..].iter().take_while(|v| v.light == light).count();
            let group = &all[i..i + n];
            i += n;
            if let Some((c, r)) = scene.lights[light].bounding_sphere() {
                if !light_space::sphere_in_planes(&planes, c, r * 1.001 + 1e-4) {
                    fit.off_screen += 1;
                    continue;
                }
            }
            let importance = crate::shadows::plan::light_importance(scene, light);
            let lod = face_lod(&scene.lights[light], options);
            light_views[light] = (views.len() as u32, n as u32);
            fit.lights += 1;
            let tiles: Vec<u32> = atlas
                .as_ref()
                .map(|a| {
                    let (first, count) = a.light_views[light];
                    if count as usize == n {
                        let f = first as usize;
                        a.layout.tiles[f..f + n].iter().map(|t| t.size).collect()
                    } else {
                        Vec::new()
                    }
                })
                .unwrap_or_default();
            for (k, v) in group.iter().enumerate() {
                let tile = tiles.get(k).copied().unwrap_or(0);
                // A texel at distance r from the light spans 2·tan(half angle)·r / side; a
                // pixel at camera distance D spans 2·D / (P11·height). Points in reach have
                // r / D <= importance, so this side gives every one a texel no larger than
                // its pixel (times the level-of-detail scale).
                let side = if v.orthographic || !importance.is_finite() {
                    max_side
                } else {
                    let tan_half = 1.0 / v.proj.x_axis.x.abs().max(1e-6);
                    let want = tan_half * p11 * height as f32 * lod * importance;
                    if want.is_finite() && want < max_side as f32 {
                        (want.ceil().max(1.0) as u32)
                            .next_power_of_two()
                            .clamp(PAGE_SIZE, max_side)
                    } else {
                        max_side
                    }
                };
                // As fine as the atlas's tile at least (its texels span the same view).
                let side = if tile > 0 {
                    side.max(tile.next_power_of_two().clamp(PAGE_SIZE, max_side))
                } else {
                    side
                };
                views.push(*v);
                sides.push(side);
                lods.push(lod);
                floors.push(tile);
                spots.push(matches!(
                    scene.lights[light].kind,
                    manyshadows_scene::LightKind::Spot { .. }
                ));
            }
        }
        // Keep the page table within its cap: halve the largest sides first.
        let mut total: u64 = sides.iter().map(|&s| table_entries(s) as u64).sum();
        while total > options.max_table_entries as u64 {
            let cap = sides.iter().copied().max().unwrap_or(PAGE_SIZE);
            if cap <= PAGE_SIZE {
                break;
            }
            for s in sides.iter_mut().filter(|s| **s == cap) {
                *s = cap / 2;
            }
            fit.capped_side = cap / 2;
            total = sides.iter().map(|&s| table_entries(s) as u64).sum();
        }
        let mut faces = Vec::with_capacity(views.len());
        let mut first = 0u32;
        for ((((v, &side), &lod), &tile), &spot) in
            views.iter().zip(&sides).zip(&lods).zip(&floors).zip(&spots)
        {
            let finest = (side / PAGE_SIZE).trailing_zeros();
            // The coarsest level whose side is no smaller than the atlas's tile (0: none).
            let floor = if tile > PAGE_SIZE {
                (tile.div_ceil(PAGE_SIZE))
                    .next_power_of_two()
                    .trailing_zeros()
            } else {
                0
            };
            // A spot face at its floor samples exactly the atlas tile's texels: there it takes
            // the atlas's whole receiver bias, so that the lookup is the atlas's (with half of
            // it, spot lights at their floors left false shadows the atlas has not). Cube and
            // cascade faces keep half at their floors too, where it measured better than the
            // atlas (docs/decisions.md, "Spot faces take the atlas's whole receiver bias at
            // their floor, other faces half").
            let floor_bias = if spot && floor > 0 && options.bias_scale > 0.0 {
                (1.0 / options.bias_scale).max(1.0)
            } else {
                0.0
            };
            faces.push(VirtualFace {
                view_proj: v.view_proj.to_cols_array_2d(),
                eye: crate::shadows::plan::view_eye(v).to_array(),
                params: [
                    v.near,
                    v.far,
                    v.texel_world * v.resolution as f32 / side as f32,
                    if v.orthographic { 1.0 } else { 0.0 },
                ],
                // w: last frame's first entry + 1 when its pages may be kept (set per frame).
                table: [first, finest, side, 0],
                dirty: NOTHING_MOVED,
                detail: [lod, floor.min(finest) as f32, floor_bias, 0.0],
            });
            first = first.saturating_add(table_entries(side));
        }
        fit.faces = faces.len();
        fit.table_entries = first;
        Self {
            views,
            light_views,
            faces,
            fit,
        }
    }

    /// GPU records of the scene's lights, their shadow views pointing at the faces.
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
}

/// Counters of one frame of virtual shadow maps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub struct VirtualStats {
    /// The plan's layout.
    pub fit: VirtualFit,
    /// Pages marked per level (level 0 = one page per face in use): asked for by a sample, or
    /// an ancestor of an asked page. Ancestors are drawn only at the admitted level, where the
    /// pool's room ends (see [`Self::asked`]).
    pub needed: [u32; MAX_LEVELS as usize],
    /// Pages some sample asked for, per level. When the pool holds every asked page only those
    /// are drawn; otherwise the finest level A whose marked pages fit with the asked pages of
    /// the coarser levels is admitted whole, asked pages finer than A are denied and read
    /// their ancestor at A.
    pub asked: [u32; MAX_LEVELS as usize],
    /// Faces some sample needs (their level-0 page is marked): of a point light's six cube
    /// faces only those its visible samples look through; the plan's other faces get no pages.
    pub faces_in_use: u32,
    /// Pages resident this frame (kept + drawn).
    pub resident: u32,
    /// Resident pages kept, with their depth, from the last frame (caching).
    pub kept: u32,
    /// Pages drawn this frame.
    pub drawn: u32,
    /// Cluster draws into this frame's pages (a cluster drawn into two pages counts twice),
    /// after the GPU's frustum and normal-cone culling.
    pub cluster_draws: u32,
    /// Triangles of those draws (before the rasterizer's own back-face culling).
    pub triangles: u32,
    /// Needed pages that did not fit the pool (their samples used a coarser level).
    pub denied: u32,
    /// Faces left without shadows because not even a quarter of a pool page was left for their
    /// level 0 (only when the pool has fewer than a quarter as many pages as faces in use).
    pub unshadowed_faces: u32,
    /// Faces whose level-0 page is a quarter of a pool page (64² texels, half the resolution):
    /// only when the pool has fewer pages than faces in use, the last faces in light order
    /// share pool pages four to one so that every face gets room while that suffices.
    pub quarter_faces: u32,
    /// Pages the pool holds.
    pub pool_pages: u32,
    /// Pool side in texels.
    pub pool_side: u32,
    /// Bytes of the pool texture.
    pub pool_bytes: u64,
    /// Bytes of the page table.
    pub table_bytes: u64,
    /// Bytes of last frame's page table, kept for the pages a frame keeps: as large as the
    /// table with caching ([`crate::RenderSettings::cache_shadows`]), 0 without.
    pub prev_table_bytes: u64,
    /// How the marking went (with [`VirtualOptions::tile_marking`]; all 0 without).
    pub tiles: TileMarking,
}

/// The tile marking's (tile, light) pairs of one frame ([`VirtualOptions::tile_marking`]):
/// settled by the bounds of the tile's samples, or handed on to per-pixel work.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub struct TileMarking {
    /// Pairs where no sample needs a page (out of the light's reach, cone or view, or facing
    /// away).
    pub empty: u32,
    /// Pairs where every sample needs the same page: marked once.
    pub one_page: u32,
    /// Pairs where the samples that need a page need the same one but some may need none:
    /// each pixel checks only whether it does.
    pub known_page: u32,
    /// Pairs marked per pixel as without tiles (a tile handed on whole counts once).
    pub per_pixel: u32,
    /// Tiles marked per pixel whole (spread over too many light clusters, too many lights
    /// left uncertain, or a sample that is not a number).
    pub whole_tiles: u32,
}

impl VirtualStats {
    /// Shadow memory the virtual maps keep between frames: the pool, the page table and,
    /// with caching, last frame's table (what `bench virtual` and `compare` set against the
    /// atlas; the per-frame working buffers — the expansion's index buffer, commands — are
    /// not counted, as the atlas techniques' are not).
    pub fn kept_bytes(&self) -> u64 {
        self.pool_bytes + self.table_bytes + self.prev_table_bytes
    }

    /// Pages marked over all levels (asked, or ancestors of asked ones).
    pub fn needed_total(&self) -> u32 {
        self.needed.iter().sum()
    }

    /// Pages asked for over all levels.
    pub fn asked_total(&self) -> u32 {
        self.asked.iter().sum()
    }

    /// The admitted level A of the frame (as the GPU's allocation chose it): the finest level
    /// whose marked pages, with the pages asked at every coarser level, fit the pool. Level 0
    /// when not even that fits.
    pub fn admitted_level(&self) -> u32 {
        let mut coarser = 0u32;
        let mut admitted = 0;
        for a in 0..MAX_LEVELS as usize {
            if coarser + self.needed[a] > self.pool_pages {
                break;
            }
            admitted = a as u32;
            coarser += self.asked[a];
        }
        admitted
    }
}

/// The pool side for a byte budget: the largest whole number of pages per row whose square
/// of 4-byte texels fits, at least one page, at most `max_dim` (rounded down to whole pages).
pub fn pool_side(bytes: u64, max_dim: u32) -> u32 {
    let page = u64::from(PAGE_SIZE);
    let texels = (bytes / 4).max(page * page);
    let mut side = (texels as f64).sqrt() as u64;
    // The float root may be one off either way; settle it exactly.
    while side * side > texels {
        side -= 1;
    }
    while (side + 1) * (side + 1) <= texels {
        side += 1;
    }
    let max = (u64::from(max_dim.max(PAGE_SIZE)) / page) * page;
    ((side / page) * page).clamp(page, max) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_entries_count_every_level() {
        assert_eq!(table_entries(128), 1);
        assert_eq!(table_entries(256), 1 + 4);
        assert_eq!(table_entries(512), 1 + 4 + 16);
        assert_eq!(
            table_entries(16384),
            (0..8).map(|l| 1u32 << (2 * l)).sum::<u32>()
        );
    }

    #[test]
    fn pool_side_is_the_largest_square_within_budget() {
        assert_eq!(pool_side(256 << 20, 16384), 8192);
        // One byte less: one page per row less (8064 = 63 pages), not half the side.
        assert_eq!(pool_side((256 << 20) - 1, 16384), 8064);
        assert_eq!(pool_side(1 << 30, 8192), 8192);
        assert_eq!(pool_side(0, 16384), PAGE_SIZE);
        assert_eq!(pool_side(64 << 20, 16384), 4096);
        // 512 MiB: 90 pages per row, 8,100 pages (a power of two would give 4,096).
        assert_eq!(pool_side(512 << 20, 16384), 11520);
        // Capped by the texture limit, in whole pages.
        assert_eq!(pool_side(4 << 30, 16100), 16000);
    }
}

with_setters!(VirtualOptions {
    with_pool_bytes: pool_bytes: u64,
    with_max_side: max_side: u32,
    with_lod: lod: f32,
    with_directed_lod: directed_lod: f32,
    with_atlas_floor: atlas_floor: bool,
    with_bias_scale: bias_scale: f32,
    with_max_table_entries: max_table_entries: u32,
    with_back_facing: back_facing: bool,
    with_group_cull: group_cull: bool,
    with_receiver_cull: receiver_cull: bool,
    with_expand_bytes: expand_bytes: u64,
    with_tile_marking: tile_marking: bool,
    with_sampled_pages: sampled_pages: bool,
    with_sampled_keep_frames: sampled_keep_frames: u32,
});
