//! glTF lights (`KHR_lights_punctual`) and the camera, placed by the world transforms of their
//! nodes, into this crate's Phong [`Light`]s and [`Camera`], with the mappings documented in
//! [`super`]. Both are read from the JSON structs rather than through the `gltf` crate's
//! wrappers, which unwrap fields that validation does not require.

use std::path::Path;

use ::gltf::json::validation::Checked;
use glam::{Mat4, Vec3};

use super::common::{parse_error, GLTF_SIZE_EXTRA, PHONG_PER_LUX};
use super::gltf_open::Opened;
use crate::builtin::{
    DIRECTIONAL_CASCADES, DIRECTIONAL_SHADOW_RESOLUTION, DIRECTIONAL_SPLIT_LAMBDA,
    POINT_SHADOW_RESOLUTION, SPOT_SHADOW_RESOLUTION,
};
use crate::error::SceneError;
use crate::model::{Attenuation, Camera, Light, LightKind, MAX_ANGULAR_SIZE_DEG};

/// The direction a node's local −Z points in world space (lights and cameras look down −Z).
fn forward_of(world: &Mat4) -> Option<Vec3> {
    world.transform_vector3(Vec3::NEG_Z).try_normalize()
}

pub(super) fn read_lights(
    path: &Path,
    opened: &Opened,
    nodes: &[(::gltf::Node<'_>, Mat4)],
    bounds: Option<(Vec3, Vec3)>,
    notes: &mut Vec<String>,
) -> Result<Vec<Light>, SceneError> {
    use ::gltf::json::extensions::scene::khr_lights_punctual::Type;
    let root = opened.document.as_json();
    let Some(defs) = root
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map(|l| &l.lights)
    else {
        return Ok(Vec::new());
    };
    let diagonal = bounds.map_or(0.0, |(lo, hi)| (hi - lo).length());
    let mut lights = Vec::new();
    for (node, world) in nodes {
        let Some(index) = root
            .nodes
            .get(node.index())
            .and_then(|n| n.extensions.as_ref())
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map(|l| l.light.value())
        else {
            continue;
        };
        let Some(def) = defs.get(index) else {
            continue;
        };
        let name = def.name.clone().unwrap_or_else(|| format!("light {index}"));
        // Physical units (candela, lux): the scene is `Lighting::Physical`.
        let colour = Vec3::from(def.color).max(Vec3::ZERO) * def.intensity.max(0.0);
        // The reach where a file gives none: as far as a Phong light of a tenth of the
        // intensity reaches (one Phong unit is 10 cd), the range the loader always gave.
        let phong = colour * PHONG_PER_LUX;
        if !colour.is_finite() {
            return Err(parse_error(
                path,
                format!("glTF light '{name}': colour × intensity is not a finite number"),
            ));
        }
        let Checked::Valid(ty) = def.type_ else {
            continue; // validation refuses unknown types; nothing to do
        };
        let position = world.w_axis.truncate();
        let range = match def.range {
            _ if ty == Type::Directional => 0.0, // unused
            Some(r) if r.is_finite() && r > 0.0 => r,
            Some(r) => {
                notes.push(format!(
                    "light '{name}': range {r} is not a positive number: computed from its \
                     intensity instead"
                ));
                super::common::light_range(phong, diagonal)
            }
            None => super::common::light_range(phong, diagonal),
        };
        let kind = match ty {
            Type::Point => LightKind::Point { position, range },
            Type::Spot | Type::Directional => {
                let Some(direction) = forward_of(world) else {
                    notes.push(format!(
                        "light '{name}' (node {}): its node's transform has no direction: skipped",
                        node.index()
                    ));
                    continue;
                };
                if ty == Type::Directional {
                    LightKind::Directional {
                        direction,
                        cascades: DIRECTIONAL_CASCADES,
                        split_lambda: DIRECTIONAL_SPLIT_LAMBDA,
                        cascade_resolution_scale: 1.0,
                    }
                } else {
                    let outer = def
                        .spot
                        .as_ref()
                        .map_or(std::f32::consts::FRAC_PI_4, |s| s.outer_cone_angle);
                    LightKind::Spot {
                        position,
                        direction,
                        cutoff_deg: super::common::spot_cutoff_deg(outer),
                        range,
                    }
                }
            }
        };
        if !position.is_finite() {
            return Err(parse_error(
                path,
                format!("glTF light '{name}': its node's position is not finite"),
            ));
        }
        let (attenuation, shadow_resolution) = match kind {
            LightKind::Directional { .. } => (Attenuation::NONE, DIRECTIONAL_SHADOW_RESOLUTION),
            LightKind::Spot { .. } => (super::common::INVERSE_SQUARE, SPOT_SHADOW_RESOLUTION),
            LightKind::Point { .. } => (super::common::INVERSE_SQUARE, POINT_SHADOW_RESOLUTION),
        };
        lights.push(Light {
            kind,
            ambient: Vec3::ZERO,
            diffuse: colour,
            specular: colour,
            attenuation,
            casts_shadows: true,
            shadow_resolution,
            size: size_from_extras(&opened.json, index, &name, &kind, notes),
        });
    }
    Ok(lights)
}

/// The size in the `extras` of light `index` of the file's `KHR_lights_punctual` list
/// ([`GLTF_SIZE_EXTRA`]); 0 (a point) without one, and with a note for a value that is not a
/// size a light of `kind` can have.
fn size_from_extras(
    json: &serde_json::Value,
    index: usize,
    name: &str,
    kind: &LightKind,
    notes: &mut Vec<String>,
) -> f32 {
    let pointer =
        format!("/extensions/KHR_lights_punctual/lights/{index}/extras/{GLTF_SIZE_EXTRA}");
    let Some(value) = json.pointer(&pointer) else {
        return 0.0;
    };
    let directional = matches!(kind, LightKind::Directional { .. });
    match value.as_f64().map(|v| v as f32) {
        Some(s) if s.is_finite() && s >= 0.0 && !(directional && s >= MAX_ANGULAR_SIZE_DEG) => s,
        _ => {
            notes.push(format!(
                "light '{name}': extras.{GLTF_SIZE_EXTRA} = {value} is not {}: ignored, the \
                 light is a point (hard shadows)",
                if directional {
                    format!("an angular diameter in degrees, >= 0 and below {MAX_ANGULAR_SIZE_DEG}")
                } else {
                    "a radius >= 0 in world units".to_string()
                }
            ));
            0.0
        }
    }
}

pub(super) fn read_camera(
    opened: &Opened,
    nodes: &[(::gltf::Node<'_>, Mat4)],
    bounds: Option<(Vec3, Vec3)>,
    notes: &mut Vec<String>,
) -> Option<Camera> {
    use ::gltf::json::camera::Type;
    let root = opened.document.as_json();
    let mut skipped = Vec::new();
    let mut found = None;
    for (node, world) in nodes {
        let Some(index) = root
            .nodes
            .get(node.index())
            .and_then(|n| n.camera.as_ref())
            .map(|c| c.value())
        else {
            continue;
        };
        let Some(def) = root.cameras.get(index) else {
            continue;
        };
        let name = def
            .name
            .clone()
            .unwrap_or_else(|| format!("camera {index}"));
        let perspective = match (&def.type_, &def.perspective) {
            (Checked::Valid(Type::Perspective), Some(p)) => p,
            _ => {
                skipped.push(format!(
                    "camera '{name}' is orthographic, which this renderer does not support"
                ));
                continue;
            }
        };
        match camera_from_node(perspective, world, bounds) {
            Ok(c) => {
                found = Some((c, name));
                break;
            }
            Err(reason) => skipped.push(format!("camera '{name}': {reason}")),
        }
    }
    let outcome = match &found {
        Some((_, name)) => format!("skipped (camera '{name}' is used)"),
        None => "the default camera is used".to_string(),
    };
    notes.extend(skipped.into_iter().map(|s| format!("{s}: {outcome}")));
    found.map(|(c, _)| c)
}

fn camera_from_node(
    p: &::gltf::json::camera::Perspective,
    world: &Mat4,
    bounds: Option<(Vec3, Vec3)>,
) -> Result<Camera, String> {
    let position = world.w_axis.truncate();
    let forward = forward_of(world);
    let up = world.transform_vector3(Vec3::Y).try_normalize();
    let (Some(forward), Some(up)) = (forward, up) else {
        return Err("its node's transform is degenerate".into());
    };
    if !position.is_finite() || forward.cross(up).length_squared() < 1e-6 {
        return Err("its node's transform is degenerate".into());
    }
    let (centre, diagonal) = super::common::centre_and_diagonal(bounds);
    let distance = (centre - position)
        .length()
        .max(1.0)
        .max(position.abs().max_element() * 1e-4);
    let near = if p.znear.is_finite() && p.znear > 0.0 {
        p.znear
    } else {
        return Err(format!("znear {} is not a positive number", p.znear));
    };
    let far = match p.zfar {
        Some(f) if f.is_finite() && f > near => f,
        _ => near + 4.0 * diagonal.max(near),
    };
    Ok(Camera {
        position,
        target: position + forward * distance,
        up,
        fov_y_deg: super::common::clamp_fov(p.yfov.to_degrees()),
        near,
        far,
    })
}
