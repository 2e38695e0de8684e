// Virtual shadow maps (vsm/): which level and page of a face a surface point needs, and
// where it falls there. Shared by the page-marking pass and the lookups of the lighting and
// visibility passes, so that a lookup asks for exactly the page the marking requested.
// Needs `frame: FrameUniforms`, `vsm: VsmUniforms` and shadow_lookup.wgsl
// (`receiver_offset_dir`).

// A sample seen from a face, computed once per (sample, face): the clip position of the
// point and of its bias direction. The receiver offset is the texel's world size times that
// direction (`receiver_offset_dir`, scaled by `VirtualOptions::bias_scale`), so the biased
// clip position for any level is `p + texel · d`: walking down to coarser levels costs no
// further transform.
struct VsmRay {
    p: vec4<f32>,
    d: vec4<f32>,
}

fn vsm_ray(light: LightData, face: VirtualFace, p: vec3<f32>, n: vec3<f32>) -> VsmRay {
    var out: VsmRay;
    out.p = face.view_proj * vec4<f32>(p, 1.0);
    out.d = face.view_proj * vec4<f32>(receiver_offset_dir(light, p, n) * vsm.lod.w, 0.0);
    return out;
}

// World size of one texel of `face` at `level` around the sample.
fn vsm_texel_world(face: VirtualFace, level: u32, ray: VsmRay) -> f32 {
    var t = face.params.z * f32(1u << (face.table.y - level));
    if (face.params.w < 0.5) {
        t = t * max(ray.p.w, 0.0);
    }
    return t;
}

// The level a sample (camera view depth `view_depth`) needs: the coarsest whose texels are no
// larger than the screen pixel there, divided by the face's level of detail (`detail.x`,
// texels per pixel), and no coarser than the atlas's tile of the view (`vsm_floor`). Level 0
// when even the finest level is coarser than that.
fn vsm_level(face: VirtualFace, ray: VsmRay, view_depth: f32) -> u32 {
    let finest = face.table.y;
    let texel = vsm_texel_world(face, finest, ray);
    let pixel = view_depth * frame.bias.w / max(face.detail.x, 1e-6);
    // Level l has texels 2^(finest - l) times the finest: the coarsest level with
    // 2^(finest - l) · texel <= pixel is finest - floor(log2(pixel / texel)).
    let k = floor(log2(max(pixel, 1e-30) / max(texel, 1e-30)));
    return vsm_floor(face, finest - u32(clamp(k, 0.0, f32(finest))));
}

// `level`, or the face's coarsest allowed level (`detail.y`: as fine as the tile the atlas
// techniques give the same view) if that is finer.
fn vsm_floor(face: VirtualFace, level: u32) -> u32 {
    return max(level, min(u32(face.detail.y), face.table.y));
}

// A point in a face: continuous coordinates over the whole face (0..1, y down, as atlas
// tiles) and its depth, after the receiver bias of `level`'s texel size.
struct VsmPoint {
    uv: vec2<f32>,
    depth: f32,
    // The receiver's distance key, linear in position and ordered as `depth`: clip w of a
    // perspective face, clip z of an orthographic one (vsm_draw.wgsl's `key_row`), unclamped.
    key: f32,
    valid: bool,
}

fn vsm_project(light: LightData, face: VirtualFace, ray: VsmRay, level: u32) -> VsmPoint {
    return vsm_project_texel(light, face, ray, vsm_texel_world(face, level, ray) * vsm_bias_factor(face, level));
}

// The receiver bias of `level` over the scaled one `ray.d` carries: at a spot face's atlas
// floor (`detail.y`, texels as large as the atlas tile's) the atlas's whole bias (`detail.z`
// = 1 / VirtualOptions::bias_scale, at least 1; plan.rs says why spots only), so that there
// the lookup is the atlas's; 1 elsewhere.
fn vsm_bias_factor(face: VirtualFace, level: u32) -> f32 {
    return select(1.0, face.detail.z, face.detail.z > 0.0 && level == u32(face.detail.y));
}

// As `vsm_project`, biased for texels of world size `texel` (a quarter page's are twice its
// level's).
fn vsm_project_texel(light: LightData, face: VirtualFace, ray: VsmRay, texel: f32) -> VsmPoint {
    var out: VsmPoint;
    out.valid = false;
    let clip = ray.p + texel * ray.d;
    if (clip.w <= 0.0) {
        return out;
    }
    let ndc = clip.xyz / clip.w;
    // Outside a spot's cone or a cascade: no shadow information (as in the atlas lookup);
    // cube faces only get here through the bias offset and are clamped.
    if (any(abs(ndc.xy) > vec2<f32>(1.0)) && light.shadow.z != LIGHT_POINT) {
        return out;
    }
    out.uv = clamp(ndc.xy * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5), vec2<f32>(0.0), vec2<f32>(1.0));
    out.depth = clamp(ndc.z, 0.0, 1.0);
    out.key = select(clip.w, clip.z, face.params.w > 0.5);
    out.valid = true;
    return out;
}

// The page-table entry of the page of `level` that holds `uv`.
fn vsm_entry(face: VirtualFace, level: u32, uv: vec2<f32>) -> u32 {
    let n = 1u << level;
    let xy = min(vec2<u32>(uv * f32(n)), vec2<u32>(n - 1u));
    return face.table.x + ((1u << (2u * level)) - 1u) / 3u + xy.y * n + xy.x;
}
