// Virtual shadow maps (vsm.rs), the passes that decide which pages exist this frame:
//
// 1. cs_mark, one thread per pixel: for every light of the pixel's cluster that reaches the
//    sample (and faces it, unless back-facing samples are wanted too), the page of the level
//    whose texels match the pixel's footprint is marked *asked*, and its ancestors up to
//    level 0 are marked *above* (whoever turns an entry from unmarked to marked walks its
//    ancestors, so a walk stops at the first entry already marked).
//    Incrementally (only casters moved; see cs_carry) it visits a rectangle of the screen.
// 2. cs_count, one thread per block of 32 page-table entries: each marked entry learns its
//    level (tagged into the entry with whether it was asked) and the block adds its marked
//    and its asked entries per level to the frame's counters.
//    Admission (cs_retain): the finest level A such that every asked page coarser than A and
//    every marked page (asked or above) of A fit the pool. Asked pages of levels below A and
//    every marked page of A are admitted; pages above only (ancestors of asked pages) are
//    not drawn at levels coarser than A, where nothing reads them; asked pages finer than A
//    are denied and their lookups fall back to their ancestor at A (a coarser shadow, never a
//    wrong or missing one). With room for everything, A is the finest level and only asked
//    pages are drawn. When level 0 alone (one page per face in use) exceeds the pool, the first
//    faces in light order get whole pool pages and the last ones share pool pages four to one
//    (quarter pages: the face's level 0 at 64²), as few as let every face fit; only past four
//    faces per pool page do faces go without shadows, counted unshadowed.
// 3. cs_retain, one thread per entry: an admitted page whose face is unchanged since the last
//    frame (the CPU sets `table.w`), that was resident then, that does not overlap where a
//    caster moved in the face (`dirty`, from the CPU) and whose casters were drawn up to at
//    least this frame's farthest receiver of the page (below) keeps its pool page and its
//    contents (caching); the other admitted pages are tagged new.
//
// Receiver bounds: the marking keeps, per asked page, the largest depth key its samples
// compare against (after the table's entries: `vsm_table[entries + e]`) and the part of the
// page their filter taps reach (`vsm_table[2 entries + e]`: 16 columns and 16 rows of 8
// texels, bit masks). A page drawn with bounds holds every caster up to that depth, drawn
// over that rectangle, so it serves any sample nearer than the depth whose taps stay in the
// rectangle: the allocation writes the bounds each resident page was drawn with over its marks
// (UNBOUNDED and ALL_CELLS when not bounded), the next frame receives them with the table, and
// a page is kept only while its samples stay within them.
//    cs_free, one thread: the pool pages not kept, in order.
//    cs_count_new / cs_scan_new / cs_alloc_new: new pages get free pool pages by their rank
//    in page-table order (block counts and a prefix sum), so the frame never depends on
//    thread order, and each gets its view in the draw list: the face's projection cropped to
//    the page, drawn into the page's tile of the pool.
// 4. cs_args, one thread: the number of pages to draw, and from it the indirect arguments of
//    the page clear and of every cull round.

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<LightData>;
@group(0) @binding(2) var gbuf_position: texture_2d<u32>;
@group(0) @binding(3) var gbuf_normal: texture_2d<u32>;
@group(0) @binding(4) var<uniform> clusters: ClusterUniforms;
@group(0) @binding(5) var<storage, read> cluster_slots: array<u32>;
@group(0) @binding(6) var<storage, read> cluster_masks: array<u32>;
@group(0) @binding(7) var<uniform> vsm: VsmUniforms;
@group(0) @binding(8) var<storage, read> vsm_faces: array<VirtualFace>;
@group(0) @binding(9) var<storage, read_write> vsm_table: array<atomic<u32>>;
// [0, 8): pages marked per level (asked or above); 9: pages kept from the last frame; 10: free
// pool pages; 11: new pages; 12: new pages that get room (full or quarter); 13: new pages that
// get a whole pool page (the rest of 12 get quarters); 14: cluster draws and 15: triangles
// drawn into pages (vsm_draw.wgsl's cull); 16: pages denied; 17: pages drawn this frame;
// 18: level-0 pages denied (faces left unshadowed); [20, 28): pages asked per level; [28, 33):
// the tile marking's VirtualStats::tiles.
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;
// The pages to draw this frame, in rank order: each one's view (the face's projection
// cropped to the page; `tile.w` holds the face index's bits).
@group(0) @binding(11) var<storage, read_write> page_views: array<ShadowViewData>;
@group(0) @binding(12) var<storage, read> rounds: array<VsmRound>;
// Per round: dispatch arguments (x, y, z); after them: the clear's draw arguments.
@group(0) @binding(13) var<storage, read_write> args: array<u32>;
// Last frame's page table (for the pages it kept).
@group(0) @binding(14) var<storage, read> prev_table: array<u32>;
// Scratch, in u32 words: [0, P) pool page kept this frame (1/0); [P, 2P) free pool pages in
// order; [2P, 2P + B) per block: new pages, then their prefix. P = pool pages, B = blocks.
@group(0) @binding(15) var<storage, read_write> scratch: array<u32>;
// Declared for shadow_lookup.wgsl's `atlas_coord`, which these entry points never call.
@group(1) @binding(0) var<storage, read> shadow_views: array<ShadowViewData>;

const COUNT_KEPT: u32 = 9u;
const COUNT_FREE: u32 = 10u;
const COUNT_NEW: u32 = 11u;
const COUNT_PLACED: u32 = 12u;
const COUNT_WHOLE: u32 = 13u;
const COUNT_DENIED: u32 = 16u;
const COUNT_DRAWN: u32 = 17u;
const COUNT_UNSHADOWED: u32 = 18u;
const COUNT_ASKED: u32 = 20u;
const COUNT_TILES: u32 = 28u;
// Marks before allocation (bits): a sample asked for the page; the page is an ancestor of an
// asked one.
const MARK_ASKED: u32 = 1u;
const MARK_ABOVE: u32 = 2u;
// Page-table entries per allocation block (one thread walks them in order).
const BLOCK: u32 = 32u;
// A marked entry after cs_count: this plus its level, plus TAG_ASKED if a sample asked for it.
const VSM_NEEDED_AT: u32 = 0x80000000u;
const TAG_ASKED: u32 = 0x100u;
// An admitted entry without a kept page after cs_retain: this plus its level.
const VSM_NEW_AT: u32 = 0xc0000000u;
// A resident page's key when its casters were drawn without a receiver bound: the largest
// finite f32, above every key (and, as a draw's bound, culling nothing).
const UNBOUNDED: u32 = 0x7f7fffffu;

// Every cell of a page (column bits low, row bits high): the whole page.
const ALL_CELLS: u32 = 0xffffffffu;
// Texels a filter tap reaches from a sample's texel position (PCF 3x3: 1.5).
const TAP_REACH: f32 = 2.0;

// Where last frame's table (`prev_table`) keeps its keys and cells: after its own entries.
fn prev_keys_at() -> u32 {
    return vsm.prev.x;
}
fn prev_cells_at() -> u32 {
    return 2u * vsm.prev.x;
}
fn cells_at() -> u32 {
    return 2u * vsm.counts.y;
}

// The cells (columns | rows << 16) the filter taps of a sample at `uv` reach in its page of
// `level`.
fn tap_cells(uv: vec2<f32>, level: u32) -> u32 {
    let pages = f32(1u << level);
    let t = (uv * pages - min(floor(uv * pages), vec2<f32>(pages - 1.0))) * f32(vsm.pool.z);
    return cells_between(t, t);
}

// The cells the filter taps of samples at page texel positions from `t0` to `t1` reach.
fn cells_between(t0: vec2<f32>, t1: vec2<f32>) -> u32 {
    let cell = f32(vsm.pool.z) / 16.0;
    let lo = vec2<u32>(clamp(floor((t0 - TAP_REACH) / cell), vec2<f32>(0.0), vec2<f32>(15.0)));
    let hi = vec2<u32>(clamp(floor((t1 + TAP_REACH) / cell), vec2<f32>(0.0), vec2<f32>(15.0)));
    let cols = (2u << hi.x) - (1u << lo.x);
    let rows = (2u << hi.y) - (1u << lo.y);
    return cols | (rows << 16u);
}

