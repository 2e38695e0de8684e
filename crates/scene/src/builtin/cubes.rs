//! The `cubes` scene: a floor, a few boxes and a sphere, lit by one light of each type.
//!
//! Why: golden-image tests need a scene that is small (about a thousand triangles, quick on a
//! software rasterizer), exercises all three light types and their shadows at once, and never
//! changes. With the default options its three lights are fixed, not seeded; asking for a light
//! count or a non-`all` mix switches to the generic seeded layout
//! ([`scatter_lights`](super::scatter_lights)). Its lights are hard (size 0) either way, unlike
//! the other built-ins' ([`crate::light_size`]): the golden images are of hard shadows.

use glam::{Mat4, Quat, Vec3};

use super::lights::{self, Tone};
use super::options::{BuiltinOptions, LightMix};
use crate::model::{Camera, Instance, Light, Material, Scene};
use crate::primitives;

/// Camera position of `cubes`.
pub const CUBES_CAMERA_POSITION: Vec3 = Vec3::new(6.0, 6.0, 8.0);
/// Camera target of `cubes`.
pub const CUBES_CAMERA_TARGET: Vec3 = Vec3::new(0.0, 0.5, 0.0);

/// The three fixed lights: a warm spot, a cool point light and a white sun, all hard.
pub fn cubes_default_lights(shadow_resolution: Option<u32>) -> Vec<Light> {
    let spot_pos = Vec3::new(-3.0, 5.0, 3.0);
    let point_pos = Vec3::new(2.5, 3.0, 2.5);
    hard(vec![
        lights::spot(
            spot_pos,
            Vec3::new(0.0, 0.5, 0.0) - spot_pos,
            35.0,
            15.0,
            (spot_pos - Vec3::new(0.0, 0.5, 0.0)).length(),
            Tone {
                color: Vec3::new(1.0, 0.82, 0.6),
                brightness: 0.7,
            },
            shadow_resolution,
        ),
        lights::point(
            point_pos,
            12.0,
            point_pos.y,
            Tone {
                color: Vec3::new(0.7, 0.82, 1.0),
                brightness: 0.5,
            },
            shadow_resolution,
        ),
        lights::directional(
            Vec3::new(-0.4, -1.0, -0.3),
            Tone {
                color: Vec3::new(1.0, 0.98, 0.95),
                brightness: 0.45,
            },
            shadow_resolution,
        ),
    ])
}

/// `lights` with size 0: points, hard shadows.
fn hard(mut lights: Vec<Light>) -> Vec<Light> {
    for l in &mut lights {
        l.size = 0.0;
    }
    lights
}

/// Builds `cubes`.
pub(crate) fn build(opts: &BuiltinOptions) -> Scene {
    let mut floor = primitives::plane(12.0, 12.0, 2);
    floor.name = "floor".into();
    let mut cube = primitives::cuboid(Vec3::ONE);
    cube.name = "cube".into();
    let mut sphere = primitives::uv_sphere(1.0, 32, 16);
    sphere.name = "sphere".into();
    let materials = vec![
        Material::matte(Vec3::splat(0.8)),
        Material {
            specular: Vec3::splat(0.4),
            shininess: 32.0,
            ..Material::matte(Vec3::new(0.8, 0.25, 0.2))
        },
        Material::matte(Vec3::new(0.25, 0.55, 0.8)),
        Material::matte(Vec3::new(0.85, 0.75, 0.3)),
        Material {
            specular: Vec3::splat(0.6),
            shininess: 64.0,
            ..Material::matte(Vec3::new(0.9, 0.9, 0.9))
        },
    ];
    let inst = |mesh, material, transform| Instance {
        mesh,
        material,
        transform,
        casts_shadows: true,
    };
    let boxed = |size: Vec3, pos: Vec3, yaw_deg: f32| {
        Mat4::from_scale_rotation_translation(
            size,
            Quat::from_rotation_y(yaw_deg.to_radians()),
            pos,
        )
    };
    let instances = vec![
        inst(0, 0, Mat4::IDENTITY),
        inst(1, 1, boxed(Vec3::ONE, Vec3::new(-2.0, 0.5, -1.0), 0.0)),
        inst(
            1,
            2,
            boxed(Vec3::splat(1.5), Vec3::new(1.5, 0.75, 1.0), 30.0),
        ),
        inst(
            1,
            3,
            boxed(Vec3::new(0.6, 2.5, 0.6), Vec3::new(-0.5, 1.25, 2.0), 15.0),
        ),
        inst(
            1,
            1,
            boxed(Vec3::splat(0.5), Vec3::new(1.5, 1.75, 1.0), 50.0),
        ),
        inst(
            1,
            2,
            boxed(Vec3::new(2.0, 0.4, 0.8), Vec3::new(-2.5, 0.2, 2.5), -20.0),
        ),
        inst(
            2,
            4,
            Mat4::from_scale_rotation_translation(
                Vec3::splat(0.8),
                Quat::IDENTITY,
                Vec3::new(2.0, 0.8, -2.0),
            ),
        ),
    ];
    let mut scene = Scene {
        textures: Vec::new(),
        name: "cubes".into(),
        meshes: vec![floor, cube, sphere],
        materials,
        instances,
        lights: Vec::new(),
        camera: Camera::look_at(CUBES_CAMERA_POSITION, CUBES_CAMERA_TARGET),
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    };
    scene.camera.far = 60.0;
    scene.lights = if opts.lights.is_none() && opts.mix == LightMix::All {
        cubes_default_lights(opts.shadow_resolution)
    } else {
        hard(lights::scatter(
            &scene,
            opts.lights.unwrap_or(3),
            opts.seed,
            opts.mix,
            opts.shadow_resolution,
        ))
    };
    scene
}
