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
//! [`load`] (behind [`load_mesh`](super::load_mesh)) reads geometry only and never decodes an
//! image. [`load_scene`] also reads materials, the images they use (each decoded once, from a
//! buffer view, a `data:` URI or a file beside the `.gltf`), `KHR_lights_punctual` lights and
//! the first perspective camera, with the mappings documented in [`super`]. Skins, morph
//! targets and animations are ignored.
//!
//! The `gltf` crate's accessors and wrappers assume a well-formed document in a few places
//! (found by fuzzing or by reading them), so: accessor types, strides and counts are checked
//! here before reading; images, cameras and lights are read from the JSON structs rather than
//! through wrappers that unwrap fields validation does not require; external buffer files are
//! held to [`MAX_FILE_BYTES`]. The raw JSON is also parsed on its own (serde_json) to recognise
//! glTF 1.0 before the 2.0 schema produces a confusing message, and to name the extensions a
//! material uses, which the typed document drops.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::json::validation::Checked;
use ::gltf::mesh::Mode;
use ::gltf::texture::WrappingMode;
use ::gltf::{Accessor, Document, Semantic};
use glam::{Mat3, Mat4, Vec2, Vec3};
use serde_json::Value;

use super::common::{
    check_triangles, io_error, mesh_name, parse_error, read_limited, set_normals, too_large, Parts,
    MAX_FILE_BYTES, PHONG_PER_LUX,
};
use crate::builtin::{
    DIRECTIONAL_CASCADES, DIRECTIONAL_SHADOW_RESOLUTION, DIRECTIONAL_SPLIT_LAMBDA,
    POINT_SHADOW_RESOLUTION, SPOT_SHADOW_RESOLUTION,
};
use crate::error::SceneError;
use crate::model::{Attenuation, Camera, Light, LightKind, Material, Mesh};
use crate::texture::{AlphaMode, Texture, TextureRef, Wrap};

/// Extensions a file may *require* that this loader still reads, ignoring the extension with a
/// note (the result looks different from what the author intended, but it is the scene): texture
/// transforms and the PBR material extensions, which a Phong renderer cannot show anyway.
fn ignorable_requirement(name: &str) -> bool {
    name == "KHR_texture_transform" || name.starts_with("KHR_materials_")
}

/// An opened, validated glTF file with its buffers.
struct Opened {
    document: Document,
    buffers: Vec<::gltf::buffer::Data>,
    /// The whole JSON document, untyped.
    json: Value,
    /// The directory external files are relative to.
    base: PathBuf,
    /// Remarks made while opening (ignored required extensions).
    notes: Vec<String>,
}

