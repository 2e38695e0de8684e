// The views of a G-buffer that holds many square views (reflection probes' faces,
// probes/faces.rs): each view's projection, where it is seen from and its tile.

struct FaceView {
    view_proj: mat4x4<f32>,
    // xyz: where the view is seen from.
    eye: vec4<f32>,
    // The tile: left and top pixel, side in pixels; w: the scene's instances (the multiview
    // pass's instance index is probe · instances + instance).
    tile: vec4<f32>,
}

@group(0) @binding(6) var<storage, read> face_views: array<FaceView>;

fn eye_position(e: u32) -> vec3<f32> {
    return face_views[e].eye.xyz;
}

