//! The `courtyard` scene: real-content features from code — textured surfaces and
//! alpha-masked casters, the things Crytek Sponza's plants, chains and banners are made of.
//!
//! Why: a shadow renderer that ignores alpha casts solid rectangles for foliage cards, lattices
//! and banners, and one that only renders its own untextured solids cannot show that it does
//! not. This scene is generated (no download, bit-for-bit reproducible) and holds:
//!
//! - a stone-tiled floor and brick walls (opaque base-colour textures; the walls also have a
//!   tangent-space normal map of their mortar joints);
//! - a pergola whose roof is one lattice card (an alpha-masked grid of bars): the sun and the
//!   spots throw a grid of shadows through it;
//! - three banners hanging from a beam (swallow-tailed, with a ring of round holes);
//! - five shrubs, each three crossed cards of a leaf texture (leaves with gaps between them);
//! - a diamond-mesh fence panel (thin wires, mostly holes);
//! - a few opaque boxes and a sphere, as in `cubes`.
//!
//! Every masked material is double-sided and uses cutoff 0.5. The textures are procedural
//! ([`courtyard_textures`]); their alpha is exactly 0 or 255, so the holes do not depend on
//! filtering. `--lights N` replaces the eight lights with a seeded layout.

use std::f32::consts::TAU;

use glam::{Mat4, Quat, Vec2, Vec3};

use super::lights::{self, Rand, Tone};
use super::options::{BuiltinOptions, LightMix};
use crate::model::{Camera, Instance, Light, Material, Scene};
use crate::primitives;
use crate::texture::{Texture, TextureRef, Wrap};

/// Camera position of `courtyard`.
pub const COURTYARD_CAMERA_POSITION: Vec3 = Vec3::new(7.5, 5.0, 8.5);
/// Camera target of `courtyard`.
pub const COURTYARD_CAMERA_TARGET: Vec3 = Vec3::new(-0.5, 1.0, -1.5);

/// Indices of the textures in [`courtyard_textures`].
pub mod tex {
    /// Stone floor tiles (opaque).
    pub const STONE: usize = 0;
    /// Bricks (opaque).
    pub const BRICK: usize = 1;
    /// The bricks' normal map.
    pub const BRICK_NORMAL: usize = 2;
    /// The pergola's lattice (alpha-masked).
    pub const LATTICE: usize = 3;
    /// A banner (alpha-masked).
    pub const BANNER: usize = 4;
    /// Leaves (alpha-masked).
    pub const LEAVES: usize = 5;
    /// Diamond wire mesh (alpha-masked).
    pub const FENCE: usize = 6;
}

fn rgba(c: Vec3, a: u8) -> [u8; 4] {
    let b = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    [b(c.x), b(c.y), b(c.z), a]
}

/// A cheap deterministic hash noise in 0..1 of integer coordinates.
fn hash(x: u32, y: u32, seed: u32) -> f32 {
    let mut h =
        x.wrapping_mul(0x27d4_eb2d) ^ y.wrapping_mul(0x1656_67b1) ^ seed.wrapping_mul(0x9e37_79b9);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    (h & 0xffff) as f32 / 65535.0
}

/// The lattice's coverage: bars `bar` texels wide every `period` texels, both directions.
pub fn lattice_solid(x: u32, y: u32) -> bool {
    const PERIOD: u32 = 64;
    const BAR: u32 = 16;
    x % PERIOD < BAR || y % PERIOD < BAR
}

/// The banner: red with blue stripes and a gold emblem, a swallow-tailed bottom and a ring
/// of eight round holes (alpha 0), 256 × 512 texels. Also hung in the atrium.
pub fn banner_texture() -> Texture {
    Texture::from_fn("banner", 256, 512, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / 256.0, (y as f32 + 0.5) / 512.0);
        // Swallow tail: a V cut into the bottom fifth.
        let tail = v > 0.8 && (v - 0.8) / 0.2 > 1.0 - (2.0 * u - 1.0).abs();
        // A ring of eight round holes around the emblem.
        let centre = Vec2::new(0.5, 0.4);
        let mut hole = false;
        for k in 0..8 {
            let a = TAU * k as f32 / 8.0;
            let c = centre + Vec2::new(a.cos() * 0.3, a.sin() * 0.15);
            if (Vec2::new(u, v * 0.5) - Vec2::new(c.x, c.y * 0.5)).length() < 0.05 {
                hole = true;
            }
        }
        let emblem = (Vec2::new(u, v * 0.5) - Vec2::new(0.5, 0.2)).length() < 0.12;
        let c = if emblem {
            Vec3::new(0.95, 0.8, 0.2)
        } else if (x / 16) % 4 == 0 {
            Vec3::new(0.2, 0.25, 0.7)
        } else {
            Vec3::new(0.7, 0.1, 0.12)
        };
        rgba(c, if tail || hole { 0 } else { 255 })
    })
}

