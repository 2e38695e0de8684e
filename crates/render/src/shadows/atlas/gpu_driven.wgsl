// `gpu-driven` (seed 002's route): a compute pass culls triangle clusters per view and writes
// indexed-indirect draw commands; one multi-draw renders the survivors into every listed
// view's atlas tile.
//
// The view is encoded without first_instance (OpenGL's support for it is shaky): a command for
// the view in batch slot s has base_vertex = s * V (V = caster vertices), so the vertex shader
// sees vertex_index = caster vertex + s * V and recovers both.

struct GpuParams {
    // caster vertices V, cullable triangles, cull bits, clusters in this round
    counts: vec4<u32>,
    // first draw-list entry of this round, views in this round, first cluster of this round,
    // 1 = compact the commands with an atomic counter (else one fixed slot per command)
    round: vec4<u32>,
    // atlas side in texels, its reciprocal, unused, unused
    atlas: vec4<f32>,
}

@group(0) @binding(0) var<uniform> gparams: GpuParams;
@group(0) @binding(1) var<storage, read> views: array<ShadowViewData>;
@group(0) @binding(2) var<storage, read> draw_list: array<u32>;

// ---- cull (compute) ----

@group(0) @binding(3) var<storage, read> eyes: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> clusters: array<GpuCluster>;
@group(0) @binding(5) var<storage, read> cluster_bounds: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> instances: array<InstanceData>;
@group(0) @binding(7) var<storage, read_write> commands: array<DrawCommand>;
@group(0) @binding(8) var<storage, read_write> command_count: atomic<u32>;

// One thread per (cluster, view): x = cluster of this round, y = view slot of this round.
@compute @workgroup_size(64, 1, 1)
fn cs_cull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let local = gid.x;
    let slot = gid.y;
    if (local >= gparams.counts.w || slot >= gparams.round.y) {
        return;
    }
    let c = gparams.round.z + local;
    let view_id = draw_list[gparams.round.x + slot];
    let cl = clusters[c];
    let sphere = cluster_bounds[c];
    let bits = gparams.counts.z;
    var visible = true;
    if ((bits & CULL_FRUSTUM) != 0u && sphere_outside(views[view_id].view_proj, sphere)) {
        visible = false;
    }
    // Clusters never straddle the cullable range (caster_layout.rs builds them per class).
    if (visible && (bits & CULL_BACKFACE) != 0u && cl.first_triangle < gparams.counts.y
        && cluster_faces_away(cl, instances[cl.instance].normal, sphere, eyes[view_id])) {
        visible = false;
    }
    var cmd: DrawCommand;
    cmd.index_count = select(0u, 3u * cl.triangles, visible);
    cmd.instance_count = 1u;
    cmd.first_index = 3u * cl.first_triangle;
    cmd.base_vertex = i32(slot * gparams.counts.x);
    cmd.first_instance = 0u;
    if (gparams.round.w != 0u) {
        if (visible) {
            commands[atomicAdd(&command_count, 1u)] = cmd;
        }
    } else {
        commands[slot * gparams.counts.w + local] = cmd;
    }
}

// ---- draw (vertex) ----

@group(0) @binding(9) var<storage, read> world: array<vec4<f32>>;
// The corner buffer, read for its mask tail by the alpha-tested rounds (alpha_mask.wgsl).
@group(0) @binding(10) var<storage, read> corners: array<u32>;

@vertex
fn vs_draw(@builtin(vertex_index) v: u32) -> TileOut {
    let slot = v / gparams.counts.x;
    return draw(slot, v - slot * gparams.counts.x);
}

fn draw(slot: u32, vertex: u32) -> TileOut {
    let view = views[draw_list[gparams.round.x + slot]];
    return into_tile_of(view.view_proj * world[vertex], view.tile, gparams.atlas.y);
}

// Rounds of alpha-tested clusters (they never share a round with opaque ones), drawn with
// `fs_alpha`.
@vertex
fn vs_draw_masked(@builtin(vertex_index) v: u32) -> MaskedTileOut {
    let slot = v / gparams.counts.x;
    let vertex = v - slot * gparams.counts.x;
    return masked_tile_out(draw(slot, vertex), mask_tail(), vertex);
}
