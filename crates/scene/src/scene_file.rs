//! The TOML scene format: meshes (procedural primitives or mesh files), materials, instances,
//! lights and a camera in one human-editable file. The full reference, with a worked example,
//! is `docs/SCENE_FORMAT.md`.
//!
//! Why a format of our own: benchmark scenes for many shadow-casting lights are mostly "these
//! models, placed here, lit by these N lights", which no interchange format expresses well (glTF
//! has no shadow settings, spot cones in degrees or cascades). The file is deserialized with
//! serde and `deny_unknown_fields` everywhere, so a misspelt key is an error that names the key
//! and its line instead of a silently ignored setting; names (meshes, materials) are resolved
//! with errors that name what is missing; and the built [`Scene`] must pass [`Scene::validate`].
//!
//! Scene files are treated as untrusted input: see the limits below ([`MAX_SCENE_FILE_BYTES`],
//! [`MAX_INSTANCES`], [`MAX_LIGHTS`], [`MAX_PRIMITIVE_SEGMENTS`], [`MAX_SCENE_TRIANGLES`]); mesh
//! files it references are held to the loader limits ([`crate::loaders`]).

use std::collections::HashMap;
use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use toml::Spanned;

use crate::error::SceneError;
use crate::loaders::{self, MAX_TRIANGLES};
use crate::model::{
    Attenuation, Camera, Instance, Light, LightKind, Material, Mesh, Scene, MAX_ANGULAR_SIZE_DEG,
};

use crate::primitives as prims;

/// Largest scene file accepted, in bytes (16 MiB): far more than any hand-written scene, small
/// enough that parsing cannot exhaust memory.
pub const MAX_SCENE_FILE_BYTES: u64 = 16 << 20;

/// Most `[[instance]]` entries in one scene file (100 000).
pub const MAX_INSTANCES: usize = 100_000;

/// Most `[[light]]` entries in one scene file (100 000).
pub const MAX_LIGHTS: usize = 100_000;

/// Most `[[probe]]` entries in one file (each is six faces drawn every frame something changes;
/// the renderer's own limit is the same).
pub const MAX_PROBES: usize = crate::model::Probe::MAX_COUNT;

/// Largest `segments`, `rings` or `subdivisions` of a procedural primitive (1024: about two
/// million triangles for the densest sphere or plane).
pub const MAX_PRIMITIVE_SEGMENTS: u32 = 1024;

/// Most triangles summed over all `[[mesh]]` entries of a scene (each counted once, however many
/// instances use it): the same 100 million as one loaded mesh ([`loaders::MAX_TRIANGLES`]).
pub const MAX_SCENE_TRIANGLES: usize = MAX_TRIANGLES;

/// Loads a scene file. Mesh `file` paths are relative to the scene file's directory.
///
/// Errors: [`SceneError::Io`] if it cannot be read, [`SceneError::TooLarge`] over
/// [`MAX_SCENE_FILE_BYTES`] (checked from metadata first) or another limit, and everything
/// [`parse_scene_str`] returns.
pub fn load_scene_file(path: &Path) -> Result<Scene, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    };
    let len = std::fs::metadata(path).map_err(io)?.len();
    check_file_size(path, len)?;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(MAX_SCENE_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    check_file_size(path, bytes.len() as u64)?;
    let text = String::from_utf8(bytes).map_err(|e| SceneError::Parse {
        path: path.to_path_buf(),
        reason: format!("not UTF-8 text: {e}"),
    })?;
    let base = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let default_name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "untitled".into());
    parse(&text, base, path, &default_name)
}

/// Parses scene-file text. Mesh `file` paths are relative to `base_dir`.
///
/// Errors: [`SceneError::Parse`] for malformed TOML, unknown or misplaced keys, unknown or
/// duplicate names and bad primitive parameters (the message gives the line);
/// [`SceneError::TooLarge`] for the limits; errors from [`loaders::load_mesh`] for mesh files;
/// and whatever [`Scene::validate`] finds in the result (e.g. [`SceneError::InvalidLight`] with
/// the 0-based index of the `[[light]]` entry in file order).
pub fn parse_scene_str(text: &str, base_dir: &Path) -> Result<Scene, SceneError> {
    parse(text, base_dir, Path::new("<scene text>"), "untitled")
}

