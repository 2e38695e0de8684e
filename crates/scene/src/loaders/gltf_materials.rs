//! glTF materials and images into this crate's Phong [`Material`]s and [`Texture`]s, with the
//! mapping documented in [`super`]: base colour, metallic and roughness to the Phong colours
//! and exponent, the base-colour and normal textures with their samplers' wrapping, each image
//! decoded once however many materials use it, a note (not an error) for an image that cannot
//! be read or decoded, and each material's `KHR_texture_transform` (baked into its meshes'
//! texture coordinates by `gltf.rs`).

use ::gltf::texture::WrappingMode;
use glam::{Affine2, Vec3};

use serde_json::Value;

use super::common::EMISSIVE_STRENGTH;
use super::gltf_extensions::TextureTransform;
use super::gltf_open::{read_uri, Opened};
use crate::look::Pbr;
use crate::model::Material;
use crate::texture::{AlphaMode, Texture, TextureRef, Wrap};

fn wrap(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::Repeat => Wrap::Repeat,
    }
}

/// Decoded images by glTF image index, each decoded on first use.
struct Images<'o> {
    opened: &'o Opened,
    /// `None`: not yet decoded; `Some(Ok(t))`: scene texture `t`; `Some(Err)`: why not.
    decoded: Vec<Option<Result<usize, String>>>,
    textures: Vec<Texture>,
}

impl<'o> Images<'o> {
    fn new(opened: &'o Opened) -> Self {
        Self {
            opened,
            decoded: vec![None; opened.document.as_json().images.len()],
            textures: Vec::new(),
        }
    }

    /// The scene texture of glTF image `image`, decoding it the first time.
    fn texture(&mut self, image: usize) -> Result<usize, String> {
        let Some(slot) = self.decoded.get(image) else {
            return Err(format!("image {image} does not exist"));
        };
        if let Some(done) = slot {
            return done.clone();
        }
        let result = self.decode(image).map(|t| {
            self.textures.push(t);
            self.textures.len() - 1
        });
        self.decoded[image] = Some(result.clone());
        result
    }

    fn decode(&self, index: usize) -> Result<Texture, String> {
        let root = self.opened.document.as_json();
        let image = root
            .images
            .get(index)
            .ok_or_else(|| format!("image {index} does not exist"))?;
        let uri_name = image
            .uri
            .as_deref()
            .filter(|u| !u.starts_with("data:"))
            .map(|u| u.rsplit('/').next().unwrap_or(u).to_string());
        let name = image
            .name
            .clone()
            .or(uri_name)
            .unwrap_or_else(|| format!("image {index}"));
        let bytes: Vec<u8> = if let Some(view) = &image.buffer_view {
            let view = root
                .buffer_views
                .get(view.value())
                .ok_or_else(|| format!("image '{name}': its buffer view does not exist"))?;
            let data = self
                .opened
                .buffers
                .get(view.buffer.value())
                .ok_or_else(|| format!("image '{name}': its buffer does not exist"))?;
            let start = view.byte_offset.map_or(0, |o| o.0 as usize);
            let end = start.checked_add(view.byte_length.0 as usize);
            match end.and_then(|end| data.0.get(start..end)) {
                Some(b) => b.to_vec(),
                None => {
                    return Err(format!(
                        "image '{name}': its buffer view is outside the buffer"
                    ))
                }
            }
        } else if let Some(uri) = &image.uri {
            read_uri(&self.opened.base, uri, self.opened.allow_outside)
                .map_err(|e| format!("image '{name}': {e}"))?
        } else {
            return Err(format!(
                "image '{name}' has neither a buffer view nor a URI"
            ));
        };
        Texture::decode(&name, &bytes)
    }
}

/// What [`read_materials`] returns.
pub(super) struct Materials {
    /// Every material of the document, in order.
    pub(super) materials: Vec<Material>,
    /// The textures they use.
    pub(super) textures: Vec<Texture>,
    /// For each material, the `KHR_texture_transform` to bake into the texture coordinates of
    /// its meshes (`None`: none, or the identity).
    pub(super) uv_transforms: Vec<Option<Affine2>>,
}

