// Shadow lookups through the virtual shadow maps' page table, for the lighting and visibility
// passes. Its bindings `vsm: VsmUniforms`, `vsm_faces` and `vsm_table` are declared by
// source.rs's lookup and numbered by the pass that composes it.

// Where `p` falls in the page pool for `light`: the page of the level the point needs, or, if
// that page is not resident (the pool was full), the nearest coarser resident page. Taps of
// the filter stay inside the page (`tile_min`, `tile_max`), so pages never bleed into each
// other. Invalid (unshadowed) when no level of the face is resident.
fn shadow_coord(light: LightData, p: vec3<f32>, n: vec3<f32>, view_depth: f32) -> ShadowCoord {
    var out: ShadowCoord;
    out.valid = false;
    let fi = select_shadow_view(light, p, view_depth);
    if (fi < 0) {
        return out;
    }
    let face = vsm_faces[fi];
    let ray = vsm_ray(light, face, p, n);
    var level = vsm_level(face, ray, view_depth);
    loop {
        let q = vsm_project(light, face, ray, level);
        if (!q.valid) {
            return out;
        }
        let e = vsm_table[vsm_entry(face, level, q.uv)];
        if (e >= VSM_FIRST_PAGE && e != VSM_DENIED) {
            var page = e - VSM_FIRST_PAGE;
            var side = f32(vsm.pool.z);
            var corner = vec2<f32>(0.0);
            var at = q;
            if (page >= VSM_QUARTER) {
                // A level-0 quarter page: half the side, its texels twice as wide (and the
                // bias with them).
                let k = page - VSM_QUARTER;
                page = k / 4u;
                side = 0.5 * side;
                corner = vec2<f32>(f32(k % 2u), f32((k / 2u) % 2u)) * side;
                at = vsm_project_texel(light, face, ray, 2.0 * vsm_texel_world(face, level, ray));
                if (!at.valid) {
                    return out;
                }
            }
            let tile = vec2<f32>(f32(page % vsm.pool.y), f32(page / vsm.pool.y)) * f32(vsm.pool.z) + corner;
            let pages = f32(1u << level);
            let cell = min(floor(at.uv * pages), vec2<f32>(pages - 1.0));
            out.tile_min = tile;
            out.tile_max = tile + vec2<f32>(side);
            out.texel = tile + (at.uv * pages - cell) * side;
            out.depth = at.depth;
            // The texel of this page per unit of distance (perspective) or in the world.
            let texel = face.params.z * f32(1u << (face.table.y - level)) * select(1.0, 2.0, side < f32(vsm.pool.z));
            out.lin = vec4<f32>(face.params.x, face.params.y, texel, face.params.w);
            if (light.diffuse.w > 0.0) {
                // The receiver's tangent plane, one texel away on each side, in page texels.
                let tw = select(texel, texel * max(ray.p.w, 0.0), face.params.w < 0.5);
                let t = plane_tangents(n) * tw;
                let r1 = vsm_ray(light, face, p + t[0], n);
                let r2 = vsm_ray(light, face, p + t[1], n);
                let q0 = ray.p + tw * ray.d;
                let q1 = r1.p + tw * r1.d;
                let q2 = r2.p + tw * r2.d;
                // Taps find their own pages: the soft texel space is the whole face at this
                // level, in full pages' texels.
                let full = pages * f32(vsm.pool.z);
                out.grad = plane_gradient(view_uvz(q0), view_uvz(q1), view_uvz(q2)) / full;
                out.soft = vec3<f32>(at.uv * full, full);
                out.src = vec2<u32>(u32(fi), level);
            }
            out.valid = true;
            return out;
        }
        if (level == 0u) {
            return out;
        }
        level = level - 1u;
    }
    return out;
}

// Where the point `t` of a sized light's soft texel space (the face at level `c.src.y`, in
// full pages' texels) lies in the pool: its continuous pool texel, its position inside its
// page and the page's side in texels; `resident` false where that page is not (the tap then
// sees no caster).
struct VsmTap {
    pool: vec2<f32>,
    local: vec2<f32>,
    side: f32,
    resident: bool,
}

