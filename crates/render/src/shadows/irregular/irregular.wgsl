// Irregular (alias-free) shadow maps (seed 001), in compute. Composed after common.wgsl,
// paraboloid.wgsl and shadow_lookup.wgsl (for `select_shadow_view` and `in_reach`).
//
// cs_init       one thread per pixel: the mask starts as "in reach" for every light.
// cs_insert     one thread per pixel and batch: for each shadowed light of the batch, the
//               pixel's ray origin (G-buffer point moved along its normal exactly as the CPU
//               reference does) is projected into the light view that covers it and pushed
//               onto that grid texel's linked list (atomic node cursor + atomicExchange of the
//               texel's head).
// cs_triangles  one thread per (caster triangle, view of the batch): the triangle's projection
//               (clipped at the light's plane) is bounded conservatively in grid texels; small
//               footprints are walked here, the 8x8-texel tiles of large ones that hold samples
//               (occupancy flags set by cs_insert) are queued for cs_tiles (one workgroup per
//               tile, one thread per texel), so a floor quad does not serialize on one thread.
// cs_args       one thread: indirect dispatch size of cs_tiles.
// cs_tiles      one workgroup per queued tile.
// Every sample in a visited texel's list gets the exact two-sided watertight segment test
// (Woop et al. 2013, as the CPU reference) against the triangle; a hit clears its light's bit.

// Per view of the frame (built once on the CPU).
struct IView {
    view_proj: mat4x4<f32>,
    // xyz light position (w = 1) or the direction light travels (w = 0, directional).
    light: vec4<f32>,
    // Grid base (in heads, within the batch), grid side, light index, 1 if orthographic.
    grid: vec4<u32>,
    // x: smallest clip w kept when clipping triangles at the light's plane (perspective).
    params: vec4<f32>,
    // Occupancy flags (one word per TILE x TILE texels, in `heads` after the batch's grids):
    // first word within the batch, tiles per row.
    occ: vec4<u32>,
}

// Per batch of lights (uniform, one bind group per pipeline and batch).
struct Batch {
    // First light, one past the last light, first view, one past the last view.
    lights_views: vec4<u32>,
    // Node capacity, tile-queue capacity, caster triangles, visibility words per pixel.
    caps: vec4<u32>,
    // x: index in `heads` of the frame's count of cut-short walks (see `walk`); y: the triangles
    // below it cast only where the light sees their front (single-sided casters and the closed
    // meshes laid out with them; 0 when the scene has no single-sided caster).
    extra: vec4<u32>,
}

// Control words (one buffer, also the indirect-dispatch arguments of cs_tiles).
const C_CURSOR: u32 = 0u;        // nodes used by this batch
const C_TILES: u32 = 1u;         // tiles queued by this batch
const C_PEAK_TILES: u32 = 2u;    // most tiles any batch queued (frame)
const C_OVERFLOW: u32 = 4u;      // samples dropped because the node pool was full (frame)
const C_PEAK: u32 = 5u;          // most nodes any batch asked for (frame)
const C_UNMAPPED: u32 = 6u;      // samples outside every view of their light (frame)
const C_DROPPED: u32 = 7u;       // occupied tiles that found the queue full (frame)
const C_ARGS: u32 = 8u;          // x, y, z workgroups of cs_tiles

// Tiles are TILE x TILE texels; footprints up to INLINE_TEXELS texels are walked in place.
const TILE: u32 = 8u;
const INLINE_TEXELS: u32 = 16u;
// Scenes with alpha-tested casters (caster_layout.rs puts them last) compile this with true: a hit
// on such a triangle counts only where its mask is solid. Without, no mask code is compiled.
override ALPHA_TESTED: bool = false;

