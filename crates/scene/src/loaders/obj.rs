//! Wavefront OBJ via `tobj`, and a small OBJ writer.
//!
//! Why: OBJ is the lowest-common-denominator interchange format (most test models ship as OBJ,
//! Sponza included). `tobj` does the parsing; here it is told to triangulate (fan) and to build
//! a single index so normals and texture coordinates line up with positions the way [`Mesh`]
//! needs. tobj starts a new model whenever the material changes, so every mesh has one
//! material. Texture coordinates are flipped to glTF's convention (`v = 1 − v_obj`: OBJ's
//! `v = 0` is the bottom of the image, ours the top).
//!
//! [`load`] (behind [`load_mesh`](super::dispatch::load_mesh)) reads geometry only and never
//! opens another file. [`load_scene`] also opens the material libraries (`mtllib`, relative to
//! the OBJ and inside its folder unless allowed, at most [`MAX_MTL_BYTES`] each) and their
//! textures ([`super::mtl`]). A library that is missing, unreadable, outside the folder or
//! empty is not an error: the meshes get a default material and the scene a note, since
//! geometry without its materials is still worth rendering. Lines that are not UTF-8 are read
//! as Latin-1, and a material without a name is called "(unnamed)" (`obj_text`).

use std::cell::RefCell;
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::common::{check_finite, mesh_name, open_limited, parse_error, set_normals, Parts};
use super::obj_text::{sanitize_mtl, ObjText};
use super::options::LoadOptions;
use super::paths::{model_folder, resolve};
use crate::error::SceneError;
use crate::model::{Material, Mesh};

/// Largest material library (`.mtl`) read, in bytes (64 MiB; real ones are kilobytes).
pub const MAX_MTL_BYTES: u64 = 64 << 20;

/// A material library named by the OBJ, and what became of it.
pub(super) struct Library {
    /// The name as the OBJ gives it.
    pub name: String,
    /// The directory its texture paths are relative to.
    pub dir: PathBuf,
    /// How many materials it defined, or why it could not be used.
    pub outcome: Result<usize, String>,
}

/// What [`read`] returns.
struct ObjRead {
    meshes: Vec<Mesh>,
    /// Each mesh's index into `materials` (tobj's, in library order), if any.
    material_ids: Vec<Option<usize>>,
    materials: Vec<tobj::Material>,
    libraries: Vec<Library>,
}

/// Loads every object / group (per material) with faces as one mesh.
pub(super) fn load(path: &Path) -> Result<Vec<Mesh>, SceneError> {
    Ok(read(path, None)?.meshes)
}

