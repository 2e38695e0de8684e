// `compute`, last pass: copies the round's depth buffer into the atlas. One instance per round
// entry (a band of rows of one view's tile): a quad covering exactly those texels, whose
// fragments load their texel's depth bits and write them as depth (compare Always). Tiles of
// views not in the round are never touched. (GL can write depth textures only this way.)

@group(0) @binding(0) var<uniform> copy_atlas: vec4<f32>;
@group(0) @binding(1) var<storage, read> copy_views: array<ShadowViewData>;
// Per round entry: view, first texel in `copy_depth`, first tile row, rows. A uniform, as in
// the raster passes: llvmpipe's OpenGL does not order a fragment shader's storage reads of it
// before the next frame's `write_buffer` into it, which left wrong texels after cached frames
// (docs/decisions.md, "Frames that change, buffers that stay").
@group(0) @binding(2) var<uniform> copy_entries: array<vec4<u32>, 4096>;
@group(0) @binding(3) var<storage, read> copy_depth: array<u32>;

struct CopyOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) entry: u32,
}

@vertex
fn vs_copy(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> CopyOut {
    let entry = copy_entries[i];
    let tile = copy_views[entry.x].tile;
    var quad = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    let corner = quad[v % 6u];
    // Texel edges of the band in atlas pixels, then NDC (y down in pixels).
    let px = vec2<f32>(
        tile.x + corner.x * tile.z,
        tile.y + f32(entry.z) + corner.y * f32(entry.w),
    );
    let side = copy_atlas.x;
    var out: CopyOut;
    out.position = vec4<f32>(px.x / side * 2.0 - 1.0, 1.0 - px.y / side * 2.0, 0.0, 1.0);
    out.entry = i;
    return out;
}

@fragment
fn fs_copy(in: CopyOut) -> @builtin(frag_depth) f32 {
    let entry = copy_entries[in.entry];
    let tile = copy_views[entry.x].tile;
    let p = vec2<u32>(floor(in.position.xy));
    let index = entry.y + (p.y - u32(tile.y) - entry.z) * u32(tile.z) + (p.x - u32(tile.x));
    // Stored as 1.0's bits minus the depth's bits (0 = far; see compute.wgsl).
    return bitcast<f32>(0x3f800000u - copy_depth[index]);
}