/// Reads, checks and validates the document and loads its buffers.
fn open(path: &Path) -> Result<Opened, SceneError> {
    let bytes = read_limited(path)?;
    let (json_bytes, blob): (Vec<u8>, Option<Vec<u8>>) = if bytes.starts_with(b"glTF") {
        if bytes.get(4..8) == Some(&1u32.to_le_bytes()[..]) {
            return Err(gltf1_error(path));
        }
        let glb =
            ::gltf::Glb::from_slice(&bytes).map_err(|e| parse_error(path, format!("glTF: {e}")))?;
        (glb.json.into_owned(), glb.bin.map(|b| b.into_owned()))
    } else {
        (bytes, None)
    };
    let json: Value =
        serde_json::from_slice(&json_bytes).map_err(|e| parse_error(path, format!("glTF: {e}")))?;
    if is_gltf1(&json) {
        return Err(gltf1_error(path));
    }
    let mut root: ::gltf::json::Root =
        serde_json::from_slice(&json_bytes).map_err(|e| parse_error(path, format!("glTF: {e}")))?;
    drop(json_bytes);

    // gltf-json 1.4.1's validation looks up a primitive's POSITION accessor before checking
    // that it exists (a panic on a dangling index, found by fuzzing): check the accessor
    // references of every primitive first, then validate.
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
    // Required extensions: the ignorable ones are dropped from the list (with a note) so that
    // validation accepts the file; any other is refused here, by name.
    let mut notes = Vec::new();
    let (ignored, unsupported): (Vec<String>, Vec<String>) =
        std::mem::take(&mut root.extensions_required)
            .into_iter()
            .filter(|e| !::gltf::json::extensions::ENABLED_EXTENSIONS.contains(&e.as_str()))
            .partition(|e| ignorable_requirement(e));
    if !unsupported.is_empty() {
        return Err(parse_error(
            path,
            format!(
                "glTF: the file requires the extension(s) {}, which this loader does not support; \
                 re-export or convert the file without them",
                unsupported.join(", ")
            ),
        ));
    }
    if !ignored.is_empty() {
        notes.push(format!(
            "the file requires {}, which this loader ignores: materials may look different",
            ignored.join(", ")
        ));
    }
    let document =
        Document::from_json(root).map_err(|e| parse_error(path, format!("glTF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    check_buffer_sources(path, &document, &base)?;
    let buffers = ::gltf::import_buffers(&document, Some(&base), blob)
        .map_err(|e| parse_error(path, format!("glTF buffers: {e}")))?;
    Ok(Opened {
        document,
        buffers,
        json,
        base,
        notes,
    })
}

/// glTF 1.0 shows itself by its version, or by `meshes` / `nodes` being dictionaries (2.0 has
/// arrays).
fn is_gltf1(json: &Value) -> bool {
    let version = json.get("asset").and_then(|a| a.get("version"));
    let old_version = match version {
        Some(Value::String(v)) => v.trim().starts_with('1'),
        Some(Value::Number(n)) => n.as_f64().is_some_and(|v| (1.0..2.0).contains(&v)),
        _ => false,
    };
    old_version
        || json.get("meshes").is_some_and(Value::is_object)
        || json.get("nodes").is_some_and(Value::is_object)
}

fn gltf1_error(path: &Path) -> SceneError {
    parse_error(
        path,
        "glTF 1.0 is not supported (this loader reads glTF 2.0): convert the file with a \
         glTF 1.0 → 2.0 converter first (e.g. Cesium's gltf-pipeline, which upgrades 1.0 files)",
    )
}

/// The triangle meshes of a document, in depth-first node order.
struct Geometry<'a> {
    meshes: Vec<Mesh>,
    /// The glTF material of each mesh (`None`: the primitive names none).
    materials: Vec<Option<usize>>,
    /// Every node reached from the default scene with its world transform, depth-first.
    nodes: Vec<(::gltf::Node<'a>, Mat4)>,
    /// Point and line primitives skipped.
    skipped: usize,
}

/// Loads every triangle primitive of the default scene, transforms baked.
pub(super) fn load(path: &Path) -> Result<Vec<Mesh>, SceneError> {
    let opened = open(path)?;
    Ok(read_geometry(path, &opened)?.meshes)
}

/// Loads meshes, materials, textures, lights and the camera (see [`super`] for the mappings).
pub(super) fn load_scene(path: &Path) -> Result<Parts, SceneError> {
    let opened = open(path)?;
    let geometry = read_geometry(path, &opened)?;
    let mut notes = opened.notes.clone();
    if geometry.skipped > 0 {
        notes.push(format!(
            "{} point or line primitive(s) skipped (only triangles are drawn)",
            geometry.skipped
        ));
    }
    let (mut materials, textures) = read_materials(&opened, &mut notes);
    let default_material = materials.len();
    let mut needs_default = false;
    let mesh_material = geometry
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
    let bounds = super::common::bounds_of(&geometry.meshes);
    let lights = read_lights(path, &opened, &geometry.nodes, bounds, &mut notes)?;
    let camera = read_camera(&opened, &geometry.nodes, bounds, &mut notes);
    Ok(Parts {
        meshes: geometry.meshes,
        mesh_material,
        materials,
        textures,
        lights,
        camera,
        notes,
    })
}

fn read_geometry<'a>(path: &Path, opened: &'a Opened) -> Result<Geometry<'a>, SceneError> {
    let document = &opened.document;
    let buffers = &opened.buffers;
    let get = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(|d| d.0.as_slice());
    let mut out = Geometry {
        meshes: Vec::new(),
        materials: Vec::new(),
        nodes: Vec::new(),
        skipped: 0,
    };
    let mut total_triangles = 0usize;
    let mut emit = |out: &mut Geometry<'a>, mesh: ::gltf::Mesh<'a>, world: Mat4| {
        for prim in mesh.primitives() {
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                log::warn!(
                    "{}: skipping a {:?} primitive of mesh {} (only triangles are loaded)",
                    path.display(),
                    mode,
                    mesh.index()
                );
                out.skipped += 1;
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
            out.meshes.push(m);
            out.materials.push(prim.material().index());
        }
        Ok::<(), SceneError>(())
    };

    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => {
            // Depth-first walk with an explicit stack; a node reached twice means the "tree" has
            // a cycle or shared child, which the specification forbids.
            let mut seen = vec![false; document.nodes().len()];
            let mut stack: Vec<(::gltf::Node<'a>, Mat4)> =
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
                    emit(&mut out, mesh, world)?;
                }
                let children: Vec<_> = node.children().collect();
                stack.extend(children.into_iter().rev().map(|c| (c, world)));
                out.nodes.push((node, world));
            }
        }
        None => {
            for mesh in document.meshes() {
                emit(&mut out, mesh, Mat4::IDENTITY)?;
            }
        }
    }
    Ok(out)
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

