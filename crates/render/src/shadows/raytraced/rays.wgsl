// Ray-traced shadows (technique raytraced): one shadow ray per (pixel, light) through the
// frame's top-level acceleration structure, composed into the lighting and visibility passes
// (after common.wgsl, paraboloid.wgsl, shadow_lookup.wgsl, alpha_mask.wgsl). The ray follows
// the exact CPU reference's conventions (crates/reference/src/visibility.rs): it starts
// `1e-4 · max(1, |p|∞)` off the surface along the normal, runs to the light's position (spot,
// point) or without end against its direction (directional), and any surface it crosses —
// front or back, the parts of alpha-masked surfaces their mask keeps, single-sided surfaces
// where it leaves through their back (the light sees their front) — shadows the point. No
// shadow-map bias applies: there is no sampling error to hide.
//
// Bindings (declared in source.rs's lookup, numbered by the pass): `scene_tlas`, the top-level
// acceleration structure; `corners`, the ray geometry (per TLAS instance its masked-triangle
// table base and material, per masked triangle its three texture coordinates, then the mask
// tail of alpha_mask.wgsl: records, coverage bits, header); `rays`, the sampling parameters.

const SHADOW_RAYS: bool = true;

struct RayParams {
    // Lights sampled per pixel (0 = every light of the pixel's cluster), frame seed, unused x2.
    samples: vec4<u32>,
}


// The start offset of the reference (RAY_OFFSET_RELATIVE in the reference crate).
const RAY_OFFSET_RELATIVE: f32 = 1e-4;

// Bit of an instance's material word: a single-sided caster (accel.rs FRONT_ONLY).
const FRONT_ONLY: u32 = 0x80000000u;

// Whether the candidate triangle hit `c` blocks the ray: always for opaque geometry (whose
// hits never reach here), by its mask for alpha-tested instances, and for single-sided ones
// only where the ray meets the triangle's back (it starts on the back side, the light lies on
// the front side). Vulkan, like DXR, calls a triangle front-facing when it appears clockwise
// from the ray's origin, in object space (mirroring instance transforms keep the mesh's
// front); scene fronts are counter-clockwise, so meeting the back is `front_face`.
fn candidate_solid(c: RayIntersection) -> bool {
    // Per instance (custom data): first word of its triangles' texture coordinates, material.
    let rec = 2u * c.instance_custom_data;
    let first = corners[rec];
    let word = corners[rec + 1u];
    if ((word & FRONT_ONLY) != 0u) {
        return !c.front_face;
    }
    let material = word;
    let base = first + 6u * c.primitive_index;
    let uv0 = vec2<f32>(bitcast<f32>(corners[base]), bitcast<f32>(corners[base + 1u]));
    let uv1 = vec2<f32>(bitcast<f32>(corners[base + 2u]), bitcast<f32>(corners[base + 3u]));
    let uv2 = vec2<f32>(bitcast<f32>(corners[base + 4u]), bitcast<f32>(corners[base + 5u]));
    let b = vec3<f32>(1.0 - c.barycentrics.x - c.barycentrics.y, c.barycentrics);
    let uv = b.x * uv0 + b.y * uv1 + b.z * uv2;
    return mask_covered(mask_tail(), material, uv);
}

// 1 when nothing lies between `p` (normal `n`) and the centre of `light`, else 0. Lights
// that cast no shadow (`shadow.y == 0`) light every point they reach.
fn ray_lit(light: LightData, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (light.shadow.y == 0u) {
        return 1.0;
    }
    if (light.shadow.z == LIGHT_DIRECTIONAL) {
        return ray_towards(ray_origin(p, n), -light.direction.xyz, 1e30);
    }
    return ray_to_point(ray_origin(p, n), light.position.xyz);
}

// Where a shadow ray from `p` (normal `n`) starts: off the surface, as the reference's.
fn ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let a = abs(p);
    return p + n * (RAY_OFFSET_RELATIVE * max(max(a.x, max(a.y, a.z)), 1.0));
}

// 1 when nothing lies between `origin` and the point `q`.
fn ray_to_point(origin: vec3<f32>, q: vec3<f32>) -> f32 {
    let to = q - origin;
    let t_max = length(to);
    if (t_max <= 0.0) {
        return 1.0;
    }
    return ray_towards(origin, to / t_max, t_max);
}

