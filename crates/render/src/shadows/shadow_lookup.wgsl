// Where a surface point falls in the shadow atlas, for one light. Shared by the lighting pass
// (filtered comparison) and the visibility pass (one hard test per light).
// Needs: `frame: FrameUniforms`, `shadow_views: array<ShadowViewData>` declared by the includer.

struct ShadowCoord {
    // Continuous atlas texel coordinates of the point.
    texel: vec2<f32>,
    // Depth of the (biased) point in the view's clip space, 0..1.
    depth: f32,
    // Tile bounds in texels: [tile_min, tile_max).
    tile_min: vec2<f32>,
    tile_max: vec2<f32>,
    // False when the light casts no shadow here (no shadow view, beyond the last cascade,
    // outside the view): the point counts as unoccluded.
    valid: bool,
    // What soft shadows need of the view (pcss.wgsl): near, far, the world size of one of
    // these texels (per unit of distance from the light where `w` is 0 or 2), and the
    // projection (0 perspective, 1 orthographic, 2 dual paraboloid).
    lin: vec4<f32>,
    // Sized lights only: how the receiver's tangent plane's depth changes per texel (x, y), so
    // wide soft-shadow filters compare each tap against the plane, not the centre's depth.
    grad: vec2<f32>,
    // Sized lights only: the point in the soft filter's texel space (xy, from 0 to side z):
    // the view's tile for the atlas, the whole face at one level for virtual maps, whose taps
    // find their own pages (`soft_tap_depth`, `soft_tap_compare` of the lookup).
    soft: vec3<f32>,
    // What the lookup's taps need to find texels (virtual maps: face, level).
    src: vec2<u32>,
}

// A clip position as the view's continuous coordinates (0..1, y down) and depth.
fn view_uvz(clip: vec4<f32>) -> vec3<f32> {
    let ndc = clip.xyz / clip.w;
    return vec3<f32>(ndc.xy * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5), ndc.z);
}

// Two unit tangents of the plane with normal `n`.
fn plane_tangents(n: vec3<f32>) -> mat2x3<f32> {
    let a = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(n.x) > 0.9);
    let t1 = normalize(cross(n, a));
    return mat2x3<f32>(t1, cross(n, t1));
}

// Depth change per unit of the view's coordinates of the plane through three of its points
// projected (`view_uvz`), bounded so a plane seen edge-on from the light stays finite.
fn plane_gradient(q0: vec3<f32>, q1: vec3<f32>, q2: vec3<f32>) -> vec2<f32> {
    let a = q1 - q0;
    let b = q2 - q0;
    let det = a.x * b.y - a.y * b.x;
    if (abs(det) < 1e-12) {
        return vec2<f32>(0.0);
    }
    let g = vec2<f32>(a.z * b.y - b.z * a.y, b.z * a.x - a.z * b.x) / det;
    // At most ten times the depth change of one step across the plane's points.
    let most = 10.0 * max(abs(a.z), abs(b.z)) / max(min(length(a.xy), length(b.xy)), 1e-12);
    let len = length(g);
    return select(g, g * (most / len), len > most);
}

// Index of the shadow view that covers `p` for `light`, or -1.
fn select_shadow_view(light: LightData, p: vec3<f32>, view_depth: f32) -> i32 {
    let first = i32(light.shadow.x);
    let count = light.shadow.y;
    if (count == 0u) {
        return -1;
    }
    let kind = light.shadow.z;
    if (kind == LIGHT_SPOT) {
        return first;
    }
    if (kind == LIGHT_POINT && count == 2u) {
        // Dual paraboloid: hemisphere 0 looks towards +Y, hemisphere 1 towards −Y.
        return first + select(1, 0, p.y >= light.position.y);
    }
    if (kind == LIGHT_POINT) {
        // Cube face by the major axis of the light-to-point vector: +X, -X, +Y, -Y, +Z, -Z.
        let d = p - light.position.xyz;
        let a = abs(d);
        if (a.x >= a.y && a.x >= a.z) {
            return first + select(1, 0, d.x > 0.0);
        }
        if (a.y >= a.z) {
            return first + select(3, 2, d.y > 0.0);
        }
        return first + select(5, 4, d.z > 0.0);
    }
    // Directional: the first cascade whose far split lies beyond the pixel's view depth.
    for (var i = 0u; i < count; i = i + 1u) {
        if (view_depth <= light.splits[i]) {
            return first + i32(i);
        }
    }
    return -1;
}

// Unit vector from `p` towards the light.
fn to_light(light: LightData, p: vec3<f32>) -> vec3<f32> {
    if (light.shadow.z == LIGHT_DIRECTIONAL) {
        return -light.direction.xyz;
    }
    return normalize(light.position.xyz - p);
}