/// Loads the meshes with their materials and textures.
pub(super) fn load_scene(path: &Path, options: &LoadOptions) -> Result<Parts, SceneError> {
    let read = read(path, Some(options.allow_outside_paths))?;
    let mut notes = Vec::new();
    for lib in &read.libraries {
        let note = match &lib.outcome {
            Err(reason) => format!(
                "the OBJ's material library '{}' could not be read ({reason}): default materials",
                lib.name
            ),
            Ok(0) => format!(
                "the OBJ's material library '{}' is empty (it defines no materials): default \
                 materials",
                lib.name
            ),
            Ok(_) => continue,
        };
        notes.push(note);
    }
    // tobj appends each library's materials in turn: the directory of material `i`.
    let mut dirs = Vec::with_capacity(read.materials.len());
    for lib in &read.libraries {
        if let Ok(n) = lib.outcome {
            dirs.extend(std::iter::repeat_n(lib.dir.clone(), n));
        }
    }
    let base = model_folder(path);
    dirs.resize(read.materials.len(), base.clone());
    let (mut materials, textures) = super::mtl::convert(
        &read.materials,
        &dirs,
        (&base, options.allow_outside_paths),
        &mut notes,
    );
    let default_material = materials.len();
    let mut needs_default = false;
    let mesh_material = read
        .material_ids
        .iter()
        .map(|id| match id {
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
    Ok(Parts {
        transforms: vec![vec![glam::Mat4::IDENTITY]; read.meshes.len()],
        meshes: read.meshes,
        mesh_material,
        materials,
        textures,
        lights: Vec::new(),
        camera: None,
        notes,
        mesh_nodes: Vec::new(),
        animations: Default::default(),
    })
}

/// Reads a material library, held to [`MAX_MTL_BYTES`]; the error is the reason in words.
fn read_mtl(file: &Path) -> Result<Vec<u8>, String> {
    let len = super::files::len(file).map_err(|e| e.to_string())?;
    if len > MAX_MTL_BYTES {
        return Err(format!(
            "it is {len} bytes; the limit is {MAX_MTL_BYTES} bytes"
        ));
    }
    let mut bytes = Vec::new();
    super::files::open(file)
        .map_err(|e| e.to_string())?
        .take(MAX_MTL_BYTES)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Reads the OBJ; `with_materials` is `None` for geometry only (no other file is opened),
/// else whether material libraries may lie outside the OBJ's folder.
fn read(path: &Path, with_materials: Option<bool>) -> Result<ObjRead, SceneError> {
    let mut reader = BufReader::new(ObjText::new(BufReader::new(open_limited(path)?)));
    // `..Default::default()` covers fields that only exist with some of tobj's optional features.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let base = model_folder(path);
    let libraries = RefCell::new(Vec::new());
    let load_library = |name: &Path| -> tobj::MTLLoadResult {
        let Some(allow_outside) = with_materials else {
            // Geometry only: never open another file.
            return Err(tobj::LoadError::OpenFileFailed);
        };
        let name = name.to_string_lossy().replace('\\', "/");
        let file = base.join(&name);
        let dir = file.parent().unwrap_or(&base).to_path_buf();
        let safe = resolve(
            &base,
            &base,
            &name,
            &format!("mtllib '{name}'"),
            allow_outside,
        );
        let (outcome, result) = match safe.and_then(|file| read_mtl(&file)) {
            Ok(bytes) => {
                match tobj::load_mtl_buf(&mut std::io::Cursor::new(sanitize_mtl(&bytes))) {
                    Ok((materials, map)) => (Ok(materials.len()), Ok((materials, map))),
                    Err(e) => (Err(format!("{e}")), Err(e)),
                }
            }
            Err(reason) => (Err(reason), Err(tobj::LoadError::OpenFileFailed)),
        };
        libraries.borrow_mut().push(Library { name, dir, outcome });
        result
    };
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, load_library)
        .map_err(|e| parse_error(path, format!("OBJ: {e}")))?;
    let materials = materials.unwrap_or_default();

    let mut meshes = Vec::with_capacity(models.len());
    let mut material_ids = Vec::with_capacity(models.len());
    for model in models {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        super::common::check_triangles(path, m.indices.len() / 3)?;
        let positions = to_vec3(&m.positions);
        let normals = (m.normals.len() == m.positions.len()).then(|| to_vec3(&m.normals));
        let uvs = if m.texcoords.len() / 2 == positions.len() && m.texcoords.len() % 2 == 0 {
            m.texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                .collect()
        } else {
            Vec::new()
        };
        let mut mesh = Mesh {
            name: mesh_name(path, Some(&model.name)),
            positions,
            normals: Vec::new(),
            uvs,
            indices: m.indices,
        };
        // Check indices and numbers before computing normals so the error is InvalidMesh
        // naming the vertex, not a silent skip or a NaN normal.
        super::common::check_indices(&mesh)?;
        check_finite(&mesh.name, &mesh.positions, normals.as_deref())?;
        set_normals(&mut mesh, normals);
        meshes.push(mesh);
        material_ids.push(m.material_id);
    }
    Ok(ObjRead {
        meshes,
        material_ids,
        materials,
        libraries: libraries.into_inner(),
    })
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
