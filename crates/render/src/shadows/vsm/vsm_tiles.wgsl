// Virtual shadow maps, page marking by tiles (tiles.rs, VirtualOptions::tile_marking; composed
// after vsm_table.wgsl and vsm_mark.wgsl, whose marking it hands its uncertain work to):
// cs_mark_tiles marks per tile, cs_mark_args sizes the hand-off, cs_mark_pixels does the
// jobs handed on, one thread per pixel.
//
// Most of a light's samples in a small patch of the screen need one and the same page, so the
// per-(pixel, light) work of cs_mark mostly repeats itself. cs_mark_tiles takes a tile of
// MARK_TILE² pixels per thread and bounds its samples: a box of positions, the range of view
// depths, a cone of normals. Per light of the tile's clusters it then shows one of:
// - TILE_NONE: no sample needs a page (the box out of the light's reach, cone or view, or
//   every normal facing away);
// - TILE_ALL: every sample needs the same page of the same level (in reach and facing, one
//   face, one level over the depth and distance ranges, one page under the projected box):
//   the page is marked once, with the box's receiver bounds, which hold every sample's (a
//   sized light: and the pages beside it that every sample's filter reaches, the same for
//   every sample);
// - TILE_SOME: as TILE_ALL, but some samples may be out of reach or face away;
// - TILE_UNSURE: nothing certain.
// TILE_SOME and TILE_UNSURE lights are handed on to cs_mark_pixels in one job per tile, one
// thread per pixel: it marks an unsure light exactly as cs_mark does (mark_light), and a
// TILE_SOME light's known page where the sample passes mark_light's reach and facing tests,
// with mark_light's receiver bounds (a sized light's: with the pages beside it that the
// sample's filter reaches, as mark_light marks them). A tile spread over too many clusters, or handing on more
// than JOB_LIGHTS lights, is handed on whole: cs_mark's loop over its pixels' clusters. So
// exactly the pages cs_mark asks for are asked.
//
// The page a sample needs: its level follows from the ratio of its pixel's footprint (view
// depth) to the face's texel (perspective: its clip w), both bounded over the box; its page
// from the face coordinates of the biased sample. The bias moves a sample towards the light
// (along its projection ray for a perspective face whose eye is the light, or along an
// orthographic face's axis: no move in face coordinates) and along its normal, by at most
// bias.z · bias scale texels, divided by 1 - (the move towards the light / the distance to
// it), which scales the clip position: the box grown by that much projects onto a rectangle
// holding every biased sample. The margins below are far above the rounding of either side.

// Pixels per side of a tile.
const MARK_TILE: u32 = 4u;
// Clusters a tile's samples may fall in before the whole tile is marked per pixel.
const TILE_CLUSTERS: u32 = 4u;
// A job's light flag: its page is known, each pixel checks only whether it needs it
// (TILE_SOME).
const PAGE_KNOWN: u32 = 0x80000000u;
// The proofs' margins: in log2 of the footprint / texel ratio, in face coordinates.
const LEVEL_MARGIN: f32 = 0.01;
const UV_MARGIN: f32 = 1e-5;
// tan θ at which receiver_offset_dir clamps the slope term.
const MAX_TAN: f32 = 10.0;
// Lights a tile hands on in one job (more, and it is handed on whole).
const JOB_LIGHTS: u32 = 16u;
// Where the whole tiles handed on start in `mark_list` (one word each: the first pixel).
const WHOLE_FIRST: u32 = 8u;

// A job of cs_mark_pixels: a tile and the lights it hands on, `2 + 3 n` words: the tile's
// first pixel (x | y << 16), n, then per light its index (| PAGE_KNOWN), and with PAGE_KNOWN
// the page's entry and face.
// `mark_list`: [0] job words used; [1, 4) (tile, light) pairs settled empty, marked for every
// sample, handed on with their page; [4] whole tiles handed on; [5] pairs handed on without
// their page (a whole tile counts once); [6] jobs; then from WHOLE_FIRST the whole tiles and
// the jobs' offsets (room for every tile of the screen in each), then the jobs' words, as many
// as fit (a tile whose job does not fit does it itself).
@group(0) @binding(16) var<storage, read_write> mark_list: array<atomic<u32>>;
// cs_mark_pixels' dispatch arguments (JOBS_PER_GROUP per workgroup, rows of 65,535).
@group(0) @binding(17) var<storage, read_write> mark_args: array<u32, 3>;

