// The lighting pass's sampled lights (mod.rs hands this to the lighting pass as a part): with
// `ray_samples() > 0` each pixel's light loop (`visit`) draws K lights in proportion to the
// luminance of their unshadowed terms and traces one ray to each (`resolve_samples`); where
// frames are denoised the draws are stratified over frames (`pick_stratified`); with reuse
// the draws meet last frame's reservoir (`resolve_reused`) and, after the pass, their
// neighbours' (`fs_spatial`). The loop itself, the terms and the shadow lookups are in
// lighting.wgsl.

// MAX_SAMPLES, the most lights a pixel samples (RayOptions::light_samples), is composed
// before this file (mod.rs).

// What a pixel's light loop accumulates: the colour, and with sampled lights (`ray_samples()
// > 0`) one weighted reservoir per sample over the lights' unshadowed direct terms, and the
// first `K` candidates themselves (a pixel with no more candidates than samples traces them
// all: exact, and no dearer).
struct Acc {
    color: vec3<f32>,
    wsum: f32,
    chosen: array<u32, MAX_SAMPLES>,
    weight: array<f32, MAX_SAMPLES>,
    frac: array<f32, MAX_SAMPLES>,
    count: u32,
    // Samples drawn (K, more in a frame whose lights changed: catch_up_samples).
    k: u32,
    first: array<u32, MAX_SAMPLES>,
    rng: u32,
    // With DENOISE: the unshadowed direct light of every light visited, and the sampled
    // estimates of the direct light with and without shadows (denoise.rs).
    unshadowed: vec3<f32>,
    est_shadowed: vec3<f32>,
    est_unshadowed: vec3<f32>,
    // Whether the samples went through temporal reuse (resolve_reused).
    reused: bool,
    // With DENOISE: the share of the pixel's unshadowed light whose segment passes a caster
    // that moved since the last frame (`moved_caster_between`): every light visited is
    // tested (`moved_light` sums their luminance while casters moved, `track_moved`), and
    // at least the largest share of a light traced.
    shadow_moved: f32,
    moved_light: f32,
    track_moved: bool,
    // Where frames are denoised: the pixel's first point of its low-discrepancy sequence
    // (`sample_point`), and checkpoints (a light with the running sum before it, after every
    // CHECKPOINT_EVERY weighed or CHECKPOINT_VISITED visited lights), from which
    // `pick_stratified` finds the light a point of the sum falls on.
    u0: f32,
    marks: u32,
    // Lights visited and weighed since the last checkpoint.
    gap_visited: u32,
    gap_weighed: u32,
    mark_light: array<u32, CHECKPOINTS>,
    mark_sum: array<f32, CHECKPOINTS>,
}