fn vsm_tap(c: ShadowCoord, t: vec2<f32>) -> VsmTap {
    var out: VsmTap;
    // Most taps lie in the sample's own page, which the lookup found (`tile_min`, `tile_max`:
    // its texels in the pool; none after `soft_coarser`): no page-table read for those.
    let side = f32(vsm.pool.z);
    let s0 = c.tile_max.x - c.tile_min.x;
    // (The page's origin from the sample's own place in it, not from rounding `soft / side`
    // again, which can put a sample on a page border into the page beside.)
    let own = t - c.soft.xy + (c.texel - c.tile_min) * (side / max(s0, 1.0));
    if (s0 > 0.0 && all(own >= vec2<f32>(0.0)) && all(own < vec2<f32>(side))) {
        out.local = own * (s0 / side);
        out.pool = c.tile_min + out.local;
        out.side = s0;
        out.resident = true;
        return out;
    }
    let face = vsm_faces[c.src.x];
    let level = c.src.y;
    let pages = f32(1u << level);
    let uv = clamp(t, vec2<f32>(0.0), vec2<f32>(c.soft.z - 1e-3)) / c.soft.z;
    let e = vsm_table[vsm_entry(face, level, uv)];
    if (e < VSM_FIRST_PAGE || e == VSM_DENIED) {
        return out;
    }
    var page = e - VSM_FIRST_PAGE;
    var s = side;
    var corner = vec2<f32>(0.0);
    if (page >= VSM_QUARTER) {
        let k = page - VSM_QUARTER;
        page = k / 4u;
        s = 0.5 * side;
        corner = vec2<f32>(f32(k % 2u), f32((k / 2u) % 2u)) * s;
    }
    let tile = vec2<f32>(f32(page % vsm.pool.y), f32(page / vsm.pool.y)) * side + corner;
    let cell = min(floor(uv * pages), vec2<f32>(pages - 1.0));
    out.local = clamp((uv * pages - cell) * s, vec2<f32>(0.0), vec2<f32>(s - 1e-3));
    out.pool = tile + out.local;
    out.side = s;
    out.resident = true;
    return out;
}

// Raw depth of the texel holding `t` (nothing, depth 1, where its page is not resident).
fn soft_tap_depth(c: ShadowCoord, t: vec2<f32>) -> f32 {
    let q = vsm_tap(c, t);
    if (!q.resident) {
        return 1.0;
    }
    return shadow_depth_at(vec2<i32>(floor(q.pool)));
}

// Bilinearly weighted comparison around `t`: the pass's comparison sampler where the four
// texels lie in one page (one page-table read), else each texel found in its own page.
fn soft_tap_compare(c: ShadowCoord, t: vec2<f32>, depth: f32) -> f32 {
    let q = vsm_tap(c, t);
    if (q.resident && all(q.local >= vec2<f32>(0.5)) && all(q.local <= vec2<f32>(q.side - 0.5))) {
        return shadow_compare_at(q.pool, depth);
    }
    let f = t - vec2<f32>(0.5);
    let b = floor(f);
    let w = f - b;
    let at = b + vec2<f32>(0.5);
    let c00 = select(0.0, 1.0, depth <= soft_tap_depth(c, at));
    let c10 = select(0.0, 1.0, depth <= soft_tap_depth(c, at + vec2<f32>(1.0, 0.0)));
    let c01 = select(0.0, 1.0, depth <= soft_tap_depth(c, at + vec2<f32>(0.0, 1.0)));
    let c11 = select(0.0, 1.0, depth <= soft_tap_depth(c, at + vec2<f32>(1.0, 1.0)));
    return mix(mix(c00, c10, w.x), mix(c01, c11, w.x), w.y);
}

// The coordinate up to `k` levels coarser: the coarsest of them whose page under the point
// is resident (the same level where none is), in a face of half the texels per level, for a
// penumbra wider than the filter's largest radius.
fn soft_coarser(c: ShadowCoord, k: u32) -> ShadowCoord {
    let face = vsm_faces[c.src.x];
    let uv = c.soft.xy / c.soft.z;
    var level = c.src.y - min(k, c.src.y);
    loop {
        if (level >= c.src.y) {
            return c;
        }
        let e = vsm_table[vsm_entry(face, level, uv)];
        if (e >= VSM_FIRST_PAGE && e != VSM_DENIED) {
            break;
        }
        level = level + 1u;
    }
    var out = c;
    let scale = f32(1u << (c.src.y - level));
    out.src.y = level;
    // The sample's page is another now: every tap finds its own (vsm_tap).
    out.tile_max = out.tile_min;
    out.soft = c.soft / scale;
    out.grad = c.grad * scale;
    out.lin.z = c.lin.z * scale;
    return out;
}
