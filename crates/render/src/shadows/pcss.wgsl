// Soft shadows of sized lights: percentage-closer soft shadows (Fernando 2005). A blocker
// search averages the depth of the casters between the receiver and the light within the
// region the light can be seen through; the light's size and the two distances give the
// penumbra's radius in texels; a filter of that radius averages comparison taps. Taps lie on a
// Vogel disc (golden-angle spiral) turned by a per-pixel angle, so neighbouring pixels sample
// different directions. Every tap stays inside the view's tile or page.
//
// Taps are read through the source's lookup, in the coordinate's soft texel space
// (`ShadowCoord::soft`): `soft_tap_depth(c, t)` (raw depth) and `soft_tap_compare(c, t,
// depth)` (bilinearly weighted comparison); the atlas's go through the pass's
// `shadow_depth_at` and `shadow_compare_at`, virtual maps' find each tap's page. The lookup's
// `soft_coarser(c, k)` gives the coordinate `k` times halved in resolution where it can.
// Needs `frame: FrameUniforms` (`soft`: taps and the largest radius) and `ShadowCoord`.


// Distance from the light of a depth of the view (`lin`: near, far, texel size, projection):
// along the view's axis for a perspective view, from the view's origin plane for an
// orthographic one, from the light for a dual paraboloid (both linear in depth).
fn soft_distance(z: f32, lin: vec4<f32>) -> f32 {
    if (lin.w > 0.5) {
        return lin.x + z * (lin.y - lin.x);
    }
    return lin.x * lin.y / max(lin.y - z * (lin.y - lin.x), 1e-20);
}

// The depth of the view at distance `d` (the inverse of `soft_distance`).
fn soft_depth(d: f32, lin: vec4<f32>) -> f32 {
    if (lin.w > 0.5) {
        return (d - lin.x) / (lin.y - lin.x);
    }
    return lin.y * (d - lin.x) / (max(d, 1e-20) * (lin.y - lin.x));
}

// World size of one texel at distance `d`.
fn soft_texel_world(d: f32, lin: vec4<f32>) -> f32 {
    if (abs(lin.w - 1.0) < 0.5) {
        return lin.z;
    }
    return lin.z * d;
}

// Radius in texels over which a light of size `size` (radius, or tangent of half the angle
// of a directional light) blurs what a caster at distance `d_b` shadows at distance `d_r`.
fn soft_radius(size: f32, d_b: f32, d_r: f32, lin: vec4<f32>) -> f32 {
    if (abs(lin.w - 1.0) < 0.5) {
        return size * max(d_r - d_b, 0.0) / lin.z;
    }
    return size * max(1.0 / max(d_b, 1e-6) - 1.0 / max(d_r, 1e-6), 0.0) / lin.z;
}

// Tap `i` of `n` on the unit Vogel disc whose direction is `dir` (the first tap's, turned by
// the golden angle once per tap: see `vogel_next`).
fn vogel(i: u32, n: u32, dir: vec2<f32>) -> vec2<f32> {
    return sqrt((f32(i) + 0.5) / f32(n)) * dir;
}

// cos and sin of GOLDEN_ANGLE, and of 1 radian (the filter's taps turned from the search's).
const GOLDEN_TURN: vec2<f32> = vec2<f32>(-0.73736886, 0.67549032);
const ONE_RADIAN_TURN: vec2<f32> = vec2<f32>(0.54030231, 0.84147098);

// `dir` turned by the angle whose cosine and sine are `turn`: the next tap's direction by a
// complex product, where a cos and a sin a tap cost a software rasterizer more than the tap's
// own read.
fn vogel_next(dir: vec2<f32>, turn: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(dir.x * turn.x - dir.y * turn.y, dir.x * turn.y + dir.y * turn.x);
}

