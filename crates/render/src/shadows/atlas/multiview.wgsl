// `multiview`: one render pass per group of equal-size views (a point light's six cube faces,
// a run of cascades or spot lights), up to the adapter's multiview view count. The pass
// renders into layers 0..n of a scratch depth array; `view_index` picks the group's view.
// World positions come from the per-frame caster transform, so per view only the
// view-projection remains; per-triangle culling pulls the triangle's three corners (as in
// `layered`) and emits a degenerate triangle when it is dropped.

struct MultiviewParams {
    // first draw-list entry of the group, cullable triangles, cull bits, unused
    counts: vec4<u32>,
    // atlas side in texels, unused, unused, unused
    atlas: vec4<f32>,
}

@group(0) @binding(0) var<uniform> mparams: MultiviewParams;
@group(0) @binding(1) var<storage, read> views: array<ShadowViewData>;
@group(0) @binding(2) var<storage, read> eyes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> world: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> corners: array<u32>;
@group(0) @binding(5) var<storage, read> draw_list: array<u32>;

// Where all three corners of a culled triangle go: zero area, and inside the clip volume so
// the triangle never reaches the clipper (lavapipe's clipper before Mesa 25 loses the view
// index: `clips_into_layer_zero`).
const MV_CULLED: vec4<f32> = vec4<f32>(0.0, 0.0, 0.5, 1.0);

// No culling: an indexed draw of the caster corners (post-transform vertex reuse applies).
@vertex
fn vs_indexed(@builtin(vertex_index) v: u32, @builtin(view_index) layer: u32) -> @builtin(position) vec4<f32> {
    return indexed(v, layer);
}

fn indexed(v: u32, layer: u32) -> vec4<f32> {
    let view = views[draw_list[mparams.counts.x + layer]];
    return view.view_proj * world[v];
}

// Culling: a non-indexed draw, three invocations per triangle, each pulling the triangle.
@vertex
fn vs_pulled(@builtin(vertex_index) v: u32, @builtin(view_index) layer: u32) -> @builtin(position) vec4<f32> {
    return pulled(v, layer);
}

// The alpha-tested range of the caster triangles (caster_layout.rs), drawn with `fs_alpha`.
struct MaskedOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
}

fn masked_out(position: vec4<f32>, v: u32) -> MaskedOut {
    let t = mask_tail();
    return MaskedOut(position, caster_uv(t, v), caster_material(t, v));
}

@vertex
fn vs_indexed_masked(@builtin(vertex_index) v: u32, @builtin(view_index) layer: u32) -> MaskedOut {
    return masked_out(indexed(v, layer), v);
}

@vertex
fn vs_pulled_masked(@builtin(vertex_index) v: u32, @builtin(view_index) layer: u32) -> MaskedOut {
    return masked_out(pulled(v, layer), corners[v]);
}


fn pulled(v: u32, layer: u32) -> vec4<f32> {
    let view_id = draw_list[mparams.counts.x + layer];
    let view = views[view_id];
    let tri = v / 3u;
    let corner = v - 3u * tri;
    let p0 = world[corners[3u * tri]];
    let p1 = world[corners[3u * tri + 1u]];
    let p2 = world[corners[3u * tri + 2u]];
    let c0 = view.view_proj * p0;
    let c1 = view.view_proj * p1;
    let c2 = view.view_proj * p2;
    let bits = mparams.counts.z;
    if ((bits & CULL_FRUSTUM) != 0u && outside_frustum(c0, c1, c2)) {
        return MV_CULLED;
    }
    if ((bits & CULL_BACKFACE) != 0u && tri < mparams.counts.y
        && faces_away(p0.xyz, p1.xyz, p2.xyz, eyes[view_id])) {
        return MV_CULLED;
    }
    return select(select(c2, c1, corner == 1u), c0, corner == 0u);
}

