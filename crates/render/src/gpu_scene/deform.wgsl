// Skinned and morphed meshes bent on the GPU (gpu_scene/deform.rs): one thread per deformed
// vertex writes the scene's position and normal of that vertex, from its bind vertex, the
// morph weights and the joints' matrices of this frame. The same arithmetic as the CPU's
// `Morph::shape` then `Skin::bend_from`: the targets' displacements weighted, the normal
// normalized; then the sum of the joint matrices weighted, the normal through its upper 3×3,
// normalized again.

struct DeformParams {
    // Deformed vertices in all.
    vertices: u32,
    // Where the per-vertex record numbers begin in `index` (after the records, 8 words each).
    owner_at: u32,
    // Where the morph weights begin in `frame`, in vec4s (after the joint matrices).
    weights_at: u32,
    _pad: u32,
};

@group(0) @binding(0) var<uniform> params: DeformParams;
// Per deformed mesh, 8 words: first deformed vertex, base vertex in the scene's buffers,
// first joint matrix (NO_SKIN: not skinned), joint slots a vertex (4 or 8), morph targets,
// first displacement (in vertices), first morph weight, vertex count. Then per deformed
// vertex, its mesh's record.
@group(0) @binding(1) var<storage, read> index: array<u32>;
// Per deformed vertex: its bind position, then its bind normal.
@group(0) @binding(2) var<storage, read> bind_vertices: array<vec4<f32>>;
// Per deformed vertex: eight joints as 16-bit halves, the first four weights' bits, the
// last four's.
@group(0) @binding(3) var<storage, read> skin: array<vec4<u32>>;
// Per target, per vertex of its mesh: position displacement, then normal displacement.
@group(0) @binding(4) var<storage, read> deltas: array<vec4<f32>>;
// This frame: the joint matrices (four columns each), then the morph weights, four a vec4.
@group(0) @binding(5) var<storage, read> frame: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out_positions: array<f32>;
@group(0) @binding(7) var<storage, read_write> out_normals: array<f32>;

const NO_SKIN: u32 = 0xffffffffu;

fn joint_matrix(k: u32) -> mat4x4<f32> {
    let b = 4u * k;
    return mat4x4<f32>(frame[b], frame[b + 1u], frame[b + 2u], frame[b + 3u]);
}

fn morph_weight(k: u32) -> f32 {
    let v = frame[params.weights_at + k / 4u];
    return v[k % 4u];
}

// `v` normalized, or `fallback` where it has no length (glam's `try_normalize`).
fn normalized_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if (l > 0.0 && l < 3.0e38) {
        return v / l;
    }
    return fallback;
}

@compute @workgroup_size(64)
fn cs_deform(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let i = gid.x + gid.y * groups.x * 64u;
    if (i >= params.vertices) {
        return;
    }
    let r = 8u * index[params.owner_at + i];
    let first = index[r];
    let base = index[r + 1u];
    let joint_base = index[r + 2u];
    let slots = index[r + 3u];
    let targets = index[r + 4u];
    let delta_base = index[r + 5u];
    let weight_base = index[r + 6u];
    let count = index[r + 7u];
    let v = i - first;

    var p = bind_vertices[2u * i].xyz;
    let n0 = bind_vertices[2u * i + 1u].xyz;
    var n = n0;
    if (targets > 0u) {
        for (var k = 0u; k < targets; k++) {
            let w = morph_weight(weight_base + k);
            if (w != 0.0) {
                let d = 2u * (delta_base + k * count + v);
                p += deltas[d].xyz * w;
                n += deltas[d + 1u].xyz * w;
            }
        }
        n = normalized_or(n, n0);
    }
    if (joint_base != NO_SKIN) {
        let joints = skin[3u * i];
        var weights = array<f32, 8>();
        let w0 = bitcast<vec4<f32>>(skin[3u * i + 1u]);
        let w1 = bitcast<vec4<f32>>(skin[3u * i + 2u]);
        weights[0] = w0.x; weights[1] = w0.y; weights[2] = w0.z; weights[3] = w0.w;
        weights[4] = w1.x; weights[5] = w1.y; weights[6] = w1.z; weights[7] = w1.w;
        var m = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        for (var k = 0u; k < slots; k++) {
            let w = weights[k];
            if (w != 0.0) {
                let j = (joints[k / 2u] >> (16u * (k % 2u))) & 0xffffu;
                m += joint_matrix(joint_base + j) * w;
            }
        }
        let q = n;
        p = (m * vec4<f32>(p, 1.0)).xyz;
        n = normalized_or((m * vec4<f32>(q, 0.0)).xyz, q);
    }
    let o = 3u * (base + v);
    out_positions[o] = p.x;
    out_positions[o + 1u] = p.y;
    out_positions[o + 2u] = p.z;
    out_normals[o] = n.x;
    out_normals[o + 1u] = n.y;
    out_normals[o + 2u] = n.z;
}