// The depth a tap `off` texels from the receiver compares against: the receiver's tangent
// plane there, moved one texel towards the light, so the receiver's own surface never
// shadows its filter; but never past the receiver's own depth (where the plane falls away
// from the light, that depth itself: the surface lies beyond it there). Whatever hides part
// of the light from the receiver lies on a segment from it to a point of the light, and a
// view's depth along such a segment never passes the receiver's (it is linear along the
// segment in the world for a perspective or orthographic view, and a distance from the light
// for a paraboloid; the light's points lie nearer than the receiver). So a caster beyond the
// receiver is no blocker, and the receiver's own depth bounds every comparison (what lets
// virtual maps bound a page at its samples' depth).
fn soft_reference(c: ShadowCoord, d_r: f32, off: vec2<f32>) -> f32 {
    let one = c.depth - soft_depth(max(d_r - soft_texel_world(d_r, c.lin), c.lin.x), c.lin);
    return min(c.depth + dot(c.grad, off) - one, c.depth);
}

// Fraction of a light of size `size` that reaches the receiver at `c` (0 in umbra, 1 lit);
// `rot` is the pixel's angle for the taps.
fn soft_shadow(size: f32, c: ShadowCoord, rot: f32) -> f32 {
    let d_r = soft_distance(c.depth, c.lin);
    let max_r = frame.soft.z;
    // Blockers can lie anywhere between the view's near plane and the receiver.
    let search = clamp(soft_radius(size, c.lin.x, d_r, c.lin), 1.0, max_r);
    let nb = u32(frame.soft.x);
    var sum = 0.0;
    var blockers = 0.0;
    let first = vec2<f32>(cos(rot), sin(rot));
    var dir = first;
    for (var i = 0u; i < nb; i = i + 1u) {
        let off = vogel(i, nb, dir) * search;
        dir = vogel_next(dir, GOLDEN_TURN);
        let t = floor(c.soft.xy + off) + vec2<f32>(0.5);
        let z = soft_tap_depth(c, t);
        if (z < soft_reference(c, d_r, t - c.soft.xy)) {
            sum = sum + soft_distance(z, c.lin);
            blockers = blockers + 1.0;
        }
    }
    if (blockers == 0.0) {
        return 1.0;
    }
    // A penumbra wider than the largest radius is filtered where the source has coarser
    // texels (virtual maps' coarser levels); the atlas has none and clamps it.
    var f = c;
    var radius = soft_radius(size, sum / blockers, d_r, c.lin);
    if (blockers == f32(nb) && radius <= search) {
        // Every tap of the search found a blocker, and the filter's disc lies within the
        // search's: the umbra (its taps would all be shadowed; skipping them cost nothing in
        // the error against the reference: docs/benchmarks.md, "What soft shadows cost:
        // `bench soft`").
        return 0.0;
    }
    if (radius > max_r) {
        f = soft_coarser(c, u32(ceil(log2(radius / max_r))));
        radius = radius * c.lin.z / f.lin.z;
    }
    radius = clamp(radius, 0.5, max_r);
    let nf = u32(frame.soft.y);
    var lit = 0.0;
    dir = vogel_next(first, ONE_RADIAN_TURN);
    for (var i = 0u; i < nf; i = i + 1u) {
        let off = vogel(i, nf, dir) * radius;
        dir = vogel_next(dir, GOLDEN_TURN);
        lit = lit + soft_tap_compare(f, f.soft.xy + off, soft_reference(f, d_r, off));
    }
    return lit / f32(nf);
}

// A pixel's shift of a sized light's sample grid for light `i` (shadow rays): hashed from the
// pixel, the light, the rays' seed and the frame's number where frames accumulate
// (`frame.modes.y`, 0 otherwise), so strata differ between neighbours and between the frames
// a denoiser accumulates.
fn soft_jitter(px_frame: vec2<i32>, i: u32) -> vec2<f32> {
    let px = eye_local(frame.eyes, px_frame);
    var h = soft_hash(u32(px.x) ^ soft_hash(u32(px.y) ^ soft_hash(i ^ soft_hash(ray_seed() + frame.modes.y))));
    let a = f32(h >> 8u) / 16777216.0;
    h = soft_hash(h);
    return vec2<f32>(a, f32(h >> 8u) / 16777216.0);
}

fn soft_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A pixel's angle for the taps: interleaved gradient noise (Jimenez 2014) of its position.
fn soft_rotation(px: vec2<i32>) -> f32 {
    let p = vec2<f32>(eye_local(frame.eyes, px));
    return 6.2831853 * fract(52.982919 * fract(0.06711056 * p.x + 0.00583715 * p.y));
}
