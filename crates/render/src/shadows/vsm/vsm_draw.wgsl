// Virtual shadow maps (draw.rs), rendering the resident pages: every page is an ordinary
// shadow view (the face's projection cropped to the page, one tile of the pool), so pages are
// drawn the `gpu-driven` way: a compute pass culls caster clusters against each page's
// frustum slice and writes indexed-indirect commands, one multi-draw renders the survivors
// into the pages' tiles. `page_views` lists this frame's pages to draw (kept pages are not in
// it); their count is known only on the GPU: cull dispatches are indirect, and rounds past
// the last page cull nothing.
//
// The cull is hierarchical: clusters come in groups of VSM_CULL_GROUP consecutive ones (one
// instance's neighbouring triangles, mostly), whose bounding spheres casters.wgsl's cs_groups
// merges once per frame, after the clusters' (cluster_bounds[clusters + g]). One
// thread per (group, page) tests the group's sphere and only if it is inside the page tests
// the group's clusters, so a page far from most of the scene costs a thread per group, not
// one per cluster.

@group(0) @binding(0) var<uniform> round: VsmRound;
@group(0) @binding(1) var<uniform> vsm: VsmUniforms;
@group(0) @binding(2) var<storage, read> page_views: array<ShadowViewData>;

// The part of a page its samples' filter taps reach (vsm_alloc.wgsl's `needed_bounds`): the page's
// casters are culled and drawn over that rectangle only, in cells of 1/16 of the page side.
// `params.y` codes the first and last column and row (0..15 each) as
// `first_col + 16 last_col + 256 first_row + 4096 last_row` (rows count from the page's top).
// Returns x0, x1, y0, y1 in the page's normalized device coordinates.
fn drawn_rect(view: ShadowViewData) -> vec4<f32> {
    let c = drawn_cells(view);
    let col = vec2<f32>(c.x, c.y + 1.0) / 8.0 - 1.0;
    let row = 1.0 - vec2<f32>(c.w + 1.0, c.z) / 8.0;
    return vec4<f32>(col, row);
}

// The drawn rectangle's first and last column, first and last row (cells, rows from the top).
fn drawn_cells(view: ShadowViewData) -> vec4<f32> {
    let code = u32(view.params.y);
    return vec4<f32>(vec4<u32>(code, code >> 4u, code >> 8u, code >> 12u) & vec4<u32>(15u));
}

// A clip position of the page in the clip space of its drawn rectangle (x and y scaled and
// moved; z and w unchanged).
fn into_drawn(r: vec4<f32>, c: vec4<f32>) -> vec4<f32> {
    let s = vec2<f32>(2.0 / (r.y - r.x), 2.0 / (r.w - r.z));
    let m = vec2<f32>(r.x + r.y, r.z + r.w) * 0.5;
    return vec4<f32>(s.x * (c.x - m.x * c.w), s.y * (c.y - m.y * c.w), c.z, c.w);
}

// The page's projection restricted to its drawn rectangle (for the frustum tests).
fn drawn_proj(view: ShadowViewData) -> mat4x4<f32> {
    let r = drawn_rect(view);
    if (all(r == vec4<f32>(-1.0, 1.0, -1.0, 1.0))) {
        return view.view_proj;
    }
    let s = vec2<f32>(2.0 / (r.y - r.x), 2.0 / (r.w - r.z));
    let m = vec2<f32>(r.x + r.y, r.z + r.w) * 0.5;
    let sub = mat4x4<f32>(
        vec4<f32>(s.x, 0.0, 0.0, 0.0),
        vec4<f32>(0.0, s.y, 0.0, 0.0),
        vec4<f32>(0.0, 0.0, 1.0, 0.0),
        vec4<f32>(-s.x * m.x, -s.y * m.y, 0.0, 1.0),
    );
    return sub * view.view_proj;
}

// ---- cull (compute) ----

