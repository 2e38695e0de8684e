//! Opening a glTF file: the GLB container or plain JSON, glTF 1.0 recognised and refused with
//! a clear message, what the `gltf` crate's schema requires but the specification does not
//! filled in (a scene without `nodes`), the accessor references checked before the crate's
//! validation (which would panic on a dangling one), the required extensions sorted into
//! supported, ignorable and refused, and the buffers loaded: external ones only from inside
//! the model's folder (unless allowed) and held to [`MAX_FILE_BYTES`], meshopt-compressed
//! buffer views decoded.

use std::path::{Path, PathBuf};

use ::gltf::Document;
use serde_json::Value;

use super::common::{io_error, parse_error, read_limited, too_large, MAX_FILE_BYTES};
use super::gltf_extensions::{ignorable_requirement, SUPPORTED};
use super::options::LoadOptions;
use super::paths::{model_folder, resolve};
use crate::error::SceneError;

/// An opened, validated glTF file with its buffers.
pub(super) struct Opened {
    pub(super) document: Document,
    pub(super) buffers: Vec<::gltf::buffer::Data>,
    /// The whole JSON document, untyped.
    pub(super) json: Value,
    /// The directory external files are relative to.
    pub(super) base: PathBuf,
    /// Whether paths may leave `base` ([`LoadOptions::allow_outside_paths`]).
    pub(super) allow_outside: bool,
    /// The extensions the file requires (all of them, before the supported ones are taken
    /// off the list the `gltf` crate validates).
    pub(super) required: Vec<String>,
}

/// Reads, checks and validates the document and loads its buffers.
pub(super) fn open(path: &Path, options: &LoadOptions) -> Result<Opened, SceneError> {
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
    let mut json: Value =
        serde_json::from_slice(&json_bytes).map_err(|e| parse_error(path, format!("glTF: {e}")))?;
    drop(json_bytes);
    if is_gltf1(&json) {
        return Err(gltf1_error(path));
    }
    // `scene.nodes` is optional in glTF 2.0 (an empty scene), but the crate's schema requires
    // it: give such scenes an empty list.
    if let Some(Value::Array(scenes)) = json.get_mut("scenes") {
        for scene in scenes.iter_mut().filter_map(Value::as_object_mut) {
            scene
                .entry("nodes")
                .or_insert_with(|| Value::Array(Vec::new()));
        }
    }
    let mut root: ::gltf::json::Root = serde_json::from_value(json.clone())
        .map_err(|e| parse_error(path, format!("glTF: {e}")))?;

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
    // Required extensions: the ones this loader reads and the ignorable ones are dropped from
    // the list so that validation accepts the file (the ignored ones get their note with the
    // other unsupported extensions, `gltf_extensions`); any other is refused here, by name.
    let required = std::mem::take(&mut root.extensions_required);
    let unsupported: Vec<String> = required
        .iter()
        .filter(|e| !SUPPORTED.contains(&e.as_str()) && !ignorable_requirement(e))
        .cloned()
        .collect();
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
    let placeholder = give_views_to_bare_accessors(&mut root);
    let document =
        Document::from_json(root).map_err(|e| parse_error(path, format!("glTF: {e}")))?;
    let base = model_folder(path);
    let mut buffers = load_buffers(path, &json, &base, blob, options.allow_outside_paths)?;
    if placeholder {
        buffers.push(Vec::new());
    }
    super::gltf_meshopt::decode_meshopt_views(path, &json, &mut buffers)?;
    Ok(Opened {
        document,
        buffers: buffers.into_iter().map(::gltf::buffer::Data).collect(),
        json,
        base,
        allow_outside: options.allow_outside_paths,
        required,
    })
}

