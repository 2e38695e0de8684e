//! The defaults of a model file that brings less than a whole scene: the camera that frames a
//! file without one, and the ground plane under a model without a floor (rules in the module
//! documentation of [`super`] and in `docs/real-content.md`).

use glam::{Mat4, Vec3};

use super::common::{centre_and_diagonal, DEFAULT_LIGHT_COUNT, PHONG_PER_LUX};
use super::options::Ground;
use crate::builtin::lights::{directional, point, Tone};
use crate::look::Lighting;
use crate::model::{Camera, Instance, Light, LightKind, Material, Scene};

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

/// The coloured point lights of the default rig, around the model.
const RIG_POINTS: usize = DEFAULT_LIGHT_COUNT - 3;

/// The light rig of a file without lights, placed for `camera` around `bounds`: a studio's
/// three-point lighting plus coloured accents, every light outside the model.
///
/// - **key**: a directional light from the camera's left, 45° above the view's horizontal
///   direction, warm white, brightness 0.9, casting shadows (onto the ground plane behind the
///   model and to its right, where the camera sees them);
/// - **fill**: from the camera's right and lower (about 15°), cool, 0.35, no shadows, so that
///   the key's shadowed side is not black;
/// - **rim**: from behind and above, white, 0.6, casting shadows: it outlines the silhouette;
/// - **accents**: [`RIG_POINTS`] shadow-casting point lights evenly around the model at 0.8
///   diagonals from its centre (outside its bounds, whose half-diagonal is 0.5) and 0.1 to 0.4
///   diagonals above it, in muted colours, each lighting the model's centre to 0.25.
///
/// Brightnesses are Phong units (what a white surface facing the light shows); in a physical
/// scene each directional light gives 10 lux per unit and each point light the candela that
/// give 10 lux per unit at the model's centre, so the rig looks the same at any model scale.
pub(crate) fn default_rig(
    bounds: Option<(Vec3, Vec3)>,
    camera: &Camera,
    lighting: Lighting,
) -> Vec<Light> {
    let (centre, diagonal) = centre_and_diagonal(bounds);
    let size = diagonal.max(1e-3);
    // The view's horizontal direction from the model towards the camera, and its right.
    let mut back = camera.position - camera.target;
    back.y = 0.0;
    let back = back.try_normalize().unwrap_or(Vec3::Z);
    let right = Vec3::Y.cross(back);
    let sun = |from: Vec3, colour: Vec3, brightness: f32, shadows: bool| {
        let mut l = directional(
            -from.normalize(),
            Tone {
                color: colour,
                brightness,
            },
            None,
        );
        l.casts_shadows = shadows;
        l
    };
    let mut lights = vec![
        sun(
            back - right + Vec3::Y * 1.41,
            Vec3::new(1.0, 0.95, 0.88),
            0.9,
            true,
        ),
        sun(
            back + right * 1.2 + Vec3::Y * 0.42,
            Vec3::new(0.82, 0.9, 1.0),
            0.35,
            false,
        ),
        sun(-back + right * 0.3 + Vec3::Y * 1.0, Vec3::ONE, 0.6, true),
    ];
    const ACCENTS: [Vec3; RIG_POINTS] = [
        Vec3::new(1.0, 0.72, 0.45),
        Vec3::new(0.55, 0.75, 1.0),
        Vec3::new(1.0, 0.55, 0.65),
        Vec3::new(0.6, 1.0, 0.75),
        Vec3::new(0.85, 0.7, 1.0),
    ];
    for (i, colour) in ACCENTS.iter().enumerate() {
        let angle = std::f32::consts::TAU * (i as f32 + 0.25) / RIG_POINTS as f32;
        let height = size * (0.1 + 0.3 * i as f32 / (RIG_POINTS - 1) as f32);
        let position =
            centre + (back * angle.cos() + right * angle.sin()) * (0.8 * size) + Vec3::Y * height;
        let key = position.distance(centre);
        let tone = Tone {
            color: *colour,
            brightness: 0.25,
        };
        lights.push(point(position, 2.5 * key, key, tone, None));
    }
    if lighting == Lighting::Physical {
        for l in &mut lights {
            // Directional: 10 lx per unit. Point: 10 lx per unit at the model's centre.
            let scale = match l.kind {
                LightKind::Point { position, .. } => {
                    position.distance_squared(centre)
                        * l.attenuation.factor(position.distance(centre))
                }
                _ => 1.0,
            } / PHONG_PER_LUX;
            l.ambient = Vec3::ZERO;
            l.diffuse *= scale;
            l.specular = l.diffuse;
        }
    }
    lights
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

/// Replaces the lights of a scene read from a file (a model or a TOML scene) with the seeded
/// layout of [`scatter_lights`](crate::builtin::scatter_lights), as `--lights N` does: in a
/// glTF file's physical units (10 cd or lx per unit of the layout's colours) where the scene
/// is lit physically. Errors: more than [`MAX_LIGHTS`](crate::builtin::MAX_LIGHTS).
pub fn seed_lights(
    scene: &mut Scene,
    n: usize,
    seed: u64,
    mix: crate::builtin::LightMix,
    shadow_resolution: Option<u32>,
) -> Result<(), crate::error::SceneError> {
    crate::builtin::check_light_count(n)?;
    scene.lights = seeded_layout(scene, n, seed, mix, shadow_resolution);
    Ok(())
}

/// Adds the seeded layout of `n` lights to the scene's own (a model's lights, or the rig the
/// loader gave it), as `--add-lights N` does: the same layout and units as [`seed_lights`]'s,
/// placed around the scene's geometry. Errors: more than
/// [`MAX_LIGHTS`](crate::builtin::MAX_LIGHTS) in all.
pub fn add_seeded_lights(
    scene: &mut Scene,
    n: usize,
    seed: u64,
    mix: crate::builtin::LightMix,
    shadow_resolution: Option<u32>,
) -> Result<(), crate::error::SceneError> {
    let own = scene.lights.len();
    crate::builtin::check_light_count(own.saturating_add(n)).map_err(|_| {
        crate::error::SceneError::InvalidRequest(format!(
            "{own} lights of the scene's own and {n} added are more than the supported {}",
            crate::builtin::MAX_LIGHTS
        ))
    })?;
    let added = seeded_layout(scene, n, seed, mix, shadow_resolution);
    scene.lights.extend(added);
    Ok(())
}

/// `n` lights of the seeded layout around `scene`, in its light units.
fn seeded_layout(
    scene: &Scene,
    n: usize,
    seed: u64,
    mix: crate::builtin::LightMix,
    shadow_resolution: Option<u32>,
) -> Vec<Light> {
    let mut lights = crate::builtin::scatter_lights(scene, n, seed, mix, shadow_resolution);
    if scene.lighting == Lighting::Physical {
        let k = 1.0 / PHONG_PER_LUX;
        for l in &mut lights {
            l.ambient *= k;
            l.diffuse *= k;
            l.specular *= k;
        }
    }
    lights
}
