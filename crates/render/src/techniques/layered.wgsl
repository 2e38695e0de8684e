// `layered`: one instanced draw renders every shadow caster into every listed view's tile
// (seed 000 §19.3 with instance → view instead of a geometry shader's layer output).
// World positions come from the per-frame caster transform; the vertex shader only applies
// the view's projection, moves clip-space xy into the tile, and keeps the triangle inside the
// tile with four clip distances.


struct LayeredParams {
    // cullable triangles, cull bits, unused, unused
    counts: vec4<u32>,
    // atlas side in texels, its reciprocal, unused, unused
    atlas: vec4<f32>,
}

@group(0) @binding(0) var<uniform> lparams: LayeredParams;
@group(0) @binding(1) var<storage, read> views: array<ShadowViewData>;
@group(0) @binding(2) var<storage, read> eyes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> world: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> corners: array<u32>;
@group(0) @binding(5) var<storage, read> draw_list: array<u32>;

// Maps a view's clip position into its tile (see `into_tile_of` in tile.wgsl).
fn into_tile(c: vec4<f32>, tile: vec4<f32>) -> TileOut {
    return into_tile_of(c, tile, lparams.atlas.y);
}

// No culling: an indexed draw of the caster corners, so shared vertices can be reused.
@vertex
fn vs_indexed(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> TileOut {
    let view = views[draw_list[i]];
    return into_tile(view.view_proj * world[v], view.tile);
}

// Culling: a non-indexed draw, three invocations per triangle; each pulls the whole triangle
// to decide, per view, whether it survives.
@vertex
fn vs_pulled(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> TileOut {
    let view_id = draw_list[i];
    let view = views[view_id];
    let tri = v / 3u;
    let corner = v - 3u * tri;
    let p0 = world[corners[3u * tri]];
    let p1 = world[corners[3u * tri + 1u]];
    let p2 = world[corners[3u * tri + 2u]];
    let bits = lparams.counts.y;
    // Back-face test first: world space, no projection needed.
    if ((bits & CULL_BACKFACE) != 0u && tri < lparams.counts.x
        && faces_away(p0.xyz, p1.xyz, p2.xyz, eyes[view_id])) {
        return culled_vertex();
    }
    var c: vec4<f32>;
    if ((bits & CULL_FRUSTUM) != 0u) {
        let c0 = view.view_proj * p0;
        let c1 = view.view_proj * p1;
        let c2 = view.view_proj * p2;
        if (outside_frustum(c0, c1, c2)) {
            return culled_vertex();
        }
        c = select(select(c2, c1, corner == 1u), c0, corner == 0u);
    } else {
        // Only this invocation's corner needs projecting.
        c = view.view_proj * select(select(p2, p1, corner == 1u), p0, corner == 0u);
    }
    return into_tile(c, view.tile);
}
