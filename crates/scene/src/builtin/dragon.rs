//! The `dragon` scene: seed 000's benchmark, one model on a floor ringed by shadow-casting
//! lights.
//!
//! Why: seed 000 times layered shadow-map generation on the Stanford dragon (35,577
//! triangles) lit by a growing number of lights. This scene reproduces that setup: the model
//! (`opts.mesh`, normalised to stand [`DRAGON_HEIGHT`] m tall at the origin) or, when none is
//! given, a procedural stand-in of the same size class ([`dragon_stand_in`]: a bumpy trefoil
//! knot tube, 35,580 triangles, which shadows itself and has real concavities), on a 20 × 20 m
//! floor, with `n` lights evenly spaced on a ring ([`RING_RADIUS`], [`RING_HEIGHT`]) all aimed
//! at the model. The ring is exactly `n` spots unless the mix is `point` or `directional`,
//! which puts that type on the ring instead. The seed only turns the ring and varies colours.

use std::f32::consts::{PI, TAU};

use glam::{Mat4, Quat, Vec2, Vec3};

use super::lights::LightCounts;
use super::lights::{self, tint, Rand, Tone};
use super::options::{BuiltinOptions, LightMix};
use crate::error::SceneError;
use crate::model::{Camera, Instance, Light, Material, Mesh, Scene};
use crate::primitives;

/// Height the model is scaled to (metres).
pub const DRAGON_HEIGHT: f32 = 2.0;
/// Edge length of the square floor.
pub const DRAGON_FLOOR_SIZE: f32 = 20.0;
/// Radius of the light ring around the model's vertical axis.
pub const RING_RADIUS: f32 = 5.0;
/// Height of the light ring above the floor.
pub const RING_HEIGHT: f32 = 3.5;
/// The point every ring light aims at (the model's middle).
pub const RING_TARGET: Vec3 = Vec3::new(0.0, 1.0, 0.0);
/// Spot cone half-angle of the ring lights (covers the model and its shadow).
pub const RING_SPOT_CUTOFF_DEG: f32 = 35.0;
/// Range of the ring's spot and point lights.
pub const RING_RANGE: f32 = 16.0;
/// Default number of ring lights.
pub const DEFAULT_RING_LIGHTS: usize = 8;
/// Camera distance from [`RING_TARGET`], looking down at 45°.
pub const DRAGON_CAMERA_DISTANCE: f32 = 6.0;

/// The procedural stand-in for the Stanford dragon: a (2, 3) torus knot tube with bumps (a
/// ridge of "scales" along its back), 593 × 30 quads = 35,580 triangles (the seed's dragon has
/// 35,577), standing up and tilted so every light of the ring sees crossings that shadow other
/// parts of it. Not yet normalised: the scene scales it with [`normalising_transform`] like any other
/// model.
pub fn dragon_stand_in() -> Mesh {
    const SEGMENTS: u32 = 593;
    const SIDES: u32 = 30;
    let curve = primitives::torus_knot_curve(2, 3, 1.0, SEGMENTS);
    let n = curve.len();
    let mut mesh = primitives::tube(&curve, SIDES, |k, angle| {
        let t = TAU * k as f32 / n as f32;
        // Scales: a bumpy pattern along the curve, a ridge on one side of the tube.
        let scales = 0.06 * (37.0 * t).sin() * (3.0 * angle).cos();
        let ridge = 0.12 * angle.cos().max(0.0).powi(6) * (0.5 + 0.5 * (74.0 * t).sin());
        0.2 * (1.0 + scales + ridge)
    });
    // Stand it up (knot plane vertical) and tilt it so no ring light sees it edge-on.
    let rotation = Quat::from_rotation_y(0.35) * Quat::from_rotation_x(PI / 2.0 - 0.5);
    mesh = primitives::merge(&[(mesh, Mat4::from_quat(rotation))]);
    mesh.name = "dragon-stand-in".into();
    mesh
}

/// The transform that puts `mesh` on the floor: centred on the Y axis (by its bounds), its
/// lowest point at `y = 0`, uniformly scaled to [`DRAGON_HEIGHT`] tall (or to that size in its
/// largest dimension if it is flat).
pub fn normalising_transform(mesh: &Mesh) -> Result<Mat4, SceneError> {
    let (lo, hi) = mesh.bounds().ok_or_else(|| SceneError::InvalidMesh {
        mesh: mesh.name.clone(),
        reason: "the mesh has no vertices".into(),
    })?;
    let size = hi - lo;
    let reference = if size.y > 1e-3 * size.max_element() {
        size.y
    } else {
        size.max_element()
    };
    if !(reference.is_finite() && reference > 0.0) {
        return Err(SceneError::InvalidMesh {
            mesh: mesh.name.clone(),
            reason: "the mesh has no extent (all vertices coincide)".into(),
        });
    }
    let scale = DRAGON_HEIGHT / reference;
    let center = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    Ok(Mat4::from_scale(Vec3::splat(scale)) * Mat4::from_translation(-center))
}