// Tiles of the screen (the room for whole tiles and for jobs).
fn screen_tiles() -> u32 {
    let size = vec2<u32>(frame.viewport.xy);
    return ((size.x + MARK_TILE - 1u) / MARK_TILE) * ((size.y + MARK_TILE - 1u) / MARK_TILE);
}

fn offsets_at() -> u32 {
    return WHOLE_FIRST + screen_tiles();
}

fn words_at() -> u32 {
    return WHOLE_FIRST + 2u * screen_tiles();
}

// What a tile's bounds show for a light (see above).
const TILE_NONE: u32 = 0u;
const TILE_ALL: u32 = 1u;
const TILE_SOME: u32 = 2u;
const TILE_UNSURE: u32 = 3u;

// Bounds of a tile's samples.
struct TileSamples {
    lo: vec3<f32>,
    hi: vec3<f32>,
    // View depth range.
    near: f32,
    far: f32,
    // Every normal lies within the cone of this axis and cosine (<= 0: no bound).
    axis: vec3<f32>,
    cos_cone: f32,
}

// A light's page for a tile (TILE_ALL, TILE_SOME): face, level, the page's cell, entry, and
// the rectangle of the tile's biased samples (face_rect, clamped).
struct TilePage {
    outcome: u32,
    face: u32,
    level: u32,
    page: vec2<u32>,
    entry: u32,
    uv_lo: vec2<f32>,
    uv_hi: vec2<f32>,
    // A sized light (its filter's reach asks pages beside), and the pages (column, row) its
    // samples' reach's corners fall in (TILE_ALL: every sample's the same).
    soft: bool,
    corners: array<vec2<u32>, 4>,
}

fn tile_outcome(outcome: u32) -> TilePage {
    var out: TilePage;
    out.outcome = outcome;
    return out;
}

// Where a box of samples falls in a face at `level`: the face coordinates of its biased
// samples (a rectangle, margins included, unclamped); not valid when the box reaches behind
// the face's eye or the bias could move samples too far to bound.
struct FaceRect {
    valid: bool,
    uv_lo: vec2<f32>,
    uv_hi: vec2<f32>,
}

fn face_rect(face: VirtualFace, level: u32, lo: vec3<f32>, hi: vec3<f32>) -> FaceRect {
    var out: FaceRect;
    out.valid = false;
    let m = face.view_proj;
    let c = 0.5 * (lo + hi);
    let e = 0.5 * (hi - lo);
    let scale = f32(1u << (face.table.y - level));
    // The largest texel of the level over the box.
    var texel = face.params.z * scale;
    // How far the bias moves a sample: towards the light by texel · (b.x + tan · b.y),
    // tan <= MAX_TAN, which scales a perspective face's clip position by 1 - (that / the
    // distance), at least kappa; along the normal by texel · b.z.
    let b = abs(frame.bias.xyz) * (vsm.lod.w * vsm_bias_factor(face, level));
    var kappa = 1.0;
    if (face.params.w < 0.5) {
        let w = dot(vec4<f32>(m[0][3], m[1][3], m[2][3], m[3][3]), vec4<f32>(c, 1.0))
            + dot(abs(vec3<f32>(m[0][3], m[1][3], m[2][3])), e);
        texel = texel * max(w, 0.0) * (1.0 + 1e-5);
        kappa = 1.0 - face.params.z * scale * (b.x + MAX_TAN * b.y) * (1.0 + 1e-5);
        if (kappa < 0.5) {
            return out;
        }
    }
    let grow = texel * b.z / kappa * (1.0 + 1e-4);
    // The grown box's corners: its centre's clip position plus or minus each axis's half
    // extent times the matrix's column.
    let g = e + vec3<f32>(grow);
    let cc = m * vec4<f32>(c, 1.0);
    let ax = m[0] * g.x;
    let ay = m[1] * g.y;
    let az = m[2] * g.z;
    out.uv_lo = vec2<f32>(3.0e38);
    out.uv_hi = vec2<f32>(-3.0e38);
    var w_min = 3.0e38;
    for (var j = 0u; j < 8u; j = j + 1u) {
        let sign = vec3<f32>(select(-1.0, 1.0, (j & 1u) != 0u), select(-1.0, 1.0, (j & 2u) != 0u), select(-1.0, 1.0, (j & 4u) != 0u));
        let clip = cc + sign.x * ax + sign.y * ay + sign.z * az;
        if (clip.w <= 0.0) {
            return out;
        }
        let uv = clip.xy / clip.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
        out.uv_lo = min(out.uv_lo, uv);
        out.uv_hi = max(out.uv_hi, uv);
        w_min = min(w_min, clip.w);
    }
    // A sample's own clip position rounds by a few ulps of its terms, which grow with its
    // distance from the world's origin: the margin grows with them.
    let mag = vec4<f32>(abs(c) + g, 1.0);
    let terms = dot(abs(vec4<f32>(m[0][0], m[1][0], m[2][0], m[3][0])), mag)
        + dot(abs(vec4<f32>(m[0][1], m[1][1], m[2][1], m[3][1])), mag)
        + 2.0 * dot(abs(vec4<f32>(m[0][3], m[1][3], m[2][3], m[3][3])), mag);
    let margin = UV_MARGIN + 2e-6 * terms / w_min;
    out.uv_lo = out.uv_lo - vec2<f32>(margin);
    out.uv_hi = out.uv_hi + vec2<f32>(margin);
    out.valid = true;
    return out;
}

