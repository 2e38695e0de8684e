// Clears the tiles of the listed views to depth 1 (far), leaving other tiles as they are: a
// depth attachment can only be cleared whole, and cached tiles must survive.

@group(0) @binding(0) var<storage, read> clear_views: array<ShadowViewData>;
@group(0) @binding(1) var<storage, read> clear_list: array<u32>;
@group(0) @binding(2) var<uniform> clear_atlas: vec4<f32>;

@vertex
fn vs_clear(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> @builtin(position) vec4<f32> {
    let tile = clear_views[clear_list[i]].tile;
    var quad = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    let corner = quad[v % 6u];
    // Cover the tile exactly: texel edges in atlas pixels, then to NDC (y down in pixels).
    let px = tile.xy + corner * tile.z;
    let ndc = vec2<f32>(px.x / clear_atlas.x * 2.0 - 1.0, 1.0 - px.y / clear_atlas.x * 2.0);
    return vec4<f32>(ndc, 1.0, 1.0);
}
