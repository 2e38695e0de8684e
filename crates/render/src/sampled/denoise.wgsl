// The ratio denoiser of sampled shadow rays (denoise.rs): one pass for every light.
//
// The lighting pass writes per pixel the exact unshadowed direct light U of the pixel's
// lights and the ratio r = shadowed / unshadowed of its sampled lights' estimate (Heitz et al.
// 2018). Only r is noisy; it is accumulated over frames at the same surface point (the
// G-buffer's position reprojected into the last frame) and filtered by an edge-stopping
// à-trous wavelet (Dammertz et al. 2010) on position, normal and its own temporal variance
// (SVGF, Schied et al. 2017). The lighting pass's `fs_composite` then shades U · r̄.

struct DenoiseParams {
    // Camera world → clip of the previous frame.
    prev_view_proj: mat4x4<f32>,
    // width, height, à-trous step (pixels), most frames of history.
    size: vec4<u32>,
    // world size of a pixel at distance 1, ratio tolerance in standard deviations; z: the
    // temporal pass: 1 = no history this frame, an à-trous pass: the frames of history from
    // which it leaves a pixel as it is (0 = never); w: the temporal pass: 1 = the lights
    // changed and nothing corrected the history for them (it cuts each pixel's frame count by
    // the change of its unshadowed light).
    pixel: vec4<f32>,
    // eye position (xyz); w (temporal pass): 1 = the lights changed and the lighting pass
    // left in `ratio_out` each pixel's correction of the history for them.
    camera: vec4<f32>,
}

@group(0) @binding(0) var<uniform> p: DenoiseParams;
@group(0) @binding(1) var gbuf_position: texture_2d<u32>;
@group(0) @binding(2) var gbuf_normal: texture_2d<u32>;

fn surface_at(px: vec2<u32>) -> vec4<f32> {
    let g = textureLoad(gbuf_position, vec2<i32>(px), 0);
    return vec4<f32>(bitcast<vec3<f32>>(g.xyz), select(0.0, 1.0, g.w != 0u));
}

// The G-buffer's normal, unit already (gbuffer.wgsl normalizes it).
fn normal_at(px: vec2<u32>) -> vec3<f32> {
    return bitcast<vec3<f32>>(textureLoad(gbuf_normal, vec2<i32>(px), 0).xyz);
}

// ---- temporal accumulation -------------------------------------------------------------

const LUMA: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

// The luminance ratio of an estimate with shadows to the same without (1 where no light).
fn ratio_of(s: vec3<f32>, u: vec3<f32>) -> f32 {
    let lu = dot(u, LUMA);
    return select(1.0, dot(s, LUMA) / lu, lu > 0.0);
}

// Per pixel, from the lighting pass: [exact unshadowed, 1 = geometry], [estimate with
// shadows], [the same without], [ambient + emission].
@group(0) @binding(3) var<storage, read> px_in: array<vec4<f32>>;
// Per pixel: [mean estimate with shadows, frames], [mean estimate without, mean ratio],
// [mean ratio², unit normal], [world position, 1 = valid].
@group(0) @binding(4) var<storage, read> hist_in: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> hist_out: array<vec4<f32>>;
// Per pixel: [estimate with shadows, variance of the ratio], [estimate without, frames].
// In a frame whose lights changed it first holds, from the lighting pass, per pixel what the
// changed lights add to the mean estimates with and without shadows: [with, 0], [without, 0].
@group(0) @binding(6) var<storage, read_write> ratio_out: array<vec4<f32>>;
// The instance seen per pixel and per instance its motion since the last frame
// (motion.rs: `last_frame_position`).
@group(0) @binding(9) var gbuf_instance: texture_2d<u32>;
@group(0) @binding(10) var<storage, read> motion_back: array<mat4x4<f32>>;