/// Material `index`'s emitted radiance: `emissiveFactor` times
/// `KHR_materials_emissive_strength`'s `emissiveStrength` (default 1); black, with a note,
/// where the product is not a finite, non-negative colour.
fn emissive(
    json: &Value,
    index: usize,
    factor: [f32; 3],
    name: &str,
    notes: &mut Vec<String>,
) -> Vec3 {
    let strength = json
        .get("materials")
        .and_then(|m| m.get(index))
        .and_then(|m| m.get("extensions"))
        .and_then(|e| e.get(EMISSIVE_STRENGTH))
        .and_then(|e| e.get("emissiveStrength"))
        .and_then(Value::as_f64)
        .map_or(1.0, |v| v as f32);
    let e = Vec3::from(factor) * strength;
    if e.is_finite() && e.min_element() >= 0.0 {
        e
    } else {
        notes.push(format!(
            "material '{name}': emissive factor {factor:?} × strength {strength} is not a \
             colour: it emits nothing"
        ));
        Vec3::ZERO
    }
}

/// Every material of the document, in order, the textures they use and their texture
/// transforms.
pub(super) fn read_materials(opened: &Opened, notes: &mut Vec<String>) -> Materials {
    let mut images = Images::new(opened);
    let mut materials = Vec::new();
    let mut uv_transforms = Vec::new();
    for (i, m) in opened.document.materials().enumerate() {
        let name = m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material {i}"));
        let pbr = m.pbr_metallic_roughness();
        let base = pbr.base_color_factor();
        let rgb = Vec3::new(base[0], base[1], base[2]);
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
        let mut out = Material {
            ambient: rgb,
            diffuse: rgb,
            specular: Vec3::splat(0.04).lerp(rgb, metallic),
            shininess: shininess_from_roughness(roughness),
            base_color_texture: None,
            normal_texture: None,
            metallic_roughness_texture: None,
            emissive_texture: None,
            base_alpha: base[3],
            alpha_mode: match m.alpha_mode() {
                ::gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                ::gltf::material::AlphaMode::Mask => AlphaMode::Mask,
                ::gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            alpha_cutoff: m.alpha_cutoff().unwrap_or(0.5),
            double_sided: m.double_sided(),
            cull_back_faces: !m.double_sided(),
            pbr: Some(Pbr {
                metallic,
                roughness,
            }),
            emissive: emissive(&opened.json, i, m.emissive_factor(), &name, notes),
            // The glTF BRDF derives its reflection from metallic and roughness.
            reflect: 0.0,
        };
        let json = opened.json.get("materials").and_then(|m| m.get(i));
        let transform_of = |pointer: &str, what: &str, notes: &mut Vec<String>| {
            let info = json.and_then(|m| m.pointer(pointer))?;
            match TextureTransform::of(info) {
                Ok(t) => t,
                Err(reason) => {
                    notes.push(format!(
                        "material '{name}': the KHR_texture_transform of its {what} texture is \
                         not used ({reason})"
                    ));
                    None
                }
            }
        };
        let base_transform = transform_of(
            "/pbrMetallicRoughness/baseColorTexture",
            "base-colour",
            notes,
        );
        let normal_transform = transform_of("/normalTexture", "normal", notes);
        let mr_transform = transform_of(
            "/pbrMetallicRoughness/metallicRoughnessTexture",
            "metallic-roughness",
            notes,
        );
        let emissive_transform = transform_of("/emissiveTexture", "emissive", notes);
        let mut use_texture = |what: &str, tex: ::gltf::Texture<'_>, set: u32| {
            if set != 0 {
                notes.push(format!(
                    "material '{name}': its {what} texture uses texture-coordinate set {set}; \
                     set 0 is used"
                ));
            }
            let sampler = tex.sampler();
            match images.texture(tex.source().index()) {
                Ok(t) => Some(TextureRef {
                    texture: t,
                    wrap_s: wrap(sampler.wrap_s()),
                    wrap_t: wrap(sampler.wrap_t()),
                }),
                Err(reason) => {
                    notes.push(format!(
                        "material '{name}': its {what} texture could not be used ({reason}): \
                         left without it"
                    ));
                    None
                }
            }
        };
        // A transform's texCoord replaces the reference's texture-coordinate set.
        let set_of = |t: &Option<TextureTransform>, set: u32| {
            t.and_then(|t| t.tex_coord)
                .map_or(set, |s| u32::try_from(s).unwrap_or(u32::MAX))
        };
        if let Some(info) = pbr.base_color_texture() {
            let set = set_of(&base_transform, info.tex_coord());
            out.base_color_texture = use_texture("base-colour", info.texture(), set);
        }
        if let Some(info) = m.normal_texture() {
            let set = set_of(&normal_transform, info.tex_coord());
            out.normal_texture = use_texture("normal", info.texture(), set);
        }
        if let Some(info) = pbr.metallic_roughness_texture() {
            let set = set_of(&mr_transform, info.tex_coord());
            out.metallic_roughness_texture = use_texture("metallic-roughness", info.texture(), set);
        }
        if out.emissive.max_element() > 0.0 {
            if let Some(info) = m.emissive_texture() {
                let set = set_of(&emissive_transform, info.tex_coord());
                out.emissive_texture = use_texture("emissive", info.texture(), set);
            }
        }
        let chosen = if out.base_color_texture.is_some() {
            base_transform
        } else {
            normal_transform
        };
        let matrix = |t: Option<TextureTransform>| t.map_or(Affine2::IDENTITY, |t| t.matrix);
        for (what, present, transform) in [
            (
                "metallic-roughness",
                out.metallic_roughness_texture.is_some(),
                mr_transform,
            ),
            (
                "emissive",
                out.emissive_texture.is_some(),
                emissive_transform,
            ),
        ] {
            if present
                && (out.base_color_texture.is_some() || out.normal_texture.is_some())
                && !matrix(transform).abs_diff_eq(matrix(chosen), 1e-6)
            {
                notes.push(format!(
                    "material '{name}': its {what} texture has a KHR_texture_transform \
                     different from its other textures'; theirs is applied (the {what} map \
                     is misplaced)"
                ));
            }
        }
        let lone_mr = out.base_color_texture.is_none() && out.normal_texture.is_none();
        uv_transforms.push(uv_transform(
            &name,
            out.base_color_texture
                .is_some()
                .then_some(base_transform)
                .flatten(),
            if lone_mr {
                out.metallic_roughness_texture
                    .is_some()
                    .then_some(mr_transform)
                    .flatten()
            } else {
                out.normal_texture
                    .is_some()
                    .then_some(normal_transform)
                    .flatten()
            },
            out.base_color_texture.is_some(),
            notes,
        ));
        materials.push(out);
    }
    Materials {
        materials,
        textures: images.textures,
        uv_transforms,
    }
}