/// Checks an accessor's buffer views are safe to hand to the crate's readers.
fn check_layout(a: &Accessor<'_>, bad: &dyn Fn(String) -> SceneError) -> Result<(), SceneError> {
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

/// Checks an accessor has one of `types` (not normalized) and `dims`, and a safe layout.
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
    check_layout(a, &bad)
}

/// Texture coordinates: `Vec2` of floats, or of normalized unsigned bytes or shorts.
fn check_texcoord_accessor(path: &Path, label: &str, a: &Accessor<'_>) -> Result<(), SceneError> {
    let bad =
        |reason: String| parse_error(path, format!("glTF primitive {label}: TEXCOORD_0 {reason}"));
    let ok = a.dimensions() == Dimensions::Vec2
        && match a.data_type() {
            DataType::F32 => !a.normalized(),
            DataType::U8 | DataType::U16 => a.normalized(),
            _ => false,
        };
    if !ok {
        return Err(bad(format!(
            "accessor has type {:?} {:?}{}; expected Vec2 of F32, or of normalized U8 or U16",
            a.dimensions(),
            a.data_type(),
            if a.normalized() { " (normalized)" } else { "" }
        )));
    }
    check_layout(a, &bad)
}

/// Triangle `i` of a strip is `(v_i, v_{i+1+i%2}, v_{i+2-i%2})` (glTF 2.0, §3.7.2.1), which
/// keeps every triangle's winding that of the first.
pub(crate) fn strip_to_list(v: &[u32]) -> Vec<u32> {
    let n = v.len().saturating_sub(2);
    let mut out = Vec::with_capacity(3 * n);
    for i in 0..n {
        out.extend_from_slice(&[v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]]);
    }
    out
}

/// Triangle `i` of a fan is `(v_{i+1}, v_{i+2}, v_0)` (glTF 2.0, §3.7.2.1).
pub(crate) fn fan_to_list(v: &[u32]) -> Vec<u32> {
    let n = v.len().saturating_sub(2);
    let mut out = Vec::with_capacity(3 * n);
    for i in 0..n {
        out.extend_from_slice(&[v[i + 1], v[i + 2], v[0]]);
    }
    out
}