// Conservative margin of the texel square in the coverage test, texels (covers the rounding
// of both projections by a wide margin).
const MARGIN: f32 = 0.05;
// Largest overshoot (ndc) of a sample projection that is still clamped onto the grid.
const NDC_SLACK: f32 = 1e-3;
const F32_MAX: f32 = 3.0e38;

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<LightData>;
// Declared for shadow_lookup.wgsl's `atlas_coord`, which these entry points never call.
@group(0) @binding(2) var<storage, read> shadow_views: array<ShadowViewData>;
@group(0) @binding(3) var gbuf_position: texture_2d<u32>;
@group(0) @binding(4) var gbuf_normal: texture_2d<u32>;
@group(0) @binding(5) var<storage, read> iviews: array<IView>;
@group(0) @binding(6) var<storage, read> world: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> corners: array<u32>;
// Per grid texel: 1 + first node of its list, 0 = empty (so clear_buffer empties the grid).
@group(0) @binding(8) var<storage, read_write> heads: array<atomic<u32>>;
// Struct of arrays in one buffer: words [0, capacity) hold 1 + next node (0 = end of list);
// words capacity + 4i .. capacity + 4i + 3 hold node i's ray origin (f32 bits) and pixel.
@group(0) @binding(9) var<storage, read_write> nodes: array<u32>;
// The visibility mask: `counts.w` words per pixel, bit set = in reach and unoccluded.
@group(0) @binding(10) var<storage, read_write> mask: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> control: array<atomic<u32>>;
// Queued tiles: triangle, view, first texel x, first texel y; entry `caps.y` (one past the
// queue) holds the number queued, written by cs_args.
@group(0) @binding(12) var<storage, read_write> tiles: array<vec4<u32>>;
@group(0) @binding(13) var<uniform> batch: Batch;

// The reference's ray-start offset (manyshadows-reference `ray_offset`).
fn ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let a = abs(p);
    return p + n * (1e-4 * max(max(a.x, a.y), max(a.z, 1.0)));
}

fn pixel_id(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

@compute @workgroup_size(64, 1, 1)
fn cs_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let w = u32(frame.viewport.x);
    let pixels = w * u32(frame.viewport.y);
    let pixel = pixel_id(gid, groups);
    if (pixel >= pixels) {
        return;
    }
    let words = frame.counts.w;
    let gpos = textureLoad(gbuf_position, vec2<i32>(vec2<u32>(pixel % w, pixel / w)), 0);
    let pos = bitcast<vec4<f32>>(gpos);
    for (var wi = 0u; wi < words; wi++) {
        var bits = 0u;
        if (has_geometry(gpos)) {
            for (var b = 0u; b < 32u; b++) {
                let li = wi * 32u + b;
                if (li >= frame.counts.x) {
                    break;
                }
                if (in_reach(lights[li], pos.xyz)) {
                    bits |= 1u << b;
                }
            }
        }
        atomicStore(&mask[pixel * words + wi], bits);
    }
}

// Continuous grid coordinates of a point in ndc (x right, y down, like atlas tiles).
// Index in `heads` of texel `t`'s list: the texel itself, or (multimap hash, `occ.z`
// buckets) the bucket the texel hashes to.
fn bucket(v: IView, t: vec2<u32>) -> u32 {
    if (v.occ.z == 0u) {
        return v.grid.x + t.y * v.grid.y + t.x;
    }
    let h = (t.x * 73856093u) ^ (t.y * 19349663u);
    return v.grid.x + h % v.occ.z;
}

fn grid_xy(ndc: vec2<f32>, side: u32) -> vec2<f32> {
    return vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * f32(side);
}

// Ndc of `o` in view `v`, or a value > 1 + NDC_SLACK in x when it is not in front of the view.
fn view_ndc(v: IView, o: vec3<f32>) -> vec2<f32> {
    let c = v.view_proj * vec4<f32>(o, 1.0);
    if (v.grid.w == 1u) {
        return c.xy;
    }
    if (c.w <= 0.0) {
        return vec2<f32>(F32_MAX);
    }
    return c.xy / c.w;
}

