//! The virtual shadow maps' GPU types: `#[repr(C)]` mirrors of the structs of
//! `vsm_types.wgsl`, which every virtual-map shader composes after `common.wgsl`
//! ([`VSM_TYPES`]), checked against it by naga.

use bytemuck::{Pod, Zeroable};

/// The structs and page-table constants of `vsm_types.wgsl`.
pub const VSM_TYPES: &str = include_str!("vsm_types.wgsl");

/// A face of a virtual shadow map (`VirtualFace`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct VirtualFace {
    /// Light world → clip of the whole face.
    pub view_proj: [[f32; 4]; 4],
    /// Light position (w = 1) or direction of travel (w = 0), for back-face culling.
    pub eye: [f32; 4],
    /// near, far, world size of a finest-level texel (per unit distance if perspective),
    /// orthographic (1/0).
    pub params: [f32; 4],
    /// First page-table entry, finest level, virtual side in texels, 1 + the face's first
    /// entry in last frame's table when its pages may be kept (0: draw them anew).
    pub table: [u32; 4],
    /// Where casters moved in the face since the last frame (uv min x, min y, max x, max y):
    /// kept pages overlapping it are drawn anew; empty (min > max) when none did.
    pub dirty: [f32; 4],
    /// x: shadow texels per screen pixel the face aims for (its level of detail:
    /// `VirtualOptions::lod`, times `VirtualOptions::directed_lod` for spot and directional
    /// lights); y: the coarsest level a sample may take (the level as fine as the atlas's tile
    /// of the same view); z: a spot face's receiver bias at that level over the one other
    /// levels take (`1 / VirtualOptions::bias_scale`, at least 1: the atlas's whole bias; 0
    /// without a floor and for other faces), so that where a spot face samples its floor the
    /// lookup is the atlas's; w unused.
    pub detail: [f32; 4],
}

/// Pool and page-table layout of the virtual shadow maps (`VsmUniforms`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct VsmUniforms {
    /// Pool side in texels, pages per pool row, page side in texels, pages in the pool.
    pub pool: [u32; 4],
    /// Faces, page-table entries, 1 = mark pages for back-facing samples too, 1 = bound each
    /// page's casters by its farthest receiver (the keys after the table's entries).
    pub counts: [u32; 4],
    /// Unused (the faces carry their level of detail, `VirtualFace::detail`); the first
    /// pixel (x, y) the marking pass visits (a
    /// rectangle of the screen when only part of it changed); the receiver bias's scale
    /// (`VirtualOptions::bias_scale`).
    pub lod: [f32; 4],
    /// Where last frame's page table keeps its pages' receiver bounds (its entry count); 1 =
    /// pages drawn now may be kept later and get bounds with room to spare; unused.
    pub prev: [u32; 4],
}

/// One cull + draw round of the page rendering (`VsmRound`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct VsmRound {
    /// First page, page slots, first cluster, clusters.
    pub round: [u32; 4],
    /// Caster vertices, cullable triangles, cull bits, 0 = a command per (page, cluster) slot
    /// or else compaction: the commands' capacity, where the pairs drawn whole start.
    pub counts: [u32; 4],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::types::layout::same_layout;

    #[test]
    fn structs_match_the_wgsl() {
        let src = crate::gpu::shaders::compose(&[crate::gpu::shaders::COMMON, VSM_TYPES]);
        same_layout!(in src, VirtualFace, view_proj, eye, params, table, dirty, detail);
        same_layout!(in src, VsmUniforms, pool, counts, lod, prev);
        same_layout!(in src, VsmRound, round, counts);
    }
}
