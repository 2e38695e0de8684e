// Virtual shadow maps, per-pixel page marking (mark.rs; composed after vsm_table.wgsl):
//
// cs_mark, one thread per pixel: for every light of the pixel's cluster that reaches the
// sample (and faces it, unless back-facing samples are wanted too), the page of the level
// whose texels match the pixel's footprint is marked *asked*, and its ancestors up to level 0
// are marked *above* (whoever turns an entry from unmarked to marked walks its ancestors, so a
// walk stops at the first entry already marked). Incrementally (only casters moved; see
// vsm_carry.wgsl) it visits a rectangle of the screen. Each asked page also keeps its
// receiver bounds (vsm_table.wgsl).
//
// The tile marking (vsm_tiles.wgsl) is composed after this file: it marks with the same
// functions (mark_light, mark_pixel, ask_page, bound_page), so that it asks for exactly the
// pages cs_mark asks for.

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<LightData>;
@group(0) @binding(2) var gbuf_position: texture_2d<u32>;
@group(0) @binding(3) var gbuf_normal: texture_2d<u32>;
@group(0) @binding(4) var<uniform> clusters: ClusterUniforms;
@group(0) @binding(5) var<storage, read> cluster_slots: array<u32>;
@group(0) @binding(6) var<storage, read> cluster_masks: array<u32>;
// Declared for shadow_lookup.wgsl's `atlas_coord`, which these entry points never call.
@group(1) @binding(0) var<storage, read> shadow_views: array<ShadowViewData>;

// mark_pixel's light for every light of the pixel's cluster.
const ALL_LIGHTS: u32 = 0xffffffffu;
// Texels a filter tap reaches from a sample's texel position (PCF 3x3: 1.5).
const TAP_REACH: f32 = 2.0;

// The cells (columns | rows << 16) the filter taps of a sample at `uv` reach in its page of
// `level`.
fn tap_cells(uv: vec2<f32>, level: u32) -> u32 {
    return tap_cells_within(uv, level, TAP_REACH);
}

// The cells taps up to `reach` texels from a sample at `uv` reach in its page of `level`.
fn tap_cells_within(uv: vec2<f32>, level: u32, reach: f32) -> u32 {
    let pages = f32(1u << level);
    let t = (uv * pages - min(floor(uv * pages), vec2<f32>(pages - 1.0))) * f32(vsm.pool.z);
    return cells_reached(t, t, reach);
}

// The cells the filter taps of samples at page texel positions from `t0` to `t1` reach.
fn cells_between(t0: vec2<f32>, t1: vec2<f32>) -> u32 {
    return cells_reached(t0, t1, TAP_REACH);
}

// The cells within `reach` texels of a sample at `uv` in the page of `level` that holds
// `inside` (a page beside the sample's: the sample lies outside it, the cells along the
// border it faces).
fn cells_beside(uv: vec2<f32>, inside: vec2<f32>, level: u32, reach: f32) -> u32 {
    let pages = f32(1u << level);
    let t = (uv * pages - min(floor(inside * pages), vec2<f32>(pages - 1.0))) * f32(vsm.pool.z);
    return cells_reached(t, t, reach);
}

// The cells within `reach` texels of page texel positions from `t0` to `t1`.
fn cells_reached(t0: vec2<f32>, t1: vec2<f32>, reach: f32) -> u32 {
    let cell = f32(vsm.pool.z) / 16.0;
    let lo = vec2<u32>(clamp(floor((t0 - reach) / cell), vec2<f32>(0.0), vec2<f32>(15.0)));
    let hi = vec2<u32>(clamp(floor((t1 + reach) / cell), vec2<f32>(0.0), vec2<f32>(15.0)));
    let cols = (2u << hi.x) - (1u << lo.x);
    let rows = (2u << hi.y) - (1u << lo.y);
    return cols | (rows << 16u);
}

// Marks the page light `i` needs for the sample at `p` (unit normal `n`, camera view depth
// `view_depth`), with its receiver bounds when they are kept.
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
    if (light.diffuse.w > 0.0) {
        mark_soft(face, level, q, e);
        return;
    }
    if (vsm.counts.w != 0u) {
        // The farthest receiver of the page (keys are never negative as bits: 0 = no bound).
        bound_page(e, bitcast<u32>(max(q.key, 0.0)), tap_cells(q.uv, level));
    }
    ask_page(face, level, q.uv, e);
}

// A sized light's sample: its soft filter's taps reach up to the largest penumbra (and a
// texel) from it, so the pages within that reach are asked for too, with bounds over the
// cells the taps reach (in a page beside the sample's, those along the border it faces) and
// the sample's own depth key: no tap compares against a depth past the receiver's
// (pcss.wgsl's `soft_reference`).
fn mark_soft(face: VirtualFace, level: u32, q: VsmPoint, e: u32) {
    let reach = frame.soft.z + 1.0;
    let key = bitcast<u32>(max(q.key, 0.0));
    if (vsm.counts.w != 0u) {
        bound_page(e, key, tap_cells_within(q.uv, level, reach));
    }
    ask_page(face, level, q.uv, e);
    for (var k = 0u; k < 4u; k = k + 1u) {
        let uv = reach_corner(q.uv, level, k);
        let n = vsm_entry(face, level, uv);
        if (n != e) {
            if (vsm.counts.w != 0u) {
                bound_page(n, key, cells_beside(q.uv, uv, level, reach));
            }
            ask_page(face, level, uv, n);
        }
    }
}

// Corner `k` of the square a sized light's filter taps reach around a sample at `uv` in the
// face at `level` (the largest penumbra and a texel away), clamped into the face. The tile
// marking (vsm_tiles.wgsl) computes the same corners of its samples' rectangle with it, so
// that both find the same pages.
fn reach_corner(uv: vec2<f32>, level: u32, k: u32) -> vec2<f32> {
    let r = vec2<f32>((frame.soft.z + 1.0) / (f32(1u << level) * f32(vsm.pool.z)));
    let corner = vec2<f32>(f32(k & 1u), f32(k >> 1u)) * 2.0 - vec2<f32>(1.0);
    return clamp(uv + corner * r, vec2<f32>(0.0), vec2<f32>(1.0 - 1e-6));
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