// `m` with one more cell on each side (per half, within the page).
fn widen_cells(m: u32) -> u32 {
    let cols = m & 0xffffu;
    let rows = m >> 16u;
    let c = (cols | (cols << 1u) | (cols >> 1u)) & 0xffffu;
    let r = (rows | (rows << 1u) | (rows >> 1u)) & 0xffffu;
    return c | (r << 16u);
}

// vsm_draw.wgsl's `drawn_rect` code of a span of cells: first and last column and row.
fn rect_code(m: u32) -> u32 {
    let cols = m & 0xffffu;
    let rows = m >> 16u;
    return u32(firstTrailingBit(cols)) + 16u * u32(firstLeadingBit(cols))
        + 256u * u32(firstTrailingBit(rows)) + 4096u * u32(firstLeadingBit(rows));
}

// Every bit between the lowest and the highest set one, per half (the rectangle spanned).
fn span_cells(m: u32) -> u32 {
    let cols = m & 0xffffu;
    let rows = m >> 16u;
    if (cols == 0u || rows == 0u) {
        return ALL_CELLS;
    }
    let c = (2u << u32(firstLeadingBit(cols))) - (1u << u32(firstTrailingBit(cols)));
    let r = (2u << u32(firstLeadingBit(rows))) - (1u << u32(firstTrailingBit(rows)));
    return c | (r << 16u);
}

fn mark_light(i: u32, p: vec3<f32>, n: vec3<f32>, view_depth: f32) {
    let light = lights[i];
    if (light.shadow.y == 0u || !in_reach(light, p)) {
        return;
    }
    // The lighting pass reads shadows only where the surface faces the light.
    if (vsm.counts.z == 0u && dot(n, to_light(light, p)) <= 0.0) {
        return;
    }
    let fi = select_shadow_view(light, p, view_depth);
    if (fi < 0) {
        return;
    }
    let face = vsm_faces[fi];
    let ray = vsm_ray(light, face, p, n);
    let level = vsm_level(face, ray, view_depth);
    let q = vsm_project(light, face, ray, level);
    if (!q.valid) {
        return;
    }
    let e = vsm_entry(face, level, q.uv);
    if (vsm.counts.w != 0u) {
        // The farthest receiver of the page (keys are never negative as bits: 0 = no bound).
        bound_page(e, bitcast<u32>(max(q.key, 0.0)), tap_cells(q.uv, level));
    }
    ask_page(face, level, q.uv, e);
}

// Widens page `e`'s receiver bounds to depth key `key` and the cells `cells`.
fn bound_page(e: u32, key: u32, cells: u32) {
    if (key > atomicLoad(&vsm_table[vsm.counts.y + e])) {
        atomicMax(&vsm_table[vsm.counts.y + e], key);
    }
    if ((atomicLoad(&vsm_table[cells_at() + e]) & cells) != cells) {
        atomicOr(&vsm_table[cells_at() + e], cells);
    }
}

// Marks page `e` (of `face` at `level`, holding `uv`) asked, and its ancestors above.
fn ask_page(face: VirtualFace, level: u32, uv: vec2<f32>, e: u32) {
    if ((atomicLoad(&vsm_table[e]) & MARK_ASKED) != 0u) {
        return;
    }
    if (atomicOr(&vsm_table[e], MARK_ASKED) != VSM_EMPTY) {
        return;
    }
    var l = i32(level) - 1;
    while (l >= 0) {
        if (!mark_above(vsm_entry(face, u32(l), uv))) {
            break;
        }
        l = l - 1;
    }
}

// Marks entry `e` as an ancestor of an asked page; false if it was marked already (its own
// ancestors are then marked, or being marked, by whoever marked it).
fn mark_above(e: u32) -> bool {
    if (atomicLoad(&vsm_table[e]) != VSM_EMPTY) {
        return false;
    }
    return atomicOr(&vsm_table[e], MARK_ABOVE) == VSM_EMPTY;
}

@compute @workgroup_size(8, 8, 1)
fn cs_mark(@builtin(global_invocation_id) id: vec3<u32>) {
    mark_pixel(id.xy + vec2<u32>(vsm.lod.yz), ALL_LIGHTS);
}

// The cluster slot of the pixel `px` at `view_depth` (CLUSTER_OVERFLOW without clusters).
fn pixel_slot(px: vec2<u32>, view_depth: f32) -> u32 {
    if (clusters.words.w == 0u) {
        return CLUSTER_OVERFLOW;
    }
    return cluster_slots[cluster_index(clusters, px, view_depth)];
}

// Whether a slot stands for every light (no list, or the pool of lists overflowed).
fn every_light(slot: u32) -> bool {
    return slot < CLUSTER_FIRST_SLOT || slot == CLUSTER_OVERFLOW;
}

// Whether light `i` is in the list of (listed) slot `slot`.
fn slot_has(slot: u32, i: u32) -> bool {
    let base = (slot - CLUSTER_FIRST_SLOT) * clusters.words.z;
    return (cluster_masks[base + clusters.words.x + i / 32u] & (1u << (i % 32u))) != 0u;
}

// The G-buffer sample of pixel `px`: position, unit normal, camera view depth; not valid off
// screen or without geometry.
struct PixelSample {
    valid: bool,
    p: vec3<f32>,
    n: vec3<f32>,
    view_depth: f32,
}

fn pixel_sample(px: vec2<u32>) -> PixelSample {
    var out: PixelSample;
    out.valid = false;
    if (any(px >= vec2<u32>(frame.viewport.xy))) {
        return out;
    }
    let gpos = textureLoad(gbuf_position, vec2<i32>(px), 0);
    if (!has_geometry(gpos)) {
        return out;
    }
    out.p = bitcast<vec4<f32>>(gpos).xyz;
    out.n = normalize(bitcast<vec3<f32>>(textureLoad(gbuf_normal, vec2<i32>(px), 0).xyz));
    out.view_depth = -(frame.view * vec4<f32>(out.p, 1.0)).z;
    out.valid = true;
    return out;
}

// Marks the pages the sample of pixel `px` needs: of light `only`, or with ALL_LIGHTS of every
// light of its cluster.
fn mark_pixel(px: vec2<u32>, only: u32) {
    let s = pixel_sample(px);
    if (!s.valid) {
        return;
    }
    let p = s.p;
    let n = s.n;
    let view_depth = s.view_depth;
    if (only != ALL_LIGHTS) {
        mark_light(only, p, n, view_depth);
        return;
    }
    let slot = pixel_slot(px, view_depth);
    if (every_light(slot)) {
        for (var i = 0u; i < frame.counts.x; i = i + 1u) {
            mark_light(i, p, n, view_depth);
        }
        return;
    }
    let base = (slot - CLUSTER_FIRST_SLOT) * clusters.words.z;
    for (var sw = 0u; sw < clusters.words.x; sw = sw + 1u) {
        var words = cluster_masks[base + sw];
        while (words != 0u) {
            let w = sw * 32u + firstTrailingBit(words);
            words = words & (words - 1u);
            var bits = cluster_masks[base + clusters.words.x + w];
            while (bits != 0u) {
                let i = w * 32u + firstTrailingBit(bits);
                bits = bits & (bits - 1u);
                mark_light(i, p, n, view_depth);
            }
        }
    }
}

