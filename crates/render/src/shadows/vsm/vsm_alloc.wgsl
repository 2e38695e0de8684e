// Virtual shadow maps, page allocation (alloc.rs; composed after vsm_table.wgsl): from the
// marked page table to the pages drawn this frame, their pool pages and the draw's indirect
// arguments, with the frame's counts (VirtualStats).
//
// 1. cs_count, one thread per block of 32 page-table entries: each marked entry learns its
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
// 2. cs_retain, one thread per entry: an admitted page whose face is unchanged since the last
//    frame (the CPU sets `table.w`), that was resident then, that does not overlap where a
//    caster moved in the face (`dirty`, from the CPU) and whose casters were drawn up to at
//    least this frame's farthest receiver of the page (its receiver bounds, vsm_table.wgsl)
//    keeps its pool page and its contents (caching); the other admitted pages are tagged
//    new.
// 3. cs_free, one thread: the pool pages not kept, in order.
//    cs_count_new / cs_scan_new / cs_alloc_new: new pages get free pool pages by their rank
//    in page-table order (block counts and a prefix sum), so the frame never depends on
//    thread order, and each gets its view in the draw list: the face's projection cropped to
//    the page, drawn into the page's tile of the pool.
// 4. cs_args, one thread: the number of pages to draw, and from it the indirect arguments of
//    the page clear and of every cull round.

// The pages to draw this frame, in rank order: each one's view (the face's projection
// cropped to the page; `tile.w` holds the face index's bits).
@group(0) @binding(11) var<storage, read_write> page_views: array<ShadowViewData>;
// The page-render rounds (draw.rs): their first page slot, slots and clusters.
@group(0) @binding(12) var<storage, read> rounds: array<VsmRound>;
// Per round: dispatch arguments (x, y, z); after them: the clear's draw arguments.
@group(0) @binding(13) var<storage, read_write> args: array<u32>;
// Scratch, in u32 words: [0, P) pool page kept this frame (1/0); [P, 2P) free pool pages in
// order; [2P, 2P + B) per block: new pages, then their prefix. P = pool pages, B = blocks.
@group(0) @binding(15) var<storage, read_write> scratch: array<u32>;

// Page-table entries per allocation block (one thread walks them in order).
const BLOCK: u32 = 32u;
// Added to a marked entry's level by cs_count when a sample asked for it (VSM_NEEDED_AT).
const TAG_ASKED: u32 = 0x100u;
// An admitted entry without a kept page after cs_retain: this plus its level.
const VSM_NEW_AT: u32 = 0xc0000000u;
// A resident page's key when its casters were drawn without a receiver bound: the largest
// finite f32, above every key (and, as a draw's bound, culling nothing).
const UNBOUNDED: u32 = 0x7f7fffffu;

// Every cell of a page (column bits low, row bits high): the whole page.
const ALL_CELLS: u32 = 0xffffffffu;

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

// Counter of this stage (a free slot of vsm_table.wgsl's buffer): where level 0 alone
// overflows the pool, the level-0 pages that could keep last frame's whole pool page.
const COUNT_KEEPABLE: u32 = 33u;

// Entry `e`'s place in last frame's table, where its face is unchanged and the page does not
// overlap where casters moved (else none: 0xffffffff).
fn prev_at(e: u32, level: u32) -> u32 {
    let face = vsm_faces[face_of(e)];
    if (face.table.w == 0u || page_moved(face, e - face.table.x, level)) {
        return 0xffffffffu;
    }
    return face.table.w - 1u + (e - face.table.x);
}

// Whether entry `e` (of `level`) may keep last frame's page: resident then in a whole pool page
// of an unchanged face, drawn far and wide enough for this frame's samples.
fn keepable(e: u32, level: u32, admitted: u32) -> bool {
    let at = prev_at(e, level);
    if (at == 0xffffffffu) {
        return false;
    }
    let before = prev_table[at];
    return before >= VSM_FIRST_PAGE && before < VSM_FIRST_PAGE + VSM_QUARTER
        && covered(needed_bounds(e, level, admitted), prev_table[prev_keys_at() + at], prev_table[prev_cells_at() + at]);
}

// Keeps last frame's page of `e` and its depth (and the bounds it was drawn with).
fn keep(e: u32, level: u32) {
    let at = prev_at(e, level);
    let before = prev_table[at];
    atomicStore(&vsm_table[e], before);
    atomicStore(&vsm_table[vsm.counts.y + e], prev_table[prev_keys_at() + at]);
    atomicStore(&vsm_table[cells_at() + e], prev_table[prev_cells_at() + at]);
    scratch[kept_at() + before - VSM_FIRST_PAGE] = 1u;
    atomicAdd(&counters[COUNT_KEPT], 1u);
}

// Whether a marked level-0 entry `v` (vsm_table's word).
fn marked_level_zero(v: u32) -> bool {
    return v >= VSM_NEEDED_AT && v < VSM_NEEDED_AT + 2u * TAG_ASKED && (v - VSM_NEEDED_AT) % TAG_ASKED == 0u;
}

// Before cs_retain, where level 0 alone overflows the pool: counts the level-0 pages that could
// keep their whole pool page (cs_retain keeps them all or none).
@compute @workgroup_size(64, 1, 1)
fn cs_count_keepable(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = gid.x + gid.y * groups.x * 64u;
    if (e >= vsm.counts.y || atomicLoad(&counters[0]) <= vsm.pool.w) {
        return;
    }
    if (marked_level_zero(atomicLoad(&vsm_table[e])) && keepable(e, 0u, 0u)) {
        atomicAdd(&counters[COUNT_KEEPABLE], 1u);
    }
}

// Whether the `k` keepable level-0 pages may be kept when level 0 (`n0` faces) overflows the
// pool: only if every face still gets room, the new ones four to a page in what the kept ones
// leave (cs_scan_new), so keeping never leaves a face unshadowed that a fresh frame shades.
fn keep_in_overflow(k: u32, n0: u32) -> bool {
    let pool = vsm.pool.w;
    return k > 0u && k <= pool && (n0 - k + 3u) / 4u <= pool - k;
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
    let n0 = atomicLoad(&counters[0]);
    if (n0 > vsm.pool.w) {
        // Not even level 0 fits: nothing else is admitted; level-0 pages keep last frame's
        // whole pool pages where all of those that can fit beside the rest (keep_in_overflow),
        // and the new ones are placed by rank (cs_alloc_new; the last ones in quarter pages).
        if (level == 0u) {
            if (keep_in_overflow(atomicLoad(&counters[COUNT_KEEPABLE]), n0) && keepable(e, 0u, 0u)) {
                keep(e, 0u);
            } else {
                atomicStore(&vsm_table[e], VSM_NEW_AT);
            }
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
    if (keepable(e, level, admitted)) {
        // Resident last frame, in an unchanged face, drawn far and wide enough: keep the
        // page and its depth (and the bounds it was drawn with).
        keep(e, level);
        return;
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
