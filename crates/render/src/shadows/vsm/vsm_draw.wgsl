// Virtual shadow maps (vsm.rs), rendering the resident pages: every page is an ordinary
// shadow view (the face's projection cropped to the page, one tile of the pool), so pages are
// drawn the `gpu-driven` way: a compute pass culls caster clusters against each page's
// frustum slice and writes indexed-indirect commands, one multi-draw renders the survivors
// into the pages' tiles. `page_views` lists this frame's pages to draw (kept pages are not in
// it); their count is known only on the GPU: cull dispatches are indirect, and rounds past
// the last page cull nothing.
//
// The cull is hierarchical: clusters come in groups of VSM_CULL_GROUP consecutive ones (one
// instance's neighbouring triangles, mostly), whose bounding spheres casters.wgsl's cs_groups
// merges once per frame, after the clusters' (cluster_bounds[clusters + g]). One
// thread per (group, page) tests the group's sphere and only if it is inside the page tests
// the group's clusters, so a page far from most of the scene costs a thread per group, not
// one per cluster.

@group(0) @binding(0) var<uniform> round: VsmRound;
@group(0) @binding(1) var<uniform> vsm: VsmUniforms;
@group(0) @binding(2) var<storage, read> page_views: array<ShadowViewData>;

// ---- cull (compute) ----

@group(0) @binding(4) var<storage, read> vsm_faces: array<VirtualFace>;
@group(0) @binding(5) var<storage, read> clusters: array<GpuCluster>;
@group(0) @binding(6) var<storage, read> cluster_bounds: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> instances: array<InstanceData>;
@group(0) @binding(8) var<storage, read_write> commands: array<DrawCommand>;
@group(0) @binding(9) var<storage, read_write> command_count: atomic<u32>;
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;
// One thread per (group, page slot) of the round; the round's clusters are [lo, hi) and its
// groups those from lo / VSM_CULL_GROUP on.
@compute @workgroup_size(64, 1, 1)
fn cs_cull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.y;
    let lo = round.round.z;
    let hi = lo + round.round.w;
    let g = lo / VSM_CULL_GROUP + gid.x;
    if (g * VSM_CULL_GROUP >= hi || slot >= round.round.y) {
        return;
    }
    let page = round.round.x + slot;
    let bits = round.counts.z;
    let compact = round.counts.w != 0u;
    // Slots past the last resident page draw nothing (only reached without compaction,
    // where every slot's command is written).
    let view = page_views[min(page, arrayLength(&page_views) - 1u)];
    var group_visible = page < atomicLoad(&counters[17]);
    let frustum = (bits & CULL_FRUSTUM) != 0u;
    let row = key_row(view.view_proj, view.params.w);
    if (group_visible && frustum && (bits & VSM_FLAT_CULL) == 0u) {
        let sphere = cluster_bounds[arrayLength(&clusters) + g];
        if (sphere_outside(view.view_proj, sphere) || beyond_receivers(view, row, sphere)) {
            group_visible = false;
        }
    }
    if (!group_visible && compact) {
        return;
    }
    let eye = vsm_faces[min(bitcast<u32>(view.tile.w), arrayLength(&vsm_faces) - 1u)].eye;
    var draws = 0u;
    var triangles = 0u;
    // In compaction, consecutive visible clusters (whose triangles are consecutive in the
    // corner buffer) go out as one command: fewer, longer draws.
    var run: DrawCommand;
    run.index_count = 0u;
    run.instance_count = 1u;
    run.base_vertex = i32(slot * round.counts.x);
    run.first_instance = 0u;
    for (var c = max(lo, g * VSM_CULL_GROUP); c < min(hi, g * VSM_CULL_GROUP + VSM_CULL_GROUP); c++) {
        let cl = clusters[c];
        var visible = group_visible;
        if (visible) {
            let sphere = cluster_bounds[c];
            if (frustum && (sphere_outside(view.view_proj, sphere) || beyond_receivers(view, row, sphere))) {
                visible = false;
            } else if ((bits & CULL_BACKFACE) != 0u && cl.first_triangle < round.counts.y
                && cluster_faces_away(cl, instances[cl.instance].normal, sphere, eye)) {
                visible = false;
            }
        }
        var cmd: DrawCommand;
        cmd.index_count = select(0u, 3u * cl.triangles, visible);
        cmd.instance_count = 1u;
        cmd.first_index = 3u * cl.first_triangle;
        cmd.base_vertex = i32(slot * round.counts.x);
        cmd.first_instance = 0u;
        if (compact) {
            if (visible) {
                if (run.index_count != 0u && run.first_index + run.index_count == cmd.first_index) {
                    run.index_count += cmd.index_count;
                } else {
                    if (run.index_count != 0u) {
                        commands[atomicAdd(&command_count, 1u)] = run;
                    }
                    run.first_index = cmd.first_index;
                    run.index_count = cmd.index_count;
                }
            }
        } else {
            commands[slot * round.round.w + (c - lo)] = cmd;
        }
        if (visible) {
            draws = draws + 1u;
            triangles = triangles + cl.triangles;
        }
    }
    if (run.index_count != 0u) {
        commands[atomicAdd(&command_count, 1u)] = run;
    }
    if (draws != 0u) {
        atomicAdd(&counters[14], draws);
        atomicAdd(&counters[15], triangles);
    }
}

