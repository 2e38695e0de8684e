//! Stanford PLY (ascii, binary little- and big-endian; `.ply.gz` through gzip) via `ply-rs-bw`,
//! and a small ascii PLY writer.
//!
//! Why: PLY is how scanned models (the Stanford bunny, dragon, Lucy…) are distributed, often
//! gzipped, and they are the standard "many triangles" shadow-casting test. The header is read
//! with `ply-rs-bw`; elements are then streamed one at a time straight into the [`Mesh`] (rather
//! than building the parser's per-element hash maps), so a 100-million-triangle scan costs about
//! what the mesh itself costs. Vertices need `x`, `y`, `z` (any scalar type, usually float or
//! double) and may carry `nx`, `ny`, `nz`; faces are a `vertex_indices` (or `vertex_index`)
//! list of any integer type, fan-triangulated. Other elements and properties (colours, texture
//! coordinates, edges…) are read past and ignored.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyType,
    ScalarType,
};

use super::common::{
    check_triangles, mesh_name, open_limited, parse_error, set_normals, too_large,
    MAX_DECOMPRESSED_BYTES, MAX_TRIANGLES,
};
use crate::error::SceneError;
use crate::model::Mesh;

/// Loads a `.ply` (or, with `gzip`, a `.ply.gz`) file as one mesh.
pub(super) fn load(path: &Path, gzip: bool) -> Result<Vec<Mesh>, SceneError> {
    let file = BufReader::new(open_limited(path)?);
    if gzip {
        load_gz(path, file, MAX_DECOMPRESSED_BYTES)
    } else {
        read_ply(path, file).map(|m| vec![m])
    }
}

/// Decompresses through `take(limit + 1)`: if the parser fails having consumed more than `limit`
/// bytes, the file is reported as too large rather than truncated.
fn load_gz(path: &Path, compressed: impl BufRead, limit: u64) -> Result<Vec<Mesh>, SceneError> {
    let mut limited =
        flate2::bufread::MultiGzDecoder::new(compressed).take(limit.saturating_add(1));
    let result = read_ply(path, BufReader::new(&mut limited));
    if limited.limit() == 0 {
        return Err(too_large(
            path,
            format!("decompresses to more than {limit} bytes (the limit for .ply.gz)"),
        ));
    }
    result.map(|m| vec![m])
}

/// What one PLY element carries that we use. The same type receives every element; which
/// fields matter depends on the element's name.
#[derive(Default)]
struct Elem {
    xyz: [f32; 3],
    normal: [f32; 3],
    face: Vec<u32>,
    negative_index: bool,
}

impl PropertyAccess for Elem {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => Some(&mut self.xyz[0]),
            "y" => Some(&mut self.xyz[1]),
            "z" => Some(&mut self.xyz[2]),
            "nx" => Some(&mut self.normal[0]),
            "ny" => Some(&mut self.normal[1]),
            "nz" => Some(&mut self.normal[2]),
            _ => None,
        };
        if let Some(slot) = slot {
            return match property.to_f32_lossy() {
                Some(v) => {
                    *slot = v;
                    PropertyAccessResult::Set
                }
                None => PropertyAccessResult::UnsupportedType,
            };
        }
        if name == "vertex_indices" || name == "vertex_index" {
            return match property {
                Property::ListFloat(_) | Property::ListDouble(_) => {
                    PropertyAccessResult::UnsupportedType
                }
                p => match p.to_u32_list() {
                    Some(list) => {
                        self.face = list;
                        PropertyAccessResult::Set
                    }
                    // An integer list that does not fit u32: negative indices.
                    None if matches!(
                        p,
                        Property::ListChar(_) | Property::ListShort(_) | Property::ListInt(_)
                    ) =>
                    {
                        self.negative_index = true;
                        PropertyAccessResult::Set
                    }
                    None => PropertyAccessResult::UnsupportedType,
                },
            };
        }
        PropertyAccessResult::Ignored
    }
}

/// What the header says about the vertex and face elements.
struct Layout {
    has_normals: bool,
}