// ---- Marking by tiles (VirtualOptions::tile_marking) ----
//
// Most of a light's samples in a small patch of the screen need one and the same page, so the
// per-(pixel, light) work of cs_mark mostly repeats itself. cs_mark_tiles takes a tile of
// MARK_TILE² pixels per thread and bounds its samples: a box of positions, the range of view
// depths, a cone of normals. Per light of the tile's clusters it then shows one of:
// - TILE_NONE: no sample needs a page (the box out of the light's reach, cone or view, or
//   every normal facing away);
// - TILE_ALL: every sample needs the same page of the same level (in reach and facing, one
//   face, one level over the depth and distance ranges, one page under the projected box):
//   the page is marked once, with the box's receiver bounds, which hold every sample's;
// - TILE_SOME: as TILE_ALL, but some samples may be out of reach or face away;
// - TILE_UNSURE: nothing certain.
// TILE_SOME and TILE_UNSURE lights are handed on to cs_mark_pixels in one job per tile, one
// thread per pixel: it marks an unsure light exactly as cs_mark does (mark_light), and a
// TILE_SOME light's known page where the sample passes mark_light's reach and facing tests,
// with mark_light's receiver bounds. A tile spread over too many clusters, or handing on more
// than JOB_LIGHTS lights, is handed on whole: cs_mark's loop over its pixels' clusters. So
// exactly the pages cs_mark asks for are asked.
//
// The page a sample needs: its level follows from the ratio of its pixel's footprint (view
// depth) to the face's texel (perspective: its clip w), both bounded over the box; its page
// from the face coordinates of the biased sample. The bias moves a sample towards the light
// (along its projection ray for a perspective face whose eye is the light, or along an
// orthographic face's axis: no move in face coordinates) and along its normal, by at most
// bias.z · bias scale texels, divided by 1 - (the move towards the light / the distance to
// it), which scales the clip position: the box grown by that much projects onto a rectangle
// holding every biased sample. The margins below are far above the rounding of either side.

// Pixels per side of a tile.
const MARK_TILE: u32 = 4u;
// Clusters a tile's samples may fall in before the whole tile is marked per pixel.
const TILE_CLUSTERS: u32 = 4u;
// mark_pixel's light for every light of the pixel's cluster.
const ALL_LIGHTS: u32 = 0xffffffffu;
// A job's light flag: its page is known, each pixel checks only whether it needs it
// (TILE_SOME).
const PAGE_KNOWN: u32 = 0x80000000u;
// The proofs' margins: in log2 of the footprint / texel ratio, in face coordinates.
const LEVEL_MARGIN: f32 = 0.01;
const UV_MARGIN: f32 = 1e-5;
// tan θ at which receiver_offset_dir clamps the slope term.
const MAX_TAN: f32 = 10.0;
// Lights a tile hands on in one job (more, and it is handed on whole).
const JOB_LIGHTS: u32 = 16u;
// Where the whole tiles handed on start in `mark_list` (one word each: the first pixel).
const WHOLE_FIRST: u32 = 8u;

// A job of cs_mark_pixels: a tile and the lights it hands on, `2 + 3 n` words: the tile's
// first pixel (x | y << 16), n, then per light its index (| PAGE_KNOWN), and with PAGE_KNOWN
// the page's entry and face.
// `mark_list`: [0] job words used; [1, 4) (tile, light) pairs settled empty, marked for every
// sample, handed on with their page; [4] whole tiles handed on; [5] pairs handed on without
// their page (a whole tile counts once); [6] jobs; then from WHOLE_FIRST the whole tiles and
// the jobs' offsets (room for every tile of the screen in each), then the jobs' words, as many
// as fit (a tile whose job does not fit does it itself).
@group(0) @binding(16) var<storage, read_write> mark_list: array<atomic<u32>>;
// cs_mark_pixels' dispatch arguments (JOBS_PER_GROUP per workgroup, rows of 65,535).
@group(0) @binding(17) var<storage, read_write> mark_args: array<u32, 3>;

// Tiles of the screen (the room for whole tiles and for jobs).
fn screen_tiles() -> u32 {
    let size = vec2<u32>(frame.viewport.xy);
    return ((size.x + MARK_TILE - 1u) / MARK_TILE) * ((size.y + MARK_TILE - 1u) / MARK_TILE);
}

fn offsets_at() -> u32 {
    return WHOLE_FIRST + screen_tiles();
}

fn words_at() -> u32 {
    return WHOLE_FIRST + 2u * screen_tiles();
}

// What a tile's bounds show for a light (see above).
const TILE_NONE: u32 = 0u;
const TILE_ALL: u32 = 1u;
const TILE_SOME: u32 = 2u;
const TILE_UNSURE: u32 = 3u;

// Bounds of a tile's samples.
struct TileSamples {
    lo: vec3<f32>,
    hi: vec3<f32>,
    // View depth range.
    near: f32,
    far: f32,
    // Every normal lies within the cone of this axis and cosine (<= 0: no bound).
    axis: vec3<f32>,
    cos_cone: f32,
}

// A light's page for a tile (TILE_ALL, TILE_SOME): face, level, the page's cell, entry, and
// the rectangle of the tile's biased samples (face_rect, clamped).
struct TilePage {
    outcome: u32,
    face: u32,
    level: u32,
    page: vec2<u32>,
    entry: u32,
    uv_lo: vec2<f32>,
    uv_hi: vec2<f32>,
}

fn tile_outcome(outcome: u32) -> TilePage {
    var out: TilePage;
    out.outcome = outcome;
    return out;
}

// Where a box of samples falls in a face at `level`: the face coordinates of its biased
// samples (a rectangle, margins included, unclamped); not valid when the box reaches behind
// the face's eye or the bias could move samples too far to bound.
struct FaceRect {
    valid: bool,
    uv_lo: vec2<f32>,
    uv_hi: vec2<f32>,
}

fn face_rect(face: VirtualFace, level: u32, lo: vec3<f32>, hi: vec3<f32>) -> FaceRect {
    var out: FaceRect;
    out.valid = false;
    let m = face.view_proj;
    let c = 0.5 * (lo + hi);
    let e = 0.5 * (hi - lo);
    let scale = f32(1u << (face.table.y - level));
    // The largest texel of the level over the box.
    var texel = face.params.z * scale;
    // How far the bias moves a sample: towards the light by texel · (b.x + tan · b.y),
    // tan <= MAX_TAN, which scales a perspective face's clip position by 1 - (that / the
    // distance), at least kappa; along the normal by texel · b.z.
    let b = abs(frame.bias.xyz) * vsm.lod.w;
    var kappa = 1.0;
    if (face.params.w < 0.5) {
        let w = dot(vec4<f32>(m[0][3], m[1][3], m[2][3], m[3][3]), vec4<f32>(c, 1.0))
            + dot(abs(vec3<f32>(m[0][3], m[1][3], m[2][3])), e);
        texel = texel * max(w, 0.0) * (1.0 + 1e-5);
        kappa = 1.0 - face.params.z * scale * (b.x + MAX_TAN * b.y) * (1.0 + 1e-5);
        if (kappa < 0.5) {
            return out;
        }
    }
    let grow = texel * b.z / kappa * (1.0 + 1e-4);
    // The grown box's corners: its centre's clip position plus or minus each axis's half
    // extent times the matrix's column.
    let g = e + vec3<f32>(grow);
    let cc = m * vec4<f32>(c, 1.0);
    let ax = m[0] * g.x;
    let ay = m[1] * g.y;
    let az = m[2] * g.z;
    out.uv_lo = vec2<f32>(3.0e38);
    out.uv_hi = vec2<f32>(-3.0e38);
    var w_min = 3.0e38;
    for (var j = 0u; j < 8u; j = j + 1u) {
        let sign = vec3<f32>(select(-1.0, 1.0, (j & 1u) != 0u), select(-1.0, 1.0, (j & 2u) != 0u), select(-1.0, 1.0, (j & 4u) != 0u));
        let clip = cc + sign.x * ax + sign.y * ay + sign.z * az;
        if (clip.w <= 0.0) {
            return out;
        }
        let uv = clip.xy / clip.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
        out.uv_lo = min(out.uv_lo, uv);
        out.uv_hi = max(out.uv_hi, uv);
        w_min = min(w_min, clip.w);
    }
    // A sample's own clip position rounds by a few ulps of its terms, which grow with its
    // distance from the world's origin: the margin grows with them.
    let mag = vec4<f32>(abs(c) + g, 1.0);
    let terms = dot(abs(vec4<f32>(m[0][0], m[1][0], m[2][0], m[3][0])), mag)
        + dot(abs(vec4<f32>(m[0][1], m[1][1], m[2][1], m[3][1])), mag)
        + 2.0 * dot(abs(vec4<f32>(m[0][3], m[1][3], m[2][3], m[3][3])), mag);
    let margin = UV_MARGIN + 2e-6 * terms / w_min;
    out.uv_lo = out.uv_lo - vec2<f32>(margin);
    out.uv_hi = out.uv_hi + vec2<f32>(margin);
    out.valid = true;
    return out;
}