// Light `i` over the tile's samples `t` (see above).
fn tile_light(i: u32, t: TileSamples) -> TilePage {
    let light = lights[i];
    if (light.shadow.y == 0u) {
        return tile_outcome(TILE_NONE);
    }
    let c = 0.5 * (t.lo + t.hi);
    let e = 0.5 * (t.hi - t.lo);
    let radius = length(e);
    let kind = light.shadow.z;
    // Whether every sample surely reaches the light and faces it.
    var every = true;
    // Unit direction from the box's centre to the light, and the sine and cosine of the box's
    // angular radius seen from the light.
    var u = -light.direction.xyz;
    var sin_b = 0.0;
    var cos_b = 1.0;
    // The cosine margin of the angle tests: 1e-4, plus the angle a sample's rounded offset from
    // the light may be off by far from the world's origin.
    var cos_margin = 1e-4;
    if (kind != LIGHT_DIRECTIONAL) {
        let to = light.position.xyz - c;
        let dist = length(to);
        let range = light.ambient.w;
        // How far a sample's offset from the light may round: a few ulps of the coordinates.
        let slack = 2e-6 * (length(abs(c) + e) + length(light.position.xyz));
        // The box's nearest point beyond the range: every sample is; its farthest: none is.
        if (length(max(abs(to) - e, vec3<f32>(0.0))) > range * (1.0 + 1e-4) + slack) {
            return tile_outcome(TILE_NONE);
        }
        every = length(abs(to) + e) < range * (1.0 - 1e-4) - slack;
        if (dist <= radius * 1.001 + 1e-6 + 2.0 * slack) {
            return tile_outcome(TILE_UNSURE);
        }
        cos_margin = 1e-4 + slack / dist;
        u = to / dist;
        sin_b = radius / dist;
        cos_b = sqrt(max(1.0 - sin_b * sin_b, 0.0));
        if (kind == LIGHT_SPOT) {
            // Outside the cone: the axis and the direction to the box's centre further apart
            // than the cutoff plus the box's radius; inside: closer than the cutoff less it.
            let cos_c = light.direction.w;
            let sin_c = sqrt(max(1.0 - cos_c * cos_c, 0.0));
            let cos_axis = dot(light.direction.xyz, -u);
            if (sin_c * cos_b + cos_c * sin_b > 0.0 && cos_axis < cos_c * cos_b - sin_c * sin_b - cos_margin) {
                return tile_outcome(TILE_NONE);
            }
            every = every && sin_c * cos_b - cos_c * sin_b > 0.0
                && cos_axis > cos_c * cos_b + sin_c * sin_b + cos_margin;
        }
    }
    if (vsm.counts.z == 0u) {
        // Facing away: the normal cone's axis and the direction to the light further apart
        // than 90° plus both cones' radii; facing: closer than 90° less them.
        if (t.cos_cone > 0.0) {
            let sin_n = sqrt(max(1.0 - t.cos_cone * t.cos_cone, 0.0));
            let cos_sum = cos_b * t.cos_cone - sin_b * sin_n;
            let sin_sum = sin_b * t.cos_cone + cos_b * sin_n;
            let cos_axis = dot(t.axis, u);
            if (cos_sum > 0.0 && cos_axis < -sin_sum - cos_margin) {
                return tile_outcome(TILE_NONE);
            }
            every = every && cos_sum > 0.0 && cos_axis > sin_sum + cos_margin;
        } else {
            every = false;
        }
    }
    // One face for every sample: a cube face's region (like a spot's or a cascade's) is
    // convex, so the box's corners decide; cascades by the depth range.
    var fi = -1;
    if (kind == LIGHT_POINT) {
        fi = select_shadow_view(light, t.lo, t.near);
        for (var k = 1u; k < 8u; k = k + 1u) {
            let corner = select(t.lo, t.hi, vec3<bool>((k & 1u) != 0u, (k & 2u) != 0u, (k & 4u) != 0u));
            if (select_shadow_view(light, corner, t.near) != fi) {
                return tile_outcome(TILE_UNSURE);
            }
        }
    } else {
        fi = select_shadow_view(light, c, t.near);
        if (select_shadow_view(light, c, t.far) != fi) {
            return tile_outcome(TILE_UNSURE);
        }
    }
    if (fi < 0) {
        return tile_outcome(TILE_NONE);
    }
    let face = vsm_faces[fi];
    let finest = face.table.y;
    // The level: vsm_level's ratio of footprint to finest texel, over the tile.
    let w_row = vec4<f32>(face.view_proj[0][3], face.view_proj[1][3], face.view_proj[2][3], face.view_proj[3][3]);
    let w_c = dot(w_row.xyz, c) + w_row.w;
    // The box's extent along the row, and how far a sample's rounded w may be off.
    let w_e = dot(abs(w_row.xyz), e) + 2e-6 * (dot(abs(w_row.xyz), abs(c) + e) + abs(w_row.w));
    var tex_lo = face.params.z;
    var tex_hi = face.params.z;
    if (face.params.w < 0.5) {
        let w_lo = (w_c - w_e) * (1.0 - 1e-5);
        if (w_lo <= 1e-6 * (abs(w_c) + w_e)) {
            return tile_outcome(TILE_UNSURE);
        }
        tex_lo = tex_lo * w_lo;
        tex_hi = tex_hi * (w_c + w_e) * (1.0 + 1e-5);
    }
    let footprint = frame.bias.w / max(face.detail.x, 1e-6);
    let k_lo = floor(log2(max(t.near * footprint, 1e-30) / max(tex_hi, 1e-30)) - LEVEL_MARGIN);
    let k_hi = floor(log2(max(t.far * footprint, 1e-30) / max(tex_lo, 1e-30)) + LEVEL_MARGIN);
    let steps = clamp(k_lo, 0.0, f32(finest));
    if (clamp(k_hi, 0.0, f32(finest)) != steps) {
        return tile_outcome(TILE_UNSURE);
    }
    let level = vsm_floor(face, finest - u32(steps));
    let r = face_rect(face, level, t.lo, t.hi);
    if (!r.valid) {
        return tile_outcome(TILE_UNSURE);
    }
    if (kind != LIGHT_POINT) {
        if (any(r.uv_hi < vec2<f32>(0.0)) || any(r.uv_lo > vec2<f32>(1.0))) {
            // Outside a spot's or a cascade's view: no sample has shadow information there.
            return tile_outcome(TILE_NONE);
        }
        if (any(r.uv_lo <= vec2<f32>(0.0)) || any(r.uv_hi >= vec2<f32>(1.0))) {
            // Some samples may fall outside the view: only per pixel can tell.
            return tile_outcome(TILE_UNSURE);
        }
    }
    let pages = 1u << level;
    let uv_lo = clamp(r.uv_lo, vec2<f32>(0.0), vec2<f32>(1.0));
    let page = page_at(uv_lo, pages);
    let last = page_at(clamp(r.uv_hi, vec2<f32>(0.0), vec2<f32>(1.0)), pages);
    if (any(last != page)) {
        return tile_outcome(TILE_UNSURE);
    }
    var out = tile_outcome(select(TILE_SOME, TILE_ALL, every));
    out.face = u32(fi);
    out.level = level;
    out.page = page;
    out.entry = vsm_entry(face, level, uv_lo);
    out.uv_lo = uv_lo;
    out.uv_hi = clamp(r.uv_hi, vec2<f32>(0.0), vec2<f32>(1.0));
    out.soft = light.diffuse.w > 0.0;
    if (out.soft) {
        // A sized light's sample also asks the pages of the four corners of the square its
        // filter's taps reach (vsm_mark.wgsl's mark_soft). The tile marks them once only
        // where each corner falls in one page for every sample (a page border seldom lies
        // within the tile's few texels of a corner's path); else each sample marks its own
        // with the tile's page known.
        for (var k = 0u; k < 4u; k = k + 1u) {
            let a = page_at(reach_corner(r.uv_lo, level, k), pages);
            let b = page_at(reach_corner(r.uv_hi, level, k), pages);
            out.corners[k] = a;
            if (any(a != b)) {
                out.outcome = TILE_SOME;
            }
        }
    }
    return out;
}

