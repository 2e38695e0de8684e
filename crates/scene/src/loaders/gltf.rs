//! glTF 2.0 (`.gltf` with embedded or external buffers, and binary `.glb`) via the `gltf` crate.
//!
//! Why: glTF is the modern interchange format and what most free test scenes (Sponza and the
//! Khronos samples) are published in. The renderer places meshes with instance transforms and
//! knows nothing of node hierarchies, so each triangle primitive reached from the default scene
//! is emitted as its own [`Mesh`] with the node's world transform baked into its positions and
//! normals (mirroring transforms flip the triangle winding back to counter-clockwise, as the glTF
//! specification asks). Triangle strips and fans are turned into lists exactly as the
//! specification numbers their triangles; points and lines are skipped with a warning.
//!
//! [`load`] (behind [`load_mesh`](super::dispatch::load_mesh)) reads geometry only and never
//! decodes an image. [`load_scene`] also reads materials, the images they use (each decoded
//! once, from a buffer view, a `data:` URI or a file in the `.gltf`'s folder),
//! `KHR_texture_transform` (baked into texture coordinates), `KHR_lights_punctual` lights and
//! the first perspective camera, with the mappings documented in [`super`];
//! `EXT_mesh_gpu_instancing` nodes become one instance per instance. Node animations are read
//! (`gltf_animation`: the instances under an animated node move, see
//! [`animation`](crate::animation)), and skins bend their meshes; morph targets are not
//! applied yet (one note says so), and every other extension the file uses gets one note.
//!
//! The `gltf` crate's accessors and wrappers assume a well-formed document in a few places
//! (found by fuzzing or by reading them), so: accessor types, strides and counts are checked
//! before reading; images, cameras and lights are read from the JSON structs rather than
//! through wrappers that unwrap fields validation does not require; external buffer files are
//! held to [`MAX_FILE_BYTES`]. The raw JSON is also parsed on its own (serde_json) to recognise
//! glTF 1.0 before the 2.0 schema produces a confusing message, and to name the extensions a
//! material uses, which the typed document drops.
//!
//! This file is the loader's entry: it opens the file (`gltf_open`, which also decodes meshopt
//! views, `gltf_compressed`), reads the geometry (`gltf_geometry`, with Draco primitives and
//! `gltf_instancing`), then for a whole scene the materials and images (`gltf_materials`),
//! the notes on extensions it ignores (`gltf_extensions`) and the lights and camera
//! (`gltf_lights_camera`), and puts the parts together.
//!
//! [`MAX_FILE_BYTES`]: super::common::MAX_FILE_BYTES

use std::path::Path;

use super::common::{bake, bounds_of_placed, check_triangles, Parts};
use super::gltf_animation::read_animations;
use super::gltf_extensions::unsupported_notes;
use super::gltf_geometry::read_geometry;
use super::gltf_lights_camera::{read_camera, read_lights};
use super::gltf_materials::read_materials;
use super::gltf_open::open;
use super::options::LoadOptions;
use crate::error::SceneError;
use crate::model::{Material, Mesh};

/// Loads every triangle primitive of the default scene, transforms baked (an instanced mesh
/// once per instance).
pub(super) fn load(path: &Path, options: &LoadOptions) -> Result<Vec<Mesh>, SceneError> {
    let opened = open(path, options)?;
    let geometry = read_geometry(path, &opened)?;
    let mut out = Vec::with_capacity(geometry.meshes.len());
    let mut total = 0usize;
    for (mesh, placed) in geometry.meshes.into_iter().zip(geometry.transforms) {
        if let [t] = placed[..] {
            if t == glam::Mat4::IDENTITY {
                out.push(mesh);
                continue;
            }
        }
        total = total.saturating_add(mesh.triangle_count().saturating_mul(placed.len()));
        check_triangles(path, total)?;
        out.extend(placed.iter().map(|&t| bake(&mesh, t)));
    }
    Ok(out)
}

/// Loads meshes, materials, textures, lights and the camera (see [`super`] for the mappings).
pub(super) fn load_scene(path: &Path, options: &LoadOptions) -> Result<Parts, SceneError> {
    let opened = open(path, options)?;
    let mut geometry = read_geometry(path, &opened)?;
    let mut notes = unsupported_notes(&opened.json, &opened.required);
    notes.append(&mut geometry.notes);
    if geometry.skipped > 0 {
        notes.push(format!(
            "{} point or line primitive(s) skipped (only triangles are drawn)",
            geometry.skipped
        ));
    }
    let materials = read_materials(&opened, &mut notes);
    let (mut materials, textures, uv_transforms) = (
        materials.materials,
        materials.textures,
        materials.uv_transforms,
    );
    let default_material = materials.len();
    let mut needs_default = false;
    let mesh_material: Vec<usize> = geometry
        .materials
        .iter()
        .map(|m| match m {
            Some(i) if *i < default_material => *i,
            _ => {
                needs_default = true;
                default_material
            }
        })
        .collect();
    if needs_default {
        materials.push(Material::default());
    }
    // KHR_texture_transform, baked into the texture coordinates of each mesh of the material.
    for (mesh, &material) in geometry.meshes.iter_mut().zip(&mesh_material) {
        if let Some(Some(t)) = uv_transforms.get(material) {
            for uv in &mut mesh.uvs {
                *uv = t.transform_point2(*uv);
            }
        }
    }
    // Skinned meshes stand where their joints put them at rest, morphed ones at their default
    // weights.
    let skinned = std::mem::take(&mut geometry.skinned);
    let morphed = std::mem::take(&mut geometry.morphed);
    let animations = read_animations(
        path,
        &opened,
        &geometry.meshes,
        skinned,
        morphed,
        &mut notes,
    )?;
    for (mesh, positions, normals) in animations.deformed_at_rest() {
        let m = &mut geometry.meshes[mesh];
        m.positions = positions;
        m.normals = normals;
    }
    let bounds = bounds_of_placed(&geometry.meshes, &geometry.transforms);
    let lights = read_lights(path, &opened, &geometry.nodes, bounds, &mut notes)?;
    let camera = read_camera(&opened, &geometry.nodes, bounds, &mut notes);
    Ok(Parts {
        meshes: geometry.meshes,
        mesh_material,
        transforms: geometry.transforms,
        materials,
        textures,
        lights,
        camera,
        notes,
        mesh_nodes: geometry.mesh_nodes,
        animations,
    })
}
