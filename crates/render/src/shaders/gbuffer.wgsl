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
    // Surfaces are two-sided: the shading normal is turned to the side of the triangle the
    // camera sees. The side comes from the triangle's own plane (position derivatives), not
    // from its winding: scanned meshes have triangles wound against their neighbours whose
    // vertex normals still point outwards, and flipping those by winding shaded them as seen
    // from inside (black speckles). Winding decides only where the plane is degenerate.
    let to_eye = frame.camera_pos.xyz - in.world;
    var ng = cross(dpdx(in.world), dpdy(in.world));
    var facing = select(-1.0, 1.0, front);
    let ng_len = length(ng);
    if (ng_len > 0.0) {
        ng = ng / ng_len;
        if (dot(ng, to_eye) < 0.0) {
            ng = -ng;
        }
    }
    var n = in.normal;
    let n_len = length(n);
    if (n_len > 0.0) {
        n = n / n_len;
        if (ng_len > 0.0) {
            facing = select(-1.0, 1.0, dot(n, ng) >= 0.0);
        }
        n = n * facing;
    } else {
        // Normals that cancel (opposite faces on one vertex): the plane's normal.
        n = select(vec3<f32>(0.0, 1.0, 0.0), ng, ng_len > 0.0);
    }
    var out: GBufferOut;
    out.position = bitcast<vec4<u32>>(vec4<f32>(in.world, 1.0));
    out.normal_material = vec4<u32>(bitcast<vec3<u32>>(n), in.material);
    return out;
}
