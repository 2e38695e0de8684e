// Shared declarations for every manyshadows shader.
// Keep in sync with crates/render/src/gpu/types.rs (a test compares the layouts naga computes
// for these structs with the Rust structs' sizes).

const LIGHT_DIRECTIONAL: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_POINT: u32 = 2u;

const PCF_OFF: u32 = 0u;
const PCF_2X2: u32 = 1u;
const PCF_3X3: u32 = 2u;

struct FrameUniforms {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    // xyz: eye position.
    camera_pos: vec4<f32>,
    // width, height, 1/width, 1/height in pixels.
    viewport: vec4<f32>,
    // light count, PCF mode, atlas side in texels, visibility words per pixel.
    counts: vec4<u32>,
    // Receiver bias in shadow texels: constant, slope (times tan of the light angle), normal
    // offset; w: world size of a screen pixel at view depth 1 (2 / (P11 · height)).
    bias: vec4<f32>,
    // Ambient-only colour of pixels no light reaches, and sky colour: rgb + unused.
    sky: vec4<f32>,
    // Soft shadows of sized lights (pcss.wgsl): blocker-search taps, filter taps, largest
    // penumbra radius in shadow texels; w: lights sampled per pixel over shadow maps (0:
    // every light; shadow rays carry theirs).
    soft: vec4<f32>,
    // Exposure scale (linear colour times it before the tone map); y: the sampled lights'
    // seed over shadow maps (bits of a u32); unused ×2 (look.rs).
    look: vec4<f32>,
    // Tone map (TONE_*); the frame number where rays are denoised or reused (else 0); in a
    // denoised frame whose lights changed, where the changed lights' records start in the
    // lights buffer and how many went | how many came << 16 (lighting.wgsl `denoise_fix`).
    modes: vec4<u32>,
    // Stereo (frame/eyes.rs): each eye's world → clip and position (mono: both the camera's),
    // and in `eyes` one eye's width in pixels (the whole width when mono), the eye count.
    eye_view_proj: array<mat4x4<f32>, 2>,
    eye_pos: array<vec4<f32>, 2>,
    eyes: vec4<f32>,
}

// The eye whose half of the image holds pixel column `x` (0 when mono), from
// `FrameUniforms::eyes`.
fn eye_of(eyes: vec4<f32>, x: u32) -> u32 {
    return min(x / max(u32(eyes.x), 1u), max(u32(eyes.y), 1u) - 1u);
}

// Pixel `px` counted from its eye's left edge: per-pixel noise (tap rotations, sample
// jitter, random choices) hashes this, so each eye of a stereo frame is the mono frame from
// that eye, noise and all.
fn eye_local(eyes: vec4<f32>, px: vec2<i32>) -> vec2<i32> {
    let e = eye_of(eyes, u32(max(px.x, 0)));
    return vec2<i32>(px.x - i32(e * u32(eyes.x)), px.y);
}

const SHADING_PHONG: u32 = 0u;
const SHADING_PBR: u32 = 1u;
const TONE_EXPONENTIAL: u32 = 0u;
const TONE_NEUTRAL: u32 = 1u;
const TONE_CLAMP: u32 = 2u;

struct InstanceData {
    model: mat4x4<f32>,
    // Inverse transpose of the model matrix (for normals).
    normal: mat4x4<f32>,
    // x: material index.
    material: vec4<u32>,
}

struct MaterialData {
    // rgb ambient, a: shininess.
    ambient: vec4<f32>,
    // rgb diffuse, a: alpha of the base colour.
    diffuse: vec4<f32>,
    specular: vec4<f32>,
    // 1 + base-colour layer (0: none), 1 + normal-map layer (0: none), flags (wrap modes of
    // the base colour in bits 0-3, of the normal map in bits 4-7, MATERIAL_ALPHA_TEST), alpha
    // cutoff (f32 bits).
    texture: vec4<u32>,
    // metallic, roughness (glTF BRDF), bits of 1 + the metallic-roughness texture's layer in
    // the data array (0: none), bits of its wrap modes.
    pbr: vec4<f32>,
    // rgb emitted radiance, w: bits of 1 + the emissive texture's layer in the colour array
    // (bits 0-23; 0: none) and its wrap modes (bits 24-27).
    emissive: vec4<f32>,
}

const MATERIAL_ALPHA_TEST: u32 = 256u;

// Wrap codes of textures (manyshadows_scene::Wrap::code).
const WRAP_REPEAT: u32 = 0u;
const WRAP_MIRROR: u32 = 1u;
const WRAP_CLAMP: u32 = 2u;

// A texture coordinate mapped into 0..1 by a wrap mode (manyshadows_scene::Wrap::apply).
fn wrap_coord(t: f32, mode: u32) -> f32 {
    if (mode == WRAP_MIRROR) {
        let m = t - 2.0 * floor(t * 0.5);
        return select(m, 2.0 - m, m > 1.0);
    }
    if (mode == WRAP_CLAMP) {
        return clamp(t, 0.0, 1.0);
    }
    return t - floor(t);
}