/// The ring of `n` lights of `mix`'s type (spots for `all` and `spot`).
pub fn ring_lights(
    n: usize,
    seed: u64,
    mix: LightMix,
    shadow_resolution: Option<u32>,
) -> Vec<Light> {
    let mut rng = Rand::new(seed, 0xd2a9);
    let phase = rng.range(0.0, TAU);
    // All ring lights overlap on the model and the floor around it: share the brightness.
    let brightness = (1.6 / n.max(1) as f32).min(0.7);
    (0..n)
        .map(|k| {
            let a = phase + TAU * k as f32 / n as f32;
            let position = Vec3::new(RING_RADIUS * a.cos(), RING_HEIGHT, RING_RADIUS * a.sin());
            let to_target = RING_TARGET - position;
            let key = to_target.length();
            let color = tint(&mut rng);
            match mix {
                LightMix::All | LightMix::Spot => lights::spot(
                    position,
                    to_target,
                    RING_SPOT_CUTOFF_DEG,
                    RING_RANGE,
                    key,
                    Tone { color, brightness },
                    shadow_resolution,
                ),
                LightMix::Point => lights::point(
                    position,
                    RING_RANGE,
                    key,
                    Tone { color, brightness },
                    shadow_resolution,
                ),
                LightMix::Directional => lights::directional(
                    to_target,
                    Tone {
                        color,
                        brightness: (1.5 / n as f32).min(0.7),
                    },
                    shadow_resolution,
                ),
            }
        })
        .collect()
}

/// Up to [`lights::LOCAL_LAYOUT_ABOVE`] lights: the ring ([`ring_lights`]). Above (except
/// for directional lights, which stay a ring of suns): a ring of [`DEFAULT_RING_LIGHTS`] and
/// every further light a local light over the floor, kept out of the model's box.
fn dragon_lights(
    n: usize,
    seed: u64,
    mix: LightMix,
    shadow_resolution: Option<u32>,
    obstacles: &[(Vec3, Vec3)],
) -> Vec<Light> {
    if n <= lights::LOCAL_LAYOUT_ABOVE || mix == LightMix::Directional {
        return ring_lights(n, seed, mix, shadow_resolution);
    }
    let mut out = ring_lights(DEFAULT_RING_LIGHTS, seed, mix, shadow_resolution);
    let local = n - DEFAULT_RING_LIGHTS;
    let (spots, points) = match mix {
        LightMix::Spot => (local, 0),
        LightMix::Point => (0, local),
        _ => {
            let c = LightCounts::split(local, LightMix::All);
            (c.spot + c.directional, c.point)
        }
    };
    let half = 0.5 * DRAGON_FLOOR_SIZE - 0.5;
    let floor = lights::Floor {
        lo: Vec2::splat(-half),
        hi: Vec2::splat(half),
    };
    let mut rng = Rand::new(seed, 0xd2aa);
    out.extend(lights::local(
        spots,
        points,
        &[floor],
        &|_, _| 0.0,
        obstacles,
        &mut rng,
        lights::LOCAL_BRIGHTNESS,
        shadow_resolution,
    ));
    out
}

/// Builds `dragon`.
pub(crate) fn build(opts: &BuiltinOptions) -> Result<Scene, SceneError> {
    let model = match &opts.mesh {
        Some(mesh) => {
            let mut mesh = mesh.clone();
            if mesh.normals.len() != mesh.positions.len() {
                mesh.compute_normals();
            }
            mesh.validate()?;
            mesh
        }
        None => dragon_stand_in(),
    };
    let transform = normalising_transform(&model)?;
    let mut floor = primitives::plane(DRAGON_FLOOR_SIZE, DRAGON_FLOOR_SIZE, 8);
    floor.name = "floor".into();
    let n = opts.lights.unwrap_or(DEFAULT_RING_LIGHTS);
    let dir = Vec3::new(0.0, 1.0, 1.0).normalize();
    let mut camera = Camera::look_at(RING_TARGET + dir * DRAGON_CAMERA_DISTANCE, RING_TARGET);
    camera.far = 60.0;
    let obstacles = lights::instance_boxes(
        std::slice::from_ref(&model),
        &[Instance::caster(0, 0, transform)],
    );
    Ok(Scene {
        textures: Vec::new(),
        name: "dragon".into(),
        meshes: vec![floor, model],
        materials: vec![
            Material::matte(Vec3::splat(0.75)),
            Material {
                specular: Vec3::splat(0.35),
                shininess: 24.0,
                ..Material::matte(Vec3::new(0.55, 0.7, 0.45))
            },
        ],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 1, transform),
        ],
        lights: dragon_lights(n, opts.seed, opts.mix, opts.shadow_resolution, &obstacles),
        camera,
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    })
}