// Light `i` over the tile's samples `t` (see above).
fn tile_light(i: u32, t: TileSamples) -> TilePage {
    let light = lights[i];
    if (light.shadow.y == 0u) {
        return tile_outcome(TILE_NONE);
    }
    let c = 0.5 * (t.lo + t.hi);
    let e = 0.5 * (t.hi - t.lo);
    let radius = length(e);
    let kind = light.shadow.z;
    // Whether every sample surely reaches the light and faces it.
    var every = true;
    // Unit direction from the box's centre to the light, and the sine and cosine of the box's
    // angular radius seen from the light.
    var u = -light.direction.xyz;
    var sin_b = 0.0;
    var cos_b = 1.0;
    // The cosine margin of the angle tests: 1e-4, plus the angle a sample's rounded offset from
    // the light may be off by far from the world's origin.
    var cos_margin = 1e-4;
    if (kind != LIGHT_DIRECTIONAL) {
        let to = light.position.xyz - c;
        let dist = length(to);
        let range = light.ambient.w;
        // How far a sample's offset from the light may round: a few ulps of the coordinates.
        let slack = 2e-6 * (length(abs(c) + e) + length(light.position.xyz));
        // The box's nearest point beyond the range: every sample is; its farthest: none is.
        if (length(max(abs(to) - e, vec3<f32>(0.0))) > range * (1.0 + 1e-4) + slack) {
            return tile_outcome(TILE_NONE);
        }
        every = length(abs(to) + e) < range * (1.0 - 1e-4) - slack;
        if (dist <= radius * 1.001 + 1e-6 + 2.0 * slack) {
            return tile_outcome(TILE_UNSURE);
        }
        cos_margin = 1e-4 + slack / dist;
        u = to / dist;
        sin_b = radius / dist;
        cos_b = sqrt(max(1.0 - sin_b * sin_b, 0.0));
        if (kind == LIGHT_SPOT) {
            // Outside the cone: the axis and the direction to the box's centre further apart
            // than the cutoff plus the box's radius; inside: closer than the cutoff less it.
            let cos_c = light.direction.w;
            let sin_c = sqrt(max(1.0 - cos_c * cos_c, 0.0));
            let cos_axis = dot(light.direction.xyz, -u);
            if (sin_c * cos_b + cos_c * sin_b > 0.0 && cos_axis < cos_c * cos_b - sin_c * sin_b - cos_margin) {
                return tile_outcome(TILE_NONE);
            }
            every = every && sin_c * cos_b - cos_c * sin_b > 0.0
                && cos_axis > cos_c * cos_b + sin_c * sin_b + cos_margin;
        }
    }
    if (vsm.counts.z == 0u) {
        // Facing away: the normal cone's axis and the direction to the light further apart
        // than 90° plus both cones' radii; facing: closer than 90° less them.
        if (t.cos_cone > 0.0) {
            let sin_n = sqrt(max(1.0 - t.cos_cone * t.cos_cone, 0.0));
            let cos_sum = cos_b * t.cos_cone - sin_b * sin_n;
            let sin_sum = sin_b * t.cos_cone + cos_b * sin_n;
            let cos_axis = dot(t.axis, u);
            if (cos_sum > 0.0 && cos_axis < -sin_sum - cos_margin) {
                return tile_outcome(TILE_NONE);
            }
            every = every && cos_sum > 0.0 && cos_axis > sin_sum + cos_margin;
        } else {
            every = false;
        }
    }
    // One face for every sample: a cube face's region (like a spot's or a cascade's) is
    // convex, so the box's corners decide; cascades by the depth range.
    var fi = -1;
    if (kind == LIGHT_POINT) {
        fi = select_shadow_view(light, t.lo, t.near);
        for (var k = 1u; k < 8u; k = k + 1u) {
            let corner = select(t.lo, t.hi, vec3<bool>((k & 1u) != 0u, (k & 2u) != 0u, (k & 4u) != 0u));
            if (select_shadow_view(light, corner, t.near) != fi) {
                return tile_outcome(TILE_UNSURE);
            }
        }
    } else {
        fi = select_shadow_view(light, c, t.near);
        if (select_shadow_view(light, c, t.far) != fi) {
            return tile_outcome(TILE_UNSURE);
        }
    }
    if (fi < 0) {
        return tile_outcome(TILE_NONE);
    }
    let face = vsm_faces[fi];
    let finest = face.table.y;
    // The level: vsm_level's ratio of footprint to finest texel, over the tile.
    let w_row = vec4<f32>(face.view_proj[0][3], face.view_proj[1][3], face.view_proj[2][3], face.view_proj[3][3]);
    let w_c = dot(w_row.xyz, c) + w_row.w;
    // The box's extent along the row, and how far a sample's rounded w may be off.
    let w_e = dot(abs(w_row.xyz), e) + 2e-6 * (dot(abs(w_row.xyz), abs(c) + e) + abs(w_row.w));
    var tex_lo = face.params.z;
    var tex_hi = face.params.z;
    if (face.params.w < 0.5) {
        let w_lo = (w_c - w_e) * (1.0 - 1e-5);
        if (w_lo <= 1e-6 * (abs(w_c) + w_e)) {
            return tile_outcome(TILE_UNSURE);
        }
        tex_lo = tex_lo * w_lo;
        tex_hi = tex_hi * (w_c + w_e) * (1.0 + 1e-5);
    }
    let footprint = frame.bias.w / max(face.detail.x, 1e-6);
    let k_lo = floor(log2(max(t.near * footprint, 1e-30) / max(tex_hi, 1e-30)) - LEVEL_MARGIN);
    let k_hi = floor(log2(max(t.far * footprint, 1e-30) / max(tex_lo, 1e-30)) + LEVEL_MARGIN);
    let steps = clamp(k_lo, 0.0, f32(finest));
    if (clamp(k_hi, 0.0, f32(finest)) != steps) {
        return tile_outcome(TILE_UNSURE);
    }
    let level = finest - u32(steps);
    let r = face_rect(face, level, t.lo, t.hi);
    if (!r.valid) {
        return tile_outcome(TILE_UNSURE);
    }
    if (kind != LIGHT_POINT) {
        if (any(r.uv_hi < vec2<f32>(0.0)) || any(r.uv_lo > vec2<f32>(1.0))) {
            // Outside a spot's or a cascade's view: no sample has shadow information there.
            return tile_outcome(TILE_NONE);
        }
        if (any(r.uv_lo <= vec2<f32>(0.0)) || any(r.uv_hi >= vec2<f32>(1.0))) {
            // Some samples may fall outside the view: only per pixel can tell.
            return tile_outcome(TILE_UNSURE);
        }
    }
    let pages = 1u << level;
    let uv_lo = clamp(r.uv_lo, vec2<f32>(0.0), vec2<f32>(1.0));
    let page = min(vec2<u32>(uv_lo * f32(pages)), vec2<u32>(pages - 1u));
    let last = min(vec2<u32>(clamp(r.uv_hi, vec2<f32>(0.0), vec2<f32>(1.0)) * f32(pages)), vec2<u32>(pages - 1u));
    if (any(last != page)) {
        return tile_outcome(TILE_UNSURE);
    }
    var out = tile_outcome(select(TILE_SOME, TILE_ALL, every));
    out.face = u32(fi);
    out.level = level;
    out.page = page;
    out.entry = vsm_entry(face, level, uv_lo);
    out.uv_lo = uv_lo;
    out.uv_hi = clamp(r.uv_hi, vec2<f32>(0.0), vec2<f32>(1.0));
    return out;
}

