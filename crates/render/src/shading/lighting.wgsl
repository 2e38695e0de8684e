// Deferred lighting: seed 004's Phong model (ambient + diffuse + specular per light, quadratic
// attenuation, spot cutoff) or the glTF BRDF (SHADING_PBR, with glTF's inverse-square falloff
// and range window for physical lights); a shadowed point keeps only the ambient term. Then
// emission, exposure and a tone map (look.rs). Shadows by comparison sampling of the atlas
// with PCF off / 2x2 / 3x3, never reading outside the view's tile.

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<LightData>;
@group(0) @binding(2) var<storage, read> shadow_views: array<ShadowViewData>;
@group(0) @binding(3) var<storage, read> materials: array<MaterialData>;
@group(0) @binding(4) var gbuf_position: texture_2d<u32>;
@group(0) @binding(5) var gbuf_normal: texture_2d<u32>;
@group(0) @binding(6) var atlas: texture_depth_2d;
// One bilinear comparison sampler for every PCF mode: OpenGL cannot pair one texture with two
// samplers. At a texel centre bilinear weights are (1, 0, 0, 0), so a lookup there compares
// exactly one texel, as a nearest-filtered one would.
@group(0) @binding(7) var cmp_linear: sampler_comparison;
// Visibility computed elsewhere: for `fs_mask` (irregular shadow maps) `counts.w` words per
// pixel, bit set = lit; for `fs_fraction` (a frame shaded with a given visibility) a byte per
// pixel and light, four to a word, 255 = all of the light. `fs_main` is bound to a dummy.
@group(0) @binding(8) var<storage, read> vis_mask: array<u32>;
// The clustered light lists (clusters.rs): per cluster a slot value, and the slot pool.
@group(0) @binding(9) var<uniform> clusters: ClusterUniforms;
@group(0) @binding(10) var<storage, read> cluster_slots: array<u32>;
@group(0) @binding(11) var<storage, read> cluster_masks: array<u32>;
// The shadow texture's raw depths for the soft shadows' blocker search: `atlas` again, read
// as floats (on OpenGL one texture cannot be paired with two samplers).
@group(0) @binding(12) var atlas_depth: texture_2d<f32>;
// The emissive texel of each pixel's material (gbuffer.rs; a white texel where the G-buffer
// keeps none, and then EMISSION_TEXTURE is false).
@group(0) @binding(13) var gbuf_emission: texture_2d<f32>;

fn shadow_depth_at(texel: vec2<i32>) -> f32 {
    return textureLoad(atlas_depth, texel, 0).r;
}

fn shadow_compare_at(t: vec2<f32>, depth: f32) -> f32 {
    return textureSampleCompareLevel(atlas, cmp_linear, t / f32(frame.counts.z), depth);
}


@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle that covers the screen.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn compare_texel(texel: vec2<f32>, depth: f32) -> f32 {
    let size = f32(frame.counts.z);
    return textureSampleCompareLevel(atlas, cmp_linear, (texel + vec2<f32>(0.5)) / size, depth);
}

// Fraction of the light that reaches the point (1 = fully lit).
fn shadow_factor(c: ShadowCoord) -> f32 {
    if (!c.valid) {
        return 1.0;
    }
    let mode = frame.counts.y;
    if (mode == PCF_2X2) {
        // Bilinear comparison of the 2x2 nearest texels; clamping the centre half a texel inside
        // the tile keeps all four inside it.
        let size = f32(frame.counts.z);
        let t = clamp(c.texel, c.tile_min + vec2<f32>(0.5), c.tile_max - vec2<f32>(0.5));
        return textureSampleCompareLevel(atlas, cmp_linear, t / size, c.depth);
    }
    let base = floor(c.texel);
    if (mode == PCF_3X3) {
        var sum = 0.0;
        for (var y = -1; y <= 1; y = y + 1) {
            for (var x = -1; x <= 1; x = x + 1) {
                let t = clamp(base + vec2<f32>(f32(x), f32(y)), c.tile_min, c.tile_max - vec2<f32>(1.0));
                sum = sum + compare_texel(t, c.depth);
            }
        }
        return sum / 9.0;
    }
    return compare_texel(vec2<f32>(hard_texel(c)), c.depth);
}

// Shadows from the atlas (every shadow-map technique).
@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(frag.xy), MASK_NONE);
}

// Shadows from the visibility mask (irregular shadow maps).
@fragment
fn fs_mask(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(frag.xy), MASK_BITS);
}

// Shadows from a given fraction per pixel and light (`Renderer::shade_with`).
@fragment
fn fs_fraction(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(frag.xy), MASK_FRACTIONS);
}

// Where `light_lit` finds shadows: the shadow source, the mask's bits, or given fractions.
const MASK_NONE: u32 = 0u;
const MASK_BITS: u32 = 1u;
const MASK_FRACTIONS: u32 = 2u;

// The surface point a pixel shades, and what every light's term needs of it.
struct Surface {
    p: vec3<f32>,
    n: vec3<f32>,
    v: vec3<f32>,
    view_depth: f32,
    mat: MaterialData,
    px: vec2<i32>,
    mask: u32,
}