// Receiver bias (documented in ARCHITECTURE.md): how far to move the point along its normal
// and towards the light, in texels of `texel_world` world size; the slope term grows with the
// tangent of the angle between normal and light, as a depth slope does.
fn receiver_offset(light: LightData, p: vec3<f32>, n: vec3<f32>, texel_world: f32) -> vec3<f32> {
    return texel_world * receiver_offset_dir(light, p, n);
}

// The receiver offset per unit of texel world size (virtual maps scale it per level).
fn receiver_offset_dir(light: LightData, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let l = to_light(light, p);
    let cos_t = clamp(dot(n, l), 0.0, 1.0);
    let tan_t = min(sqrt(max(1.0 - cos_t * cos_t, 0.0)) / max(cos_t, 1e-4), 10.0);
    return n * frame.bias.z + l * (frame.bias.x + frame.bias.y * tan_t);
}

// Where `p` (normal `n`, camera view depth `view_depth`) falls in the atlas for `light`.
fn atlas_coord(light: LightData, p: vec3<f32>, n: vec3<f32>, view_depth: f32) -> ShadowCoord {
    var out: ShadowCoord;
    out.valid = false;
    let vi = select_shadow_view(light, p, view_depth);
    if (vi < 0) {
        return out;
    }
    let sv = shadow_views[vi];
    if (sv.tile.z <= 0.0) {
        // A tile that holds nothing of its view yet (a shadow budget left it for later).
        return out;
    }
    let paraboloid = sv.params.w > 1.5;
    // World size of one shadow texel at p.
    let clip0 = sv.view_proj * vec4<f32>(p, 1.0);
    var texel_world = sv.params.z;
    if (paraboloid) {
        texel_world = texel_world * length(p - light.position.xyz);
    } else if (sv.params.w < 0.5) {
        texel_world = texel_world * max(clip0.w, 0.0);
    }
    let offset = receiver_offset(light, p, n, texel_world);
    var clip = sv.view_proj * vec4<f32>(p + offset, 1.0);
    if (paraboloid) {
        clip = paraboloid_clip(sv.view_proj, sv.params, vec4<f32>(p + offset, 1.0)).clip;
    }
    if (clip.w <= 0.0) {
        return out;
    }
    let ndc = clip.xyz / clip.w;
    if (any(abs(ndc.xy) > vec2<f32>(1.0))) {
        // Outside the view (a spot light's cone edge, a cascade's side): no shadow information.
        // Point-light faces never get here except through the bias offset; clamp those instead.
        if (light.shadow.z != LIGHT_POINT) {
            return out;
        }
    }
    let uv = clamp(ndc.xy * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5), vec2<f32>(0.0), vec2<f32>(1.0));
    if (light.diffuse.w > 0.0) {
        // The tangent plane through the biased point, one texel away on each side.
        let t = plane_tangents(n) * texel_world;
        let q = p + offset;
        var c1 = sv.view_proj * vec4<f32>(q + t[0], 1.0);
        var c2 = sv.view_proj * vec4<f32>(q + t[1], 1.0);
        if (paraboloid) {
            c1 = paraboloid_clip(sv.view_proj, sv.params, vec4<f32>(q + t[0], 1.0)).clip;
            c2 = paraboloid_clip(sv.view_proj, sv.params, vec4<f32>(q + t[1], 1.0)).clip;
        }
        out.grad = plane_gradient(view_uvz(clip), view_uvz(c1), view_uvz(c2)) / sv.tile.z;
        out.soft = vec3<f32>(uv * sv.tile.z, sv.tile.z);
    }
    out.tile_min = sv.tile.xy;
    out.tile_max = sv.tile.xy + vec2<f32>(sv.tile.z);
    out.texel = sv.tile.xy + uv * sv.tile.z;
    out.depth = clamp(ndc.z, 0.0, 1.0);
    out.lin = sv.params;
    out.valid = true;
    return out;
}

// The atlas texel holding the nearest sample to `c` (what a nearest-filtered lookup reads).
fn hard_texel(c: ShadowCoord) -> vec2<i32> {
    return vec2<i32>(clamp(floor(c.texel), c.tile_min, c.tile_max - vec2<f32>(1.0)));
}

// True when `p` lies within the light's range and cone (directional lights reach everywhere).
fn in_reach(light: LightData, p: vec3<f32>) -> bool {
    let kind = light.shadow.z;
    if (kind == LIGHT_DIRECTIONAL) {
        return true;
    }
    let d = p - light.position.xyz;
    let dist = length(d);
    if (dist > light.ambient.w) {
        return false;
    }
    if (kind == LIGHT_SPOT) {
        return dot(d / max(dist, 1e-6), light.direction.xyz) >= light.direction.w;
    }
    return true;
}
