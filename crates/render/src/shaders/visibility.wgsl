// Hard-shadow visibility: one bit per light and pixel, no filtering. Bit set = the point is
// within the light's reach (range, cone) and the shadow map says nothing occludes it. This is
// what shadow quality is scored on.

struct VisibilityParams {
    // First light of this chunk, number of 32-light words in this chunk, unused x2.
    first_word: u32,
    word_count: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<LightData>;
@group(0) @binding(2) var<storage, read> shadow_views: array<ShadowViewData>;
@group(0) @binding(3) var gbuf_position: texture_2d<u32>;
@group(0) @binding(4) var gbuf_normal: texture_2d<u32>;
// The depth atlas read as plain floats: compute shaders on GL cannot load depth textures.
@group(0) @binding(5) var atlas: texture_2d<f32>;
@group(0) @binding(6) var<storage, read_write> mask: array<u32>;
@group(0) @binding(7) var<uniform> params: VisibilityParams;

@compute @workgroup_size(8, 8, 1)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = u32(frame.viewport.x);
    let h = u32(frame.viewport.y);
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let pixel = gid.y * w + gid.x;
    let pos = bitcast<vec4<f32>>(textureLoad(gbuf_position, vec2<i32>(gid.xy), 0));
    let has_geometry = pos.w >= 0.5;
    let p = pos.xyz;
    let n = normalize(bitcast<vec3<f32>>(textureLoad(gbuf_normal, vec2<i32>(gid.xy), 0).xyz));
    let view_depth = -(frame.view * vec4<f32>(p, 1.0)).z;
    let count = frame.counts.x;
    for (var wi = 0u; wi < params.word_count; wi = wi + 1u) {
        var bits = 0u;
        let word = params.first_word + wi;
        if (has_geometry) {
            for (var b = 0u; b < 32u; b = b + 1u) {
                let li = word * 32u + b;
                if (li >= count) {
                    break;
                }
                let light = lights[li];
                if (!in_reach(light, p)) {
                    continue;
                }
                let c = shadow_coord(light, p, n, view_depth);
                var lit = true;
                if (c.valid) {
                    lit = c.depth <= textureLoad(atlas, hard_texel(c), 0).r;
                }
                if (lit) {
                    bits = bits | (1u << b);
                }
            }
        }
        mask[pixel * params.word_count + wi] = bits;
    }
}
