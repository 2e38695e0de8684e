// Alpha-tested shadow casters (caster_layout.rs, manyshadows_scene::masks): whether a caster's
// surface exists at a point. Composed after common.wgsl into the shaders of every technique;
// each declares `corners: array<u32>`, the caster corner buffer, whose *mask tail* holds what
// is read here (caster_layout.rs `mask_tail`): per masked caster vertex its texture coordinate and
// material, per material a mask record, the coverage bits, and a header in the last 4 words.
// The lookup is the nearest texel of the wrapped coordinate at full resolution, the same
// arithmetic as `MaskSet::covered` in Rust (the CPU reference).

struct MaskTail {
    // Triangles from here on are alpha-tested.
    first_triangle: u32,
    // Caster vertices from here on belong to alpha-tested instances.
    first_vertex: u32,
    // Word where the per-vertex table starts (3 words per masked caster vertex).
    vertices: u32,
    // Word where the per-material records start (4 words each).
    records: u32,
}

fn mask_tail() -> MaskTail {
    let n = arrayLength(&corners);
    return MaskTail(corners[n - 4u], corners[n - 3u], corners[n - 2u], corners[n - 1u]);
}

// Texture coordinate of masked caster vertex `v`.
fn caster_uv(t: MaskTail, v: u32) -> vec2<f32> {
    let i = t.vertices + 3u * (v - t.first_vertex);
    return vec2<f32>(bitcast<f32>(corners[i]), bitcast<f32>(corners[i + 1u]));
}

// Material of masked caster vertex `v`.
fn caster_material(t: MaskTail, v: u32) -> u32 {
    return corners[t.vertices + 3u * (v - t.first_vertex) + 2u];
}

// True where `material`'s surface exists at `uv` (always for materials without a mask).
fn mask_covered(t: MaskTail, material: u32, uv: vec2<f32>) -> bool {
    let r = t.records + 4u * material;
    let flags = corners[r + 3u];
    if ((flags & 1u) == 0u) {
        return true;
    }
    let w = corners[r + 1u];
    let h = corners[r + 2u];
    let x = min(u32(wrap_coord(uv.x, (flags >> 1u) & 3u) * f32(w)), w - 1u);
    let y = min(u32(wrap_coord(uv.y, (flags >> 3u) & 3u) * f32(h)), h - 1u);
    let i = y * w + x;
    return ((corners[corners[r] + i / 32u] >> (i % 32u)) & 1u) != 0u;
}

// True where masked triangle `tri` (its caster corners) exists at barycentric weights `b`
// of its three corners.
fn triangle_covered(t: MaskTail, tri: u32, b: vec3<f32>) -> bool {
    let v0 = corners[3u * tri];
    let v1 = corners[3u * tri + 1u];
    let v2 = corners[3u * tri + 2u];
    let uv = b.x * caster_uv(t, v0) + b.y * caster_uv(t, v1) + b.z * caster_uv(t, v2);
    return mask_covered(t, caster_material(t, v0), uv);
}

// Perspective-correct barycentric weights of the point that projects to `ndc` (x, y) on the
// triangle with clip-space corners c0, c1, c2: the weights λ with Σλ·(c.xy − ndc·c.w) = 0 and
// Σλ = 1 (homogeneous rasterization, Olano and Greer 1997). Exact for orthographic views too.
fn clip_barycentrics(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, ndc: vec2<f32>) -> vec3<f32> {
    let a0 = c0.xy - ndc * c0.w;
    let a1 = c1.xy - ndc * c1.w;
    let a2 = c2.xy - ndc * c2.w;
    let l = vec3<f32>(a1.x * a2.y - a1.y * a2.x, a2.x * a0.y - a2.y * a0.x, a0.x * a1.y - a0.y * a1.x);
    let sum = l.x + l.y + l.z;
    return select(vec3<f32>(1.0 / 3.0), l / sum, sum != 0.0);
}

// What the fragment stage of an alpha-tested depth pipeline receives (each technique's vertex
// output carries these two locations besides its builtins).
struct MaskedFragment {
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
}

// The fragment stage of every alpha-tested depth pipeline: uncovered texels write no depth.
@fragment
fn fs_alpha(in: MaskedFragment) {
    if (!mask_covered(mask_tail(), in.material, in.uv)) {
        discard;
    }
}