/// The seven procedural textures of the scene (see [`tex`]).
pub fn courtyard_textures() -> Vec<Texture> {
    let stone = Texture::from_fn("stone", 256, 256, |x, y| {
        // 4x4 tiles with grout lines; each tile its own shade, fine noise on top.
        let (tx, ty) = (x / 64, y / 64);
        let grout = x % 64 < 3 || y % 64 < 3;
        let shade = 0.55 + 0.2 * hash(tx, ty, 1) + 0.08 * hash(x, y, 2);
        let c = if grout {
            Vec3::splat(0.25)
        } else {
            Vec3::new(shade, shade * 0.96, shade * 0.9)
        };
        rgba(c, 255)
    });
    // Bricks 64 x 32 texels, rows offset by half a brick, 4-texel mortar.
    let brick_at = |x: u32, y: u32| -> (bool, u32, u32) {
        let row = y / 32;
        let xs = x + if row % 2 == 1 { 32 } else { 0 };
        let mortar = y % 32 < 4 || xs % 64 < 4;
        (mortar, xs / 64, row)
    };
    let brick = Texture::from_fn("brick", 256, 256, |x, y| {
        let (mortar, bx, by) = brick_at(x, y);
        let c = if mortar {
            Vec3::splat(0.7)
        } else {
            let v = 0.75 + 0.25 * hash(bx, by, 3);
            Vec3::new(0.62 * v, 0.28 * v, 0.2 * v) * (0.92 + 0.08 * hash(x, y, 4))
        };
        rgba(c, 255)
    });
    // Mortar joints are 4 texels deep grooves: the normal tilts across each groove's walls.
    let height = |x: u32, y: u32| {
        if brick_at(x % 256, y % 256).0 {
            0.0
        } else {
            1.0
        }
    };
    let brick_normal = Texture::from_fn("brick-normal", 256, 256, |x, y| {
        let dx = height(x + 1, y) - height(x + 255, y);
        let dy = height(x, y + 1) - height(x, y + 255);
        // Image v runs down, tangent-space +Y up (glTF): green is −dh/dv.
        let n = Vec3::new(-dx * 0.5, dy * 0.5, 1.0).normalize();
        rgba(n * 0.5 + Vec3::splat(0.5), 255)
    });
    let lattice = Texture::from_fn("lattice", 256, 256, |x, y| {
        let wood = Vec3::new(0.55, 0.38, 0.22) * (0.85 + 0.15 * hash(x / 4, y, 5));
        rgba(wood, if lattice_solid(x, y) { 255 } else { 0 })
    });
    let banner = banner_texture();
    // Leaves: ellipses scattered over the texture, each its own green.
    let mut rng = Rand::new(7, 0x1eaf);
    let leaves: Vec<(Vec2, Vec2, f32, Vec3)> = (0..140)
        .map(|_| {
            let centre = Vec2::new(rng.range(0.05, 0.95), rng.range(0.1, 1.0));
            let angle = rng.range(0.0, TAU);
            let size = Vec2::new(rng.range(0.04, 0.07), rng.range(0.015, 0.03));
            let green = Vec3::new(
                rng.range(0.1, 0.3),
                rng.range(0.4, 0.7),
                rng.range(0.1, 0.25),
            );
            (centre, size, angle, green)
        })
        .collect();
    let leaf_tex = Texture::from_fn("leaves", 256, 256, |x, y| {
        let p = Vec2::new((x as f32 + 0.5) / 256.0, (y as f32 + 0.5) / 256.0);
        for (centre, size, angle, green) in &leaves {
            let d = p - *centre;
            let (s, c) = angle.sin_cos();
            let q = Vec2::new(c * d.x + s * d.y, -s * d.x + c * d.y) / *size;
            if q.length_squared() <= 1.0 {
                return rgba(*green * (0.8 + 0.2 * q.x), 255);
            }
        }
        rgba(Vec3::new(0.2, 0.4, 0.15), 0)
    });
    let fence = Texture::from_fn("fence", 256, 256, |x, y| {
        // Diamond mesh: wires along both diagonals every 32 texels, 3 texels thick.
        let a = (x + y) % 32;
        let b = (x + 256 - y) % 32;
        let wire = !(2..=29).contains(&a) || !(2..=29).contains(&b);
        rgba(Vec3::splat(0.6), if wire { 255 } else { 0 })
    });
    vec![stone, brick, brick_normal, lattice, banner, leaf_tex, fence]
}