// Light `i`'s terms at `s` before its shadow: whether it reaches the point, whether the point
// faces it, the ambient term (added whatever the shadow), the attenuation and the
// unattenuated diffuse + specular terms (scaled by how lit the point is).
struct Terms {
    reaches: bool,
    facing: bool,
    ambient: vec3<f32>,
    att: f32,
    ds: vec3<f32>,
}

const PI: f32 = 3.14159265358979;

// The glTF specification's BRDF (appendix B, "Complete model") for base colour `base`,
// `metallic` and perceptual `roughness`, times nothing: the caller multiplies by the light's
// irradiance. Roughness is kept at least 0.045 (Filament's and three.js' floor), so a point
// light's highlight on a mirror stays finite.
fn gltf_brdf(base: vec3<f32>, metallic: f32, roughness: f32, n: vec3<f32>, l: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let h = normalize(l + v);
    let ndl = max(dot(n, l), 0.0);
    let ndv = max(abs(dot(n, v)), 1e-4);
    let ndh = max(dot(n, h), 0.0);
    let vdh = max(dot(v, h), 0.0);
    let r = clamp(roughness, 0.045, 1.0);
    let a2 = r * r * r * r;
    let dd = ndh * ndh * (a2 - 1.0) + 1.0;
    let d = a2 / (PI * dd * dd);
    let gv = ndl * sqrt(ndv * ndv * (1.0 - a2) + a2);
    let gl = ndv * sqrt(ndl * ndl * (1.0 - a2) + a2);
    let vis = 0.5 / max(gv + gl, 1e-7);
    let spec = d * vis;
    let fw = pow(1.0 - vdh, 5.0);
    let metal = spec * (base + (vec3<f32>(1.0) - base) * fw);
    let f = 0.04 + 0.96 * fw;
    let dielectric = mix(base / PI, vec3<f32>(spec), f);
    return mix(dielectric, metal, metallic);
}

fn light_terms(i: u32, s: Surface) -> Terms {
    return light_terms_of(lights[i], s);
}

fn light_terms_of(light: LightData, s: Surface) -> Terms {
    var t: Terms;
    t.reaches = in_reach(light, s.p);
    if (!t.reaches) {
        return t;
    }
    let kind = light.shadow.z;
    t.att = 1.0;
    if (kind != LIGHT_DIRECTIONAL) {
        let d = distance(light.position.xyz, s.p);
        if (PHYSICAL_FALLOFF) {
            // glTF: inverse square (kept finite within 10 cm) times the range window.
            let x = d / light.ambient.w;
            let w = clamp(1.0 - x * x * x * x, 0.0, 1.0);
            t.att = w * w / max(d * d, 0.01);
        } else {
            let a = light.attenuation;
            t.att = 1.0 / max(a.x + a.y * d + a.z * d * d, 1e-6);
        }
    }
    let l = to_light(light, s.p);
    if (SHADING_MODEL == SHADING_PBR) {
        let base = s.mat.diffuse.rgb;
        let c_diff = base * (1.0 - s.mat.pbr.x);
        t.ambient = light.ambient.rgb * c_diff * (t.att * LIGHT_SCALE / PI);
        let ndl = dot(s.n, l);
        t.facing = ndl > 0.0;
        if (!t.facing) {
            return t;
        }
        t.ds = light.diffuse.rgb * gltf_brdf(base, s.mat.pbr.x, s.mat.pbr.y, s.n, l, s.v) * (ndl * LIGHT_SCALE);
        return t;
    }
    t.ambient = light.ambient.rgb * s.mat.ambient.rgb * t.att;
    let ndl = dot(s.n, l);
    t.facing = ndl > 0.0;
    if (!t.facing) {
        return t;
    }
    let diffuse = light.diffuse.rgb * s.mat.diffuse.rgb * ndl;
    let r = reflect(-l, s.n);
    let spec = light.specular.rgb * s.mat.specular.rgb * pow(max(dot(r, s.v), 0.0), max(s.mat.ambient.w, 1.0));
    t.ds = diffuse + spec;
    if (LIGHT_SCALE != 1.0) {
        // Physical lights shaded with Phong (look.rs).
        t.ambient = t.ambient * LIGHT_SCALE;
        t.ds = t.ds * LIGHT_SCALE;
    }
    return t;
}

// Khronos PBR Neutral (https://github.com/KhronosGroup/ToneMapping, 2024): identity up to
// 0.76 after a small black offset, then highlights compressed towards 1 and desaturated.
fn tone_neutral(c_in: vec3<f32>) -> vec3<f32> {
    let start = 0.8 - 0.04;
    let desaturation = 0.15;
    var c = c_in;
    let x = min(c.r, min(c.g, c.b));
    let offset = select(0.04, x - 6.25 * x * x, x < 0.08);
    c = c - offset;
    let peak = max(c.r, max(c.g, c.b));
    if (peak < start) {
        return c;
    }
    let d = 1.0 - start;
    let new_peak = 1.0 - d * d / (peak + d - start);
    c = c * (new_peak / peak);
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return mix(c, vec3<f32>(new_peak), g);
}

// Linear colour to a displayable one: exposure, then the tone map. A fixed exposure is a
// constant (the compiler folds it into exp's own scale, as it always did for the Phong
// scenes' 1.4); a metered one the frame's.
fn tone_map(c: vec3<f32>) -> vec3<f32> {
    if (EXPOSURE_IS_FIXED) {
        return tone_map_at(c, FIXED_EXPOSURE);
    }
    return tone_map_at(c, frame.look.x);
}

