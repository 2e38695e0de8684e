// A probe's six faces in one multiview pass (probes/faces.rs): view `view_index` of the
// pass is face `6 · probe + view_index`; draw instance `probe · instances + i` is scene
// instance `i` (instances in `face_views[0].tile.w`). Each face lands in its layer of
// six-layer targets, at the origin, as one pass per face would draw it.

@vertex
fn vs_face_layers(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
    @builtin(view_index) layer: u32,
) -> VsOut {
    let n = max(u32(face_views[0].tile.w), 1u);
    let f = 6u * (instance / n) + layer;
    return surface_vertex_seen(position, normal, uv, instance % n, face_views[f].view_proj, f);
}