/// The eight default lights: a sun slanting through the lattice, four spots on the banners,
/// shrubs and fence, three point lights among them.
pub fn courtyard_default_lights(shadow_resolution: Option<u32>) -> Vec<Light> {
    let warm = Vec3::new(1.0, 0.85, 0.65);
    let cool = Vec3::new(0.7, 0.82, 1.0);
    let spot = |from: Vec3, to: Vec3, cutoff: f32, tone: Tone| {
        lights::spot(
            from,
            to - from,
            cutoff,
            (to - from).length() * 2.0,
            (to - from).length(),
            tone,
            shadow_resolution,
        )
    };
    vec![
        lights::directional(
            Vec3::new(-0.35, -1.0, -0.25),
            Tone {
                color: Vec3::new(1.0, 0.97, 0.9),
                brightness: 0.8,
            },
            shadow_resolution,
        ),
        spot(
            Vec3::new(0.0, 7.0, 0.5),
            Vec3::new(0.0, 0.0, -0.5),
            40.0,
            Tone {
                color: warm,
                brightness: 0.7,
            },
        ),
        spot(
            Vec3::new(-6.0, 5.0, 4.0),
            Vec3::new(-5.0, 2.0, -6.0),
            30.0,
            Tone {
                color: cool,
                brightness: 0.6,
            },
        ),
        spot(
            Vec3::new(5.5, 4.0, 5.0),
            Vec3::new(5.5, 0.5, 0.0),
            35.0,
            Tone {
                color: warm,
                brightness: 0.6,
            },
        ),
        spot(
            Vec3::new(-2.0, 4.5, 7.0),
            Vec3::new(-3.0, 0.8, 3.0),
            30.0,
            Tone {
                color: Vec3::new(1.0, 0.95, 0.9),
                brightness: 0.6,
            },
        ),
        lights::point(
            Vec3::new(3.0, 1.8, -3.5),
            9.0,
            2.0,
            Tone {
                color: warm,
                brightness: 0.45,
            },
            shadow_resolution,
        ),
        lights::point(
            Vec3::new(-4.0, 1.5, 0.5),
            8.0,
            2.0,
            Tone {
                color: cool,
                brightness: 0.4,
            },
            shadow_resolution,
        ),
        lights::point(
            Vec3::new(1.5, 2.6, 4.5),
            8.0,
            2.0,
            Tone {
                color: Vec3::new(1.0, 0.75, 0.5),
                brightness: 0.4,
            },
            shadow_resolution,
        ),
    ]
}

