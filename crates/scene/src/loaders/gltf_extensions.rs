//! The glTF extensions: which ones this loader reads, which a file may require and still be
//! loaded without them, one note for each one it uses but the loader ignores, and
//! `KHR_texture_transform`'s texture-coordinate transform.
//!
//! Read here: `KHR_lights_punctual` (lights), `KHR_texture_transform` (baked into texture
//! coordinates, `gltf.rs`), `EXT_mesh_gpu_instancing` (`gltf_instancing`),
//! `KHR_draco_mesh_compression` (`gltf_draco`), `EXT_meshopt_compression` (`gltf_meshopt`),
//! `KHR_mesh_quantization` (integer vertex attributes, `gltf_accessors`). Everything
//! else a file uses gets exactly one note naming it, however many materials or nodes use it.

use std::collections::BTreeMap;

use glam::{Affine2, Vec2};
use serde_json::Value;

/// The extensions this loader reads.
pub(crate) const SUPPORTED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_mesh_quantization",
    "KHR_materials_emissive_strength",
];

/// Extensions a file may *require* that this loader still reads without: the PBR material
/// extensions beyond metallic-roughness and emissive strength (the scene looks different from
/// what the author intended, and a note says so). Any other unsupported requirement (compressed
/// textures, for one) is refused.
pub(crate) fn ignorable_requirement(name: &str) -> bool {
    name.starts_with("KHR_materials_")
}

/// One note per extension the file uses (in `extensionsUsed`, or in an `extensions` object
/// anywhere in the document) that this loader does not read, naming it, what uses it and what
/// that means for the picture.
pub(crate) fn unsupported_notes(json: &Value, required: &[String]) -> Vec<String> {
    // Extension name → the kinds of things using it (`materials`, `nodes`, …) and how many.
    let mut uses: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    if let Some(Value::Array(used)) = json.get("extensionsUsed") {
        for name in used.iter().filter_map(Value::as_str) {
            uses.entry(name.to_string()).or_default();
        }
    }
    if let Value::Object(top) = json {
        for (key, value) in top {
            if key == "extensions" {
                if let Value::Object(e) = value {
                    for name in e.keys() {
                        uses.entry(name.clone()).or_default();
                    }
                }
                continue;
            }
            if let Value::Array(items) = value {
                for item in items {
                    let mut found = Vec::new();
                    collect(item, &mut found);
                    found.sort();
                    found.dedup();
                    for name in found {
                        *uses
                            .entry(name)
                            .or_default()
                            .entry(key.clone())
                            .or_default() += 1;
                    }
                }
            }
        }
    }
    uses.into_iter()
        .filter(|(name, _)| !SUPPORTED.contains(&name.as_str()))
        .map(|(name, by)| {
            let users: Vec<String> = by
                .iter()
                .map(|(kind, n)| format!("{n} of its {kind}"))
                .collect();
            let on = if users.is_empty() {
                String::new()
            } else {
                format!(" (on {})", users.join(", "))
            };
            let required = if required.contains(&name) {
                " although the file requires it"
            } else {
                ""
            };
            format!(
                "the file uses the extension {name}{on}, which this loader ignores{required}: \
                 {}",
                consequence(&name)
            )
        })
        .collect()
}

/// Every extension name in `value` and below.
fn collect(value: &Value, out: &mut Vec<String>) {
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                if key == "extensions" {
                    if let Value::Object(e) = v {
                        out.extend(e.keys().cloned());
                    }
                }
                collect(v, out);
            }
        }
        Value::Array(items) => items.iter().for_each(|v| collect(v, out)),
        _ => {}
    }
}

/// What ignoring an extension does to the picture, in a few words.
fn consequence(name: &str) -> &'static str {
    if name.starts_with("KHR_materials_") {
        "materials may look different from what the author intended"
    } else if name.starts_with("KHR_texture_") || name.starts_with("EXT_texture_") {
        "textures stored that way are not shown"
    } else if name == "KHR_animation_pointer" || name.contains("anim") {
        "the scene is shown as it stands, unanimated"
    } else {
        "what it adds is not shown"
    }
}