fn check_header(path: &Path, header: &Header) -> Result<Layout, SceneError> {
    let vertex = header
        .elements
        .get("vertex")
        .ok_or_else(|| parse_error(path, "PLY: the header declares no 'vertex' element"))?;
    let scalar = |e: &ElementDef, p: &str| matches!(e.properties.get(p), Some(d) if matches!(d.data_type, PropertyType::Scalar(_)));
    for p in ["x", "y", "z"] {
        if !scalar(vertex, p) {
            return Err(parse_error(
                path,
                format!("PLY: the vertex element needs a scalar property '{p}'"),
            ));
        }
    }
    let has_normals = ["nx", "ny", "nz"].iter().all(|p| scalar(vertex, p));
    if vertex.count > u32::MAX as usize {
        return Err(too_large(
            path,
            format!(
                "{} vertices cannot be indexed with 32-bit indices",
                vertex.count
            ),
        ));
    }
    let face = header.elements.get("face").ok_or_else(|| {
        parse_error(
            path,
            "PLY: the header declares no 'face' element (point clouds are not meshes)",
        )
    })?;
    let list = face
        .properties
        .get("vertex_indices")
        .or_else(|| face.properties.get("vertex_index"))
        .ok_or_else(|| {
            parse_error(
                path,
                "PLY: the face element has no 'vertex_indices' (or 'vertex_index') list",
            )
        })?;
    match &list.data_type {
        PropertyType::List(_, t) if !matches!(t, ScalarType::Float | ScalarType::Double) => {}
        other => {
            return Err(parse_error(
                path,
                format!(
                    "PLY: face '{}' must be a list of integers, not {other:?}",
                    list.name
                ),
            ))
        }
    }
    if face.count > MAX_TRIANGLES {
        return Err(too_large(
            path,
            format!(
                "the header declares {} faces; the limit is {MAX_TRIANGLES} triangles",
                face.count
            ),
        ));
    }
    Ok(Layout { has_normals })
}

/// Parses a whole PLY stream into one mesh.
fn read_ply(path: &Path, source: impl BufRead) -> Result<Mesh, SceneError> {
    let parser = Parser::<Elem>::new();
    let mut reader = Reader::new(source);
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| parse_error(path, format!("PLY header: {e}")))?;
    let layout = check_header(path, &header)?;

    let mut mesh = Mesh {
        name: mesh_name(path, None),
        ..Mesh::default()
    };
    let mut normals = Vec::new();
    let mut skipped_faces = 0usize;
    let mut line = String::new();

    for (name, def) in &header.elements {
        let is_vertex = name == "vertex";
        let is_face = name == "face";
        for i in 0..def.count {
            let elem = match header.encoding {
                Encoding::Ascii => {
                    line.clear();
                    // Skip blank lines; one element per line otherwise, as the format says.
                    loop {
                        let n = reader
                            .get_mut()
                            .read_line(&mut line)
                            .map_err(|e| parse_error(path, format!("PLY: {e}")))?;
                        if n == 0 || !line.trim().is_empty() {
                            break;
                        }
                        line.clear();
                    }
                    if line.is_empty() {
                        return Err(eof(path, name, i, def.count));
                    }
                    parser.read_ascii_element(&line, def)
                }
                Encoding::BinaryLittleEndian => {
                    parser.read_little_endian_element(reader.get_mut(), def)
                }
                Encoding::BinaryBigEndian => parser.read_big_endian_element(reader.get_mut(), def),
            };
            let elem = elem.map_err(|e| {
                if e.kind() == std::io::ErrorKind::UnexpectedEof {
                    eof(path, name, i, def.count)
                } else {
                    parse_error(path, format!("PLY: element '{name}' {i}: {e}"))
                }
            })?;
            if is_vertex {
                mesh.positions.push(Vec3::from_array(elem.xyz));
                if layout.has_normals {
                    normals.push(Vec3::from_array(elem.normal));
                }
            } else if is_face {
                if elem.negative_index {
                    return Err(SceneError::InvalidMesh {
                        mesh: mesh.name,
                        reason: format!("face {i} has a negative vertex index"),
                    });
                }
                let f = &elem.face;
                if f.len() < 3 {
                    skipped_faces += 1;
                    continue;
                }
                check_triangles(path, mesh.indices.len() / 3 + f.len() - 2)?;
                for k in 1..f.len() - 1 {
                    mesh.indices.extend_from_slice(&[f[0], f[k], f[k + 1]]);
                }
            }
        }
    }
    if skipped_faces > 0 {
        log::warn!(
            "{}: skipped {skipped_faces} faces with fewer than 3 vertices",
            path.display()
        );
    }
    super::common::check_indices(&mesh)?;
    let normals = layout.has_normals.then_some(normals);
    super::common::check_finite(&mesh.name, &mesh.positions, normals.as_deref())?;
    set_normals(&mut mesh, normals);
    Ok(mesh)
}

