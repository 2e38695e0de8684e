// Culling whole triangle clusters of casters.wgsl against a view, shared by `gpu-driven` and
// the virtual shadow maps' page rendering (vsm/draw.rs): frustum by the cluster's bounding sphere,
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

// The six planes of a view's clip volume (wgpu clip space: -w <= x, y <= w, 0 <= z <= w):
// the rows of the view-projection combined (Gribb and Hartmann), with their normals' lengths.
// Separate fields, not an array: a software driver keeps an indexed private array in memory.
// A cull testing many spheres or boxes against one view builds them once.
struct ViewPlanes {
    left: vec4<f32>,
    right: vec4<f32>,
    bottom: vec4<f32>,
    top: vec4<f32>,
    near: vec4<f32>,
    far: vec4<f32>,
    // left, right, bottom, top; then near, far.
    lengths: vec4<f32>,
    depth_lengths: vec2<f32>,
}

fn view_planes(m: mat4x4<f32>) -> ViewPlanes {
    let r0 = vec4<f32>(m[0].x, m[1].x, m[2].x, m[3].x);
    let r1 = vec4<f32>(m[0].y, m[1].y, m[2].y, m[3].y);
    let r2 = vec4<f32>(m[0].z, m[1].z, m[2].z, m[3].z);
    let r3 = vec4<f32>(m[0].w, m[1].w, m[2].w, m[3].w);
    var out: ViewPlanes;
    out.left = r3 + r0;
    out.right = r3 - r0;
    out.bottom = r3 + r1;
    out.top = r3 - r1;
    out.near = r2;
    out.far = r3 - r2;
    out.lengths = vec4<f32>(length(out.left.xyz), length(out.right.xyz), length(out.bottom.xyz), length(out.top.xyz));
    out.depth_lengths = vec2<f32>(length(out.near.xyz), length(out.far.xyz));
    return out;
}

// Whether sphere `s` (centre, radius; `c` = length of the centre) lies wholly outside plane `p`
// (normal length `len`); a small slack keeps rounding from culling a visible sphere.
fn sphere_outside_plane(p: vec4<f32>, len: f32, s: vec4<f32>, c: f32) -> bool {
    return dot(p.xyz, s.xyz) + p.w < -s.w * len - 1e-5 * (len * c + abs(p.w));
}

// True if the sphere (centre, radius) lies wholly outside one of the planes.
fn sphere_outside_planes(v: ViewPlanes, s: vec4<f32>) -> bool {
    let c = length(s.xyz);
    let l = v.lengths;
    return sphere_outside_plane(v.left, l.x, s, c) || sphere_outside_plane(v.right, l.y, s, c)
        || sphere_outside_plane(v.bottom, l.z, s, c) || sphere_outside_plane(v.top, l.w, s, c)
        || sphere_outside_plane(v.near, v.depth_lengths.x, s, c)
        || sphere_outside_plane(v.far, v.depth_lengths.y, s, c);
}

// True if the sphere (centre, radius) lies wholly outside one plane of the view's clip volume.
fn sphere_outside(m: mat4x4<f32>, s: vec4<f32>) -> bool {
    return sphere_outside_planes(view_planes(m), s);
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