// The cells the filter taps of the tile's samples reach in its page.
fn tile_cells(q: TilePage) -> u32 {
    let pages = f32(1u << q.level);
    let at = vec2<f32>(q.page);
    let side = f32(vsm.pool.z);
    return cells_between((q.uv_lo * pages - at) * side, (q.uv_hi * pages - at) * side);
}

// The farthest depth key of a biased sample in the box of centre `c` and half extent `e` at
// `level` of `face`: the box's, plus the bias's move along the key's row (a move towards the
// light only lowers it when the slope term cannot be negative: then the normal term alone
// counts).
fn box_key(face: VirtualFace, level: u32, c: vec3<f32>, e: vec3<f32>) -> u32 {
    let m = face.view_proj;
    let persp = face.params.w < 0.5;
    let row = select(vec4<f32>(m[0][2], m[1][2], m[2][2], m[3][2]), vec4<f32>(m[0][3], m[1][3], m[2][3], m[3][3]), persp);
    var texel = face.params.z * f32(1u << (face.table.y - level));
    if (persp) {
        texel = texel * max(dot(row.xyz, c) + row.w + dot(abs(row.xyz), e), 0.0);
    }
    let b = abs(frame.bias.xyz) * vsm.lod.w;
    let toward = min(frame.bias.x, frame.bias.x + MAX_TAN * frame.bias.y);
    let moved = texel * (1.0 + 1e-5) * select(b.x + MAX_TAN * b.y + b.z, b.z, toward >= 0.0);
    // (With a few ulps of the terms for the samples' own rounding.)
    let key = (dot(row.xyz, c) + row.w + dot(abs(row.xyz), e) + length(row.xyz) * moved) * (1.0 + 1e-5)
        + 2e-6 * (dot(abs(row.xyz), abs(c) + e) + abs(row.w)) + 1e-30;
    return bitcast<u32>(max(key, 0.0));
}

// Marks a tile's page every sample of the tile (in the box `lo`..`hi`) needs, with the
// tile's receiver bounds.
fn mark_tile_page(q: TilePage, lo: vec3<f32>, hi: vec3<f32>) {
    let face = vsm_faces[q.face];
    if (vsm.counts.w != 0u) {
        bound_page(q.entry, box_key(face, q.level, 0.5 * (lo + hi), 0.5 * (hi - lo)), tile_cells(q));
    }
    ask_page(face, q.level, (vec2<f32>(q.page) + vec2<f32>(0.5)) / f32(1u << q.level), q.entry);
}

// A tile's account of its lights.
struct Handoffs {
    // Lights per outcome of tile_light.
    seen: array<u32, 4>,
    // The lights handed on (| PAGE_KNOWN) and, with PAGE_KNOWN, their pages' entries and faces.
    lights: array<u32, JOB_LIGHTS>,
    entries: array<u32, JOB_LIGHTS>,
    faces: array<u32, JOB_LIGHTS>,
    count: u32,
    // Too many: the tile is handed on whole.
    whole: bool,
}

fn visit_tile_light(i: u32, t: TileSamples, h: ptr<function, Handoffs>) {
    let q = tile_light(i, t);
    (*h).seen[q.outcome] = (*h).seen[q.outcome] + 1u;
    if (q.outcome == TILE_NONE) {
        return;
    }
    if (q.outcome == TILE_ALL) {
        mark_tile_page(q, t.lo, t.hi);
        return;
    }
    let k = (*h).count;
    if (k == JOB_LIGHTS) {
        (*h).whole = true;
        return;
    }
    (*h).lights[k] = select(i, i | PAGE_KNOWN, q.outcome == TILE_SOME);
    (*h).entries[k] = q.entry;
    (*h).faces[k] = q.face;
    (*h).count = k + 1u;
}

// Hands the tile's lights on as one job; false when the jobs' room is full.
fn hand_on(origin: vec2<u32>, h: Handoffs) -> bool {
    let words = 2u + 3u * h.count;
    let at = atomicAdd(&mark_list[0], words);
    if (words_at() + at + words > arrayLength(&mark_list)) {
        return false;
    }
    let w = words_at() + at;
    atomicStore(&mark_list[w], origin.x | (origin.y << 16u));
    atomicStore(&mark_list[w + 1u], h.count);
    for (var k = 0u; k < h.count; k = k + 1u) {
        atomicStore(&mark_list[w + 2u + 3u * k], h.lights[k]);
        atomicStore(&mark_list[w + 3u + 3u * k], h.entries[k]);
        atomicStore(&mark_list[w + 4u + 3u * k], h.faces[k]);
    }
    let j = atomicAdd(&mark_list[6], 1u);
    atomicStore(&mark_list[offsets_at() + j], at);
    return true;
}

fn hand_on_whole(origin: vec2<u32>) {
    let k = atomicAdd(&mark_list[4], 1u);
    if (k < screen_tiles()) {
        atomicStore(&mark_list[WHOLE_FIRST + k], origin.x | (origin.y << 16u));
    }
}

@compute @workgroup_size(8, 8, 1)
fn cs_mark_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    let origin = vec2<u32>(vsm.lod.yz) + id.xy * MARK_TILE;
    if (any(origin >= vec2<u32>(frame.viewport.xy))) {
        return;
    }
    var t: TileSamples;
    t.lo = vec3<f32>(3.0e38);
    t.hi = vec3<f32>(-3.0e38);
    t.near = 3.0e38;
    t.far = 0.0;
    var n_lo = vec3<f32>(1.0);
    var n_hi = vec3<f32>(-1.0);
    var slots: array<u32, TILE_CLUSTERS>;
    var used = 0u;
    var spread = false;
    for (var y = 0u; y < MARK_TILE; y = y + 1u) {
        for (var x = 0u; x < MARK_TILE; x = x + 1u) {
            let s = pixel_sample(origin + vec2<u32>(x, y));
            if (!s.valid) {
                continue;
            }
            let view_depth = s.view_depth;
            // A NaN would drop out of min and max: such a tile is marked per pixel.
            spread = spread || any(s.p != s.p) || any(s.n != s.n);
            t.lo = min(t.lo, s.p);
            t.hi = max(t.hi, s.p);
            t.near = min(t.near, view_depth);
            t.far = max(t.far, view_depth);
            n_lo = min(n_lo, s.n);
            n_hi = max(n_hi, s.n);
            let slot = pixel_slot(origin + vec2<u32>(x, y), view_depth);
            var known = false;
            for (var k = 0u; k < used; k = k + 1u) {
                known = known || slots[k] == slot;
            }
            if (!known) {
                if (used < TILE_CLUSTERS) {
                    slots[used] = slot;
                    used = used + 1u;
                } else {
                    spread = true;
                }
            }
        }
    }
    if (used == 0u) {
        return;
    }
    if (spread || any(t.hi - t.lo != t.hi - t.lo)) {
        hand_on_whole(origin);
        atomicAdd(&mark_list[5], 1u);
        return;
    }
    // A few ulps more on each side: the box's centre and half extent, as the tests compute
    // them, round.
    let pad = 1e-6 * max(abs(t.lo), abs(t.hi));
    t.lo = t.lo - pad;
    t.hi = t.hi + pad;
    // The normal cone: around the normal box's centre direction, with the least cosine of the
    // box (a linear function's minimum over the box) as its bound.
    let nc = 0.5 * (n_lo + n_hi);
    t.cos_cone = 0.0;
    t.axis = vec3<f32>(0.0, 0.0, 1.0);
    if (length(nc) > 1e-3) {
        t.axis = normalize(nc);
        t.cos_cone = dot(nc, t.axis) - dot(abs(t.axis), 0.5 * (n_hi - n_lo)) - 1e-5;
    }
    var h: Handoffs;
    var every = false;
    for (var k = 0u; k < used; k = k + 1u) {
        every = every || every_light(slots[k]);
    }
    if (every) {
        for (var i = 0u; i < frame.counts.x && !h.whole; i = i + 1u) {
            visit_tile_light(i, t, &h);
        }
    } else {
        for (var k = 0u; k < used && !h.whole; k = k + 1u) {
            let base = (slots[k] - CLUSTER_FIRST_SLOT) * clusters.words.z;
            for (var sw = 0u; sw < clusters.words.x && !h.whole; sw = sw + 1u) {
                var words = cluster_masks[base + sw];
                while (words != 0u && !h.whole) {
                    let w = sw * 32u + firstTrailingBit(words);
                    words = words & (words - 1u);
                    var bits = cluster_masks[base + clusters.words.x + w];
                    while (bits != 0u && !h.whole) {
                        let i = w * 32u + firstTrailingBit(bits);
                        bits = bits & (bits - 1u);
                        // Once per light: the first of the tile's clusters that lists it.
                        var listed = false;
                        for (var j = 0u; j < k; j = j + 1u) {
                            listed = listed || slot_has(slots[j], i);
                        }
                        if (!listed) {
                            visit_tile_light(i, t, &h);
                        }
                    }
                }
            }
        }
    }
    for (var k = 0u; k < 3u; k = k + 1u) {
        if (h.seen[k] != 0u) {
            atomicAdd(&mark_list[1u + k], h.seen[k]);
        }
    }
    if (h.whole) {
        hand_on_whole(origin);
        atomicAdd(&mark_list[5], 1u);
        return;
    }
    if (h.count == 0u) {
        return;
    }
    var unsure = 0u;
    for (var k = 0u; k < h.count; k = k + 1u) {
        unsure = unsure + select(1u, 0u, (h.lights[k] & PAGE_KNOWN) != 0u);
    }
    atomicAdd(&mark_list[5], unsure);
    if (!hand_on(origin, h)) {
        // No room left for the job (rare: which tiles find room depends on thread order, so
        // the counts above do not): the thread does it, the same work.
        for (var y = 0u; y < MARK_TILE; y = y + 1u) {
            for (var x = 0u; x < MARK_TILE; x = x + 1u) {
                let s = pixel_sample(origin + vec2<u32>(x, y));
                if (!s.valid) {
                    continue;
                }
                for (var k = 0u; k < h.count; k = k + 1u) {
                    mark_job_light(h.lights[k], h.entries[k], h.faces[k], s.p, s.n, s.view_depth);
                }
            }
        }
    }
}

