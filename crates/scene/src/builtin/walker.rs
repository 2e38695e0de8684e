//! `walker`: one skinned figure walking across a floor, for the histories that must follow
//! bent surfaces (the denoiser's and the reservoirs': `bench denoise --scene walker
//! --animation walk`). The figure is one mesh of tubes (torso, head, arms, legs) skinned to
//! eight joints: the pelvis, which carries it forward at 1.4 m/s, two hips and two knees (a
//! leg bends at its knee, its vertices blended over 0.2 m), and two shoulders. Its one clip,
//! "walk", is two strides in 2 s (LINEAR keys every 1/8 s): hips swing ±25°, knees bend 5° to
//! 45°, arms swing ±20° against the legs. It walks from x = −1.4 m to +1.4 m.

use glam::{Mat4, Quat, Vec3, Vec4};

use super::lights;
use super::options::BuiltinOptions;
use crate::animation::{Animations, Channel, Clip, Interpolation, Node, Property, Skin};
use crate::model::{Camera, Instance, Material, Mesh, Scene};
use crate::primitives::plane;

/// Where the pelvis starts (x) and how fast it goes (m/s).
const START_X: f32 = -1.4;
const SPEED: f32 = 1.4;

/// The pelvis's height at rest.
const PELVIS_Y: f32 = 0.95;

/// The clip's length in seconds (two strides of 1 s each).
pub const DURATION: f32 = 2.0;

/// A vertical tube of 12 sides around the axis through `x, z`, between heights `y0` and `y1`
/// in `rings` rings, radius `r`, capped at both ends (the caps' rims share the side's
/// vertices, so their normals are the side's); appended to `mesh`, each vertex weighted by
/// `weights(y)` (joint indices into the skin, weights).
#[allow(clippy::too_many_arguments)]
fn tube(
    mesh: &mut Mesh,
    skin: &mut (Vec<[u16; 4]>, Vec<[f32; 4]>),
    (x, z): (f32, f32),
    (y0, y1): (f32, f32),
    r: f32,
    rings: u32,
    weights: impl Fn(f32) -> ([u16; 4], [f32; 4]),
) {
    let sides = 12u32;
    // Built upwards whichever way it was asked, so that its faces wind outwards.
    let (y0, y1) = (y0.min(y1), y0.max(y1));
    let first = mesh.positions.len() as u32;
    let mut push = |p: Vec3, n: Vec3| {
        mesh.positions.push(p);
        mesh.normals.push(n);
        let (j, w) = weights(p.y);
        skin.0.push(j);
        skin.1.push(w);
    };
    for k in 0..=rings {
        let y = y0 + (y1 - y0) * k as f32 / rings as f32;
        for s in 0..sides {
            let a = s as f32 / sides as f32 * std::f32::consts::TAU;
            let n = Vec3::new(a.cos(), 0.0, -a.sin());
            push(Vec3::new(x, y, z) + r * n, n);
        }
    }
    // The caps' centres.
    push(Vec3::new(x, y0, z), -Vec3::Y);
    push(Vec3::new(x, y1, z), Vec3::Y);
    let (c0, c1) = (first + (rings + 1) * sides, first + (rings + 1) * sides + 1);
    for k in 0..rings {
        for s in 0..sides {
            let a = first + k * sides + s;
            let b = first + k * sides + (s + 1) % sides;
            mesh.indices
                .extend([a, b, b + sides, a, b + sides, a + sides]);
        }
    }
    let last = first + rings * sides;
    for s in 0..sides {
        let (a, b) = (s, (s + 1) % sides);
        mesh.indices.extend([c0, first + b, first + a]);
        mesh.indices.extend([c1, last + a, last + b]);
    }
}