// Two orthonormal vectors perpendicular to the unit vector `a` (Duff et al. 2017).
fn ray_basis(a: vec3<f32>) -> mat2x3<f32> {
    let s = select(-1.0, 1.0, a.z >= 0.0);
    let k = -1.0 / (s + a.z);
    let b = a.x * a.y * k;
    return mat2x3<f32>(
        vec3<f32>(1.0 + s * a.x * a.x * k, s * b, -s * a.x),
        vec3<f32>(b, s + a.y * a.y * k, -a.y),
    );
}

// The unit square onto the unit disc, preserving area and strata (Shirley and Chiu 1997).
fn ray_concentric(u: vec2<f32>) -> vec2<f32> {
    let a = 2.0 * u - vec2<f32>(1.0);
    if (a.x == 0.0 && a.y == 0.0) {
        return vec2<f32>(0.0);
    }
    var r: f32;
    var phi: f32;
    if (abs(a.x) > abs(a.y)) {
        r = a.x;
        phi = 0.7853982 * (a.y / a.x);
    } else {
        r = a.y;
        phi = 1.5707964 - 0.7853982 * (a.x / a.y);
    }
    return r * vec2<f32>(cos(phi), sin(phi));
}

// 1 when the sample `u` (unit square) of the sized light's shape is visible from `p`: a spot
// light's disc facing along its direction, a point light's sphere as the disc through its
// centre facing `p`, a directional light's cone of directions (uniform in solid angle). The
// same shapes as the CPU reference (crates/reference/src/soft.rs).
fn ray_lit_sample(light: LightData, p: vec3<f32>, n: vec3<f32>, u: vec2<f32>) -> f32 {
    let origin = ray_origin(p, n);
    let size = light.diffuse.w;
    if (light.shadow.z == LIGHT_DIRECTIONAL) {
        let axis = -light.direction.xyz;
        let cos_max = 1.0 / sqrt(1.0 + size * size);
        let cos_t = 1.0 - u.x * (1.0 - cos_max);
        let sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
        let phi = 6.2831853 * u.y;
        let b = ray_basis(axis);
        return ray_towards(origin, axis * cos_t + (b[0] * cos(phi) + b[1] * sin(phi)) * sin_t, 1e30);
    }
    var normal = light.direction.xyz;
    if (light.shadow.z == LIGHT_POINT) {
        normal = normalize(light.position.xyz - p);
    }
    let b = ray_basis(normal);
    let d = ray_concentric(u) * size;
    return ray_to_point(origin, light.position.xyz + b[0] * d.x + b[1] * d.y);
}

// Fraction of a sized light visible from `p`: `m`² stratified samples of its shape, the grid
// shifted by `jitter` (the pixel's and the frame's).
fn ray_lit_area(light: LightData, p: vec3<f32>, n: vec3<f32>, m: u32, jitter: vec2<f32>) -> f32 {
    if (light.shadow.y == 0u) {
        return 1.0;
    }
    var lit = 0.0;
    for (var y = 0u; y < m; y = y + 1u) {
        for (var x = 0u; x < m; x = x + 1u) {
            let u = fract((vec2<f32>(f32(x), f32(y)) + jitter) / f32(m));
            lit = lit + ray_lit_sample(light, p, n, u);
        }
    }
    return lit / f32(m * m);
}

// Samples per side of a sized light's grid (`RayOptions::area_samples`).
fn ray_area_side() -> u32 {
    return max(rays.samples.z, 1u);
}

// 1 when nothing lies within `t_max` of `origin` along the unit direction `dir`.
fn ray_towards(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> f32 {
    var rq: ray_query;
    rayQueryInitialize(&rq, scene_tlas, RayDesc(RAY_FLAG_TERMINATE_ON_FIRST_HIT, 0xFFu, 0.0, t_max, origin, dir));
    while (rayQueryProceed(&rq)) {
        let c = rayQueryGetCandidateIntersection(&rq);
        if (c.kind == RAY_QUERY_INTERSECTION_TRIANGLE && candidate_solid(c)) {
            rayQueryConfirmIntersection(&rq);
        }
    }
    let hit = rayQueryGetCommittedIntersection(&rq);
    return select(1.0, 0.0, hit.kind != RAY_QUERY_INTERSECTION_NONE);
}

// Lights sampled per pixel (0: every light).
fn ray_samples() -> u32 {
    return rays.samples.x;
}

// The frame's seed for the sampled lights.
fn ray_seed() -> u32 {
    return rays.samples.y;
}