fn on_grid(ndc: vec2<f32>) -> bool {
    return all(abs(ndc) <= vec2<f32>(1.0 + NDC_SLACK));
}

@compute @workgroup_size(64, 1, 1)
fn cs_insert(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let w = u32(frame.viewport.x);
    let pixels = w * u32(frame.viewport.y);
    let pixel = pixel_id(gid, groups);
    if (pixel >= pixels) {
        return;
    }
    let px = vec2<i32>(vec2<u32>(pixel % w, pixel / w));
    let gpos = textureLoad(gbuf_position, px, 0);
    let pos = bitcast<vec4<f32>>(gpos);
    if (!has_geometry(gpos)) {
        return;
    }
    let p = pos.xyz;
    let n = normalize(bitcast<vec3<f32>>(textureLoad(gbuf_normal, px, 0).xyz));
    let o = ray_origin(p, n);
    let view_depth = -(frame.view * vec4<f32>(p, 1.0)).z;
    let capacity = batch.caps.x;
    for (var li = batch.lights_views.x; li < batch.lights_views.y; li++) {
        let light = lights[li];
        if (light.shadow.y == 0u || !in_reach(light, p)) {
            continue;
        }
        // The view that covers the point, as the atlas techniques choose it; point faces by
        // the ray origin (the point the segment starts from), so it projects inside the face.
        var vi = select_shadow_view(light, p, view_depth);
        if (light.shadow.z == LIGHT_POINT) {
            vi = select_shadow_view(light, o, view_depth);
        }
        var ndc = vec2<f32>(F32_MAX);
        if (vi >= 0) {
            ndc = view_ndc(iviews[vi], o);
        }
        if (light.shadow.z == LIGHT_DIRECTIONAL && !on_grid(ndc)) {
            // Outside its cascade's square: any cascade that holds it will do.
            let first = i32(light.shadow.x);
            for (var c = 0; c < i32(light.shadow.y); c++) {
                let cn = view_ndc(iviews[first + c], o);
                if (on_grid(cn)) {
                    vi = first + c;
                    ndc = cn;
                    break;
                }
            }
        }
        if (vi < 0 || !on_grid(ndc)) {
            atomicAdd(&control[C_UNMAPPED], 1u);
            continue;
        }
        let v = iviews[vi];
        let side = v.grid.y;
        let t = vec2<u32>(clamp(floor(grid_xy(ndc, side)), vec2<f32>(0.0), vec2<f32>(f32(side - 1u))));
        let node = atomicAdd(&control[C_CURSOR], 1u);
        if (node >= capacity) {
            // Reported as an error after the frame: the sample's bit would be wrong.
            atomicAdd(&control[C_OVERFLOW], 1u);
            continue;
        }
        let d = capacity + 4u * node;
        nodes[d] = bitcast<u32>(o.x);
        nodes[d + 1u] = bitcast<u32>(o.y);
        nodes[d + 2u] = bitcast<u32>(o.z);
        nodes[d + 3u] = pixel;
        nodes[node] = atomicExchange(&heads[bucket(v, t)], node + 1u);
        let occ = v.occ.x + (t.y / TILE) * v.occ.y + t.x / TILE;
        if (atomicLoad(&heads[occ]) == 0u) {
            atomicStore(&heads[occ], 1u);
        }
    }
}

