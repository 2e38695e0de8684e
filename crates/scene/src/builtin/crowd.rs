//! `crowd`: a skinned crowd for animation. A grid of tubes, 2 m tall, each skinned to two
//! joints (its base and its middle) and swaying at its middle, every tube about its own axis,
//! over a floor: the moving, deforming content that caching, virtual pages and ray tracing's
//! rebuilt structures must follow (`bench animation`). Its one clip, "sway", turns
//! each upper joint by 0, +35°, 0, −35°, 0 at 0, 0.5, 1, 1.5 and 2 s (LINEAR).
//!
//! Each tube is a mesh of its own (a skin bends one mesh), with vertices in world coordinates
//! at rest; [`build_with`] makes any number of them ([`DEFAULT_COUNT`] for the built-in scene).

use glam::{Mat4, Quat, Vec3, Vec4};

use super::lights;
use super::options::BuiltinOptions;
use crate::animation::{Animations, Channel, Clip, Interpolation, Node, Property, Skin};
use crate::model::{Camera, Instance, Material, Mesh, Scene};
use crate::primitives::plane;

/// Tubes of the built-in `crowd`.
pub const DEFAULT_COUNT: usize = 64;

/// Most tubes [`build_with`] makes.
pub const MAX_COUNT: usize = 4096;

/// Metres between neighbouring tubes.
const SPACING: f32 = 1.5;

/// A tube standing at `base` (radius 0.2, height 2, rings every 0.25 m, 12 sides, open ends),
/// and each vertex's weight on the upper joint: 0 below 0.5 m, 1 above 1.5 m, linear between.
fn tube(base: Vec3) -> (Mesh, Vec<f32>) {
    let (rings, sides) = (9u32, 12u32);
    let mut mesh = Mesh {
        name: "crowd tube".into(),
        ..Default::default()
    };
    let mut upper = Vec::new();
    for r in 0..rings {
        let y = r as f32 * 0.25;
        for k in 0..sides {
            let a = k as f32 / sides as f32 * std::f32::consts::TAU;
            let n = Vec3::new(a.cos(), 0.0, -a.sin());
            mesh.positions.push(base + Vec3::new(0.0, y, 0.0) + 0.2 * n);
            mesh.normals.push(n);
            upper.push((y - 0.5).clamp(0.0, 1.0));
        }
    }
    for r in 0..rings - 1 {
        for k in 0..sides {
            let (a, b) = (r * sides + k, r * sides + (k + 1) % sides);
            mesh.indices
                .extend([a, b, b + sides, a, b + sides, a + sides]);
        }
    }
    (mesh, upper)
}

/// The built-in `crowd` of [`DEFAULT_COUNT`] tubes.
pub fn build(opts: &BuiltinOptions) -> Scene {
    build_with(DEFAULT_COUNT, opts)
}

/// A crowd of `count` tubes (at most [`MAX_COUNT`]) in a square grid over a floor, with the
/// seeded lights `opts` asks for (16 by default).
pub fn build_with(count: usize, opts: &BuiltinOptions) -> Scene {
    let count = count.min(MAX_COUNT);
    let side = (count as f32).sqrt().ceil().max(1.0) as usize;
    let extent = side as f32 * SPACING;
    let floor = plane(extent + 4.0, extent + 4.0, 1);
    let mut meshes = vec![floor];
    let mut instances = vec![Instance::caster(0, 0, Mat4::IDENTITY)];
    let mut anim = Animations::default();
    let mut channels = Vec::new();
    let times = vec![0.0, 0.5, 1.0, 1.5, 2.0];
    for i in 0..count {
        let (gx, gz) = ((i % side) as f32, (i / side) as f32);
        let base = Vec3::new(
            (gx - (side as f32 - 1.0) / 2.0) * SPACING,
            0.0,
            (gz - (side as f32 - 1.0) / 2.0) * SPACING,
        );
        let (mesh, upper) = tube(base);
        let lower = anim.nodes.len();
        let node = |parent, t: Vec3| Node {
            parent,
            rest: Mat4::from_translation(t),
            translation: t,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        };
        anim.nodes.push(node(None, base));
        anim.nodes.push(node(Some(lower), Vec3::Y));
        // Each tube sways about its own horizontal axis (golden-angle steps round the circle).
        let phi = i as f32 * 2.399_963;
        let axis = Vec3::new(phi.cos(), 0.0, phi.sin());
        let q = |deg: f32| Vec4::from(Quat::from_axis_angle(axis, deg.to_radians()));
        channels.push(Channel {
            node: lower + 1,
            property: Property::Rotation,
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: vec![q(0.0), q(35.0), q(0.0), q(-35.0), q(0.0)],
        });
        let m = meshes.len();
        anim.skins.push(Skin {
            mesh: m,
            joints: vec![lower, lower + 1],
            inverse_bind: vec![
                Mat4::from_translation(-base),
                Mat4::from_translation(-(base + Vec3::Y)),
            ],
            vertex_joints: vec![[0, 1, 0, 0]; mesh.positions.len()],
            vertex_weights: upper.iter().map(|&w| [1.0 - w, w, 0.0, 0.0]).collect(),
            extra_joints: Vec::new(),
            extra_weights: Vec::new(),
            bind_positions: mesh.positions.clone(),
            bind_normals: mesh.normals.clone(),
        });
        meshes.push(mesh);
        instances.push(Instance::caster(m, 1, Mat4::IDENTITY));
    }
    anim.clips.push(Clip {
        name: "sway".into(),
        channels,
        weights: Vec::new(),
    });
    let materials = vec![
        Material {
            diffuse: Vec3::splat(0.7),
            ..Material::default()
        },
        Material {
            diffuse: Vec3::new(0.8, 0.45, 0.25),
            double_sided: true,
            ..Material::default()
        },
    ];
    let mut scene = Scene {
        name: "crowd".into(),
        meshes,
        materials,
        instances,
        camera: Camera::look_at(
            Vec3::new(0.0, extent * 0.55 + 3.0, extent * 0.75 + 4.0),
            Vec3::new(0.0, 0.5, 0.0),
        ),
        animations: anim,
        ..Default::default()
    };
    scene.camera.far = (extent * 3.0 + 30.0).max(60.0);
    scene.lights = lights::scatter(
        &scene,
        opts.lights.unwrap_or(16),
        opts.seed,
        opts.mix,
        opts.shadow_resolution,
    );
    scene
}
