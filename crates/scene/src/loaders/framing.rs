//! The defaults of a model file that brings less than a whole scene: the camera that frames a
//! file without one, and the ground plane under a model without a floor (rules in the module
//! documentation of [`super`] and in `docs/real-content.md`).

use glam::{Mat4, Vec3};

use super::common::centre_and_diagonal;
use super::options::Ground;
use crate::model::{Camera, Instance, Material, Scene};

/// Vertical field of view of the framing camera, in degrees.
const FRAMING_FOV_DEG: f32 = 60.0;

/// Room left around the model by the framing camera: its bounds fill 1/1.05 of the frame's
/// height (or of its width, if that is what limits).
const FRAMING_MARGIN: f32 = 1.05;

/// The side of the ground plane, in diagonals of the model's bounds: wide enough for the
/// shadows of lights that stand low beside the model.
const GROUND_SIDE_DIAGONALS: f32 = 3.0;

/// How far below the model's lowest point the ground lies, in diagonals: enough that a flat
/// underside does not fight it for depth.
const GROUND_GAP_DIAGONALS: f32 = 1e-3;

/// A floor: the upward (or downward) facing triangles at the bottom of the bounds cover at
/// least this share of the bounds' footprint.
const FLOOR_COVER: f32 = 0.25;

/// Triangles whose unit normal has |y| above this are horizontal.
const HORIZONTAL_Y: f32 = 0.95;

/// The camera of a file without one: from the direction (1, 0.6, 1) (above and to the side,
/// the usual three-quarter view) towards the centre of `bounds`, at the nearest distance at
/// which all eight corners of the bounds lie inside a 60° field of view both vertically and
/// horizontally (so any frame at least as wide as it is high shows the whole model, and the
/// model fills the frame's height or, for a wide model, its width), with a 5 % margin.
/// near = diagonal / 1000, far = 4 × diagonal + that distance.
pub(crate) fn default_camera(bounds: Option<(Vec3, Vec3)>) -> Camera {
    let (centre, diagonal) = centre_and_diagonal(bounds);
    // A floor on the size, relative to how far from the origin the scene is, so that a
    // degenerate (flat or point-like) scene still gets distinct eye and target.
    let size = diagonal.max(1e-3).max(centre.abs().max_element() * 1e-5);
    let back = Vec3::new(1.0, 0.6, 1.0).normalize(); // from the target towards the eye
    let right = Vec3::Y.cross(back).normalize();
    let up = back.cross(right);
    let tan_half = (0.5 * FRAMING_FOV_DEG).to_radians().tan();
    let (lo, hi) = bounds.unwrap_or((centre, centre));
    let mut distance: f32 = 0.0;
    for i in 0..8 {
        let corner = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        ) - centre;
        // The corner's depth in front of an eye at `centre + back × d` is d − corner·back; it
        // is in view when its offsets from the axis are within tan_half × that depth.
        let spread = corner.dot(up).abs().max(corner.dot(right).abs());
        distance = distance.max(corner.dot(back) + FRAMING_MARGIN * spread / tan_half);
    }
    // At least past the nearest corner, and never zero for a point-like model.
    let distance = distance.max(0.5 * size).max(size * 1e-3);
    Camera {
        position: centre + back * distance,
        target: centre,
        up: Vec3::Y,
        fov_y_deg: FRAMING_FOV_DEG,
        near: size / 1000.0,
        far: 4.0 * size + distance,
    }
}

/// Whether the scene has a floor of its own: its horizontal triangles within the lowest 2 % of
/// the bounds' height (at least a thousandth of the diagonal) cover at least a quarter of the
/// bounds' footprint (the X-Z rectangle), counted by their area seen from above.
pub(crate) fn has_floor(scene: &Scene) -> bool {
    let Some((lo, hi)) = scene.world_bounds(false) else {
        return false;
    };
    let extent = hi - lo;
    let footprint = extent.x * extent.z;
    if footprint.is_nan() || footprint <= 0.0 {
        return false;
    }
    let tolerance = (0.02 * extent.y).max(1e-3 * extent.length());
    let top = lo.y + tolerance;
    let mut covered = 0.0f32;
    for inst in &scene.instances {
        let Some(mesh) = scene.meshes.get(inst.mesh) else {
            continue;
        };
        let world: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|&p| inst.transform.transform_point3(p))
            .collect();
        for t in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| world[t[k] as usize]);
            if a.y.max(b.y).max(c.y) > top {
                continue;
            }
            let n = (b - a).cross(c - a);
            let len = n.length();
            if len > 0.0 && (n.y / len).abs() > HORIZONTAL_Y {
                covered += 0.5 * n.y.abs();
            }
        }
        if covered >= FLOOR_COVER * footprint {
            return true;
        }
    }
    covered >= FLOOR_COVER * footprint
}

/// Adds the ground plane `ground` asks for (for [`Ground::Auto`], only if the scene has no
/// floor): a square of [`GROUND_SIDE_DIAGONALS`] diagonals, facing +Y, centred under the
/// bounds just below their lowest point, light grey, receiving shadows but casting none.
/// Returns the note that says so.
pub(crate) fn add_ground(scene: &mut Scene, ground: Ground) -> Option<String> {
    let why = match ground {
        Ground::Off => return None,
        Ground::On => "asked for",
        Ground::Auto if has_floor(scene) => return None,
        Ground::Auto => "the model has no floor",
    };
    let (lo, hi) = scene.world_bounds(false)?;
    let diagonal = (hi - lo).length().max(1e-3);
    let side = GROUND_SIDE_DIAGONALS * diagonal;
    let y = lo.y - GROUND_GAP_DIAGONALS * diagonal;
    let centre = Vec3::new(0.5 * (lo.x + hi.x), y, 0.5 * (lo.z + hi.z));
    let mut mesh = crate::primitives::plane(side, side, 1);
    mesh.name = "ground".into();
    let grey = Vec3::splat(0.7);
    scene.materials.push(Material {
        ambient: grey,
        diffuse: grey,
        specular: Vec3::splat(0.04),
        shininess: 8.0,
        ..Material::default()
    });
    scene.meshes.push(mesh);
    scene.instances.push(Instance {
        mesh: scene.meshes.len() - 1,
        material: scene.materials.len() - 1,
        transform: Mat4::from_translation(centre),
        casts_shadows: false,
    });
    Some(format!(
        "{why}: added a ground plane, a {side:.3} × {side:.3} square at y = {y:.4} under it \
         (catching shadows; --ground off leaves it out)"
    ))
}
