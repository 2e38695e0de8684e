// Alpha-tested casters drawn into atlas tiles (`layered`, `gpu-driven`, virtual pages): the
// tile output of tile.wgsl plus the caster's texture coordinate and material for `fs_alpha`
// (alpha_mask.wgsl), which drops uncovered texels. Opaque casters use pipelines without a
// fragment stage, so they never pay for this.

struct MaskedTileOut {
    @builtin(position) position: vec4<f32>,
    @builtin(clip_distances) clip: array<f32, 5>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
}

// `o` carrying caster vertex `v`'s texture coordinate and material.
fn masked_tile_out(o: TileOut, t: MaskTail, v: u32) -> MaskedTileOut {
    var out: MaskedTileOut;
    out.position = o.position;
    out.clip = o.clip;
    out.uv = caster_uv(t, v);
    out.material = caster_material(t, v);
    return out;
}