fn tone_map_at(c: vec3<f32>, k: f32) -> vec3<f32> {
    if (TONE_MAP == TONE_NEUTRAL) {
        return clamp(tone_neutral(c * k), vec3<f32>(0.0), vec3<f32>(1.0));
    }
    if (TONE_MAP == TONE_CLAMP) {
        return clamp(c * k, vec3<f32>(0.0), vec3<f32>(1.0));
    }
    // Exponential: many overlapping lights add up past 1 without clipping to white.
    return vec3<f32>(1.0) - exp(-c * k);
}

// How much of light `i` reaches `s` past the casters, 0..1: from the visibility mask, a shadow
// ray, or the shadow test of the atlas or page pool.
fn light_lit(i: u32, s: Surface) -> f32 {
    if (s.mask == MASK_FRACTIONS) {
        let k = (u32(s.px.y) * u32(frame.viewport.x) + u32(s.px.x)) * frame.counts.x + i;
        return f32((vis_mask[k / 4u] >> (8u * (k % 4u))) & 255u) / 255.0;
    }
    if (s.mask == MASK_BITS) {
        let word = vis_mask[(u32(s.px.y) * u32(frame.viewport.x) + u32(s.px.x)) * frame.counts.w + i / 32u];
        return f32((word >> (i % 32u)) & 1u);
    }
    let light = lights[i];
    if (SHADOW_RAYS) {
        if (light.diffuse.w > 0.0) {
            // With sampled lights (`ray_samples() > 0`) a pixel's sample is a light and one
            // point on it; with every light, a stratified grid over each sized light's shape.
            let side = select(ray_area_side(), 1u, ray_samples() > 0u);
            return ray_lit_area(light, s.p, s.n, side, soft_jitter(s.px, i));
        }
        return ray_lit(light, s.p, s.n);
    }
    let c = shadow_coord(light, s.p, s.n, s.view_depth);
    if (light.diffuse.w > 0.0 && c.valid) {
        return soft_shadow(light.diffuse.w, c, soft_rotation(s.px));
    }
    return shadow_factor(c);
}

// `color` plus light `i`'s contribution at `s` (nothing beyond the light's reach). Both light
// loops below call exactly this, in ascending light order, so they add the same numbers in the
// same order.
fn add_light(color: vec3<f32>, i: u32, s: Surface) -> vec3<f32> {
    let t = light_terms(i, s);
    if (!t.reaches) {
        return color;
    }
    if (!t.facing) {
        return color + t.ambient;
    }
    return color + t.ambient + light_lit(i, s) * t.att * t.ds;
}

// Most lights a pixel samples (RayOptions::light_samples).
const MAX_SAMPLES: u32 = 16u;

// What a pixel's light loop accumulates: the colour, and with sampled lights (`ray_samples()
// > 0`) one weighted reservoir per sample over the lights' unshadowed direct terms, and the
// first `K` candidates themselves (a pixel with no more candidates than samples traces them
// all: exact, and no dearer).
struct Acc {
    color: vec3<f32>,
    wsum: f32,
    chosen: array<u32, MAX_SAMPLES>,
    weight: array<f32, MAX_SAMPLES>,
    count: u32,
    first: array<u32, MAX_SAMPLES>,
    rng: u32,
    // With DENOISE: the unshadowed direct light of every light visited, and the sampled
    // estimates of the direct light with and without shadows (denoise.rs).
    unshadowed: vec3<f32>,
    est_shadowed: vec3<f32>,
    est_unshadowed: vec3<f32>,
    // Whether the samples went through temporal reuse (resolve_reused).
    reused: bool,
    // Where frames are denoised: the pixel's first point of its low-discrepancy sequence
    // (`sample_point`), and every CHECKPOINT_EVERY-th weighed light with the running sum
    // before it, from which `pick_stratified` finds the light a point of the sum falls on.
    u0: f32,
    marks: u32,
    mark_light: array<u32, CHECKPOINTS>,
    mark_sum: array<f32, CHECKPOINTS>,
}

// Checkpoints of the running sum (a pixel's 64 · 16 = 1,024 first weighed lights; past them
// the last stretch is longer, never wrong).
const CHECKPOINTS: u32 = 32u;
const CHECKPOINT_EVERY: u32 = 4u;

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform in [0, 1).
fn random(acc: ptr<function, Acc>) -> f32 {
    (*acc).rng = pcg((*acc).rng);
    return f32((*acc).rng >> 8u) / 16777216.0;
}