// The row of a face's (or page's: the crop leaves rows z and w alone) projection whose dot
// product with a point is its distance key: w for perspective, z for orthographic
// (`ortho` = params.w), as vsm_common.wgsl's `VsmPoint::key`.
fn key_row(view_proj: mat4x4<f32>, ortho: f32) -> vec4<f32> {
    let r = select(3u, 2u, ortho > 0.5);
    return vec4<f32>(view_proj[0][r], view_proj[1][r], view_proj[2][r], view_proj[3][r]);
}

// Whether a caster sphere lies wholly beyond the page's farthest receiver (`params.x`, 0 =
// no bound): its depths then exceed every depth the page's samples compare against, so it
// can shadow none of them (the comparison is `receiver <= stored`).
fn beyond_receivers(view: ShadowViewData, row: vec4<f32>, sphere: vec4<f32>) -> bool {
    let bound = view.params.x;
    if (bound <= 0.0) {
        return false;
    }
    let nearest = dot(row, vec4<f32>(sphere.xyz, 1.0)) - sphere.w * length(row.xyz);
    return nearest > bound + 1e-4 * abs(bound) + 1e-6;
}

// ---- draw and clear (vertex) ----

@group(0) @binding(11) var<storage, read> world: array<vec4<f32>>;
// The corner buffer, read for its mask tail by the alpha-tested rounds (alpha_mask.wgsl).
@group(0) @binding(13) var<storage, read> corners: array<u32>;

@vertex
fn vs_draw(@builtin(vertex_index) v: u32) -> TileOut {
    let slot = v / round.counts.x;
    return draw(slot, v - slot * round.counts.x);
}

fn draw(slot: u32, vertex: u32) -> TileOut {
    let view = page_views[round.round.x + slot];
    return into_tile_of(view.view_proj * world[vertex], view.tile, 1.0 / f32(vsm.pool.x));
}

// Rounds of alpha-tested clusters, drawn with `fs_alpha`.
@vertex
fn vs_draw_masked(@builtin(vertex_index) v: u32) -> MaskedTileOut {
    let slot = v / round.counts.x;
    let vertex = v - slot * round.counts.x;
    return masked_tile_out(draw(slot, vertex), mask_tail(), vertex);
}

// Covers drawn page `i`'s tile at depth 1 (far), before its casters are drawn.
@vertex
fn vs_clear(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> @builtin(position) vec4<f32> {
    let tile = page_views[i].tile;
    var quad = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    let px = tile.xy + quad[v % 6u] * tile.z;
    let size = f32(vsm.pool.x);
    return vec4<f32>(px.x / size * 2.0 - 1.0, 1.0 - px.y / size * 2.0, 1.0, 1.0);
}
