// The probe faces' cluster cull (clusters.rs): one thread per (cluster, face of the
// round). A cluster is a run of triangles of one instance's mesh; it is drawn into a face
// unless its bounding sphere lies wholly outside the face's frustum, or the instance's
// material shows only front faces and the cluster's normal cone proves every triangle faces
// away from the face's eye (the probe's centre). Survivors become indexed-indirect commands
// whose base vertex carries the face slot and the instance (gbuffer_face_clusters.wgsl).
//
// FaceDrawParams: frame/gbuffer_pull.wgsl; FaceView and face_views (binding 6):
// frame/gbuffer_face_views.wgsl; GpuCluster, sphere_outside, cluster_faces_away, DrawCommand:
// shadows/cluster_cull.wgsl.

struct ProbeCluster {
    // First index of the cluster's triangles in the scene's index buffer, and how many.
    first_index: u32,
    index_count: u32,
    // instance * V + the mesh's base vertex.
    base_vertex: u32,
    instance: u32,
    // Object-space bounding sphere: centre, radius.
    sphere: vec4<f32>,
    // Object-space normal cone of the triangles' windings: axis, half angle (>= pi/2: the
    // cluster is never culled for facing away).
    cone: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: FaceDrawParams;
@group(0) @binding(1) var<storage, read> probe_clusters: array<ProbeCluster>;
@group(0) @binding(2) var<storage, read> instances: array<InstanceData>;
@group(0) @binding(3) var<storage, read_write> commands: array<DrawCommand>;
@group(0) @binding(4) var<storage, read_write> command_count: atomic<u32>;
// Pairs kept over the frame's rounds (for inspection: `Renderer::probe_clusters_kept`).
@group(0) @binding(5) var<storage, read_write> kept: atomic<u32>;

// x: cluster of the round, y: face slot of the round.
@compute @workgroup_size(64, 1, 1)
fn cs_cull_faces(@builtin(global_invocation_id) gid: vec3<u32>) {
    let local = gid.x;
    let slot = gid.y;
    if (local >= params.round.w || slot >= params.round.y) {
        return;
    }
    let cl = probe_clusters[params.round.z + local];
    let view = face_views[params.round.x + slot];
    let inst = instances[cl.instance];
    let m = inst.model;
    // The world sphere holds the object sphere under any affine transform: centre moved,
    // radius scaled by the longest axis.
    let scale = max(length(m[0].xyz), max(length(m[1].xyz), length(m[2].xyz)));
    let sphere = vec4<f32>((m * vec4<f32>(cl.sphere.xyz, 1.0)).xyz, cl.sphere.w * scale);
    var visible = !sphere_outside(view.view_proj, sphere);
    if (visible) {
        var g: GpuCluster;
        g.cone = cl.cone;
        visible = !cluster_faces_away(g, inst.normal, sphere, vec4<f32>(view.eye.xyz, 1.0));
    }
    var cmd: DrawCommand;
    cmd.index_count = select(0u, cl.index_count, visible);
    cmd.instance_count = 1u;
    cmd.first_index = cl.first_index;
    cmd.base_vertex = i32(slot * params.stride.x + cl.base_vertex);
    cmd.first_instance = 0u;
    if (visible) {
        atomicAdd(&kept, 1u);
    }
    if (params.stride.z != 0u) {
        if (visible) {
            commands[atomicAdd(&command_count, 1u)] = cmd;
        }
    } else {
        commands[slot * params.round.w + local] = cmd;
    }
}