fn check_file_size(path: &Path, len: u64) -> Result<(), SceneError> {
    if len > MAX_SCENE_FILE_BYTES {
        return Err(SceneError::TooLarge {
            path: path.to_path_buf(),
            reason: format!(
                "scene file is {len} bytes; the limit is {MAX_SCENE_FILE_BYTES} bytes (16 MiB)"
            ),
        });
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// The file's shape (serde).
// ---------------------------------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneDoc {
    name: Option<String>,
    camera: Option<Camera>,
    #[serde(default)]
    material: Vec<Spanned<MaterialDef>>,
    #[serde(default)]
    mesh: Vec<Spanned<MeshDef>>,
    #[serde(default)]
    instance: Vec<Spanned<InstanceDef>>,
    #[serde(default)]
    light: Vec<Spanned<LightDef>>,
    #[serde(default)]
    probe: Vec<crate::model::Probe>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialDef {
    name: String,
    ambient: Option<Vec3>,
    diffuse: Option<Vec3>,
    specular: Option<Vec3>,
    shininess: Option<f32>,
    cull_back_faces: Option<bool>,
    reflect: Option<f32>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum PrimitiveKind {
    Plane,
    Cube,
    Sphere,
    Cylinder,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDef {
    name: String,
    file: Option<String>,
    primitive: Option<PrimitiveKind>,
    size: Option<NumberOrList>,
    subdivisions: Option<u32>,
    radius: Option<f32>,
    height: Option<f32>,
    segments: Option<u32>,
    rings: Option<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InstanceDef {
    mesh: String,
    material: Option<String>,
    translate: Option<Vec3>,
    rotate_deg: Option<Vec3>,
    scale: Option<NumberOrList>,
    casts_shadows: Option<bool>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum LightType {
    Spot,
    Point,
    Directional,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightDef {
    #[serde(rename = "type")]
    kind: LightType,
    position: Option<Vec3>,
    direction: Option<Vec3>,
    cutoff_deg: Option<f32>,
    range: Option<f32>,
    cascades: Option<u32>,
    split_lambda: Option<f32>,
    cascade_resolution_scale: Option<f32>,
    ambient: Option<Vec3>,
    diffuse: Option<Vec3>,
    specular: Option<Vec3>,
    attenuation: Option<Attenuation>,
    casts_shadows: Option<bool>,
    shadow_resolution: Option<u32>,
    size: Option<f32>,
}

/// A number or an array of numbers (`scale = 2` or `scale = [1, 2, 1]`).
#[derive(Clone, Debug, PartialEq)]
enum NumberOrList {
    Number(f32),
    List(Vec<f32>),
}

impl<'de> Deserialize<'de> for NumberOrList {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = NumberOrList;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(NumberOrList::Number(v as f32))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(NumberOrList::Number(v as f32))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(NumberOrList::Number(v as f32))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some(x) = seq.next_element::<f32>()? {
                    out.push(x);
                }
                Ok(NumberOrList::List(out))
            }
        }
        d.deserialize_any(V)
    }
}

// ---------------------------------------------------------------------------------------------
// Building the scene.
// ---------------------------------------------------------------------------------------------

/// Context for error messages: the source path and the text (to turn spans into lines).
struct Ctx<'a> {
    text: &'a str,
    source: &'a Path,
    base_dir: &'a Path,
}

impl Ctx<'_> {
    fn line(&self, span: std::ops::Range<usize>) -> usize {
        let end = span.start.min(self.text.len());
        self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    }

    /// A [`SceneError::Parse`] whose message starts with the line of `span`.
    fn err(&self, span: std::ops::Range<usize>, what: impl fmt::Display) -> SceneError {
        SceneError::Parse {
            path: self.source.to_path_buf(),
            reason: format!("line {}: {what}", self.line(span)),
        }
    }

    fn too_large(&self, reason: String) -> SceneError {
        SceneError::TooLarge {
            path: self.source.to_path_buf(),
            reason,
        }
    }
}

fn parse(
    text: &str,
    base_dir: &Path,
    source: &Path,
    default_name: &str,
) -> Result<Scene, SceneError> {
    check_file_size(source, text.len() as u64)?;
    let doc: SceneDoc = toml::from_str(text).map_err(|e| SceneError::Parse {
        path: source.to_path_buf(),
        reason: e.to_string().trim_end().to_string(),
    })?;
    let cx = Ctx {
        text,
        source,
        base_dir,
    };
    if doc.instance.len() > MAX_INSTANCES {
        return Err(cx.too_large(format!(
            "{} [[instance]] entries; the limit is {MAX_INSTANCES}",
            doc.instance.len()
        )));
    }
    if doc.light.len() > MAX_LIGHTS {
        return Err(cx.too_large(format!(
            "{} [[light]] entries; the limit is {MAX_LIGHTS}",
            doc.light.len()
        )));
    }
    if doc.probe.len() > MAX_PROBES {
        return Err(cx.too_large(format!(
            "{} [[probe]] entries; the limit is {MAX_PROBES}",
            doc.probe.len()
        )));
    }

    // Materials, by name.
    let mut materials = Vec::with_capacity(doc.material.len() + 1);
    let mut material_index = HashMap::new();
    for m in &doc.material {
        let span = m.span();
        let m = m.get_ref();
        if material_index
            .insert(m.name.as_str(), materials.len())
            .is_some()
        {
            return Err(cx.err(span, format_args!("duplicate material name '{}'", m.name)));
        }
        let d = Material::default();
        materials.push(Material {
            ambient: m.ambient.unwrap_or(d.ambient),
            diffuse: m.diffuse.unwrap_or(d.diffuse),
            specular: m.specular.unwrap_or(d.specular),
            shininess: m.shininess.unwrap_or(d.shininess),
            cull_back_faces: m.cull_back_faces.unwrap_or(d.cull_back_faces),
            reflect: m.reflect.unwrap_or(d.reflect),
            ..d
        });
    }

    // Mesh names (meshes are built after every reference is known to resolve).
    let mut mesh_index = HashMap::new();
    for (i, m) in doc.mesh.iter().enumerate() {
        if mesh_index.insert(m.get_ref().name.as_str(), i).is_some() {
            return Err(cx.err(
                m.span(),
                format_args!("duplicate mesh name '{}'", m.get_ref().name),
            ));
        }
    }

    // Instances.
    let mut default_material = None;
    let mut instances = Vec::with_capacity(doc.instance.len());
    for (i, inst) in doc.instance.iter().enumerate() {
        let span = inst.span();
        let d = inst.get_ref();
        let mesh = *mesh_index.get(d.mesh.as_str()).ok_or_else(|| {
            cx.err(
                span.clone(),
                format_args!(
                    "[[instance]] {i} uses unknown mesh '{}' (defined meshes: {})",
                    d.mesh,
                    list_names(doc.mesh.iter().map(|m| m.get_ref().name.as_str()))
                ),
            )
        })?;
        let material = match &d.material {
            Some(name) => *material_index.get(name.as_str()).ok_or_else(|| {
                cx.err(
                    span.clone(),
                    format_args!(
                        "[[instance]] {i} uses unknown material '{name}' (defined materials: {})",
                        list_names(doc.material.iter().map(|m| m.get_ref().name.as_str()))
                    ),
                )
            })?,
            None => *default_material.get_or_insert_with(|| {
                materials.push(Material::default());
                materials.len() - 1
            }),
        };
        let scale = match &d.scale {
            None => Vec3::ONE,
            Some(s) => vec3_param(s).ok_or_else(|| {
                cx.err(
                    span.clone(),
                    format_args!("[[instance]] {i}: scale must be a number or [x, y, z]"),
                )
            })?,
        };
        let r = d.rotate_deg.unwrap_or(Vec3::ZERO);
        let rotation = Quat::from_rotation_z(r.z.to_radians())
            * Quat::from_rotation_y(r.y.to_radians())
            * Quat::from_rotation_x(r.x.to_radians());
        let transform = Mat4::from_translation(d.translate.unwrap_or(Vec3::ZERO))
            * Mat4::from_quat(rotation)
            * Mat4::from_scale(scale);
        instances.push(Instance {
            mesh,
            material,
            transform,
            casts_shadows: d.casts_shadows.unwrap_or(true),
        });
    }

    // Lights.
    let lights = doc
        .light
        .iter()
        .enumerate()
        .map(|(i, l)| build_light(&cx, i, l))
        .collect::<Result<Vec<_>, _>>()?;

    // Meshes (the expensive part: procedural generation and file loading).
    let mut meshes = Vec::with_capacity(doc.mesh.len());
    let mut total_triangles = 0usize;
    for m in &doc.mesh {
        let mesh = build_mesh(&cx, m)?;
        total_triangles += mesh.triangle_count();
        if total_triangles > MAX_SCENE_TRIANGLES {
            return Err(cx.too_large(format!(
                "the meshes up to '{}' have {total_triangles} triangles; the limit is \
                 {MAX_SCENE_TRIANGLES} over all [[mesh]] entries",
                mesh.name
            )));
        }
        meshes.push(mesh);
    }

    let scene = Scene {
        textures: Vec::new(),
        name: doc.name.unwrap_or_else(|| default_name.to_string()),
        meshes,
        materials,
        instances,
        lights,
        camera: doc.camera.unwrap_or_default(),
        lighting: Default::default(),
        probes: doc.probe,
        animations: Default::default(),
    };
    scene.validate()?;
    Ok(scene)
}

/// Up to 20 names, comma-separated, for "did you mean" style messages.
fn list_names<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let all: Vec<&str> = names.collect();
    if all.is_empty() {
        return "none".into();
    }
    let mut s = all
        .iter()
        .take(20)
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ");
    if all.len() > 20 {
        s.push_str(&format!(", … ({} in all)", all.len()));
    }
    s
}

/// `2` → (2, 2, 2); `[x, y, z]` → (x, y, z).
fn vec3_param(v: &NumberOrList) -> Option<Vec3> {
    match v {
        NumberOrList::Number(x) => Some(Vec3::splat(*x)),
        NumberOrList::List(l) if l.len() == 3 => Some(Vec3::new(l[0], l[1], l[2])),
        NumberOrList::List(_) => None,
    }
}

fn build_light(cx: &Ctx<'_>, i: usize, l: &Spanned<LightDef>) -> Result<Light, SceneError> {
    let span = l.span();
    let d = l.get_ref();
    let type_name = match d.kind {
        LightType::Spot => "spot",
        LightType::Point => "point",
        LightType::Directional => "directional",
    };
    let present = [
        ("position", d.position.is_some()),
        ("direction", d.direction.is_some()),
        ("cutoff_deg", d.cutoff_deg.is_some()),
        ("range", d.range.is_some()),
        ("attenuation", d.attenuation.is_some()),
        ("cascades", d.cascades.is_some()),
        ("split_lambda", d.split_lambda.is_some()),
        (
            "cascade_resolution_scale",
            d.cascade_resolution_scale.is_some(),
        ),
    ];
    let allowed: &[&str] = match d.kind {
        LightType::Spot => &[
            "position",
            "direction",
            "cutoff_deg",
            "range",
            "attenuation",
        ],
        LightType::Point => &["position", "range", "attenuation"],
        LightType::Directional => &[
            "direction",
            "cascades",
            "split_lambda",
            "cascade_resolution_scale",
        ],
    };
    for (key, is_set) in present {
        if is_set && !allowed.contains(&key) {
            return Err(cx.err(
                span,
                format_args!(
                    "[[light]] {i}: `{key}` does not apply to a {type_name} light \
                     (its keys: {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    let need = |v: Option<Vec3>, key: &str| {
        v.ok_or_else(|| {
            cx.err(
                span.clone(),
                format_args!("[[light]] {i}: a {type_name} light needs `{key}`"),
            )
        })
    };
    let need_f = |v: Option<f32>, key: &str| {
        v.ok_or_else(|| {
            cx.err(
                span.clone(),
                format_args!("[[light]] {i}: a {type_name} light needs `{key}`"),
            )
        })
    };
    // Directions are normalized; a zero or non-finite one is kept for `Scene::validate` to name.
    let unit = |v: Vec3| v.try_normalize().unwrap_or(v);
    let (kind, attenuation, default_resolution) = match d.kind {
        LightType::Spot => {
            let range = need_f(d.range, "range")?;
            (
                LightKind::Spot {
                    position: need(d.position, "position")?,
                    direction: unit(need(d.direction, "direction")?),
                    cutoff_deg: need_f(d.cutoff_deg, "cutoff_deg")?,
                    range,
                },
                d.attenuation
                    .unwrap_or_else(|| Attenuation::for_range(range)),
                1024,
            )
        }
        LightType::Point => {
            let range = need_f(d.range, "range")?;
            (
                LightKind::Point {
                    position: need(d.position, "position")?,
                    range,
                },
                d.attenuation
                    .unwrap_or_else(|| Attenuation::for_range(range)),
                1024,
            )
        }
        LightType::Directional => (
            LightKind::Directional {
                direction: unit(need(d.direction, "direction")?),
                cascades: d.cascades.unwrap_or(3),
                split_lambda: d.split_lambda.unwrap_or(0.75),
                cascade_resolution_scale: d.cascade_resolution_scale.unwrap_or(1.0),
            },
            Attenuation::NONE,
            2048,
        ),
    };
    let size = d.size.unwrap_or(0.0);
    let size_err = |what: String| cx.err(span.clone(), format_args!("[[light]] {i}: {what}"));
    if !(size.is_finite() && size >= 0.0) {
        return Err(size_err(format!(
            "`size` = {size} must be a finite number >= 0 ({}; 0 = hard shadows)",
            if d.kind == LightType::Directional {
                "an angular diameter in degrees"
            } else {
                "a radius in world units"
            }
        )));
    }
    if d.kind == LightType::Directional && size >= MAX_ANGULAR_SIZE_DEG {
        return Err(size_err(format!(
            "`size` = {size} of a directional light is an angular diameter in degrees and must \
             be below {MAX_ANGULAR_SIZE_DEG} (the sun is about 0.53)"
        )));
    }
    let diffuse = d.diffuse.unwrap_or(Vec3::ONE);
    Ok(Light {
        kind,
        ambient: d.ambient.unwrap_or(Vec3::ZERO),
        diffuse,
        specular: d.specular.unwrap_or(diffuse),
        attenuation,
        casts_shadows: d.casts_shadows.unwrap_or(true),
        shadow_resolution: d.shadow_resolution.unwrap_or(default_resolution),
        size,
    })
}

fn build_mesh(cx: &Ctx<'_>, m: &Spanned<MeshDef>) -> Result<Mesh, SceneError> {
    let span = m.span();
    let d = m.get_ref();
    let name = d.name.as_str();
    let err = |what: String| cx.err(span.clone(), format_args!("[[mesh]] '{name}': {what}"));

    let set_keys = [
        ("size", d.size.is_some()),
        ("subdivisions", d.subdivisions.is_some()),
        ("radius", d.radius.is_some()),
        ("height", d.height.is_some()),
        ("segments", d.segments.is_some()),
        ("rings", d.rings.is_some()),
    ];
    let kind = match (&d.file, d.primitive) {
        (Some(_), Some(_)) => {
            return Err(err("give either `file` or `primitive`, not both".into()))
        }
        (None, None) => return Err(err("needs `file = \"...\"` or `primitive = \"...\"`".into())),
        (Some(file), None) => {
            if let Some((key, _)) = set_keys.iter().find(|(_, set)| *set) {
                return Err(err(format!(
                    "`{key}` is a primitive parameter; it does not apply to a `file` mesh"
                )));
            }
            let mut mesh = load_merged(cx, file, name)?;
            mesh.name = name.to_string();
            return Ok(mesh);
        }
        (None, Some(kind)) => kind,
    };

    let (kind_name, allowed): (&str, &[&str]) = match kind {
        PrimitiveKind::Plane => ("plane", &["size", "subdivisions"]),
        PrimitiveKind::Cube => ("cube", &["size"]),
        PrimitiveKind::Sphere => ("sphere", &["radius", "segments", "rings"]),
        PrimitiveKind::Cylinder => ("cylinder", &["radius", "height", "segments"]),
    };
    if let Some((key, _)) = set_keys
        .iter()
        .find(|(k, set)| *set && !allowed.contains(k))
    {
        return Err(err(format!(
            "`{key}` does not apply to primitive \"{kind_name}\" (its parameters: {})",
            allowed.join(", ")
        )));
    }
    let positive = |v: Option<f32>, key: &str| -> Result<f32, SceneError> {
        let v = v.ok_or_else(|| err(format!("primitive \"{kind_name}\" needs `{key}`")))?;
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(err(format!("`{key}` = {v} must be a finite number > 0")))
        }
    };
    let count = |v: Option<u32>, key: &str, default: u32, min: u32| -> Result<u32, SceneError> {
        let v = v.unwrap_or(default);
        if (min..=MAX_PRIMITIVE_SEGMENTS).contains(&v) {
            Ok(v)
        } else {
            Err(err(format!(
                "`{key}` = {v} must be between {min} and {MAX_PRIMITIVE_SEGMENTS}"
            )))
        }
    };
    let size_of = |dims: usize| -> Result<Vec<f32>, SceneError> {
        let v = d
            .size
            .as_ref()
            .ok_or_else(|| err(format!("primitive \"{kind_name}\" needs `size`")))?;
        let list = match v {
            NumberOrList::Number(x) => vec![*x; dims],
            NumberOrList::List(l) if l.len() == dims => l.clone(),
            NumberOrList::List(l) => {
                return Err(err(format!(
                    "`size` has {} numbers; \"{kind_name}\" takes a number or {dims}",
                    l.len()
                )))
            }
        };
        for &x in &list {
            positive(Some(x), "size")?;
        }
        Ok(list)
    };

    let mut mesh = match kind {
        PrimitiveKind::Plane => {
            let s = size_of(2)?;
            prims::plane(s[0], s[1], count(d.subdivisions, "subdivisions", 1, 1)?)
        }
        PrimitiveKind::Cube => {
            let s = size_of(3)?;
            prims::cuboid(Vec3::new(s[0], s[1], s[2]))
        }
        PrimitiveKind::Sphere => prims::uv_sphere(
            positive(d.radius, "radius")?,
            count(d.segments, "segments", 32, 3)?,
            count(d.rings, "rings", 16, 2)?,
        ),
        PrimitiveKind::Cylinder => prims::cylinder(
            positive(d.radius, "radius")?,
            positive(d.height, "height")?,
            count(d.segments, "segments", 32, 3)?,
        ),
    };
    mesh.name = name.to_string();
    Ok(mesh)
}

/// Loads a mesh file (relative to the scene's directory) and merges all its meshes into one.
fn load_merged(cx: &Ctx<'_>, file: &str, name: &str) -> Result<Mesh, SceneError> {
    let path: PathBuf = cx.base_dir.join(file);
    let parts = loaders::load_mesh(&path)?;
    let mut out = Mesh {
        name: name.to_string(),
        ..Mesh::default()
    };
    for p in parts {
        let offset = u32::try_from(out.positions.len())
            .ok()
            .filter(|o| (*o as u64) + (p.positions.len() as u64) <= u32::MAX as u64 + 1)
            .ok_or_else(|| SceneError::TooLarge {
                path: path.clone(),
                reason: "too many vertices for 32-bit indices once its meshes are merged".into(),
            })?;
        if !p.uvs.is_empty() || !out.uvs.is_empty() {
            out.uvs.resize(out.positions.len(), glam::Vec2::ZERO);
            if p.uvs.is_empty() {
                out.uvs
                    .resize(out.positions.len() + p.positions.len(), glam::Vec2::ZERO);
            } else {
                out.uvs.extend_from_slice(&p.uvs);
            }
        }
        out.positions.extend_from_slice(&p.positions);
        out.normals.extend_from_slice(&p.normals);
        out.indices.extend(p.indices.iter().map(|i| i + offset));
        loaders::common::check_triangles(&path, out.triangle_count())?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_or_list_parses_both_forms() {
        #[derive(Deserialize)]
        struct T {
            a: NumberOrList,
            b: NumberOrList,
        }
        let t: T = toml::from_str("a = 2\nb = [1, 2.5, 3]").unwrap();
        assert_eq!(t.a, NumberOrList::Number(2.0));
        assert_eq!(t.b, NumberOrList::List(vec![1.0, 2.5, 3.0]));
        assert!(toml::from_str::<T>("a = \"x\"\nb = 1").is_err());
    }
}