@group(0) @binding(4) var<storage, read> vsm_faces: array<VirtualFace>;
@group(0) @binding(5) var<storage, read> clusters: array<GpuCluster>;
@group(0) @binding(6) var<storage, read> cluster_bounds: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> instances: array<InstanceData>;
@group(0) @binding(8) var<storage, read_write> commands: array<DrawCommand>;
// [0] (cluster, page) pairs the cull found, [1] triangles kept by the expansion (past
// `expanded`'s capacity their pairs are drawn whole), [2] and [3] unused.
@group(0) @binding(9) var<storage, read_write> command_count: array<atomic<u32>, 4>;
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;
// One thread per (group, page slot) of the round; the round's clusters are [lo, hi) and its
// groups those from lo / VSM_CULL_GROUP on.
@compute @workgroup_size(64, 1, 1)
fn cs_cull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.y;
    let lo = round.round.z;
    let hi = lo + round.round.w;
    let g = lo / VSM_CULL_GROUP + gid.x;
    if (g * VSM_CULL_GROUP >= hi || slot >= round.round.y) {
        return;
    }
    let page = round.round.x + slot;
    let bits = round.counts.z;
    let compact = round.counts.w != 0u;
    // Slots past the last resident page draw nothing (only reached without compaction,
    // where every slot's command is written).
    let view = page_views[min(page, arrayLength(&page_views) - 1u)];
    var group_visible = page < atomicLoad(&counters[17]);
    let frustum = (bits & CULL_FRUSTUM) != 0u;
    let planes = page_planes(view);
    if (group_visible && frustum && (bits & VSM_FLAT_CULL) == 0u) {
        if (sphere_outside_page(planes, view, cluster_bounds[arrayLength(&clusters) + g])) {
            group_visible = false;
        }
    }
    if (!group_visible && compact) {
        return;
    }
    let eye = vsm_faces[min(bitcast<u32>(view.tile.w), arrayLength(&vsm_faces) - 1u)].eye;
    var draws = 0u;
    var triangles = 0u;
    for (var c = max(lo, g * VSM_CULL_GROUP); c < min(hi, g * VSM_CULL_GROUP + VSM_CULL_GROUP); c++) {
        let cl = clusters[c];
        var visible = group_visible;
        if (visible) {
            let sphere = cluster_bounds[c];
            let boxes = arrayLength(&clusters) + (arrayLength(&clusters) + VSM_CULL_GROUP - 1u) / VSM_CULL_GROUP;
            if (frustum && (sphere_outside_page(planes, view, sphere)
                || box_outside(planes, view, boxes + 2u * c))) {
                visible = false;
            } else if ((bits & CULL_BACKFACE) != 0u && cl.first_triangle < round.counts.y
                && cluster_faces_away(cl, instances[cl.instance].normal, sphere, eye)) {
                visible = false;
            }
        }
        // With compaction: which parts of the cluster touch the page (their boxes), for
        // cs_expand to skip the others' triangles.
        var parts = (1u << VSM_PARTS) - 1u;
        if (visible && compact && frustum) {
            let n = arrayLength(&clusters);
            let first_part = 3u * n + (n + VSM_CULL_GROUP - 1u) / VSM_CULL_GROUP + 2u * VSM_PARTS * c;
            for (var k = 0u; k < VSM_PARTS; k++) {
                if (k * VSM_PART_TRIANGLES >= cl.triangles || box_outside(planes, view, first_part + 2u * k)) {
                    parts = parts & ~(1u << k);
                }
            }
            visible = parts != 0u;
        }
        var cmd: DrawCommand;
        cmd.index_count = select(0u, 3u * cl.triangles, visible);
        cmd.instance_count = 1u;
        cmd.first_index = 3u * cl.first_triangle;
        cmd.base_vertex = i32(slot * round.counts.x);
        cmd.first_instance = 0u;
        if (compact) {
            // A (cluster, page) pair for cs_expand, and its whole-cluster command, empty
            // unless the expansion runs out of room for the pair's triangles.
            if (visible) {
                let k = atomicAdd(&command_count[0], 1u);
                var pair = cmd;
                // The part mask and the page slot (saves cs_expand a division per thread).
                pair.first_instance = parts | (slot << VSM_PARTS);
                commands[k] = pair;
                var empty = cmd;
                empty.index_count = 0u;
                commands[round.counts.w + k] = empty;
            }
        } else {
            commands[slot * round.round.w + (c - lo)] = cmd;
        }
        if (visible) {
            draws = draws + 1u;
            triangles = triangles + cl.triangles;
        }
    }
    if (draws != 0u) {
        atomicAdd(&counters[14], draws);
        if (!compact) {
            atomicAdd(&counters[15], triangles);
        }
    }
}

