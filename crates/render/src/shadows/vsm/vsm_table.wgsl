// Virtual shadow maps (table.rs): what every page pass of pages.rs shares, composed before
// each stage's own WGSL (vsm_mark.wgsl, vsm_tiles.wgsl, vsm_carry.wgsl, vsm_alloc.wgsl):
// the page table and its bindings, the states of its entries, the frame's counters, and the
// walks through a face's mip chain of page grids.
//
// The stages, in the order pages.rs records them: *carry* (incrementally: last frame's needs
// asked again), *mark* (per pixel, or by tiles with their hand-off jobs: the pages the samples
// ask for and their ancestors), *alloc* (count, admit or deny, keep or place, the draw's
// indirect arguments).
//
// Receiver bounds: the marking keeps, per asked page, the largest depth key its samples
// compare against (after the table's entries: `vsm_table[entries + e]`) and the part of the
// page their filter taps reach (`vsm_table[2 entries + e]`: 16 columns and 16 rows of 8
// texels, bit masks). A page drawn with bounds holds every caster up to that depth, drawn
// over that rectangle, so it serves any sample nearer than the depth whose taps stay in the
// rectangle: the allocation writes the bounds each resident page was drawn with over its marks
// (UNBOUNDED and ALL_CELLS of vsm_alloc.wgsl when not bounded), the next frame receives them
// with the table, and a page is kept only while its samples stay within them.

@group(0) @binding(7) var<uniform> vsm: VsmUniforms;
@group(0) @binding(8) var<storage, read> vsm_faces: array<VirtualFace>;
@group(0) @binding(9) var<storage, read_write> vsm_table: array<atomic<u32>>;
// [0, 8): pages marked per level (asked or above); 9: pages kept from the last frame; 10: free
// pool pages; 11: new pages; 12: new pages that get room (full or quarter); 13: new pages that
// get a whole pool page (the rest of 12 get quarters); 14: cluster draws and 15: triangles
// drawn into pages (vsm_draw.wgsl's cull); 16: pages denied; 17: pages drawn this frame;
// 18: level-0 pages denied (faces left unshadowed); [20, 28): pages asked per level; [28, 33):
// the tile marking's VirtualStats::tiles; 33: level-0 pages that could be kept where level 0
// overflows the pool (vsm_alloc.wgsl).
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;
// Last frame's page table (for the pages it kept).
@group(0) @binding(14) var<storage, read> prev_table: array<u32>;

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
// A marked entry after vsm_alloc.wgsl's cs_count: this plus its level, plus TAG_ASKED if a
// sample asked for it.
const VSM_NEEDED_AT: u32 = 0x80000000u;

// Where last frame's table (`prev_table`) keeps its keys and cells: after its own entries.
fn prev_keys_at() -> u32 {
    return vsm.prev.x;
}
fn prev_cells_at() -> u32 {
    return 2u * vsm.prev.x;
}
// Where this frame's table keeps its cells (its keys: from `vsm.counts.y`, its entry count).
fn cells_at() -> u32 {
    return 2u * vsm.counts.y;
}

// Marks entry `e` as an ancestor of an asked page; false if it was marked already (its own
// ancestors are then marked, or being marked, by whoever marked it).
fn mark_above(e: u32) -> bool {
    if (atomicLoad(&vsm_table[e]) != VSM_EMPTY) {
        return false;
    }
    return atomicOr(&vsm_table[e], MARK_ABOVE) == VSM_EMPTY;
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