/// A `KHR_texture_transform` on a texture reference: `uv' = T(offset) · R(rotation) ·
/// S(scale) · uv`, as the extension defines it (rotation counter-clockwise in UV space, about
/// the origin), and the texture-coordinate set it overrides the reference's with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TextureTransform {
    pub(crate) matrix: Affine2,
    pub(crate) tex_coord: Option<u64>,
}

impl TextureTransform {
    /// The transform on the texture reference `info` (a `textureInfo` JSON object), if it has
    /// one; the error says which number is not one.
    pub(crate) fn of(info: &Value) -> Result<Option<Self>, String> {
        let Some(t) = info.pointer("/extensions/KHR_texture_transform") else {
            return Ok(None);
        };
        let pair = |key: &str, default: Vec2| -> Result<Vec2, String> {
            match t.get(key) {
                None => Ok(default),
                Some(v) => {
                    let a: Option<Vec<f32>> = v.as_array().map(|a| {
                        a.iter()
                            .filter_map(|x| x.as_f64().map(|x| x as f32))
                            .collect()
                    });
                    match a.as_deref() {
                        Some([x, y]) if x.is_finite() && y.is_finite() => Ok(Vec2::new(*x, *y)),
                        _ => Err(format!("its {key} {v} is not two numbers")),
                    }
                }
            }
        };
        let offset = pair("offset", Vec2::ZERO)?;
        let scale = pair("scale", Vec2::ONE)?;
        let rotation = match t.get("rotation") {
            None => 0.0,
            Some(v) => match v.as_f64() {
                Some(r) if r.is_finite() => r as f32,
                _ => return Err(format!("its rotation {v} is not a number")),
            },
        };
        // The extension's rotation matrix is [[cos, sin], [−sin, cos]] (rows), which is glam's
        // rotation by −rotation.
        let matrix = Affine2::from_translation(offset)
            * Affine2::from_angle(-rotation)
            * Affine2::from_scale(scale);
        Ok(Some(Self {
            matrix,
            tex_coord: t.get("texCoord").and_then(Value::as_u64),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn texture_transform_follows_the_extension() {
        // The extension's sample: offset (0.5, 0), rotation π/2, scale (2, 2).
        let info = json!({ "index": 0, "extensions": { "KHR_texture_transform": {
            "offset": [0.5, 0.0], "rotation": std::f64::consts::FRAC_PI_2, "scale": [2.0, 2.0]
        }}});
        let t = TextureTransform::of(&info).unwrap().unwrap();
        // Rows [[cos, sin], [−sin, cos]] at π/2: (u, v) → (v, −u), then × 2, then + offset.
        let uv = t.matrix.transform_point2(Vec2::new(0.25, 0.5));
        assert!(
            (uv - Vec2::new(0.5 + 2.0 * 0.5, -2.0 * 0.25)).length() < 1e-6,
            "{uv}"
        );
        assert_eq!(TextureTransform::of(&json!({ "index": 0 })).unwrap(), None);
        assert!(TextureTransform::of(
            &json!({ "extensions": { "KHR_texture_transform": { "scale": [1] } } })
        )
        .is_err());
    }

    #[test]
    fn one_note_per_unsupported_extension() {
        let doc = json!({
            "extensionsUsed": ["KHR_materials_sheen", "KHR_lights_punctual", "EXT_foo"],
            "materials": [
                { "extensions": { "KHR_materials_sheen": {} } },
                { "pbrMetallicRoughness": { "baseColorTexture": { "index": 0,
                    "extensions": { "KHR_materials_sheen": {}, "KHR_texture_transform": {} } } } }
            ]
        });
        let notes = unsupported_notes(&doc, &["EXT_foo".to_string()]);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(notes[0].contains("EXT_foo") && notes[0].contains("requires"));
        assert!(
            notes[1].contains("KHR_materials_sheen") && notes[1].contains("2 of its materials")
        );
    }
}