// The row of a face's (or page's: the crop leaves rows z and w alone) projection whose dot
// product with a point is its distance key: w for perspective, z for orthographic
// (`ortho` = params.w), as vsm_common.wgsl's `VsmPoint::key`.
fn key_row(view_proj: mat4x4<f32>, ortho: f32) -> vec4<f32> {
    let r = select(3u, 2u, ortho > 0.5);
    return vec4<f32>(view_proj[0][r], view_proj[1][r], view_proj[2][r], view_proj[3][r]);
}

// A page's culling planes, built once per cull thread: its drawn rectangle's clip volume
// (cluster_cull.wgsl's `ViewPlanes`) and the row whose dot product with a point is its distance
// key (`key_row`).
struct PagePlanes {
    clip: ViewPlanes,
    row: vec4<f32>,
}

fn page_planes(view: ShadowViewData) -> PagePlanes {
    var out: PagePlanes;
    out.clip = view_planes(drawn_proj(view));
    out.row = key_row(view.view_proj, view.params.w);
    return out;
}

// Whether a caster sphere lies wholly outside the page's drawn frustum or wholly beyond the
// page's farthest receiver (`params.x`, 0 = no bound): its depths then exceed every depth the
// page's samples compare against, so it can shadow none of them (the comparison is
// `receiver <= stored`).
fn sphere_outside_page(planes: PagePlanes, view: ShadowViewData, s: vec4<f32>) -> bool {
    if (sphere_outside_planes(planes.clip, s)) {
        return true;
    }
    let row = planes.row;
    return key_beyond(view.params.x, dot(row, vec4<f32>(s.xyz, 1.0)) - s.w * length(row.xyz));
}

// The largest value of plane `p` over the box of centre `c` and half extent `e` (at the corner
// farthest along the plane's normal), less a slack of a few ulps of its terms so that rounding
// never puts a box that touches the plane outside it.
fn box_reach(p: vec4<f32>, c: vec3<f32>, e: vec3<f32>, scale: vec3<f32>) -> f32 {
    let a = abs(p.xyz);
    return dot(p.xyz, c) + p.w + dot(a, e) + 1e-6 * (dot(a, scale) + abs(p.w));
}

// Whether the box at cluster_bounds[at] (low corner; + 1: high corner) — a cluster's or a
// cluster part's, which casters.wgsl writes after the groups' spheres — lies wholly outside
// one side of the page's drawn rectangle, or beyond its farthest receiver: each side is a
// half-space of homogeneous clip space, so the box is outside it when the corner reaching
// farthest into it is (the seed's re-projected cluster boxes, without transforming eight
// corners). Tighter than the sphere for flat and long clusters.
fn box_outside(planes: PagePlanes, view: ShadowViewData, at: u32) -> bool {
    let lo = cluster_bounds[at].xyz;
    let hi = cluster_bounds[at + 1u].xyz;
    let c = 0.5 * (lo + hi);
    let e = 0.5 * (hi - lo);
    let scale = abs(c) + e;
    let v = planes.clip;
    if (box_reach(v.left, c, e, scale) < 0.0 || box_reach(v.right, c, e, scale) < 0.0
        || box_reach(v.bottom, c, e, scale) < 0.0 || box_reach(v.top, c, e, scale) < 0.0) {
        return true;
    }
    // The nearest key over the box: the reach of the negated row, negated.
    return key_beyond(view.params.x, -box_reach(-planes.row, c, e, scale));
}

// Whether a triangle (page clip positions, all in front of the light) lies between the page's
// texel centres on some axis, so that rasterizing it writes no texel: its bounding box in
// page texels (`side` of them) holds no centre k + 1/2 with a margin far above the
// rasterizer's 1/256-texel snapping. Small triangles of coarse pages are most of a
// detailed caster's, and each costs a software rasterizer its setup.
fn covers_no_texel(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, side: f32) -> bool {
    if (min(a.w, min(b.w, c.w)) <= 0.0) {
        return false;
    }
    let s = vec2<f32>(0.5, -0.5) * side;
    let ta = a.xy / a.w * s;
    let tb = b.xy / b.w * s;
    let tc = c.xy / c.w * s;
    // Centres sit at k + 1/2 from the page's corner, i.e. at integers from its middle
    // (`side` is even) minus one half: shift by the half.
    let lo = min(ta, min(tb, tc)) + vec2<f32>(0.5 * side - 0.5);
    let hi = max(ta, max(tb, tc)) + vec2<f32>(0.5 * side - 0.5);
    let margin = 1.0 / 32.0;
    return any(ceil(lo - margin) > floor(hi + margin));
}

