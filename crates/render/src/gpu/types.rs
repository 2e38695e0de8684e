//! Rust mirrors of the structs in `common.wgsl` (beside this module).
//!
//! Keep in sync with `common.wgsl`: the test at the bottom asks naga for the WGSL
//! layout of each struct and compares it with the Rust size, so a drifted field fails the test.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use manyshadows_scene::{light_space::ShadowView, Light, LightKind, Material, Pbr};

/// Light type codes, as `LIGHT_*` in `common.wgsl`.
pub const LIGHT_DIRECTIONAL: u32 = 0;
/// Spot light type code.
pub const LIGHT_SPOT: u32 = 1;
/// Point light type code.
pub const LIGHT_POINT: u32 = 2;

/// Per-frame constants (`FrameUniforms`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    /// Camera world → clip.
    pub view_proj: [[f32; 4]; 4],
    /// Camera world → view.
    pub view: [[f32; 4]; 4],
    /// Eye position (xyz).
    pub camera_pos: [f32; 4],
    /// width, height, 1/width, 1/height.
    pub viewport: [f32; 4],
    /// light count, PCF mode, atlas side, visibility words per pixel.
    pub counts: [u32; 4],
    /// constant, slope, normal-offset bias in texels; unused.
    pub bias: [f32; 4],
    /// Sky colour (rgb).
    pub sky: [f32; 4],
    /// Soft shadows: blocker-search taps, filter taps, largest penumbra radius in texels.
    pub soft: [f32; 4],
    /// Exposure scale, unused ×3 (`ResolvedLook::uniforms`).
    pub look: [f32; 4],
    /// Tone map; the frame number where rays are denoised or reused (else 0); with the
    /// denoiser, in a frame whose lights changed: where the changed lights' records start in
    /// the lights buffer and how many went | how many came << 16 (else 0, 0).
    pub modes: [u32; 4],
    /// Each eye's world → clip (`frame::eyes`; mono: both the camera's `view_proj`).
    pub eye_view_proj: [[[f32; 4]; 4]; 2],
    /// Each eye's position (xyz; mono: both `camera_pos`).
    pub eye_pos: [[f32; 4]; 2],
    /// Width of one eye in pixels (the whole width when mono), eye count, unused ×2.
    pub eyes: [f32; 4],
}

/// Per-instance data (`InstanceData`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct InstanceData {
    /// Object → world.
    pub model: [[f32; 4]; 4],
    /// Inverse transpose of `model`.
    pub normal: [[f32; 4]; 4],
    /// x: material index.
    pub material: [u32; 4],
}

impl InstanceData {
    /// From a transform and a material index.
    pub fn new(model: Mat4, material: u32) -> Self {
        Self {
            model: model.to_cols_array_2d(),
            normal: model.inverse().transpose().to_cols_array_2d(),
            material: [material, 0, 0, 0],
        }
    }
}

/// A Phong material (`MaterialData`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MaterialData {
    /// rgb ambient, a: shininess.
    pub ambient: [f32; 4],
    /// rgb diffuse, a: alpha of the base colour.
    pub diffuse: [f32; 4],
    /// rgb specular.
    pub specular: [f32; 4],
    /// 1 + base-colour layer (0: none), 1 + normal-map layer (0: none), flags
    /// (`MATERIAL_*` in common.wgsl: wrap modes, alpha test), alpha cutoff (`f32` bits).
    pub texture: [u32; 4],
    /// metallic, roughness (the glTF BRDF's), the bits of 1 + the metallic-roughness layer in
    /// the data array (0: none), the bits of its wrap modes.
    pub pbr: [f32; 4],
    /// rgb emitted radiance, w: the bits of 1 + the emissive texture's layer in the colour
    /// array (bits 0-23; 0: none) and its wrap modes (bits 24-27).
    pub emissive: [f32; 4],
}

/// Material flag: the G-buffer alpha-tests the material (its coverage mask is not all solid).
pub const MATERIAL_ALPHA_TEST: u32 = 1 << 8;

