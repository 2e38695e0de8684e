//! How the passes that read shadows (lighting, visibility) find them: the WGSL every such pass
//! composes (view selection, receiver bias, atlas addressing, the dual-paraboloid warp), and
//! the lookup each shadow source supplies on top of it ([`LookupWgsl`]): what defines
//! `shadow_coord` and the ray functions, with its own bindings. A source that fills something
//! new writes its lookup beside itself; the passes compose whatever they are handed.

use crate::gpu::shaders::COMMON;

/// Shadow-view selection, receiver bias and atlas addressing.
pub const SHADOW_LOOKUP: &str = include_str!("shadow_lookup.wgsl");

/// The dual-paraboloid warp.
pub const PARABOLOID: &str = include_str!("paraboloid.wgsl");

/// Soft shadows of sized lights (percentage-closer soft shadows); the pass defines the two
/// reads of its shadow texture that it calls.
pub const PCSS: &str = include_str!("pcss.wgsl");

/// `shadow_coord` of the passes when shadows come from the atlas's tiles.
const ATLAS_COORD: &str = "fn shadow_coord(light: LightData, p: vec3<f32>, n: vec3<f32>, \
     view_depth: f32) -> ShadowCoord {\n    return atlas_coord(light, p, n, view_depth);\n}";

/// The soft filter's taps in an atlas tile (`ShadowCoord::soft` counts texels from the tile's
/// corner): raw depth, and the pass's bilinear comparison, clamped to the tile.
pub const ATLAS_TAPS: &str = "fn soft_tap_depth(c: ShadowCoord, t: vec2<f32>) -> f32 {\n\
     \x20   return shadow_depth_at(vec2<i32>(c.tile_min + clamp(floor(t), vec2<f32>(0.0), vec2<f32>(c.soft.z - 1.0))));\n\
     }\n\
     fn soft_tap_compare(c: ShadowCoord, t: vec2<f32>, depth: f32) -> f32 {\n\
     \x20   return shadow_compare_at(c.tile_min + clamp(t, vec2<f32>(0.5), vec2<f32>(c.soft.z - 0.5)), depth);\n\
     }\n\
     fn soft_coarser(c: ShadowCoord, k: u32) -> ShadowCoord {\n\
     \x20   return c;\n\
     }";

/// What the passes call where shadows do not come from rays: no ray is ever cast.
pub const NO_RAYS: &str = "const SHADOW_RAYS: bool = false;\n\
     fn ray_lit(light: LightData, p: vec3<f32>, n: vec3<f32>) -> f32 { return 1.0; }\n\
     fn ray_lit_area(light: LightData, p: vec3<f32>, n: vec3<f32>, m: u32, jitter: vec2<f32>) -> f32 { return 1.0; }\n\
     fn ray_area_side() -> u32 { return 1u; }\n\
     fn ray_samples() -> u32 { return 0u; }\n\
     fn ray_seed() -> u32 { return 0u; }";

/// A source's part of the shadow-reading passes' WGSL. It defines `shadow_coord(light, p, n,
/// view_depth) -> ShadowCoord`, `SHADOW_RAYS`, `ray_lit`, `ray_samples` and `ray_seed`, after
/// `common.wgsl`, `paraboloid.wgsl` and `shadow_lookup.wgsl`; its own declarations take the
/// bindings from `first` on, in the order of the source's
/// [`ShadowOutput::bindings`](crate::shadows::source::ShadowOutput::bindings).
#[derive(Clone, Copy, Debug)]
pub struct LookupWgsl {
    /// `enable` directives it needs, placed first in the shader ("" for none).
    pub enables: &'static str,
    /// Its WGSL, declarations from binding `first` on.
    pub source: fn(first: u32) -> String,
    /// The device features it compiles only with (the registry's shader test reads them).
    #[cfg_attr(not(test), allow(dead_code))]
    pub features: wgpu::Features,
}

fn atlas_lookup(_first: u32) -> String {
    format!("{ATLAS_COORD}\n{ATLAS_TAPS}\n{NO_RAYS}")
}

/// Shadows from the atlas's tiles through the view table (every atlas technique, and the
/// sources whose output is the mask: their passes never call `shadow_coord`).
pub const ATLAS_LOOKUP: LookupWgsl = LookupWgsl {
    enables: "",
    source: atlas_lookup,
    features: wgpu::Features::empty(),
};

/// The atlas addressing alone (`shadow_coord` through the atlas), for a lookup that adds its
/// own ray functions to it.
pub fn atlas_coord() -> &'static str {
    ATLAS_COORD
}

/// A shadow-reading pass: `lookup`'s enables, the shared parts (with the soft-shadow filter),
/// `lookup` with its declarations
/// from binding `first`, then `pass` (the pass's own WGSL, which declares bindings below
/// `first`).
pub fn compose_reader(lookup: &LookupWgsl, first: u32, pass: &str) -> String {
    [
        lookup.enables,
        COMMON,
        PARABOLOID,
        SHADOW_LOOKUP,
        PCSS,
        &(lookup.source)(first),
        pass,
    ]
    .join("\n")
}
