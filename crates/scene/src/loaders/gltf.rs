//! glTF 2.0 (`.gltf` with embedded or external buffers, and binary `.glb`) via the `gltf` crate.
//!
//! Why: glTF is the modern interchange format and what most free test scenes (Sponza and the
//! Khronos samples) are published in. The renderer places meshes with instance transforms and
//! knows nothing of node hierarchies, so each triangle primitive reached from the default scene
//! is emitted as its own [`Mesh`] with the node's world transform baked into its positions and
//! normals (mirroring transforms flip the triangle winding back to counter-clockwise, as the glTF
//! specification asks). Only geometry is read: the document and its buffers are loaded with
//! `Gltf::from_slice` + `gltf::import_buffers` rather than `gltf::import`, so images are never
//! decoded. Skins, morph targets, cameras and lights in the file are ignored.
//!
//! The crate's accessor readers assume a well-formed document in a few places, so accessor
//! types, strides and counts are checked here before reading and external buffer files are held
//! to [`MAX_FILE_BYTES`].

use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::{Accessor, Document, Gltf, Semantic};
use glam::{Mat3, Mat4, Vec3};

use super::{
    check_triangles, io_error, mesh_name, parse_error, read_limited, set_normals, too_large,
    MAX_FILE_BYTES,
};
use crate::{Mesh, SceneError};