/// The one texture-coordinate transform a material's meshes get (this renderer samples every
/// texture of a material with the same coordinates): the base-colour texture's, or the normal
/// texture's where the material has no base-colour texture. Where the two textures have
/// different transforms, the base colour's wins and a note says the normal map is misplaced.
fn uv_transform(
    name: &str,
    base: Option<TextureTransform>,
    normal: Option<TextureTransform>,
    has_base: bool,
    notes: &mut Vec<String>,
) -> Option<Affine2> {
    let base_matrix = base.map_or(Affine2::IDENTITY, |t| t.matrix);
    let normal_matrix = normal.map_or(Affine2::IDENTITY, |t| t.matrix);
    let chosen = if has_base {
        if normal.is_some() && !normal_matrix.abs_diff_eq(base_matrix, 1e-6) {
            notes.push(format!(
                "material '{name}': its normal texture has a KHR_texture_transform different \
                 from its base-colour texture's; the base colour's is applied to both (the normal \
                 map is misplaced)"
            ));
        }
        base_matrix
    } else {
        normal_matrix
    };
    (chosen != Affine2::IDENTITY).then_some(chosen)
}

/// Phong exponent of a glTF roughness: `2/α² − 2` with `α = roughness²` (the Blinn-Phong
/// exponent whose lobe matches GGX of that α), clamped to 1..=512.
pub(crate) fn shininess_from_roughness(roughness: f32) -> f32 {
    let alpha = roughness * roughness;
    let s = 2.0 / (alpha * alpha) - 2.0;
    if s.is_nan() {
        512.0
    } else {
        s.clamp(1.0, 512.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roughness_to_shininess() {
        assert_eq!(shininess_from_roughness(0.0), 512.0);
        assert_eq!(shininess_from_roughness(1.0), 1.0);
        let r: f32 = 0.5;
        let a = r * r;
        assert!((shininess_from_roughness(r) - (2.0 / (a * a) - 2.0)).abs() < 1e-3);
    }
}