// One light of the pixel's loop: all of it (every light traced or looked up), or its ambient
// term plus a candidate for each sample's reservoir, with probability proportional to the
// luminance of its unshadowed direct term (resampled importance sampling over the lights).
fn visit(i: u32, s: Surface, acc: ptr<function, Acc>) {
    let k = ray_samples();
    if (k == 0u && !DENOISE) {
        (*acc).color = add_light((*acc).color, i, s);
        return;
    }
    let t = light_terms(i, s);
    if (!t.reaches) {
        return;
    }
    (*acc).color = (*acc).color + t.ambient;
    if (!t.facing) {
        return;
    }
    if (DENOISE) {
        (*acc).unshadowed = (*acc).unshadowed + t.att * t.ds;
    }
    if (k == 0u) {
        // Every light traced, its area samples new each frame: the direct light is kept
        // apart from the ambient (resolve_samples adds it) and both "estimates" are exact
        // but for those samples, which the denoiser accumulates over frames.
        (*acc).est_unshadowed = (*acc).est_unshadowed + t.att * t.ds;
        (*acc).est_shadowed = (*acc).est_shadowed + light_lit(i, s) * t.att * t.ds;
        return;
    }
    let w = dot(t.att * t.ds, vec3<f32>(0.2126, 0.7152, 0.0722));
    if (w <= 0.0) {
        return;
    }
    (*acc).wsum = (*acc).wsum + w;
    if ((*acc).count < k) {
        (*acc).first[(*acc).count] = i;
    }
    (*acc).count = (*acc).count + 1u;
    if (DENOISE) {
        // Drawn after the loop, once the sum is known (pick_stratified).
        let n = (*acc).count - 1u;
        if (n % CHECKPOINT_EVERY == 0u && (*acc).marks < CHECKPOINTS) {
            (*acc).mark_light[(*acc).marks] = i;
            (*acc).mark_sum[(*acc).marks] = (*acc).wsum - w;
            (*acc).marks = (*acc).marks + 1u;
        }
        return;
    }
    // A single frame: weighted reservoir sampling in one pass (no total needed).
    for (var j = 0u; j < k; j = j + 1u) {
        if (random(acc) * (*acc).wsum < w) {
            (*acc).chosen[j] = i;
            (*acc).weight[j] = w;
        }
    }
}

// One light of `pick_stratified`'s walk: a light that weighs anything becomes the pick and
// adds its weight to the running sum; true once the sum has passed `point`.
fn weigh_past(i: u32, s: Surface, point: f32, sum: ptr<function, f32>, picked: ptr<function, u32>, weight: ptr<function, f32>) -> bool {
    let w = light_weight(i, s);
    if (w <= 0.0) {
        return false;
    }
    *picked = i;
    *weight = w;
    *sum = *sum + w;
    return *sum > point;
}

// Sample `j`'s point in [0, 1) this frame: the golden-ratio sequence (Weyl, R1) from the
// pixel's own start, so a pixel's points over frames (and its K points in one frame) are
// spread evenly over the weights instead of independently, and neighbours start apart
// (interleaved gradient noise) for the denoiser's filter. Each point alone is uniform.
fn sample_point(acc: ptr<function, Acc>, j: u32) -> f32 {
    let n = frame.modes.y * ray_samples() + j;
    return fract((*acc).u0 + f32(n) * 0.6180339887);
}

// The luminance of light `i`'s unshadowed direct term at `s` (0 beyond reach or facing away):
// the weight `visit` samples it by.
fn light_weight(i: u32, s: Surface) -> f32 {
    let t = light_terms(i, s);
    if (!t.reaches || !t.facing) {
        return 0.0;
    }
    return max(dot(t.att * t.ds, vec3<f32>(0.2126, 0.7152, 0.0722)), 0.0);
}

// Where frames are denoised, each sample is drawn once the loop's sum is known: the light
// whose stretch of the running sum holds the sample's point of it (inverting the weights'
// distribution), found from the last checkpoint before that point by weighing again at most
// CHECKPOINT_EVERY lights in the loop's order (a point the sum never reaches, as rounding
// might leave one, keeps the last light weighed). Over frames the points follow the
// golden-ratio sequence, so a pixel's samples cover its lights evenly (stratified).
fn pick_stratified(s: Surface, slot: u32, acc: ptr<function, Acc>) {
    for (var j = 0u; j < ray_samples(); j = j + 1u) {
        let point = sample_point(acc, j) * (*acc).wsum;
        var m = 0u;
        for (var c = 1u; c < (*acc).marks; c = c + 1u) {
            if ((*acc).mark_sum[c] <= point) {
                m = c;
            }
        }
        let first_light = (*acc).mark_light[m];
        var sum = (*acc).mark_sum[m];
        var picked = first_light;
        var weight = 0.0;
        if (slot < CLUSTER_FIRST_SLOT || slot == CLUSTER_OVERFLOW) {
            for (var i = first_light; i < frame.counts.x; i = i + 1u) {
                if (weigh_past(i, s, point, &sum, &picked, &weight)) {
                    break;
                }
            }
        } else {
            let base = (slot - CLUSTER_FIRST_SLOT) * clusters.words.z;
            var done = false;
            for (var wi = first_light / 32u; wi < clusters.words.y && !done; wi = wi + 1u) {
                var bits = cluster_masks[base + clusters.words.x + wi];
                if (wi == first_light / 32u) {
                    bits = bits & ~((1u << (first_light % 32u)) - 1u);
                }
                while (bits != 0u) {
                    let i = wi * 32u + firstTrailingBit(bits);
                    bits = bits & (bits - 1u);
                    if (weigh_past(i, s, point, &sum, &picked, &weight)) {
                        done = true;
                        break;
                    }
                }
            }
        }
        (*acc).chosen[j] = picked;
        (*acc).weight[j] = weight;
    }
}

