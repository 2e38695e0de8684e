//! Scene and mesh loaders: Wavefront OBJ (with its MTL materials), glTF 2.0 (`.gltf` /
//! `.glb`), Stanford PLY (ascii and binary, optionally gzip-compressed as `.ply.gz`), plus small
//! OBJ / PLY / glTF writers.
//!
//! Why this module exists: the renderer only understands the plain [`Mesh`] of this crate
//! (indexed triangles with one unit normal per vertex, optional texture coordinates) and the
//! Phong [`Material`] / [`Light`] / [`Camera`] model. Each loader turns its format into that
//! shape, so everything downstream deals with one representation:
//!
//! - polygons are triangulated (glTF strips and fans exactly as the glTF specification numbers
//!   their triangles), normals and texture coordinates are re-indexed so they align with
//!   positions;
//! - missing normals are computed with a crease angle ([`Mesh::compute_normals_with_crease`]
//!   at [`CREASE_ANGLE_DEG`]): edges sharper than 60° stay sharp (boxes keep flat faces),
//!   finely tessellated curves stay smooth;
//! - glTF node transforms are baked into the vertices (the renderer places meshes with
//!   [`Instance`] transforms, not with a node hierarchy);
//! - every returned mesh has passed [`Mesh::validate`] (and every [`load_scene`] result
//!   [`Scene::validate`]), so NaNs and out-of-range indices become a [`SceneError`] here
//!   instead of a GPU fault later.
//!
//! [`load_mesh`] reads geometry only (the TOML scene format and benchmarks place meshes
//! themselves). [`load_scene`] reads a whole scene: one [`Mesh`] per glTF triangle primitive
//! or OBJ (object, material), one identity [`Instance`] per mesh (casting shadows), the file's
//! materials, textures, lights and camera, and one-line notes on whatever it had to ignore,
//! replace or invent (the CLI prints them).
//!
//! # glTF lights (`KHR_lights_punctual`) → Phong lights
//!
//! glTF lights are physical: candela (lm/sr) for point and spot lights, lux (lm/m²) for
//! directional ones, falling off with the inverse square of distance. This renderer's lights
//! are Phong colours with an attenuation. The mapping:
//!
//! - diffuse = specular = `color × intensity × PHONG_PER_LUX`, with [`PHONG_PER_LUX`] = 0.1:
//!   one unit of this renderer's light colour stands for 10 lux of irradiance (a 10 lux
//!   directional light is colour 1: a white surface facing it shows its full diffuse colour);
//!   ambient = 0 (the file's lights add no ambient term);
//! - point and spot attenuation = `1 / (1 + d²)` (constant 1, linear 0, quadratic 1: the
//!   inverse square, kept finite at the light);
//! - range = the light's `range` if the file gives one, else the distance at which
//!   `max(colour) / (1 + d²)` falls to 1/256 (below one step of an 8-bit image), at least 0.1
//!   and at most 4 × the diagonal of the scene's bounds;
//! - position = the node's world translation; direction (spot, directional) = the node's
//!   world rotation applied to (0, 0, −1);
//! - spot `cutoff_deg` = `outerConeAngle` in degrees (glTF's default π/4), clamped into
//!   (0°, 89°) (at most 88.99°, as [`Light::validate`] requires); `innerConeAngle` is ignored:
//!   this renderer's spot lights have a hard cone edge;
//! - directional lights get [`DIRECTIONAL_CASCADES`] cascades, split blend
//!   [`DIRECTIONAL_SPLIT_LAMBDA`], every cascade at [`DIRECTIONAL_SHADOW_RESOLUTION`]
//!   (`cascade_resolution_scale` 1); spot and point lights [`SPOT_SHADOW_RESOLUTION`] and
//!   [`POINT_SHADOW_RESOLUTION`]; every light casts shadows. A light of zero intensity or colour
//!   is kept (it adds nothing).
//!
//! A file with no lights (and every OBJ and PLY file) gets the seeded layout
//! [`scatter_lights`]`(scene, 8, seed 1, LightMix::All, None)` and a note saying so.
//! [`write_gltf`] writes the inverse mapping (`intensity = max(diffuse) / PHONG_PER_LUX`,
//! `color = diffuse / max(diffuse)`), so a written light loads back with the same colours,
//! range, cone and direction; a light's ambient colour, a specular colour different from its
//! diffuse one and its attenuation are not representable in glTF and come back as above.
//!
//! # glTF materials → Phong materials
//!
//! - `baseColorFactor` rgb → `diffuse` and `ambient`; its alpha → `base_alpha`;
//! - specular = `mix(0.04, base rgb, metallic)` per channel (dielectrics reflect about 4 %
//!   white, metals their own colour);
//! - shininess = `2/α² − 2` with `α = roughness²` (the Blinn-Phong exponent whose highlight
//!   matches GGX of that α), clamped to 1..=512;
//! - `baseColorTexture` → `base_color_texture`, `normalTexture` → `normal_texture`, each with
//!   its sampler's `wrapS` / `wrapT`; texture-coordinate set 0 is always used (a texture that
//!   names another set gets a note); metallic-roughness, occlusion and emissive textures are
//!   not used;
//! - `alphaMode`, `alphaCutoff` (default 0.5) and `doubleSided` are copied;
//! - primitives without a material get [`Material::default`];
//! - extensions used by a material (`KHR_texture_transform`, `KHR_materials_*`, …) are
//!   ignored with a note; a file that *requires* one of those still loads (with a note), a
//!   file that requires any other unsupported extension (compressed geometry or textures) is
//!   refused with a [`SceneError::Parse`] naming it.
//!
//! Images come from a buffer view (GLB), a base64 `data:` URI or a file relative to the
//! `.gltf` (nothing is downloaded); each is decoded once with [`Texture::decode`] (PNG or
//! JPEG), however many materials use it. An image that cannot be read or decoded (another
//! format, a missing file, garbage) is **not** an error: the material is left without that
//! texture and the scene gets a note naming the material and the image, because one broken
//! texture should not keep a scene from rendering.
//!
//! OBJ materials (`Kd`, `Ka`, `Ks`, `Ns`, `map_Kd`, `map_d` masks, `map_Bump`) are mapped as
//! described in the `mtl` module: in short, `map_d` becomes the alpha of the base-colour
//! texture of a masked, double-sided material, and `d` / `Tr` without `map_d` are ignored.
//! An OBJ whose material library is missing, unreadable or empty loads with default
//! materials, a note and a logged warning. PLY files get one default material.
//!
//! # Cameras
//!
//! glTF: the first node, depth-first from the default scene, with a perspective camera.
//! Position = the node's world translation; forward = its world rotation · (0, 0, −1); up =
//! its world rotation · (0, 1, 0); target = position + forward × (the distance to the centre
//! of the scene's bounds, at least 1: glTF cameras have no target, and a viewer orbiting the
//! target should turn about a point at the scene's depth); `fov_y_deg` = `yfov` in degrees
//! (clamped into [`Camera::validate`]'s range); near = `znear`; far = `zfar`, or for an
//! infinite projection (no `zfar`) near + 4 × the diagonal of the scene's bounds;
//! `aspectRatio` is ignored (the output image decides). Orthographic cameras are skipped with
//! a note.
//!
//! Without a camera (and for OBJ and PLY): the default camera looks at the centre of the
//! bounds from the direction (1, 0.6, 1) (above and to the side, the usual three-quarter
//! view), at the distance where the bounding sphere fits a 60° vertical field of view with a
//! 10 % margin; near = diagonal / 1000, far = 4 × diagonal + that distance.
//!
//! # Hostile input
//!
//! Mesh files are untrusted input. The loaders never panic on bad data (a parser panic is caught
//! and reported as [`SceneError::Parse`]) and enforce the limits below so a huge or hostile file
//! fails fast with [`SceneError::TooLarge`] instead of exhausting memory. Images are held to
//! [`MAX_TEXTURE_SIDE`](crate::texture::MAX_TEXTURE_SIDE) and
//! [`MAX_TEXTURE_BYTES`](crate::texture::MAX_TEXTURE_BYTES) before they are decoded, material
//! libraries to [`MAX_MTL_BYTES`].
//!
//! [`Instance`]: crate::Instance
//! [`scatter_lights`]: crate::builtin::scatter_lights
//! [`DIRECTIONAL_CASCADES`]: crate::builtin::DIRECTIONAL_CASCADES
//! [`DIRECTIONAL_SPLIT_LAMBDA`]: crate::builtin::DIRECTIONAL_SPLIT_LAMBDA
//! [`DIRECTIONAL_SHADOW_RESOLUTION`]: crate::builtin::DIRECTIONAL_SHADOW_RESOLUTION
//! [`SPOT_SHADOW_RESOLUTION`]: crate::builtin::SPOT_SHADOW_RESOLUTION
//! [`POINT_SHADOW_RESOLUTION`]: crate::builtin::POINT_SHADOW_RESOLUTION