// The page (column, row) of `pages` per side holding face coordinates `uv` (in the face), as
// vsm_entry finds it.
fn page_at(uv: vec2<f32>, pages: u32) -> vec2<u32> {
    return min(vec2<u32>(uv * f32(pages)), vec2<u32>(pages - 1u));
}

// The cells the filter taps of the tile's samples reach in its page (`page`: its own or, for
// a sized light, one beside it that its reach's corners fall in).
fn tile_cells(q: TilePage, page: vec2<u32>) -> u32 {
    let pages = f32(1u << q.level);
    let at = vec2<f32>(page);
    let side = f32(vsm.pool.z);
    let reach = select(TAP_REACH, frame.soft.z + 1.0, q.soft);
    return cells_reached((q.uv_lo * pages - at) * side, (q.uv_hi * pages - at) * side, reach);
}

// The farthest depth key of a biased sample in the box of centre `c` and half extent `e` at
// `level` of `face`: the box's, plus the bias's move along the key's row (a move towards the
// light only lowers it when the slope term cannot be negative: then the normal term alone
// counts).
fn box_key(face: VirtualFace, level: u32, c: vec3<f32>, e: vec3<f32>) -> u32 {
    let m = face.view_proj;
    let persp = face.params.w < 0.5;
    let row = select(vec4<f32>(m[0][2], m[1][2], m[2][2], m[3][2]), vec4<f32>(m[0][3], m[1][3], m[2][3], m[3][3]), persp);
    var texel = face.params.z * f32(1u << (face.table.y - level));
    if (persp) {
        texel = texel * max(dot(row.xyz, c) + row.w + dot(abs(row.xyz), e), 0.0);
    }
    let b = abs(frame.bias.xyz) * (vsm.lod.w * vsm_bias_factor(face, level));
    let toward = min(frame.bias.x, frame.bias.x + MAX_TAN * frame.bias.y);
    let moved = texel * (1.0 + 1e-5) * select(b.x + MAX_TAN * b.y + b.z, b.z, toward >= 0.0);
    // (With a few ulps of the terms for the samples' own rounding.)
    let key = (dot(row.xyz, c) + row.w + dot(abs(row.xyz), e) + length(row.xyz) * moved) * (1.0 + 1e-5)
        + 2e-6 * (dot(abs(row.xyz), abs(c) + e) + abs(row.w)) + 1e-30;
    return bitcast<u32>(max(key, 0.0));
}