// The sampled lights' shadowed direct terms, each weighted by the reservoir's total over its
// own weight: an unbiased estimate of the sum over every light of the loop.
fn resolve_samples(s: Surface, acc: ptr<function, Acc>) {
    let k = ray_samples();
    if (k == 0u && DENOISE) {
        (*acc).color = (*acc).color + (*acc).est_shadowed;
        return;
    }
    if (k == 0u || (*acc).wsum <= 0.0) {
        if (REUSE) {
            reuse_store_point(s.px, s.p, false);
        }
        return;
    }
    var direct = vec3<f32>(0.0);
    if ((*acc).count <= k) {
        if (REUSE) {
            // Exact: nothing to reuse, and the next frame starts anew here.
            reuse_store_point(s.px, s.p, false);
        }
        for (var j = 0u; j < (*acc).count; j = j + 1u) {
            let i = (*acc).first[j];
            let t = light_terms(i, s);
            direct = direct + light_lit(i, s) * t.att * t.ds;
        }
        (*acc).color = (*acc).color + direct;
        if (DENOISE) {
            // Every light traced: both "estimates" are exact.
            (*acc).est_shadowed = direct;
            (*acc).est_unshadowed = (*acc).unshadowed;
        }
        return;
    }
    if (REUSE) {
        resolve_reused(s, acc);
        return;
    }
    var unlit = vec3<f32>(0.0);
    for (var j = 0u; j < k; j = j + 1u) {
        let i = (*acc).chosen[j];
        let t = light_terms(i, s);
        let term = t.att * t.ds * ((*acc).wsum / (*acc).weight[j]);
        direct = direct + light_lit(i, s) * term;
        if (DENOISE) {
            unlit = unlit + term;
        }
    }
    (*acc).color = (*acc).color + direct / f32(k);
    if (DENOISE) {
        (*acc).est_shadowed = direct / f32(k);
        (*acc).est_unshadowed = unlit / f32(k);
    }
}

// Whether the point `jitter` (0..1², on the light's shape) of light `i` reaches `s` (its
// centre for a light without size): one ray.
fn light_lit_point(i: u32, s: Surface, jitter: vec2<f32>) -> f32 {
    let light = lights[i];
    if (light.diffuse.w > 0.0) {
        return ray_lit_area(light, s.p, s.n, 1u, jitter);
    }
    return ray_lit(light, s.p, s.n);
}

// Temporal reuse (reuse.rs): each sample's new light (drawn in proportion to `f`, the
// luminance of its unshadowed term, with `W = wsum / f`, and a new point on a sized light's
// shape) and last frame's reservoir of the
// same surface point are weighed by the target `f · V` here and now (both rays traced) with
// confidence weights; the light kept, its `W` and the frames it stands for go to the next
// frame, and the pixel's estimate is `f(y) V(y) W` (the sum of the two weights, in the kept
// light's colour).
fn resolve_reused(s: Surface, acc: ptr<function, Acc>) {
    let k = ray_samples();
    let luma = vec3<f32>(0.2126, 0.7152, 0.0722);
    (*acc).reused = true;
    let r = reuse_history(s.p);
    reuse_store_point(s.px, s.p, true);
    var direct = vec3<f32>(0.0);
    for (var j = 0u; j < k; j = j + 1u) {
        let yn = (*acc).chosen[j];
        let tn = light_terms(yn, s);
        let f_new = tn.att * tn.ds;
        let jn = soft_jitter(s.px, yn);
        let vn = light_lit_point(yn, s, jn);
        var m_old = 0.0;
        var y_old = yn;
        var j_old = jn;
        var f_old = vec3<f32>(0.0);
        var v_old = 0.0;
        var w_old = 0.0;
        if (r != 0xffffffffu) {
            let h = reuse_load(r, j);
            y_old = h.x;
            j_old = unpack2x16unorm(h.w);
            m_old = min(bitcast<f32>(h.z), reuse_cap());
            let w_kept = bitcast<f32>(h.y);
            if (y_old < frame.counts.x && w_kept > 0.0) {
                let to = light_terms(y_old, s);
                if (to.reaches && to.facing) {
                    f_old = to.att * to.ds;
                    let p_old = dot(f_old, luma);
                    if (p_old > 0.0) {
                        v_old = light_lit_point(y_old, s, j_old);
                        w_old = p_old * v_old * w_kept;
                    }
                }
            }
        }
        // The two weights m · p̂(y) · W: the new draw's W is wsum / f(y_n).
        let a = (*acc).wsum * vn / (1.0 + m_old);
        let b = w_old * m_old / (1.0 + m_old);
        let total = a + b;
        var y = yn;
        var jy = jn;
        var f_rgb = f_new;
        var p_hat = dot(f_new, luma) * vn;
        if (b > 0.0 && random(acc) * total < b) {
            y = y_old;
            jy = j_old;
            f_rgb = f_old;
            p_hat = dot(f_old, luma) * v_old;
        }
        var w = 0.0;
        if (p_hat > 0.0) {
            w = total / p_hat;
            // f(y) V(y) W in the kept light's colour: f(y) · total / lum(f(y)).
            direct = direct + f_rgb * (total / dot(f_rgb, luma));
        }
        reuse_store(s.px, j, y, w, min(m_old + 1.0, reuse_cap()), jy);
    }
    (*acc).color = (*acc).color + direct / f32(k);
    if (DENOISE) {
        (*acc).est_shadowed = direct / f32(k);
        (*acc).est_unshadowed = (*acc).unshadowed;
    }
}