/// Builds `courtyard`; `masks: false` builds the same scene with every material opaque (what a
/// renderer that ignores alpha would draw: `courtyard-opaque`).
pub(crate) fn build(opts: &BuiltinOptions, masks: bool) -> Scene {
    let textures = courtyard_textures();
    let repeat = |t| Some(TextureRef::repeat(t));
    let textured = |base: Vec3, t: usize| Material {
        base_color_texture: repeat(t),
        ..Material::matte(base)
    };
    let masked = |base: Vec3, t: usize| {
        let m = textured(base, t);
        if masks {
            m.masked(0.5)
        } else {
            Material {
                double_sided: true,
                ..m
            }
        }
    };
    let clamp_u = |t: usize| {
        Some(TextureRef {
            texture: t,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::ClampToEdge,
        })
    };
    // Materials.
    const FLOOR: usize = 0;
    const WALL: usize = 1;
    const WOOD: usize = 2;
    const LATTICE: usize = 3;
    const BANNER: usize = 4;
    const LEAVES: usize = 5;
    const FENCE: usize = 6;
    const RED: usize = 7;
    const BLUE: usize = 8;
    const WHITE: usize = 9;
    let materials = vec![
        textured(Vec3::ONE, tex::STONE),
        Material {
            normal_texture: repeat(tex::BRICK_NORMAL),
            ..textured(Vec3::ONE, tex::BRICK)
        },
        Material::matte(Vec3::new(0.45, 0.3, 0.18)),
        masked(Vec3::ONE, tex::LATTICE),
        Material {
            base_color_texture: clamp_u(tex::BANNER),
            ..masked(Vec3::ONE, tex::BANNER)
        },
        masked(Vec3::ONE, tex::LEAVES),
        masked(Vec3::ONE, tex::FENCE),
        Material::matte(Vec3::new(0.8, 0.25, 0.2)),
        Material::matte(Vec3::new(0.25, 0.55, 0.8)),
        Material {
            specular: Vec3::splat(0.6),
            shininess: 64.0,
            ..Material::matte(Vec3::splat(0.9))
        },
    ];
    // Meshes.
    let mut floor = primitives::plane(24.0, 24.0, 4);
    for t in &mut floor.uvs {
        *t *= 6.0;
    }
    floor.name = "floor".into();
    // Brick walls: 20 m x 4 m along X and 16 m x 4 m along Z, one texture copy per 4 m x 2 m
    // (a cuboid face spans the texture once; on the ±X faces u runs up, so swap).
    let mut wall = primitives::cuboid(Vec3::ONE);
    wall.name = "wall".into();
    for t in &mut wall.uvs {
        *t *= Vec2::new(5.0, 2.0);
    }
    let mut side_wall = primitives::cuboid(Vec3::ONE);
    side_wall.name = "side-wall".into();
    for t in &mut side_wall.uvs {
        *t = Vec2::new(t.y * 4.0, t.x * 2.0);
    }
    let mut post = primitives::cuboid(Vec3::ONE);
    post.name = "post".into();
    post.uvs.clear();
    let mut lattice = primitives::card(1.0, 1.0, Vec2::splat(4.0));
    lattice.name = "lattice".into();
    let mut banner = primitives::card(1.0, 2.0, Vec2::ONE);
    banner.name = "banner".into();
    let mut leaf_card = primitives::card(1.6, 1.6, Vec2::ONE);
    leaf_card.name = "leaf-card".into();
    let mut fence = primitives::card(1.0, 1.0, Vec2::new(3.0, 1.5));
    fence.name = "fence".into();
    let mut sphere = primitives::uv_sphere(1.0, 32, 16);
    sphere.name = "sphere".into();
    let meshes = vec![
        floor, wall, post, lattice, banner, leaf_card, fence, sphere, side_wall,
    ];
    const M_FLOOR: usize = 0;
    const M_WALL: usize = 1;
    const M_POST: usize = 2;
    const M_LATTICE: usize = 3;
    const M_BANNER: usize = 4;
    const M_LEAVES: usize = 5;
    const M_FENCE: usize = 6;
    const M_SPHERE: usize = 7;
    const M_SIDE_WALL: usize = 8;

    let mut instances = vec![Instance::caster(M_FLOOR, FLOOR, Mat4::IDENTITY)];
    // Two brick walls (back and left).
    for (mesh, size, pos) in [
        (M_WALL, Vec3::new(20.0, 4.0, 0.5), Vec3::new(0.0, 2.0, -8.0)),
        (
            M_SIDE_WALL,
            Vec3::new(0.5, 4.0, 16.0),
            Vec3::new(-10.0, 2.0, 0.0),
        ),
    ] {
        instances.push(Instance::caster(
            mesh,
            WALL,
            Mat4::from_scale_rotation_translation(size, Quat::IDENTITY, pos),
        ));
    }
    // Pergola: four posts and a lattice roof at 3 m, 6 m x 6 m, centred at (0, 0, -2).
    for (x, z) in [(-3.0, -5.0), (3.0, -5.0), (-3.0, 1.0), (3.0, 1.0)] {
        instances.push(Instance::caster(
            M_POST,
            WOOD,
            Mat4::from_scale_rotation_translation(
                Vec3::new(0.2, 3.0, 0.2),
                Quat::IDENTITY,
                Vec3::new(x, 1.5, z),
            ),
        ));
    }
    // The lattice card lies flat: rotating the standing card to face +Y puts it over
    // z = 0 .. −1; scaled to 6.4 m and moved so that it spans z = 1.2 .. −5.2.
    instances.push(Instance::caster(
        M_LATTICE,
        LATTICE,
        Mat4::from_translation(Vec3::new(0.0, 3.05, 1.2))
            * Mat4::from_rotation_x(-TAU / 4.0)
            * Mat4::from_scale(Vec3::new(6.4, 6.4, 1.0)),
    ));
    // A beam along the pergola's front and three banners hanging from it.
    instances.push(Instance::caster(
        M_POST,
        WOOD,
        Mat4::from_scale_rotation_translation(
            Vec3::new(6.4, 0.2, 0.2),
            Quat::IDENTITY,
            Vec3::new(0.0, 2.95, 1.0),
        ),
    ));
    for x in [-2.0f32, 0.0, 2.0] {
        instances.push(Instance::caster(
            M_BANNER,
            BANNER,
            Mat4::from_translation(Vec3::new(x, 0.85, 1.0))
                * Mat4::from_scale(Vec3::new(1.1, 1.0, 1.0)),
        ));
    }
    // Five shrubs of three crossed leaf cards each.
    for (k, (x, z)) in [
        (-6.0, -5.0),
        (-5.0, 3.0),
        (5.5, 0.0),
        (6.5, -5.5),
        (-2.5, 4.5),
    ]
    .into_iter()
    .enumerate()
    {
        for c in 0..3 {
            let yaw = TAU / 6.0 * c as f32 + 0.4 * k as f32;
            instances.push(Instance::caster(
                M_LEAVES,
                LEAVES,
                Mat4::from_translation(Vec3::new(x, 0.0, z)) * Mat4::from_rotation_y(yaw),
            ));
        }
    }
    // A fence panel, 4 m x 2 m, on the right.
    instances.push(Instance::caster(
        M_FENCE,
        FENCE,
        Mat4::from_translation(Vec3::new(8.0, 0.0, -2.0))
            * Mat4::from_rotation_y(-TAU / 4.0)
            * Mat4::from_scale(Vec3::new(6.0, 2.0, 1.0)),
    ));
    // Opaque objects.
    let boxed = |size: Vec3, pos: Vec3, yaw_deg: f32| {
        Mat4::from_scale_rotation_translation(
            size,
            Quat::from_rotation_y(yaw_deg.to_radians()),
            pos,
        )
    };
    instances.push(Instance::caster(
        M_POST,
        RED,
        boxed(Vec3::splat(1.0), Vec3::new(0.5, 0.5, -3.5), 20.0),
    ));
    instances.push(Instance::caster(
        M_POST,
        BLUE,
        boxed(Vec3::new(1.5, 0.8, 1.0), Vec3::new(3.5, 0.4, 4.0), -30.0),
    ));
    instances.push(Instance::caster(
        M_SPHERE,
        WHITE,
        Mat4::from_scale_rotation_translation(
            Vec3::splat(0.7),
            Quat::IDENTITY,
            Vec3::new(-1.5, 0.7, -1.5),
        ),
    ));

    let mut scene = Scene {
        textures,
        name: if masks {
            "courtyard"
        } else {
            "courtyard-opaque"
        }
        .into(),
        meshes,
        materials,
        instances,
        lights: Vec::new(),
        camera: Camera::look_at(COURTYARD_CAMERA_POSITION, COURTYARD_CAMERA_TARGET),
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    };
    scene.camera.far = 80.0;
    scene.lights = if opts.lights.is_none() && opts.mix == LightMix::All {
        courtyard_default_lights(opts.shadow_resolution)
    } else {
        lights::scatter(
            &scene,
            opts.lights.unwrap_or(8),
            opts.seed,
            opts.mix,
            opts.shadow_resolution,
        )
    };
    scene
}
