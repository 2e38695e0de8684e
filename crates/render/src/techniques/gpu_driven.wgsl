// `gpu-driven` (seed 002's route): a compute pass culls triangle clusters per view and writes
// indexed-indirect draw commands; one multi-draw renders the survivors into every listed
// view's atlas tile.
//
// The view is encoded without first_instance (OpenGL's support for it is shaky): a command for
// the view in batch slot s has base_vertex = s * V (V = caster vertices), so the vertex shader
// sees vertex_index = caster vertex + s * V and recovers both.

struct GpuParams {
    // caster vertices V, cullable triangles, cull bits, clusters in this round
    counts: vec4<u32>,
    // first draw-list entry of this round, views in this round, first cluster of this round,
    // 1 = compact the commands with an atomic counter (else one fixed slot per command)
    round: vec4<u32>,
    // atlas side in texels, its reciprocal, unused, unused
    atlas: vec4<f32>,
}

// A cluster of casters.wgsl: a run of triangles of one instance and its object-space normal
// cone (axis, half angle; >= pi/2: never back-face culled).
struct GpuCluster {
    first_triangle: u32,
    triangles: u32,
    instance: u32,
    flags: u32,
    cone: vec4<f32>,
}

// wgpu::util::DrawIndexedIndirectArgs.
struct DrawCommand {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

@group(0) @binding(0) var<uniform> gparams: GpuParams;
@group(0) @binding(1) var<storage, read> views: array<ShadowViewData>;
@group(0) @binding(2) var<storage, read> draw_list: array<u32>;

const HALF_PI: f32 = 1.5707963;
// Angle (radians) added to every cone test so rounding never culls a visible cluster.
const CONE_MARGIN: f32 = 1e-4;

// ---- cull (compute) ----

@group(0) @binding(3) var<storage, read> eyes: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> clusters: array<GpuCluster>;
@group(0) @binding(5) var<storage, read> cluster_bounds: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> instances: array<InstanceData>;
@group(0) @binding(7) var<storage, read_write> commands: array<DrawCommand>;
@group(0) @binding(8) var<storage, read_write> command_count: atomic<u32>;

// True if the sphere (centre, radius) lies wholly outside one plane of the view's clip volume
// (wgpu clip space: -w <= x, y <= w, 0 <= z <= w). Planes are the rows of the view-projection
// combined (Gribb and Hartmann); a small slack keeps rounding from culling a visible sphere.
fn sphere_outside(m: mat4x4<f32>, s: vec4<f32>) -> bool {
    let r0 = vec4<f32>(m[0].x, m[1].x, m[2].x, m[3].x);
    let r1 = vec4<f32>(m[0].y, m[1].y, m[2].y, m[3].y);
    let r2 = vec4<f32>(m[0].z, m[1].z, m[2].z, m[3].z);
    let r3 = vec4<f32>(m[0].w, m[1].w, m[2].w, m[3].w);
    let planes = array<vec4<f32>, 6>(r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2);
    let c = length(s.xyz);
    for (var i = 0u; i < 6u; i++) {
        let p = planes[i];
        let len = length(p.xyz);
        let slack = 1e-5 * (len * c + abs(p.w));
        if (dot(p.xyz, s.xyz) + p.w < -s.w * len - slack) {
            return true;
        }
    }
    return false;
}

// True if every triangle of the cluster faces away from every point of its bounding sphere as
// seen from `eye` (light position, w = 1; direction light travels, w = 0), so that back-face
// culling (cull.wgsl's faces_away) would drop each of them.
//
// A triangle with unit normal n faces away from the light at p iff dot(n, p - light) > 0,
// i.e. the angle between n and d = normalize(p - light) is below pi/2. Normals lie within
// half-angle a of the cone axis; directions d to points of the sphere lie within
// b = asin(r / dist) of u = normalize(centre - light). The largest angle between any n and any
// d is angle(axis, u) + a + b, so: cull iff a + b < pi/2 and dot(axis, u) > sin(a + b)
// (= cos(pi/2 - a - b)). For a directional light d is the direction of travel and b = 0.
fn cluster_faces_away(cl: GpuCluster, sphere: vec4<f32>, eye: vec4<f32>) -> bool {
    let a = cl.cone.w;
    if (a >= HALF_PI) {
        return false;
    }
    // Object-space axis to world space (instances hold similarity transforms when the cone
    // exists, so angles are kept).
    let axis = normalize((instances[cl.instance].normal * vec4<f32>(cl.cone.xyz, 0.0)).xyz);
    if (eye.w < 0.5) {
        let ab = a + CONE_MARGIN;
        return ab < HALF_PI && dot(axis, eye.xyz) > sin(ab);
    }
    let to_centre = sphere.xyz - eye.xyz;
    let dist = length(to_centre);
    if (dist <= sphere.w * 1.001) {
        return false;
    }
    let ab = a + asin(sphere.w / dist) + CONE_MARGIN;
    return ab < HALF_PI && dot(axis, to_centre / dist) > sin(ab);
}

// One thread per (cluster, view): x = cluster of this round, y = view slot of this round.
@compute @workgroup_size(64, 1, 1)
fn cs_cull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let local = gid.x;
    let slot = gid.y;
    if (local >= gparams.counts.w || slot >= gparams.round.y) {
        return;
    }
    let c = gparams.round.z + local;
    let view_id = draw_list[gparams.round.x + slot];
    let cl = clusters[c];
    let sphere = cluster_bounds[c];
    let bits = gparams.counts.z;
    var visible = true;
    if ((bits & CULL_FRUSTUM) != 0u && sphere_outside(views[view_id].view_proj, sphere)) {
        visible = false;
    }
    // Clusters never straddle the cullable range (casters.rs builds them per class).
    if (visible && (bits & CULL_BACKFACE) != 0u && cl.first_triangle < gparams.counts.y
        && cluster_faces_away(cl, sphere, eyes[view_id])) {
        visible = false;
    }
    var cmd: DrawCommand;
    cmd.index_count = select(0u, 3u * cl.triangles, visible);
    cmd.instance_count = 1u;
    cmd.first_index = 3u * cl.first_triangle;
    cmd.base_vertex = i32(slot * gparams.counts.x);
    cmd.first_instance = 0u;
    if (gparams.round.w != 0u) {
        if (visible) {
            commands[atomicAdd(&command_count, 1u)] = cmd;
        }
    } else {
        commands[slot * gparams.counts.w + local] = cmd;
    }
}

// ---- draw (vertex) ----

@group(0) @binding(9) var<storage, read> world: array<vec4<f32>>;

@vertex
fn vs_draw(@builtin(vertex_index) v: u32) -> TileOut {
    let slot = v / gparams.counts.x;
    let vertex = v - slot * gparams.counts.x;
    let view = views[draw_list[gparams.round.x + slot]];
    return into_tile_of(view.view_proj * world[vertex], view.tile, gparams.atlas.y);
}