// The G-buffer's position target: xyz = world position (f32 bits), w = the surface's albedo
// (linear colour encoded as sRGB bytes by pack4x8unorm, alpha byte 255). The clear value 0
// marks pixels without geometry.
fn has_geometry(texel: vec4<u32>) -> bool {
    return texel.w != 0u;
}

fn linear_from_srgb(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + vec3<f32>(0.055)) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

fn srgb_from_linear(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - vec3<f32>(0.055), x * 12.92, x <= vec3<f32>(0.0031308));
}

// The albedo a G-buffer position texel holds (white for untextured surfaces).
fn gbuffer_albedo(texel: vec4<u32>) -> vec3<f32> {
    // Exactly white for untextured surfaces, so their shading is bit for bit what it was
    // before textures existed.
    if (texel.w == 0xffffffffu) {
        return vec3<f32>(1.0);
    }
    return linear_from_srgb(unpack4x8unorm(texel.w).rgb);
}

struct LightData {
    // xyz position (spot, point).
    position: vec4<f32>,
    // xyz unit direction the light travels (spot axis, directional), w: cos(cutoff) for spots.
    direction: vec4<f32>,
    // rgb, w: range (spot, point).
    ambient: vec4<f32>,
    diffuse: vec4<f32>,
    specular: vec4<f32>,
    // constant, linear, quadratic, unused.
    attenuation: vec4<f32>,
    // Cascade far split distances (camera view depth), nearest cascade first.
    splits: vec4<f32>,
    // first shadow view, shadow view count (0 = casts no shadow), light type, unused.
    shadow: vec4<u32>,
}

struct ShadowViewData {
    view_proj: mat4x4<f32>,
    // Atlas tile: x0, y0, side (texels), unused.
    tile: vec4<f32>,
    // near, far, world size of a texel (orthographic) or of a texel at distance 1
    // (perspective: multiply by clip w), 1 if orthographic else 0.
    params: vec4<f32>,
}

// The clustered light lists (clusters.rs): the view is cut into tiles of `grid.w` pixels and
// `grid.z` depth slices (exponential in view depth); each cluster that holds a visible sample
// gets a slot of `words.z` words: `words.x` summary words (bit w set = light word w is not
// empty), then `words.y` light words (bit b of word w set = light 32w + b may reach the cluster).
struct ClusterUniforms {
    // Tiles across, tiles down, depth slices, tile side in pixels.
    grid: vec4<u32>,
    // Summary words, light words, words per slot, 1 = shading reads the lists (0 = every light).
    words: vec4<u32>,
    // Slicing near depth, slices per unit of ln(depth), camera near, camera far: slice s holds
    // view depths near·e^(s/per_ln) .. near·e^((s+1)/per_ln); the first and last slices reach
    // out to the camera's near and far planes.
    depth: vec4<f32>,
    // View-space x and y per unit depth per NDC unit (1/P00, 1/P11), one eye's width in
    // pixels (the whole width when mono), half the eye separation (frame/eyes.rs).
    proj: vec4<f32>,
    // Slot capacity, lights in the assignment list, clusters in the grid, eyes (1 or 2).
    counts: vec4<u32>,
}

// Depth slice of a view depth: ln(depth / near) · per_ln, clamped to the grid.
fn cluster_slice(c: ClusterUniforms, view_depth: f32) -> u32 {
    let s = floor(log(max(view_depth, 1e-30) / c.depth.x) * c.depth.y);
    return u32(clamp(s, 0.0, f32(c.grid.z - 1u)));
}

// Cluster index of pixel `px` at `view_depth`.
// With two eyes each eye's half has its own `grid.x / 2` tile columns, counted from its edge.
fn cluster_index(c: ClusterUniforms, px: vec2<u32>, view_depth: f32) -> u32 {
    let eyes = max(c.counts.w, 1u);
    let per_eye = c.grid.x / eyes;
    let eye_width = max(u32(c.proj.z), 1u);
    let eye = min(px.x / eye_width, eyes - 1u);
    let local = vec2<u32>(px.x - eye * eye_width, px.y);
    let t = min(local / c.grid.w, vec2<u32>(per_eye, c.grid.y) - vec2<u32>(1u));
    return (cluster_slice(c, view_depth) * c.grid.y + t.y) * c.grid.x + eye * per_eye + t.x;
}

// Slot values: 0 = no sample in the cluster, 1 = marked (before allocation), 2 + slot
// index = allocated, CLUSTER_OVERFLOW = marked but the pool was full (shade with every light).
const CLUSTER_EMPTY: u32 = 0u;
const CLUSTER_MARKED: u32 = 1u;
const CLUSTER_FIRST_SLOT: u32 = 2u;
const CLUSTER_OVERFLOW: u32 = 0xffffffffu;