// Marks a tile's page every sample of the tile (in the box `lo`..`hi`) needs, with the
// tile's receiver bounds; for a sized light also the pages beside it its samples' filters
// reach.
fn mark_tile_page(q: TilePage, lo: vec3<f32>, hi: vec3<f32>) {
    let face = vsm_faces[q.face];
    let key = box_key(face, q.level, 0.5 * (lo + hi), 0.5 * (hi - lo));
    if (vsm.counts.w != 0u) {
        bound_page(q.entry, key, tile_cells(q, q.page));
    }
    let pages = 1u << q.level;
    ask_page(face, q.level, (vec2<f32>(q.page) + vec2<f32>(0.5)) / f32(pages), q.entry);
    if (!q.soft) {
        return;
    }
    for (var k = 0u; k < 4u; k = k + 1u) {
        let c = q.corners[k];
        var seen = all(c == q.page);
        for (var j = 0u; j < k; j = j + 1u) {
            seen = seen || all(c == q.corners[j]);
        }
        if (seen) {
            continue;
        }
        let uv = (vec2<f32>(c) + vec2<f32>(0.5)) / f32(pages);
        let e = vsm_entry(face, q.level, uv);
        if (vsm.counts.w != 0u) {
            bound_page(e, key, tile_cells(q, c));
        }
        ask_page(face, q.level, uv, e);
    }
}

