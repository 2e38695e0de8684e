//! The `terrain` scene, after seed 004's OpenGL terrain renderer: a 251 × 251-vertex height
//! field (125,000 triangles) over 100 × 100 m with 600 instanced objects on it.
//!
//! Why: it is the opposite workload to the atrium. One large mesh that every shadow view
//! touches (so per-instance culling cannot help and per-triangle culling must), a sun whose
//! cascades cover a wide area, and many small casters (200 "tree A", 200 "tree B", 50 rocks,
//! 150 grass tufts, as in the seed) whose shadows fall on a slope.
//!
//! The ground is a seeded sum of sines and value noise ([`terrain_height`]); objects stand
//! exactly on the triangulated surface ([`surface_height`]), sunk a little so none floats on a
//! slope. Geometry uses a fixed seed ([`TERRAIN_SEED`]) so every `--seed` gives the same
//! ground and objects; the light layout uses `opts.seed`.

use std::f32::consts::TAU;

use glam::{Mat4, Quat, Vec2, Vec3};

use super::lights::LightCounts;
use super::lights::{self, density_dim, r2, tint, Rand, Tone};
use super::options::BuiltinOptions;
use crate::model::{Camera, Instance, Light, Material, Mesh, Scene};
use crate::primitives;

/// Edge length of the square terrain (metres), centred at the origin.
pub const TERRAIN_SIZE: f32 = 100.0;
/// Quads per side: 251 × 251 vertices, 250 × 250 × 2 = 125,000 triangles.
pub const TERRAIN_SUBDIVISIONS: u32 = 250;
/// Seed of the ground shape and object placement (fixed, independent of `opts.seed`).
pub const TERRAIN_SEED: u64 = 0x7e44_a1d0_5eed_0004;
/// Instances of "tree A" (a conifer: trunk and three cones).
pub const TREE_A_COUNT: usize = 200;
/// Instances of "tree B" (a broadleaf: trunk and a cluster of spheres).
pub const TREE_B_COUNT: usize = 200;
/// Instances of the rock (a squashed, lumpy sphere).
pub const ROCK_COUNT: usize = 50;
/// Instances of the grass tuft (thin tilted boxes).
pub const GRASS_COUNT: usize = 150;
/// Default number of lights (one sun, the rest spots and points).
pub const DEFAULT_TERRAIN_LIGHTS: usize = 8;
/// Camera position: above one corner of the terrain.
pub const TERRAIN_CAMERA_POSITION: Vec3 = Vec3::new(-46.0, 30.0, -46.0);
/// Camera target: across the terrain, past its centre.
pub const TERRAIN_CAMERA_TARGET: Vec3 = Vec3::new(8.0, 0.0, 8.0);
/// Mesh index of the height field.
pub const TERRAIN_MESH: usize = 0;

fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Value noise in `[0, 1)`: seeded random values at integer lattice points, smoothly
/// interpolated.
fn value_noise(x: f32, z: f32, seed: u64) -> f32 {
    let (ix, iz) = (x.floor(), z.floor());
    let (fx, fz) = (x - ix, z - iz);
    let corner = |dx: i64, dz: i64| {
        let key = ((ix as i64 + dx) as u64).wrapping_mul(0x1000_0000_01b3)
            ^ ((iz as i64 + dz) as u64).rotate_left(32)
            ^ seed;
        (splitmix(key) >> 40) as f32 / (1u64 << 24) as f32
    };
    let (sx, sz) = (fx * fx * (3.0 - 2.0 * fx), fz * fz * (3.0 - 2.0 * fz));
    let a = corner(0, 0) + sx * (corner(1, 0) - corner(0, 0));
    let b = corner(0, 1) + sx * (corner(1, 1) - corner(0, 1));
    a + sz * (b - a)
}

/// The smooth ground height at `(x, z)`: two broad sine swells plus four octaves of value
/// noise, roughly −9..9 m.
pub fn terrain_height(x: f32, z: f32) -> f32 {
    let mut h = 2.5 * (0.055 * x + 0.7).sin() * (0.045 * z - 0.3).cos()
        + 1.2 * (0.11 * x + 0.08 * z + 1.9).sin();
    let (mut amp, mut freq) = (3.5, 1.0 / 18.0);
    for octave in 0..4u64 {
        h += amp * (2.0 * value_noise(x * freq, z * freq, TERRAIN_SEED.wrapping_add(octave)) - 1.0);
        amp *= 0.5;
        freq *= 2.0;
    }
    h
}

fn grid_coord(i: u32) -> f32 {
    // The same expression as primitives::heightfield, so heights match bit for bit.
    -0.5 * TERRAIN_SIZE + TERRAIN_SIZE * i as f32 / TERRAIN_SUBDIVISIONS as f32
}