fn eof(path: &Path, element: &str, read: usize, count: usize) -> SceneError {
    parse_error(
        path,
        format!(
            "PLY: unexpected end of file in element '{element}' (read {read} of {count}); \
             the file is truncated"
        ),
    )
}

/// Writes `mesh` as an ascii PLY: `x y z nx ny nz` float vertices (normals only when there is one
/// per position) and `vertex_indices` triangle faces (`list uchar uint`).
///
/// Floats are written with Rust's shortest round-trip formatting, so loading the file back with
/// [`load_mesh`](super::load_mesh) reproduces positions and normals exactly.
pub fn write_ply_ascii(mesh: &Mesh, w: impl Write) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(w);
    let with_normals = !mesh.normals.is_empty() && mesh.normals.len() == mesh.positions.len();
    writeln!(w, "ply")?;
    writeln!(w, "format ascii 1.0")?;
    writeln!(w, "comment written by manyshadows-scene")?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    for p in ["x", "y", "z"] {
        writeln!(w, "property float {p}")?;
    }
    if with_normals {
        for p in ["nx", "ny", "nz"] {
            writeln!(w, "property float {p}")?;
        }
    }
    writeln!(w, "element face {}", mesh.indices.len() / 3)?;
    writeln!(w, "property list uchar uint vertex_indices")?;
    writeln!(w, "end_header")?;
    for (i, p) in mesh.positions.iter().enumerate() {
        if with_normals {
            let n = mesh.normals[i];
            writeln!(w, "{} {} {} {} {} {}", p.x, p.y, p.z, n.x, n.y, n.z)?;
        } else {
            writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
        }
    }
    for t in mesh.indices.chunks_exact(3) {
        writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn gz(bytes: &[u8]) -> Vec<u8> {
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(bytes).unwrap();
        enc.finish().unwrap()
    }

    fn triangle_ply() -> Vec<u8> {
        let mesh = Mesh {
            name: "t".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            indices: vec![0, 1, 2],
            ..Mesh::default()
        };
        let mut out = Vec::new();
        write_ply_ascii(&mesh, &mut out).unwrap();
        out
    }

    #[test]
    fn gzip_within_limit_loads() {
        let data = triangle_ply();
        let meshes = load_gz(
            Path::new("t.ply.gz"),
            Cursor::new(gz(&data)),
            data.len() as u64,
        )
        .unwrap();
        assert_eq!(meshes[0].indices, vec![0, 1, 2]);
    }

    #[test]
    fn gzip_bomb_is_too_large() {
        // A valid header that promises many vertices, then lots of highly compressible data.
        let mut data = b"ply\nformat ascii 1.0\nelement vertex 1000000\nproperty float x\n\
            property float y\nproperty float z\nelement face 0\n\
            property list uchar uint vertex_indices\nend_header\n"
            .to_vec();
        for _ in 0..100_000 {
            data.extend_from_slice(b"0 0 0\n");
        }
        let r = load_gz(Path::new("bomb.ply.gz"), Cursor::new(gz(&data)), 64 * 1024);
        assert!(matches!(r, Err(SceneError::TooLarge { .. })), "{r:?}");
    }
}