mod base64;
mod gltf;
mod gltf_write;
mod mtl;
pub(crate) mod normals;
mod obj;
mod ply;

use std::fs::File;
use std::path::Path;

use glam::{Mat4, Vec3};

use crate::builtin::{scatter_lights, LightMix};
use crate::{Attenuation, Camera, Instance, Light, Material, Mesh, Scene, SceneError, Texture};

pub use gltf_write::write_gltf;
pub use obj::{write_obj, MAX_MTL_BYTES};
pub use ply::write_ply_ascii;

/// Crease angle of computed normals, in degrees: where a file gives no normals, triangles
/// meeting at more than this angle keep a sharp edge between them (see
/// [`Mesh::compute_normals_with_crease`]). 60° keeps boxes flat and the 5.6° steps of a
/// 64-segment cylinder smooth.
pub const CREASE_ANGLE_DEG: f32 = 60.0;

/// Phong light colour per lux of irradiance: glTF light intensities (candela for point and
/// spot lights, lux for directional ones) times this are the renderer's diffuse and specular
/// colours (one unit of light colour is 10 lux). See the module documentation.
pub const PHONG_PER_LUX: f32 = 0.1;

/// Number of seeded lights a scene without lights gets.
pub const DEFAULT_LIGHT_COUNT: usize = 8;