// Whether distance key `nearest` lies beyond receiver bound `bound` (0 = none).
fn key_beyond(bound: f32, nearest: f32) -> bool {
    return bound > 0.0 && nearest > bound + 1e-4 * abs(bound) + 1e-6;
}

// ---- triangle expansion (compute; with compaction) ----
//
// The cull's pairs become triangles: one thread per (cluster, page) pair, one loop step per
// triangle, each tested against the page as the cluster was (outside the page's sides, beyond
// its farthest receiver, facing away from the light where that is exact) and the survivors'
// corners written, tagged with the page's slot, to `expanded`, which one indexed draw per
// round renders. Software drivers transform vertices on one thread; this keeps that thread
// to the triangles that touch a page. Where `expanded` runs out, the pairs of the triangles
// past it are drawn whole from the corner buffer (the commands from `round.counts.w` on).

@group(0) @binding(15) var<storage, read_write> expanded: array<u32>;

// One thread per pair walks the pair's triangles (the parts the cull kept), keeps the
// survivors' numbers in a private list and reserves their room with one atomic: the page's
// view, drawn rectangle and projection are read and built once per pair, not per triangle,
// and a software driver runs no per-pair workgroup.
@compute @workgroup_size(64, 1, 1)
fn cs_expand(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * groups.x * 64u;
    if (k >= atomicLoad(&command_count[0])) {
        return;
    }
    var cmd = commands[k];
    let parts = cmd.first_instance & ((1u << VSM_PARTS) - 1u);
    let slot = cmd.first_instance >> VSM_PARTS;
    cmd.first_instance = 0u;
    let view = page_views[min(round.round.x + slot, arrayLength(&page_views) - 1u)];
    let r = drawn_rect(view);
    let ortho = view.params.w > 0.5;
    let bits = round.counts.z;
    let frustum = (bits & CULL_FRUSTUM) != 0u;
    let backface = (bits & CULL_BACKFACE) != 0u;
    let eye = vsm_faces[min(bitcast<u32>(view.tile.w), arrayLength(&vsm_faces) - 1u)].eye;
    let first = cmd.first_index / 3u;
    let triangles = cmd.index_count / 3u;
    var kept: array<u32, VSM_CLUSTER_TRIANGLES>;
    var n = 0u;
    for (var part = 0u; part < VSM_PARTS; part++) {
        if ((parts & (1u << part)) == 0u) {
            continue;
        }
        let hi = min(triangles, (part + 1u) * VSM_PART_TRIANGLES);
        for (var t = part * VSM_PART_TRIANGLES; t < hi; t++) {
            let at = 3u * (first + t);
            let p0 = world[corners[at]].xyz;
            let p1 = world[corners[at + 1u]].xyz;
            let p2 = world[corners[at + 2u]].xyz;
            if (frustum) {
                let pa = view.view_proj * vec4<f32>(p0, 1.0);
                let pb = view.view_proj * vec4<f32>(p1, 1.0);
                let pc = view.view_proj * vec4<f32>(p2, 1.0);
                if (covers_no_texel(pa, pb, pc, view.tile.z)) {
                    continue;
                }
                // In the drawn rectangle's clip space, as vs_draw clips them.
                let a = into_drawn(r, pa);
                let b = into_drawn(r, pb);
                let c = into_drawn(r, pc);
                // The drawn rectangle's sides only: depth is left to the rasterizer.
                let outside = (a.x < -a.w && b.x < -b.w && c.x < -c.w)
                    || (a.x > a.w && b.x > b.w && c.x > c.w)
                    || (a.y < -a.w && b.y < -b.w && c.y < -c.w)
                    || (a.y > a.w && b.y > b.w && c.y > c.w);
                let nearest = select(min(a.w, min(b.w, c.w)), min(a.z, min(b.z, c.z)), ortho);
                if (outside || key_beyond(view.params.x, nearest)) {
                    continue;
                }
            }
            if (backface && first + t < round.counts.y && faces_away(p0, p1, p2, eye)) {
                continue;
            }
            kept[n] = t;
            n = n + 1u;
        }
    }
    if (n == 0u) {
        return;
    }
    let v = atomicAdd(&command_count[1], n);
    let room = arrayLength(&expanded) / 3u;
    let base = u32(cmd.base_vertex);
    for (var j = 0u; j < n && v + j < room; j++) {
        let at = 3u * (first + kept[j]);
        let w = 3u * (v + j);
        expanded[w] = base + corners[at];
        expanded[w + 1u] = base + corners[at + 1u];
        expanded[w + 2u] = base + corners[at + 2u];
    }
    if (v + n > room) {
        // Out of room: the pair is drawn whole (its triangles written below the room's end are
        // drawn twice, to the same depth).
        commands[round.counts.w + k] = cmd;
    }
}

