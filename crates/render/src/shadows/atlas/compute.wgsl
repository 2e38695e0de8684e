// `compute`: a software rasterizer for every listed shadow view in compute shaders.
//
// cs_setup     one thread per (triangle, round entry): per-view culling, near-plane clipping,
//              the fixed-function viewport transform and 8-bit sub-pixel snapping, then either
//              rasterizes a small triangle itself (exact integer edge functions) or appends its
//              large triangle as chunks of at most CHUNK² texels to `chunks`.
// cs_finalize  one thread: the indirect dispatch of cs_large (2D beyond the per-dimension limit).
// cs_large     one 8×8 workgroup per chunk.
//
// Depth goes into `depth` (one u32 per texel of the round's tiles) as 1.0's bits minus the
// depth's bits, with atomicMax: depths in [0, 1] order like their bits, so the largest value
// is the nearest depth (atomicMin on the bits, turned around so that the far plane is 0 and
// the buffer is cleared by a fill with zeros, much faster than a clear shader on software
// drivers). A render pass then copies the buffer into the atlas (compute_copy.wgsl).
//
// Matching the hardware path (`traditional`): window x = ndc.x · size/2 + (tile.x + size/2),
// y = ndc.y · (−size/2) + (tile.y + size/2), z = ndc.z; vertices snapped to 1/256 texel; a texel
// is covered when its centre (+0.5) is inside all three edges, ties going to top and left edges
// (D3D/Vulkan rule, y down); depth is the triangle's plane evaluated at the texel centre (z/w
// is affine in screen space; taken from the clip-space plane, which stays accurate for corners
// far outside the tile or clipped away); z < 0 is clipped
// geometrically (the near plane, which also removes w ≤ 0), z ≥ 1 per texel (the far plane).

struct ComputeParams {
    // triangles, cullable triangles, cull bits, entries in this round
    counts: vec4<u32>,
    // texels in this round, chunk capacity, most workgroups along x of a dispatch, flags
    sizes: vec4<u32>,
}

// Alpha-tested triangles (caster_layout.rs puts them last) test each covered texel's centre against
// their coverage mask (alpha_mask.wgsl) before writing depth; opaque ones skip the test.

// A chunk of a large triangle: its snapped corners (fixed point, positive orientation), its
// depth plane and the texels of the chunk.
struct Chunk {
    // A.x, A.y, B.x, B.y in 1/256 texel
    ab: vec4<f32>,
    // C.x, C.y, dz/dx, dz/dy
    cd: vec4<f32>,
    // x0, y0, z0: the depth plane's origin (the tile centre) and depth there, unused
    plane: vec4<f32>,
    // first texel x | y << 16, last texel x | y << 16 (atlas texels, inclusive), round entry,
    // 1 + the triangle if it is alpha-tested (0: opaque)
    rect: vec4<u32>,
}

const FLAG_DISCARD: u32 = 1u;
// Sub-pixel precision of the snapped vertices (8 bits, as Mesa's rasterizer and most GPUs).
const SUB: f32 = 256.0;
// Triangles whose vertex bounding box is narrower than this (in 1/256 texel) in both axes have
// exact 32-bit edge functions: every product stays below 2^30.
const EXACT_EXTENT: f32 = 32768.0;
// Most texels of a bounding box rasterized by the setup thread itself.
const SMALL_AREA: u32 = 512u;
// Side of a large triangle's chunk in texels (one 8×8 workgroup each).
const CHUNK: u32 = 32u;
const FAR_BITS: u32 = 0x3f800000u;

@group(0) @binding(0) var<uniform> params: ComputeParams;
@group(0) @binding(1) var<storage, read> views: array<ShadowViewData>;
@group(0) @binding(2) var<storage, read> eyes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> world: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> corners: array<u32>;
// Per round entry: view, first texel in `depth`, first tile row, rows. A uniform (at most
// MAX_ROUND_ENTRIES per round) keeps the pass within WebGPU's 8 storage buffers per stage.
const MAX_ROUND_ENTRIES: u32 = 4096u;
struct RoundEntries {
    list: array<vec4<u32>, MAX_ROUND_ENTRIES>,
}
@group(0) @binding(5) var<uniform> entries: RoundEntries;
@group(0) @binding(6) var<storage, read_write> depth: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> chunks: array<Chunk>;
// Chunks requested, chunks rasterized by their setup thread because the list was full.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 4>;