/// Largest spot cone half-angle a glTF spot light maps to: just under the 89° that
/// [`Light::validate`] refuses.
const MAX_SPOT_CUTOFF_DEG: f32 = 88.99;

/// The attenuation of glTF point and spot lights: `1 / (1 + d²)`.
pub(crate) const INVERSE_SQUARE: Attenuation = Attenuation {
    constant: 1.0,
    linear: 0.0,
    quadratic: 1.0,
};

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

/// A scene read from a file, with remarks on it.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene; it has passed [`Scene::validate`].
    pub scene: Scene,
    /// One-line, human-readable remarks on what was ignored, replaced or added (lights
    /// invented for a file without any, extensions ignored, a material library that could not
    /// be read, …), in the order they arose. Empty when the file was used as it is.
    pub notes: Vec<String>,
}

/// Loads a whole scene from a mesh file, choosing the format by extension as [`load_mesh`]
/// does (`.gltf`, `.glb`, `.obj`, `.ply`, `.ply.gz`): meshes (one per glTF triangle primitive,
/// node transforms baked; one per OBJ object and material; one for PLY), one identity
/// [`Instance`] per mesh casting shadows, the file's materials and textures,
/// its lights and camera, mapped as the module documentation describes. A file without lights
/// gets [`DEFAULT_LIGHT_COUNT`] seeded ones, a file without a camera one that frames the
/// bounds; the notes say so.
///
/// Errors: those of [`load_mesh`], plus [`SceneError::Parse`] for glTF 1.0 files (with how to
/// convert them) and for glTF files requiring an unsupported extension, and the
/// [`Scene::validate`] errors (e.g. a material colour that is not finite).
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    let format = format_of(path).ok_or_else(|| SceneError::UnsupportedFormat {
        path: path.to_path_buf(),
    })?;
    check_file_size(path)?;
    catch_parser_panic(path, || {
        let parts = match format {
            Format::Obj => obj::load_scene(path)?,
            Format::Gltf => gltf::load_scene(path)?,
            Format::Ply { gzip } => {
                let meshes = ply::load(path, gzip)?;
                Parts {
                    mesh_material: vec![0; meshes.len()],
                    meshes,
                    materials: vec![Material::default()],
                    textures: Vec::new(),
                    lights: Vec::new(),
                    camera: None,
                    notes: Vec::new(),
                }
            }
        };
        assemble(path, parts)
    })
}

/// What a format's scene loader produces, before [`assemble`] makes it a [`Scene`].
pub(crate) struct Parts {
    /// Meshes in world space (node transforms baked).
    pub meshes: Vec<Mesh>,
    /// The material of each mesh (an index into `materials`).
    pub mesh_material: Vec<usize>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    /// The file's lights; empty: seeded ones are added.
    pub lights: Vec<Light>,
    /// The file's camera; `None`: the default framing.
    pub camera: Option<Camera>,
    pub notes: Vec<String>,
}

