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

// Marks the pixel's shadow as maybe moved this frame (after `denoise_store`): the segment to
// a light it traced passes a caster that moved (`moved_caster_between`); the temporal pass
// then keeps at most MOVING_HISTORY frames of its history.
fn denoise_note_shadow_moved(px: vec2<i32>, share: f32) {
    if (choosing) {
        return;
    }
    let i = 4u * (u32(px.y) * u32(frame.viewport.x) + u32(px.x));
    denoise_px[i + 2u].w = share;
}

// Casters that moved since the last frame (0: none, and `moved_caster_between` is false).
fn moved_casters() -> u32 {
    let base = arrayLength(&denoise_ratio) - DENOISE_MOVED_SLOTS;
    return min(u32(denoise_ratio[base].x), DENOISE_MOVED_SLOTS - 1u);
}

// Whether a caster that moved since the last frame (a sphere around its old and new bounds,
// at the end of `denoise_ratio`: denoise.rs `upload_moved`) may lie between `s` and light `i`:
// the segment to the light's centre (a directional light: the ray towards it) passes within
// the sphere's radius grown by the light's size (the cone to its shape is no wider).
fn moved_caster_between(i: u32, s: Surface) -> bool {
    let base = arrayLength(&denoise_ratio) - DENOISE_MOVED_SLOTS;
    let n = min(u32(denoise_ratio[base].x), DENOISE_MOVED_SLOTS - 1u);
    if (n == 0u) {
        return false;
    }
    let light = lights[i];
    let size = max(light.diffuse.w, 0.0);
    let directional = light.shadow.z == LIGHT_DIRECTIONAL;
    for (var k = 1u; k <= n; k = k + 1u) {
        let m = denoise_ratio[base + k];
        let to_c = m.xyz - s.p;
        var near = 0.0;
        var grow = 0.0;
        if (directional) {
            let axis = -light.direction.xyz;
            let t = max(dot(to_c, axis), 0.0);
            near = length(to_c - axis * t);
            grow = t * size;
        } else {
            let seg = light.position.xyz - s.p;
            let t = clamp(dot(to_c, seg) / max(dot(seg, seg), 1e-30), 0.0, 1.0);
            near = length(to_c - seg * t);
            grow = size;
        }
        if (near <= m.w + grow) {
            return true;
        }
    }
    return false;
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
