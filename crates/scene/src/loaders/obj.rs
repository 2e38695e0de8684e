//! Wavefront OBJ via `tobj`, and a small OBJ writer.
//!
//! Why: OBJ is the lowest-common-denominator interchange format (most test models ship as OBJ).
//! `tobj` does the parsing; here it is told to triangulate (fan) and to build a single index so
//! normals line up with positions the way [`Mesh`] needs. Materials (`mtllib`) are not opened:
//! the scene format assigns materials itself, and skipping them means a model never makes the
//! loader touch other files.

use std::io::{BufReader, Write};
use std::path::Path;

use glam::Vec3;

use super::{mesh_name, open_limited, parse_error, set_normals};
use crate::{Mesh, SceneError};

/// Loads every object / group with faces as one mesh.
pub(super) fn load(path: &Path) -> Result<Vec<Mesh>, SceneError> {
    let mut reader = BufReader::new(open_limited(path)?);
    // `..Default::default()` covers fields that only exist with some of tobj's optional features.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Material libraries are deliberately not opened (see the module docs).
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| parse_error(path, format!("OBJ: {e}")))?;

    let mut meshes = Vec::with_capacity(models.len());
    for model in models {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        super::check_triangles(path, m.indices.len() / 3)?;
        let positions = to_vec3(&m.positions);
        let normals = (m.normals.len() == m.positions.len()).then(|| to_vec3(&m.normals));
        let mut mesh = Mesh {
            name: mesh_name(path, Some(&model.name)),
            positions,
            normals: Vec::new(),
            uvs: Vec::new(),
            indices: m.indices,
        };
        // Check indices before computing normals so the error is InvalidMesh, not a silent skip.
        super::check_indices(&mesh)?;
        set_normals(&mut mesh, normals);
        meshes.push(mesh);
    }
    Ok(meshes)
}

fn to_vec3(flat: &[f32]) -> Vec<Vec3> {
    flat.chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect()
}

/// Writes `mesh` as a Wavefront OBJ: one object named after the mesh, `v` lines, `vn` lines (when
/// there is one normal per position) and triangle `f` lines with 1-based indices.
///
/// Floats are written with Rust's shortest round-trip formatting, so loading the file back with
/// [`load_mesh`](super::load_mesh) reproduces positions exactly.
pub fn write_obj(mesh: &Mesh, w: impl Write) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(w);
    let name = mesh.name.replace(['\n', '\r'], " ");
    writeln!(w, "# written by manyshadows-scene")?;
    writeln!(
        w,
        "o {}",
        if name.trim().is_empty() {
            "mesh"
        } else {
            name.trim()
        }
    )?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    let with_normals = !mesh.normals.is_empty() && mesh.normals.len() == mesh.positions.len();
    if with_normals {
        for n in &mesh.normals {
            writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
        }
    }
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0] as u64 + 1, t[1] as u64 + 1, t[2] as u64 + 1];
        if with_normals {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    w.flush()
}
