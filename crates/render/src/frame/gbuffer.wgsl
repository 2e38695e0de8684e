// G-buffer pass: world position and normal + material of the nearest surface per pixel.

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> instances: array<InstanceData>;
@group(0) @binding(2) var<storage, read> materials: array<MaterialData>;
// The scene's images (textures.rs): base colours (sRGB, so samples are linear), and normal and
// metallic-roughness maps (linear data), one layer each, every layer the same side; wrap
// modes are applied here, not by the sampler.
@group(0) @binding(3) var colour_tex: texture_2d_array<f32>;
@group(0) @binding(4) var normal_tex: texture_2d_array<f32>;
@group(0) @binding(5) var tex_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    @location(3) uv: vec2<f32>,
    // The eye this copy of the triangle is drawn for (frame/eyes.rs; 0 when mono).
    @location(4) @interpolate(flat) eye: u32,
}

// The same with the scene instance drawn, which the `_moving` entry points keep per pixel
// (sampled/motion.rs): one camera only (`vs_moving`); and where the point was last frame
// before its instance moved, as an offset in this frame's world (zero unless its mesh bent).
struct MovingVsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    @location(3) uv: vec2<f32>,
    @location(4) @interpolate(flat) eye: u32,
    @location(5) @interpolate(flat) instance: u32,
    @location(6) bent: vec3<f32>,
}

fn without_instance(v: MovingVsOut) -> VsOut {
    return VsOut(v.clip, v.world, v.normal, v.material, v.uv, v.eye);
}

// Instance `instance` of a draw is scene instance `instance / eyes`, seen by eye
// `instance % eyes` (one eye per pass: each pass draws its eye's copies; layered: both).
@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
) -> VsOut {
    let eyes = max(u32(frame.eyes.y), 1u);
    return surface_vertex(position, normal, uv, instance / eyes, instance % eyes);
}

// One camera, the instance drawn kept (`MovingVsOut`), and the vertex's position last frame
// (`last`: gpu_scene/last_positions.rs, or this frame's where meshes do not bend) taken as an
// offset through this frame's model matrix: the instance's motion takes it the rest of the way.
@vertex
fn vs_moving(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) last: vec3<f32>,
    @builtin(instance_index) instance: u32,
) -> MovingVsOut {
    let v = surface_vertex(position, normal, uv, instance, 0u);
    let bent = (instances[instance].model * vec4<f32>(last - position, 0.0)).xyz;
    return MovingVsOut(v.clip, v.world, v.normal, v.material, v.uv, v.eye, instance, bent);
}

fn surface_vertex(position: vec3<f32>, normal: vec3<f32>, uv: vec2<f32>, instance: u32, eye: u32) -> VsOut {
    return surface_vertex_seen(position, normal, uv, instance, frame.eye_view_proj[eye], eye);
}

// The vertex of scene instance `instance` seen through `view_proj` by view `eye` (an eye of
// the frame, or a probe face: `gbuffer_face_layers.wgsl`, `gbuffer_faces.wgsl`).
fn surface_vertex_seen(position: vec3<f32>, normal: vec3<f32>, uv: vec2<f32>, instance: u32, view_proj: mat4x4<f32>, eye: u32) -> VsOut {
    let inst = instances[instance];
    let world = inst.model * vec4<f32>(position, 1.0);
    var out: VsOut;
    out.clip = view_proj * world;
    out.world = world.xyz;
    out.normal = (inst.normal * vec4<f32>(normal, 0.0)).xyz;
    out.material = inst.material.x;
    out.uv = uv;
    out.eye = eye;
    return out;
}

// Screen-space derivatives of the fragment's texture coordinate and position, taken where
// control flow is uniform; sampling then uses them explicitly (wrapping in the shader would
// otherwise break the mip selection at every seam).
struct Derivs {
    uv_dx: vec2<f32>,
    uv_dy: vec2<f32>,
    p_dx: vec3<f32>,
    p_dy: vec3<f32>,
}

fn derivs(in: VsOut) -> Derivs {
    var d: Derivs;
    d.uv_dx = dpdx(in.uv);
    d.uv_dy = dpdy(in.uv);
    d.p_dx = dpdx(in.world);
    d.p_dy = dpdy(in.world);
    return d;
}

// Layer `layer1 - 1` of `tex` at `uv` wrapped by the two modes in `wrap` (bits 0-1: u, 2-3: v).
fn sample_layer(tex: texture_2d_array<f32>, layer1: u32, wrap: u32, uv: vec2<f32>, d: Derivs) -> vec4<f32> {
    let t = vec2<f32>(wrap_coord(uv.x, wrap & 3u), wrap_coord(uv.y, (wrap >> 2u) & 3u));
    return textureSampleGrad(tex, tex_sampler, t, layer1 - 1u, d.uv_dx, d.uv_dy);
}