// Does the open segment o + t·dir, 0 < t < tmax, cross triangle (a, b, c) from either side?
// The watertight test of Woop, Benthin and Wald (JCGT 2013), as the CPU reference (without
// its double-precision re-evaluation of exact zeros, which WGSL cannot express). Returns the
// hit's unnormalised barycentric weights of a, b, c in xyz and their sum in w on a hit (the
// weights are xyz / w), w = 0 otherwise.
fn segment_hit(o: vec3<f32>, dir: vec3<f32>, tmax: f32, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>) -> vec4<f32> {
    let ad = abs(dir);
    var kz = 2u;
    if (ad.x >= ad.y && ad.x >= ad.z) {
        kz = 0u;
    } else if (ad.y >= ad.z) {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if (dir[kz] < 0.0) {
        let k = kx;
        kx = ky;
        ky = k;
    }
    let sx = dir[kx] / dir[kz];
    let sy = dir[ky] / dir[kz];
    let sz = 1.0 / dir[kz];
    let a = p0 - o;
    let b = p1 - o;
    let c = p2 - o;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return vec4<f32>(0.0);
    }
    let det = u + v + w;
    if (det == 0.0) {
        return vec4<f32>(0.0);
    }
    let t = (u * sz * a[kz] + v * sz * b[kz] + w * sz * c[kz]) / det;
    return vec4<f32>(u, v, w, select(0.0, det, t > 0.0 && t < tmax));
}

// A caster triangle in one view: world corners and its conservative grid footprint.
struct Footprint {
    // The caster triangle (alpha-tested ones test their mask at each hit).
    tri: u32,
    p0: vec3<f32>,
    p1: vec3<f32>,
    p2: vec3<f32>,
    // Inclusive texel bounds; empty when lo > hi.
    lo: vec2<i32>,
    hi: vec2<i32>,
    // Edge functions e_i(q) = dot(e_i.xy, q) + e_i.z, >= 0 inside; only when `edges` is set
    // (no corner was clipped at the light's plane and the projection has an area).
    e0: vec3<f32>,
    e1: vec3<f32>,
    e2: vec3<f32>,
    edges: bool,
}

fn include(lo: ptr<function, vec2<f32>>, hi: ptr<function, vec2<f32>>, q: vec2<f32>) {
    *lo = min(*lo, q);
    *hi = max(*hi, q);
}

fn edge(a: vec2<f32>, b: vec2<f32>, s: f32) -> vec3<f32> {
    // s · cross(b − a, q − a) = dot(n, q) + c with n = s·(−d.y, d.x).
    let d = b - a;
    let n = s * vec2<f32>(-d.y, d.x);
    return vec3<f32>(n, -dot(n, a));
}

fn footprint(tri: u32, v: IView) -> Footprint {
    var f: Footprint;
    f.tri = tri;
    f.p0 = world[corners[3u * tri]].xyz;
    f.p1 = world[corners[3u * tri + 1u]].xyz;
    f.p2 = world[corners[3u * tri + 2u]].xyz;
    f.edges = false;
    f.lo = vec2<i32>(1);
    f.hi = vec2<i32>(0);
    let side = v.grid.y;
    var c = array<vec4<f32>, 3>(
        v.view_proj * vec4<f32>(f.p0, 1.0),
        v.view_proj * vec4<f32>(f.p1, 1.0),
        v.view_proj * vec4<f32>(f.p2, 1.0),
    );
    var lo = vec2<f32>(F32_MAX);
    var hi = vec2<f32>(-F32_MAX);
    var q: array<vec2<f32>, 3>;
    var clipped = false;
    if (v.grid.w == 1u) {
        for (var i = 0; i < 3; i++) {
            q[i] = grid_xy(c[i].xy, side);
            include(&lo, &hi, q[i]);
        }
    } else {
        // Clip at w = eps (just in front of the light's plane): a segment from a sample to
        // the light lies wholly at w > 0, so only that part of the triangle can cross it.
        let eps = v.params.x;
        for (var i = 0; i < 3; i++) {
            let a = c[i];
            let b = c[(i + 1) % 3];
            if (a.w >= eps) {
                q[i] = grid_xy(a.xy / a.w, side);
                include(&lo, &hi, q[i]);
            } else {
                clipped = true;
            }
            if ((a.w - eps) * (b.w - eps) < 0.0) {
                let x = mix(a, b, (eps - a.w) / (b.w - a.w));
                include(&lo, &hi, grid_xy(x.xy / eps, side));
            }
        }
        if (lo.x > hi.x) {
            return f;
        }
    }
    let fs = f32(side);
    if (hi.x < -MARGIN || hi.y < -MARGIN || lo.x > fs + MARGIN || lo.y > fs + MARGIN) {
        return f;
    }
    let top = vec2<f32>(fs - 1.0);
    f.lo = vec2<i32>(clamp(floor(lo - vec2<f32>(MARGIN)), vec2<f32>(0.0), top));
    f.hi = vec2<i32>(clamp(floor(hi + vec2<f32>(MARGIN)), vec2<f32>(0.0), top));
    if (!clipped) {
        let area = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[1].y - q[0].y) * (q[2].x - q[0].x);
        if (abs(area) > 1e-6) {
            let s = sign(area);
            f.e0 = edge(q[0], q[1], s);
            f.e1 = edge(q[1], q[2], s);
            f.e2 = edge(q[2], q[0], s);
            f.edges = true;
        }
    }
    return f;
}