/// The height of the rendered (triangulated) ground at `(x, z)`.
pub fn surface_height(x: f32, z: f32) -> f32 {
    primitives::heightfield_height(
        TERRAIN_SIZE,
        TERRAIN_SIZE,
        TERRAIN_SUBDIVISIONS,
        |i, j| terrain_height(grid_coord(i), grid_coord(j)),
        x,
        z,
    )
}

/// The ground mesh: 251 × 251 vertices, 125,000 triangles.
pub fn terrain_mesh() -> Mesh {
    let mut mesh = primitives::heightfield(
        TERRAIN_SIZE,
        TERRAIN_SIZE,
        TERRAIN_SUBDIVISIONS,
        terrain_height,
    );
    mesh.name = "terrain".into();
    mesh
}

fn tree_a() -> Mesh {
    let mut m = primitives::merge(&[
        (primitives::cylinder(0.18, 1.6, 12), Mat4::IDENTITY),
        (
            primitives::cone(1.5, 2.4, 24),
            Mat4::from_translation(Vec3::Y * 1.2),
        ),
        (
            primitives::cone(1.15, 2.0, 24),
            Mat4::from_translation(Vec3::Y * 2.3),
        ),
        (
            primitives::cone(0.8, 1.7, 24),
            Mat4::from_translation(Vec3::Y * 3.3),
        ),
    ]);
    m.name = "tree-a".into();
    m
}

fn tree_b() -> Mesh {
    let mut m = primitives::merge(&[
        (primitives::cylinder(0.2, 2.6, 12), Mat4::IDENTITY),
        (
            primitives::uv_sphere(1.3, 12, 8),
            Mat4::from_translation(Vec3::new(0.0, 3.2, 0.0)),
        ),
        (
            primitives::uv_sphere(0.9, 10, 6),
            Mat4::from_translation(Vec3::new(0.8, 2.7, 0.3)),
        ),
        (
            primitives::uv_sphere(0.85, 10, 6),
            Mat4::from_translation(Vec3::new(-0.6, 2.8, -0.6)),
        ),
    ]);
    m.name = "tree-b".into();
    m
}

fn rock() -> Mesh {
    let mut m = primitives::uv_sphere(1.0, 12, 8);
    for p in &mut m.positions {
        let lump = 1.0
            + 0.25
                * (value_noise(
                    2.0 * p.x + 5.0,
                    2.0 * p.z + 2.0 * p.y + 9.0,
                    TERRAIN_SEED ^ 0x50c,
                ) - 0.5);
        *p *= lump * Vec3::new(1.2, 0.65, 1.0);
    }
    m.compute_normals();
    m.name = "rock".into();
    m
}

fn grass() -> Mesh {
    let blades: Vec<(Mesh, Mat4)> = (0..7)
        .map(|k| {
            let a = TAU * k as f32 / 7.0;
            let h = 0.5 + 0.1 * (k % 3) as f32;
            let tilt =
                Quat::from_rotation_y(a) * Quat::from_rotation_x(0.25 + 0.05 * (k % 2) as f32);
            (
                primitives::cuboid(Vec3::new(0.12, h, 0.03)),
                Mat4::from_rotation_translation(
                    tilt,
                    Vec3::new(0.06 * a.cos(), 0.0, 0.06 * a.sin()),
                ) * Mat4::from_translation(Vec3::Y * (0.5 * h)),
            )
        })
        .collect();
    let mut m = primitives::merge(&blades);
    m.name = "grass".into();
    m
}