impl MaterialData {
    /// Packs `m` whose base-colour, normal, metallic-roughness and emissive textures sit in
    /// those layers of the scene's texture arrays (`None`: untextured; normal and
    /// metallic-roughness maps share the data array, emissive textures the colour array),
    /// alpha-tested if `alpha_test`.
    pub fn new(
        m: &Material,
        base_layer: Option<u32>,
        normal_layer: Option<u32>,
        mr_layer: Option<u32>,
        emissive_layer: Option<u32>,
        alpha_test: bool,
    ) -> Self {
        let wrap = |t: Option<manyshadows_scene::TextureRef>| {
            t.map_or(0, |t| t.wrap_s.code() | (t.wrap_t.code() << 2))
        };
        let pbr = m
            .pbr
            .unwrap_or_else(|| Pbr::from_phong(m.shininess, m.specular));
        let flags = wrap(m.base_color_texture)
            | (wrap(m.normal_texture) << 4)
            | if alpha_test { MATERIAL_ALPHA_TEST } else { 0 };
        Self {
            ambient: m.ambient.extend(m.shininess).to_array(),
            diffuse: m.diffuse.extend(m.base_alpha).to_array(),
            specular: m.specular.extend(m.reflect).to_array(),
            texture: [
                base_layer.map_or(0, |l| l + 1),
                normal_layer.map_or(0, |l| l + 1),
                flags,
                m.effective_cutoff().unwrap_or(0.0).to_bits(),
            ],
            pbr: [
                pbr.metallic,
                pbr.roughness,
                f32::from_bits(mr_layer.map_or(0, |l| l + 1)),
                f32::from_bits(wrap(m.metallic_roughness_texture)),
            ],
            emissive: m
                .emissive
                .extend(f32::from_bits(
                    emissive_layer.map_or(0, |l| (l + 1) | (wrap(m.emissive_texture) << 24)),
                ))
                .to_array(),
        }
    }
}

impl From<&Material> for MaterialData {
    /// An untextured, opaque material.
    fn from(m: &Material) -> Self {
        Self::new(m, None, None, None, None, false)
    }
}

/// A light (`LightData`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightData {
    /// xyz position.
    pub position: [f32; 4],
    /// xyz direction, w: cos(cutoff).
    pub direction: [f32; 4],
    /// rgb ambient, w: range.
    pub ambient: [f32; 4],
    /// rgb diffuse, w: the light's size as soft shadows read it (a spot or point light's
    /// radius, a directional light's tangent of half its angular diameter; 0: hard).
    pub diffuse: [f32; 4],
    /// rgb specular.
    pub specular: [f32; 4],
    /// constant, linear, quadratic.
    pub attenuation: [f32; 4],
    /// Cascade far splits.
    pub splits: [f32; 4],
    /// first view, view count, type, unused.
    pub shadow: [u32; 4],
}

impl LightData {
    /// Packs a light whose shadow views are `views[first_view .. first_view + view_count]`
    /// (`view_count` 0 = no shadow).
    pub fn new(light: &Light, first_view: u32, views: &[ShadowView]) -> Self {
        let (kind, position, direction, cos_cutoff, range) = match light.kind {
            LightKind::Directional { direction, .. } => (
                LIGHT_DIRECTIONAL,
                Vec3::ZERO,
                direction.normalize(),
                -1.0,
                f32::MAX,
            ),
            LightKind::Spot {
                position,
                direction,
                cutoff_deg,
                range,
            } => (
                LIGHT_SPOT,
                position,
                direction.normalize(),
                cutoff_deg.to_radians().cos(),
                range,
            ),
            LightKind::Point { position, range } => (LIGHT_POINT, position, Vec3::Y, -1.0, range),
        };
        let mut splits = [f32::MAX; 4];
        for (i, v) in views.iter().take(4).enumerate() {
            if v.split_far > 0.0 {
                splits[i] = v.split_far;
            }
        }
        let a = light.attenuation;
        Self {
            position: position.extend(1.0).to_array(),
            direction: direction.extend(cos_cutoff).to_array(),
            ambient: light.ambient.extend(range).to_array(),
            diffuse: light.diffuse.extend(soft_size(light)).to_array(),
            specular: light.specular.extend(0.0).to_array(),
            attenuation: [a.constant, a.linear, a.quadratic, 0.0],
            splits,
            shadow: [first_view, views.len() as u32, kind, 0],
        }
    }
}

/// A light's size as the shaders read it: radius (spot, point) or the tangent of half the
/// angular diameter (directional); 0 for a hard light.
fn soft_size(light: &Light) -> f32 {
    match light.kind {
        LightKind::Directional { .. } => (0.5 * light.size).to_radians().tan(),
        _ => light.size,
    }
}

/// Grid and list layout of the clustered light lists (`ClusterUniforms`, see
/// [`crate::frame::clusters`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ClusterUniforms {
    /// Tiles across, tiles down, depth slices, tile side in pixels.
    pub grid: [u32; 4],
    /// Summary words, light words, words per slot, 1 = shading reads the lists.
    pub words: [u32; 4],
    /// Slicing near depth, slices per unit of ln(depth), camera near, camera far.
    pub depth: [f32; 4],
    /// 1/P00, 1/P11 of the (eye's) projection, one eye's width in pixels (the whole width
    /// when mono), half the eye separation (`frame::eyes`).
    pub proj: [f32; 4],
    /// Slot capacity, lights in the assignment list, clusters in the grid, eyes (1 or 2).
    pub counts: [u32; 4],
}