fn read_primitive<'p, 's, F>(
    path: &Path,
    label: &str,
    prim: &'p ::gltf::Primitive<'p>,
    get: &F,
    world: Mat4,
) -> Result<Mesh, SceneError>
where
    F: Clone + Fn(::gltf::Buffer<'p>) -> Option<&'s [u8]>,
{
    let name = mesh_name(path, Some(label));
    let mode = prim.mode();
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
    let uv_acc = prim
        .get(&Semantic::TexCoords(0))
        .filter(|a| a.count() == vertex_count);
    if let Some(a) = &uv_acc {
        check_texcoord_accessor(path, label, a)?;
    }
    let index_acc = prim.indices();
    let listed = match &index_acc {
        Some(a) => {
            check_accessor(
                path,
                label,
                "indices",
                a,
                &[DataType::U8, DataType::U16, DataType::U32],
                Dimensions::Scalar,
            )?;
            a.count()
        }
        None => vertex_count,
    };
    check_triangles(
        path,
        match mode {
            Mode::Triangles => listed / 3,
            _ => listed.saturating_sub(2),
        },
    )?;

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
    let uvs: Vec<Vec2> = match &uv_acc {
        Some(_) => {
            let uvs: Vec<Vec2> = reader
                .read_tex_coords(0)
                .ok_or_else(|| missing("TEXCOORD_0"))?
                .into_f32()
                .map(Vec2::from_array)
                .collect();
            if uvs.len() != vertex_count {
                return Err(missing("TEXCOORD_0"));
            }
            uvs
        }
        None => Vec::new(),
    };
    let listed: Vec<u32> = match &index_acc {
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
    let mut indices = match mode {
        Mode::TriangleStrip => strip_to_list(&listed),
        Mode::TriangleFan => fan_to_list(&listed),
        _ => {
            if !listed.len().is_multiple_of(3) {
                return Err(parse_error(
                    path,
                    format!(
                        "glTF primitive {label}: {} indices is not a multiple of 3",
                        listed.len()
                    ),
                ));
            }
            listed
        }
    };

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
        uvs,
        indices,
    };
    super::common::check_indices(&mesh)?;
    set_normals(&mut mesh, normals);
    Ok(mesh)
}

// ---------------------------------------------------------------------------------------------
// Materials and images
// ---------------------------------------------------------------------------------------------

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

/// Every material of the document, in order, and the textures they use.
fn read_materials(opened: &Opened, notes: &mut Vec<String>) -> (Vec<Material>, Vec<Texture>) {
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
        let extensions = material_extensions(&opened.json, i);
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

// ---------------------------------------------------------------------------------------------
// Lights and camera
// ---------------------------------------------------------------------------------------------

/// The direction a node's local −Z points in world space (lights and cameras look down −Z).
fn forward_of(world: &Mat4) -> Option<Vec3> {
    world.transform_vector3(Vec3::NEG_Z).try_normalize()
}

fn read_lights(
    path: &Path,
    opened: &Opened,
    nodes: &[(::gltf::Node<'_>, Mat4)],
    bounds: Option<(Vec3, Vec3)>,
    notes: &mut Vec<String>,
) -> Result<Vec<Light>, SceneError> {
    use ::gltf::json::extensions::scene::khr_lights_punctual::Type;
    let root = opened.document.as_json();
    let Some(defs) = root
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map(|l| &l.lights)
    else {
        return Ok(Vec::new());
    };
    let diagonal = bounds.map_or(0.0, |(lo, hi)| (hi - lo).length());
    let mut lights = Vec::new();
    for (node, world) in nodes {
        let Some(index) = root
            .nodes
            .get(node.index())
            .and_then(|n| n.extensions.as_ref())
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map(|l| l.light.value())
        else {
            continue;
        };
        let Some(def) = defs.get(index) else {
            continue;
        };
        let name = def.name.clone().unwrap_or_else(|| format!("light {index}"));
        let colour = Vec3::from(def.color).max(Vec3::ZERO) * def.intensity.max(0.0) * PHONG_PER_LUX;
        if !colour.is_finite() {
            return Err(parse_error(
                path,
                format!("glTF light '{name}': colour × intensity is not a finite number"),
            ));
        }
        let Checked::Valid(ty) = def.type_ else {
            continue; // validation refuses unknown types; nothing to do
        };
        let position = world.w_axis.truncate();
        let range = match def.range {
            _ if ty == Type::Directional => 0.0, // unused
            Some(r) if r.is_finite() && r > 0.0 => r,
            Some(r) => {
                notes.push(format!(
                    "light '{name}': range {r} is not a positive number: computed from its \
                     intensity instead"
                ));
                super::common::light_range(colour, diagonal)
            }
            None => super::common::light_range(colour, diagonal),
        };
        let kind = match ty {
            Type::Point => LightKind::Point { position, range },
            Type::Spot | Type::Directional => {
                let Some(direction) = forward_of(world) else {
                    notes.push(format!(
                        "light '{name}' (node {}): its node's transform has no direction: skipped",
                        node.index()
                    ));
                    continue;
                };
                if ty == Type::Directional {
                    LightKind::Directional {
                        direction,
                        cascades: DIRECTIONAL_CASCADES,
                        split_lambda: DIRECTIONAL_SPLIT_LAMBDA,
                        cascade_resolution_scale: 1.0,
                    }
                } else {
                    let outer = def
                        .spot
                        .as_ref()
                        .map_or(std::f32::consts::FRAC_PI_4, |s| s.outer_cone_angle);
                    LightKind::Spot {
                        position,
                        direction,
                        cutoff_deg: super::common::spot_cutoff_deg(outer),
                        range,
                    }
                }
            }
        };
        if !position.is_finite() {
            return Err(parse_error(
                path,
                format!("glTF light '{name}': its node's position is not finite"),
            ));
        }
        let (attenuation, shadow_resolution) = match kind {
            LightKind::Directional { .. } => (Attenuation::NONE, DIRECTIONAL_SHADOW_RESOLUTION),
            LightKind::Spot { .. } => (super::common::INVERSE_SQUARE, SPOT_SHADOW_RESOLUTION),
            LightKind::Point { .. } => (super::common::INVERSE_SQUARE, POINT_SHADOW_RESOLUTION),
        };
        lights.push(Light {
            kind,
            ambient: Vec3::ZERO,
            diffuse: colour,
            specular: colour,
            attenuation,
            casts_shadows: true,
            shadow_resolution,
        });
    }
    Ok(lights)
}

fn read_camera(
    opened: &Opened,
    nodes: &[(::gltf::Node<'_>, Mat4)],
    bounds: Option<(Vec3, Vec3)>,
    notes: &mut Vec<String>,
) -> Option<Camera> {
    use ::gltf::json::camera::Type;
    let root = opened.document.as_json();
    let mut skipped = Vec::new();
    let mut found = None;
    for (node, world) in nodes {
        let Some(index) = root
            .nodes
            .get(node.index())
            .and_then(|n| n.camera.as_ref())
            .map(|c| c.value())
        else {
            continue;
        };
        let Some(def) = root.cameras.get(index) else {
            continue;
        };
        let name = def
            .name
            .clone()
            .unwrap_or_else(|| format!("camera {index}"));
        let perspective = match (&def.type_, &def.perspective) {
            (Checked::Valid(Type::Perspective), Some(p)) => p,
            _ => {
                skipped.push(format!(
                    "camera '{name}' is orthographic, which this renderer does not support"
                ));
                continue;
            }
        };
        match camera_from_node(perspective, world, bounds) {
            Ok(c) => {
                found = Some((c, name));
                break;
            }
            Err(reason) => skipped.push(format!("camera '{name}': {reason}")),
        }
    }
    let outcome = match &found {
        Some((_, name)) => format!("skipped (camera '{name}' is used)"),
        None => "the default camera is used".to_string(),
    };
    notes.extend(skipped.into_iter().map(|s| format!("{s}: {outcome}")));
    found.map(|(c, _)| c)
}

fn camera_from_node(
    p: &::gltf::json::camera::Perspective,
    world: &Mat4,
    bounds: Option<(Vec3, Vec3)>,
) -> Result<Camera, String> {
    let position = world.w_axis.truncate();
    let forward = forward_of(world);
    let up = world.transform_vector3(Vec3::Y).try_normalize();
    let (Some(forward), Some(up)) = (forward, up) else {
        return Err("its node's transform is degenerate".into());
    };
    if !position.is_finite() || forward.cross(up).length_squared() < 1e-6 {
        return Err("its node's transform is degenerate".into());
    }
    let (centre, diagonal) = super::common::centre_and_diagonal(bounds);
    let distance = (centre - position)
        .length()
        .max(1.0)
        .max(position.abs().max_element() * 1e-4);
    let near = if p.znear.is_finite() && p.znear > 0.0 {
        p.znear
    } else {
        return Err(format!("znear {} is not a positive number", p.znear));
    };
    let far = match p.zfar {
        Some(f) if f.is_finite() && f > near => f,
        _ => near + 4.0 * diagonal.max(near),
    };
    Ok(Camera {
        position,
        target: position + forward * distance,
        up,
        fov_y_deg: super::common::clamp_fov(p.yfov.to_degrees()),
        near,
        far,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("100%").as_deref(), Some("100%"));
        assert_eq!(percent_decode("%zz").as_deref(), Some("%zz"));
        assert_eq!(percent_decode("%FF"), None);
        assert_eq!(percent_decode("%C3%A9").as_deref(), Some("é"));
    }

    #[test]
    fn strips_and_fans_follow_the_specification() {
        assert_eq!(
            strip_to_list(&[0, 1, 2, 3, 4]),
            vec![0, 1, 2, 1, 3, 2, 2, 3, 4]
        );
        assert_eq!(fan_to_list(&[0, 1, 2, 3]), vec![1, 2, 0, 2, 3, 0]);
        assert!(strip_to_list(&[0, 1]).is_empty());
        assert!(fan_to_list(&[]).is_empty());
    }

    #[test]
    fn roughness_to_shininess() {
        assert_eq!(shininess_from_roughness(0.0), 512.0);
        assert_eq!(shininess_from_roughness(1.0), 1.0);
        let r: f32 = 0.5;
        let a = r * r;
        assert!((shininess_from_roughness(r) - (2.0 / (a * a) - 2.0)).abs() < 1e-3);
    }
}
