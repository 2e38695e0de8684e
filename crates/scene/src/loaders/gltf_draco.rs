//! `KHR_draco_mesh_compression` primitives, decoded with the pure-Rust `draco-core` decoder.
//!
//! Draco replaces a primitive's accessors: the extension names a buffer view holding a Draco
//! mesh and, for each attribute, the Draco attribute's unique id; the triangles are the Draco
//! mesh's faces. Only `POSITION`, `NORMAL` and `TEXCOORD_0` are read (as for uncompressed
//! primitives). The decoder's own limits hold a hostile stream's allocations, and the result
//! is held to [`MAX_TRIANGLES`].

use std::path::Path;

use glam::{Vec2, Vec3};
use serde_json::Value;

use super::common::{parse_error, too_large, RawTriangles, MAX_TRIANGLES};
use super::gltf_open::Opened;
use crate::error::SceneError;

/// The bytes of buffer view `view` of an opened document.
fn view_bytes(opened: &Opened, view: usize) -> Result<&[u8], String> {
    let root = opened.document.as_json();
    let v = root
        .buffer_views
        .get(view)
        .ok_or_else(|| format!("buffer view {view} does not exist"))?;
    let data = opened
        .buffers
        .get(v.buffer.value())
        .ok_or_else(|| format!("buffer view {view}: its buffer does not exist"))?;
    let start = v.byte_offset.map_or(0, |o| o.0 as usize);
    start
        .checked_add(v.byte_length.0 as usize)
        .and_then(|end| data.0.get(start..end))
        .ok_or_else(|| format!("buffer view {view} is outside its buffer"))
}

/// Decodes a `KHR_draco_mesh_compression` primitive (`ext` is the extension's JSON).
pub(super) fn decode_draco(
    path: &Path,
    label: &str,
    opened: &Opened,
    ext: &Value,
) -> Result<RawTriangles, SceneError> {
    let bad = |reason: String| {
        parse_error(
            path,
            format!("glTF primitive {label}: KHR_draco_mesh_compression {reason}"),
        )
    };
    let view = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .ok_or_else(|| bad("names no buffer view".into()))?;
    let bytes = view_bytes(opened, view as usize).map_err(bad)?;
    let mut mesh = draco_core::Mesh::new();
    draco_core::MeshDecoder::new()
        .decode(&mut draco_core::DecoderBuffer::new(bytes), &mut mesh)
        .map_err(|e| bad(format!("data could not be decoded ({e})")))?;
    if mesh.num_faces() > MAX_TRIANGLES {
        return Err(too_large(
            path,
            format!(
                "glTF primitive {label}: {} Draco triangles; the limit is {MAX_TRIANGLES}",
                mesh.num_faces()
            ),
        ));
    }
    let points = mesh.num_points();
    // The Draco attribute the extension maps glTF attribute `name` to, read as `components`
    // floats per point.
    let attribute = |name: &str, components: usize| -> Result<Option<Vec<f32>>, SceneError> {
        let Some(id) = ext.pointer(&format!("/attributes/{name}")) else {
            return Ok(None);
        };
        let id = id.as_u64().ok_or_else(|| {
            bad(format!(
                "attribute {name} is {id}, not a Draco attribute id"
            ))
        })?;
        let found = (0..mesh.num_attributes())
            .map(|i| mesh.attribute(i))
            .find(|a| u64::from(a.unique_id()) == id)
            .ok_or_else(|| {
                bad(format!(
                    "attribute {name}'s id {id} is not in the Draco data"
                ))
            })?;
        if (found.num_components() as usize) < components {
            return Err(bad(format!(
                "attribute {name} has {} components; {components} are needed",
                found.num_components()
            )));
        }
        Ok(Some(found.read_f32s(points, components)))
    };
    let positions: Vec<Vec3> = attribute("POSITION", 3)?
        .ok_or_else(|| bad("has no POSITION attribute".into()))?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    let normals: Option<Vec<Vec3>> =
        attribute("NORMAL", 3)?.map(|n| n.chunks_exact(3).map(Vec3::from_slice).collect());
    let uvs: Vec<Vec2> = attribute("TEXCOORD_0", 2)?
        .map(|t| t.chunks_exact(2).map(Vec2::from_slice).collect())
        .unwrap_or_default();
    let indices: Vec<u32> = mesh.faces().iter().flat_map(|f| f.map(|p| p.0)).collect();
    if let Some(i) = indices.iter().find(|&&i| i as usize >= points) {
        return Err(bad(format!(
            "a face uses point {i}, but the data has {points}"
        )));
    }
    Ok(RawTriangles {
        positions,
        normals,
        uvs,
        indices,
    })
}