// Spatial reuse (reuse.rs), after the lighting pass: each pixel's samples after temporal
// reuse resample those of up to SPATIAL_NEIGHBOURS pixels drawn from a disc of
// SPATIAL_RADIUS pixels around it (those of similar view depth and normal, their samples
// new this frame); the light drawn is shaded here (the next frame's temporal reuse starts from
// the pixel's own reservoir: reuse.rs says why).
@fragment
fn fs_spatial(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    let rest = spatial_rest(px);
    let color = bitcast<vec3<f32>>(rest.xyz);
    if (rest.w == SPATIAL_SKY) {
        return vec4<f32>(color, 1.0);
    }
    if (rest.w == SPATIAL_WHOLE) {
        return vec4<f32>(tone_map(color), 1.0);
    }
    let s = surface_at(px, textureLoad(gbuf_position, px, 0), MASK_NONE);
    let direct = spatial_resolve(s);
    if (DENOISE) {
        denoise_set_shadowed(px, direct);
    }
    return vec4<f32>(tone_map(color + direct), 1.0);
}

// A pixel's target at light `y` (point `jit` on its shape): the luminance of the light's
// unshadowed term, times its visibility where `trace` (one ray; else taken as seen), and
// the term itself.
struct SpatialTarget {
    p: f32,
    f: vec3<f32>,
}

fn spatial_target(s: Surface, y: u32, jit: vec2<f32>, trace: bool) -> SpatialTarget {
    var out: SpatialTarget;
    out.p = 0.0;
    out.f = vec3<f32>(0.0);
    if (y >= frame.counts.x) {
        return out;
    }
    let t = light_terms(y, s);
    if (!t.reaches || !t.facing) {
        return out;
    }
    out.f = t.att * t.ds;
    out.p = dot(out.f, vec3<f32>(0.2126, 0.7152, 0.0722));
    if (out.p > 0.0 && trace) {
        out.p = out.p * light_lit_point(y, s, jit);
    }
    return out;
}

// Uniform in [0, 1) from a generator's state, which it advances.
fn spatial_random(rng: ptr<function, u32>) -> f32 {
    *rng = pcg(*rng);
    return f32(*rng >> 8u) / 16777216.0;
}

// The pixel's direct light from its and its neighbours' samples (see fs_spatial). Each
// candidate `i` (pixel `i`'s light y_i with weight W_i standing for M_i frames) is drawn with
// weight m_i · p̂(y_i) · W_i, p̂ this pixel's target f · V (a ray per neighbour's light; the
// pixel's own light was seen: W > 0 only where its ray reached it), m_i its MIS weight:
// biased, c_i / Σ c; unbiased, the generalized balance heuristic c_i p̂_i(y_i) / Σ_o c_o
// p̂_o(y_i) over every pixel o resampled (rays from each), with confidences c: this pixel's
// M, 1 for a neighbour (spatial_confidence). The light drawn is shaded with W = Σ w / p̂(y).
fn spatial_confidence(c: vec4<u32>, i: u32) -> f32 {
    if (i == 0u) {
        return bitcast<f32>(c.z);
    }
    return min(bitcast<f32>(c.z), 1.0);
}

fn spatial_resolve(s: Surface) -> vec3<f32> {
    let k = ray_samples();
    let luma = vec3<f32>(0.2126, 0.7152, 0.0722);
    let noise_px = eye_local(frame.eyes, s.px);
    var rng = pcg(u32(noise_px.x) + pcg(u32(noise_px.y) + pcg(ray_seed() + frame.modes.y + 0x5bd1e995u)));
    // The pixels resampled: this one first, then the neighbours that pass.
    var pxs: array<vec2<i32>, SPATIAL_SLOTS>;
    var surfs: array<Surface, SPATIAL_SLOTS>;
    pxs[0] = s.px;
    surfs[0] = s;
    var n = 1u;
    let size = vec2<i32>(frame.viewport.xy);
    for (var t = 0u; t < SPATIAL_NEIGHBOURS; t = t + 1u) {
        let r = SPATIAL_RADIUS * sqrt(spatial_random(&rng));
        let a = 6.2831853 * spatial_random(&rng);
        let q = s.px + vec2<i32>(round(r * vec2<f32>(cos(a), sin(a))));
        if (any(q < vec2<i32>(0)) || any(q >= size) || all(q == s.px)) {
            continue;
        }
        if (spatial_rest(q).w != SPATIAL_SAMPLED) {
            continue;
        }
        let sq = surface_at(q, textureLoad(gbuf_position, q, 0), MASK_NONE);
        if (abs(sq.view_depth - s.view_depth) > 0.1 * s.view_depth || dot(sq.n, s.n) < 0.9) {
            continue;
        }
        pxs[n] = q;
        surfs[n] = sq;
        n = n + 1u;
    }
    var direct = vec3<f32>(0.0);
    for (var j = 0u; j < k; j = j + 1u) {
        // Confidence: this pixel's reservoir the frames it stands for, a neighbour's one.
        var m_total = 0.0;
        for (var i = 0u; i < n; i = i + 1u) {
            m_total = m_total + spatial_confidence(spatial_load(pxs[i], j), i);
        }
        var kept_f = vec3<f32>(0.0);
        var kept_p = 0.0;
        var total = 0.0;
        for (var i = 0u; i < n; i = i + 1u) {
            let c = spatial_load(pxs[i], j);
            let w_i = bitcast<f32>(c.y);
            let m_i = spatial_confidence(c, i);
            if (w_i <= 0.0 || m_i <= 0.0) {
                continue;
            }
            let jit = unpack2x16unorm(c.w);
            let here = spatial_target(s, c.x, jit, i != 0u);
            if (here.p <= 0.0) {
                continue;
            }
            var mis = m_i / m_total;
            if (SPATIAL == 2u) {
                var num = 0.0;
                var den = 0.0;
                for (var o = 0u; o < n; o = o + 1u) {
                    let m_o = spatial_confidence(spatial_load(pxs[o], j), o);
                    var p_o = here.p;
                    if (o != 0u) {
                        // Pixel i's own light was seen from it (W > 0).
                        p_o = spatial_target(surfs[o], c.x, jit, o != i).p;
                    }
                    den = den + m_o * p_o;
                    if (o == i) {
                        num = m_o * p_o;
                    }
                }
                mis = select(0.0, num / den, den > 0.0);
            }
            let w = mis * here.p * w_i;
            if (w <= 0.0) {
                continue;
            }
            total = total + w;
            if (spatial_random(&rng) * total < w) {
                kept_f = here.f;
                kept_p = here.p;
            }
        }
        if (total > 0.0 && kept_p > 0.0) {
            direct = direct + kept_f * (total / dot(kept_f, luma));
        }
    }
    return direct / f32(k);
}

