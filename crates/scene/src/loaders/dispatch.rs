//! The loaders' entry points: the format chosen by file extension, the parser run so that a
//! panic inside it becomes an error, and a format's parts put together into a checked
//! [`Scene`] with default lights, camera and ground where the file has none (the rules are in
//! the module documentation of [`super`]).

use std::path::Path;

use glam::Mat4;

use super::common::{bounds_of_placed, check_file_size, check_triangles, parse_error, Parts};
use super::framing::{add_ground, default_camera, default_rig};
use super::options::LoadOptions;
use crate::animation::Moving;
use crate::error::SceneError;
use crate::look::Lighting;
use crate::model::{Camera, Instance, Material, Mesh, Scene};

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

impl super::files::MemoryFiles {
    /// The files that are model files (`.gltf`, `.glb`, `.obj`, `.ply`, `.ply.gz`, any
    /// case), sorted: what a page offers to open among dropped files.
    pub fn models(&self) -> Vec<&str> {
        self.names()
            .filter(|n| format_of(Path::new(n)).is_some())
            .collect()
    }
}

/// Loads every triangle mesh in a file, choosing the format by extension (case-insensitive):
///
/// - `.obj`: one [`Mesh`] per OBJ object / group (polygons fan-triangulated, normals from `vn`
///   where the file has them, computed otherwise; materials and texture coordinates ignored);
/// - `.gltf` / `.glb`: one [`Mesh`] per triangle primitive per node of the default scene
///   (the first scene if none is marked default; every mesh untransformed if the file has no
///   scene), with the node's world transform baked into positions and normals (a node with
///   `EXT_mesh_gpu_instancing`: one mesh per instance);
/// - `.ply` / `.ply.gz`: one [`Mesh`] (ascii, binary little- or big-endian).
///
/// The same as [`load_mesh_with`] with [`LoadOptions::default`] (paths in the file stay
/// inside its folder).
///
/// Every returned mesh passes [`Mesh::validate`]. Errors: [`SceneError::UnsupportedFormat`] for
/// another extension, [`SceneError::Io`] if the file cannot be read, [`SceneError::TooLarge`] for
/// the limits ([`MAX_FILE_BYTES`], [`MAX_DECOMPRESSED_BYTES`], [`MAX_TRIANGLES`]),
/// [`SceneError::Parse`] (with the path and the parser's reason) for malformed content or a
/// path that leaves the model's folder, and [`SceneError::InvalidMesh`] for non-finite
/// coordinates or out-of-range indices.
///
/// [`MAX_FILE_BYTES`]: super::common::MAX_FILE_BYTES
/// [`MAX_DECOMPRESSED_BYTES`]: super::common::MAX_DECOMPRESSED_BYTES
/// [`MAX_TRIANGLES`]: super::common::MAX_TRIANGLES
pub fn load_mesh(path: &Path) -> Result<Vec<Mesh>, SceneError> {
    load_mesh_with(path, &LoadOptions::default())
}

