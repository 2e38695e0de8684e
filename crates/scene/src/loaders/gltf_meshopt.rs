//! `EXT_meshopt_compression` buffer views, decoded with meshoptimizer's own decoder (the
//! `meshopt` crate; not in the browser build, where such files are refused with a message
//! saying so).
//!
//! Meshopt works below the accessors: a compressed buffer view's bytes are decoded (vertex
//! attributes, triangle indices or index sequences, then the view's filter) into the view's
//! place in its buffer, where the accessors read them as if they had never been compressed.
//! What all views decode to is held to [`MAX_DECOMPRESSED_BYTES`].

use std::path::Path;

use serde_json::Value;

use super::common::{parse_error, too_large, MAX_DECOMPRESSED_BYTES};
use crate::error::SceneError;

/// One `EXT_meshopt_compression` buffer view, as its extension describes it.
struct MeshoptView {
    /// The buffer holding the compressed bytes, and where.
    source: usize,
    offset: usize,
    length: usize,
    /// Decoded elements and their size in bytes.
    count: usize,
    stride: usize,
    mode: String,
    filter: String,
    /// Where the decoded bytes go: the view's own buffer, at the view's offset.
    target: usize,
    target_offset: usize,
}

fn meshopt_view(view: &Value, ext: &Value) -> Result<MeshoptView, String> {
    let number = |v: &Value, key: &str| -> Result<usize, String> {
        v.get(key)
            .and_then(Value::as_u64)
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| format!("{key} is missing or not a number"))
    };
    Ok(MeshoptView {
        source: number(ext, "buffer")?,
        offset: ext
            .get("byteOffset")
            .map_or(Ok(0), |_| number(ext, "byteOffset"))?,
        length: number(ext, "byteLength")?,
        count: number(ext, "count")?,
        stride: number(ext, "byteStride")?,
        mode: ext
            .get("mode")
            .and_then(Value::as_str)
            .unwrap_or_default()
            .to_string(),
        filter: ext
            .get("filter")
            .and_then(Value::as_str)
            .unwrap_or("NONE")
            .to_string(),
        target: number(view, "buffer")?,
        target_offset: view
            .get("byteOffset")
            .map_or(Ok(0), |_| number(view, "byteOffset"))?,
    })
}

/// Decodes every `EXT_meshopt_compression` buffer view of the document into its place in
/// `buffers` (growing a fallback buffer as far as the decoded views reach).
pub(super) fn decode_meshopt_views(
    path: &Path,
    json: &Value,
    buffers: &mut [Vec<u8>],
) -> Result<(), SceneError> {
    let Some(Value::Array(views)) = json.get("bufferViews") else {
        return Ok(());
    };
    let mut total = 0u64;
    for (v, view) in views.iter().enumerate() {
        let Some(ext) = view.pointer("/extensions/EXT_meshopt_compression") else {
            continue;
        };
        let bad = |reason: String| {
            parse_error(
                path,
                format!("glTF buffer view {v}: EXT_meshopt_compression {reason}"),
            )
        };
        let m = meshopt_view(view, ext).map_err(bad)?;
        let size = m
            .count
            .checked_mul(m.stride)
            .ok_or_else(|| bad("count × byteStride overflows".into()))?;
        total = total.saturating_add(size as u64);
        if total > MAX_DECOMPRESSED_BYTES {
            return Err(too_large(
                path,
                format!(
                    "meshopt-compressed buffer views decode to over {MAX_DECOMPRESSED_BYTES} bytes"
                ),
            ));
        }
        let source = buffers
            .get(m.source)
            .and_then(|b| b.get(m.offset..m.offset.checked_add(m.length)?))
            .ok_or_else(|| bad("compressed bytes are outside their buffer".into()))?
            .to_vec();
        let decoded = decode_meshopt(&source, &m).map_err(bad)?;
        let target = buffers
            .get_mut(m.target)
            .ok_or_else(|| bad(format!("buffer {} does not exist", m.target)))?;
        let end = m.target_offset.saturating_add(decoded.len());
        if target.len() < end {
            target.resize(end, 0);
        }
        target[m.target_offset..end].copy_from_slice(&decoded);
    }
    Ok(())
}

