//! Mesh loaders: Wavefront OBJ, glTF 2.0 (`.gltf` / `.glb`), Stanford PLY (ascii and binary,
//! optionally gzip-compressed as `.ply.gz`), plus small OBJ / PLY writers.
//!
//! Why this module exists: the renderer only understands the plain [`Mesh`] of this crate
//! (indexed triangles with one unit normal per vertex). Each loader turns its format into that
//! shape, so everything downstream deals with one representation:
//!
//! - polygons are triangulated, normals are re-indexed so they align with positions, and missing
//!   normals are computed with [`Mesh::compute_normals`];
//! - glTF node transforms are baked into the vertices (the renderer places meshes with
//!   [`Instance`](crate::Instance) transforms, not with a node hierarchy);
//! - every returned mesh has passed [`Mesh::validate`], so NaNs and out-of-range indices become a
//!   [`SceneError`] here instead of a GPU fault later.
//!
//! Mesh files are untrusted input. The loaders never panic on bad data (a parser panic is caught
//! and reported as [`SceneError::Parse`]) and enforce the limits below so a huge or hostile file
//! fails fast with [`SceneError::TooLarge`] instead of exhausting memory.

mod gltf;
mod obj;
mod ply;

use std::fs::File;
use std::path::Path;

use glam::Vec3;

use crate::{Mesh, SceneError};

pub use obj::write_obj;
pub use ply::write_ply_ascii;

/// Largest mesh file accepted, in bytes (2 GiB). Checked with the file's metadata before anything
/// is read, so an oversized file costs nothing. Also applies to external `.bin` buffers referenced
/// by a `.gltf` file.
pub const MAX_FILE_BYTES: u64 = 2 << 30;

/// Largest decompressed size of a `.ply.gz` file, in bytes (4 GiB). A small gzip file can expand
/// enormously ("zip bomb"), so decompression is read through `Read::take` and stops here.
pub const MAX_DECOMPRESSED_BYTES: u64 = 4 << 30;

/// Largest number of triangles in one loaded mesh (100 million, about 3.6 GB of vertex and index
/// data before deduplication). Checked from headers / accessor counts before reading where the
/// format allows it, and again on the result.
pub const MAX_TRIANGLES: usize = 100_000_000;

/// The file formats [`load_mesh`] understands, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Obj,
    Gltf,
    Ply { gzip: bool },
}

fn format_of(path: &Path) -> Option<Format> {
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".ply.gz") {
        return Some(Format::Ply { gzip: true });
    }
    let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
    match ext.as_str() {
        "obj" => Some(Format::Obj),
        "gltf" | "glb" => Some(Format::Gltf),
        "ply" => Some(Format::Ply { gzip: false }),
        _ => None,
    }
}

/// Loads every triangle mesh in a file, choosing the format by extension (case-insensitive):
///
/// - `.obj`: one [`Mesh`] per OBJ object / group (polygons fan-triangulated, normals from `vn`
///   where the file has them, computed otherwise; materials and texture coordinates ignored);
/// - `.gltf` / `.glb`: one [`Mesh`] per triangle primitive per node of the default scene
///   (the first scene if none is marked default; every mesh untransformed if the file has no
///   scene), with the node's world transform baked into positions and normals;
/// - `.ply` / `.ply.gz`: one [`Mesh`] (ascii, binary little- or big-endian).
///
/// Every returned mesh passes [`Mesh::validate`]. Errors: [`SceneError::UnsupportedFormat`] for
/// another extension, [`SceneError::Io`] if the file cannot be read, [`SceneError::TooLarge`] for
/// the limits ([`MAX_FILE_BYTES`], [`MAX_DECOMPRESSED_BYTES`], [`MAX_TRIANGLES`]),
/// [`SceneError::Parse`] (with the path and the parser's reason) for malformed content and
/// [`SceneError::InvalidMesh`] for non-finite coordinates or out-of-range indices.
pub fn load_mesh(path: &Path) -> Result<Vec<Mesh>, SceneError> {
    let format = format_of(path).ok_or_else(|| SceneError::UnsupportedFormat {
        path: path.to_path_buf(),
    })?;
    check_file_size(path)?;
    let meshes = catch_parser_panic(path, || match format {
        Format::Obj => obj::load(path),
        Format::Gltf => gltf::load(path),
        Format::Ply { gzip } => ply::load(path, gzip),
    })?;
    if meshes.is_empty() {
        return Err(parse_error(path, "the file contains no triangles"));
    }
    for m in &meshes {
        check_triangles(path, m.triangle_count())?;
        m.validate()?;
    }
    Ok(meshes)
}

/// Runs a parser, turning a panic inside a third-party parser into [`SceneError::Parse`]. The
/// loaders check what they can before calling the parsers; this is the last line of defence so
/// a hostile file can never take the process down.
fn catch_parser_panic<T>(
    path: &Path,
    f: impl FnOnce() -> Result<T, SceneError>,
) -> Result<T, SceneError> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(parse_error(
                path,
                format!("the parser failed on malformed data ({what})"),
            ))
        }
    }
}

pub(crate) fn io_error(path: &Path, source: std::io::Error) -> SceneError {
    SceneError::Io {
        path: path.to_path_buf(),
        source,
    }
}