// Conservative: may the triangle's projection touch texel t (its square grown by MARGIN)?
fn touches(f: Footprint, t: vec2<i32>) -> bool {
    if (!f.edges) {
        return true;
    }
    let centre = vec2<f32>(t) + vec2<f32>(0.5);
    let h = 0.5 + MARGIN;
    let r = vec3<f32>(
        h * (abs(f.e0.x) + abs(f.e0.y)),
        h * (abs(f.e1.x) + abs(f.e1.y)),
        h * (abs(f.e2.x) + abs(f.e2.y)),
    );
    let e = vec3<f32>(dot(f.e0.xy, centre) + f.e0.z, dot(f.e1.xy, centre) + f.e1.z, dot(f.e2.xy, centre) + f.e2.z);
    return all(e + r >= vec3<f32>(0.0));
}

// Tests every sample in texel t's list against the triangle; hits clear their light's bit.
fn walk(f: Footprint, v: IView, t: vec2<i32>) {
    if (!touches(f, t)) {
        return;
    }
    let capacity = batch.caps.x;
    let words = batch.caps.w;
    let li = v.grid.z;
    let word = li / 32u;
    let bit = 1u << (li % 32u);
    let directional = v.light.w < 0.5;
    var masked_from = 0u;
    if (ALPHA_TESTED) {
        masked_from = corners[arrayLength(&corners) - 4u];
    }
    var n = atomicLoad(&heads[bucket(v, vec2<u32>(t))]);
    loop {
        if (n == 0u) {
            break;
        }
        let i = n - 1u;
        n = nodes[i];
        let d = capacity + 4u * i;
        let m = nodes[d + 3u] * words + word;
        if ((atomicLoad(&mask[m]) & bit) == 0u) {
            continue;
        }
        let o = bitcast<vec3<f32>>(vec3<u32>(nodes[d], nodes[d + 1u], nodes[d + 2u]));
        var dir = -normalize(v.light.xyz);
        var tmax = F32_MAX;
        if (!directional) {
            let to = v.light.xyz - o;
            tmax = length(to);
            if (tmax <= 0.0) {
                continue;
            }
            dir = to / tmax;
        }
        let hit = segment_hit(o, dir, tmax, f.p0, f.p1, f.p2);
        // An alpha-tested triangle blocks only where its mask is solid at the hit.
        if (hit.w != 0.0 && (!ALPHA_TESTED || f.tri < masked_from
            || triangle_covered(mask_tail(), f.tri, hit.xyz / hit.w))) {
            atomicAnd(&mask[m], ~bit);
        }
    }
    if (n != 0u) {
        cut_short();
    }
}

// llvmpipe (Mesa's software rasterizer, GL and Vulkan) ends every loop of an invocation once
// the invocation has run 65535 loop iterations in all. Walks are kept short (one list per
// invocation in cs_tiles, at most INLINE_TEXELS lists in cs_triangles); a walk that was cut
// anyway is counted here and turned into an error after the frame, never a wrong bit.
fn cut_short() {
    atomicAdd(&heads[batch.extra.x], 1u);
}