@group(1) @binding(0) var<storage, read_write> args: array<u32, 4>;

// The pipeline for alpha-tested triangles (caster_layout.rs puts them last): its cs_setup threads
// cover only those, and it tests masks. The opaque pipeline (false) compiles without any
// alpha test, so opaque casters rasterize exactly as before masks existed.
override ALPHA_TESTED: bool = false;

const NO_MASK: u32 = 0xffffffffu;
// The alpha-tested triangle this invocation rasterizes (NO_MASK: opaque) and its clip-space
// corners before near-plane clipping.
var<private> masked_tri: u32 = NO_MASK;
var<private> mask_clip: array<vec4<f32>, 3>;

// Whether texel (x, y) of `tile` is solid: always for opaque triangles; for an alpha-tested
// one, the mask at the point of the triangle seen through the texel's centre.
fn texel_solid(tile: vec4<f32>, x: u32, y: u32) -> bool {
    if (!ALPHA_TESTED || masked_tri == NO_MASK) {
        return true;
    }
    let half = 0.5 * tile.z;
    let ndc = vec2<f32>(
        (f32(x) + 0.5 - (tile.x + half)) / half,
        (tile.y + half - (f32(y) + 0.5)) / half,
    );
    let b = clip_barycentrics(mask_clip[0], mask_clip[1], mask_clip[2], ndc);
    return triangle_covered(mask_tail(), masked_tri, b);
}

// The rows of the atlas a round entry covers, as texel bounds (inclusive).
struct Band {
    lo: vec2<f32>,
    hi: vec2<f32>,
}

fn band_of(entry: vec4<u32>, tile: vec4<f32>) -> Band {
    var b: Band;
    b.lo = vec2<f32>(tile.x, tile.y + f32(entry.z));
    b.hi = vec2<f32>(tile.x + tile.z - 1.0, tile.y + f32(entry.z + entry.w) - 1.0);
    return b;
}

fn texel_index(entry: vec4<u32>, tile: vec4<f32>, x: u32, y: u32) -> u32 {
    return entry.y + (y - u32(tile.y) - entry.z) * u32(tile.z) + (x - u32(tile.x));
}

fn write_depth(index: u32, z: f32) {
    // Far clipping per texel; NaN fails too. -0.0 and rounding below the near plane become 0.
    if (z < 1.0) {
        atomicMax(&depth[index], FAR_BITS - select(bitcast<u32>(z), 0u, z <= 0.0));
    }
}

// Window position (x, y in texels of the atlas, z = depth) as the viewport transform computes it.
fn window(c: vec4<f32>, tile: vec4<f32>) -> vec3<f32> {
    let inv = 1.0 / c.w;
    let half = 0.5 * tile.z;
    return vec3<f32>(
        c.x * inv * half + (tile.x + half),
        c.y * inv * -half + (tile.y + half),
        c.z * inv,
    );
}

// Edge test of the large path, in f32. The edge is evaluated from its lexicographically first
// end point whichever triangle asks, so the two triangles sharing an edge compute the same value
// with opposite signs: exactly one of them owns a texel on it (no cracks), as with exact
// arithmetic. Rounding can only misplace texels within ~1/1000 texel of the edge.
fn edge_inside(u: vec2<f32>, v: vec2<f32>, p: vec2<f32>) -> bool {
    let swap = u.y > v.y || (u.y == v.y && u.x > v.x);
    let a = select(u, v, swap);
    let b = select(v, u, swap);
    var e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    if (swap) {
        e = -e;
    }
    let d = v - u;
    let top_left = d.y < 0.0 || (d.y == 0.0 && d.x > 0.0);
    return e > 0.0 || (e == 0.0 && top_left);
}

fn unpack_texel(v: u32) -> vec2<u32> {
    return vec2<u32>(v & 0xffffu, v >> 16u);
}

