//! WGSL sources and the one way they share code: `common.wgsl` (struct declarations beside
//! this module, kept in sync with [`crate::gpu::types`]) and `shadow_lookup.wgsl` (where a
//! point falls in the atlas, `shadows/`) are prepended to the shaders that need them. Each
//! WGSL file lies beside the module that owns it (`frame/`, `gpu_scene/`, `shadows/`,
//! `shadows/atlas/`, `shadows/irregular/`, `shadows/vsm/`); this module only composes them,
//! so it imports nothing of the crate. Every composed shader is parsed and validated by naga
//! in a test, so broken WGSL fails `cargo test` without a GPU.

/// Struct declarations shared by all shaders.
pub const COMMON: &str = include_str!("common.wgsl");
/// Shadow-view selection, receiver bias and atlas addressing.
pub const SHADOW_LOOKUP: &str = include_str!("../shadows/shadow_lookup.wgsl");
/// The lighting and visibility passes' `shadow_coord` when shadows come from the atlas.
pub const ATLAS_COORD: &str = "fn shadow_coord(light: LightData, p: vec3<f32>, n: vec3<f32>, \
     view_depth: f32) -> ShadowCoord {\n    return atlas_coord(light, p, n, view_depth);\n}";
/// Virtual shadow maps: level and page selection shared by marking and lookups.
pub const VSM_COMMON: &str = include_str!("../shadows/vsm/vsm_common.wgsl");

/// Where the lighting and visibility passes find shadows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowSource {
    /// The atlas of per-view tiles (every shadow-map technique but `virtual`).
    Atlas,
    /// The virtual shadow maps' page table and pool; the three declarations take bindings
    /// `first`, `first + 1`, `first + 2` of group 0.
    Virtual {
        /// First binding of the page-table declarations.
        first: u32,
    },
    /// Shadow rays through an acceleration structure (technique raytraced); the three
    /// declarations take bindings `first` .. `first + 2`.
    Rays {
        /// First binding of the ray declarations.
        first: u32,
    },
}

/// What the passes call where shadows do not come from rays: no ray is ever cast.
const NO_RAYS: &str = "const SHADOW_RAYS: bool = false;\n\
     fn ray_lit(light: LightData, p: vec3<f32>, n: vec3<f32>) -> f32 { return 1.0; }\n\
     fn ray_samples() -> u32 { return 0u; }\n\
     fn ray_seed() -> u32 { return 0u; }";

/// `enable` directives `source` needs before everything else.
fn enables(source: ShadowSource) -> &'static str {
    match source {
        ShadowSource::Rays { .. } => "enable wgpu_ray_query;",
        _ => "",
    }
}

/// The pieces that define `shadow_coord` for `source`.
fn shadow_source(source: ShadowSource) -> Vec<String> {
    match source {
        ShadowSource::Atlas => vec![ATLAS_COORD.to_string(), NO_RAYS.to_string()],
        ShadowSource::Rays { first } => vec![
            ATLAS_COORD.to_string(),
            ALPHA_MASK.to_string(),
            include_str!("../shadows/raytraced/rays.wgsl")
                .replace("RT_FIRST", &first.to_string())
                .replace("RT_SECOND", &(first + 1).to_string())
                .replace("RT_THIRD", &(first + 2).to_string()),
        ],
        ShadowSource::Virtual { first } => vec![
            NO_RAYS.to_string(),
            VSM_COMMON.to_string(),
            format!(
                "@group(0) @binding({}) var<uniform> vsm: VsmUniforms;\n\
                 @group(0) @binding({}) var<storage, read> vsm_faces: array<VirtualFace>;\n\
                 @group(0) @binding({}) var<storage, read> vsm_table: array<u32>;",
                first,
                first + 1,
                first + 2
            ),
            include_str!("../shadows/vsm/vsm_lookup.wgsl").to_string(),
        ],
    }
}

/// Concatenates shader parts in order.
pub fn compose(parts: &[&str]) -> String {
    parts.join("\n")
}

/// G-buffer pass.
pub fn gbuffer() -> String {
    compose(&[COMMON, include_str!("../frame/gbuffer.wgsl")])
}

/// Deferred lighting pass, shadows from `source` (bindings 12–14 for virtual maps).
pub fn lighting(source: ShadowSource) -> String {
    reading_shadows(source, include_str!("../frame/lighting.wgsl"))
}

/// The common parts, the shadow lookup from `source`, then `pass`: the lighting and
/// visibility passes, which declare the same bindings.
fn reading_shadows(source: ShadowSource, pass: &str) -> String {
    let mut parts = vec![
        enables(source).to_string(),
        COMMON.to_string(),
        PARABOLOID.to_string(),
        SHADOW_LOOKUP.to_string(),
    ];
    parts.extend(shadow_source(source));
    parts.push(pass.to_string());
    parts.join("\n")
}

/// Clustered light assignment (mark, compact, assign, statistics).
pub fn clusters() -> String {
    compose(&[COMMON, include_str!("../frame/clusters.wgsl")])
}

/// Hard visibility mask, shadows from `source` (bindings 12–14 for virtual maps, as in
/// [`lighting`]).
pub fn visibility(source: ShadowSource) -> String {
    reading_shadows(source, include_str!("../frame/visibility.wgsl"))
}

