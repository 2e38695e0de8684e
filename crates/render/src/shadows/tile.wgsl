// Drawing into an atlas tile from an atlas-wide viewport, shared by `layered` and
// `gpu-driven`: clip-space xy moves into the tile and four clip distances keep the triangle
// inside it.

struct TileOut {
    @builtin(position) position: vec4<f32>,
    @builtin(clip_distances) clip: array<f32, 5>,
}

// Maps a view's clip position into its tile of the atlas-wide viewport (`inv` = 1 / atlas
// side in texels): the same pixel the traditional pass's per-tile viewport gives, up to
// rounding. Depth (z, w) is untouched.
fn into_tile_of(c: vec4<f32>, tile: vec4<f32>, inv: f32) -> TileOut {
    let s = tile.z * inv;
    let ox = (2.0 * tile.x + tile.z) * inv - 1.0;
    let oy = 1.0 - (2.0 * tile.y + tile.z) * inv;
    var out: TileOut;
    out.position = vec4<f32>(c.x * s + c.w * ox, c.y * s + c.w * oy, c.z, c.w);
    out.clip = array<f32, 5>(c.w + c.x, c.w - c.x, c.w + c.y, c.w - c.y, 1.0);
    return out;
}

fn culled_vertex() -> TileOut {
    var out: TileOut;
    // All three corners of a culled triangle land here: zero area, and clipped anyway.
    out.position = vec4<f32>(0.0, 0.0, 2.0, 1.0);
    out.clip = array<f32, 5>(-1.0, -1.0, -1.0, -1.0, -1.0);
    return out;
}
