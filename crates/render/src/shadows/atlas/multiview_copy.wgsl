// `multiview`, second half: copies each layer of the scratch depth array into its view's atlas
// tile. One draw per group, six vertices per layer: a quad covering the tile exactly,
// whose fragments load the scratch texel and write it as depth (depth copies into a
// sub-rectangle of a texture are not allowed by copy_texture_to_texture).

struct MultiviewParams {
    // first draw-list entry of the group, cullable triangles, cull bits, unused
    counts: vec4<u32>,
    // atlas side in texels, unused, unused, unused
    atlas: vec4<f32>,
}

@group(0) @binding(0) var<uniform> cparams: MultiviewParams;
@group(0) @binding(1) var<storage, read> copy_views: array<ShadowViewData>;
@group(0) @binding(2) var<storage, read> copy_list: array<u32>;
@group(0) @binding(3) var scratch: texture_depth_2d_array;

struct CopyOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) layer: u32,
}

@vertex
fn vs_copy(@builtin(vertex_index) v: u32) -> CopyOut {
    let layer = v / 6u;
    let tile = copy_views[copy_list[cparams.counts.x + layer]].tile;
    var quad = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    // Tile edges in atlas pixels, then NDC (y down in pixels): covers exactly the tile.
    let px = tile.xy + quad[v % 6u] * tile.z;
    let side = cparams.atlas.x;
    var out: CopyOut;
    out.position = vec4<f32>(px.x / side * 2.0 - 1.0, 1.0 - px.y / side * 2.0, 0.0, 1.0);
    out.layer = layer;
    return out;
}

@fragment
fn fs_copy(in: CopyOut) -> @builtin(frag_depth) f32 {
    let tile = copy_views[copy_list[cparams.counts.x + in.layer]].tile;
    let texel = vec2<i32>(floor(in.position.xy)) - vec2<i32>(tile.xy);
    return textureLoad(scratch, texel, i32(in.layer), 0);
}
