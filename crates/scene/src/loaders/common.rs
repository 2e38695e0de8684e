//! What the loaders share: limits, the conversions from a file's lights and cameras, the
//! parts a loader returns, error constructors and size checks, and baking a transform into a
//! mesh. The loaders and their dispatch (`dispatch.rs`) import these from here.

use std::path::Path;

use crate::animation::Animations;
use glam::{Mat3, Mat4, Vec3};

use crate::error::SceneError;
use crate::model::{Attenuation, Camera, Light, Material, Mesh};
use crate::texture::Texture;

/// Crease angle of computed normals, in degrees: where a file gives no normals, triangles
/// meeting at more than this angle keep a sharp edge between them (see
/// [`Mesh::compute_normals_with_crease`]). 60° keeps boxes flat and the 5.6° steps of a
/// 64-segment cylinder smooth.
pub const CREASE_ANGLE_DEG: f32 = 60.0;

/// Phong light colour per lux of irradiance: glTF light intensities (candela for point and
/// spot lights, lux for directional ones) times this are the renderer's diffuse and specular
/// colours (one unit of light colour is 10 lux). See the module documentation.
pub const PHONG_PER_LUX: f32 = 0.1;

/// The glTF extension that scales a material's emissive factor past 1.
pub(crate) const EMISSIVE_STRENGTH: &str = "KHR_materials_emissive_strength";

/// The key in a glTF light's `extras` that holds its [`Light::size`], which
/// `KHR_lights_punctual` has no field for: `"extras": { "manyshadows_size": 0.1 }` on the
/// light's entry in the extension's `lights` array, in the units of [`Light::size`] (a radius
/// in world units for point and spot lights, unaffected by node scale like `range`; an angular
/// diameter in degrees for directional ones). Without it a loaded light is a point (size 0),
/// so a file looks as its author made it.
pub const GLTF_SIZE_EXTRA: &str = "manyshadows_size";

/// Number of lights a model file without lights gets: the default rig's key, fill and rim
/// directional lights and its coloured point lights (`default_rig` in framing.rs).
pub const DEFAULT_LIGHT_COUNT: usize = 8;

/// Largest spot cone half-angle a glTF spot light maps to: just under the 89° that
/// [`Light::validate`] refuses.
pub(crate) const MAX_SPOT_CUTOFF_DEG: f32 = 88.99;

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

/// What a format's scene loader produces, before [`assemble`] makes it a [`Scene`].
pub(crate) struct Parts {
    /// Meshes in world space (node transforms baked).
    pub meshes: Vec<Mesh>,
    /// The material of each mesh (an index into `materials`).
    pub mesh_material: Vec<usize>,
    /// The placements of each mesh: one instance per transform (the identity for a mesh whose
    /// node transform is baked in; one per instance of an `EXT_mesh_gpu_instancing` node).
    pub transforms: Vec<Vec<Mat4>>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    /// The file's lights; empty: the default rig is added.
    pub lights: Vec<Light>,
    /// The file's camera; `None`: the default framing.
    pub camera: Option<Camera>,
    pub notes: Vec<String>,
    /// The node each mesh is drawn at, for animation (empty: a format without nodes).
    pub mesh_nodes: Vec<Option<usize>>,
    /// The file's node tree and clips ([`Animations::moving`] is filled when the instances
    /// are made).
    pub animations: Animations,
}

/// A primitive's vertices as a file stores them (before any transform), its triangles as a
/// list: what the glTF accessor reader and the Draco decoder hand to the same finishing.
pub(crate) struct RawTriangles {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    /// Empty: no texture coordinates.
    pub uvs: Vec<glam::Vec2>,
    pub indices: Vec<u32>,
}

/// The union of the bounds of every placement of every mesh (`transforms[i]` places mesh `i`).
pub(crate) fn bounds_of_placed(meshes: &[Mesh], transforms: &[Vec<Mat4>]) -> Option<(Vec3, Vec3)> {
    let mut out: Option<(Vec3, Vec3)> = None;
    for (m, placed) in meshes.iter().zip(transforms) {
        let Some((lo, hi)) = m.bounds() else {
            continue;
        };
        for t in placed {
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                let p = t.transform_point3(corner);
                out = Some(out.map_or((p, p), |(a, b)| (a.min(p), b.max(p))));
            }
        }
    }
    out
}

/// `mesh` with `transform` baked into its positions and normals (normals by the inverse
/// transpose, renormalised): a mirroring transform swaps two corners of every triangle so the
/// winding stays counter-clockwise, a singular one (which flattens the mesh) gets its normals
/// computed again from what is left.
pub(crate) fn bake(mesh: &Mesh, transform: Mat4) -> Mesh {
    let mut out = mesh.clone();
    for p in &mut out.positions {
        *p = transform.transform_point3(*p);
    }
    let linear = Mat3::from_mat4(transform);
    let det = linear.determinant();
    if det < 0.0 {
        for t in out.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    if det.is_finite() && det.abs() > 1e-30 {
        let normal_matrix = linear.inverse().transpose();
        for n in &mut out.normals {
            *n = (normal_matrix * *n).try_normalize().unwrap_or(*n);
        }
    } else {
        out.compute_normals_with_crease(CREASE_ANGLE_DEG);
    }
    out
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
    let len = super::files::len(path).map_err(|e| io_error(path, e))?;
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
pub(crate) fn open_limited(
    path: &Path,
) -> Result<std::io::Take<Box<dyn std::io::Read>>, SceneError> {
    use std::io::Read;
    let file = super::files::open(path).map_err(|e| io_error(path, e))?;
    Ok(file.take(MAX_FILE_BYTES + 1))
}

/// Reads a whole file (size-checked) into memory.
pub(crate) fn read_limited(path: &Path) -> Result<Vec<u8>, SceneError> {
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
pub(crate) fn set_normals(mesh: &mut Mesh, normals: Option<Vec<Vec3>>) {
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
pub(crate) fn mesh_name(path: &Path, inner: Option<&str>) -> String {
    let file = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    match inner {
        Some(s) if !s.trim().is_empty() => format!("{file}/{}", s.trim()),
        _ => file,
    }
}

/// Fails with [`SceneError::InvalidMesh`] naming the mesh and the first vertex (numbered as
/// the file stores them, before any transform or normal computation) whose position or
/// normal is not finite (NaN or infinite): such a vertex would poison bounds, normals and
/// every shadow map it is drawn into.
pub(crate) fn check_finite(
    mesh: &str,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
) -> Result<(), SceneError> {
    let bad = |reason: String| SceneError::InvalidMesh {
        mesh: mesh.to_string(),
        reason,
    };
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(bad(format!(
            "vertex {i} has a non-finite position {}: the file is damaged (fix or re-export it)",
            positions[i]
        )));
    }
    if let Some(i) = normals.and_then(|n| n.iter().position(|n| !n.is_finite())) {
        let n = normals.map_or(Vec3::ZERO, |n| n[i]);
        return Err(bad(format!(
            "vertex {i} has a non-finite normal {n}: the file is damaged (fix or re-export it, \
             or leave its normals out to have them computed)"
        )));
    }
    Ok(())
}
