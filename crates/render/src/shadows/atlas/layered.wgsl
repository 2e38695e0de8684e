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
// The view's projection of a world point, for the tile: a matrix, or the paraboloid warp
// (whose hemisphere base becomes the fifth clip distance).
fn project_into_tile(view: ShadowViewData, p: vec4<f32>) -> TileOut {
    if (view.params.w > 1.5) {
        let pc = paraboloid_clip(view.view_proj, view.params, p);
        var out = into_tile(pc.clip, view.tile);
        out.clip[4] = pc.front;
        return out;
    }
    return into_tile(view.view_proj * p, view.tile);
}

// Clip position used by the frustum test: for paraboloid views the warped position, with
// points behind the hemisphere pushed beyond the far plane so "all behind" culls.
fn cull_clip(view: ShadowViewData, p: vec4<f32>) -> vec4<f32> {
    if (view.params.w > 1.5) {
        let pc = paraboloid_clip(view.view_proj, view.params, p);
        return select(vec4<f32>(pc.clip.xy, 2.0, 1.0), pc.clip, pc.front >= 0.0);
    }
    return view.view_proj * p;
}

@vertex
fn vs_indexed(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> TileOut {
    return indexed(v, i);
}

fn indexed(v: u32, i: u32) -> TileOut {
    let view = views[draw_list[i]];
    return project_into_tile(view, world[v]);
}

// Culling: a non-indexed draw, three invocations per triangle; each pulls the whole triangle
// to decide, per view, whether it survives.
@vertex
fn vs_pulled(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> TileOut {
    return pulled(v, i);
}

// The alpha-tested range of the caster triangles (caster_layout.rs), drawn with `fs_alpha`.
@vertex
fn vs_indexed_masked(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> MaskedTileOut {
    return masked_tile_out(indexed(v, i), mask_tail(), v);
}

@vertex
fn vs_pulled_masked(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> MaskedTileOut {
    return masked_tile_out(pulled(v, i), mask_tail(), corners[v]);
}

fn pulled(v: u32, i: u32) -> TileOut {
    let view_id = draw_list[i];
    let view = views[view_id];
    let tri = v / 3u;
    let corner = v - 3u * tri;
    let p0 = world[corners[3u * tri]];
    let p1 = world[corners[3u * tri + 1u]];
    let p2 = world[corners[3u * tri + 2u]];
    let bits = lparams.counts.y;
    // Back-face test first: world space, no projection needed. Not for paraboloid views but
    // where it is the rule (CULL_ALWAYS): the warp's interpolation error can put a back
    // face's depth in front of the front face it hides, so dropping back faces would change
    // the map there.
    if ((bits & CULL_BACKFACE) != 0u && tri < lparams.counts.x
        && (view.params.w < 1.5 || (bits & CULL_ALWAYS) != 0u)
        && faces_away(p0.xyz, p1.xyz, p2.xyz, eyes[view_id])) {
        return culled_vertex();
    }
    if ((bits & CULL_FRUSTUM) != 0u
        && outside_frustum(cull_clip(view, p0), cull_clip(view, p1), cull_clip(view, p2))) {
        return culled_vertex();
    }
    // Only this invocation's corner needs projecting for output.
    return project_into_tile(view, select(select(p2, p1, corner == 1u), p0, corner == 0u));
}