// The surface point pixel `px` of the G-buffer holds (`gpos`: its position texel, which has
// geometry), its shadows found as `mask` says.
fn surface_at(px: vec2<i32>, gpos: vec4<u32>, mask: u32) -> Surface {
    let pos = bitcast<vec4<f32>>(gpos);
    let nm = textureLoad(gbuf_normal, px, 0);
    var s: Surface;
    s.p = pos.xyz;
    s.n = normalize(bitcast<vec3<f32>>(nm.xyz));
    s.mat = materials[nm.w & 0xffffu];
    if (bitcast<u32>(s.mat.pbr.z) != 0u) {
        // The metallic-roughness texel the G-buffer kept (gbuffer.wgsl) times the factors.
        s.mat.pbr.x = s.mat.pbr.x * (f32(nm.w >> 24u) / 255.0);
        s.mat.pbr.y = s.mat.pbr.y * (f32((nm.w >> 16u) & 255u) / 255.0);
    }
    // The texture's colour multiplies the material's ambient and diffuse reflectance (exactly
    // 1 for untextured surfaces, so their numbers do not change).
    let albedo = gbuffer_albedo(gpos);
    s.mat.ambient = vec4<f32>(s.mat.ambient.rgb * albedo, s.mat.ambient.w);
    s.mat.diffuse = vec4<f32>(s.mat.diffuse.rgb * albedo, s.mat.diffuse.w);
    s.v = normalize(frame.eye_pos[eye_of(frame.eyes, u32(px.x))].xyz - s.p);
    s.view_depth = -(frame.view * vec4<f32>(s.p, 1.0)).z;
    s.px = px;
    s.mask = mask;
    return s;
}