fn chunk_covers(ch: Chunk, x: u32, y: u32) -> bool {
    let p = vec2<f32>(f32(x) * SUB + 0.5 * SUB, f32(y) * SUB + 0.5 * SUB);
    return edge_inside(ch.ab.xy, ch.ab.zw, p) && edge_inside(ch.ab.zw, ch.cd.xy, p)
        && edge_inside(ch.cd.xy, ch.ab.xy, p);
}

fn chunk_depth(ch: Chunk, x: u32, y: u32) -> f32 {
    return ch.plane.z + ch.cd.z * (f32(x) + 0.5 - ch.plane.x) + ch.cd.w * (f32(y) + 0.5 - ch.plane.y);
}

// Rasterizes a chunk from one thread (the fallback when the chunk list is full).
fn raster_chunk_serial(ch: Chunk, entry: vec4<u32>, tile: vec4<f32>) {
    let lo = unpack_texel(ch.rect.x);
    let hi = unpack_texel(ch.rect.y);
    for (var y = lo.y; y <= hi.y; y++) {
        for (var x = lo.x; x <= hi.x; x++) {
            if (chunk_covers(ch, x, y) && texel_solid(tile, x, y)) {
                write_depth(texel_index(entry, tile, x, y), chunk_depth(ch, x, y));
            }
        }
    }
}

// Rasterizes one clip-space triangle (all w > 0) into round entry `e`.
fn raster_triangle(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, plane: vec3<f32>, e: u32, entry: vec4<u32>, tile: vec4<f32>) {
    if (c0.w <= 0.0 || c1.w <= 0.0 || c2.w <= 0.0) {
        return;
    }
    let w0 = window(c0, tile);
    let w1 = window(c1, tile);
    let w2 = window(c2, tile);
    // Snapped positions in 1/256 texel (round half to even, as the hardware's lrint).
    let s0 = round(w0.xy * SUB);
    var s1 = round(w1.xy * SUB);
    var s2 = round(w2.xy * SUB);
    let lo = min(s0, min(s1, s2));
    let hi = max(s0, max(s1, s2));
    // Texels whose centre (x + 0.5) lies in the box, clamped to the entry's band of the tile.
    let band = band_of(entry, tile);
    let first = max(ceil((lo - 0.5 * SUB) / SUB), band.lo);
    let last = min(floor((hi - 0.5 * SUB) / SUB), band.hi);
    if (any(first > last)) {
        // Zero coverage: outside the tile or between texel centres.
        return;
    }
    // Depth plane: z at the tile centre and its slope per texel.
    let half = 0.5 * tile.z;
    let centre = tile.xy + half;
    let z_c = plane.x;
    let dzdx = plane.y / half;
    let dzdy = -plane.z / half;
    let discard_raster = (params.sizes.w & FLAG_DISCARD) != 0u;

    let ext = hi - lo;
    let span = vec2<u32>(last - first) + 1u;
    if (ext.x < EXACT_EXTENT && ext.y < EXACT_EXTENT && span.x * span.y <= SMALL_AREA) {
        // Small: exact integer edge functions relative to the first texel centre.
        let origin = first * SUB + 0.5 * SUB;
        let a = vec2<i32>(s0 - origin);
        var b = vec2<i32>(s1 - origin);
        var c = vec2<i32>(s2 - origin);
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if (area == 0) {
            return;
        }
        if (area < 0) {
            let t = b;
            b = c;
            c = t;
        }
        if (discard_raster) {
            return;
        }
        // Per edge u→v: E(q) = dx·(q.y − u.y) − dy·(q.x − u.x), minus 1 unless the edge is a
        // top or left edge, so that "covered" is E ≥ 0 for all three.
        let d_ab = b - a;
        let d_bc = c - b;
        let d_ca = a - c;
        var row = vec3<i32>(
            d_ab.y * a.x - d_ab.x * a.y - select(1, 0, d_ab.y < 0 || (d_ab.y == 0 && d_ab.x > 0)),
            d_bc.y * b.x - d_bc.x * b.y - select(1, 0, d_bc.y < 0 || (d_bc.y == 0 && d_bc.x > 0)),
            d_ca.y * c.x - d_ca.x * c.y - select(1, 0, d_ca.y < 0 || (d_ca.y == 0 && d_ca.x > 0)),
        );
        let step_x = -256 * vec3<i32>(d_ab.y, d_bc.y, d_ca.y);
        let step_y = 256 * vec3<i32>(d_ab.x, d_bc.x, d_ca.x);
        let x0 = u32(first.x);
        let y0 = u32(first.y);
        for (var j = 0u; j < span.y; j++) {
            var ev = row;
            let y = y0 + j;
            let zy = z_c + dzdy * (f32(y) + 0.5 - centre.y);
            for (var i = 0u; i < span.x; i++) {
                let x = x0 + i;
                if (all(ev >= vec3<i32>(0)) && texel_solid(tile, x, y)) {
                    write_depth(texel_index(entry, tile, x, y), zy + dzdx * (f32(x) + 0.5 - centre.x));
                }
                ev += step_x;
            }
            row += step_y;
        }
        return;
    }

    // Large: positive orientation in f32, then chunks of CHUNK² texels.
    let area = (s1.x - s0.x) * (s2.y - s0.y) - (s1.y - s0.y) * (s2.x - s0.x);
    if (area == 0.0) {
        return;
    }
    if (area < 0.0) {
        let t = s1;
        s1 = s2;
        s2 = t;
    }
    var ch: Chunk;
    ch.ab = vec4<f32>(s0, s1);
    ch.cd = vec4<f32>(s2, dzdx, dzdy);
    ch.plane = vec4<f32>(centre, z_c, 0.0);
    let nx = (span.x + CHUNK - 1u) / CHUNK;
    let ny = (span.y + CHUNK - 1u) / CHUNK;
    let n = nx * ny;
    let base = atomicAdd(&counters[0], n);
    let capacity = params.sizes.y;
    let fx = u32(first.x);
    let fy = u32(first.y);
    let lx = u32(last.x);
    let ly = u32(last.y);
    for (var k = 0u; k < n; k++) {
        let cy = k / nx;
        let cx = k - cy * nx;
        let x = fx + cx * CHUNK;
        let y = fy + cy * CHUNK;
        ch.rect = vec4<u32>(x | (y << 16u), min(x + CHUNK - 1u, lx) | (min(y + CHUNK - 1u, ly) << 16u), e, masked_tri + 1u);
        if (base + k < capacity && base + k >= base) {
            chunks[base + k] = ch;
        } else {
            // The list is full: never drop work, rasterize the chunk here.
            atomicAdd(&counters[1], 1u);
            if (!discard_raster) {
                raster_chunk_serial(ch, entry, tile);
            }
        }
    }
}