// Checkpoints of the running sum (past the last one the stretch to weigh again is longer,
// never wrong). With lights listed in space order (scene `lights::spatial_order`) a pixel's
// weighed lights clump, so a checkpoint also follows every CHECKPOINT_VISITED lights visited;
// the walk skips empty words by the cluster's summary bits (reading every word made the
// denoised frame markedly dearer at 16,384 lights: docs/techniques.md, "The denoiser's
// stratified samples").
const CHECKPOINTS: u32 = 32u;
const CHECKPOINT_EVERY: u32 = 4u;
const CHECKPOINT_VISITED: u32 = 16u;

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
    if (DENOISE && k > 0u) {
        // A checkpoint before this light where 4 weighed or 16 visited lights passed since
        // the last (the first light always): pick_stratified then weighs again at most that
        // many, whatever the share of the cluster's lights that reach the pixel.
        let due = (*acc).marks == 0u || (*acc).gap_weighed >= CHECKPOINT_EVERY
            || (*acc).gap_visited >= CHECKPOINT_VISITED;
        if (due && (*acc).marks < CHECKPOINTS) {
            (*acc).mark_light[(*acc).marks] = i;
            (*acc).mark_sum[(*acc).marks] = (*acc).wsum;
            (*acc).marks = (*acc).marks + 1u;
            (*acc).gap_visited = 0u;
            (*acc).gap_weighed = 0u;
        }
        (*acc).gap_visited = (*acc).gap_visited + 1u;
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
        if ((*acc).track_moved && moved_caster_between(i, s)) {
            (*acc).moved_light = (*acc).moved_light
                + dot(t.att * t.ds, vec3<f32>(0.2126, 0.7152, 0.0722));
        }
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
        (*acc).gap_weighed = (*acc).gap_weighed + 1u;
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

// Sample `j`'s point in [0, 1) this frame: the van der Corput sequence (base 2, indexed
// from the first frame) from the pixel's own start, so a pixel's points over frames (and its
// K points in one frame) are spread evenly over the weights instead of independently: any
// first 2^m of them one in each 2^-m of the interval. Neighbours start apart (lighting.wgsl,
// `u0`). Each point alone is uniform. Frames count from 1 (`modes.y`), the sequence from 0
// (frame f's K points are its (f − 1)K-th to fK − 1-th): from 1 a pixel's first 8 points
// would not be one in each eighth. Chosen by measurement over the golden-ratio sequence it
// replaced (docs/techniques.md, "The denoiser's stratified samples").
fn sample_point(acc: ptr<function, Acc>, j: u32) -> f32 {
    if ((*acc).k != ray_samples()) {
        // A catch-up frame: its samples spread evenly from the sequence's point of this frame.
        let n0 = (frame.modes.y - 1u) * ray_samples();
        return fract((*acc).u0 + f32(reverseBits(n0) >> 8u) / 16777216.0 + f32(j) / f32((*acc).k));
    }
    let n = (frame.modes.y - 1u) * ray_samples() + j;
    return fract((*acc).u0 + f32(reverseBits(n) >> 8u) / 16777216.0);
}

// Where frames are denoised, the point on a sized light's shape that a sample of light `i`
// traces: first coordinate `t`, where in the light's stretch of the running sum the sample's
// point fell (uniform given the pick, and spread evenly over the frames that pick the light,
// as the points are), the second the pixel's hash: lower error than both coordinates hashed
// or a lattice for the second (docs/techniques.md, "The denoiser's stratified samples").
fn sample_shape_point(s: Surface, i: u32, t: f32) -> vec2<f32> {
    return vec2<f32>(t, soft_jitter(s.px, i).y);
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
// CHECKPOINT_EVERY weighed or CHECKPOINT_VISITED lights in the loop's order while checkpoints
// last (a point the sum never reaches, as rounding
// might leave one, keeps the last light weighed). Over frames the points follow the
// van der Corput sequence, so a pixel's samples cover its lights evenly (stratified); each
// sample also keeps where it fell within its light's stretch (`frac`, for the point on a
// sized light: sample_shape_point).
fn pick_stratified(s: Surface, slot: u32, acc: ptr<function, Acc>) {
    for (var j = 0u; j < (*acc).k; j = j + 1u) {
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
            // The cluster's words from the checkpoint's on, the empty ones skipped by the
            // summary bits as in the light loop (lights listed in space order leave long runs
            // of empty words between a cluster's far-reaching lights).
            let base = (slot - CLUSTER_FIRST_SLOT) * clusters.words.z;
            let w0 = first_light / 32u;
            var done = false;
            for (var sw = w0 / 32u; sw < clusters.words.x && !done; sw = sw + 1u) {
                var words = cluster_masks[base + sw];
                if (sw == w0 / 32u) {
                    words = words & ~((1u << (w0 % 32u)) - 1u);
                }
                while (words != 0u && !done) {
                    let w = sw * 32u + firstTrailingBit(words);
                    words = words & (words - 1u);
                    var bits = cluster_masks[base + clusters.words.x + w];
                    if (w == w0) {
                        bits = bits & ~((1u << (first_light % 32u)) - 1u);
                    }
                    while (bits != 0u) {
                        let i = w * 32u + firstTrailingBit(bits);
                        bits = bits & (bits - 1u);
                        if (weigh_past(i, s, point, &sum, &picked, &weight)) {
                            done = true;
                            break;
                        }
                    }
                }
            }
        }
        (*acc).chosen[j] = picked;
        (*acc).weight[j] = weight;
        (*acc).frac[j] = clamp((point - (sum - weight)) / max(weight, 1e-30), 0.0, 0.99999);
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
            reuse_store_point(s.px, s.p, s.n, false);
        }
        return;
    }
    var direct = vec3<f32>(0.0);
    if ((*acc).count <= k) {
        if (REUSE) {
            // Exact: nothing to reuse, and the next frame starts anew here.
            reuse_store_point(s.px, s.p, s.n, false);
        }
        for (var j = 0u; j < (*acc).count; j = j + 1u) {
            let i = (*acc).first[j];
            let t = light_terms(i, s);
            direct = direct + light_lit(i, s) * t.att * t.ds;
            if (DENOISE) {
                note_moved_share(acc, i, s);
            }
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
    let n = (*acc).k;
    for (var j = 0u; j < n; j = j + 1u) {
        let i = (*acc).chosen[j];
        let t = light_terms(i, s);
        let term = t.att * t.ds * ((*acc).wsum / (*acc).weight[j]);
        var lit = 0.0;
        if (DENOISE) {
            lit = light_lit_point(i, s, sample_shape_point(s, i, (*acc).frac[j]));
            note_moved_share(acc, i, s);
        } else {
            lit = light_lit(i, s);
        }
        direct = direct + lit * term;
        if (DENOISE) {
            unlit = unlit + term;
        }
    }
    (*acc).color = (*acc).color + direct / f32(n);
    if (DENOISE) {
        (*acc).est_shadowed = direct / f32(n);
        (*acc).est_unshadowed = unlit / f32(n);
    }
}

// With DENOISE: light `i`, traced at `s`, passes a caster that moved since the last frame:
// its share of the pixel's unshadowed light is the most of the history's ratio that may have
// changed with it (the temporal pass cuts the history by it).
fn note_moved_share(acc: ptr<function, Acc>, i: u32, s: Surface) {
    if (!moved_caster_between(i, s)) {
        return;
    }
    let luma = vec3<f32>(0.2126, 0.7152, 0.0722);
    let t = light_terms(i, s);
    let share = dot(t.att * t.ds, luma) / max(dot((*acc).unshadowed, luma), 1e-30);
    (*acc).shadow_moved = max((*acc).shadow_moved, clamp(share, 0.0, 1.0));
}

// Whether the point `jitter` (0..1², on the light's shape) of light `i` reaches `s` (its
// centre for a light without size): one ray.
fn light_lit_point(i: u32, s: Surface, jitter: vec2<f32>) -> f32 {
    if (!SHADOW_RAYS) {
        // Shadow maps answer for the whole light: a sized light's percentage-closer soft
        // fraction, a hard one's shadow test (the point on the shape is not needed).
        return light_lit(i, s);
    }
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
    let r = reuse_history(s.px, s.p, s.n);
    reuse_store_point(s.px, s.p, s.n, true);
    var direct = vec3<f32>(0.0);
    for (var j = 0u; j < k; j = j + 1u) {
        let yn = (*acc).chosen[j];
        let tn = light_terms(yn, s);
        let f_new = tn.att * tn.ds;
        let jn = soft_jitter(s.px, yn);
        let vn = light_lit_point(yn, s, jn);
        if (DENOISE) {
            note_moved_share(acc, yn, s);
        }
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
                        if (DENOISE) {
                            note_moved_share(acc, y_old, s);
                        }
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
    // Catch-up samples beside the reservoirs (a history a moved caster cut:
    // lighting.wgsl `moved_catch_up_samples`), each drawn and traced as without reuse, kept
    // in no reservoir.
    let n = max((*acc).k, k);
    for (var j = k; j < n; j = j + 1u) {
        let i = (*acc).chosen[j];
        let t = light_terms(i, s);
        let term = t.att * t.ds * ((*acc).wsum / (*acc).weight[j]);
        direct = direct + light_lit_point(i, s, sample_shape_point(s, i, (*acc).frac[j])) * term;
    }
    (*acc).color = (*acc).color + direct / f32(n);
    if (DENOISE) {
        (*acc).est_shadowed = direct / f32(n);
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

// The choose pass (pages.rs: sampled lights over virtual maps' pages), drawn before the
// shadows are made: `fs_choose` runs the pixel's light loop as the lighting pass will run it
// (the same draws from the same random numbers and last frame's reservoirs; nothing is
// stored), and notes instead of looking up every light whose visibility the pass will ask
// for (`light_lit` calls `want_light` while `choosing`): the K lights drawn, the lights last
// frame's reservoirs kept, the lights whose change the denoiser corrects. The notes go to
// `vis_mask` (the lighting pass's mask binding, which a source without a mask leaves free):
// `wants_per_pixel(K)` words per pixel (pages.rs), unused ones NO_WANT; the page
// marking (shadows/vsm, `cs_mark_wanted`) marks the pages of those pairs only. A pixel that
// asks for more (the denoiser's catch-up samples or corrections in a frame whose lights
// changed) loses the rest: their lookups fall back to the coarser pages that are resident.

var<private> choosing: bool = false;
// Lights noted so far for this pixel.
var<private> wanted: u32 = 0u;

fn wants_base(px: vec2<i32>) -> u32 {
    return (u32(px.y) * u32(frame.viewport.x) + u32(px.x)) * wants_per_pixel(ray_samples());
}

// Notes light `i` for the pixel of `s` (once).
fn want_light(i: u32, s: Surface) {
    let base = wants_base(s.px);
    for (var n = 0u; n < wanted; n = n + 1u) {
        if (vis_mask[base + n] == i) {
            return;
        }
    }
    if (wanted < wants_per_pixel(ray_samples())) {
        vis_mask[base + wanted] = i;
        wanted = wanted + 1u;
    }
}

// With CARRY (pages.rs, `PageWants::carry`) the choose pass also hands the lighting pass its
// draws, after every pixel's notes in the same buffer (`carry_per_pixel(K)` words per pixel):
// what the light loop and `pick_stratified` leave in `Acc` (the colour so far, the unshadowed
// light, the weights' sum, the count of lights weighed, the random state, and per sample its
// light, weight and point), so that the lighting pass does not run the loop again. The draws
// do not depend on the shadows (CARRY is off where they do: the denoiser's catch-up samples
// without reuse), so the lighting pass shades exactly what it would have drawn itself.
fn carry_base(px: vec2<i32>) -> u32 {
    let k = ray_samples();
    let pixels = u32(frame.viewport.x) * u32(frame.viewport.y);
    return pixels * wants_per_pixel(k) + (u32(px.y) * u32(frame.viewport.x) + u32(px.x)) * carry_per_pixel(k);
}

fn carry_store(px: vec2<i32>, acc: ptr<function, Acc>) {
    let b = carry_base(px);
    vis_mask[b] = bitcast<u32>((*acc).color.x);
    vis_mask[b + 1u] = bitcast<u32>((*acc).color.y);
    vis_mask[b + 2u] = bitcast<u32>((*acc).color.z);
    vis_mask[b + 3u] = bitcast<u32>((*acc).unshadowed.x);
    vis_mask[b + 4u] = bitcast<u32>((*acc).unshadowed.y);
    vis_mask[b + 5u] = bitcast<u32>((*acc).unshadowed.z);
    vis_mask[b + 6u] = bitcast<u32>((*acc).wsum);
    vis_mask[b + 7u] = (*acc).count;
    vis_mask[b + 8u] = (*acc).rng;
    let k = ray_samples();
    for (var j = 0u; j < k; j = j + 1u) {
        // A pixel with no more lights than samples traces its first ones (resolve_samples).
        vis_mask[b + 9u + 3u * j] = select((*acc).chosen[j], (*acc).first[j], (*acc).count <= k);
        vis_mask[b + 10u + 3u * j] = bitcast<u32>((*acc).weight[j]);
        vis_mask[b + 11u + 3u * j] = bitcast<u32>((*acc).frac[j]);
    }
}

fn carry_load(px: vec2<i32>, acc: ptr<function, Acc>) {
    let b = carry_base(px);
    (*acc).color = bitcast<vec3<f32>>(vec3<u32>(vis_mask[b], vis_mask[b + 1u], vis_mask[b + 2u]));
    (*acc).unshadowed = bitcast<vec3<f32>>(vec3<u32>(vis_mask[b + 3u], vis_mask[b + 4u], vis_mask[b + 5u]));
    (*acc).wsum = bitcast<f32>(vis_mask[b + 6u]);
    (*acc).count = vis_mask[b + 7u];
    (*acc).rng = vis_mask[b + 8u];
    let k = ray_samples();
    for (var j = 0u; j < k; j = j + 1u) {
        let light = vis_mask[b + 9u + 3u * j];
        (*acc).chosen[j] = light;
        (*acc).first[j] = light;
        (*acc).weight[j] = bitcast<f32>(vis_mask[b + 10u + 3u * j]);
        (*acc).frac[j] = bitcast<f32>(vis_mask[b + 11u + 3u * j]);
    }
}

@fragment
fn fs_choose(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let px = vec2<i32>(frag.xy);
    choosing = true;
    wanted = 0u;
    let color = shade(px, MASK_NONE);
    let base = wants_base(px);
    for (var n = wanted; n < wants_per_pixel(ray_samples()); n = n + 1u) {
        vis_mask[base + n] = NO_WANT;
    }
    return color;
}