/// A shadow view and its atlas tile (`ShadowViewData`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadowViewData {
    /// Light world → clip.
    pub view_proj: [[f32; 4]; 4],
    /// x0, y0, side in texels.
    pub tile: [f32; 4],
    /// near, far, texel_world, orthographic (1/0).
    pub params: [f32; 4],
}

/// The per-view uniform of depth-only passes, padded to the 256-byte dynamic-offset alignment.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ViewUniform {
    /// Light world → clip.
    pub view_proj: [[f32; 4]; 4],
    /// near, far, texel size, projection (0 perspective, 1 orthographic, 2 paraboloid), as
    /// in [`ShadowViewData::params`].
    pub params: [f32; 4],
    /// Padding to 256 bytes.
    pub _pad: [[f32; 4]; 11],
}

/// Byte stride between consecutive [`ViewUniform`]s (the common `min_uniform_buffer_offset_alignment`).
pub const VIEW_UNIFORM_STRIDE: u64 = std::mem::size_of::<ViewUniform>() as u64;

/// The layout check every `#[repr(C)]` mirror of a WGSL struct is held to: naga's size and
/// member offsets of the struct in the composed shader against Rust's. Each module that owns a
/// mirror tests it beside its WGSL (`same_layout!(in SOURCE, Type, field, …)`).
#[cfg(test)]
pub(crate) mod layout {
    use wgpu::naga;

    /// naga's (size, [(member, offset)]) of the WGSL struct `name` in `source`.
    pub(crate) fn wgsl_layout_in(source: &str, name: &str) -> (u32, Vec<(String, u32)>) {
        let module = naga::front::wgsl::parse_str(source).expect("the shader parses");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).expect("layout");
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("struct {name} not found"));
        let naga::TypeInner::Struct { members, .. } = &ty.inner else {
            panic!("{name} is not a struct");
        };
        let fields = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
            .collect();
        (layouter[handle].size, fields)
    }

    /// Asserts that the Rust struct and the WGSL struct of the same name have the same fields
    /// at the same offsets and the same size.
    macro_rules! same_layout {
        ($ty:ty, $($field:ident),+) => {{
            $crate::gpu::types::layout::same_layout!(in $crate::gpu::shaders::COMMON, $ty, $($field),+)
        }};
        (in $src:expr, $ty:ty as $name:literal, $($field:ident),+) => {{
            let (size, fields) = $crate::gpu::types::layout::wgsl_layout_in(&$src, $name);
            let rust: Vec<(String, u32)> = vec![$((stringify!($field).to_string(), std::mem::offset_of!($ty, $field) as u32)),+];
            assert_eq!(fields, rust, "{} fields/offsets differ between WGSL {} and Rust", stringify!($ty), $name);
            assert_eq!(size as usize, std::mem::size_of::<$ty>(), "{} size differs", stringify!($ty));
        }};
        (in $src:expr, $ty:ty, $($field:ident),+) => {{
            let (size, fields) = $crate::gpu::types::layout::wgsl_layout_in(&$src, stringify!($ty));
            let rust: Vec<(String, u32)> = vec![$((stringify!($field).to_string(), std::mem::offset_of!($ty, $field) as u32)),+];
            assert_eq!(fields, rust, "{} fields/offsets differ between WGSL and Rust", stringify!($ty));
            assert_eq!(size as usize, std::mem::size_of::<$ty>(), "{} size differs", stringify!($ty));
        }};
    }
    pub(crate) use same_layout;
}

#[cfg(test)]
mod tests {
    use super::layout::same_layout;
    use super::*;

    #[test]
    fn rust_structs_match_wgsl_layouts() {
        same_layout!(
            FrameUniforms,
            view_proj,
            view,
            camera_pos,
            viewport,
            counts,
            bias,
            sky,
            soft,
            look,
            modes,
            eye_view_proj,
            eye_pos,
            eyes
        );
        same_layout!(InstanceData, model, normal, material);
        same_layout!(
            MaterialData,
            ambient,
            diffuse,
            specular,
            texture,
            pbr,
            emissive
        );
        same_layout!(
            LightData,
            position,
            direction,
            ambient,
            diffuse,
            specular,
            attenuation,
            splits,
            shadow
        );
        same_layout!(ShadowViewData, view_proj, tile, params);
        same_layout!(ClusterUniforms, grid, words, depth, proj, counts);
        assert_eq!(VIEW_UNIFORM_STRIDE, 256);
    }
}
