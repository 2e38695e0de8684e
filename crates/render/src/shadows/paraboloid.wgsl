// Dual-paraboloid projection (seed 003): a hemisphere of directions around a view's −Z axis
// maps onto the unit disk, `xy = n.xy / (1 + front)` for the unit direction `n` from the light
// (`front = −n.z`), and depth is the linear distance `(d − near) / (far − near)`. The warp is
// not a matrix, and rasterization interpolates linearly between the warped corners, so
// coarse triangles come out with straight edges where true outlines curve (seed 003's
// weakness). `ShadowViewData.params.w == 2` marks such views. Matches
// `light_space::paraboloid_project` in the scene crate.

const PROJECTION_PARABOLOID: f32 = 2.0;

struct ParaboloidClip {
    // Clip position, w = 1.
    clip: vec4<f32>,
    // −n.z: ≥ 0 inside the hemisphere (used as a clip distance).
    front: f32,
}

fn paraboloid_clip(view: mat4x4<f32>, params: vec4<f32>, p: vec4<f32>) -> ParaboloidClip {
    let v = (view * p).xyz;
    let d = length(v);
    let n = v / max(d, 1e-20);
    let front = -n.z;
    // Points behind the hemisphere stay finite (and are clipped by `front`).
    let k = 1.0 / max(1.0 + front, 1e-3);
    var out: ParaboloidClip;
    out.clip = vec4<f32>(n.x * k, n.y * k, (d - params.x) / (params.y - params.x), 1.0);
    out.front = front;
    return out;
}