// The expansion's dispatch (one thread per pair) and, after it, the
// round's indexed draw of what it kept.
@group(0) @binding(16) var<storage, read_write> round_args: array<u32, 9>;
@group(0) @binding(17) var<storage, read> round_counts: array<u32, 4>;

@compute @workgroup_size(1, 1, 1)
fn cs_expand_args() {
    // One thread per pair, in workgroups of 64, rows of 65,535 workgroups.
    let n = (round_counts[0] + 63u) / 64u;
    round_args[0] = min(n, 65535u);
    round_args[1] = (n + 65534u) / 65535u;
    round_args[2] = 1u;
}

@compute @workgroup_size(1, 1, 1)
fn cs_draw_args() {
    round_args[3] = 3u * min(round_counts[1], arrayLength(&expanded) / 3u);
    // Triangles drawn into pages (the stats): every one the expansion kept.
    atomicAdd(&counters[15], round_counts[1]);
    round_args[4] = 1u;
    round_args[5] = 0u;
    round_args[6] = 0u;
    round_args[7] = 0u;
    // The whole-cluster commands (one per pair) are drawn only if the expansion overflowed.
    round_args[8] = select(0u, round_counts[0], round_counts[1] > arrayLength(&expanded) / 3u);
}

// ---- draw and clear (vertex) ----

@group(0) @binding(11) var<storage, read> world: array<vec4<f32>>;
// The corner buffer, read for its mask tail by the alpha-tested rounds (alpha_mask.wgsl).
@group(0) @binding(13) var<storage, read> corners: array<u32>;

@vertex
fn vs_draw(@builtin(vertex_index) v: u32) -> TileOut {
    let slot = v / round.counts.x;
    return draw(slot, v - slot * round.counts.x);
}

fn draw(slot: u32, vertex: u32) -> TileOut {
    let view = page_views[round.round.x + slot];
    let c = view.view_proj * world[vertex];
    var out = into_tile_of(c, view.tile, 1.0 / f32(vsm.pool.x));
    // Clipped to the page's drawn rectangle (the whole page: into_tile_of's distances).
    let r = drawn_rect(view);
    out.clip = array<f32, 5>(c.x - r.x * c.w, r.y * c.w - c.x, c.y - r.z * c.w, r.w * c.w - c.y, 1.0);
    return out;
}

// Rounds of alpha-tested clusters, drawn with `fs_alpha`.
@vertex
fn vs_draw_masked(@builtin(vertex_index) v: u32) -> MaskedTileOut {
    let slot = v / round.counts.x;
    let vertex = v - slot * round.counts.x;
    return masked_tile_out(draw(slot, vertex), mask_tail(), vertex);
}

// Covers drawn page `i`'s drawn rectangle of its tile at depth 1 (far), before its casters are
// drawn (texels outside it are read by no sample that asked for the page).
@vertex
fn vs_clear(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> @builtin(position) vec4<f32> {
    let tile = page_views[i].tile;
    var quad = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    // The rectangle in page texels, from the page's drawn cells (rows from the top).
    let c = drawn_cells(page_views[i]);
    let cell = tile.z / 16.0;
    let lo = c.xz * cell;
    let hi = c.yw * cell + cell;
    let px = tile.xy + lo + quad[v % 6u] * (hi - lo);
    let size = f32(vsm.pool.x);
    return vec4<f32>(px.x / size * 2.0 - 1.0, 1.0 - px.y / size * 2.0, 1.0, 1.0);
}
