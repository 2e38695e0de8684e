//! How the passes that read shadows (lighting, visibility) find them: the WGSL every such pass
//! composes (view selection, receiver bias, atlas addressing, the dual-paraboloid warp), and
//! the lookup each shadow source supplies on top of it ([`LookupWgsl`]): what defines
//! `shadow_coord` and the ray functions, with its own bindings. A source that fills something
//! new writes its lookup beside itself; the passes compose whatever they are handed.

use crate::gpu::bindings::{Binding, BindingList};
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

/// What the passes call where shadows do not come from rays: no ray is ever cast. Sampled
/// lights (`ray_samples() > 0`) take their visibility from the shadow maps instead
/// (`light_lit`'s map branch); their count and seed come in the frame's uniforms
/// (`FrameUniforms::soft.w`, `look.y`; `renderer::uniforms`).
pub const NO_RAYS: &str = "const SHADOW_RAYS: bool = false;\n\
     fn ray_lit(light: LightData, p: vec3<f32>, n: vec3<f32>) -> f32 { return 1.0; }\n\
     fn ray_lit_area(light: LightData, p: vec3<f32>, n: vec3<f32>, m: u32, jitter: vec2<f32>) -> f32 { return 1.0; }\n\
     fn ray_area_side() -> u32 { return 1u; }\n\
     fn ray_samples() -> u32 { return u32(frame.soft.w); }\n\
     fn ray_seed() -> u32 { return bitcast<u32>(frame.look.y); }";

/// A source's part of the shadow-reading passes' WGSL. It defines `shadow_coord(light, p, n,
/// view_depth) -> ShadowCoord`, `SHADOW_RAYS`, `ray_lit`, `ray_samples` and `ray_seed`, after
/// `common.wgsl`, `paraboloid.wgsl` and `shadow_lookup.wgsl`. Its own bindings are declared
/// once, in [`LookupWgsl::bindings`]: the pass that composes it numbers them after its own and
/// generates their WGSL declarations (`gpu::bindings`), and the source hands their resources
/// in the same order ([`ShadowOutput::resources`](crate::shadows::source::ShadowOutput::resources)).
#[derive(Clone, Copy, Debug)]
pub struct LookupWgsl {
    /// `enable` directives it needs, placed first in the shader ("" for none).
    pub enables: &'static str,
    /// Its bindings, in order.
    pub bindings: &'static [Binding],
    /// Its WGSL, without the bindings' declarations.
    pub source: fn() -> String,
    /// The device features it compiles only with (the registry's shader test reads them).
    #[cfg_attr(not(test), allow(dead_code))]
    pub features: wgpu::Features,
}

fn atlas_lookup() -> String {
    format!("{ATLAS_COORD}\n{ATLAS_TAPS}\n{NO_RAYS}")
}

/// Shadows from the atlas's tiles through the view table (every atlas technique, and the
/// sources whose output is the mask: their passes never call `shadow_coord`).
pub const ATLAS_LOOKUP: LookupWgsl = LookupWgsl {
    enables: "",
    bindings: &[],
    source: atlas_lookup,
    features: wgpu::Features::empty(),
};

/// The atlas addressing alone (`shadow_coord` through the atlas), for a lookup that adds its
/// own ray functions to it.
pub fn atlas_coord() -> &'static str {
    ATLAS_COORD
}

/// A shadow-reading pass: `lookup`'s enables, the declarations of `bindings` (the pass's own,
/// then the lookup's, then those of the parts plugged into it: `gpu::bindings` numbers them in
/// that order), the shared parts (with the soft-shadow filter), `lookup`'s WGSL, then `pass`
/// (the pass's own WGSL and its parts', which declare no bindings of their own).
pub fn compose_reader(lookup: &LookupWgsl, bindings: &BindingList, pass: &str) -> String {
    [
        lookup.enables,
        &bindings.wgsl(),
        COMMON,
        PARABOLOID,
        SHADOW_LOOKUP,
        PCSS,
        &(lookup.source)(),
        pass,
    ]
    .join("\n")
}