fn det3(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return dot(a, cross(b, c));
}

// The edge a→b of a triangle crosses the near plane: the crossing point, computed from the
// inside end whichever triangle asks (neighbours get the same vertex, so no crack opens).
fn near_crossing(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    let a_in = a.z >= 0.0;
    let i = select(b, a, a_in);
    let o = select(a, b, a_in);
    let t = i.z / (i.z - o.z);
    var p = i + t * (o - i);
    p.z = max(p.z, 0.0);
    return p;
}

@compute @workgroup_size(64, 1, 1)
fn cs_setup(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let g = gid.x + gid.y * groups.x * 64u;
    // This pipeline's triangles: the opaque ones before the first alpha-tested one, or the
    // alpha-tested ones after it (the mask tail's header, alpha_mask.wgsl).
    let first_masked = corners[arrayLength(&corners) - 4u];
    var first = 0u;
    var tris = first_masked;
    if (ALPHA_TESTED) {
        first = first_masked;
        tris = params.counts.x - first_masked;
    }
    let e = g / max(tris, 1u);
    if (e >= params.counts.w) {
        return;
    }
    let tri = first + g - e * tris;
    let entry = entries.list[e];
    let view = views[entry.x];
    let p0 = world[corners[3u * tri]];
    let p1 = world[corners[3u * tri + 1u]];
    let p2 = world[corners[3u * tri + 2u]];
    let bits = params.counts.z;
    if ((bits & CULL_BACKFACE) != 0u && tri < params.counts.y
        && faces_away(p0.xyz, p1.xyz, p2.xyz, eyes[entry.x])) {
        return;
    }
    let c0 = view.view_proj * p0;
    let c1 = view.view_proj * p1;
    let c2 = view.view_proj * p2;
    if ((bits & CULL_FRUSTUM) != 0u && outside_frustum(c0, c1, c2)) {
        return;
    }
    if (ALPHA_TESTED) {
        masked_tri = tri;
        mask_clip = array<vec4<f32>, 3>(c0, c1, c2);
    }
    // The triangle's plane in clip space, A·x + B·y + C·z + D·w = 0 (the 4D cross product of
    // its corners), gives z/w as an affine function of NDC x, y that needs neither the
    // division by w nor the window positions of far-away (or clipped) corners: accurate
    // wherever the triangle is seen, and the same for every piece of a clipped triangle.
    // Rows c0, c1 − c0, c2 − c0 have the same minors and keep small triangles accurate.
    let e1 = c1 - c0;
    let e2 = c2 - c0;
    let pa = det3(c0.yzw, e1.yzw, e2.yzw);
    let pb = -det3(c0.xzw, e1.xzw, e2.xzw);
    let pc = det3(c0.xyw, e1.xyw, e2.xyw);
    let pd = -det3(c0.xyz, e1.xyz, e2.xyz);
    if (pc == 0.0) {
        // Seen edge-on: no area.
        return;
    }
    // z/w at the view's centre (NDC 0, 0) and its change per unit of NDC x and y.
    let plane = vec3<f32>(-pd / pc, -pa / pc, -pb / pc);
    let in0 = c0.z >= 0.0;
    let in1 = c1.z >= 0.0;
    let in2 = c2.z >= 0.0;
    if (!in0 && !in1 && !in2) {
        return;
    }
    // Clip against the near plane (z ≥ 0; this also removes every w ≤ 0): walk the edges
    // 0→1→2→0 keeping inside corners and adding crossings, then fan the 3 or 4 corners.
    var poly = array<vec4<f32>, 4>(c0, c1, c2, c2);
    var n = 3u;
    if (!(in0 && in1 && in2)) {
        n = 0u;
        var cs = array<vec4<f32>, 3>(c0, c1, c2);
        var ins = array<bool, 3>(in0, in1, in2);
        for (var k = 0u; k < 3u; k++) {
            let k1 = (k + 1u) % 3u;
            if (ins[k]) {
                poly[n] = cs[k];
                n++;
            }
            if (ins[k] != ins[k1]) {
                poly[n] = near_crossing(cs[k], cs[k1]);
                n++;
            }
        }
    }
    // One call site keeps the shader small (software drivers pay for code size).
    for (var k = 2u; k < n; k++) {
        raster_triangle(poly[0], poly[k - 1u], poly[k], plane, e, entry, view.tile);
    }
}

