// Shared declarations for every manyshadows shader.
// Keep in sync with crates/render/src/gpu_types.rs (a test compares the layouts naga computes
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
    // Receiver bias in shadow texels: constant, slope (times tan of the light angle), normal offset.
    bias: vec4<f32>,
    // Ambient-only colour of pixels no light reaches, and sky colour: rgb + unused.
    sky: vec4<f32>,
}

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
    diffuse: vec4<f32>,
    specular: vec4<f32>,
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
