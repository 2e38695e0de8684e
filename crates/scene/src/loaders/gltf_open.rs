//! Opening a glTF file: the GLB container or plain JSON, glTF 1.0 recognised and refused with
//! a clear message, the accessor references checked before the `gltf` crate's validation
//! (which would panic on a dangling one), the required extensions sorted into ignorable and
//! refused, and the buffers loaded, external ones held to [`MAX_FILE_BYTES`].

use std::path::{Path, PathBuf};

use ::gltf::Document;
use serde_json::Value;

use super::common::{io_error, parse_error, read_limited, too_large, MAX_FILE_BYTES};
use crate::error::SceneError;

/// Extensions a file may *require* that this loader still reads, ignoring the extension with a
/// note (the result looks different from what the author intended, but it is the scene): texture
/// transforms and the PBR material extensions, which a Phong renderer cannot show anyway.
fn ignorable_requirement(name: &str) -> bool {
    name == "KHR_texture_transform" || name.starts_with("KHR_materials_")
}

/// An opened, validated glTF file with its buffers.
pub(super) struct Opened {
    pub(super) document: Document,
    pub(super) buffers: Vec<::gltf::buffer::Data>,
    /// The whole JSON document, untyped.
    pub(super) json: Value,
    /// The directory external files are relative to.
    pub(super) base: PathBuf,
    /// Remarks made while opening (ignored required extensions).
    pub(super) notes: Vec<String>,
}

/// Reads, checks and validates the document and loads its buffers.
pub(super) fn open(path: &Path) -> Result<Opened, SceneError> {
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
pub(super) fn percent_decode(s: &str) -> Option<String> {
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
}
