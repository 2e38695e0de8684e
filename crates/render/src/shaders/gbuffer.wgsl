// G-buffer pass: world position and normal + material of the nearest surface per pixel.

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> instances: array<InstanceData>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
}

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) instance: u32,
) -> VsOut {
    let inst = instances[instance];
    let world = inst.model * vec4<f32>(position, 1.0);
    var out: VsOut;
    out.clip = frame.view_proj * world;
    out.world = world.xyz;
    out.normal = (inst.normal * vec4<f32>(normal, 0.0)).xyz;
    out.material = inst.material.x;
    return out;
}

// Both targets hold f32 bit patterns in u32 channels (exact, and renderable on every backend).
struct GBufferOut {
    // xyz world position, w = 1.0 where there is geometry (the clear value 0 reads as 0.0).
    @location(0) position: vec4<u32>,
    // xyz unit normal facing the camera, w = material index (as u32, not bits).
    @location(1) normal_material: vec4<u32>,
}

@fragment
fn fs_main(in: VsOut, @builtin(front_facing) front: bool) -> GBufferOut {
    var n = normalize(in.normal);
    // Surfaces are two-sided: a back face seen by the camera is shaded with its normal flipped.
    if (!front) {
        n = -n;
    }
    var out: GBufferOut;
    out.position = bitcast<vec4<u32>>(vec4<f32>(in.world, 1.0));
    out.normal_material = vec4<u32>(bitcast<vec3<u32>>(n), in.material);
    return out;
}