fn shade(px: vec2<i32>, mask: u32) -> vec4<f32> {
    let gpos = textureLoad(gbuf_position, px, 0);
    let pos = bitcast<vec4<f32>>(gpos);
    if (!has_geometry(gpos)) {
        if (REUSE) {
            reuse_store_point(px, vec3<f32>(0.0), false);
        }
        if (DENOISE) {
            denoise_store(px, vec4<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
        }
        if (SPATIAL != 0u) {
            spatial_store_rest(px, frame.sky.rgb, SPATIAL_SKY);
        }
        return vec4<f32>(frame.sky.rgb, 1.0);
    }
    let s = surface_at(px, gpos, mask);
    var acc: Acc;
    acc.color = vec3<f32>(0.0);
    acc.wsum = 0.0;
    acc.count = 0u;
    // `modes.y` is the frame's number when rays are denoised (new random numbers each frame),
    // else 0.
    let noise_px = eye_local(frame.eyes, px);
    acc.rng = pcg(u32(noise_px.x) + pcg(u32(noise_px.y) + pcg(ray_seed() + frame.modes.y)));
    acc.unshadowed = vec3<f32>(0.0);
    acc.est_shadowed = vec3<f32>(0.0);
    acc.est_unshadowed = vec3<f32>(0.0);
    acc.reused = false;
    var slot = CLUSTER_OVERFLOW;
    if (clusters.words.w != 0u) {
        slot = cluster_slots[cluster_index(clusters, vec2<u32>(px), s.view_depth)];
    }
    acc.u0 = 0.0;
    acc.marks = 0u;
    if (ray_samples() > 0u && DENOISE) {
        let p = vec2<f32>(noise_px);
        let ign = fract(52.982919 * fract(0.06711056 * p.x + 0.00583715 * p.y));
        acc.u0 = fract(ign + f32(pcg(ray_seed()) >> 8u) / 16777216.0);
    }
    if (slot < CLUSTER_FIRST_SLOT || slot == CLUSTER_OVERFLOW) {
        // Every light: the reference loop, and the fallback of clusters without a slot.
        let count = frame.counts.x;
        for (var i = 0u; i < count; i = i + 1u) {
            visit(i, s, &acc);
        }
    } else {
        // The cluster's lights in ascending order: summary bits pick the non-empty words.
        let base = (slot - CLUSTER_FIRST_SLOT) * clusters.words.z;
        for (var sw = 0u; sw < clusters.words.x; sw = sw + 1u) {
            var words = cluster_masks[base + sw];
            while (words != 0u) {
                let w = sw * 32u + firstTrailingBit(words);
                words = words & (words - 1u);
                var bits = cluster_masks[base + clusters.words.x + w];
                while (bits != 0u) {
                    let i = w * 32u + firstTrailingBit(bits);
                    bits = bits & (bits - 1u);
                    visit(i, s, &acc);
                }
            }
        }
    }
    // What the denoiser's composite and spatial reuse add to the direct light they estimate:
    // ambient, the probes' reflections and emission.
    var rest = acc.color;
    if (DENOISE && ray_samples() > 0u && acc.count > ray_samples()) {
        pick_stratified(s, slot, &acc);
    }
    resolve_samples(s, &acc);
    if (PROBES) {
        let mirrored = probe_reflection(s);
        acc.color = acc.color + mirrored;
        rest = rest + mirrored;
    }
    if (EMISSION) {
        // Emitted radiance (times the emissive texel), through the exposure like reflected
        // light.
        var emitted = s.mat.emissive.rgb;
        if (EMISSION_TEXTURE && (bitcast<u32>(s.mat.emissive.w) & 0xffffffu) != 0u) {
            emitted = emitted * textureLoad(gbuf_emission, px, 0).rgb;
        }
        acc.color = acc.color + emitted;
        rest = rest + emitted;
    }
    if (DENOISE) {
        denoise_store(px, vec4<f32>(acc.unshadowed, 1.0), acc.est_shadowed, acc.est_unshadowed, rest);
        if (frame.modes.w != 0u) {
            denoise_fix(s);
        }
    }
    if (SPATIAL != 0u) {
        if (acc.reused) {
            spatial_store_rest(px, rest, SPATIAL_SAMPLED);
        } else {
            spatial_store_rest(px, acc.color, SPATIAL_WHOLE);
        }
    }
    if (LINEAR_OUT) {
        return vec4<f32>(acc.color, 1.0);
    }
    return vec4<f32>(tone_map(acc.color), 1.0);
}

// Samples per side of a sized light's grid when the denoiser's history is corrected for it:
// the correction stays in the history for many frames, so its noise should be below a
// frame's.
const FIX_SIDE: u32 = 4u;

// The lights changed since the last frame (denoise.rs, `light_fixes`): their records follow
// the frame's lights in the lights buffer from `frame.modes.z`, first the old records of those
// that went (`frame.modes.w & 0xffff` of them), then the new ones of those that came. What
// each adds at `s` to the estimates with and without shadows (its unshadowed direct term,
// times its visibility traced here on a fine grid), those that went negated, is written for
// the denoiser's temporal pass, which adds it to the history's means; with the luminance of
// what went (the history's samples of it are lost: it counts fewer frames).
fn denoise_fix(s: Surface) {
    let gone = frame.modes.w & 0xffffu;
    let count = gone + (frame.modes.w >> 16u);
    var with_shadows = vec3<f32>(0.0);
    var without = vec3<f32>(0.0);
    var went = 0.0;
    for (var c = 0u; c < count; c = c + 1u) {
        let light = lights[frame.modes.z + c];
        let t = light_terms_of(light, s);
        if (!t.reaches || !t.facing) {
            continue;
        }
        var lit = 1.0;
        if (light.diffuse.w > 0.0) {
            lit = ray_lit_area(light, s.p, s.n, max(ray_area_side(), FIX_SIDE), soft_jitter(s.px, 0x9e3779b9u + c));
        } else {
            lit = ray_lit(light, s.p, s.n);
        }
        let sign = select(1.0, -1.0, c < gone);
        without = without + sign * t.att * t.ds;
        with_shadows = with_shadows + sign * lit * t.att * t.ds;
        if (c < gone) {
            went = went + max(dot(t.att * t.ds, vec3<f32>(0.2126, 0.7152, 0.0722)), 0.0);
        }
    }
    denoise_store_fix(s.px, with_shadows, without, went);
}

// What the surface mirrors of the nearest probe (probes.wgsl): Phong materials their
// `reflect` (specular.w) at every angle; the glTF BRDF its Fresnel reflectance (0.04 for
// dielectrics, the base colour for metals), raised by Schlick towards 1 at grazing angles and
// scaled by the gloss (1 − roughness)².
fn probe_reflection(s: Surface) -> vec3<f32> {
    if (SHADING_MODEL == SHADING_PBR) {
        let gloss = (1.0 - s.mat.pbr.y) * (1.0 - s.mat.pbr.y);
        let f0 = mix(vec3<f32>(0.04), s.mat.diffuse.rgb, s.mat.pbr.x);
        return gloss * probe_fresnel(f0, s.n, s.v) * probe_reflected(s.p, s.n, s.v);
    }
    if (s.mat.specular.w <= 0.0) {
        return vec3<f32>(0.0);
    }
    return s.mat.specular.w * probe_reflected(s.p, s.n, s.v);
}