// A job's light for the sample at `p` (normal `n`): an unsure light marked as cs_mark marks
// it; a known page (PAGE_KNOWN, its entry `e` of face `fi`) marked if the sample reaches and
// faces the light (mark_light's first tests: its level and page are then the tile's, what
// mark_light would compute), with the receiver bounds mark_light computes.
fn mark_job_light(light: u32, e: u32, fi: u32, p: vec3<f32>, n: vec3<f32>, view_depth: f32) {
    if ((light & PAGE_KNOWN) == 0u) {
        mark_light(light, p, n, view_depth);
        return;
    }
    let l = lights[light & ~PAGE_KNOWN];
    if (!in_reach(l, p) || (vsm.counts.z == 0u && dot(n, to_light(l, p)) <= 0.0)) {
        return;
    }
    let face = vsm_faces[fi];
    if (vsm.counts.w != 0u) {
        let level = level_of(e - face.table.x);
        let q = vsm_project(l, face, vsm_ray(l, face, p, n), level);
        bound_page(e, bitcast<u32>(max(q.key, 0.0)), tap_cells(q.uv, level));
    }
    ask_entry(face, e);
}

// Jobs of cs_mark_pixels per workgroup (one thread per pixel of each).
const JOBS_PER_GROUP: u32 = 64u / (MARK_TILE * MARK_TILE);

// The jobs and whole tiles handed on, JOBS_PER_GROUP per workgroup, one thread per pixel of
// each (lavapipe pays per workgroup: with one each the marking took 160 ms instead of 134).
@compute @workgroup_size(64, 1, 1)
fn cs_mark_pixels(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    var k = (wg.x + wg.y * groups.x) * JOBS_PER_GROUP + local / (MARK_TILE * MARK_TILE);
    let pixel = local % (MARK_TILE * MARK_TILE);
    let offset = vec2<u32>(pixel % MARK_TILE, pixel / MARK_TILE);
    let jobs = min(atomicLoad(&mark_list[6]), screen_tiles());
    if (k >= jobs) {
        k = k - jobs;
        if (k < min(atomicLoad(&mark_list[4]), screen_tiles())) {
            let at = atomicLoad(&mark_list[WHOLE_FIRST + k]);
            mark_pixel(vec2<u32>(at & 0xffffu, at >> 16u) + offset, ALL_LIGHTS);
        }
        return;
    }
    let w = words_at() + atomicLoad(&mark_list[offsets_at() + k]);
    let first = atomicLoad(&mark_list[w]);
    let s = pixel_sample(vec2<u32>(first & 0xffffu, first >> 16u) + offset);
    if (!s.valid) {
        return;
    }
    let count = atomicLoad(&mark_list[w + 1u]);
    for (var j = 0u; j < count; j = j + 1u) {
        let at = w + 2u + 3u * j;
        mark_job_light(atomicLoad(&mark_list[at]), atomicLoad(&mark_list[at + 1u]), atomicLoad(&mark_list[at + 2u]), s.p, s.n, s.view_depth);
    }
}

@compute @workgroup_size(1, 1, 1)
fn cs_mark_args() {
    let n = min(atomicLoad(&mark_list[6]), screen_tiles()) + min(atomicLoad(&mark_list[4]), screen_tiles());
    // The stats (VirtualStats::tiles): pairs settled empty, marked once, handed on with their
    // page, marked per pixel; tiles marked per pixel whole.
    for (var k = 0u; k < 3u; k = k + 1u) {
        atomicStore(&counters[COUNT_TILES + k], atomicLoad(&mark_list[1u + k]));
    }
    atomicStore(&counters[COUNT_TILES + 3u], atomicLoad(&mark_list[5]));
    atomicStore(&counters[COUNT_TILES + 4u], min(atomicLoad(&mark_list[4]), screen_tiles()));
    let g = (n + JOBS_PER_GROUP - 1u) / JOBS_PER_GROUP;
    mark_args[0] = min(g, 65535u);
    mark_args[1] = (g + 65534u) / 65535u;
    mark_args[2] = 1u;
}

// Incremental marking (the camera, the lights and every face unchanged since the last frame,
// only casters moved): every page resident or denied last frame is asked again, one thread
// per entry, and its ancestors are marked above; cs_mark then visits only the pixels the moved
// casters may cover. (Last frame's resident pages of the admitted level A may have been
// ancestors only; carried as asked they stay resident while only casters move.)
@compute @workgroup_size(64, 1, 1)
fn cs_carry(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = gid.x + gid.y * groups.x * 64u;
    if (e >= vsm.counts.y) {
        return;
    }
    let face = vsm_faces[face_of(e)];
    if (face.table.w == 0u) {
        return;
    }
    let local = e - face.table.x;
    let before = prev_table[face.table.w - 1u + local];
    if (before < VSM_FIRST_PAGE || (before >= VSM_NEEDED_AT && before != VSM_DENIED)) {
        return;
    }
    // The samples are last frame's (cs_mark adds those under the moved casters): so are their
    // receiver bounds, or the bounds the page was drawn with, which cover them. Before the
    // entry's mark: another thread's walk up may have marked it already (as an ancestor).
    if (vsm.counts.w != 0u) {
        let at = face.table.w - 1u + local;
        atomicMax(&vsm_table[vsm.counts.y + e], prev_table[prev_keys_at() + at]);
        atomicOr(&vsm_table[cells_at() + e], prev_table[prev_cells_at() + at]);
    }
    ask_entry(face, e);
}

// Marks entry `e` of `face` asked and, if it was unmarked, its ancestors above.
fn ask_entry(face: VirtualFace, e: u32) {
    if ((atomicLoad(&vsm_table[e]) & MARK_ASKED) != 0u) {
        return;
    }
    if (atomicOr(&vsm_table[e], MARK_ASKED) != VSM_EMPTY) {
        return;
    }
    let local = e - face.table.x;
    var level = level_of(local);
    let n = 1u << level;
    let within = local - ((1u << (2u * level)) - 1u) / 3u;
    var xy = vec2<u32>(within % n, within / n);
    while (level > 0u) {
        level = level - 1u;
        xy = xy / 2u;
        let up = face.table.x + ((1u << (2u * level)) - 1u) / 3u + xy.y * (1u << level) + xy.x;
        if (!mark_above(up)) {
            break;
        }
    }
}

