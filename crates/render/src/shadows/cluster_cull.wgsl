// Culling whole triangle clusters of casters.wgsl against a view, shared by `gpu-driven` and
// the virtual shadow maps' page rendering (vsm.rs): frustum by the cluster's bounding sphere,
// back faces by its normal cone.

// A cluster of casters.wgsl: a run of triangles of one instance and its object-space normal
// cone (axis, half angle; >= pi/2: never back-face culled).
struct GpuCluster {
    first_triangle: u32,
    triangles: u32,
    instance: u32,
    flags: u32,
    cone: vec4<f32>,
}

const HALF_PI: f32 = 1.5707963;
// Angle (radians) added to every cone test so rounding never culls a visible cluster.
const CONE_MARGIN: f32 = 1e-4;

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
fn cluster_faces_away(cl: GpuCluster, normal: mat4x4<f32>, sphere: vec4<f32>, eye: vec4<f32>) -> bool {
    let a = cl.cone.w;
    if (a >= HALF_PI) {
        return false;
    }
    // Object-space axis to world space by the instance's normal matrix (instances hold similarity transforms when the cone
    // exists, so angles are kept).
    let axis = normalize((normal * vec4<f32>(cl.cone.xyz, 0.0)).xyz);
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


// wgpu::util::DrawIndexedIndirectArgs.
struct DrawCommand {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}
