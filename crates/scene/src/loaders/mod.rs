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
//!   [`Instance`] transforms, not with a node hierarchy), except that an
//!   `EXT_mesh_gpu_instancing` node's mesh stays in its own coordinates with one instance per
//!   instance;
//! - positions and normals are checked finite right after reading (an error naming the mesh
//!   and the vertex as the file numbers them), and every returned mesh has passed
//!   [`Mesh::validate`] (and every [`load_scene`] result [`Scene::validate`]), so NaNs and
//!   out-of-range indices become a [`SceneError`] here instead of a GPU fault later.
//!
//! [`load_mesh`] reads geometry only (the TOML scene format and benchmarks place meshes
//! themselves). [`load_scene`] reads a whole scene: one [`Mesh`] per glTF triangle primitive
//! or OBJ (object, material), one identity [`Instance`] per mesh (casting shadows; one per
//! instance for instanced glTF nodes), the file's materials, textures, lights and camera, and
//! one-line notes on whatever it had to ignore, replace or invent, each said once (the CLI
//! prints them; nothing is logged beside a note). [`load_scene_with`] and [`load_mesh_with`]
//! take [`LoadOptions`]: whether the file may read outside its folder, and the ground plane.
//!
//! # Paths a file may read
//!
//! Every path a file names (glTF buffer and image URIs, OBJ `mtllib`, MTL texture statements)
//! must resolve inside the model file's folder or below: an absolute path, a `..` that climbs
//! above the folder and a symbolic link that leads out are refused, naming the path and
//! `--allow-outside-paths` ([`LoadOptions::allow_outside_paths`] lets them through). A glTF
//! buffer outside is an error; an image, material library or texture outside is left out with
//! a note, as a missing one is. Nothing is ever downloaded.
//!
//! # Text and names
//!
//! OBJ and MTL lines that are not UTF-8 are read as Latin-1; a `newmtl` / `usemtl` without a
//! name names the material "(unnamed)" on both sides; MTL statements `tobj` would refuse
//! (a texture statement without a file, a colour with fewer than three numbers) are mended or
//! dropped. A glTF scene without `nodes` is an empty scene.
//!
//! # glTF lights (`KHR_lights_punctual`) → physical lights
//!
//! glTF lights are physical: candela (lm/sr) for point and spot lights, lux (lm/m²) for
//! directional ones, falling off with the inverse square of distance. A loaded glTF scene is
//! [`Lighting::Physical`](crate::Lighting): its lights keep those units and the renderer
//! shades it with the glTF BRDF through an exposure (see `manyshadows::Look`). The
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
//! A file with no lights (and every OBJ and PLY file) gets a light rig placed for its camera
//! around its bounds (`default_rig` in framing.rs: key, fill and rim directional lights and
//! coloured point lights outside the model, with the built-in default sizes,
//! [`crate::light_size`]) and a note saying so; in a glTF scene their Phong colours are
//! turned into lux (directional: × 10, 1 / [`PHONG_PER_LUX`]) and into the candela that give
//! as much at the model's centre (point).
//! [`write_gltf`] writes the inverse mapping (`intensity = max(diffuse)` for a physical
//! scene, `max(diffuse) / PHONG_PER_LUX` for a Phong one; `color = diffuse / max(diffuse)`, a
//! size above 0 as [`GLTF_SIZE_EXTRA`]), so a written light loads back with the same colours
//! (ten times a Phong scene's), range, cone, direction and size; a light's ambient
//! colour, a specular colour different from its
//! diffuse one and its attenuation are not representable in glTF and come back as above.
//!
//! # glTF materials → materials
//!
//! - `metallicFactor` and `roughnessFactor` → [`Material::pbr`](crate::Material::pbr) (the glTF BRDF's parameters;
//!   the Phong terms below are what `--shading phong` shows);
//! - `emissiveFactor` × `KHR_materials_emissive_strength` → [`Material::emissive`](crate::Material::emissive);
//! - `baseColorFactor` rgb → `diffuse` and `ambient`; its alpha → `base_alpha`;
//! - specular = `mix(0.04, base rgb, metallic)` per channel (dielectrics reflect about 4 %
//!   white, metals their own colour);
//! - shininess = `2/α² − 2` with `α = roughness²` (the Blinn-Phong exponent whose highlight
//!   matches GGX of that α), clamped to 1..=512;
//! - `baseColorTexture` → `base_color_texture`, `normalTexture` → `normal_texture`,
//!   `metallicRoughnessTexture` → `metallic_roughness_texture`, `emissiveTexture` →
//!   `emissive_texture` (for a material that emits), each with its sampler's `wrapS` /
//!   `wrapT`; texture-coordinate set 0 is always used (a texture that names another set gets a
//!   note); occlusion textures are not used (occlusion scales indirect light, which punctual
//!   lights do not give);
//! - `KHR_texture_transform` (offset, rotation, scale) is baked into the texture coordinates
//!   of the material's meshes: the base-colour texture's transform, or the normal texture's
//!   where there is no base colour (all of a material's textures are sampled with one set of
//!   coordinates; a normal texture with a different transform gets a note);
//! - `alphaMode`, `alphaCutoff` (default 0.5) and `doubleSided` are copied;
//! - primitives without a material get [`Material::default`].
//!
//! # glTF extensions
//!
//! Read: `KHR_lights_punctual`, `KHR_texture_transform`, `EXT_mesh_gpu_instancing`,
//! `KHR_draco_mesh_compression` (decoded with `draco-core`), `EXT_meshopt_compression`
//! (decoded with meshoptimizer; not in the browser build) and `KHR_mesh_quantization`
//! (integer positions, normals and texture coordinates). Every other extension the file
//! uses (listed in `extensionsUsed` or found in an `extensions` object) gets exactly one
//! note naming it and what uses it. A file that *requires* one of them still loads if it is
//! a `KHR_materials_*` extension (the note says it is required); any other unsupported
//! requirement (compressed textures: KTX2 / BasisU, WebP) is refused with a
//! [`SceneError::Parse`] naming it.
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
//! materials and a note. PLY files get one default material.
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
//! Without a camera (and for OBJ and PLY): the framing camera looks at the centre of the
//! bounds from the direction (1, 0.6, 1) (above and to the side, the usual three-quarter
//! view), at the nearest distance where all eight corners of the bounds fit a 60° field of
//! view vertically and horizontally with a 5 % margin (the model fills any frame at least as
//! wide as it is high); near = diagonal / 1000, far = 4 × diagonal + that distance.
//!
//! # The ground plane
//!
//! With [`Ground::On`], or [`Ground::Auto`] for a model without a floor, [`load_scene_with`]
//! adds a ground plane after the lights and camera: a square of 3 × the bounds' diagonal,
//! facing +Y (the scene's up), centred under the bounds a thousandth of the diagonal below
//! their lowest point, light grey, receiving shadows and casting none, with a note. A model
//! has a floor when its horizontal triangles (|normal.y| > 0.95) within the lowest 2 % of the
//! bounds' height cover at least a quarter of the bounds' X-Z footprint, seen from above.
//! [`LoadOptions::default`] is [`Ground::Off`]; the CLI's `--ground` is `auto`.
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
//! [`Instance`]: crate::model::Instance
//! [`Light`]: crate::model::Light
//! [`Mesh`]: crate::model::Mesh
//! [`Material`]: crate::model::Material
//! [`Camera`]: crate::model::Camera
//! [`Light::validate`]: crate::model::Light::validate
//! [`Camera::validate`]: crate::model::Camera::validate
//! [`Scene::validate`]: crate::model::Scene::validate
//! [`Mesh::validate`]: crate::model::Mesh::validate
//! [`Mesh::compute_normals_with_crease`]: crate::model::Mesh::compute_normals_with_crease
//! [`Material::default`]: crate::model::Material
//! [`SceneError`]: crate::error::SceneError
//! [`SceneError::Parse`]: crate::error::SceneError::Parse
//! [`SceneError::TooLarge`]: crate::error::SceneError::TooLarge
//! [`Texture::decode`]: crate::texture::Texture::decode
//! [`load_scene`]: dispatch::load_scene
//! [`load_mesh`]: dispatch::load_mesh
//! [`load_scene_with`]: dispatch::load_scene_with
//! [`load_mesh_with`]: dispatch::load_mesh_with
//! [`LoadOptions`]: options::LoadOptions
//! [`LoadOptions::allow_outside_paths`]: options::LoadOptions::allow_outside_paths
//! [`LoadOptions::default`]: options::LoadOptions
//! [`Ground::On`]: options::Ground::On
//! [`Ground::Auto`]: options::Ground::Auto
//! [`Ground::Off`]: options::Ground::Off
//! [`write_gltf`]: gltf_write::write_gltf
//! [`CREASE_ANGLE_DEG`]: common::CREASE_ANGLE_DEG
//! [`PHONG_PER_LUX`]: common::PHONG_PER_LUX
//! [`GLTF_SIZE_EXTRA`]: common::GLTF_SIZE_EXTRA
//! [`MAX_MTL_BYTES`]: obj::MAX_MTL_BYTES
//! [`scatter_lights`]: crate::builtin::scatter_lights
//! [`DIRECTIONAL_CASCADES`]: crate::builtin::DIRECTIONAL_CASCADES
//! [`DIRECTIONAL_SPLIT_LAMBDA`]: crate::builtin::DIRECTIONAL_SPLIT_LAMBDA
//! [`DIRECTIONAL_SHADOW_RESOLUTION`]: crate::builtin::DIRECTIONAL_SHADOW_RESOLUTION
//! [`SPOT_SHADOW_RESOLUTION`]: crate::builtin::SPOT_SHADOW_RESOLUTION
//! [`POINT_SHADOW_RESOLUTION`]: crate::builtin::POINT_SHADOW_RESOLUTION