// A tile's account of its lights.
struct Handoffs {
    // Lights per outcome of tile_light.
    seen: array<u32, 4>,
    // The lights handed on (| PAGE_KNOWN) and, with PAGE_KNOWN, their pages' entries and faces.
    lights: array<u32, JOB_LIGHTS>,
    entries: array<u32, JOB_LIGHTS>,
    faces: array<u32, JOB_LIGHTS>,
    count: u32,
    // Too many: the tile is handed on whole.
    whole: bool,
}

fn visit_tile_light(i: u32, t: TileSamples, h: ptr<function, Handoffs>) {
    let q = tile_light(i, t);
    (*h).seen[q.outcome] = (*h).seen[q.outcome] + 1u;
    if (q.outcome == TILE_NONE) {
        return;
    }
    if (q.outcome == TILE_ALL) {
        mark_tile_page(q, t.lo, t.hi);
        return;
    }
    let k = (*h).count;
    if (k == JOB_LIGHTS) {
        (*h).whole = true;
        return;
    }
    (*h).lights[k] = select(i, i | PAGE_KNOWN, q.outcome == TILE_SOME);
    (*h).entries[k] = q.entry;
    (*h).faces[k] = q.face;
    (*h).count = k + 1u;
}

// Hands the tile's lights on as one job; false when the jobs' room is full.
fn hand_on(origin: vec2<u32>, h: Handoffs) -> bool {
    let words = 2u + 3u * h.count;
    let at = atomicAdd(&mark_list[0], words);
    if (words_at() + at + words > arrayLength(&mark_list)) {
        return false;
    }
    let w = words_at() + at;
    atomicStore(&mark_list[w], origin.x | (origin.y << 16u));
    atomicStore(&mark_list[w + 1u], h.count);
    for (var k = 0u; k < h.count; k = k + 1u) {
        atomicStore(&mark_list[w + 2u + 3u * k], h.lights[k]);
        atomicStore(&mark_list[w + 3u + 3u * k], h.entries[k]);
        atomicStore(&mark_list[w + 4u + 3u * k], h.faces[k]);
    }
    let j = atomicAdd(&mark_list[6], 1u);
    atomicStore(&mark_list[offsets_at() + j], at);
    return true;
}

fn hand_on_whole(origin: vec2<u32>) {
    let k = atomicAdd(&mark_list[4], 1u);
    if (k < screen_tiles()) {
        atomicStore(&mark_list[WHOLE_FIRST + k], origin.x | (origin.y << 16u));
    }
}

