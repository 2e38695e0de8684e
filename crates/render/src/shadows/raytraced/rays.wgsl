// Ray-traced shadows (technique raytraced): one shadow ray per (pixel, light) through the
// frame's top-level acceleration structure, composed into the lighting and visibility passes
// (after common.wgsl, paraboloid.wgsl, shadow_lookup.wgsl, alpha_mask.wgsl). The ray follows
// the exact CPU reference's conventions (crates/reference/src/visibility.rs): it starts
// `1e-4 · max(1, |p|∞)` off the surface along the normal, runs to the light's position (spot,
// point) or without end against its direction (directional), and any surface it crosses —
// front or back, the parts of alpha-masked surfaces their mask keeps — shadows the point. No
// shadow-map bias applies: there is no sampling error to hide.
//
// Bindings (`first` = 13): the top-level acceleration structure, the ray geometry (per TLAS
// instance its masked-triangle table base and material, per masked triangle its three texture
// coordinates, then the mask tail of alpha_mask.wgsl: records, coverage bits, header) and the
// sampling parameters.

const SHADOW_RAYS: bool = true;

struct RayParams {
    // Lights sampled per pixel (0 = every light of the pixel's cluster), frame seed, unused x2.
    samples: vec4<u32>,
}

@group(0) @binding(RT_FIRST) var scene_tlas: acceleration_structure;
@group(0) @binding(RT_SECOND) var<storage, read> corners: array<u32>;
@group(0) @binding(RT_THIRD) var<uniform> rays: RayParams;

// The start offset of the reference (RAY_OFFSET_RELATIVE in the reference crate).
const RAY_OFFSET_RELATIVE: f32 = 1e-4;

// Whether the candidate triangle hit `c` is solid there: always for opaque geometry (whose
// hits never reach here), by its mask for alpha-tested instances.
fn candidate_solid(c: RayIntersection) -> bool {
    // Per instance (custom data): first word of its triangles' texture coordinates, material.
    let rec = 2u * c.instance_custom_data;
    let first = corners[rec];
    let material = corners[rec + 1u];
    let base = first + 6u * c.primitive_index;
    let uv0 = vec2<f32>(bitcast<f32>(corners[base]), bitcast<f32>(corners[base + 1u]));
    let uv1 = vec2<f32>(bitcast<f32>(corners[base + 2u]), bitcast<f32>(corners[base + 3u]));
    let uv2 = vec2<f32>(bitcast<f32>(corners[base + 4u]), bitcast<f32>(corners[base + 5u]));
    let b = vec3<f32>(1.0 - c.barycentrics.x - c.barycentrics.y, c.barycentrics);
    let uv = b.x * uv0 + b.y * uv1 + b.z * uv2;
    return mask_covered(mask_tail(), material, uv);
}

// 1 when nothing lies between `p` (normal `n`) and `light`, else 0. Lights that cast no
// shadow (`shadow.y == 0`) light every point they reach.
fn ray_lit(light: LightData, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (light.shadow.y == 0u) {
        return 1.0;
    }
    let a = abs(p);
    let origin = p + n * (RAY_OFFSET_RELATIVE * max(max(a.x, max(a.y, a.z)), 1.0));
    var dir: vec3<f32>;
    var t_max: f32;
    if (light.shadow.z == LIGHT_DIRECTIONAL) {
        dir = -light.direction.xyz;
        t_max = 1e30;
    } else {
        let to = light.position.xyz - origin;
        t_max = length(to);
        if (t_max <= 0.0) {
            return 1.0;
        }
        dir = to / t_max;
    }
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
