// Stereo in one layered pass (frame/eyes.rs): instance `i` is scene instance `i / 2` seen by
// eye `i % 2`. Clip-space x is moved into the eye's half of the image, and a clip distance
// keeps the copy there: x_ndc' = x_ndc / 2 + eye − 1/2, so the left eye keeps x_ndc' ≤ 0 and
// the right eye x_ndc' ≥ 0.

struct LayeredVsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    @location(3) uv: vec2<f32>,
    @location(4) @interpolate(flat) eye: u32,
    @builtin(clip_distances) half: array<f32, 1>,
}

@vertex
fn vs_layered(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
) -> LayeredVsOut {
    let eye = instance % 2u;
    let v = surface_vertex(position, normal, uv, instance / 2u, eye);
    let c = v.clip;
    let x = 0.5 * c.x + (f32(eye) - 0.5) * c.w;
    var out: LayeredVsOut;
    out.clip = vec4<f32>(x, c.yzw);
    out.world = v.world;
    out.normal = v.normal;
    out.material = v.material;
    out.uv = v.uv;
    out.eye = eye;
    out.half[0] = select(-x, x, eye == 1u);
    return out;
}
