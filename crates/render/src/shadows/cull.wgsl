// Per-view triangle culling shared by the single-pass techniques (seed 000 Listings 19.9 and
// 19.10, moved from a geometry shader to vertex pulling).

const CULL_FRUSTUM: u32 = 1u;
const CULL_BACKFACE: u32 = 2u;
// Back-face culling of the cullable triangles is the rule (single-sided casters cast only where
// a light sees their front): applied in every kind of view, dual-paraboloid ones too.
const CULL_ALWAYS: u32 = 4u;

// True if the triangle's three clip-space corners are all outside one clip plane (wgpu clip
// space: -w <= x, y <= w, 0 <= z <= w): conservative, never drops a visible triangle.
fn outside_frustum(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> bool {
    return (a.x < -a.w && b.x < -b.w && c.x < -c.w)
        || (a.x > a.w && b.x > b.w && c.x > c.w)
        || (a.y < -a.w && b.y < -b.w && c.y < -c.w)
        || (a.y > a.w && b.y > b.w && c.y > c.w)
        || (a.z < 0.0 && b.z < 0.0 && c.z < 0.0)
        || (a.z > a.w && b.z > b.w && c.z > c.w);
}

// True if the counter-clockwise (front) side of the world-space triangle faces away from the
// light. `eye` is the light position (w = 1) or the direction light travels (w = 0).
fn faces_away(p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, eye: vec4<f32>) -> bool {
    let n = cross(p1 - p0, p2 - p0);
    let to_light = select(-eye.xyz, eye.xyz - p0, eye.w > 0.5);
    return dot(n, to_light) < 0.0;
}
