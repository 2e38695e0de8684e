//! A small glTF 2.0 writer: a [`Scene`] as one self-contained `.gltf` (buffer and images as
//! base64 `data:` URIs) or `.glb` (buffer and images in the binary chunk).
//!
//! Why: tests and tools need scene files with textures, alpha masks, lights and a camera that
//! go through the real loading path ([`load_scene`](super::load_scene)); writing them from a
//! [`Scene`] keeps them exact and free of downloads. So the writer is the loader's inverse
//! where the formats meet, and says where they do not (see [`write_gltf`]).

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat3, Mat4, Quat, Vec3};
use serde_json::{json, Map, Value};

use super::base64;
use super::common::{EMISSIVE_STRENGTH, GLTF_SIZE_EXTRA, PHONG_PER_LUX};
use crate::error::SceneError;
use crate::look::Lighting;
use crate::model::{LightKind, Material, Scene};
use crate::texture::{AlphaMode, TextureRef, Wrap};

/// Writes `scene` as glTF 2.0 at `path`: binary (`.glb`) if the extension says so (any case),
/// else JSON with everything embedded.
///
/// - Each instance becomes a node (its transform as a `matrix`, omitted when identity) with a
///   mesh of one triangle primitive: `POSITION` (with bounds), `NORMAL`, `TEXCOORD_0` when the
///   mesh has texture coordinates, `u32` indices, and the instance's material. Meshes without
///   triangles are left out. Loading bakes each node's transform, so a mesh placed twice comes
///   back as two meshes.
/// - Materials, all and in order: `baseColorFactor` = (diffuse, `base_alpha`), `alphaMode`,
///   `alphaCutoff` (only for `Mask`, where it means something), `doubleSided`, base-colour,
///   normal, metallic-roughness and emissive textures (each scene texture an embedded PNG
///   image, with a sampler for its wrap modes). The Phong terms go through the loader's mapping backwards: roughness =
///   `(2 / (shininess + 2))^¼` (shininess clamped to 1..=512), metallic = the least-squares
///   fit of `specular = mix(0.04, diffuse, metallic)`. So shininess always round-trips,
///   specular only when it has that form (e.g. grey diffuse with grey specular), and ambient
///   comes back equal to diffuse. A material with [`Material::pbr`] writes those parameters
///   instead (they load back exactly). A non-black [`Material::emissive`] is written as
///   `emissiveFactor`, its part above 1 as `KHR_materials_emissive_strength`.
/// - Lights as `KHR_lights_punctual` nodes: `intensity = max(diffuse)` for a physical scene
///   ([`Lighting::Physical`]: the colours are candela and lux already), `max(diffuse) /
///   PHONG_PER_LUX` for a Phong one (one unit of Phong light is 10 cd or 10 lx),
///   `color = diffuse / max(diffuse)` (negative channels written as 0), `range`, the spot's
///   cutoff as `outerConeAngle` (inner 0), the direction as the node's rotation of −Z, the
///   position as its translation, a size above 0 as the light's
///   `"extras": { "manyshadows_size": size }` ([`GLTF_SIZE_EXTRA`]). Loading gives back the
///   diffuse colour (as diffuse and specular), range, cone, position, direction and size to
///   float rounding. Not representable:
///   ambient and a specular colour different from diffuse, the attenuation (loaded lights use
///   the inverse square), shadow resolutions, cascades, `casts_shadows`.
/// - The camera as a perspective camera node: `yfov`, `znear`, `zfar`, translation = position,
///   rotation taking −Z to the view direction and +Y to the up vector made orthogonal to it.
///   glTF cameras have no target, so a loaded camera looks the same way from the same point
///   but its target is placed at the scene's centre distance (same view matrix).
/// - Instances that cast no shadow are written like the others (glTF has no such flag).
///
/// Errors: [`Scene::validate`]'s, [`SceneError::TooLarge`] for a `.glb` over 4 GiB,
/// [`SceneError::Io`] if the file cannot be written.
pub fn write_gltf(scene: &Scene, path: &Path) -> Result<(), SceneError> {
    scene.validate()?;
    let glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let mut w = Writer::default();

    // Images, samplers and textures.
    let mut images = Vec::with_capacity(scene.textures.len());
    for (i, t) in scene.textures.iter().enumerate() {
        let png =
            encode_png(t).map_err(|reason| SceneError::InvalidTexture { index: i, reason })?;
        let mut image = json!({ "name": t.name });
        if glb {
            image["bufferView"] = json!(w.view(&png, None));
            image["mimeType"] = json!("image/png");
        } else {
            image["uri"] = json!(format!("data:image/png;base64,{}", base64::encode(&png)));
        }
        images.push(image);
    }
    let mut samplers: Vec<Value> = Vec::new();
    let mut sampler_of: HashMap<(Wrap, Wrap), usize> = HashMap::new();
    let mut textures: Vec<Value> = Vec::new();
    let mut texture_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut texture_ref = |r: TextureRef| -> usize {
        let sampler = *sampler_of.entry((r.wrap_s, r.wrap_t)).or_insert_with(|| {
            samplers.push(json!({ "wrapS": wrap_code(r.wrap_s), "wrapT": wrap_code(r.wrap_t) }));
            samplers.len() - 1
        });
        *texture_of.entry((r.texture, sampler)).or_insert_with(|| {
            textures.push(json!({ "source": r.texture, "sampler": sampler }));
            textures.len() - 1
        })
    };

    let materials: Vec<Value> = scene
        .materials
        .iter()
        .enumerate()
        .map(|(i, m)| material_json(i, m, &mut texture_ref))
        .collect();

    // Meshes (one accessor set per scene mesh, one glTF mesh per mesh and material) and nodes.
    let mut mesh_accessors: HashMap<usize, Value> = HashMap::new();
    let mut gltf_meshes: Vec<Value> = Vec::new();
    let mut gltf_mesh_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut nodes: Vec<Value> = Vec::new();
    for (i, inst) in scene.instances.iter().enumerate() {
        let mesh = &scene.meshes[inst.mesh];
        if mesh.indices.is_empty() || mesh.positions.is_empty() {
            continue;
        }
        let attributes = mesh_accessors
            .entry(inst.mesh)
            .or_insert_with(|| w.mesh(mesh))
            .clone();
        let gltf_mesh = *gltf_mesh_of
            .entry((inst.mesh, inst.material))
            .or_insert_with(|| {
                let mut primitive = attributes.clone();
                primitive["material"] = json!(inst.material);
                primitive["mode"] = json!(4);
                gltf_meshes.push(json!({ "name": mesh.name, "primitives": [primitive] }));
                gltf_meshes.len() - 1
            });
        let mut node = json!({ "name": format!("instance {i}"), "mesh": gltf_mesh });
        if inst.transform != Mat4::IDENTITY {
            node["matrix"] = json!(inst.transform.to_cols_array());
        }
        nodes.push(node);
    }

    // Lights.
    let mut lights: Vec<Value> = Vec::new();
    for (i, l) in scene.lights.iter().enumerate() {
        let peak = l.diffuse.max_element();
        let (color, intensity) = if peak > 0.0 && peak.is_finite() {
            let per_unit = match scene.lighting {
                Lighting::Phong => 1.0 / PHONG_PER_LUX,
                Lighting::Physical => 1.0,
            };
            ((l.diffuse / peak).max(Vec3::ZERO), peak * per_unit)
        } else {
            (Vec3::ONE, 0.0)
        };
        let mut def = json!({
            "name": format!("light {i} ({})", l.type_name()),
            "type": l.type_name(),
            "color": color.to_array(),
            "intensity": intensity,
        });
        if l.size > 0.0 {
            def["extras"] = json!({ GLTF_SIZE_EXTRA: l.size });
        }
        let mut node = json!({ "name": format!("light {i}") });
        let aim = |direction: Vec3| -> [f32; 4] {
            Quat::from_rotation_arc(Vec3::NEG_Z, direction.normalize())
                .normalize()
                .to_array()
        };
        match l.kind {
            LightKind::Directional { direction, .. } => {
                node["rotation"] = json!(aim(direction));
            }
            LightKind::Spot {
                position,
                direction,
                cutoff_deg,
                range,
            } => {
                def["range"] = json!(range);
                def["spot"] = json!({
                    "innerConeAngle": 0.0,
                    "outerConeAngle": cutoff_deg.to_radians(),
                });
                node["translation"] = json!(position.to_array());
                node["rotation"] = json!(aim(direction));
            }
            LightKind::Point { position, range } => {
                def["range"] = json!(range);
                node["translation"] = json!(position.to_array());
            }
        }
        node["extensions"] = json!({ "KHR_lights_punctual": { "light": lights.len() } });
        lights.push(def);
        nodes.push(node);
    }

    // The camera.
    let c = &scene.camera;
    let forward = (c.target - c.position).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let rotation = Quat::from_mat3(&Mat3::from_cols(right, up, -forward)).normalize();
    nodes.push(json!({
        "name": "camera",
        "camera": 0,
        "translation": c.position.to_array(),
        "rotation": rotation.to_array(),
    }));
    let cameras = json!([{
        "name": "camera",
        "type": "perspective",
        "perspective": {
            "yfov": c.fov_y_deg.to_radians(),
            "znear": c.near,
            "zfar": c.far,
        },
    }]);

    // The document.
    let mut doc = Map::new();
    doc.insert(
        "asset".into(),
        json!({ "version": "2.0", "generator": "manyshadows-scene write_gltf" }),
    );
    doc.insert("scene".into(), json!(0));
    doc.insert(
        "scenes".into(),
        json!([{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }]),
    );
    let mut put = |key: &str, items: Vec<Value>| {
        if !items.is_empty() {
            doc.insert(key.into(), Value::Array(items));
        }
    };
    put("nodes", nodes);
    put("meshes", gltf_meshes);
    put("materials", materials);
    put("textures", textures);
    put("samplers", samplers);
    put("images", images);
    put("accessors", w.accessors);
    put("bufferViews", w.views);
    doc.insert("cameras".into(), cameras);
    let mut used = Vec::new();
    if !lights.is_empty() {
        used.push("KHR_lights_punctual");
    }
    if scene
        .materials
        .iter()
        .any(|m| m.emissive.max_element() > 1.0)
    {
        used.push(EMISSIVE_STRENGTH);
    }
    if !used.is_empty() {
        doc.insert("extensionsUsed".into(), json!(used));
    }
    if !lights.is_empty() {
        doc.insert(
            "extensions".into(),
            json!({ "KHR_lights_punctual": { "lights": lights } }),
        );
    }
    if !w.bin.is_empty() {
        let mut buffer = json!({ "byteLength": w.bin.len() });
        if !glb {
            buffer["uri"] = json!(format!(
                "data:application/octet-stream;base64,{}",
                base64::encode(&w.bin)
            ));
        }
        doc.insert("buffers".into(), json!([buffer]));
    }
    let text = serde_json::to_vec(&Value::Object(doc))
        .map_err(|e| SceneError::InvalidRequest(format!("glTF writer: {e}")))?;
    let bytes = if glb {
        glb_bytes(path, text, w.bin)?
    } else {
        text
    };
    std::fs::write(path, bytes).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Buffer views and accessors over one growing binary buffer.
#[derive(Default)]
struct Writer {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Writer {
    /// Appends `bytes` (4-byte aligned) as a buffer view; returns its index.
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({
            "buffer": 0,
            "byteOffset": self.bin.len(),
            "byteLength": bytes.len(),
        });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// An accessor over a new view of `bytes`; returns its index.
    fn accessor(&mut self, bytes: &[u8], target: u32, mut accessor: Value) -> usize {
        accessor["bufferView"] = json!(self.view(bytes, Some(target)));
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Writes a mesh's vertex data and indices; returns the primitive's `attributes` and
    /// `indices` as JSON.
    fn mesh(&mut self, mesh: &crate::model::Mesh) -> Value {
        const ARRAY_BUFFER: u32 = 34962;
        const ELEMENT_ARRAY_BUFFER: u32 = 34963;
        const FLOAT: u32 = 5126;
        const UNSIGNED_INT: u32 = 5125;
        let n = mesh.positions.len();
        let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let floats = |v: &mut dyn Iterator<Item = f32>| -> Vec<u8> {
            v.flat_map(f32::to_le_bytes).collect()
        };
        let position = self.accessor(
            &floats(&mut mesh.positions.iter().flat_map(|p| p.to_array())),
            ARRAY_BUFFER,
            json!({ "componentType": FLOAT, "count": n, "type": "VEC3",
                    "min": lo.to_array(), "max": hi.to_array() }),
        );
        let normal = self.accessor(
            &floats(&mut mesh.normals.iter().flat_map(|p| p.to_array())),
            ARRAY_BUFFER,
            json!({ "componentType": FLOAT, "count": n, "type": "VEC3" }),
        );
        let mut attributes = json!({ "POSITION": position, "NORMAL": normal });
        if mesh.uvs.len() == n {
            attributes["TEXCOORD_0"] = json!(self.accessor(
                &floats(&mut mesh.uvs.iter().flat_map(|t| t.to_array())),
                ARRAY_BUFFER,
                json!({ "componentType": FLOAT, "count": n, "type": "VEC2" }),
            ));
        }
        let indices: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = self.accessor(
            &indices,
            ELEMENT_ARRAY_BUFFER,
            json!({ "componentType": UNSIGNED_INT, "count": mesh.indices.len(), "type": "SCALAR" }),
        );
        json!({ "attributes": attributes, "indices": indices })
    }
}

fn wrap_code(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 10497,
        Wrap::MirroredRepeat => 33648,
        Wrap::ClampToEdge => 33071,
    }
}

/// The glTF material of a Phong material (see [`write_gltf`] for what round-trips).
fn material_json(
    index: usize,
    m: &Material,
    texture: &mut dyn FnMut(TextureRef) -> usize,
) -> Value {
    // specular = 0.04 + (diffuse − 0.04)·metallic per channel: least squares over the channels.
    let a = m.diffuse - Vec3::splat(0.04);
    let b = m.specular - Vec3::splat(0.04);
    let metallic = if a.length_squared() > 1e-12 {
        (a.dot(b) / a.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let shininess = m.shininess.clamp(1.0, 512.0);
    let roughness = (2.0 / (shininess + 2.0)).sqrt().sqrt();
    let (metallic, roughness) = m
        .pbr
        .map_or((metallic, roughness), |p| (p.metallic, p.roughness));
    let mut pbr = json!({
        "baseColorFactor": [m.diffuse.x, m.diffuse.y, m.diffuse.z, m.base_alpha],
        "metallicFactor": metallic,
        "roughnessFactor": roughness,
    });
    if let Some(t) = m.base_color_texture {
        pbr["baseColorTexture"] = json!({ "index": texture(t) });
    }
    if let Some(t) = m.metallic_roughness_texture {
        pbr["metallicRoughnessTexture"] = json!({ "index": texture(t) });
    }
    let mut out = json!({
        "name": format!("material {index}"),
        "pbrMetallicRoughness": pbr,
        "alphaMode": match m.alpha_mode {
            AlphaMode::Opaque => "OPAQUE",
            AlphaMode::Mask => "MASK",
            AlphaMode::Blend => "BLEND",
        },
        "doubleSided": m.double_sided,
    });
    if m.alpha_mode == AlphaMode::Mask {
        out["alphaCutoff"] = json!(m.alpha_cutoff);
    }
    if let Some(t) = m.normal_texture {
        out["normalTexture"] = json!({ "index": texture(t) });
    }
    let peak = m.emissive.max_element();
    if let Some(t) = m.emissive_texture.filter(|_| peak > 0.0) {
        out["emissiveTexture"] = json!({ "index": texture(t) });
    }
    if peak > 0.0 {
        // emissiveFactor is at most 1: brighter emission goes into the strength extension.
        let strength = peak.max(1.0);
        out["emissiveFactor"] = json!((m.emissive / strength).to_array());
        if strength > 1.0 {
            out["extensions"] = json!({ EMISSIVE_STRENGTH: { "emissiveStrength": strength } });
        }
    }
    out
}

fn encode_png(t: &crate::texture::Texture) -> Result<Vec<u8>, String> {
    let image = image::RgbaImage::from_raw(t.width, t.height, t.rgba.to_vec())
        .ok_or_else(|| format!("'{}': data does not match its size", t.name))?;
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| format!("'{}': PNG encoding failed: {e}", t.name))?;
    Ok(png)
}

/// A GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded) if any.
fn glb_bytes(path: &Path, mut json: Vec<u8>, mut bin: Vec<u8>) -> Result<Vec<u8>, SceneError> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12
        + 8
        + json.len() as u64
        + if bin.is_empty() {
            0
        } else {
            8 + bin.len() as u64
        };
    if total > u32::MAX as u64 {
        return Err(SceneError::TooLarge {
            path: path.to_path_buf(),
            reason: format!(
                "a GLB file holds at most 4 GiB; this scene needs {total} bytes (write .gltf)"
            ),
        });
    }
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    Ok(out)
}
