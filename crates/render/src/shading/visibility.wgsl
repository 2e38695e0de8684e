// Hard-shadow visibility: one bit per light and pixel, no filtering. Bit set = the point is
// within the light's reach (range, cone) and the shadow map says nothing occludes it. This is
// what shadow quality is scored on.

struct VisibilityParams {
    // First light of this chunk, number of 32-light words in this chunk, 1 when the soft
    // visibility is written too, unused.
    first_word: u32,
    word_count: u32,
    soft: u32,
    _pad1: u32,
}

// The bindings (frame, lights, shadow_views, gbuf_position, gbuf_normal, atlas read as
// floats, params, mask, clusters, cluster_slots, cluster_masks, soft_out, then the shadow
// source's) are declared in visibility.rs and inputs.rs, which say what each holds.

fn shadow_depth_at(texel: vec2<i32>) -> f32 {
    return textureLoad(atlas, texel, 0).r;
}

// The bilinearly weighted comparison a comparison sampler makes, from the four texels' loads.
fn shadow_compare_at(t: vec2<f32>, depth: f32) -> f32 {
    let f = t - vec2<f32>(0.5);
    let b = floor(f);
    let w = f - b;
    let i = vec2<i32>(b);
    let c00 = select(0.0, 1.0, depth <= shadow_depth_at(i));
    let c10 = select(0.0, 1.0, depth <= shadow_depth_at(i + vec2<i32>(1, 0)));
    let c01 = select(0.0, 1.0, depth <= shadow_depth_at(i + vec2<i32>(0, 1)));
    let c11 = select(0.0, 1.0, depth <= shadow_depth_at(i + vec2<i32>(1, 1)));
    return mix(mix(c00, c10, w.x), mix(c01, c11, w.x), w.y);
}

// One word's answers: bit b set = light 32·word + b is lit at the point (in reach, and the
// shadow test at the light's centre says unoccluded); with `soft`, each light's fraction.
struct WordVisibility {
    bits: u32,
    soft: array<u32, 8>,
}

// The lights of `word` whose bits are set in `candidates`, at pixel `px`.
fn word_bits(word: u32, candidates: u32, p: vec3<f32>, n: vec3<f32>, view_depth: f32, px: vec2<i32>) -> WordVisibility {
    var out: WordVisibility;
    var left = candidates;
    while (left != 0u) {
        let b = firstTrailingBit(left);
        left = left & (left - 1u);
        let i = word * 32u + b;
        let light = lights[i];
        if (!in_reach(light, p)) {
            continue;
        }
        var lit = true;
        var fraction = 1.0;
        let sized = light.diffuse.w > 0.0 && params.soft != 0u;
        if (SHADOW_RAYS) {
            lit = ray_lit(light, p, n) > 0.5;
            fraction = select(0.0, 1.0, lit);
            if (sized) {
                fraction = ray_lit_area(light, p, n, ray_area_side(), soft_jitter(px, i));
            }
        } else {
            let c = shadow_coord(light, p, n, view_depth);
            if (c.valid) {
                lit = c.depth <= textureLoad(atlas, hard_texel(c), 0).r;
                fraction = select(0.0, 1.0, lit);
                if (sized) {
                    fraction = soft_shadow(light.diffuse.w, c, soft_rotation(px));
                }
            }
        }
        if (lit) {
            out.bits = out.bits | (1u << b);
        }
        let byte = u32(round(clamp(fraction, 0.0, 1.0) * 255.0));
        out.soft[b / 4u] = out.soft[b / 4u] | (byte << (8u * (b % 4u)));
    }
    return out;
}

@compute @workgroup_size(8, 8, 1)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = u32(frame.viewport.x);
    let h = u32(frame.viewport.y);
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let pixel = gid.y * w + gid.x;
    let gpos = textureLoad(gbuf_position, vec2<i32>(gid.xy), 0);
    let pos = bitcast<vec4<f32>>(gpos);
    let covered = has_geometry(gpos);
    let p = pos.xyz;
    let n = normalize(bitcast<vec3<f32>>(textureLoad(gbuf_normal, vec2<i32>(gid.xy), 0).xyz));
    let view_depth = -(frame.view * vec4<f32>(p, 1.0)).z;
    let count = frame.counts.x;
    var slot = CLUSTER_OVERFLOW;
    if (covered && clusters.words.w != 0u) {
        slot = cluster_slots[cluster_index(clusters, gid.xy, view_depth)];
    }
    let clustered = slot >= CLUSTER_FIRST_SLOT && slot != CLUSTER_OVERFLOW;
    let base = (slot - CLUSTER_FIRST_SLOT) * clusters.words.z;
    for (var wi = 0u; wi < params.word_count; wi = wi + 1u) {
        let word = params.first_word + wi;
        var vis: WordVisibility;
        if (covered) {
            // The lights of this word to test: the cluster's, or every light.
            var candidates = 0xffffffffu;
            if (word * 32u + 32u > count) {
                candidates = (1u << (count - word * 32u)) - 1u;
            }
            if (clustered) {
                let summary = cluster_masks[base + word / 32u];
                if (((summary >> (word % 32u)) & 1u) == 0u) {
                    candidates = 0u;
                } else {
                    candidates = candidates & cluster_masks[base + clusters.words.x + word];
                }
            }
            vis = word_bits(word, candidates, p, n, view_depth, vec2<i32>(gid.xy));
        }
        mask[pixel * params.word_count + wi] = vis.bits;
        if (params.soft != 0u) {
            let base_soft = (pixel * params.word_count + wi) * 8u;
            for (var k = 0u; k < 8u; k = k + 1u) {
                soft_out[base_soft + k] = vis.soft[k];
            }
        }
    }
}