// Base colour (linear rgb) and alpha of the material at the fragment.
fn base_colour(mat: MaterialData, uv: vec2<f32>, d: Derivs) -> vec4<f32> {
    if (mat.texture.x == 0u) {
        return vec4<f32>(1.0, 1.0, 1.0, mat.diffuse.a);
    }
    let c = sample_layer(colour_tex, mat.texture.x, mat.texture.z & 15u, uv, d);
    return vec4<f32>(c.rgb, c.a * mat.diffuse.a);
}

// The shading normal `n` (unit, facing the camera) bent by the material's tangent-space normal
// map, with the tangent frame taken from the derivatives of position and texture coordinate
// (no tangent attribute needed; Schüler, "Normal mapping without precomputed tangents", 2006).
// glTF's normal maps have +Y up while its v runs down the image, hence the flipped green.
fn bent_normal(mat: MaterialData, n: vec3<f32>, uv: vec2<f32>, d: Derivs) -> vec3<f32> {
    if (mat.texture.y == 0u) {
        return n;
    }
    let s = sample_layer(normal_tex, mat.texture.y, (mat.texture.z >> 4u) & 15u, uv, d).xyz;
    let m = vec3<f32>(s.x * 2.0 - 1.0, 1.0 - s.y * 2.0, s.z * 2.0 - 1.0);
    let dp2perp = cross(d.p_dy, n);
    let dp1perp = cross(n, d.p_dx);
    let t = dp2perp * d.uv_dx.x + dp1perp * d.uv_dy.x;
    let b = dp2perp * d.uv_dx.y + dp1perp * d.uv_dy.y;
    let len2 = max(dot(t, t), dot(b, b));
    if (!(len2 > 0.0)) {
        return n;
    }
    let scale = inverseSqrt(len2);
    let bent = normalize(t * scale * m.x + b * scale * m.y + n * m.z);
    // Keep the bent normal on the camera's side of the surface.
    return select(n, bent, dot(bent, n) > 0.0);
}

// Both targets hold f32 bit patterns in u32 channels (exact, and renderable on every backend).
struct GBufferOut {
    // xyz world position, w = albedo (see has_geometry in common.wgsl; the clear value 0 means
    // no geometry).
    @location(0) position: vec4<u32>,
    // xyz unit normal facing the camera, w = material index (bits 0-15) and, for a material
    // with a metallic-roughness texture, the texel's roughness (bits 16-23) and metallic
    // (bits 24-31) as bytes.
    @location(1) normal_material: vec4<u32>,
}

// With emissive textures (gbuffer.rs): the emissive texel too, linear rgb (white where the
// material has none: the lighting pass reads it only for materials that have one).
struct GBufferOutEmission {
    @location(0) position: vec4<u32>,
    @location(1) normal_material: vec4<u32>,
    @location(2) emission: vec4<f32>,
}

// With the instance seen (sampled/motion.rs: histories that follow moving instances): x, the
// scene instance + 1 (the clear value 0: no geometry); yzw, the bent offset's f32 bits (kept
// where the target has them: gbuffer.rs `MOTION_FORMAT`, for scenes whose meshes bend).
struct GBufferOutMoving {
    @location(0) position: vec4<u32>,
    @location(1) normal_material: vec4<u32>,
    @location(2) instance: vec4<u32>,
}

// Both.
struct GBufferOutEmissionMoving {
    @location(0) position: vec4<u32>,
    @location(1) normal_material: vec4<u32>,
    @location(2) emission: vec4<f32>,
    @location(3) instance: vec4<u32>,
}

fn emission_texel(mat: MaterialData, uv: vec2<f32>, d: Derivs) -> vec4<f32> {
    let bits = bitcast<u32>(mat.emissive.w);
    let layer1 = bits & 0xffffffu;
    if (layer1 == 0u) {
        return vec4<f32>(1.0);
    }
    return vec4<f32>(sample_layer(colour_tex, layer1, bits >> 24u, uv, d).rgb, 1.0);
}

// The base colour of an alpha-tested material at the fragment; texels whose alpha is below
// the cutoff are holes (discarded).
fn masked_base(mat: MaterialData, uv: vec2<f32>, d: Derivs) -> vec4<f32> {
    let base = base_colour(mat, uv, d);
    if ((mat.texture.z & MATERIAL_ALPHA_TEST) != 0u && base.a < bitcast<f32>(mat.texture.w)) {
        discard;
    }
    return base;
}

// A fragment's surface, the material and the derivatives it was shaded with (the emissive
// texel reads them too).
struct Shaded {
    g: GBufferOut,
    mat: MaterialData,
    d: Derivs,
}

fn opaque(in: VsOut, front: bool) -> Shaded {
    let d = derivs(in);
    let mat = materials[in.material];
    return Shaded(surface(in, front, mat, base_colour(mat, in.uv, d), d), mat, d);
}

