// Clustered light assignment (Olsson et al. 2012; seed 002's "only the occupied clusters").
//
// cs_mark:    one thread per pixel marks the cluster its G-buffer sample falls in.
// cs_compact: one thread per cluster gives each marked cluster a slot of the pool (or marks it
//             overflowed) and fills the slot with the lights that reach everywhere
//             (directional lights: `global_words`).
// cs_assign:  one thread per (light of the list, depth slice) walks the tiles its bounding
//             sphere covers in that slice and sets its bit in every occupied cluster the sphere
//             (and, for spots, the cone) touches.
// cs_stats:   one thread per slot counts its lights (mean and maximum for the summary).
//
// Bits are set with atomicOr, so the lists are the same whatever order threads run in, and
// shading walks them in ascending light order: the same sum as looping over every light.

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<uniform> clusters: ClusterUniforms;
@group(0) @binding(2) var gbuf_position: texture_2d<u32>;
// Per cluster: CLUSTER_EMPTY, CLUSTER_MARKED, CLUSTER_FIRST_SLOT + slot, or CLUSTER_OVERFLOW;
// then, for the `counts.z` clusters again, the farthest view depth of the cluster's samples
// (float bits: positive floats order as their bits) and the nearest one's bits inverted (so
// that both start at 0 and grow by atomicMax).
@group(0) @binding(3) var<storage, read_write> slots: array<atomic<u32>>;
// `counts.x` slots of `words.z` words.
@group(0) @binding(4) var<storage, read_write> masks: array<atomic<u32>>;
// The words every slot starts with (summary, then light words).
@group(0) @binding(5) var<storage, read> global_words: array<u32>;
// Lights to assign: index, and world bounding sphere (xyz centre, w radius).
@group(0) @binding(6) var<storage, read> assign_index: array<u32>;
@group(0) @binding(7) var<storage, read> assign_sphere: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> lights: array<LightData>;
// Slots handed out, clusters overflowed, lights summed over slots, most lights in one slot.
@group(0) @binding(9) var<storage, read_write> control: array<atomic<u32>, 4>;

@compute @workgroup_size(8, 8, 1)
fn cs_mark(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = u32(frame.viewport.x);
    let h = u32(frame.viewport.y);
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let gpos = textureLoad(gbuf_position, vec2<i32>(gid.xy), 0);
    let pos = bitcast<vec4<f32>>(gpos);
    if (!has_geometry(gpos)) {
        return;
    }
    let view_depth = -(frame.view * vec4<f32>(pos.xyz, 1.0)).z;
    let ci = cluster_index(clusters, gid.xy, view_depth);
    atomicStore(&slots[ci], CLUSTER_MARKED);
    let bits = bitcast<u32>(max(view_depth, 0.0));
    atomicMax(&slots[clusters.counts.z + ci], bits);
    atomicMax(&slots[2u * clusters.counts.z + ci], ~bits);
}

// The view depths the samples of cluster `ci` span (cs_mark), padded like `slice_range`: the
// cluster's box need only hold its samples, not its whole slice (Olsson et al.'s explicit
// bounds: a far slice is metres deep where the surfaces a tile sees in it are not).
fn sample_range(ci: u32) -> vec2<f32> {
    let far = bitcast<f32>(atomicLoad(&slots[clusters.counts.z + ci]));
    let near = bitcast<f32>(~atomicLoad(&slots[2u * clusters.counts.z + ci]));
    return vec2<f32>(near * (1.0 - 1e-3), far * (1.0 + 1e-3));
}

@compute @workgroup_size(64, 1, 1)
fn cs_compact(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let c = gid.x + gid.y * groups.x * 64u;
    if (c >= clusters.counts.z || atomicLoad(&slots[c]) != CLUSTER_MARKED) {
        return;
    }
    let s = atomicAdd(&control[0], 1u);
    if (s >= clusters.counts.x) {
        atomicStore(&slots[c], CLUSTER_OVERFLOW);
        atomicAdd(&control[1], 1u);
        return;
    }
    atomicStore(&slots[c], CLUSTER_FIRST_SLOT + s);
    let stride = clusters.words.z;
    for (var i = 0u; i < stride; i = i + 1u) {
        atomicStore(&masks[s * stride + i], global_words[i]);
    }
}

