// Shadow-caster geometry in world space, once per frame (the work seed 000 §19.4.1 shows
// layered rendering saves: model transform and skinning run once, not once per shadow view).
//
// cs_transform: one thread per caster vertex writes its world position.
// cs_bounds:    one thread per triangle cluster writes the cluster's bounding sphere.
// cs_groups:    one thread per group of CLUSTER_GROUP consecutive clusters writes a sphere
//               holding theirs, after the clusters' own (cluster_bounds[clusters + g]).
// (cs_bounds also writes each cluster's axis-aligned box after the groups' spheres:
// cluster_bounds[clusters + groups + 2c] its low corner, + 1 its high one; and after those
// the boxes of its CLUSTER_PARTS parts of PART_TRIANGLES consecutive triangles:
// cluster_bounds[3 clusters + groups + 2 (CLUSTER_PARTS c + k)], + 1.)
//               (CLUSTER_GROUP is composed in from casters.rs.)

struct TransformParams {
    // Caster vertices, clusters, 1 if skinned, unused.
    counts: vec4<u32>,
}

// Interleaved skinned vertex, 32 bytes (seed 000 Listing 19.7's layout): position, four joint
// indices packed as bytes, four weights.
struct SkinVertex {
    px: f32,
    py: f32,
    pz: f32,
    joints: u32,
    weights: vec4<f32>,
}

struct Bones {
    m: array<mat4x4<f32>, 64>,
}

// A run of triangles of one instance; `cone` is the object-space normal cone (axis, half angle
// in radians; >= pi/2 means the cluster cannot be back-face culled).
struct Cluster {
    first_triangle: u32,
    triangles: u32,
    instance: u32,
    flags: u32,
    cone: vec4<f32>,
}

@group(0) @binding(0) var<uniform> tparams: TransformParams;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> instances: array<InstanceData>;
// Per caster vertex: (vertex in the scene's vertex buffer, instance).
@group(0) @binding(3) var<storage, read> sources: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> world: array<vec4<f32>>;
@group(0) @binding(5) var<uniform> bones: Bones;
@group(0) @binding(6) var<storage, read> skin: array<SkinVertex>;
@group(0) @binding(7) var<storage, read> clusters: array<Cluster>;
@group(0) @binding(8) var<storage, read> corners: array<u32>;
@group(0) @binding(9) var<storage, read_write> cluster_bounds: array<vec4<f32>>;

// Must match the skinned vertex shader of `traditional` operation for operation, so both
// paths produce the same depth.
fn skinned_position(v: SkinVertex) -> vec4<f32> {
    let p = vec4<f32>(v.px, v.py, v.pz, 1.0);
    let j = unpack4xU8(v.joints);
    return v.weights.x * (bones.m[j.x] * p) + v.weights.y * (bones.m[j.y] * p)
        + v.weights.z * (bones.m[j.z] * p) + v.weights.w * (bones.m[j.w] * p);
}

@compute @workgroup_size(64, 1, 1)
fn cs_transform(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = gid.x + gid.y * groups.x * 64u;
    if (v >= tparams.counts.x) {
        return;
    }
    let src = sources[v];
    let model = instances[src.y].model;
    if (tparams.counts.z != 0u) {
        world[v] = model * skinned_position(skin[src.x]);
    } else {
        let p = vec4<f32>(positions[3u * src.x], positions[3u * src.x + 1u], positions[3u * src.x + 2u], 1.0);
        world[v] = model * p;
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_bounds(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = gid.x;
    if (c >= tparams.counts.y) {
        return;
    }
    let cl = clusters[c];
    let first = 3u * cl.first_triangle;
    let n = 3u * cl.triangles;
    var lo = world[corners[first]].xyz;
    var hi = lo;
    for (var i = 1u; i < n; i++) {
        let p = world[corners[first + i]].xyz;
        lo = min(lo, p);
        hi = max(hi, p);
    }
    let centre = 0.5 * (lo + hi);
    var r2 = 0.0;
    for (var i = 0u; i < n; i++) {
        let d = world[corners[first + i]].xyz - centre;
        r2 = max(r2, dot(d, d));
    }
    // Grow by a relative epsilon so rounding never makes the sphere miss a vertex.
    cluster_bounds[c] = vec4<f32>(centre, sqrt(r2) * 1.0001 + 1e-6);
    // The box, after the groups' spheres (grown alike).
    let pad = 1e-5 * max(abs(lo), abs(hi)) + vec3<f32>(1e-6);
    let at = tparams.counts.y + (tparams.counts.y + CLUSTER_GROUP - 1u) / CLUSTER_GROUP + 2u * c;
    cluster_bounds[at] = vec4<f32>(lo - pad, 0.0);
    cluster_bounds[at + 1u] = vec4<f32>(hi + pad, 0.0);
    // The parts' boxes (grown alike; empty parts of a short cluster get an inverted box).
    let parts = at + 2u * (tparams.counts.y - c) + 2u * CLUSTER_PARTS * c;
    for (var k = 0u; k < CLUSTER_PARTS; k++) {
        var plo = vec3<f32>(3.0e38);
        var phi = vec3<f32>(-3.0e38);
        for (var i = 3u * PART_TRIANGLES * k; i < min(n, 3u * PART_TRIANGLES * (k + 1u)); i++) {
            let p = world[corners[first + i]].xyz;
            plo = min(plo, p);
            phi = max(phi, p);
        }
        let ppad = 1e-5 * max(abs(plo), abs(phi)) + vec3<f32>(1e-6);
        cluster_bounds[parts + 2u * k] = vec4<f32>(plo - ppad, 0.0);
        cluster_bounds[parts + 2u * k + 1u] = vec4<f32>(phi + ppad, 0.0);
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_groups(@builtin(global_invocation_id) gid: vec3<u32>) {
    let g = gid.x;
    let n = tparams.counts.y;
    if (g * CLUSTER_GROUP >= n) {
        return;
    }
    let last = min(n, g * CLUSTER_GROUP + CLUSTER_GROUP);
    var lo = vec3<f32>(3.0e38);
    var hi = vec3<f32>(-3.0e38);
    for (var c = g * CLUSTER_GROUP; c < last; c++) {
        let s = cluster_bounds[c];
        lo = min(lo, s.xyz - vec3<f32>(s.w));
        hi = max(hi, s.xyz + vec3<f32>(s.w));
    }
    let centre = 0.5 * (lo + hi);
    var r = 0.0;
    for (var c = g * CLUSTER_GROUP; c < last; c++) {
        let s = cluster_bounds[c];
        r = max(r, length(s.xyz - centre) + s.w);
    }
    // Grown like the clusters' spheres, so rounding never drops a cluster the group holds.
    cluster_bounds[n + g] = vec4<f32>(centre, r * 1.0001 + 1e-6);
}