/// The scene's default light layout for `n` lights: directional suns first, then spots
/// hanging 7–10 m above the ground pointing down, then point lights 2–4 m above the ground,
/// spread over the central 80 × 80 m.
pub fn terrain_lights(
    n: usize,
    seed: u64,
    mix: super::options::LightMix,
    shadow_resolution: Option<u32>,
) -> Vec<Light> {
    let counts = LightCounts::split(n, mix);
    let mut rng = Rand::new(seed, 0x7e44);
    let offset = Vec2::new(rng.unit(), rng.unit());
    let dim = density_dim(counts.spot + counts.point, 16);
    let mut out = Vec::with_capacity(n);
    for d in 0..counts.directional {
        let direction = if d == 0 {
            Vec3::new(0.55, -0.5, 0.45)
                + 0.1 * Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0))
        } else {
            lights::slanted_direction(&mut rng, 30.0, 60.0)
        };
        let brightness = if d == 0 {
            0.75
        } else {
            0.6 / counts.directional as f32
        };
        let color = if d == 0 {
            Vec3::new(1.0, 0.93, 0.8)
        } else {
            tint(&mut rng)
        };
        out.push(lights::directional(
            direction,
            Tone { color, brightness },
            shadow_resolution,
        ));
    }
    if n > lights::LOCAL_LAYOUT_ABOVE {
        // Local lights over the central 80 × 80 m, standing on the ground (trees and rocks
        // are not avoided: a light in a canopy lights its tree).
        let floor = lights::Floor {
            lo: Vec2::splat(-40.0),
            hi: Vec2::splat(40.0),
        };
        out.extend(lights::local(
            counts.spot,
            counts.point,
            &[floor],
            &|_, xz: Vec2| surface_height(xz.x, xz.y),
            &[],
            &mut rng,
            lights::LOCAL_BRIGHTNESS,
            shadow_resolution,
        ));
        return out;
    }
    let mut k = 0;
    let mut place = |rng: &mut Rand| {
        let u = r2(k, offset);
        k += 1;
        let x = -40.0 + 80.0 * u.x + rng.range(-1.0, 1.0);
        let z = -40.0 + 80.0 * u.y + rng.range(-1.0, 1.0);
        (x, z, surface_height(x, z))
    };
    for _ in 0..counts.spot {
        let (x, z, ground) = place(&mut rng);
        let above = rng.range(7.0, 10.0);
        let tilt = rng.range(0.0, 20f32.to_radians());
        let az = rng.range(0.0, TAU);
        let direction = Vec3::new(tilt.sin() * az.cos(), -tilt.cos(), tilt.sin() * az.sin());
        let key = above / tilt.cos();
        let tone = Tone {
            color: tint(&mut rng),
            brightness: 0.8 * dim,
        };
        out.push(lights::spot(
            Vec3::new(x, ground + above, z),
            direction,
            rng.range(30.0, 40.0),
            2.5 * key,
            key,
            tone,
            shadow_resolution,
        ));
    }
    for _ in 0..counts.point {
        let (x, z, ground) = place(&mut rng);
        let above = rng.range(2.0, 4.0);
        let tone = Tone {
            color: tint(&mut rng),
            brightness: 0.7 * dim,
        };
        out.push(lights::point(
            Vec3::new(x, ground + above, z),
            3.0 * above,
            above,
            tone,
            shadow_resolution,
        ));
    }
    out
}

/// Builds `terrain`.
pub(crate) fn build(opts: &BuiltinOptions) -> Scene {
    let meshes = vec![terrain_mesh(), tree_a(), tree_b(), rock(), grass()];
    let materials = vec![
        Material {
            specular: Vec3::splat(0.03),
            ..Material::matte(Vec3::new(0.42, 0.5, 0.28))
        },
        Material::matte(Vec3::new(0.16, 0.36, 0.18)),
        Material::matte(Vec3::new(0.35, 0.5, 0.2)),
        Material::matte(Vec3::new(0.5, 0.48, 0.45)),
        Material::matte(Vec3::new(0.55, 0.65, 0.25)),
    ];
    let mut instances = vec![Instance::caster(TERRAIN_MESH, 0, Mat4::IDENTITY)];
    let mut rng = Rand::new(TERRAIN_SEED, 0x0b1e);
    let half = 0.5 * TERRAIN_SIZE - 2.0;
    let kinds = [
        (1, TREE_A_COUNT, 0.8, 1.3),
        (2, TREE_B_COUNT, 0.8, 1.25),
        (3, ROCK_COUNT, 0.5, 1.6),
        (4, GRASS_COUNT, 0.8, 1.5),
    ];
    for (mesh, count, smin, smax) in kinds {
        for _ in 0..count {
            let x = rng.range(-half, half);
            let z = rng.range(-half, half);
            let scale = rng.range(smin, smax);
            let yaw = rng.range(0.0, TAU);
            let y = surface_height(x, z) - 0.15 * scale;
            instances.push(Instance {
                mesh,
                material: mesh,
                transform: Mat4::from_scale_rotation_translation(
                    Vec3::splat(scale),
                    Quat::from_rotation_y(yaw),
                    Vec3::new(x, y, z),
                ),
                casts_shadows: true,
            });
        }
    }
    let n = opts.lights.unwrap_or(DEFAULT_TERRAIN_LIGHTS);
    let mut camera = Camera::look_at(TERRAIN_CAMERA_POSITION, TERRAIN_CAMERA_TARGET);
    camera.near = 0.5;
    camera.far = 300.0;
    Scene {
        textures: Vec::new(),
        name: "terrain".into(),
        meshes,
        materials,
        instances,
        lights: terrain_lights(n, opts.seed, opts.mix, opts.shadow_resolution),
        camera,
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}
