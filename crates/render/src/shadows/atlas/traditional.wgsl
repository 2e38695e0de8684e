// Traditional shadow generation: a depth-only pass per shadow view (seed 004, seed 000 §19.2).
// Position-only vertex input, no fragment stage.

struct ViewUniform {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> shadow_view: ViewUniform;
@group(0) @binding(1) var<storage, read> instances: array<InstanceData>;

@vertex
fn vs_depth(@location(0) position: vec3<f32>, @builtin(instance_index) instance: u32) -> @builtin(position) vec4<f32> {
    return shadow_view.view_proj * (instances[instance].model * vec4<f32>(position, 1.0));
}

// The caster corner buffer, read for its mask tail (alpha_mask.wgsl): the records and bits of
// alpha-tested materials.
@group(0) @binding(3) var<storage, read> corners: array<u32>;

// Alpha-tested instances: the texture coordinate travels to `fs_alpha`.
struct MaskedOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
}

@vertex
fn vs_depth_masked(
    @location(0) position: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
) -> MaskedOut {
    let inst = instances[instance];
    return MaskedOut(shadow_view.view_proj * (inst.model * vec4<f32>(position, 1.0)), uv, inst.material.x);
}


struct Bones {
    m: array<mat4x4<f32>, 64>,
}

@group(0) @binding(2) var<uniform> bones: Bones;

// Seed 000 Listing 19.7's workload: up to four bones per vertex, then the instance's model
// matrix. The arithmetic matches `skinned_position` in casters.wgsl operation for operation.
@vertex
fn vs_skinned(
    @location(0) position: vec3<f32>,
    @location(1) joints: u32,
    @location(2) weights: vec4<f32>,
    @builtin(instance_index) instance: u32,
) -> @builtin(position) vec4<f32> {
    let p = vec4<f32>(position, 1.0);
    let j = unpack4xU8(joints);
    let s = weights.x * (bones.m[j.x] * p) + weights.y * (bones.m[j.y] * p)
        + weights.z * (bones.m[j.z] * p) + weights.w * (bones.m[j.w] * p);
    return shadow_view.view_proj * (instances[instance].model * s);
}
