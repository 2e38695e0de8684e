// The virtual shadow maps' GPU types (types.rs mirrors the structs), composed after
// common.wgsl into every shader that reads the page table or the faces.
//
// Every shadow view of the plan (spot, cube face, cascade) is a *face*: a virtual map of
// `table.z`² texels cut into pages of `VsmUniforms.pool.z`² texels, held as a mip chain of
// page grids: level l has 2^l × 2^l pages (level 0 = the whole face in one page). A face's
// page-table entries are consecutive from `table.x`, coarsest level first, row-major.
struct VirtualFace {
    view_proj: mat4x4<f32>,
    // What back-face culling faces: light position (w = 1) or direction of travel (w = 0).
    eye: vec4<f32>,
    // near, far, world size of a texel of the finest level (per unit distance if perspective),
    // 1 if orthographic else 0.
    params: vec4<f32>,
    // first page-table entry, finest level, virtual side in texels, and 1 + the face's first
    // entry in last frame's table when its resident pages may be kept (0: draw them anew).
    table: vec4<u32>,
    // The part of the face (uv min xy, max xy) where casters moved since the last frame:
    // kept pages overlapping it are drawn anew. Empty (min > max) when nothing moved there.
    dirty: vec4<f32>,
    // x: shadow texels per screen pixel the face aims for (its level of detail); y: the
    // atlas floor's level; z: a spot face's receiver bias there over the scaled one (0: none);
    // w unused.
    detail: vec4<f32>,
}

struct VsmUniforms {
    // Pool side in texels, pages per pool row, page side in texels, pages in the pool.
    pool: vec4<u32>,
    // Faces, page-table entries, 1 = mark pages for back-facing samples too, 1 = bound each
    // page's casters by its farthest receiver (the keys after the table's entries).
    counts: vec4<u32>,
    // Unused (the faces carry their level of detail); the marking pass's first pixel
    // (x, y: it marks a rectangle from there when only part of the screen changed); the
    // receiver bias's scale (texels of the bias settings per texel of a page).
    lod: vec4<f32>,
    // Where last frame's page table keeps its pages' receiver bounds (its entry count); 1 =
    // pages drawn now may be kept later and get bounds with room to spare; unused.
    prev: vec4<u32>,
}

// One cull + draw round of the page rendering (dynamic uniform offset).
struct VsmRound {
    // First page of the round, page slots in the round, first cluster, clusters in the round.
    round: vec4<u32>,
    // Caster vertices V, cullable triangles, cull bits, 0 = a command per (page, cluster) slot
    // or else compaction (pairs then triangles, vsm_draw.wgsl): the commands' capacity, where
    // the pairs drawn whole start.
    counts: vec4<u32>,
}

// Page-table entry values: 0 = not needed (before allocation, marks 1 and 2: vsm_table.wgsl), VSM_FIRST_PAGE + p
// = resident in pool page p, VSM_FIRST_PAGE + VSM_QUARTER + 4p + k = resident in quadrant k
// of pool page p (a level-0 page at half resolution, only when the pool has fewer pages than
// faces in use), VSM_DENIED = needed but the pool was full.
const VSM_EMPTY: u32 = 0u;
const VSM_FIRST_PAGE: u32 = 2u;
const VSM_QUARTER: u32 = 0x40000000u;
const VSM_DENIED: u32 = 0xffffffffu;
// Levels a face can have: 2^0 .. 2^(VSM_LEVELS - 1) pages per side.
const VSM_LEVELS: u32 = 8u;