// Depth range [z0, z1] of slice `s`, padded by 1e-3 relative so that a sample whose slice was
// rounded either way still lies inside.
fn slice_range(s: u32) -> vec2<f32> {
    let c = clusters;
    var z0 = c.depth.x * exp(f32(s) / c.depth.y);
    var z1 = c.depth.x * exp(f32(s + 1u) / c.depth.y);
    if (s == 0u) {
        z0 = c.depth.z;
    }
    if (s + 1u >= c.grid.z) {
        z1 = c.depth.w;
    }
    return vec2<f32>(z0 * (1.0 - 1e-3), z1 * (1.0 + 1e-3));
}

// Smallest and largest of x / d over x in [x0, x1] and d in [d0, d1] (0 < d0 <= d1).
fn ratio_range(x0: f32, x1: f32, d0: f32, d1: f32) -> vec2<f32> {
    let lo = select(x0 / d0, x0 / d1, x0 >= 0.0);
    let hi = select(x1 / d1, x1 / d0, x1 >= 0.0);
    return vec2<f32>(lo, hi);
}

// Conservative test of a spot light's cone against a sphere (view space): false only when the
// sphere lies wholly outside the cone's infinite lateral surface, behind its apex, or beyond
// its range along the axis. The lateral distance is measured to the full line through the apex,
// never more than the distance to the cone itself.
fn cone_touches_sphere(apex: vec3<f32>, axis: vec3<f32>, cos_c: f32, range: f32, centre: vec3<f32>, radius: f32) -> bool {
    let v = centre - apex;
    let along = dot(v, axis);
    let across = sqrt(max(dot(v, v) - along * along, 0.0));
    let sin_c = sqrt(max(1.0 - cos_c * cos_c, 0.0));
    let lateral = cos_c * across - along * sin_c;
    return !(lateral > radius || along > radius + range || along < -radius);
}

@compute @workgroup_size(64, 1, 1)
fn cs_assign(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = clusters;
    if (gid.x >= c.counts.y) {
        return;
    }
    let light_index = assign_index[gid.x];
    let sphere = assign_sphere[gid.x];
    let s = gid.z;
    let zr = slice_range(s);
    let light = lights[light_index];
    let is_spot = light.shadow.z == LIGHT_SPOT;
    let eyes = max(c.counts.w, 1u);
    let per_eye = c.grid.x / eyes;
    // Each eye's view space is the centre camera's moved along x (frame/eyes.rs).
    for (var eye = 0u; eye < eyes; eye = eye + 1u) {
        let shift = vec3<f32>(select(0.0, (f32(eye) * 2.0 - 1.0) * c.proj.w, eyes > 1u), 0.0, 0.0);
        assign_in_eye(light_index, sphere, light, is_spot, s, zr, shift, eye * per_eye, per_eye);
    }
}

