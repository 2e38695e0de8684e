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
//! # glTF lights (`KHR_lights_punctual`) → physical lights
//!
//! glTF lights are physical: candela (lm/sr) for point and spot lights, lux (lm/m²) for
//! directional ones, falling off with the inverse square of distance. A loaded glTF scene is
//! [`Lighting::Physical`](crate::Lighting): its lights keep those units and the renderer
//! shades it with the glTF BRDF through an exposure (see `manyshadows_render::Look`). The
//! mapping:
//!
//! - diffuse = specular = `color × intensity` (candela or lux); ambient = 0 (the file's
//!   lights add no ambient term);
//! - point and spot attenuation = `1 / (1 + d²)` (the Phong model's inverse square, kept
//!   finite at the light); shaded physically, the falloff is glTF's instead:
//!   `window(d / range) / max(d², 0.01)`;
//! - range = the light's `range` if the file gives one, else the distance at which a Phong
//!   light of a tenth of the intensity, `max(colour × PHONG_PER_LUX) / (1 + d²)`, falls to
//!   1/256 ([`PHONG_PER_LUX`] = 0.1: one Phong unit is 10 cd), at least 0.1 and at most 4 ×
//!   the diagonal of the scene's bounds;
//! - position = the node's world translation; direction (spot, directional) = the node's
//!   world rotation applied to (0, 0, −1);
//! - spot `cutoff_deg` = `outerConeAngle` in degrees (glTF's default π/4), clamped into
//!   (0°, 89°) (at most 88.99°, as [`Light::validate`] requires); `innerConeAngle` is ignored:
//!   this renderer's spot lights have a hard cone edge;
//! - directional lights get [`DIRECTIONAL_CASCADES`] cascades, split blend
//!   [`DIRECTIONAL_SPLIT_LAMBDA`], every cascade at [`DIRECTIONAL_SHADOW_RESOLUTION`]
//!   (`cascade_resolution_scale` 1); spot and point lights [`SPOT_SHADOW_RESOLUTION`] and
//!   [`POINT_SHADOW_RESOLUTION`]; every light casts shadows. A light of zero intensity or colour
//!   is kept (it adds nothing);
//! - size: `KHR_lights_punctual` lights are punctual, so a loaded light is a point (size 0,
//!   hard shadows: the file looks as its author made it) unless the light's `extras` give
//!   [`GLTF_SIZE_EXTRA`] (`"extras": { "manyshadows_size": 0.1 }`: a radius in world units for
//!   point and spot lights, an angular diameter in degrees for directional ones, as
//!   [`Light::size`](crate::Light::size)); a value that is not a number, negative, or
//!   (directional) 30° or more is ignored with a note.
//!
//! A file with no lights (and every OBJ and PLY file) gets the seeded layout
//! [`scatter_lights`]`(scene, 8, seed 1, LightMix::All, None)` (whose lights have the built-in
//! default sizes, [`crate::light_size`]) and a note saying so; in a glTF scene their Phong
//! colours are turned into candela and lux (× 10, 1 / [`PHONG_PER_LUX`]).
//! [`write_gltf`] writes the inverse mapping (`intensity = max(diffuse)` for a physical
//! scene, `max(diffuse) / PHONG_PER_LUX` for a Phong one; `color = diffuse / max(diffuse)`, a
//! size above 0 as [`GLTF_SIZE_EXTRA`]), so a written light loads back with the same colours
//! (ten times a Phong scene's), range, cone, direction and size; a light's ambient
//! colour, a specular colour different from its
//! diffuse one and its attenuation are not representable in glTF and come back as above.
//!
//! # glTF materials → materials
//!
//! - `metallicFactor` and `roughnessFactor` → [`Material::pbr`] (the glTF BRDF's parameters;
//!   the Phong terms below are what `--shading phong` shows);
//! - `emissiveFactor` × `KHR_materials_emissive_strength` → [`Material::emissive`];
//! - `baseColorFactor` rgb → `diffuse` and `ambient`; its alpha → `base_alpha`;
//! - specular = `mix(0.04, base rgb, metallic)` per channel (dielectrics reflect about 4 %
//!   white, metals their own colour);
//! - shininess = `2/α² − 2` with `α = roughness²` (the Blinn-Phong exponent whose highlight
//!   matches GGX of that α), clamped to 1..=512;
//! - `baseColorTexture` → `base_color_texture`, `normalTexture` → `normal_texture`, each with
//!   its sampler's `wrapS` / `wrapT`; texture-coordinate set 0 is always used (a texture that
//!   names another set gets a note); metallic-roughness, occlusion and emissive textures are
//!   not used (their factors are);
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
//! [`Light`]: crate::Light
//! [`scatter_lights`]: crate::builtin::scatter_lights
//! [`DIRECTIONAL_CASCADES`]: crate::builtin::DIRECTIONAL_CASCADES
//! [`DIRECTIONAL_SPLIT_LAMBDA`]: crate::builtin::DIRECTIONAL_SPLIT_LAMBDA
//! [`DIRECTIONAL_SHADOW_RESOLUTION`]: crate::builtin::DIRECTIONAL_SHADOW_RESOLUTION
//! [`SPOT_SHADOW_RESOLUTION`]: crate::builtin::SPOT_SHADOW_RESOLUTION
//! [`POINT_SHADOW_RESOLUTION`]: crate::builtin::POINT_SHADOW_RESOLUTION

mod base64;
pub(crate) mod common;
mod gltf;
mod gltf_geometry;
mod gltf_lights_camera;
mod gltf_materials;
mod gltf_open;
mod gltf_write;
mod mtl;
mod obj;
mod ply;

use std::path::Path;

use glam::Mat4;

use crate::builtin::{scatter_lights, LightMix};
use crate::error::SceneError;
use crate::look::Lighting;
use crate::model::{Camera, Instance, Material, Mesh, Scene};

use common::{check_file_size, check_triangles, default_camera, parse_error, Parts};
pub use common::{
    CREASE_ANGLE_DEG, DEFAULT_LIGHT_COUNT, GLTF_SIZE_EXTRA, MAX_DECOMPRESSED_BYTES, MAX_FILE_BYTES,
    MAX_TRIANGLES, PHONG_PER_LUX,
};
pub use gltf_write::write_gltf;
pub use obj::{write_obj, MAX_MTL_BYTES};
pub use ply::write_ply_ascii;

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
        let mut lighting = Lighting::Phong;
        let parts = match format {
            Format::Obj => obj::load_scene(path)?,
            Format::Gltf => {
                lighting = Lighting::Physical;
                gltf::load_scene(path)?
            }
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
        assemble(path, parts, lighting)
    })
}

/// Checks the meshes, places them, adds default lights and camera where the file has none,
/// and validates the result.
fn assemble(path: &Path, parts: Parts, lighting: Lighting) -> Result<LoadedScene, SceneError> {
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
        lighting,
    };
    let bounds = scene.world_bounds(false);
    scene.camera = camera.unwrap_or_else(|| default_camera(bounds));
    if scene.lights.is_empty() {
        scene.lights = scatter_lights(&scene, DEFAULT_LIGHT_COUNT, 1, LightMix::All, None);
        if lighting == Lighting::Physical {
            // The seeded lights are in Phong units: 10 cd (or lx) each.
            for l in &mut scene.lights {
                l.ambient /= PHONG_PER_LUX;
                l.diffuse /= PHONG_PER_LUX;
                l.specular /= PHONG_PER_LUX;
            }
        }
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
    use super::common::*;
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