/// Loads every triangle primitive of the default scene, transforms baked.
pub(super) fn load(path: &Path) -> Result<Vec<Mesh>, SceneError> {
    let bytes = read_limited(path)?;
    let gltf = Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| parse_error(path, format!("glTF: {e}")))?;
    drop(bytes);
    let Gltf { document, blob } = gltf;
    // gltf-json 1.4.1's validation looks up a primitive's POSITION accessor before checking
    // that it exists (a panic on a dangling index, found by fuzzing): check the accessor
    // references of every primitive first, then validate.
    let root = document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let used = primitive
                .attributes
                .values()
                .chain(primitive.indices.as_ref());
            if let Some(bad) = used.map(|i| i.value()).find(|&i| i >= root.accessors.len()) {
                return Err(parse_error(
                    path,
                    format!(
                        "glTF: mesh {m}, primitive {p} uses accessor {bad}, but the file has {}",
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    let document = ::gltf::Document::from_json(document.into_json())
        .map_err(|e| parse_error(path, format!("glTF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("."));
    check_buffer_sources(path, &document, base)?;
    let buffers = ::gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| parse_error(path, format!("glTF buffers: {e}")))?;
    let get = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(|d| d.0.as_slice());

    let mut meshes = Vec::new();
    let mut total_triangles = 0usize;
    let mut emit = |mesh: ::gltf::Mesh<'_>, world: Mat4| -> Result<(), SceneError> {
        for prim in mesh.primitives() {
            if prim.mode() != Mode::Triangles {
                log::warn!(
                    "{}: skipping a {:?} primitive of mesh {} (only triangle lists are loaded)",
                    path.display(),
                    prim.mode(),
                    mesh.index()
                );
                continue;
            }
            let label = match mesh.name() {
                Some(n) => format!("{n}#{}", prim.index()),
                None => format!("mesh{}#{}", mesh.index(), prim.index()),
            };
            let m = read_primitive(path, &label, &prim, &get, world)?;
            if m.indices.is_empty() {
                continue;
            }
            total_triangles += m.triangle_count();
            check_triangles(path, total_triangles)?;
            meshes.push(m);
        }
        Ok(())
    };

    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => {
            // Depth-first walk with an explicit stack; a node reached twice means the "tree" has
            // a cycle or shared child, which the specification forbids.
            let mut seen = vec![false; document.nodes().len()];
            let mut stack: Vec<(::gltf::Node<'_>, Mat4)> =
                scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
            stack.reverse();
            while let Some((node, parent)) = stack.pop() {
                if std::mem::replace(&mut seen[node.index()], true) {
                    return Err(parse_error(
                        path,
                        format!(
                            "glTF: node {} is reached twice (the node graph is not a tree)",
                            node.index()
                        ),
                    ));
                }
                let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
                if let Some(mesh) = node.mesh() {
                    emit(mesh, world)?;
                }
                let children: Vec<_> = node.children().collect();
                stack.extend(children.into_iter().rev().map(|c| (c, world)));
            }
        }
        None => {
            for mesh in document.meshes() {
                emit(mesh, Mat4::IDENTITY)?;
            }
        }
    }
    Ok(meshes)
}

/// Refuses external buffer files over the size limit, and URIs the `gltf` crate would choke on.
fn check_buffer_sources(path: &Path, document: &Document, base: &Path) -> Result<(), SceneError> {
    for buffer in document.buffers() {
        let ::gltf::buffer::Source::Uri(uri) = buffer.source() else {
            continue;
        };
        let file: PathBuf = if let Some(rest) = uri.strip_prefix("file://") {
            PathBuf::from(rest)
        } else if let Some(rest) = uri.strip_prefix("file:") {
            PathBuf::from(rest)
        } else if uri.contains(':') {
            continue; // data: URIs (bounded by the file size) or schemes the crate rejects.
        } else {
            let decoded = percent_decode(uri).ok_or_else(|| {
                parse_error(
                    path,
                    format!("glTF: buffer URI '{uri}' is not valid percent-encoded UTF-8"),
                )
            })?;
            base.join(decoded)
        };
        let len = std::fs::metadata(&file)
            .map_err(|e| io_error(&file, e))?
            .len();
        if len > MAX_FILE_BYTES {
            return Err(too_large(
                &file,
                format!("glTF buffer is {len} bytes; the limit is {MAX_FILE_BYTES} bytes (2 GiB)"),
            ));
        }
    }
    Ok(())
}

/// Decodes `%XX` escapes; `None` if the result is not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8(out).ok()
}

/// Checks an accessor is safe to hand to the crate's readers.
fn check_accessor(
    path: &Path,
    label: &str,
    what: &str,
    a: &Accessor<'_>,
    types: &[DataType],
    dims: Dimensions,
) -> Result<(), SceneError> {
    let bad =
        |reason: String| parse_error(path, format!("glTF primitive {label}: {what} {reason}"));
    if !types.contains(&a.data_type()) || a.dimensions() != dims || a.normalized() {
        return Err(bad(format!(
            "accessor has type {:?} {:?}{}; expected {dims:?} of {types:?}",
            a.dimensions(),
            a.data_type(),
            if a.normalized() { " (normalized)" } else { "" }
        )));
    }
    let size = a.size();
    let views = a
        .view()
        .into_iter()
        .chain(a.sparse().map(|s| s.values().view()));
    for v in views {
        if let Some(stride) = v.stride() {
            if stride < size {
                return Err(bad(format!(
                    "buffer view stride {stride} is smaller than an element ({size} bytes)"
                )));
            }
        }
    }
    if let Some(s) = a.sparse() {
        if s.count() == 0 {
            return Err(bad("accessor has an empty sparse section".into()));
        }
    }
    Ok(())
}

fn read_primitive<'a, 's, F>(
    path: &Path,
    label: &str,
    prim: &'a ::gltf::Primitive<'a>,
    get: &F,
    world: Mat4,
) -> Result<Mesh, SceneError>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let name = mesh_name(path, Some(label));
    let pos_acc = prim.get(&Semantic::Positions).ok_or_else(|| {
        parse_error(
            path,
            format!("glTF primitive {label} has no POSITION attribute"),
        )
    })?;
    check_accessor(
        path,
        label,
        "POSITION",
        &pos_acc,
        &[DataType::F32],
        Dimensions::Vec3,
    )?;
    let vertex_count = pos_acc.count();
    if vertex_count == 0 {
        return Ok(Mesh {
            name,
            ..Mesh::default()
        });
    }
    if vertex_count > u32::MAX as usize {
        return Err(too_large(
            path,
            format!("glTF primitive {label} has {vertex_count} vertices"),
        ));
    }
    let normal_acc = prim
        .get(&Semantic::Normals)
        .filter(|a| a.count() == vertex_count);
    if let Some(a) = &normal_acc {
        check_accessor(path, label, "NORMAL", a, &[DataType::F32], Dimensions::Vec3)?;
    }
    let index_acc = prim.indices();
    if let Some(a) = &index_acc {
        check_accessor(
            path,
            label,
            "indices",
            a,
            &[DataType::U8, DataType::U16, DataType::U32],
            Dimensions::Scalar,
        )?;
        check_triangles(path, a.count() / 3)?;
    } else {
        check_triangles(path, vertex_count / 3)?;
    }

    let reader = prim.reader(get.clone());
    let missing = |what: &str| {
        parse_error(
            path,
            format!("glTF primitive {label}: {what} data is missing or outside its buffer"),
        )
    };
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| missing("POSITION"))?
        .map(Vec3::from_array)
        .collect();
    if positions.len() != vertex_count {
        return Err(missing("POSITION"));
    }
    let normals: Option<Vec<Vec3>> = match &normal_acc {
        Some(_) => Some(
            reader
                .read_normals()
                .ok_or_else(|| missing("NORMAL"))?
                .map(Vec3::from_array)
                .collect(),
        ),
        None => None,
    };
    let mut indices: Vec<u32> = match &index_acc {
        Some(a) => {
            let idx: Vec<u32> = reader
                .read_indices()
                .ok_or_else(|| missing("indices"))?
                .into_u32()
                .collect();
            if idx.len() != a.count() {
                return Err(missing("indices"));
            }
            idx
        }
        None => (0..vertex_count as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(parse_error(
            path,
            format!(
                "glTF primitive {label}: {} indices is not a multiple of 3",
                indices.len()
            ),
        ));
    }

    // Bake the node's world transform.
    let positions: Vec<Vec3> = positions
        .into_iter()
        .map(|p| world.transform_point3(p))
        .collect();
    let linear = Mat3::from_mat4(world);
    let det = linear.determinant();
    if det < 0.0 {
        // A mirroring transform turns counter-clockwise triangles clockwise; swap two corners.
        for t in indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    let normals = if det.is_finite() && det.abs() > 1e-30 {
        let normal_matrix = linear.inverse().transpose();
        normals.map(|ns| ns.into_iter().map(|n| normal_matrix * n).collect())
    } else {
        None // a singular transform flattens the mesh: derive normals from what is left
    };
    let mut mesh = Mesh {
        name,
        positions,
        normals: Vec::new(),
        indices,
    };
    super::check_indices(&mesh)?;
    set_normals(&mut mesh, normals);
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::percent_decode;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("100%").as_deref(), Some("100%"));
        assert_eq!(percent_decode("%zz").as_deref(), Some("%zz"));
        assert_eq!(percent_decode("%FF"), None);
        assert_eq!(percent_decode("%C3%A9").as_deref(), Some("é"));
    }
}
