// Virtual shadow maps (vsm.rs), rendering the resident pages: every page is an ordinary
// shadow view (the face's projection cropped to the page, one tile of the pool), so pages are
// drawn the `gpu-driven` way: a compute pass culls caster clusters against each page's
// frustum slice and writes indexed-indirect commands, one multi-draw renders the survivors
// into the pages' tiles. `page_views` lists this frame's pages to draw (kept pages are not in
// it); their count is known only on the GPU: cull dispatches are indirect, and rounds past
// the last page cull nothing.

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

// One thread per (cluster, page slot) of the round.
@compute @workgroup_size(64, 1, 1)
fn cs_cull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let local = gid.x;
    let slot = gid.y;
    if (local >= round.round.w || slot >= round.round.y) {
        return;
    }
    let page = round.round.x + slot;
    let c = round.round.z + local;
    let cl = clusters[c];
    let sphere = cluster_bounds[c];
    let bits = round.counts.z;
    // Slots past the last resident page draw nothing (only reached without compaction,
    // where every slot's command is written).
    var visible = page < atomicLoad(&counters[17]);
    let view = page_views[min(page, arrayLength(&page_views) - 1u)];
    if (visible && (bits & CULL_FRUSTUM) != 0u && sphere_outside(view.view_proj, sphere)) {
        visible = false;
    }
    if (visible && (bits & CULL_BACKFACE) != 0u && cl.first_triangle < round.counts.y
        && cluster_faces_away(cl, instances[cl.instance].normal, sphere, vsm_faces[bitcast<u32>(view.tile.w)].eye)) {
        visible = false;
    }
    if (visible) { atomicAdd(&counters[14], 1u); atomicAdd(&counters[15], cl.triangles); }
    var cmd: DrawCommand;
    cmd.index_count = select(0u, 3u * cl.triangles, visible);
    cmd.instance_count = 1u;
    cmd.first_index = 3u * cl.first_triangle;
    cmd.base_vertex = i32(slot * round.counts.x);
    cmd.first_instance = 0u;
    if (round.counts.w != 0u) {
        if (visible) {
            commands[atomicAdd(&command_count, 1u)] = cmd;
        }
    } else {
        commands[slot * round.round.w + local] = cmd;
    }
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
