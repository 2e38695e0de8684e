// Deferred lighting: seed 004's Phong model (ambient + diffuse + specular per light, quadratic
// attenuation, spot cutoff) or the glTF BRDF (SHADING_PBR, with glTF's inverse-square falloff
// and range window for physical lights); a shadowed point keeps only the ambient term. Then
// emission, exposure and a tone map (look.rs). Shadows by comparison sampling of the atlas
// with PCF off / 2x2 / 3x3, never reading outside the view's tile.

// The bindings (frame, lights, shadow_views, materials, gbuf_position, gbuf_normal, atlas,
// cmp_linear, vis_mask, clusters, cluster_slots, cluster_masks, atlas_depth, gbuf_emission,
// then the shadow source's and the parts') are declared in lighting.rs and inputs.rs, which
// say what each holds.

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
    if (choosing) {
        // The choose pass (sampled/lights.wgsl, `fs_choose`): the pair is noted, not looked up.
        want_light(i, s);
        return 1.0;
    }
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
    if (SOFT_SHADOWS && light.diffuse.w > 0.0 && c.valid) {
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
            reuse_store_point(px, vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0), false);
        }
        if (DENOISE) {
            denoise_store(px, vec4<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
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
    acc.k = ray_samples();
    // `modes.y` is the frame's number when rays are denoised (new random numbers each frame),
    // else 0.
    let noise_px = eye_local(frame.eyes, px);
    acc.rng = pcg(u32(noise_px.x) + pcg(u32(noise_px.y) + pcg(ray_seed() + frame.modes.y)));
    acc.unshadowed = vec3<f32>(0.0);
    acc.est_shadowed = vec3<f32>(0.0);
    acc.est_unshadowed = vec3<f32>(0.0);
    acc.reused = false;
    acc.shadow_moved = 0.0;
    acc.moved_light = 0.0;
    acc.track_moved = DENOISE && moved_casters() > 0u;
    var slot = CLUSTER_OVERFLOW;
    if (clusters.words.w != 0u) {
        slot = cluster_slots[cluster_index(clusters, vec2<u32>(px), s.view_depth)];
    }
    acc.u0 = 0.0;
    acc.marks = 0u;
    acc.gap_visited = 0u;
    acc.gap_weighed = 0u;
    if (ray_samples() > 0u && DENOISE) {
        // The start of the pixel's sequence of sample points (sampled/lights.wgsl,
        // `sample_point`): in the fifth of (x + 2y) mod 5, so the five pixels of every
        // à-trous cross (steps 1, 2, 4, 8) start in different fifths, and within it by
        // interleaved gradient noise (Jimenez 2014). Chosen by measurement over the noise
        // alone (docs/techniques.md, "The denoiser's stratified samples").
        let p = vec2<f32>(noise_px);
        let ign = fract(52.982919 * fract(0.06711056 * p.x + 0.00583715 * p.y));
        let cls = f32(u32(noise_px.x + 2 * noise_px.y) % 5u);
        acc.u0 = fract((cls + ign) / 5.0 + f32(pcg(ray_seed()) >> 8u) / 16777216.0);
    }
    // The choose pass's draws, where it hands them over (sampled/lights.wgsl, CARRY): the
    // loop's result without the loop.
    let carried = CARRY && !choosing && ray_samples() > 0u;
    if (carried) {
        carry_load(px, &acc);
    } else if (slot < CLUSTER_FIRST_SLOT || slot == CLUSTER_OVERFLOW) {
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
    var fix: DenoiseFix;
    if (DENOISE && frame.modes.w != 0u) {
        fix = denoise_fix(s);
        if (ray_samples() > 0u && !REUSE) {
            acc.k = catch_up_samples(acc.unshadowed, fix);
        }
    }
    if (DENOISE && REUSE && ray_samples() > 0u && acc.moved_light > 0.0) {
        acc.k = max(acc.k, moved_catch_up_samples(acc.unshadowed, acc.moved_light));
    }
    if (DENOISE && ray_samples() > 0u && acc.count > ray_samples() && !carried) {
        pick_stratified(s, slot, &acc);
    }
    if (CARRY && choosing && ray_samples() > 0u) {
        carry_store(px, &acc);
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
        denoise_store(px, vec4<f32>(acc.unshadowed, 1.0), acc.est_shadowed, acc.est_unshadowed, rest, f32(acc.k) / f32(max(ray_samples(), 1u)));
        if (acc.moved_light > 0.0) {
            let all = dot(acc.unshadowed, vec3<f32>(0.2126, 0.7152, 0.0722));
            acc.shadow_moved = max(acc.shadow_moved, clamp(acc.moved_light / max(all, 1e-30), 0.0, 1.0));
        }
        if (acc.shadow_moved > 0.0) {
            denoise_note_shadow_moved(px, acc.shadow_moved);
        }
        if (frame.modes.w != 0u) {
            denoise_store_fix(s.px, fix.with_shadows, fix.without, fix.went);
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
struct DenoiseFix {
    with_shadows: vec3<f32>,
    without: vec3<f32>,
    went: f32,
}

fn denoise_fix(s: Surface) -> DenoiseFix {
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
        if (!SHADOW_RAYS) {
            // Over shadow maps: the slot's map this frame (denoise.rs `light_fixes` stamps
            // the slot; `follow_lights` falls back where a slot went). Exact for a light whose
            // colour changed; a light that moved is read where it is now.
            lit = light_lit(u32(light.attenuation.w), s);
        } else if (light.diffuse.w > 0.0) {
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
    return DenoiseFix(with_shadows, without, went);
}

// Samples a pixel draws in the frame its lights changed. The history loses its samples of the
// lights that went (the temporal pass cuts its frame count to the share that stays), so the
// lights that stay are left with fewer samples than a history of them alone would hold: this
// frame draws the lost share of the most frames a history holds (`CATCH_UP_FRAMES`, the
// denoiser's `MAX_HISTORY`, composed by sampled/denoise.rs) again (up to MAX_SAMPLES),
// spread evenly over the weights (`sample_point`), and its estimate counts as that many
// frames. With it a light switched off leaves the frames after it near the steady error at
// once, where K samples alone stay well above it for four frames (test
// `a_light_switched_off_leaves_the_frame_within_four_frames`; docs/techniques.md, "The
// denoiser when lights change").
fn catch_up_samples(unshadowed: vec3<f32>, fix: DenoiseFix) -> u32 {
    let k = ray_samples();
    let luma = vec3<f32>(0.2126, 0.7152, 0.0722);
    let before = dot(unshadowed - fix.without, luma);
    let lost = clamp(fix.went / max(before, 1e-30), 0.0, 1.0);
    let frames = u32(round(CATCH_UP_FRAMES * lost));
    return min(k * (1u + frames), MAX_SAMPLES);
}

// With reuse: a still point whose light passes a caster that moved loses that share of its
// history (the temporal pass cuts it, denoise.wgsl); like a light change (`catch_up_samples`)
// this frame draws the lost frames again, beside the reservoirs (`resolve_reused`), and its
// estimate counts as that many frames.
fn moved_catch_up_samples(unshadowed: vec3<f32>, moved: f32) -> u32 {
    let k = ray_samples();
    let all = dot(unshadowed, vec3<f32>(0.2126, 0.7152, 0.0722));
    let share = clamp(moved / max(all, 1e-30), 0.0, 1.0);
    let lost = 1.0 - pow(1.0 - share, SHADOW_MOVED_POWER);
    let frames = u32(round(CATCH_UP_FRAMES * lost));
    return min(k * (1u + frames), MAX_SAMPLES);
}

// What the surface mirrors of the nearest probe (probes/maps.wgsl): Phong materials their
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
