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