mod base64;
pub(crate) mod common;
mod dispatch;
mod files;
mod framing;
mod gltf;
mod gltf_accessors;
mod gltf_animation;
mod gltf_draco;
mod gltf_extensions;
mod gltf_geometry;
mod gltf_instancing;
mod gltf_lights_camera;
mod gltf_materials;
mod gltf_meshopt;
mod gltf_open;
mod gltf_write;
mod mtl;
mod obj;
mod obj_text;
pub(crate) mod options;
mod paths;
mod ply;
mod zip_files;

pub use common::{
    CREASE_ANGLE_DEG, DEFAULT_LIGHT_COUNT, GLTF_SIZE_EXTRA, MAX_DECOMPRESSED_BYTES, MAX_FILE_BYTES,
    MAX_TRIANGLES, PHONG_PER_LUX,
};
pub use dispatch::{
    load_mesh, load_mesh_with, load_scene, load_scene_from_memory, load_scene_with, LoadedScene,
};
pub use files::MemoryFiles;
pub use framing::{add_seeded_lights, seed_lights};
pub use gltf_write::write_gltf;
pub use obj::{write_obj, MAX_MTL_BYTES};
pub use options::{Ground, LoadOptions};
pub use ply::write_ply_ascii;
pub use zip_files::MAX_ZIP_ENTRIES;