pub(crate) fn parse_error(path: &Path, reason: impl Into<String>) -> SceneError {
    SceneError::Parse {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

pub(crate) fn too_large(path: &Path, reason: impl Into<String>) -> SceneError {
    SceneError::TooLarge {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Refuses files over [`MAX_FILE_BYTES`] from their metadata alone (also gives the `Io` error
/// for a missing file).
pub(crate) fn check_file_size(path: &Path) -> Result<u64, SceneError> {
    let len = std::fs::metadata(path)
        .map_err(|e| io_error(path, e))?
        .len();
    if len > MAX_FILE_BYTES {
        return Err(too_large(
            path,
            format!("file is {len} bytes; the limit is {MAX_FILE_BYTES} bytes (2 GiB)"),
        ));
    }
    Ok(len)
}

/// Opens a file for reading, never yielding more than [`MAX_FILE_BYTES`] + 1 bytes even if the
/// file grows after [`check_file_size`].
fn open_limited(path: &Path) -> Result<std::io::Take<File>, SceneError> {
    use std::io::Read;
    let file = File::open(path).map_err(|e| io_error(path, e))?;
    Ok(file.take(MAX_FILE_BYTES + 1))
}

/// Reads a whole file (size-checked) into memory.
fn read_limited(path: &Path) -> Result<Vec<u8>, SceneError> {
    use std::io::Read;
    let len = check_file_size(path)?;
    let mut bytes = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    open_limited(path)?
        .read_to_end(&mut bytes)
        .map_err(|e| io_error(path, e))?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large(
            path,
            "file grew past the 2 GiB limit while being read",
        ));
    }
    Ok(bytes)
}

/// Refuses a mesh of more than [`MAX_TRIANGLES`] triangles.
pub(crate) fn check_triangles(path: &Path, triangles: usize) -> Result<(), SceneError> {
    if triangles > MAX_TRIANGLES {
        return Err(too_large(
            path,
            format!("{triangles} triangles; the limit is {MAX_TRIANGLES} per mesh"),
        ));
    }
    Ok(())
}

/// Installs per-vertex normals read from a file: each finite one is normalized (unless it already
/// is unit length to within 1e-5, then it is kept as it is); zero-length ones
/// are replaced by the computed (area-weighted) normal; non-finite ones are kept so that
/// Fails with [`SceneError::InvalidMesh`] if any index points past the vertices. Loaders call it
/// before computing normals, so a bad index is reported rather than silently skipped.
pub(crate) fn check_indices(mesh: &Mesh) -> Result<(), SceneError> {
    match mesh
        .indices
        .iter()
        .find(|&&i| i as usize >= mesh.positions.len())
    {
        Some(&i) => Err(SceneError::InvalidMesh {
            mesh: mesh.name.clone(),
            reason: format!(
                "index {i} is out of range ({} vertices)",
                mesh.positions.len()
            ),
        }),
        None => Ok(()),
    }
}

/// [`Mesh::validate`] reports them. `None` (or a count mismatch) computes all normals.
fn set_normals(mesh: &mut Mesh, normals: Option<Vec<Vec3>>) {
    let Some(mut normals) = normals.filter(|n| n.len() == mesh.positions.len()) else {
        mesh.compute_normals();
        return;
    };
    let mut computed: Option<Vec<Vec3>> = None;
    for (i, n) in normals.iter_mut().enumerate() {
        if !n.is_finite() {
            continue;
        }
        if (n.length_squared() - 1.0).abs() <= 1e-5 {
            continue; // already unit: kept bit-exact, so written files round-trip exactly
        }
        *n = match n.try_normalize() {
            Some(unit) => unit,
            None => {
                let c = computed.get_or_insert_with(|| {
                    let mut tmp = Mesh {
                        name: String::new(),
                        positions: mesh.positions.clone(),
                        normals: Vec::new(),
                        uvs: Vec::new(),
                        indices: mesh.indices.clone(),
                    };
                    tmp.compute_normals();
                    tmp.normals
                });
                c[i]
            }
        };
    }
    mesh.normals = normals;
}

/// A mesh name for messages: the file name, plus the object name inside it if there is one.
fn mesh_name(path: &Path, inner: Option<&str>) -> String {
    let file = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    match inner {
        Some(s) if !s.trim().is_empty() => format!("{file}/{}", s.trim()),
        _ => file,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_dispatch_is_case_insensitive() {
        assert_eq!(format_of(Path::new("a/B.OBJ")), Some(Format::Obj));
        assert_eq!(format_of(Path::new("x.GlB")), Some(Format::Gltf));
        assert_eq!(format_of(Path::new("x.gltf")), Some(Format::Gltf));
        assert_eq!(
            format_of(Path::new("x.Ply")),
            Some(Format::Ply { gzip: false })
        );
        assert_eq!(
            format_of(Path::new("x.PLY.GZ")),
            Some(Format::Ply { gzip: true })
        );
        assert_eq!(format_of(Path::new("x.gz")), None);
        assert_eq!(format_of(Path::new("x.stl")), None);
        assert_eq!(format_of(Path::new("noext")), None);
    }

    #[test]
    fn triangle_limit() {
        assert!(check_triangles(Path::new("m.ply"), MAX_TRIANGLES).is_ok());
        assert!(matches!(
            check_triangles(Path::new("m.ply"), MAX_TRIANGLES + 1),
            Err(SceneError::TooLarge { .. })
        ));
    }

    #[test]
    fn parser_panic_becomes_parse_error() {
        let r: Result<(), _> = catch_parser_panic(Path::new("p.ply"), || panic!("boom"));
        match r {
            Err(SceneError::Parse { reason, .. }) => assert!(reason.contains("boom"), "{reason}"),
            other => panic!("unexpected {other:?}"),
        }
    }

    #[test]
    fn zero_normals_fall_back_to_computed() {
        let mut m = Mesh {
            name: "t".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Z],
            normals: vec![],
            indices: vec![0, 2, 1],
        };
        set_normals(&mut m, Some(vec![Vec3::ZERO, Vec3::Y * 3.0, Vec3::Y]));
        // Triangle (0, Z, X) winds counter-clockwise seen from +Y.
        assert_eq!(m.normals, vec![Vec3::Y, Vec3::Y, Vec3::Y]);
    }
}