/// [`load_mesh`] with options: [`LoadOptions::allow_outside_paths`] lets a glTF file's buffer
/// URIs leave its folder ([`LoadOptions::ground`] does not apply to geometry alone).
pub fn load_mesh_with(path: &Path, options: &LoadOptions) -> Result<Vec<Mesh>, SceneError> {
    let format = format_of(path).ok_or_else(|| SceneError::UnsupportedFormat {
        path: path.to_path_buf(),
    })?;
    check_file_size(path)?;
    let meshes = catch_parser_panic(path, || match format {
        Format::Obj => super::obj::load(path),
        Format::Gltf => super::gltf::load(path, options),
        Format::Ply { gzip } => super::ply::load(path, gzip),
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

/// A scene read from a file, with remarks on it.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene; it has passed [`Scene::validate`].
    pub scene: Scene,
    /// One-line, human-readable remarks on what was ignored, replaced or added (lights
    /// invented for a file without any, extensions ignored, a material library that could not
    /// be read, a ground plane, …), in the order they arose, each said once. Empty when the
    /// file was used as it is.
    pub notes: Vec<String>,
}

/// Loads a whole scene from a mesh file, choosing the format by extension as [`load_mesh`]
/// does (`.gltf`, `.glb`, `.obj`, `.ply`, `.ply.gz`): meshes (one per glTF triangle primitive,
/// node transforms baked, one instance per `EXT_mesh_gpu_instancing` instance; one per OBJ
/// object and material; one for PLY), instances casting shadows, the file's materials and
/// textures, its lights and camera, mapped as the module documentation describes. A file
/// without lights gets the [`DEFAULT_LIGHT_COUNT`](super::DEFAULT_LIGHT_COUNT) lights of a default rig (key, fill, rim,
/// coloured accents), a file without a camera one that frames the bounds, a model without a
/// floor a ground plane; the notes say so.
///
/// The same as [`load_scene_with`] with [`LoadOptions::default`].
///
/// Errors: those of [`load_mesh`], plus [`SceneError::Parse`] for glTF 1.0 files (with how to
/// convert them) and for glTF files requiring an unsupported extension, and the
/// [`Scene::validate`] errors (e.g. a material colour that is not finite).
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    load_scene_with(path, &LoadOptions::default())
}

/// [`load_scene`] with options (paths outside the model's folder, the ground plane).
pub fn load_scene_with(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let format = format_of(path).ok_or_else(|| SceneError::UnsupportedFormat {
        path: path.to_path_buf(),
    })?;
    check_file_size(path)?;
    catch_parser_panic(path, || {
        let mut lighting = Lighting::Phong;
        let parts = match format {
            Format::Obj => super::obj::load_scene(path, options)?,
            Format::Gltf => {
                lighting = Lighting::Physical;
                super::gltf::load_scene(path, options)?
            }
            Format::Ply { gzip } => {
                let meshes = super::ply::load(path, gzip)?;
                Parts {
                    mesh_material: vec![0; meshes.len()],
                    transforms: vec![vec![Mat4::IDENTITY]; meshes.len()],
                    meshes,
                    materials: vec![Material::default()],
                    textures: Vec::new(),
                    lights: Vec::new(),
                    camera: None,
                    notes: Vec::new(),
                    mesh_nodes: Vec::new(),
                    animations: Default::default(),
                }
            }
        };
        assemble(path, parts, options, lighting)
    })
}

/// [`load_scene_with`] on a set of files held in memory (a web page's dropped files): `name`
/// is the model file's name in `files`, and every path the model names (glTF buffers and
/// images, an OBJ's material library and textures) resolves only among `files`, relative to
/// the model's folder in the set; a path that names none of them is an [`SceneError::Io`]
/// error naming the path and listing the files given. The options apply as on disk (a path
/// that climbs above the model's folder is refused unless
/// [`LoadOptions::allow_outside_paths`], and even then it stays inside the set).
pub fn load_scene_from_memory(
    files: &super::files::MemoryFiles,
    name: &str,
    options: &LoadOptions,
) -> Result<LoadedScene, SceneError> {
    super::files::with_memory(files, || load_scene_with(Path::new(name), options))
}

/// Checks the meshes, places them, adds default lights, camera and ground where the file has
/// none, and validates the result.
fn assemble(
    path: &Path,
    parts: Parts,
    options: &LoadOptions,
    lighting: Lighting,
) -> Result<LoadedScene, SceneError> {
    let Parts {
        meshes,
        mesh_material,
        transforms,
        materials,
        textures,
        lights,
        camera,
        mut notes,
        mesh_nodes,
        mut animations,
    } = parts;
    if meshes.is_empty() {
        return Err(parse_error(path, "the file contains no triangles"));
    }
    let mut total = 0usize;
    for m in &meshes {
        total = total.saturating_add(m.triangle_count());
        check_triangles(path, m.triangle_count())?;
        m.validate()?;
    }
    let bounds = bounds_of_placed(&meshes, &transforms);
    let mut instances = Vec::new();
    let animated = animations.animated_nodes();
    let rest = animations.rest_worlds();
    let mut frozen = std::collections::BTreeSet::new();
    for (mesh, (&material, placed)) in mesh_material.iter().zip(&transforms).enumerate() {
        for &t in placed {
            let node = mesh_nodes.get(mesh).copied().flatten();
            if let Some(n) = node.filter(|&n| animated.get(n) == Some(&true)) {
                // The rest world transform is baked into the vertices (or into `t`): the
                // animation moves the instance by W(t) · W₀⁻¹.
                if rest[n].is_finite() && rest[n].determinant().abs() >= 1e-12 {
                    animations.moving.push(Moving {
                        instance: instances.len(),
                        node: n,
                        from_rest: rest[n].inverse() * t,
                    });
                } else {
                    frozen.insert(n);
                }
            }
            instances.push(Instance::caster(mesh, material, t));
        }
    }
    if !frozen.is_empty() {
        notes.push(format!(
            "node(s) {frozen:?} are scaled to nothing at rest, so their meshes cannot be \
             placed by the animation: they stay still"
        ));
    }
    if !animations.clips.is_empty() && animations.is_empty() {
        notes.push(
            "the file's animations move no mesh (only lights, cameras or empty nodes)".into(),
        );
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    let mut scene = Scene {
        name,
        meshes,
        materials,
        textures,
        instances,
        lights,
        camera: Camera::default(),
        lighting,
        probes: Vec::new(),
        animations,
    };
    scene.camera = camera.unwrap_or_else(|| default_camera(bounds));
    if scene.lights.is_empty() {
        scene.lights = default_rig(bounds, &scene.camera, lighting);
        notes.push(format!(
            "the file has no lights: added a light rig of {} (key, fill and rim directional \
             lights, {} coloured point lights around the model)",
            scene.lights.len(),
            scene.lights.len() - 3
        ));
    }
    if let Some(note) = add_ground(&mut scene, options.ground) {
        notes.push(note);
    }
    log::debug!("{}: {total} triangles", path.display());
    scene.validate()?;
    let mut seen = std::collections::HashSet::new();
    notes.retain(|n| seen.insert(n.clone()));
    Ok(LoadedScene { scene, notes })
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

#[cfg(test)]
mod tests {
    use super::super::common::*;
    use super::*;
    use glam::Vec3;

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
            indices: vec![0, 2, 1],
            ..Mesh::default()
        };
        set_normals(&mut m, Some(vec![Vec3::ZERO, Vec3::Y * 3.0, Vec3::Y]));
        // Triangle (0, Z, X) winds counter-clockwise seen from +Y.
        assert_eq!(m.normals, vec![Vec3::Y, Vec3::Y, Vec3::Y]);
    }
}
