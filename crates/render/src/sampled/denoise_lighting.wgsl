// The lighting pass's side of the denoiser (denoise.rs): where it writes each pixel's
// unshadowed light and shadow ratio, and `fs_composite`, which shades the filtered ratio.
// Bindings (denoise.rs `LIGHTING_BINDINGS`): `denoise_px`, per pixel what the lighting pass
// leaves the denoiser; `denoise_ratio`, the filtered ratio the composite reads, written by the
// lighting pass only in a frame whose lights changed, with the history's correction for the
// temporal pass (denoise_store_fix).

// Per pixel: [exact unshadowed direct light, 1 = geometry], [estimate with shadows, the
// frames of samples it stands for (0 = 1)], [the same estimate without, 0], [ambient +
// emission, 0].
fn denoise_store(px: vec2<i32>, a: vec4<f32>, shadowed: vec3<f32>, unshadowed: vec3<f32>, rest: vec3<f32>, frames: f32) {
    if (choosing) {
        return;
    }
    let i = 4u * (u32(px.y) * u32(frame.viewport.x) + u32(px.x));
    denoise_px[i] = a;
    denoise_px[i + 1u] = vec4<f32>(shadowed, frames);
    denoise_px[i + 2u] = vec4<f32>(unshadowed, 0.0);
    denoise_px[i + 3u] = vec4<f32>(rest, 0.0);
}

// Replaces the pixel's estimate with shadows (spatial reuse's, after the lighting pass's).
fn denoise_set_shadowed(px: vec2<i32>, shadowed: vec3<f32>) {
    let i = 4u * (u32(px.y) * u32(frame.viewport.x) + u32(px.x));
    denoise_px[i + 1u] = vec4<f32>(shadowed, 0.0);
}

// What the lights that changed add to the pixel's estimates with and without shadows, and
// the luminance of the unshadowed light that went (denoise_fix), for the denoiser's temporal
// pass.
fn denoise_store_fix(px: vec2<i32>, shadowed: vec3<f32>, unshadowed: vec3<f32>, went: f32) {
    if (choosing) {
        return;
    }
    let i = 2u * (u32(px.y) * u32(frame.viewport.x) + u32(px.x));
    denoise_ratio[i] = vec4<f32>(shadowed, 0.0);
    denoise_ratio[i + 1u] = vec4<f32>(unshadowed, went);
}

@fragment
fn fs_composite(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    let i = u32(px.y) * u32(frame.viewport.x) + u32(px.x);
    let exact = denoise_px[4u * i];
    if (exact.w == 0.0) {
        return vec4<f32>(frame.sky.rgb, 1.0);
    }
    // Per channel: the filtered estimate with shadows over the same without, where that
    // channel carries light (else the luminance ratio).
    let s = denoise_ratio[2u * i].rgb;
    let u = denoise_ratio[2u * i + 1u].rgb;
    let luma = vec3<f32>(0.2126, 0.7152, 0.0722);
    let r_lum = dot(s, luma) / max(dot(u, luma), 1e-30);
    let r = select(vec3<f32>(r_lum), s / max(u, vec3<f32>(1e-30)), u > vec3<f32>(1e-6 * dot(u, luma)));
    let rest = denoise_px[4u * i + 3u].rgb;
    return vec4<f32>(tone_map(rest + exact.rgb * clamp(r, vec3<f32>(0.0), vec3<f32>(1.0))), 1.0);
}
