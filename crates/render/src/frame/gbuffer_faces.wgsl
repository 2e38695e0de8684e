// Many square views in one layered pass (reflection probes' faces, probes/faces.rs): every
// view is a tile of one atlas G-buffer. Instance `i` is scene instance `i / views` seen by view
// `i % views`; its clip position is moved into the view's tile and four clip distances keep
// the triangle there (seed 000's layered rendering on colour targets, as the layered shadow
// technique does on depth).

struct FacesVsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    @location(3) uv: vec2<f32>,
    @location(4) @interpolate(flat) eye: u32,
    @builtin(clip_distances) inside: array<f32, 4>,
}

@vertex
fn vs_faces(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
) -> FacesVsOut {
    let views = arrayLength(&face_views);
    let f = instance % views;
    return into_face_tile(surface_vertex_seen(position, normal, uv, instance / views, face_views[f].view_proj, f), f);
}

// A vertex seen by view `f`, moved into the view's tile of the atlas.
fn into_face_tile(v: VsOut, f: u32) -> FacesVsOut {
    let c = v.clip;
    // The atlas's size in pixels is the frame's viewport.
    let tile = face_views[f].tile;
    let s = tile.z / frame.viewport.xy;
    let o = vec2<f32>(
        (2.0 * tile.x + tile.z) / frame.viewport.x - 1.0,
        1.0 - (2.0 * tile.y + tile.z) / frame.viewport.y,
    );
    var out: FacesVsOut;
    out.clip = vec4<f32>(c.x * s.x + c.w * o.x, c.y * s.y + c.w * o.y, c.z, c.w);
    out.inside = array<f32, 4>(c.w + c.x, c.w - c.x, c.w + c.y, c.w - c.y);
    out.world = v.world;
    out.normal = v.normal;
    out.material = v.material;
    out.uv = v.uv;
    out.eye = f;
    return out;
}
