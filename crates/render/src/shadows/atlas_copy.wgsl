// Copies rows of the depth atlas into a float buffer for read-back (GL cannot copy depth
// textures to buffers, and compute cannot load depth textures there, so the atlas is bound
// as an unfilterable float texture).

struct CopyParams {
    first_row: u32,
    rows: u32,
    width: u32,
    _pad: u32,
}

@group(0) @binding(0) var atlas: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> out_depth: array<f32>;
@group(0) @binding(2) var<uniform> params: CopyParams;

@compute @workgroup_size(16, 16, 1)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.width || gid.y >= params.rows) {
        return;
    }
    let y = params.first_row + gid.y;
    out_depth[gid.y * params.width + gid.x] = textureLoad(atlas, vec2<u32>(gid.x, y), 0).r;
}