/// Copy of the lit frame into a caller's texture (`Renderer::render_to`).
pub fn blit() -> String {
    compose(&[include_str!("../frame/blit.wgsl")])
}

/// Atlas read-back copy.
pub fn atlas_copy() -> String {
    compose(&[include_str!("../shadows/atlas_copy.wgsl")])
}

/// Consecutive caster clusters per group (`CLUSTER_GROUP` in `casters.wgsl`; see
/// `gpu_scene::casters`): each group's bounding sphere holds its clusters' spheres, for
/// culling a group before its clusters.
pub const CLUSTER_GROUP: u32 = 16;

/// Parts of a caster cluster with boxes of their own (`CLUSTER_PARTS` in `casters.wgsl`):
/// consecutive runs of a quarter of the cluster's triangles, so that a page cull can tell
/// which parts of a cluster touch a page.
pub const CLUSTER_PARTS: u32 = 4;

/// Most triangles per caster cluster (`gpu_scene::casters`; here beside the shaders it is
/// spliced into).
pub const CLUSTER_TRIANGLES: u32 = 128;

/// Per-frame world transform of shadow casters.
pub fn casters() -> String {
    let group = format!(
        "const CLUSTER_GROUP: u32 = {CLUSTER_GROUP}u;\nconst CLUSTER_PARTS: u32 = {CLUSTER_PARTS}u;\n\
         const PART_TRIANGLES: u32 = {}u;",
        CLUSTER_TRIANGLES / CLUSTER_PARTS
    );
    compose(&[COMMON, &group, include_str!("../gpu_scene/casters.wgsl")])
}

/// The dual-paraboloid warp.
pub const PARABOLOID: &str = include_str!("../shadows/paraboloid.wgsl");

/// Alpha-tested casters: the mask tail of the corner buffer (needs a `corners` binding).
pub const ALPHA_MASK: &str = include_str!("../gpu_scene/alpha_mask.wgsl");

/// Alpha-tested casters drawn into tiles: outputs and the discarding fragment stage.
pub const TILE_MASK: &str = include_str!("../shadows/tile_mask.wgsl");

/// Per-view triangle culling (frustum, back-face).
pub const CULL: &str = include_str!("../shadows/cull.wgsl");

/// Clearing single tiles of the atlas.
pub fn tile_clear() -> String {
    compose(&[COMMON, include_str!("../shadows/atlas/tile_clear.wgsl")])
}

/// Culling whole caster clusters by bounding sphere and normal cone (`gpu-driven`, virtual).
pub const CLUSTER_CULL: &str = include_str!("../shadows/cluster_cull.wgsl");

/// Mapping clip positions into atlas tiles with clip distances (`layered`, `gpu-driven`).
pub const TILE: &str = include_str!("../shadows/tile.wgsl");

#[cfg(test)]
/// Every composed shader no technique owns, with its name (for validation; each technique
/// lists its own in its `TechniqueInfo`).
pub fn all() -> Vec<(&'static str, String)> {
    vec![
        ("gbuffer", gbuffer()),
        ("lighting", lighting(ShadowSource::Atlas)),
        (
            "lighting_vsm",
            lighting(ShadowSource::Virtual { first: 12 }),
        ),
        ("visibility", visibility(ShadowSource::Atlas)),
        (
            "visibility_vsm",
            visibility(ShadowSource::Virtual { first: 12 }),
        ),
        ("clusters", clusters()),
        ("atlas_copy", atlas_copy()),
        ("casters", casters()),
        ("tile_clear", tile_clear()),
        ("blit", blit()),
    ]
}

/// Creates a shader module from composed WGSL.
pub fn module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// Parses and validates `source` as a WebGPU device with `features` would: naga's
/// capabilities from WebGPU's core (a fully compliant downlevel, no optional feature) plus
/// those `features` bring, as wgpu maps them. A shader that relies on more fails here, not in
/// a browser.
#[cfg(test)]
pub(crate) fn validate_for_webgpu(
    name: &str,
    source: &str,
    features: wgpu::Features,
) -> Result<(), String> {
    use wgpu::naga;
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))?;
    let caps = wgpu_naga_bridge::features_to_naga_capabilities(
        features,
        wgpu::DownlevelFlags::compliant(),
    );
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
        .validate(&module)
        .map(|_| ())
        .map_err(|e| {
            format!("{name} does not validate with WebGPU's capabilities + {features:?}: {e:?}")
        })
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_shared_shader_validates_for_webgpu() {
        for (name, src) in super::all() {
            super::validate_for_webgpu(name, &src, wgpu::Features::empty())
                .unwrap_or_else(|e| panic!("{e}"));
        }
    }

    /// The check above can fail: a shader that enables clip distances is refused without the
    /// feature and accepted with it.
    #[test]
    fn webgpu_validation_refuses_a_feature_the_shader_was_not_given() {
        let src = "enable clip_distances;\nstruct O { @builtin(position) p: vec4<f32>, @builtin(clip_distances) c: array<f32, 1> }\n@vertex fn vs() -> O { return O(vec4<f32>(0.0), array<f32, 1>(1.0)); }";
        assert!(super::validate_for_webgpu("probe", src, wgpu::Features::empty()).is_err());
        super::validate_for_webgpu("probe", src, wgpu::Features::CLIP_DISTANCES)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}
