// Virtual shadow maps under sampled lights (sampled.rs; composed after vsm_table.wgsl and
// vsm_mark.wgsl): the pages of the (pixel, light) pairs the sampled lights' choose pass noted
// (sampled/pages.rs), and those asked within the last frames.
//
// cs_mark_wanted, one thread per pixel: marks the pages of the pixel's noted lights with
// mark_light, as cs_mark marks every light of the cluster.
//
// cs_keep_recent, one thread per entry, after it: the samples change every frame (new draws,
// stratified over frames where they are denoised), so a page asked last frame is often not
// asked now and would be drawn again when asked next. A page resident last frame that no
// sample asked for now is asked again, with the bounds it was drawn with, while the frames
// since a sample last asked for it are at most KEEP_FRAMES (`ages`, per entry from frame to
// frame: 1 + those frames; 0 for an entry no sample asked for, such as a resident ancestor).
// Lights no pixel sampled in that long draw nothing. Kept pages must leave the pool to the
// asked ones: they are kept only while the pages asked this frame (counted first, by
// cs_count_asked) and those kept so far stay under KEEP_SHARE of the pool (past that, which
// are kept depends on thread order: never a pixel of the frame, only how many pages are
// drawn anew).

@group(0) @binding(15) var<storage, read> page_wants: array<u32>;
@group(0) @binding(16) var<storage, read_write> ages: array<u32>;
@group(0) @binding(17) var<storage, read> prev_ages: array<u32>;

@compute @workgroup_size(8, 8, 1)
fn cs_mark_wanted(@builtin(global_invocation_id) id: vec3<u32>) {
    let px = id.xy + vec2<u32>(vsm.lod.yz);
    let s = pixel_sample(px);
    if (!s.valid) {
        return;
    }
    let stride = wants_per_pixel(u32(frame.soft.w));
    let base = (px.y * u32(frame.viewport.x) + px.x) * stride;
    for (var n = 0u; n < stride; n = n + 1u) {
        let i = page_wants[base + n];
        if (i >= frame.counts.x) {
            return;
        }
        mark_light(i, s.p, s.n, s.view_depth);
    }
}

// Counters of vsm_table.wgsl's buffer this stage uses (free slots there): pages asked by
// samples this frame, pages kept without.
const COUNT_SAMPLED: u32 = 8u;
const COUNT_RETAINED: u32 = 19u;
// The share of the pool the asked and the kept pages may fill together.
const KEEP_SHARE: f32 = 0.75;

@compute @workgroup_size(64, 1, 1)
fn cs_count_asked(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = gid.x + gid.y * groups.x * 64u;
    if (e < vsm.counts.y && (atomicLoad(&vsm_table[e]) & MARK_ASKED) != 0u) {
        atomicAdd(&counters[COUNT_SAMPLED], 1u);
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_keep_recent(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = gid.x + gid.y * groups.x * 64u;
    if (e >= vsm.counts.y) {
        return;
    }
    // Only this thread marks entry `e` asked in this pass (the others mark it above at most).
    let asked = (atomicLoad(&vsm_table[e]) & MARK_ASKED) != 0u;
    if (asked) {
        ages[e] = 1u;
    }
    let face = vsm_faces[face_of(e)];
    if (face.table.w == 0u) {
        return;
    }
    let at = face.table.w - 1u + (e - face.table.x);
    let before = prev_table[at];
    if (before < VSM_FIRST_PAGE || before >= VSM_FIRST_PAGE + VSM_QUARTER) {
        return;
    }
    if (asked) {
        // This frame's samples of the page are others than last frame's: its bounds grow to
        // hold both (the allocation keeps it where the bounds it was drawn with already do),
        // so that pixels coming back to a light find its pages drawn wide enough.
        if (vsm.counts.w != 0u) {
            atomicMax(&vsm_table[vsm.counts.y + e], prev_table[prev_keys_at() + at]);
            atomicOr(&vsm_table[cells_at() + e], prev_table[prev_cells_at() + at]);
        }
        return;
    }
    let was = prev_ages[at];
    if (was == 0u || was > KEEP_FRAMES) {
        return;
    }
    let budget = u32(KEEP_SHARE * f32(vsm.pool.w));
    if (atomicLoad(&counters[COUNT_SAMPLED]) + atomicAdd(&counters[COUNT_RETAINED], 1u) >= budget) {
        return;
    }
    ages[e] = was + 1u;
    if (vsm.counts.w != 0u) {
        atomicMax(&vsm_table[vsm.counts.y + e], prev_table[prev_keys_at() + at]);
        atomicOr(&vsm_table[cells_at() + e], prev_table[prev_cells_at() + at]);
    }
    ask_entry(face, e);
}
