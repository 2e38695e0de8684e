// Copies the lit frame into a texture the caller owns (Renderer::render_to), any size and any
// colour format: nearest texel, decoded from sRGB by the sampler-free load, re-encoded here
// when the target stores raw (non-sRGB) 8-bit values.

@group(0) @binding(0) var blit_src: texture_2d<f32>;
// Target width, height; 1 = encode to sRGB in the shader; unused.
@group(0) @binding(1) var<uniform> blit_params: vec4<f32>;

@vertex
fn vs_blit(@builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the target.
    let uv = vec2<f32>(f32((v << 1u) & 2u), f32(v & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn encode_srgb(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(max(c, vec3<f32>(0.0)), vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

@fragment
fn fs_blit(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(blit_src));
    let texel = min(vec2<u32>(floor(p.xy * size / blit_params.xy)), vec2<u32>(size) - 1u);
    let c = textureLoad(blit_src, texel, 0);
    if (blit_params.z > 0.5) {
        return vec4<f32>(encode_srgb(c.rgb), c.a);
    }
    return c;
}