// Alpha-tested materials: their own entry points (and pipelines), so that opaque surfaces
// keep early depth testing (a shader that may discard loses it).
fn masked(in: VsOut, front: bool) -> Shaded {
    let d = derivs(in);
    let mat = materials[in.material];
    return Shaded(surface(in, front, mat, masked_base(mat, in.uv, d), d), mat, d);
}

fn with_emission(s: Shaded, uv: vec2<f32>) -> GBufferOutEmission {
    return GBufferOutEmission(s.g.position, s.g.normal_material, emission_texel(s.mat, uv, s.d));
}

fn motion_texel(v: MovingVsOut) -> vec4<u32> {
    return vec4<u32>(v.instance + 1u, bitcast<vec3<u32>>(v.bent));
}

fn with_instance(s: Shaded, v: MovingVsOut) -> GBufferOutMoving {
    return GBufferOutMoving(s.g.position, s.g.normal_material, motion_texel(v));
}

fn with_both(s: Shaded, v: MovingVsOut) -> GBufferOutEmissionMoving {
    let e = emission_texel(s.mat, v.uv, s.d);
    return GBufferOutEmissionMoving(s.g.position, s.g.normal_material, e, motion_texel(v));
}

@fragment
fn fs_main(in: VsOut, @builtin(front_facing) front: bool) -> GBufferOut {
    return opaque(in, front).g;
}

@fragment
fn fs_masked(in: VsOut, @builtin(front_facing) front: bool) -> GBufferOut {
    return masked(in, front).g;
}

@fragment
fn fs_main_emission(in: VsOut, @builtin(front_facing) front: bool) -> GBufferOutEmission {
    return with_emission(opaque(in, front), in.uv);
}

@fragment
fn fs_masked_emission(in: VsOut, @builtin(front_facing) front: bool) -> GBufferOutEmission {
    return with_emission(masked(in, front), in.uv);
}

@fragment
fn fs_main_moving(v: MovingVsOut, @builtin(front_facing) front: bool) -> GBufferOutMoving {
    return with_instance(opaque(without_instance(v), front), v);
}

@fragment
fn fs_masked_moving(v: MovingVsOut, @builtin(front_facing) front: bool) -> GBufferOutMoving {
    return with_instance(masked(without_instance(v), front), v);
}

@fragment
fn fs_main_emission_moving(v: MovingVsOut, @builtin(front_facing) front: bool) -> GBufferOutEmissionMoving {
    return with_both(opaque(without_instance(v), front), v);
}

@fragment
fn fs_masked_emission_moving(v: MovingVsOut, @builtin(front_facing) front: bool) -> GBufferOutEmissionMoving {
    return with_both(masked(without_instance(v), front), v);
}

fn surface(in: VsOut, front: bool, mat: MaterialData, base: vec4<f32>, d: Derivs) -> GBufferOut {
    // Surfaces are two-sided: the shading normal is turned to the side of the triangle the
    // camera sees. The side comes from the triangle's own plane (position derivatives), not
    // from its winding: scanned meshes have triangles wound against their neighbours whose
    // vertex normals still point outwards, and flipping those by winding shaded them as seen
    // from inside (black speckles). Winding decides only where the plane is degenerate.
    let to_eye = eye_position(in.eye) - in.world;
    var ng = cross(d.p_dx, d.p_dy);
    var facing = select(-1.0, 1.0, front);
    let ng_len = length(ng);
    if (ng_len > 0.0) {
        ng = ng / ng_len;
        if (dot(ng, to_eye) < 0.0) {
            ng = -ng;
        }
    }
    var n = in.normal;
    let n_len = length(n);
    if (n_len > 0.0) {
        n = n / n_len;
        if (ng_len > 0.0) {
            facing = select(-1.0, 1.0, dot(n, ng) >= 0.0);
        }
        n = n * facing;
    } else {
        // Normals that cancel (opposite faces on one vertex): the plane's normal.
        n = select(vec3<f32>(0.0, 1.0, 0.0), ng, ng_len > 0.0);
    }
    n = bent_normal(mat, n, in.uv, d);
    var out: GBufferOut;
    // w: the albedo (see has_geometry in common.wgsl); all ones, exactly, when untextured.
    var albedo = 0xffffffffu;
    if (mat.texture.x != 0u) {
        albedo = pack4x8unorm(vec4<f32>(srgb_from_linear(base.rgb), 1.0)) | 0xff000000u;
    }
    out.position = vec4<u32>(bitcast<vec3<u32>>(in.world), albedo);
    var material_word = in.material;
    let mr_layer = bitcast<u32>(mat.pbr.z);
    if (mr_layer != 0u) {
        let t = sample_layer(normal_tex, mr_layer, bitcast<u32>(mat.pbr.w), in.uv, d);
        let bytes = vec2<u32>(round(clamp(t.gb, vec2<f32>(0.0), vec2<f32>(1.0)) * 255.0));
        material_word = material_word | (bytes.x << 16u) | (bytes.y << 24u);
    }
    out.normal_material = vec4<u32>(bitcast<vec3<u32>>(n), material_word);
    return out;
}