@compute @workgroup_size(1, 1, 1)
fn cs_finalize() {
    let n = min(atomicLoad(&counters[0]), params.sizes.y);
    let x = min(n, params.sizes.z);
    args[0] = x;
    args[1] = select(0u, (n + x - 1u) / max(x, 1u), x > 0u);
    args[2] = 1u;
    args[3] = 0u;
}

@compute @workgroup_size(8, 8, 1)
fn cs_large(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    let k = wg.x + wg.y * groups.x;
    if (k >= min(atomicLoad(&counters[0]), params.sizes.y)) {
        return;
    }
    let ch = chunks[k];
    let entry = entries.list[ch.rect.z];
    let view = views[entry.x];
    let tile = view.tile;
    if (ALPHA_TESTED && ch.rect.w != 0u) {
        let tri = ch.rect.w - 1u;
        masked_tri = tri;
        mask_clip = array<vec4<f32>, 3>(
            view.view_proj * world[corners[3u * tri]],
            view.view_proj * world[corners[3u * tri + 1u]],
            view.view_proj * world[corners[3u * tri + 2u]],
        );
    }
    let lo = unpack_texel(ch.rect.x);
    let hi = unpack_texel(ch.rect.y);
    for (var y = lo.y + lid.y; y <= hi.y; y += 8u) {
        for (var x = lo.x + lid.x; x <= hi.x; x += 8u) {
            if (chunk_covers(ch, x, y) && texel_solid(tile, x, y)) {
                write_depth(texel_index(entry, tile, x, y), chunk_depth(ch, x, y));
            }
        }
    }
}