/// The bytes of one view, decoded and filtered; the error is the reason in words.
#[cfg(not(target_arch = "wasm32"))]
fn decode_meshopt(source: &[u8], m: &MeshoptView) -> Result<Vec<u8>, String> {
    let failed = |e: meshopt::Error| format!("data could not be decoded ({e})");
    let (count, stride) = (m.count, m.stride);
    match m.mode.as_str() {
        "TRIANGLES" | "INDICES" => {
            if m.mode == "TRIANGLES" && !count.is_multiple_of(3) {
                return Err(format!("TRIANGLES count {count} is not a multiple of 3"));
            }
            let triangles = m.mode == "TRIANGLES";
            match stride {
                2 => {
                    let v: Vec<u16> = if triangles {
                        meshopt::decode_index_buffer(source, count).map_err(failed)?
                    } else {
                        meshopt::decode_index_sequence(source, count).map_err(failed)?
                    };
                    Ok(bytemuck::cast_slice(&v).to_vec())
                }
                4 => {
                    let v: Vec<u32> = if triangles {
                        meshopt::decode_index_buffer(source, count).map_err(failed)?
                    } else {
                        meshopt::decode_index_sequence(source, count).map_err(failed)?
                    };
                    Ok(bytemuck::cast_slice(&v).to_vec())
                }
                _ => Err(format!("index byteStride {stride} is not 2 or 4")),
            }
        }
        "ATTRIBUTES" => {
            let mut bytes = decode_vertices(source, count, stride)?;
            filter(&mut bytes, stride, &m.filter)?;
            Ok(bytes)
        }
        other => Err(format!(
            "mode '{other}' is not ATTRIBUTES, TRIANGLES or INDICES"
        )),
    }
}

#[cfg(target_arch = "wasm32")]
fn decode_meshopt(_: &[u8], m: &MeshoptView) -> Result<Vec<u8>, String> {
    Err(format!(
        "({} view, filter {}) is not decoded in the browser build (meshoptimizer is C++): \
         convert the file without it (e.g. gltfpack without -c) or load it with the native \
         manyshadows",
        m.mode, m.filter
    ))
}

/// A vertex of `N` bytes, for meshopt's typed decoder.
#[cfg(not(target_arch = "wasm32"))]
#[derive(Clone, Copy)]
struct Row<const N: usize>([u8; N]);

#[cfg(not(target_arch = "wasm32"))]
impl<const N: usize> Default for Row<N> {
    fn default() -> Self {
        Self([0; N])
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn rows<const N: usize>(source: &[u8], count: usize) -> Result<Vec<u8>, String> {
    let rows: Vec<Row<N>> = meshopt::decode_vertex_buffer(source, count)
        .map_err(|e| format!("data could not be decoded ({e})"))?;
    Ok(rows.into_iter().flat_map(|r| r.0).collect())
}

/// meshopt's vertex decoder for a byte stride known at run time (a multiple of 4 up to 256,
/// as the extension requires).
#[cfg(not(target_arch = "wasm32"))]
fn decode_vertices(source: &[u8], count: usize, stride: usize) -> Result<Vec<u8>, String> {
    macro_rules! by_stride {
        ($($n:literal)*) => {
            match stride {
                $($n => rows::<$n>(source, count),)*
                _ => Err(format!(
                    "ATTRIBUTES byteStride {stride} is not a multiple of 4 between 4 and 256"
                )),
            }
        };
    }
    by_stride!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100 104
        108 112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184 188 192
        196 200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
}

/// Applies a view's filter to its decoded vertices, in place.
#[cfg(not(target_arch = "wasm32"))]
fn filter(bytes: &mut Vec<u8>, stride: usize, name: &str) -> Result<(), String> {
    match (name, stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4) => {
            let mut v: Vec<[i8; 4]> = bytemuck::pod_collect_to_vec(bytes);
            meshopt::decode_filter_oct(&mut v);
            *bytes = bytemuck::cast_slice(&v).to_vec();
        }
        ("OCTAHEDRAL", 8) | ("QUATERNION", 8) => {
            let mut v: Vec<[i16; 4]> = bytemuck::pod_collect_to_vec(bytes);
            if name == "OCTAHEDRAL" {
                meshopt::decode_filter_oct(&mut v);
            } else {
                meshopt::decode_filter_quat(&mut v);
            }
            *bytes = bytemuck::cast_slice(&v).to_vec();
        }
        ("EXPONENTIAL", s) if s % 4 == 0 => {
            // Each 32-bit component is decoded on its own, so the stride does not matter.
            let mut v: Vec<[u32; 1]> = bytemuck::pod_collect_to_vec(bytes);
            meshopt::decode_filter_exp(&mut v);
            *bytes = bytemuck::cast_slice(&v).to_vec();
        }
        _ => {
            return Err(format!(
                "filter '{name}' with byteStride {stride} is not one the extension defines"
            ))
        }
    }
    Ok(())
}