// Last frame's history where the point `was` lies, its surface facing `facing` (`footprint`:
// a pixel's world size at the point), bilinearly from the four pixels around where it was
// seen that saw it (within two pixel footprints, facing the same way: `same_facing`): the
// sums weighed and the weight (0: none saw it). Taking the nearest
// pixel instead rounds a slow camera's sub-pixel motion away frame after frame, and the
// history drifts by pixels against the image (docs/techniques.md, "Histories under motion").
struct History {
    h0: vec4<f32>,
    h1: vec4<f32>,
    h2: f32,
    weight: f32,
}

fn history_at(was: vec3<f32>, facing: vec3<f32>, footprint: f32) -> History {
    var out = History(vec4<f32>(0.0), vec4<f32>(0.0), 0.0, 0.0);
    let w = p.size.x;
    let h = p.size.y;
    let clip = p.prev_view_proj * vec4<f32>(was, 1.0);
    if (p.pixel.z != 0.0 || clip.w <= 0.0) {
        return out;
    }
    let ndc = clip.xy / clip.w;
    let q = vec2<f32>((ndc.x * 0.5 + 0.5) * f32(w), (0.5 - ndc.y * 0.5) * f32(h));
    let f = q - vec2<f32>(0.5);
    let b = floor(f);
    let t = f - b;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let o = vec2<f32>(f32(k & 1u), f32(k >> 1u));
        let at = b + o;
        if (at.x < 0.0 || at.y < 0.0 || at.x >= f32(w) || at.y >= f32(h)) {
            continue;
        }
        let j = u32(at.y) * w + u32(at.x);
        let hp = hist_in[4u * j + 3u];
        if (hp.w == 0.0 || distance(hp.xyz, was) > 2.0 * footprint + 1e-6) {
            continue;
        }
        let h2 = hist_in[4u * j + 2u];
        if (!same_facing(h2.yzw, facing)) {
            continue;
        }
        let wt = mix(1.0 - t.x, t.x, o.x) * mix(1.0 - t.y, t.y, o.y);
        out.h0 = out.h0 + wt * hist_in[4u * j];
        out.h1 = out.h1 + wt * hist_in[4u * j + 1u];
        out.h2 = out.h2 + wt * h2.x;
        out.weight = out.weight + wt;
    }
    if (out.weight <= 1e-3) {
        out.weight = 0.0;
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn temporal(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = p.size.x;
    let h = p.size.y;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let i = gid.y * w + gid.x;
    let s = surface_at(gid.xy);
    if (s.w == 0.0) {
        for (var k = 0u; k < 4u; k = k + 1u) {
            hist_out[4u * i + k] = vec4<f32>(0.0);
        }
        ratio_out[2u * i] = vec4<f32>(0.0);
        ratio_out[2u * i + 1u] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return;
    }
    let pos = s.xyz;
    var fix_s = vec3<f32>(0.0);
    var fix_u = vec4<f32>(0.0);
    if (p.camera.w != 0.0) {
        fix_s = ratio_out[2u * i].rgb;
        fix_u = ratio_out[2u * i + 1u];
    }
    var shadowed = px_in[4u * i + 1u].rgb;
    var unshadowed = px_in[4u * i + 2u].rgb;
    let r = ratio_of(shadowed, unshadowed);
    var mean = r;
    var m2 = r * r;
    // The frames of samples this frame's estimate stands for (more than 1 where the frame
    // of a light change drew more: lighting.wgsl `catch_up_samples`).
    let weight = max(px_in[4u * i + 1u].w, 1.0);
    var frames = weight;
    // The history of the same point where it was last frame (its instance's motion taken
    // back, motion.rs). A point that moved keeps at most MOVING_HISTORY frames
    // (denoise.rs): the light on a moving surface changes.
    let footprint = distance(pos, p.camera.xyz) * p.pixel.x;
    let back = instance_back(gid.xy);
    let was = last_frame_position(gid.xy, back, pos);
    let moved = any(was != pos);
    let n = normal_at(gid.xy);
    let g = history_at(was, last_frame_normal(back, n), footprint);
    if (g.weight > 0.0) {
        var h0 = g.h0 / g.weight;
        var h1 = g.h1 / g.weight;
        var h2 = g.h2 / g.weight;
        if (p.camera.w != 0.0) {
            // The lights changed: the means become those of the new lights by what the
            // lights that went took and those that came add, traced here once (their
            // visibility as the history's samples would have found it on average); the
            // mean ratio moves with them, its spread kept.
            // The samples of the lights that went are lost to the mean: the history
            // counts as many frames as its samples of the lights that stay (what their
            // share of the unshadowed light sampled them with).
            let before = ratio_of(h0.rgb, h1.rgb);
            let stays = clamp(1.0 - fix_u.w / max(dot(h1.rgb, LUMA), 1e-30), 0.0, 1.0);
            h0.w = max(floor(h0.w * stays), 1.0);
            h1 = vec4<f32>(max(h1.rgb + fix_u.rgb, vec3<f32>(0.0)), h1.w);
            h0 = vec4<f32>(clamp(h0.rgb + fix_s, vec3<f32>(0.0), h1.rgb), h0.w);
            let shift = ratio_of(h0.rgb, h1.rgb) - before;
            let shifted = clamp(h1.w + shift, 0.0, 1.0);
            h2 = max(h2 + shifted * shifted - h1.w * h1.w, shifted * shifted);
            h1.w = shifted;
        }
        if (p.pixel.w != 0.0) {
            // The lights changed more than the lighting pass corrects for: the history
            // counts as many frames as the share of its unshadowed light (the mean of
            // estimates whose luminance is the exact sum each frame) that this frame's
            // exact unshadowed light keeps, to the fourth power (measured: docs/techniques.md,
            // "The denoiser when lights change").
            let now = dot(px_in[4u * i].rgb, LUMA);
            let then = dot(h1.rgb, LUMA);
            let stays = clamp(1.0 - abs(now - then) / max(max(now, then), 1e-30), 0.0, 1.0);
            // A history cut below one frame is dropped (the frame's own estimate alone).
            let kept = stays * stays;
            h0.w = floor(h0.w * kept * kept);
        }
        // A light traced here passes a caster that moved (denoise_lighting.wgsl,
        // `moved_caster_between`): the shadow may have moved under a still point too.
        // Its history counts as many frames as the share of its light that stays, to the
        // power SHADOW_MOVED_POWER (as when lights change); cut below one frame it is dropped.
        let moved_share = px_in[4u * i + 2u].w;
        if (moved_share > 0.0 && !moved) {
            h0.w = floor(h0.w * pow(1.0 - moved_share, SHADOW_MOVED_POWER));
        }
        frames = min(round(h0.w) + weight, select(f32(p.size.w), MOVING_HISTORY, moved));
        let a = min(weight / frames, 1.0);
        shadowed = mix(h0.rgb, shadowed, a);
        unshadowed = mix(h1.rgb, unshadowed, a);
        mean = mix(h1.w, r, a);
        m2 = mix(h2, r * r, a);
    }
    hist_out[4u * i] = vec4<f32>(shadowed, frames);
    hist_out[4u * i + 1u] = vec4<f32>(unshadowed, mean);
    hist_out[4u * i + 2u] = vec4<f32>(m2, n);
    hist_out[4u * i + 3u] = vec4<f32>(pos, 1.0);
    ratio_out[2u * i] = vec4<f32>(shadowed, max(m2 - mean * mean, 0.0));
    ratio_out[2u * i + 1u] = vec4<f32>(unshadowed, frames);
}

// ---- à-trous filter --------------------------------------------------------------------

@group(0) @binding(7) var<storage, read> ratio_in: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> ratio_filtered: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn atrous(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = p.size.x;
    let h = p.size.y;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let i = gid.y * w + gid.x;
    let c0 = ratio_in[2u * i];
    let c1 = ratio_in[2u * i + 1u];
    // The wide passes leave a pixel with a settled history as it is (denoise.rs,
    // SETTLED_FRAMES): its own mean is better than their blur; nor do they read its
    // G-buffer. So is a pixel without geometry.
    let frames = max(c1.w, 1.0);
    if (p.pixel.z > 0.0 && frames >= p.pixel.z) {
        ratio_filtered[2u * i] = c0;
        ratio_filtered[2u * i + 1u] = c1;
        return;
    }
    let s = surface_at(gid.xy);
    if (s.w == 0.0) {
        ratio_filtered[2u * i] = c0;
        ratio_filtered[2u * i + 1u] = c1;
        return;
    }
    let pos = s.xyz;
    let n = normal_at(gid.xy);
    let step = i32(p.size.z);
    let footprint = distance(pos, p.camera.xyz) * p.pixel.x;
    let r = ratio_of(c0.rgb, c1.rgb);
    // How far a neighbour's ratio may differ: a few standard deviations of the two pixels'
    // mean ratios, with the variance at least a coin's of their mean ratio (a pixel whose
    // few rays all came out alike has an estimated variance of 0, and would never average
    // with its neighbours), and wide while the history is short: over frames^¾ (denoise.rs,
    // RATIO_SIGMAS). The ratio's weight falls as a Gaussian of the difference over 1.2 times
    // that (1/e there): differences well within it, mostly noise, average almost fully,
    // those past it, mostly shadows, hardly (denoise.rs, RATIO_SIGMAS).
    let narrow = sqrt(frames) * sqrt(sqrt(frames)) / 1.2;
    // One over the distance from the pixel's plane that weighs a tap 1/e.
    let reach = 1.0 / (footprint * f32(step) + 1e-6);
    var sum_s = vec3<f32>(0.0);
    var sum_u = vec3<f32>(0.0);
    var vsum = 0.0;
    var wsum = 0.0;
    // Five taps: the pixel and its four neighbours `step` pixels along the axes (the
    // diagonals left out: denoise.rs, ATROUS_STEPS).
    for (var k = 0; k < 5; k = k + 1) {
        let dx = select(0, 2 * (k & 1) - 1, k > 0 && k < 3);
        let dy = select(0, 2 * (k & 1) - 1, k >= 3);
        let q = vec2<i32>(gid.xy) + vec2<i32>(dx, dy) * step;
        if (q.x < 0 || q.y < 0 || q.x >= i32(w) || q.y >= i32(h)) {
            continue;
        }
        let qs = surface_at(vec2<u32>(q));
        if (qs.w == 0.0) {
            continue;
        }
        let j = u32(q.y) * w + u32(q.x);
        let q0 = ratio_in[2u * j];
        let q1 = ratio_in[2u * j + 1u];
        // cos³² by five squarings (pow is an exp and a log).
        var wn = max(dot(n, normal_at(vec2<u32>(q))), 0.0);
        wn = wn * wn;
        wn = wn * wn;
        wn = wn * wn;
        wn = wn * wn;
        wn = wn * wn;
        let rq = ratio_of(q0.rgb, q1.rgb);
        let rm = clamp(0.5 * (r + rq), 0.0, 1.0);
        let variance = max(0.5 * (c0.w + q0.w), rm * (1.0 - rm));
        let tol = max((p.pixel.y * sqrt(variance) + 0.5) / narrow, 1e-3);
        // The 3-tap B-spline (1/4, 1/2, 1/4) per axis, on the cross; the plane's and the
        // ratio's weights in one exp (a software rasterizer pays for each exp, and for an
        // array indexed per tap).
        let kernel = select(0.25, 0.5, dx == 0) * select(0.25, 0.5, dy == 0);
        let dr = (rq - r) / tol;
        let wpr = exp(-(abs(dot(n, qs.xyz - pos)) * reach + dr * dr));
        let wt = kernel * wn * wpr;
        sum_s = sum_s + wt * q0.rgb;
        sum_u = sum_u + wt * q1.rgb;
        vsum = vsum + wt * wt * q0.w;
        wsum = wsum + wt;
    }
    // The centre tap always counts (its weights are all 1 but the kernel's).
    ratio_filtered[2u * i] = vec4<f32>(sum_s / wsum, vsum / (wsum * wsum));
    ratio_filtered[2u * i + 1u] = vec4<f32>(sum_u / wsum, c1.w);
}