/// The built-in `walker`, with the seeded lights `opts` asks for (16 by default).
pub fn build(opts: &BuiltinOptions) -> Scene {
    // Joints (nodes): 0 pelvis, 1 left hip, 2 left knee, 3 right hip, 4 right knee, 5 left
    // shoulder, 6 right shoulder. The left side is −z; the figure faces +x.
    let at_rest = [
        Vec3::new(START_X, PELVIS_Y, 0.0),
        Vec3::new(START_X, PELVIS_Y, -0.12),
        Vec3::new(START_X, 0.5, -0.12),
        Vec3::new(START_X, PELVIS_Y, 0.12),
        Vec3::new(START_X, 0.5, 0.12),
        Vec3::new(START_X, 1.5, -0.24),
        Vec3::new(START_X, 1.5, 0.24),
    ];
    let parents = [None, Some(0), Some(1), Some(0), Some(3), Some(0), Some(0)];
    let mut anim = Animations::default();
    for (k, (&p, parent)) in at_rest.iter().zip(parents).enumerate() {
        let local = match parent {
            Some(q) => p - at_rest[q],
            None => p,
        };
        debug_assert_eq!(anim.nodes.len(), k);
        anim.nodes.push(Node {
            parent,
            rest: Mat4::from_translation(local),
            translation: local,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        });
    }
    let mut mesh = Mesh {
        name: "walker".into(),
        ..Default::default()
    };
    let mut weights = (Vec::new(), Vec::new());
    let only = |j: u16| move |_y: f32| ([j, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]);
    let x = START_X;
    tube(
        &mut mesh,
        &mut weights,
        (x, 0.0),
        (0.88, 1.55),
        0.16,
        6,
        only(0),
    );
    tube(
        &mut mesh,
        &mut weights,
        (x, 0.0),
        (1.6, 1.85),
        0.1,
        2,
        only(0),
    );
    for (hip, knee, z) in [(1u16, 2u16, -0.12f32), (3, 4, 0.12)] {
        // The knee takes the leg over 0.2 m round it.
        let leg = move |y: f32| {
            let w = ((0.6 - y) / 0.2).clamp(0.0, 1.0);
            ([hip, knee, 0, 0], [1.0 - w, w, 0.0, 0.0])
        };
        tube(
            &mut mesh,
            &mut weights,
            (x, z),
            (PELVIS_Y, 0.04),
            0.07,
            12,
            leg,
        );
    }
    for (shoulder, z) in [(5u16, -0.24f32), (6, 0.24)] {
        tube(
            &mut mesh,
            &mut weights,
            (x, z),
            (1.5, 0.85),
            0.045,
            6,
            only(shoulder),
        );
    }
    // Keys every 1/8 s over the clip; phase 0: left leg at the middle of its forward swing.
    let keys = (DURATION * 8.0) as usize;
    let times: Vec<f32> = (0..=keys).map(|k| k as f32 / 8.0).collect();
    let turn = |deg: f32| Vec4::from(Quat::from_rotation_z(deg.to_radians()));
    let swing = |t: f32, phase: f32| (std::f32::consts::TAU * t + phase).sin();
    let mut channels = vec![Channel {
        node: 0,
        property: Property::Translation,
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: times
            .iter()
            .map(|&t| Vec4::new(START_X + SPEED * t, PELVIS_Y, 0.0, 0.0))
            .collect(),
    }];
    let rotation = |node: usize, deg: &dyn Fn(f32) -> f32| Channel {
        node,
        property: Property::Rotation,
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: times.iter().map(|&t| turn(deg(t))).collect(),
    };
    let pi = std::f32::consts::PI;
    for (hip, knee, phase) in [(1, 2, 0.0), (3, 4, pi)] {
        channels.push(rotation(hip, &|t| 25.0 * swing(t, phase)));
        // The knee bends most as the leg swings through (a negative turn takes the foot back).
        channels.push(rotation(knee, &|t| {
            -(25.0 + 20.0 * swing(t, phase + pi / 2.0))
        }));
    }
    for (shoulder, phase) in [(5, pi), (6, 0.0)] {
        channels.push(rotation(shoulder, &|t| 20.0 * swing(t, phase)));
    }
    anim.skins.push(Skin {
        mesh: 1,
        joints: (0..at_rest.len()).collect(),
        inverse_bind: at_rest
            .iter()
            .map(|&p| Mat4::from_translation(-p))
            .collect(),
        vertex_joints: weights.0,
        vertex_weights: weights.1,
        extra_joints: Vec::new(),
        extra_weights: Vec::new(),
        bind_positions: mesh.positions.clone(),
        bind_normals: mesh.normals.clone(),
    });
    anim.clips.push(Clip {
        name: "walk".into(),
        channels,
        weights: Vec::new(),
    });
    let floor = plane(10.0, 6.0, 1);
    let materials = vec![
        Material {
            diffuse: Vec3::splat(0.7),
            ..Material::default()
        },
        Material {
            diffuse: Vec3::new(0.3, 0.5, 0.8),
            ..Material::default()
        },
    ];
    let mut scene = Scene {
        name: "walker".into(),
        meshes: vec![floor, mesh],
        materials,
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 1, Mat4::IDENTITY),
        ],
        camera: Camera::look_at(Vec3::new(0.4, 1.5, 3.3), Vec3::new(0.0, 0.8, 0.0)),
        animations: anim,
        ..Default::default()
    };
    scene.camera.far = 40.0;
    scene.lights = lights::scatter(
        &scene,
        opts.lights.unwrap_or(16),
        opts.seed,
        opts.mix,
        opts.shadow_resolution,
    );
    scene
}
