//! glTF materials and images into this crate's Phong [`Material`]s and [`Texture`]s, with the
//! mapping documented in [`super`]: base colour, metallic and roughness to the Phong colours
//! and exponent, the base-colour and normal textures with their samplers' wrapping, each image
//! decoded once however many materials use it, and a note (not an error) for an image that
//! cannot be read or decoded and for the material extensions that are ignored.

use std::collections::BTreeSet;
use std::path::PathBuf;

use ::gltf::texture::WrappingMode;
use glam::Vec3;
use serde_json::Value;

use super::common::{read_limited, EMISSIVE_STRENGTH};
use super::gltf_open::{percent_decode, Opened};
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
            if let Some(rest) = uri.strip_prefix("data:") {
                let (meta, data) = rest
                    .split_once(',')
                    .ok_or_else(|| format!("image '{name}': malformed data URI"))?;
                if !meta.ends_with(";base64") {
                    return Err(format!(
                        "image '{name}': only base64 data URIs are supported"
                    ));
                }
                super::base64::decode(data).map_err(|e| format!("image '{name}': {e}"))?
            } else {
                let file = if let Some(rest) = uri.strip_prefix("file://") {
                    PathBuf::from(rest)
                } else if let Some(rest) = uri.strip_prefix("file:") {
                    PathBuf::from(rest)
                } else if uri.contains(':') {
                    return Err(format!(
                        "image '{name}': URI '{uri}' is neither a file nor a data: URI (nothing \
                         is downloaded)"
                    ));
                } else {
                    let decoded = percent_decode(uri).ok_or_else(|| {
                        format!("image '{name}': URI '{uri}' is not valid percent-encoded UTF-8")
                    })?;
                    self.opened.base.join(decoded)
                };
                read_limited(&file).map_err(|e| e.to_string())?
            }
        } else {
            return Err(format!(
                "image '{name}' has neither a buffer view nor a URI"
            ));
        };
        Texture::decode(&name, &bytes)
    }
}

/// The extensions a material (or one of its texture references) uses, from the raw JSON.
fn material_extensions(json: &Value, material: usize) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let Some(m) = json.get("materials").and_then(|m| m.get(material)) else {
        return names;
    };
    let mut add = |v: Option<&Value>| {
        if let Some(Value::Object(e)) = v.and_then(|v| v.get("extensions")) {
            names.extend(e.keys().cloned());
        }
    };
    add(Some(m));
    for key in ["normalTexture", "occlusionTexture", "emissiveTexture"] {
        add(m.get(key));
    }
    if let Some(p) = m.get("pbrMetallicRoughness") {
        add(Some(p));
        add(p.get("baseColorTexture"));
        add(p.get("metallicRoughnessTexture"));
    }
    names
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

/// Every material of the document, in order, and the textures they use.
pub(super) fn read_materials(
    opened: &Opened,
    notes: &mut Vec<String>,
) -> (Vec<Material>, Vec<Texture>) {
    let mut images = Images::new(opened);
    let mut materials = Vec::new();
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
        };
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
                    log::warn!("material '{name}': {what} texture not used: {reason}");
                    notes.push(format!(
                        "material '{name}': its {what} texture could not be used ({reason}): \
                         left without it"
                    ));
                    None
                }
            }
        };
        if let Some(info) = pbr.base_color_texture() {
            out.base_color_texture = use_texture("base-colour", info.texture(), info.tex_coord());
        }
        if let Some(info) = m.normal_texture() {
            out.normal_texture = use_texture("normal", info.texture(), info.tex_coord());
        }
        let mut extensions = material_extensions(&opened.json, i);
        extensions.remove(EMISSIVE_STRENGTH);
        if !extensions.is_empty() {
            notes.push(format!(
                "material '{name}': {} ignored",
                extensions.into_iter().collect::<Vec<_>>().join(", ")
            ));
        }
        materials.push(out);
    }
    (materials, images.textures)
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