@compute @workgroup_size(8, 8, 1)
fn cs_mark_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    let origin = vec2<u32>(vsm.lod.yz) + id.xy * MARK_TILE;
    if (any(origin >= vec2<u32>(frame.viewport.xy))) {
        return;
    }
    var t: TileSamples;
    t.lo = vec3<f32>(3.0e38);
    t.hi = vec3<f32>(-3.0e38);
    t.near = 3.0e38;
    t.far = 0.0;
    var n_lo = vec3<f32>(1.0);
    var n_hi = vec3<f32>(-1.0);
    var slots: array<u32, TILE_CLUSTERS>;
    var used = 0u;
    var spread = false;
    for (var y = 0u; y < MARK_TILE; y = y + 1u) {
        for (var x = 0u; x < MARK_TILE; x = x + 1u) {
            let s = pixel_sample(origin + vec2<u32>(x, y));
            if (!s.valid) {
                continue;
            }
            let view_depth = s.view_depth;
            // A NaN would drop out of min and max: such a tile is marked per pixel.
            spread = spread || any(s.p != s.p) || any(s.n != s.n);
            t.lo = min(t.lo, s.p);
            t.hi = max(t.hi, s.p);
            t.near = min(t.near, view_depth);
            t.far = max(t.far, view_depth);
            n_lo = min(n_lo, s.n);
            n_hi = max(n_hi, s.n);
            let slot = pixel_slot(origin + vec2<u32>(x, y), view_depth);
            var known = false;
            for (var k = 0u; k < used; k = k + 1u) {
                known = known || slots[k] == slot;
            }
            if (!known) {
                if (used < TILE_CLUSTERS) {
                    slots[used] = slot;
                    used = used + 1u;
                } else {
                    spread = true;
                }
            }
        }
    }
    if (used == 0u) {
        return;
    }
    if (spread || any(t.hi - t.lo != t.hi - t.lo)) {
        hand_on_whole(origin);
        atomicAdd(&mark_list[5], 1u);
        return;
    }
    // A few ulps more on each side: the box's centre and half extent, as the tests compute
    // them, round.
    let pad = 1e-6 * max(abs(t.lo), abs(t.hi));
    t.lo = t.lo - pad;
    t.hi = t.hi + pad;
    // The normal cone: around the normal box's centre direction, with the least cosine of the
    // box (a linear function's minimum over the box) as its bound.
    let nc = 0.5 * (n_lo + n_hi);
    t.cos_cone = 0.0;
    t.axis = vec3<f32>(0.0, 0.0, 1.0);
    if (length(nc) > 1e-3) {
        t.axis = normalize(nc);
        t.cos_cone = dot(nc, t.axis) - dot(abs(t.axis), 0.5 * (n_hi - n_lo)) - 1e-5;
    }
    var h: Handoffs;
    var every = false;
    for (var k = 0u; k < used; k = k + 1u) {
        every = every || every_light(slots[k]);
    }
    if (every) {
        for (var i = 0u; i < frame.counts.x && !h.whole; i = i + 1u) {
            visit_tile_light(i, t, &h);
        }
    } else {
        for (var k = 0u; k < used && !h.whole; k = k + 1u) {
            let base = (slots[k] - CLUSTER_FIRST_SLOT) * clusters.words.z;
            for (var sw = 0u; sw < clusters.words.x && !h.whole; sw = sw + 1u) {
                var words = cluster_masks[base + sw];
                while (words != 0u && !h.whole) {
                    let w = sw * 32u + firstTrailingBit(words);
                    words = words & (words - 1u);
                    var bits = cluster_masks[base + clusters.words.x + w];
                    while (bits != 0u && !h.whole) {
                        let i = w * 32u + firstTrailingBit(bits);
                        bits = bits & (bits - 1u);
                        // Once per light: the first of the tile's clusters that lists it.
                        var listed = false;
                        for (var j = 0u; j < k; j = j + 1u) {
                            listed = listed || slot_has(slots[j], i);
                        }
                        if (!listed) {
                            visit_tile_light(i, t, &h);
                        }
                    }
                }
            }
        }
    }
    for (var k = 0u; k < 3u; k = k + 1u) {
        if (h.seen[k] != 0u) {
            atomicAdd(&mark_list[1u + k], h.seen[k]);
        }
    }
    if (h.whole) {
        hand_on_whole(origin);
        atomicAdd(&mark_list[5], 1u);
        return;
    }
    if (h.count == 0u) {
        return;
    }
    var unsure = 0u;
    for (var k = 0u; k < h.count; k = k + 1u) {
        unsure = unsure + select(1u, 0u, (h.lights[k] & PAGE_KNOWN) != 0u);
    }
    atomicAdd(&mark_list[5], unsure);
    if (!hand_on(origin, h)) {
        // No room left for the job (rare: which tiles find room depends on thread order, so
        // the counts above do not): the thread does it, the same work.
        for (var y = 0u; y < MARK_TILE; y = y + 1u) {
            for (var x = 0u; x < MARK_TILE; x = x + 1u) {
                let s = pixel_sample(origin + vec2<u32>(x, y));
                if (!s.valid) {
                    continue;
                }
                for (var k = 0u; k < h.count; k = k + 1u) {
                    mark_job_light(h.lights[k], h.entries[k], h.faces[k], s.p, s.n, s.view_depth);
                }
            }
        }
    }
}

