// Reflections from probes (maps.rs): each probe's six faces are layers 6·k .. 6·k + 5 of
// `probe_faces`, linear radiance, drawn through `Probe::face_cameras` (+X, −X, +Y, −Y, +Z,
// −Z; 90°, square). A surface mirrors the nearest probe's light along its reflected view
// ray, box-projected where the probe stands for a box.

struct ProbeData {
    // xyz: where the faces were seen from; w: the first layer (f32).
    position: vec4<f32>,
    // The box's corners; lo.w = 1 when there is a box (else the plain direction is used).
    box_lo: vec4<f32>,
    box_hi: vec4<f32>,
}

// A uniform, not storage (maps.rs says why).
struct ProbeList {
    // x: probes.
    count: vec4<u32>,
    items: array<ProbeData, 64>,
}

// Bindings (maps.rs `LIGHTING_BINDINGS`): `probe_faces`, `probe_sampler`, `probes: ProbeList`.

// The face cameras' forward and up directions, as `Probe::face_cameras` sets them.
fn probe_face_axes(face: u32) -> array<vec3<f32>, 2> {
    switch face {
        case 0u: { return array<vec3<f32>, 2>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, -1.0, 0.0)); }
        case 1u: { return array<vec3<f32>, 2>(vec3<f32>(-1.0, 0.0, 0.0), vec3<f32>(0.0, -1.0, 0.0)); }
        case 2u: { return array<vec3<f32>, 2>(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0)); }
        case 3u: { return array<vec3<f32>, 2>(vec3<f32>(0.0, -1.0, 0.0), vec3<f32>(0.0, 0.0, -1.0)); }
        case 4u: { return array<vec3<f32>, 2>(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, -1.0, 0.0)); }
        default: { return array<vec3<f32>, 2>(vec3<f32>(0.0, 0.0, -1.0), vec3<f32>(0.0, -1.0, 0.0)); }
    }
}

// Radiance probe `k` saw in direction `d` (not normalized): the face of `d`'s largest
// component, at the texel its camera projects `d` to.
fn probe_radiance(k: u32, d: vec3<f32>) -> vec3<f32> {
    let a = abs(d);
    var face = select(5u, 4u, d.z > 0.0);
    if (a.x >= a.y && a.x >= a.z) {
        face = select(1u, 0u, d.x > 0.0);
    } else if (a.y >= a.z) {
        face = select(3u, 2u, d.y > 0.0);
    }
    let axes = probe_face_axes(face);
    let f = axes[0];
    // look_at_rh's basis: right = normalize(f × up), up' = right × f.
    let r = normalize(cross(f, axes[1]));
    let u = cross(r, f);
    let z = dot(d, f);
    let ndc = vec2<f32>(dot(d, r), dot(d, u)) / z;
    let uv = vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
    let layer = u32(probes.items[k].position.w) + face;
    return textureSampleLevel(probe_faces, probe_sampler, uv, layer, 0.0).rgb;
}

// The probe nearest `p`.
fn nearest_probe(p: vec3<f32>) -> u32 {
    var best = 0u;
    var best_d = 3.4e38;
    let n = probes.count.x;
    for (var k = 0u; k < n; k = k + 1u) {
        let v = probes.items[k].position.xyz - p;
        let d = dot(v, v);
        if (d < best_d) {
            best_d = d;
            best = k;
        }
    }
    return best;
}

// Light the nearest probe saw along the reflection of the view direction `v` about `n` at
// `p`: where the probe has a box, the ray is followed to the box's wall and the probe looked
// up towards that point (parallax correction); else the direction alone.
fn probe_reflected(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let k = nearest_probe(p);
    let pr = probes.items[k];
    let r = reflect(-v, n);
    var dir = r;
    if (pr.box_lo.w > 0.5) {
        // Slabs: the far crossing of each axis; the nearest of those is where the ray leaves.
        let safe = select(r, vec3<f32>(1e-20), abs(r) < vec3<f32>(1e-20));
        let t1 = (pr.box_hi.xyz - p) / safe;
        let t2 = (pr.box_lo.xyz - p) / safe;
        let far = max(t1, t2);
        let t = min(min(far.x, far.y), far.z);
        if (t > 0.0) {
            dir = p + r * t - pr.position.xyz;
        }
    }
    return probe_radiance(k, dir);
}

// How much of the probe's light a surface mirrors towards `v` (Schlick's Fresnel from the
// reflectance at normal incidence `f0`).
fn probe_fresnel(f0: vec3<f32>, n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let c = 1.0 - clamp(dot(n, v), 0.0, 1.0);
    let c2 = c * c;
    return f0 + (vec3<f32>(1.0) - f0) * (c2 * c2 * c);
}