@compute @workgroup_size(64, 1, 1)
fn cs_triangles(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let tris = batch.caps.z;
    let views = batch.lights_views.w - batch.lights_views.z;
    let g = gid.x + gid.y * groups.x * 64u;
    if (g >= tris * views) {
        return;
    }
    let vi = batch.lights_views.z + g / tris;
    let tri = g % tris;
    let v = iviews[vi];
    let f = footprint(tri, v);
    if (f.lo.x > f.hi.x || f.lo.y > f.hi.y) {
        return;
    }
    // A triangle the light sees from behind blocks no segment towards it (the rule for
    // single-sided casters, the CPU reference's): the segment from its front side would leave
    // through its back.
    if (tri < batch.extra.y) {
        let to_light = select(-v.light.xyz, v.light.xyz - f.p0, v.light.w > 0.5);
        if (dot(cross(f.p1 - f.p0, f.p2 - f.p0), to_light) < 0.0) {
            return;
        }
    }
    let size = vec2<u32>(f.hi - f.lo) + vec2<u32>(1u);
    if (size.x * size.y <= INLINE_TEXELS) {
        var y = f.lo.y;
        for (; y <= f.hi.y; y++) {
            for (var x = f.lo.x; x <= f.hi.x; x++) {
                walk(f, v, vec2<i32>(x, y));
            }
        }
        if (y <= f.hi.y) {
            cut_short();
        }
        return;
    }
    // Queue the footprint's tiles that hold samples, one entry per TILE x TILE texels; at most
    // (1024 / TILE)^2 iterations, within llvmpipe's loop budget.
    let cap = batch.caps.y;
    let t0 = vec2<u32>(f.lo) / TILE;
    let t1 = vec2<u32>(f.hi) / TILE;
    var ty = t0.y;
    for (; ty <= t1.y; ty++) {
        for (var tx = t0.x; tx <= t1.x; tx++) {
            if (atomicLoad(&heads[v.occ.x + ty * v.occ.y + tx]) == 0u) {
                continue;
            }
            let origin = max(vec2<i32>(vec2<u32>(tx, ty) * TILE), f.lo);
            let slot = atomicAdd(&control[C_TILES], 1u);
            if (slot < cap) {
                tiles[slot] = vec4<u32>(tri, vi, u32(origin.x), u32(origin.y));
            } else {
                atomicAdd(&control[C_DROPPED], 1u);
            }
        }
    }
    if (ty <= t1.y) {
        cut_short();
    }
}

@compute @workgroup_size(1, 1, 1)
fn cs_args() {
    atomicMax(&control[C_PEAK], atomicLoad(&control[C_CURSOR]));
    atomicMax(&control[C_PEAK_TILES], atomicLoad(&control[C_TILES]));
    let n = min(atomicLoad(&control[C_TILES]), batch.caps.y);
    let x = min(n, 65535u);
    atomicStore(&control[C_ARGS], x);
    atomicStore(&control[C_ARGS + 1u], select(0u, (n + 65534u) / 65535u, n > 0u));
    atomicStore(&control[C_ARGS + 2u], 1u);
    // cs_tiles cannot bind `control` (it is its indirect buffer): the count goes after the queue.
    tiles[batch.caps.y] = vec4<u32>(n, 0u, 0u, 0u);
}

@compute @workgroup_size(8, 8, 1)
fn cs_tiles(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    let e = wg.x + wg.y * 65535u;
    if (e >= tiles[batch.caps.y].x) {
        return;
    }
    let job = tiles[e];
    let v = iviews[job.y];
    let f = footprint(job.x, v);
    // Tiles are aligned to TILE texels; the first one of a footprint may start inside it.
    let t = vec2<i32>((vec2<u32>(job.z, job.w) / TILE) * TILE + lid.xy);
    if (f.lo.x > f.hi.x || any(t > f.hi) || any(t < f.lo)) {
        return;
    }
    walk(f, v, t);
}
