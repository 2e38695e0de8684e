// Deferred Phong lighting (seed 004): ambient + diffuse + specular per light, quadratic
// attenuation, spot cutoff; a shadowed point keeps only the ambient term. Shadows by comparison
// sampling of the atlas with PCF off / 2x2 / 3x3, never reading outside the view's tile.

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<LightData>;
@group(0) @binding(2) var<storage, read> shadow_views: array<ShadowViewData>;
@group(0) @binding(3) var<storage, read> materials: array<MaterialData>;
@group(0) @binding(4) var gbuf_position: texture_2d<u32>;
@group(0) @binding(5) var gbuf_normal: texture_2d<u32>;
@group(0) @binding(6) var atlas: texture_depth_2d;
// One bilinear comparison sampler for every PCF mode: OpenGL cannot pair one texture with two
// samplers. At a texel centre bilinear weights are (1, 0, 0, 0), so a lookup there compares
// exactly one texel, as a nearest-filtered one would.
@group(0) @binding(7) var cmp_linear: sampler_comparison;
// Visibility computed elsewhere (irregular shadow maps): `counts.w` words per pixel, bit set =
// lit. Read by `fs_mask` only; the atlas entry point `fs_main` is bound to a dummy.
@group(0) @binding(8) var<storage, read> vis_mask: array<u32>;

// Scale of the linear colour before tone mapping.
const EXPOSURE: f32 = 1.4;

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle that covers the screen.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn compare_texel(texel: vec2<f32>, depth: f32) -> f32 {
    let size = f32(frame.counts.z);
    return textureSampleCompareLevel(atlas, cmp_linear, (texel + vec2<f32>(0.5)) / size, depth);
}

// Fraction of the light that reaches the point (1 = fully lit).
fn shadow_factor(c: ShadowCoord) -> f32 {
    if (!c.valid) {
        return 1.0;
    }
    let mode = frame.counts.y;
    if (mode == PCF_2X2) {
        // Bilinear comparison of the 2x2 nearest texels; clamping the centre half a texel inside
        // the tile keeps all four inside it.
        let size = f32(frame.counts.z);
        let t = clamp(c.texel, c.tile_min + vec2<f32>(0.5), c.tile_max - vec2<f32>(0.5));
        return textureSampleCompareLevel(atlas, cmp_linear, t / size, c.depth);
    }
    let base = floor(c.texel);
    if (mode == PCF_3X3) {
        var sum = 0.0;
        for (var y = -1; y <= 1; y = y + 1) {
            for (var x = -1; x <= 1; x = x + 1) {
                let t = clamp(base + vec2<f32>(f32(x), f32(y)), c.tile_min, c.tile_max - vec2<f32>(1.0));
                sum = sum + compare_texel(t, c.depth);
            }
        }
        return sum / 9.0;
    }
    return compare_texel(vec2<f32>(hard_texel(c)), c.depth);
}

// Shadows from the atlas (every shadow-map technique).
@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(frag.xy), false);
}

// Shadows from the visibility mask (irregular shadow maps).
@fragment
fn fs_mask(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(frag.xy), true);
}

fn shade(px: vec2<i32>, from_mask: bool) -> vec4<f32> {
    let pos = bitcast<vec4<f32>>(textureLoad(gbuf_position, px, 0));
    if (pos.w < 0.5) {
        return vec4<f32>(frame.sky.rgb, 1.0);
    }
    let nm = textureLoad(gbuf_normal, px, 0);
    let p = pos.xyz;
    let n = normalize(bitcast<vec3<f32>>(nm.xyz));
    let mat = materials[nm.w];
    let v = normalize(frame.camera_pos.xyz - p);
    let view_depth = -(frame.view * vec4<f32>(p, 1.0)).z;
    var color = vec3<f32>(0.0);
    let count = frame.counts.x;
    for (var i = 0u; i < count; i = i + 1u) {
        let light = lights[i];
        if (!in_reach(light, p)) {
            continue;
        }
        let kind = light.shadow.z;
        var att = 1.0;
        if (kind != LIGHT_DIRECTIONAL) {
            let d = distance(light.position.xyz, p);
            let a = light.attenuation;
            att = 1.0 / max(a.x + a.y * d + a.z * d * d, 1e-6);
        }
        let l = to_light(light, p);
        let ambient = light.ambient.rgb * mat.ambient.rgb * att;
        let ndl = dot(n, l);
        if (ndl <= 0.0) {
            color = color + ambient;
            continue;
        }
        let diffuse = light.diffuse.rgb * mat.diffuse.rgb * ndl;
        let r = reflect(-l, n);
        let spec = light.specular.rgb * mat.specular.rgb * pow(max(dot(r, v), 0.0), max(mat.ambient.w, 1.0));
        var lit = 1.0;
        if (from_mask) {
            let word = vis_mask[(u32(px.y) * u32(frame.viewport.x) + u32(px.x)) * frame.counts.w + i / 32u];
            lit = f32((word >> (i % 32u)) & 1u);
        } else {
            lit = shadow_factor(shadow_coord(light, p, n, view_depth));
        }
        color = color + ambient + lit * att * (diffuse + spec);
    }
    // Exponential tone mapping: many overlapping lights add up past 1 without clipping to white.
    return vec4<f32>(vec3<f32>(1.0) - exp(-color * EXPOSURE), 1.0);
}