// The face owning page-table entry `e`: the last whose first entry is at or before it.
fn face_of(e: u32) -> u32 {
    var lo = 0u;
    var hi = vsm.counts.x;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (vsm_faces[mid].table.x <= e) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// Level of entry `local` of a face's chain (coarsest level first).
fn level_of(local: u32) -> u32 {
    var level = 0u;
    while (((1u << (2u * (level + 1u))) - 1u) / 3u <= local) {
        level = level + 1u;
    }
    return level;
}

// One thread per block of BLOCK entries (no workgroup barriers: a software driver pays
// dearly for those); `gid` and `groups` of a dispatch of 64-thread workgroups.
fn block_of(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

fn blocks() -> u32 {
    return (vsm.counts.y + BLOCK - 1u) / BLOCK;
}

// Scratch sections (see the binding).
fn kept_at() -> u32 {
    return 0u;
}
fn free_at() -> u32 {
    return vsm.pool.w;
}
fn new_counts_at() -> u32 {
    return 2u * vsm.pool.w;
}
@compute @workgroup_size(64, 1, 1)
fn cs_count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let b = block_of(gid, groups);
    if (b >= blocks()) {
        return;
    }
    var marked: array<u32, VSM_LEVELS>;
    var asked_pages: array<u32, VSM_LEVELS>;
    // The face of the entries (found again only when an entry lies past it).
    var first = 1u;
    var end = 0u;
    for (var e = b * BLOCK; e < min(b * BLOCK + BLOCK, vsm.counts.y); e++) {
        let v = atomicLoad(&vsm_table[e]);
        if (v == VSM_EMPTY) {
            continue;
        }
        if (e < first || e >= end) {
            let fi = face_of(e);
            first = vsm_faces[fi].table.x;
            end = select(vsm.counts.y, vsm_faces[min(fi + 1u, vsm.counts.x - 1u)].table.x, fi + 1u < vsm.counts.x);
        }
        let level = level_of(e - first);
        let asked = (v & MARK_ASKED) != 0u;
        atomicStore(&vsm_table[e], VSM_NEEDED_AT + level + select(0u, TAG_ASKED, asked));
        marked[level] += 1u;
        if (asked) {
            asked_pages[level] += 1u;
        }
    }
    for (var l = 0u; l < VSM_LEVELS; l++) {
        if (marked[l] != 0u) {
            atomicAdd(&counters[l], marked[l]);
            atomicAdd(&counters[COUNT_ASKED + l], asked_pages[l]);
        }
    }
}

// The admitted level A: the finest level whose marked pages, with the asked pages of every
// coarser level, fit the pool (that sum grows with A: an above-only page of A has a marked
// child at A + 1). Level 0 when not even that fits (cs_retain's quarter pages then).
fn admitted_level() -> u32 {
    var coarser = 0u;
    var admitted = 0u;
    for (var a = 0u; a < VSM_LEVELS; a = a + 1u) {
        if (coarser + atomicLoad(&counters[a]) > vsm.pool.w) {
            break;
        }
        admitted = a;
        coarser = coarser + atomicLoad(&counters[COUNT_ASKED + a]);
    }
    return admitted;
}

fn deny(e: u32, level: u32) {
    atomicStore(&vsm_table[e], VSM_DENIED);
    atomicAdd(&counters[COUNT_DENIED], 1u);
    if (level == 0u) {
        atomicAdd(&counters[COUNT_UNSHADOWED], 1u);
    }
}

// Whether page `local` of a face's chain (at `level`) overlaps where casters moved.
fn page_moved(face: VirtualFace, local: u32, level: u32) -> bool {
    let n = 1u << level;
    let within = local - ((1u << (2u * level)) - 1u) / 3u;
    let lo = vec2<f32>(f32(within % n), f32(within / n)) / f32(n);
    let hi = lo + vec2<f32>(1.0 / f32(n));
    let d = face.dirty;
    return d.x <= d.z && d.y <= d.w && all(lo <= d.zw) && all(d.xy <= hi);
}

@compute @workgroup_size(64, 1, 1)
fn cs_retain(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = gid.x + gid.y * groups.x * 64u;
    if (e >= vsm.counts.y) {
        return;
    }
    let v = atomicLoad(&vsm_table[e]);
    if (v < VSM_NEEDED_AT || v >= VSM_NEEDED_AT + 2u * TAG_ASKED) {
        return;
    }
    let level = (v - VSM_NEEDED_AT) % TAG_ASKED;
    let asked = v >= VSM_NEEDED_AT + TAG_ASKED;
    if (atomicLoad(&counters[0]) > vsm.pool.w) {
        // Not even level 0 fits: level-0 pages are placed by rank (cs_alloc_new; the last
        // ones in quarter pages), nothing else is admitted and nothing is kept.
        if (level == 0u) {
            atomicStore(&vsm_table[e], VSM_NEW_AT);
        } else if (asked) {
            deny(e, level);
        } else {
            atomicStore(&vsm_table[e], VSM_EMPTY);
        }
        return;
    }
    let admitted = admitted_level();
    if (level != admitted && !asked) {
        // Only an ancestor: nothing reads it at levels coarser than A (their asked pages'
        // own pages are resident) and finer ones are not admitted.
        atomicStore(&vsm_table[e], VSM_EMPTY);
        return;
    }
    if (level > admitted) {
        deny(e, level);
        return;
    }
    let face = vsm_faces[face_of(e)];
    if (face.table.w != 0u && !page_moved(face, e - face.table.x, level)) {
        let at = face.table.w - 1u + (e - face.table.x);
        let before = prev_table[at];
        let drawn = prev_table[prev_keys_at() + at];
        let drawn_cells = prev_table[prev_cells_at() + at];
        if (before >= VSM_FIRST_PAGE && before < VSM_FIRST_PAGE + VSM_QUARTER
            && covered(needed_bounds(e, level, admitted), drawn, drawn_cells)) {
            // Resident last frame, in an unchanged face, drawn far and wide enough: keep the
            // page and its depth (and the bounds it was drawn with).
            atomicStore(&vsm_table[e], before);
            atomicStore(&vsm_table[vsm.counts.y + e], drawn);
            atomicStore(&vsm_table[cells_at() + e], drawn_cells);
            scratch[kept_at() + before - VSM_FIRST_PAGE] = 1u;
            atomicAdd(&counters[COUNT_KEPT], 1u);
            return;
        }
    }
    atomicStore(&vsm_table[e], VSM_NEW_AT + level);
}

// Whether bounds `needed` (`needed_bounds`) lie within those a page was drawn with.
fn covered(needed: vec2<u32>, drawn: u32, drawn_cells: u32) -> bool {
    return needed.x <= drawn && (needed.y & ~drawn_cells) == 0u;
}

// Asked pages finer than the admitted level (denied: their samples read level `admitted`).
fn asked_finer_than(admitted: u32) -> u32 {
    var finer = 0u;
    for (var k = admitted + 1u; k < VSM_LEVELS; k = k + 1u) {
        finer = finer + atomicLoad(&counters[COUNT_ASKED + k]);
    }
    return finer;
}

// The receiver bounds admitted entry `e` (of `level`) is drawn with: x, its farthest
// receiver's key bits; y, the cells its samples' filter taps span. When not every sample that
// reads the page marked it (at the admitted level while finer asked pages are denied, their
// samples read it too; in the quarter-page regime; without receiver bounds; for an entry no
// sample asked for: an ancestor at the admitted level, read only by denied finer pages'
// samples): UNBOUNDED and ALL_CELLS.
fn needed_bounds(e: u32, level: u32, admitted: u32) -> vec2<u32> {
    let bounded = vsm.counts.w != 0u && atomicLoad(&counters[0]) <= vsm.pool.w
        && (level != admitted || asked_finer_than(admitted) == 0u);
    if (!bounded) {
        return vec2<u32>(UNBOUNDED, ALL_CELLS);
    }
    let key = atomicLoad(&vsm_table[vsm.counts.y + e]);
    return vec2<u32>(select(key, UNBOUNDED, key == 0u), span_cells(atomicLoad(&vsm_table[cells_at() + e])));
}

@compute @workgroup_size(1, 1, 1)
fn cs_free() {
    var k = 0u;
    for (var p = 0u; p < vsm.pool.w; p = p + 1u) {
        if (scratch[kept_at() + p] == 0u) {
            scratch[free_at() + k] = p;
            k = k + 1u;
        }
    }
    atomicStore(&counters[COUNT_FREE], k);
}

fn is_new(v: u32) -> bool {
    return v >= VSM_NEW_AT && v < VSM_NEW_AT + VSM_LEVELS;
}

@compute @workgroup_size(64, 1, 1)
fn cs_count_new(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let b = block_of(gid, groups);
    if (b >= blocks()) {
        return;
    }
    var n = 0u;
    for (var e = b * BLOCK; e < min(b * BLOCK + BLOCK, vsm.counts.y); e++) {
        if (is_new(atomicLoad(&vsm_table[e]))) {
            n += 1u;
        }
    }
    scratch[new_counts_at() + b] = n;
}

@compute @workgroup_size(1, 1, 1)
fn cs_scan_new() {
    var sum = 0u;
    for (var b = 0u; b < blocks(); b = b + 1u) {
        let c = scratch[new_counts_at() + b];
        scratch[new_counts_at() + b] = sum;
        sum = sum + c;
    }
    atomicStore(&counters[COUNT_NEW], sum);
    // Which new pages get room: normally one free pool page each while they last. When level
    // 0 alone exceeds the pool (every new page is a level-0 page then, and nothing is kept),
    // the last q of them share pool pages four to a page (quarter pages, half the face's
    // level-0 resolution): the fewest q with (sum - q) + ceil(q / 4) <= free, so that as many
    // faces as the pool can hold get a whole page and every face gets room while 4 per page
    // suffice.
    let free = atomicLoad(&counters[COUNT_FREE]);
    var whole = min(sum, free);
    var placed = whole;
    if (atomicLoad(&counters[0]) > vsm.pool.w && sum > free) {
        var q = min(sum, ((sum - free) * 4u + 2u) / 3u);
        while (q < sum && (sum - q) + (q + 3u) / 4u > free) {
            q = q + 1u;
        }
        whole = sum - q;
        placed = min(sum, whole + 4u * (free - min(whole, free)));
    }
    placed = min(placed, arrayLength(&page_views));
    atomicStore(&counters[COUNT_WHOLE], whole);
    atomicStore(&counters[COUNT_PLACED], placed);
}

@compute @workgroup_size(64, 1, 1)
fn cs_alloc_new(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let b = block_of(gid, groups);
    if (b >= blocks()) {
        return;
    }
    // Ranks among this frame's new pages, in page-table order.
    var rank = scratch[new_counts_at() + b];
    for (var e = b * BLOCK; e < min(b * BLOCK + BLOCK, vsm.counts.y); e++) {
        let v = atomicLoad(&vsm_table[e]);
        if (is_new(v)) {
            alloc_new(e, v - VSM_NEW_AT, rank);
            rank += 1u;
        }
    }
}

// New page `e` of `level`, of rank `rank` among the frame's new pages: its pool page (or
// quarter), its table entry and its view in the draw list.
fn alloc_new(e: u32, level: u32, rank: u32) {
    if (rank >= atomicLoad(&counters[COUNT_PLACED])) {
        // Only when level 0 alone overflows the pool even four faces to a page.
        deny(e, level);
        return;
    }
    let whole = atomicLoad(&counters[COUNT_WHOLE]);
    let side = f32(vsm.pool.z);
    var page = 0u;
    var corner = vec2<f32>(0.0);
    var size = side;
    var texel_scale = 1.0;
    if (rank < whole) {
        page = scratch[free_at() + rank];
        atomicStore(&vsm_table[e], VSM_FIRST_PAGE + page);
    } else {
        // A quarter page: quadrant k of a pool page shared by four faces' level 0.
        let k = rank - whole;
        page = scratch[free_at() + whole + k / 4u];
        let quadrant = k % 4u;
        atomicStore(&vsm_table[e], VSM_FIRST_PAGE + VSM_QUARTER + 4u * page + quadrant);
        size = 0.5 * side;
        corner = vec2<f32>(f32(quadrant % 2u), f32(quadrant / 2u)) * size;
        texel_scale = 2.0;
    }
    let fi = face_of(e);
    let face = vsm_faces[fi];
    let within = e - face.table.x - ((1u << (2u * level)) - 1u) / 3u;
    let n = 1u << level;
    let x = within % n;
    let y = within / n;
    // Crop the face's clip space to the page: ndc' = (ndc - centre) · n.
    let nf = f32(n);
    let cx = (2.0 * f32(x) + 1.0) / nf - 1.0;
    let cy = 1.0 - (2.0 * f32(y) + 1.0) / nf;
    let crop = mat4x4<f32>(
        vec4<f32>(nf, 0.0, 0.0, 0.0),
        vec4<f32>(0.0, nf, 0.0, 0.0),
        vec4<f32>(0.0, 0.0, 1.0, 0.0),
        vec4<f32>(-nf * cx, -nf * cy, 0.0, 1.0),
    );
    var view: ShadowViewData;
    view.view_proj = crop * face.view_proj;
    let origin = vec2<f32>(f32(page % vsm.pool.y), f32(page / vsm.pool.y)) * side + corner;
    view.tile = vec4<f32>(origin, size, bitcast<f32>(fi));
    // params.x: the receiver bound the page's casters are culled by (`needed_bounds`; the
    // largest finite f32 culls nothing); params.y: the cells drawn; both
    // kept with the page for the next frame's cs_retain. (params.z: the texel's world size.)
    let admitted = admitted_level();
    let needed = needed_bounds(e, level, admitted);
    var bound = needed.x;
    var cells = needed.y;
    if (vsm.prev.y != 0u) {
        // Pages that may be kept are drawn with some room to spare, so that a camera moving a
        // little does not outgrow them at once: one cell more on each side, an eighth deeper.
        cells = widen_cells(cells);
        if (bound != UNBOUNDED) {
            bound = bitcast<u32>(bitcast<f32>(bound) * 1.125);
        }
    }
    atomicStore(&vsm_table[vsm.counts.y + e], bound);
    atomicStore(&vsm_table[cells_at() + e], cells);
    view.params = vec4<f32>(bitcast<f32>(bound), f32(rect_code(cells)), face.params.z * f32(1u << (face.table.y - level)) * texel_scale, face.params.w);
    page_views[rank] = view;
}

@compute @workgroup_size(1, 1, 1)
fn cs_args() {
    let drawn = atomicLoad(&counters[COUNT_PLACED]);
    atomicStore(&counters[COUNT_DRAWN], drawn);
    let n = arrayLength(&rounds);
    for (var r = 0u; r < n; r = r + 1u) {
        let first = rounds[r].round.x;
        var slots = 0u;
        if (drawn > first) {
            slots = min(drawn - first, rounds[r].round.y);
        }
        // One cull thread per group of clusters the round touches (vsm_draw.wgsl's cs_cull).
        let lo = rounds[r].round.z;
        let groups = (lo + rounds[r].round.w + VSM_CULL_GROUP - 1u) / VSM_CULL_GROUP - lo / VSM_CULL_GROUP;
        args[3u * r] = (groups + 63u) / 64u;
        args[3u * r + 1u] = slots;
        args[3u * r + 2u] = 1u;
    }
    // draw_indirect: vertices, instances, first vertex, first instance.
    args[3u * n] = 6u;
    args[3u * n + 1u] = drawn;
    args[3u * n + 2u] = 0u;
    args[3u * n + 3u] = 0u;
}
