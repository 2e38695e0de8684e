// `traditional` into dual-paraboloid views: the same depth-only pass with the paraboloid warp
// (paraboloid.wgsl) instead of a projection matrix, and the hemisphere's base plane as a clip
// distance: triangles crossing it are clipped where their (linearly interpolated) `front`
// reaches 0, so the two hemispheres meet at the disk's rim.

struct ParaboloidView {
    view: mat4x4<f32>,
    params: vec4<f32>,
}

@group(0) @binding(0) var<uniform> shadow_view: ParaboloidView;
@group(0) @binding(1) var<storage, read> instances: array<InstanceData>;

struct ParaboloidOut {
    @builtin(position) position: vec4<f32>,
    @builtin(clip_distances) clip: array<f32, 1>,
}

@vertex
fn vs_paraboloid(@location(0) position: vec3<f32>, @builtin(instance_index) instance: u32) -> ParaboloidOut {
    let w = instances[instance].model * vec4<f32>(position, 1.0);
    let pc = paraboloid_clip(shadow_view.view, shadow_view.params, w);
    var out: ParaboloidOut;
    out.position = pc.clip;
    out.clip[0] = pc.front;
    return out;
}

// The caster corner buffer, read for its mask tail (alpha_mask.wgsl).
@group(0) @binding(3) var<storage, read> corners: array<u32>;

// Alpha-tested instances into paraboloid views.
struct MaskedParaboloidOut {
    @builtin(position) position: vec4<f32>,
    @builtin(clip_distances) clip: array<f32, 1>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
}

@vertex
fn vs_paraboloid_masked(
    @location(0) position: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
) -> MaskedParaboloidOut {
    let inst = instances[instance];
    let pc = paraboloid_clip(shadow_view.view, shadow_view.params, inst.model * vec4<f32>(position, 1.0));
    var out: MaskedParaboloidOut;
    out.position = pc.clip;
    out.clip[0] = pc.front;
    out.uv = uv;
    out.material = inst.material.x;
    return out;
}