/// Checks the meshes, places them, adds default lights and camera where the file has none,
/// and validates the result.
fn assemble(path: &Path, parts: Parts) -> Result<LoadedScene, SceneError> {
    let Parts {
        meshes,
        mesh_material,
        materials,
        textures,
        lights,
        camera,
        mut notes,
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
    let instances = mesh_material
        .iter()
        .enumerate()
        .map(|(mesh, &material)| Instance::caster(mesh, material, Mat4::IDENTITY))
        .collect();
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
    };
    let bounds = scene.world_bounds(false);
    scene.camera = camera.unwrap_or_else(|| default_camera(bounds));
    if scene.lights.is_empty() {
        scene.lights = scatter_lights(&scene, DEFAULT_LIGHT_COUNT, 1, LightMix::All, None);
        let count = |t: &str| scene.lights.iter().filter(|l| l.type_name() == t).count();
        notes.push(format!(
            "the file has no lights: added {} seeded lights ({} spot, {} point, {} directional)",
            scene.lights.len(),
            count("spot"),
            count("point"),
            count("directional")
        ));
    }
    log::debug!("{}: {total} triangles", path.display());
    scene.validate()?;
    Ok(LoadedScene { scene, notes })
}

/// The union of the meshes' bounds.
pub(crate) fn bounds_of(meshes: &[Mesh]) -> Option<(Vec3, Vec3)> {
    meshes
        .iter()
        .filter_map(Mesh::bounds)
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
}

/// Centre and diagonal length of bounds (the origin and 0 without any).
pub(crate) fn centre_and_diagonal(bounds: Option<(Vec3, Vec3)>) -> (Vec3, f32) {
    bounds.map_or((Vec3::ZERO, 0.0), |(lo, hi)| {
        ((lo + hi) * 0.5, (hi - lo).length())
    })
}

/// The reach of a point or spot light of Phong colour `colour` under [`INVERSE_SQUARE`]: where
/// `max(colour) / (1 + d²)` is 1/256, clamped to 0.1 ..= 4 × the scene's diagonal.
pub(crate) fn light_range(colour: Vec3, diagonal: f32) -> f32 {
    let d = (256.0 * colour.max_element() - 1.0).max(0.0).sqrt();
    let most = (4.0 * diagonal).max(0.1);
    if d.is_nan() {
        most
    } else {
        d.clamp(0.1, most)
    }
}

/// A glTF `outerConeAngle` (radians) as a spot cutoff in degrees, within (0°, 89°).
pub(crate) fn spot_cutoff_deg(outer_rad: f32) -> f32 {
    let deg = outer_rad.to_degrees();
    if deg.is_nan() {
        45.0
    } else {
        deg.clamp(0.01, MAX_SPOT_CUTOFF_DEG)
    }
}

/// A vertical field of view clamped into what [`Camera::validate`] accepts (0.5°, 179°).
pub(crate) fn clamp_fov(deg: f32) -> f32 {
    if deg.is_nan() {
        60.0
    } else {
        deg.clamp(0.501, 178.999)
    }
}

/// The camera of a file without one: see the module documentation.
pub(crate) fn default_camera(bounds: Option<(Vec3, Vec3)>) -> Camera {
    let (centre, diagonal) = centre_and_diagonal(bounds);
    // A floor on the size, relative to how far from the origin the scene is, so that a
    // degenerate (flat or point-like) scene still gets distinct eye and target.
    let size = diagonal.max(1e-3).max(centre.abs().max_element() * 1e-5);
    let radius = 0.5 * size;
    let distance = 1.1 * radius / 30f32.to_radians().sin();
    let direction = Vec3::new(1.0, 0.6, 1.0).normalize();
    Camera {
        position: centre + direction * distance,
        target: centre,
        up: Vec3::Y,
        fov_y_deg: 60.0,
        near: size / 1000.0,
        far: 4.0 * size + distance,
    }
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

/// Installs per-vertex normals read from a file: each finite one is normalized (unless it already
/// is unit length to within 1e-5, then it is kept as it is); zero-length ones
/// are replaced by the computed (area-weighted) normal; non-finite ones are kept so that
/// [`Mesh::validate`] reports them. `None` (or a count mismatch) computes all normals with
/// the crease angle [`CREASE_ANGLE_DEG`] (which may split vertices: set texture coordinates
/// first).
fn set_normals(mesh: &mut Mesh, normals: Option<Vec<Vec3>>) {
    let Some(mut normals) = normals.filter(|n| n.len() == mesh.positions.len()) else {
        mesh.compute_normals_with_crease(CREASE_ANGLE_DEG);
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
            indices: vec![0, 2, 1],
            ..Mesh::default()
        };
        set_normals(&mut m, Some(vec![Vec3::ZERO, Vec3::Y * 3.0, Vec3::Y]));
        // Triangle (0, Z, X) winds counter-clockwise seen from +Y.
        assert_eq!(m.normals, vec![Vec3::Y, Vec3::Y, Vec3::Y]);
    }
}
