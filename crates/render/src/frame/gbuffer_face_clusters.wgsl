// Probe faces drawn from GPU-culled triangle clusters (probes/clusters.rs): a compute
// pass keeps each (cluster, face) pair whose cluster may be seen by the face and writes an
// indexed-indirect command for it; one multi-draw per round draws them into the faces' tiles
// of the atlas, as `vs_faces` does for whole instances.
//
// The face and the instance ride in the vertex index, not in first_instance (OpenGL ES has
// no indirect first instance): a command for face slot s of the round and scene instance i
// has base_vertex = s * S + i * V + the mesh's base vertex (V = the scene's vertices,
// S = V * instances), so vertex_index = s * S + i * V + vertex. The vertex's attributes are
// therefore read from storage, not from vertex buffers (which the base vertex would shift).

// FaceDrawParams: gbuffer_pull.wgsl.
@group(1) @binding(0) var<uniform> draw_params: FaceDrawParams;
@group(1) @binding(1) var<storage, read> pull_positions: array<f32>;
@group(1) @binding(2) var<storage, read> pull_normals: array<f32>;
@group(1) @binding(3) var<storage, read> pull_uvs: array<f32>;

@vertex
fn vs_face_clusters(@builtin(vertex_index) v: u32) -> FacesVsOut {
    let slot = v / draw_params.stride.x;
    let rest = v - slot * draw_params.stride.x;
    let instance = rest / draw_params.stride.y;
    let k = rest - instance * draw_params.stride.y;
    let position = vec3<f32>(pull_positions[3u * k], pull_positions[3u * k + 1u], pull_positions[3u * k + 2u]);
    let normal = vec3<f32>(pull_normals[3u * k], pull_normals[3u * k + 1u], pull_normals[3u * k + 2u]);
    let uv = vec2<f32>(pull_uvs[2u * k], pull_uvs[2u * k + 1u]);
    let f = draw_params.round.x + slot;
    return into_face_tile(surface_vertex_seen(position, normal, uv, instance, face_views[f].view_proj, f), f);
}