/// An accessor without a buffer view is legal glTF (it reads as zeros, and the accessors of a
/// Draco-compressed primitive are such accessors), but the `gltf` crate's validation refuses
/// it. Each one is pointed at an empty placeholder view of an empty placeholder buffer
/// (appended after the file's own), so that the document validates; a Draco primitive never
/// reads its accessors, and any other read of such an accessor finds no data and says so.
/// Returns whether the placeholder was added.
fn give_views_to_bare_accessors(root: &mut ::gltf::json::Root) -> bool {
    let bare: Vec<usize> = root
        .accessors
        .iter()
        .enumerate()
        .filter(|(_, a)| a.buffer_view.is_none() && a.sparse.is_none())
        .map(|(i, _)| i)
        .collect();
    if bare.is_empty() {
        return false;
    }
    let buffer = root.buffers.len();
    let view = root.buffer_views.len();
    let (Ok(b), Ok(v)) = (
        serde_json::from_value(serde_json::json!({ "byteLength": 1 })),
        serde_json::from_value(serde_json::json!({ "buffer": buffer, "byteLength": 1 })),
    ) else {
        return false;
    };
    root.buffers.push(b);
    root.buffer_views.push(v);
    for i in bare {
        root.accessors[i].buffer_view = Some(::gltf::json::Index::new(view as u32));
    }
    true
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

/// The data of every buffer, in order: the GLB's binary chunk for a first buffer without a
/// URI, a base64 `data:` URI decoded, or a file inside the model's folder (nothing is
/// downloaded); a buffer that only stands in for meshopt-compressed views
/// (`EXT_meshopt_compression`'s `fallback`) starts empty and is filled by their decoding.
fn load_buffers(
    path: &Path,
    json: &Value,
    base: &Path,
    mut blob: Option<Vec<u8>>,
    allow_outside: bool,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let empty = Vec::new();
    let list = json
        .get("buffers")
        .and_then(Value::as_array)
        .unwrap_or(&empty);
    let mut out = Vec::with_capacity(list.len());
    for (i, buffer) in list.iter().enumerate() {
        let length = buffer
            .get("byteLength")
            .and_then(Value::as_u64)
            .unwrap_or(0);
        let fallback = buffer
            .pointer("/extensions/EXT_meshopt_compression/fallback")
            .and_then(Value::as_bool)
            .unwrap_or(false);
        let data = match buffer.get("uri").and_then(Value::as_str) {
            Some(uri) => read_uri(base, uri, allow_outside)
                .map_err(|reason| parse_error(path, format!("glTF buffer {i}: {reason}")))?,
            None if i == 0 && blob.is_some() => blob.take().unwrap_or_default(),
            None if fallback => {
                out.push(Vec::new());
                continue;
            }
            None => {
                return Err(parse_error(
                    path,
                    format!(
                        "glTF buffer {i} has no URI and is not the binary chunk of a .glb: its data is missing"
                    ),
                ))
            }
        };
        if (data.len() as u64) < length {
            return Err(parse_error(
                path,
                format!(
                    "glTF buffer {i} holds {} bytes but declares a byteLength of {length}",
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes a URI names: a base64 `data:` URI or a file relative to `base` (percent-decoded,
/// `file:` accepted), which must lie inside `base` unless `allow_outside`. The error is the
/// reason in words.
pub(super) fn read_uri(base: &Path, uri: &str, allow_outside: bool) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (meta, data) = rest
            .split_once(',')
            .ok_or_else(|| "malformed data URI".to_string())?;
        if !meta.ends_with(";base64") {
            return Err("only base64 data URIs are supported".into());
        }
        return super::base64::decode(data);
    }
    let name = if let Some(rest) = uri.strip_prefix("file://") {
        rest
    } else if let Some(rest) = uri.strip_prefix("file:") {
        rest
    } else if uri.contains(':') && !is_drive_letter(uri) {
        return Err(format!(
            "URI '{uri}' is neither a file nor a data: URI (nothing is downloaded)"
        ));
    } else {
        uri
    };
    let decoded = percent_decode(name)
        .ok_or_else(|| format!("URI '{uri}' is not valid percent-encoded UTF-8"))?;
    let file: PathBuf = resolve(base, base, &decoded, &format!("URI '{uri}'"), allow_outside)?;
    let len = super::files::len(&file).map_err(|e| io_error(&file, e).to_string())?;
    if len > MAX_FILE_BYTES {
        return Err(too_large(
            &file,
            format!("it is {len} bytes; the limit is {MAX_FILE_BYTES} bytes (2 GiB)"),
        )
        .to_string());
    }
    read_limited(&file).map_err(|e| e.to_string())
}

/// `C:\…`: a Windows drive path, not a URI scheme (refused as absolute by [`resolve`]).
fn is_drive_letter(uri: &str) -> bool {
    let b = uri.as_bytes();
    b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':'
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