// Sets the light's bit in the occupied clusters of one eye's tile columns
// (`first_tile`.. + `tiles_x`), in that eye's view space (the centre's minus `shift`).
fn assign_in_eye(light_index: u32, sphere: vec4<f32>, light: LightData, is_spot: bool, s: u32, zr: vec2<f32>, shift: vec3<f32>, first_tile: u32, tiles_x: u32) {
    let c = clusters;
    let centre = (frame.view * vec4<f32>(sphere.xyz, 1.0)).xyz - shift;
    // Pad the radius against rounding of the view transform.
    let r = sphere.w * (1.0 + 1e-4) + 1e-5 * length(centre);
    let depth = -centre.z;
    if (depth + r < zr.x || depth - r > zr.y) {
        return;
    }
    let d0 = max(zr.x, depth - r);
    let d1 = min(zr.y, depth + r);
    // NDC rectangle of the sphere's box within the slab, then tiles.
    let nx = ratio_range(centre.x - r, centre.x + r, d0, d1) / c.proj.x;
    let ny = ratio_range(centre.y - r, centre.y + r, d0, d1) / c.proj.y;
    let size = vec2<f32>(c.proj.z, frame.viewport.y);
    let tile = f32(c.grid.w);
    // Pixel x = (ndc.x + 1) / 2 · width; pixel y = (1 − ndc.y) / 2 · height.
    let px0 = (nx.x + 1.0) * 0.5 * size.x;
    let px1 = (nx.y + 1.0) * 0.5 * size.x;
    let py0 = (1.0 - ny.y) * 0.5 * size.y;
    let py1 = (1.0 - ny.x) * 0.5 * size.y;
    if (px1 < 0.0 || py1 < 0.0 || px0 > size.x || py0 > size.y) {
        return;
    }
    let last = vec2<f32>(vec2<u32>(tiles_x, c.grid.y) - vec2<u32>(1u));
    let t0 = vec2<u32>(clamp(floor(vec2<f32>(px0, py0) / tile), vec2<f32>(0.0), last));
    let t1 = vec2<u32>(clamp(floor(vec2<f32>(px1, py1) / tile), vec2<f32>(0.0), last));

    let apex = (frame.view * vec4<f32>(light.position.xyz, 1.0)).xyz - shift;
    let axis = normalize((frame.view * vec4<f32>(light.direction.xyz, 0.0)).xyz);
    let word = light_index / 32u;
    let bit = 1u << (light_index % 32u);
    let summary_word = word / 32u;
    let summary_bit = 1u << (word % 32u);
    let stride = c.words.z;
    for (var ty = t0.y; ty <= t1.y; ty = ty + 1u) {
        for (var tx = t0.x; tx <= t1.x; tx = tx + 1u) {
            let ci = (s * c.grid.y + ty) * c.grid.x + first_tile + tx;
            let v = atomicLoad(&slots[ci]);
            if (v < CLUSTER_FIRST_SLOT || v == CLUSTER_OVERFLOW) {
                continue;
            }
            // The cluster's view-space box: the tile's pixel rectangle at the depths its
            // samples span (padded like the slice).
            let zc = sample_range(ci);
            let p0 = vec2<f32>(f32(tx), f32(ty)) * tile;
            let p1 = min(p0 + vec2<f32>(tile), size);
            let ndc_x = vec2<f32>(p0.x, p1.x) / size.x * 2.0 - 1.0;
            let ndc_y = 1.0 - vec2<f32>(p1.y, p0.y) / size.y * 2.0;
            let xs = vec4<f32>(ndc_x.x * zc.x, ndc_x.x * zc.y, ndc_x.y * zc.x, ndc_x.y * zc.y) * c.proj.x;
            let ys = vec4<f32>(ndc_y.x * zc.x, ndc_y.x * zc.y, ndc_y.y * zc.x, ndc_y.y * zc.y) * c.proj.y;
            let pad = 1e-3 * zc.y;
            let lo = vec3<f32>(min(min(xs.x, xs.y), min(xs.z, xs.w)) - pad, min(min(ys.x, ys.y), min(ys.z, ys.w)) - pad, -zc.y);
            let hi = vec3<f32>(max(max(xs.x, xs.y), max(xs.z, xs.w)) + pad, max(max(ys.x, ys.y), max(ys.z, ys.w)) + pad, -zc.x);
            let nearest = clamp(centre, lo, hi);
            if (dot(nearest - centre, nearest - centre) > r * r) {
                continue;
            }
            if (is_spot) {
                let mid = 0.5 * (lo + hi);
                let half = 0.5 * length(hi - lo);
                if (!cone_touches_sphere(apex, axis, light.direction.w, light.ambient.w * (1.0 + 1e-4), mid, half)) {
                    continue;
                }
            }
            let base = (v - CLUSTER_FIRST_SLOT) * stride;
            atomicOr(&masks[base + c.words.x + word], bit);
            atomicOr(&masks[base + summary_word], summary_bit);
        }
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_stats(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let s = gid.x + gid.y * groups.x * 64u;
    let used = min(atomicLoad(&control[0]), clusters.counts.x);
    if (s >= used) {
        return;
    }
    let c = clusters;
    let base = s * c.words.z + c.words.x;
    var n = 0u;
    for (var w = 0u; w < c.words.y; w = w + 1u) {
        n = n + countOneBits(atomicLoad(&masks[base + w]));
    }
    atomicAdd(&control[2], n);
    atomicMax(&control[3], n);
}