// A job's light for the sample at `p` (normal `n`): an unsure light marked as cs_mark marks
// it; a known page (PAGE_KNOWN, its entry `e` of face `fi`) marked if the sample reaches and
// faces the light (mark_light's first tests: its level and page are then the tile's, what
// mark_light would compute), with the receiver bounds mark_light computes.
fn mark_job_light(light: u32, e: u32, fi: u32, p: vec3<f32>, n: vec3<f32>, view_depth: f32) {
    if ((light & PAGE_KNOWN) == 0u) {
        mark_light(light, p, n, view_depth);
        return;
    }
    let l = lights[light & ~PAGE_KNOWN];
    if (!in_reach(l, p) || (vsm.counts.z == 0u && dot(n, to_light(l, p)) <= 0.0)) {
        return;
    }
    let face = vsm_faces[fi];
    if (l.diffuse.w > 0.0) {
        let level = level_of(e - face.table.x);
        mark_soft(face, level, vsm_project(l, face, vsm_ray(l, face, p, n), level), e);
        return;
    }
    if (vsm.counts.w != 0u) {
        let level = level_of(e - face.table.x);
        let q = vsm_project(l, face, vsm_ray(l, face, p, n), level);
        bound_page(e, bitcast<u32>(max(q.key, 0.0)), tap_cells(q.uv, level));
    }
    ask_entry(face, e);
}

// Jobs of cs_mark_pixels per workgroup (one thread per pixel of each).
const JOBS_PER_GROUP: u32 = 64u / (MARK_TILE * MARK_TILE);

// The jobs and whole tiles handed on, JOBS_PER_GROUP per workgroup, one thread per pixel of
// each (several jobs per workgroup: a software driver such as lavapipe pays per workgroup).
@compute @workgroup_size(64, 1, 1)
fn cs_mark_pixels(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    var k = (wg.x + wg.y * groups.x) * JOBS_PER_GROUP + local / (MARK_TILE * MARK_TILE);
    let pixel = local % (MARK_TILE * MARK_TILE);
    let offset = vec2<u32>(pixel % MARK_TILE, pixel / MARK_TILE);
    let jobs = min(atomicLoad(&mark_list[6]), screen_tiles());
    if (k >= jobs) {
        k = k - jobs;
        if (k < min(atomicLoad(&mark_list[4]), screen_tiles())) {
            let at = atomicLoad(&mark_list[WHOLE_FIRST + k]);
            mark_pixel(vec2<u32>(at & 0xffffu, at >> 16u) + offset, ALL_LIGHTS);
        }
        return;
    }
    let w = words_at() + atomicLoad(&mark_list[offsets_at() + k]);
    let first = atomicLoad(&mark_list[w]);
    let s = pixel_sample(vec2<u32>(first & 0xffffu, first >> 16u) + offset);
    if (!s.valid) {
        return;
    }
    let count = atomicLoad(&mark_list[w + 1u]);
    for (var j = 0u; j < count; j = j + 1u) {
        let at = w + 2u + 3u * j;
        mark_job_light(atomicLoad(&mark_list[at]), atomicLoad(&mark_list[at + 1u]), atomicLoad(&mark_list[at + 2u]), s.p, s.n, s.view_depth);
    }
}

@compute @workgroup_size(1, 1, 1)
fn cs_mark_args() {
    let n = min(atomicLoad(&mark_list[6]), screen_tiles()) + min(atomicLoad(&mark_list[4]), screen_tiles());
    // The stats (VirtualStats::tiles): pairs settled empty, marked once, handed on with their
    // page, marked per pixel; tiles marked per pixel whole.
    for (var k = 0u; k < 3u; k = k + 1u) {
        atomicStore(&counters[COUNT_TILES + k], atomicLoad(&mark_list[1u + k]));
    }
    atomicStore(&counters[COUNT_TILES + 3u], atomicLoad(&mark_list[5]));
    atomicStore(&counters[COUNT_TILES + 4u], min(atomicLoad(&mark_list[4]), screen_tiles()));
    let g = (n + JOBS_PER_GROUP - 1u) / JOBS_PER_GROUP;
    mark_args[0] = min(g, 65535u);
    mark_args[1] = (g + 65534u) / 65535u;
    mark_args[2] = 1u;
}
