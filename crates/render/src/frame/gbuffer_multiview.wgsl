// Stereo in one multiview pass (frame/eyes.rs): the pass draws into layer `view_index` of
// two-layer targets, one per eye, each at the origin (gbuffer_record.rs then copies each layer
// into its eye's half). Instance `i` is scene instance `i`, drawn once for both views.

@vertex
fn vs_multiview(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
    @builtin(view_index) eye: u32,
) -> VsOut {
    return surface_vertex(position, normal, uv, instance, eye);
}
