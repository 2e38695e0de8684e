//! The `atrium` scene: a Sponza-like two-storey arcaded hall, the many-lights workload.
//!
//! Why this shape: many shadow-casting lights only pay off, and only stress a renderer, when
//! each light lights a *neighbourhood* full of occluders. A hall with arcades gives exactly
//! that: lights hang under the arches and between the columns, and every one of them throws
//! column, arch and baluster shadows nearby, while most of the hall lies outside its range.
//! The geometry is built from **many instances of a few meshes** (columns, arches, balusters,
//! urns, slabs) rather than one giant mesh, so per-view culling of instances has something to
//! cull. Well-tessellated columns, balusters and urns bring it above 200,000 triangles.
//!
//! Layout (metres; X along the nave, Z across, Y up): the hall is
//! [`HALL_LENGTH`] × [`HALL_WIDTH`] × [`HALL_HEIGHT`], centred on the origin at floor level.
//! Two arcades at `z = ±`[`ARCADE_Z`] separate the nave from the side aisles, each with
//! [`COLUMNS_PER_ROW`] columns [`BAY`] apart and an arch over every bay, on both storeys. The
//! upper storey stands on a gallery floor over the aisles (top at [`GALLERY_Y`]) with a
//! balustrade between its columns; the aisles are roofed, the nave is open to the sky so a
//! sun slants in. The end walls have round-headed doorways; urns, planters, crates and a
//! fountain stand on the floors.
//!
//! Like Crytek Sponza's drapes, alpha-masked **banners** hang from the gallery's edge in every
//! other bay on both sides (textured cards, [`super::courtyard::banner_texture`]: a
//! swallow-tailed cloth with a ring of holes, double-sided); their shadows show the holes.
//!
//! Lights ([`atrium_lights`]) are placed on **slots** along the arcades: spots under every
//! arch (both storeys, both sides) pointing down and into the nave, points in the middle of
//! every aisle bay (both storeys), and directional suns through the open roof. A layout
//! spreads the requested count evenly over the slots (seeded); more lights than slots reuse
//! slots with seeded offsets.

use glam::{Mat4, Quat, Vec2, Vec3};

use super::lights::LightCounts;
use super::lights::{self, density_dim, slanted_direction, tint, Rand, Tone};
use super::options::{BuiltinOptions, LightMix};
use crate::model::{Camera, Instance, Light, Material, Mesh, Probe, Scene};
use crate::primitives;

/// Length of the hall along X (inner faces of the end walls at `x = ±20`).
pub const HALL_LENGTH: f32 = 40.0;
/// Width of the hall along Z (inner faces of the side walls at `z = ±8`).
pub const HALL_WIDTH: f32 = 16.0;
/// Height of the hall (top of the aisle roofs).
pub const HALL_HEIGHT: f32 = 12.0;
/// The two arcades stand at `z = ±ARCADE_Z`; the nave between them is 8 m wide.
pub const ARCADE_Z: f32 = 4.0;
/// Distance between neighbouring columns.
pub const BAY: f32 = 4.0;
/// Columns per arcade row per storey (at `x = −18, −14, …, 18`).
pub const COLUMNS_PER_ROW: usize = 10;
/// Top of the gallery floor, the upper storey's ground.
pub const GALLERY_Y: f32 = 6.6;
/// Default number of lights.
pub const DEFAULT_ATRIUM_LIGHTS: usize = 32;
/// Camera position: inside the west doorway, slightly elevated.
pub const ATRIUM_CAMERA_POSITION: Vec3 = Vec3::new(-19.2, 4.5, -1.0);
/// Camera target: down the nave.
pub const ATRIUM_CAMERA_TARGET: Vec3 = Vec3::new(4.0, 3.2, 0.6);

const LOWER_COLUMN_HEIGHT: f32 = 4.4;
const LOWER_COLUMN_RADIUS: f32 = 0.3;
const LOWER_ARCH_RADIUS: f32 = 1.6;
const ARCH_HEIGHT: f32 = 1.9;
const ARCH_DEPTH: f32 = 0.7;
const UPPER_COLUMN_HEIGHT: f32 = 3.2;
const UPPER_COLUMN_RADIUS: f32 = 0.24;
const UPPER_ARCH_RADIUS: f32 = 1.65;
const WALL: f32 = 0.4;

/// Materials of the atrium, by index.
mod mat {
    pub const FLOOR: usize = 0;
    pub const STONE: usize = 1;
    pub const PLASTER: usize = 2;
    pub const BRONZE: usize = 3;
    pub const TERRACOTTA: usize = 4;
    pub const FOLIAGE: usize = 5;
    pub const WOOD: usize = 6;
    pub const MARBLE: usize = 7;
    pub const BANNER: usize = 8;
}

fn materials() -> Vec<Material> {
    let shiny = |c: Vec3, s: f32, e: f32| Material {
        specular: Vec3::splat(s),
        shininess: e,
        ..Material::matte(c)
    };
    // Polished floor, marble and bronze mirror a little of the probes' light (only where the
    // scene has probes: `BuiltinOptions::default_probes`).
    vec![
        shiny(Vec3::new(0.62, 0.57, 0.5), 0.25, 32.0).reflecting(0.12),
        Material::matte(Vec3::new(0.78, 0.72, 0.62)),
        Material::matte(Vec3::new(0.82, 0.77, 0.68)),
        shiny(Vec3::new(0.55, 0.38, 0.2), 0.6, 48.0).reflecting(0.2),
        Material::matte(Vec3::new(0.72, 0.38, 0.25)),
        Material::matte(Vec3::new(0.22, 0.45, 0.18)),
        Material::matte(Vec3::new(0.45, 0.3, 0.18)),
        shiny(Vec3::new(0.9, 0.89, 0.86), 0.5, 64.0).reflecting(0.2),
        Material::matte(Vec3::ONE).with_texture(0).masked(0.5),
    ]
}

/// Banner cards: 1.4 m wide, 2.6 m long.
const BANNER_SIZE: Vec2 = Vec2::new(1.4, 2.6);

/// x of column `k` (0-based) of a row.
fn column_x(k: usize) -> f32 {
    -0.5 * BAY * (COLUMNS_PER_ROW - 1) as f32 + BAY * k as f32
}

/// x of the middle of bay `b` (between columns `b` and `b + 1`).
fn bay_x(b: usize) -> f32 {
    column_x(b) + 0.5 * BAY
}

/// Smooth profile through `(r, y)` control points (Catmull-Rom), `steps` points per span.
fn smooth_profile(points: &[Vec2], steps: usize) -> Vec<Vec2> {
    let mut out = Vec::new();
    let n = points.len();
    for i in 0..n - 1 {
        let p0 = points[i.saturating_sub(1)];
        let (p1, p2) = (points[i], points[i + 1]);
        let p3 = points[(i + 2).min(n - 1)];
        for s in 0..steps {
            let t = s as f32 / steps as f32;
            let t2 = t * t;
            let t3 = t2 * t;
            let p = 0.5
                * ((2.0 * p1)
                    + (p2 - p0) * t
                    + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
                    + (3.0 * p1 - p0 - 3.0 * p2 + p3) * t3);
            out.push(Vec2::new(p.x.max(0.0), p.y));
        }
    }
    out.push(points[n - 1]);
    out
}

fn named(mut mesh: Mesh, name: &str) -> Mesh {
    mesh.name = name.into();
    mesh
}

/// A turned baluster, 0.85 m tall.
fn baluster() -> Mesh {
    let mut profile = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(0.07, 0.0),
        Vec2::new(0.07, 0.06),
    ];
    profile.extend(smooth_profile(
        &[
            Vec2::new(0.05, 0.08),
            Vec2::new(0.075, 0.22),
            Vec2::new(0.065, 0.42),
            Vec2::new(0.035, 0.6),
            Vec2::new(0.05, 0.72),
        ],
        3,
    ));
    profile.extend([
        Vec2::new(0.07, 0.76),
        Vec2::new(0.07, 0.85),
        Vec2::new(0.0, 0.85),
    ]);
    named(primitives::lathe(&profile, 10), "baluster")
}

/// A two-handled-looking urn (turned), 1.2 m tall, on the floor.
fn urn() -> Mesh {
    let mut profile = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(0.2, 0.0),
        Vec2::new(0.2, 0.08),
    ];
    profile.extend(smooth_profile(
        &[
            Vec2::new(0.12, 0.12),
            Vec2::new(0.1, 0.25),
            Vec2::new(0.3, 0.5),
            Vec2::new(0.36, 0.72),
            Vec2::new(0.22, 0.98),
            Vec2::new(0.17, 1.08),
            Vec2::new(0.26, 1.18),
        ],
        4,
    ));
    // Lip and the inside of the mouth (open, down to a floor inside).
    profile.extend([
        Vec2::new(0.24, 1.2),
        Vec2::new(0.2, 1.15),
        Vec2::new(0.15, 1.02),
        Vec2::new(0.0, 1.0),
    ]);
    named(primitives::lathe(&profile, 24), "urn")
}

/// A two-tier fountain, 2.5 m tall, basin 4.2 m across.
fn fountain() -> Mesh {
    let mut profile = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(2.0, 0.0),
        Vec2::new(2.0, 0.45),
        Vec2::new(2.12, 0.5),
        Vec2::new(2.12, 0.62),
        Vec2::new(1.9, 0.62),
        Vec2::new(1.9, 0.35),
        Vec2::new(0.32, 0.35),
    ];
    profile.extend(smooth_profile(
        &[
            Vec2::new(0.3, 0.4),
            Vec2::new(0.22, 0.8),
            Vec2::new(0.2, 1.2),
            Vec2::new(0.45, 1.42),
            Vec2::new(0.95, 1.55),
        ],
        4,
    ));
    profile.extend([
        Vec2::new(1.05, 1.62),
        Vec2::new(1.05, 1.7),
        Vec2::new(0.95, 1.7),
        Vec2::new(0.95, 1.62),
        Vec2::new(0.16, 1.62),
        Vec2::new(0.12, 2.2),
    ]);
    // A ball finial of radius 0.17 on the spout.
    for k in 0..=9 {
        let a = (-45.0 + 15.0 * k as f32).to_radians();
        profile.push(Vec2::new(0.17 * a.cos(), 2.38 + 0.17 * a.sin()));
    }
    named(primitives::lathe(&profile, 64), "fountain")
}

/// The scene's light layout for `n` lights of `mix`; see the module docs.
pub fn atrium_lights(
    n: usize,
    seed: u64,
    mix: LightMix,
    shadow_resolution: Option<u32>,
) -> Vec<Light> {
    build(&BuiltinOptions {
        lights: Some(n),
        seed,
        mix,
        shadow_resolution,
        ..BuiltinOptions::default()
    })
    .lights
}

/// Most spot and point lights on the arcade slots when the layout has local lights too.
const ARCHITECTURAL_SPOTS: usize = 24;
const ARCHITECTURAL_POINTS: usize = 12;

/// Up to [`lights::LOCAL_LAYOUT_ABOVE`] lights: all on the arcade slots. Above: the suns,
/// [`ARCHITECTURAL_SPOTS`] spots and [`ARCHITECTURAL_POINTS`] points on the slots, and every
/// further light a local light over the ground floor or a gallery floor, kept out of the
/// `obstacles` (the scene's instance boxes).
fn layout_lights(
    n: usize,
    seed: u64,
    mix: LightMix,
    shadow_resolution: Option<u32>,
    obstacles: &[(Vec3, Vec3)],
) -> Vec<Light> {
    let counts = LightCounts::split(n, mix);
    let mut rng = Rand::new(seed, 0xa7e1);
    if n <= lights::LOCAL_LAYOUT_ABOVE {
        return slot_lights(counts, &mut rng, shadow_resolution);
    }
    let arch = LightCounts {
        spot: counts.spot.min(ARCHITECTURAL_SPOTS),
        point: counts.point.min(ARCHITECTURAL_POINTS),
        directional: counts.directional,
    };
    let mut out = slot_lights(arch, &mut rng, shadow_resolution);
    let (hx, hz) = (0.5 * HALL_LENGTH - 0.4, 0.5 * HALL_WIDTH - 0.4);
    let gallery_z = ARCADE_Z + 0.45;
    let floors = [
        lights::Floor {
            lo: Vec2::new(-hx, -hz),
            hi: Vec2::new(hx, hz),
        },
        lights::Floor {
            lo: Vec2::new(-hx, gallery_z),
            hi: Vec2::new(hx, hz),
        },
        lights::Floor {
            lo: Vec2::new(-hx, -hz),
            hi: Vec2::new(hx, -gallery_z),
        },
    ];
    let height = |floor: usize, _: Vec2| if floor == 0 { 0.0 } else { GALLERY_Y };
    out.extend(lights::local(
        counts.spot - arch.spot,
        counts.point - arch.point,
        &floors,
        &height,
        obstacles,
        &mut rng,
        lights::LOCAL_BRIGHTNESS,
        shadow_resolution,
    ));
    out
}

/// The arcade-slot layout of `counts` lights; see the module docs.
fn slot_lights(counts: LightCounts, rng: &mut Rand, shadow_resolution: Option<u32>) -> Vec<Light> {
    let n = counts.total();
    // Slots in bay-major order, alternating storey and side, so an even pick over the list
    // covers both arcades, both storeys and the whole length.
    let order = [(0usize, 1.0f32), (1, -1.0), (0, -1.0), (1, 1.0)];
    let slots: Vec<(usize, usize, f32)> = (0..COLUMNS_PER_ROW - 1)
        .flat_map(|b| order.iter().map(move |&(storey, side)| (b, storey, side)))
        .collect();
    let pick = |count: usize, rng: &mut Rand| -> Vec<(usize, usize)> {
        let len = slots.len();
        (0..count)
            .map(|k| {
                if count <= len {
                    // Light k takes a random slot among those in the k-th of `count` equal
                    // strata of the list; each stratum holds at least one slot, and strata
                    // don't overlap, so no two lights share a slot.
                    let first = (k * len).div_ceil(count);
                    let last = ((k + 1) * len).div_ceil(count) - 1;
                    (first + rng.below(last - first + 1), 0)
                } else {
                    (k % len, k / len)
                }
            })
            .collect()
    };
    let mut out = Vec::with_capacity(n);
    for d in 0..counts.directional {
        let (direction, color, brightness) = match (d, counts.directional) {
            (0, 1..=2) => (
                Vec3::new(0.35, -1.0, 0.25)
                    + 0.08 * Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0)),
                Vec3::new(1.0, 0.94, 0.82),
                0.55,
            ),
            (1, 2) => (
                Vec3::new(-0.4, -1.0, -0.3),
                Vec3::new(0.75, 0.85, 1.0),
                0.25,
            ),
            _ => (
                slanted_direction(rng, 50.0, 80.0),
                tint(rng),
                1.0 / counts.directional as f32,
            ),
        };
        out.push(lights::directional(
            direction,
            Tone { color, brightness },
            shadow_resolution,
        ));
    }
    for (slot, cycle) in pick(counts.spot, rng) {
        let (b, storey, side) = slots[slot];
        let mut position = if storey == 0 {
            Vec3::new(bay_x(b), 5.6, side * ARCADE_Z)
        } else {
            Vec3::new(bay_x(b), 11.0, side * ARCADE_Z)
        };
        if cycle > 0 {
            position += Vec3::new(rng.range(-1.3, 1.3), rng.range(-0.4, 0.2), 0.0);
        }
        let inward = if storey == 0 { 0.35 } else { 0.3 };
        let direction = Vec3::new(rng.range(-0.1, 0.1), -1.0, -side * inward).normalize();
        let key = position.y / -direction.y;
        let (cutoff, range) = if storey == 0 {
            (40.0, 14.0)
        } else {
            (32.0, 24.0)
        };
        let tone = Tone {
            color: tint(rng),
            brightness: 0.4 * density_dim(counts.spot, slots.len()),
        };
        out.push(lights::spot(
            position,
            direction,
            cutoff,
            range,
            key,
            tone,
            shadow_resolution,
        ));
    }
    for (slot, cycle) in pick(counts.point, rng) {
        let (b, storey, side) = slots[slot];
        let mut position = if storey == 0 {
            Vec3::new(bay_x(b), 3.2, side * 6.0)
        } else {
            Vec3::new(bay_x(b), 9.0, side * 6.0)
        };
        if cycle > 0 {
            position += Vec3::new(
                rng.range(-1.3, 1.3),
                rng.range(-0.4, 0.4),
                rng.range(-0.8, 0.8),
            );
        }
        let (range, key) = if storey == 0 { (9.0, 3.5) } else { (8.0, 2.8) };
        let tone = Tone {
            color: tint(rng),
            brightness: 0.45 * density_dim(counts.point, slots.len()),
        };
        out.push(lights::point(position, range, key, tone, shadow_resolution));
    }
    out
}

/// Collects meshes and instances.
struct Hall {
    meshes: Vec<Mesh>,
    instances: Vec<Instance>,
}

impl Hall {
    fn mesh(&mut self, mesh: Mesh) -> usize {
        self.meshes.push(mesh);
        self.meshes.len() - 1
    }

    fn put(&mut self, mesh: usize, material: usize, transform: Mat4) {
        self.instances.push(Instance {
            mesh,
            material,
            transform,
            casts_shadows: true,
        });
    }

    /// A box from `lo` to `hi` made of the shared unit cube (axis-aligned faces shade
    /// correctly under non-uniform scale).
    fn block(&mut self, cube: usize, material: usize, lo: Vec3, hi: Vec3) {
        self.put(
            cube,
            material,
            Mat4::from_scale_rotation_translation(hi - lo, Quat::IDENTITY, 0.5 * (lo + hi)),
        );
    }
}

/// Builds `atrium`.
pub(crate) fn build(opts: &BuiltinOptions) -> Scene {
    let mut h = Hall {
        meshes: Vec::new(),
        instances: Vec::new(),
    };
    let cube = h.mesh(named(primitives::cuboid(Vec3::ONE), "block"));
    let floor_tile = h.mesh(named(primitives::plane(BAY, BAY, 4), "floor-tile"));
    let lower_column = h.mesh(named(
        primitives::column(LOWER_COLUMN_RADIUS, LOWER_COLUMN_HEIGHT, 32),
        "column-lower",
    ));
    let upper_column = h.mesh(named(
        primitives::column(UPPER_COLUMN_RADIUS, UPPER_COLUMN_HEIGHT, 24),
        "column-upper",
    ));
    let lower_arch = h.mesh(named(
        primitives::arch(BAY, ARCH_HEIGHT, LOWER_ARCH_RADIUS, ARCH_DEPTH, 48),
        "arch-lower",
    ));
    let upper_arch = h.mesh(named(
        primitives::arch(BAY, ARCH_HEIGHT, UPPER_ARCH_RADIUS, ARCH_DEPTH, 48),
        "arch-upper",
    ));
    let door_arch = h.mesh(named(
        primitives::arch(3.0, 2.0, 1.5, WALL, 32),
        "door-arch",
    ));
    let baluster = h.mesh(baluster());
    let urn = h.mesh(urn());
    let fountain = h.mesh(fountain());
    let bush = h.mesh(named(primitives::uv_sphere(0.5, 20, 10), "bush"));
    let banner = h.mesh(named(
        primitives::card(BANNER_SIZE.x, BANNER_SIZE.y, Vec2::ONE),
        "banner",
    ));
    let ball = h.mesh(named(primitives::uv_sphere(0.3, 24, 12), "ball"));

    let (hx, hz) = (0.5 * HALL_LENGTH, 0.5 * HALL_WIDTH);
    let lower_top = LOWER_COLUMN_HEIGHT + ARCH_HEIGHT; // 6.3
    let upper_base = GALLERY_Y;
    let upper_spring = upper_base + UPPER_COLUMN_HEIGHT; // 9.8
    let roof_lo = upper_spring + ARCH_HEIGHT; // 11.7
    let arch_z0 = ARCADE_Z - 0.5 * ARCH_DEPTH;

    // Floor: 4 × 4 m tiles, so each light's views cull most of them.
    for i in 0..(HALL_LENGTH / BAY) as usize {
        for j in 0..(HALL_WIDTH / BAY) as usize {
            let x = -hx + BAY * (i as f32 + 0.5);
            let z = -hz + BAY * (j as f32 + 0.5);
            h.put(
                floor_tile,
                mat::FLOOR,
                Mat4::from_translation(Vec3::new(x, 0.0, z)),
            );
        }
    }
    for side in [-1.0f32, 1.0] {
        let z = side * ARCADE_Z;
        // Columns, both storeys.
        for k in 0..COLUMNS_PER_ROW {
            let x = column_x(k);
            h.put(
                lower_column,
                mat::STONE,
                Mat4::from_translation(Vec3::new(x, 0.0, z)),
            );
            h.put(
                upper_column,
                mat::STONE,
                Mat4::from_translation(Vec3::new(x, upper_base, z)),
            );
            // Pilasters on the outer wall, facing each column.
            h.block(
                cube,
                mat::PLASTER,
                Vec3::new(x - 0.3, 0.0, side * hz - 0.15 * (1.0 + side)),
                Vec3::new(x + 0.3, roof_lo, side * hz + 0.15 * (1.0 - side)),
            );
        }
        // Arches over every bay, both storeys, and the balustrade between upper columns.
        for b in 0..COLUMNS_PER_ROW - 1 {
            let x = bay_x(b);
            h.put(
                lower_arch,
                mat::STONE,
                Mat4::from_translation(Vec3::new(x, LOWER_COLUMN_HEIGHT, z)),
            );
            h.put(
                upper_arch,
                mat::STONE,
                Mat4::from_translation(Vec3::new(x, upper_spring, z)),
            );
            for m in 0..11 {
                let bx = column_x(b) + 0.5 + 0.3 * m as f32;
                h.put(
                    baluster,
                    mat::STONE,
                    Mat4::from_translation(Vec3::new(bx, upper_base, z)),
                );
            }
            h.block(
                cube,
                mat::STONE,
                Vec3::new(column_x(b) + 0.36, upper_base + 0.85, z - 0.08),
                Vec3::new(column_x(b + 1) - 0.36, upper_base + 0.97, z + 0.08),
            );
        }
        // Banners from the gallery's edge in every other bay, on the nave side of the arches,
        // facing the nave (the card faces +Z; turned half round on the +Z side).
        for b in (1..COLUMNS_PER_ROW - 1).step_by(2) {
            let top = GALLERY_Y - 0.15;
            h.put(
                banner,
                mat::BANNER,
                Mat4::from_translation(Vec3::new(
                    bay_x(b),
                    top - BANNER_SIZE.y,
                    side * (arch_z0 - 0.1),
                )) * Mat4::from_rotation_y(if side > 0.0 {
                    std::f32::consts::PI
                } else {
                    0.0
                }),
            );
        }
        // Spandrels between the end columns and the end walls.
        for end in [-1.0f32, 1.0] {
            let x0 = end * column_x(COLUMNS_PER_ROW - 1);
            let (xa, xb) = (x0.min(end * hx), x0.max(end * hx));
            for (y0, y1) in [(LOWER_COLUMN_HEIGHT, lower_top), (upper_spring, roof_lo)] {
                h.block(
                    cube,
                    mat::STONE,
                    Vec3::new(xa, y0, z - 0.5 * ARCH_DEPTH),
                    Vec3::new(xb, y1, z + 0.5 * ARCH_DEPTH),
                );
            }
        }
        // Gallery floor over the aisle and the aisle roof, in 8 m pieces.
        let (za, zb) = if side > 0.0 {
            (arch_z0, hz)
        } else {
            (-hz, -arch_z0)
        };
        let (ra, rb) = if side > 0.0 {
            (arch_z0 - 0.1, hz + WALL)
        } else {
            (-hz - WALL, -arch_z0 + 0.1)
        };
        for piece in 0..5 {
            let x0 = -hx + 8.0 * piece as f32;
            h.block(
                cube,
                mat::STONE,
                Vec3::new(x0, lower_top, za),
                Vec3::new(x0 + 8.0, upper_base, zb),
            );
            h.block(
                cube,
                mat::PLASTER,
                Vec3::new(x0, roof_lo, ra),
                Vec3::new(x0 + 8.0, HALL_HEIGHT, rb),
            );
            // Outer wall.
            let (wa, wb) = if side > 0.0 {
                (hz, hz + WALL)
            } else {
                (-hz - WALL, -hz)
            };
            let (xa, xb) = (
                x0 - if piece == 0 { WALL } else { 0.0 },
                x0 + 8.0 + if piece == 4 { WALL } else { 0.0 },
            );
            h.block(
                cube,
                mat::PLASTER,
                Vec3::new(xa, 0.0, wa),
                Vec3::new(xb, HALL_HEIGHT, wb),
            );
        }
    }
    // End walls with a round-headed doorway (3 m wide, 4.5 m high).
    for end in [-1.0f32, 1.0] {
        let (xa, xb) = if end > 0.0 {
            (hx, hx + WALL)
        } else {
            (-hx - WALL, -hx)
        };
        let xc = 0.5 * (xa + xb);
        h.block(
            cube,
            mat::PLASTER,
            Vec3::new(xa, 0.0, -hz),
            Vec3::new(xb, HALL_HEIGHT, -1.5),
        );
        h.block(
            cube,
            mat::PLASTER,
            Vec3::new(xa, 0.0, 1.5),
            Vec3::new(xb, HALL_HEIGHT, hz),
        );
        h.block(
            cube,
            mat::PLASTER,
            Vec3::new(xa, 5.0, -1.5),
            Vec3::new(xb, HALL_HEIGHT, 1.5),
        );
        h.put(
            door_arch,
            mat::PLASTER,
            Mat4::from_rotation_translation(
                Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
                Vec3::new(xc, 3.0, 0.0),
            ),
        );
    }
    // Props.
    h.put(fountain, mat::MARBLE, Mat4::IDENTITY);
    for (x, z) in [(3.2, 1.8), (3.2, -1.8), (-3.2, 1.8), (-3.2, -1.8)] {
        h.put(
            urn,
            mat::BRONZE,
            Mat4::from_translation(Vec3::new(x, 0.0, z)),
        );
    }
    for b in 0..COLUMNS_PER_ROW - 1 {
        for side in [-1.0f32, 1.0] {
            h.put(
                urn,
                mat::TERRACOTTA,
                Mat4::from_translation(Vec3::new(bay_x(b), 0.0, side * 6.9)),
            );
            if b % 2 == 1 {
                h.put(
                    urn,
                    mat::TERRACOTTA,
                    Mat4::from_translation(Vec3::new(bay_x(b), upper_base, side * 6.9)),
                );
            }
        }
    }
    for x in [-14.0f32, -10.0, -6.0, 6.0, 10.0, 14.0] {
        for side in [-1.0f32, 1.0] {
            let z = side * 2.6;
            h.block(
                cube,
                mat::WOOD,
                Vec3::new(x - 0.5, 0.0, z - 0.5),
                Vec3::new(x + 0.5, 0.5, z + 0.5),
            );
            h.put(
                bush,
                mat::FOLIAGE,
                Mat4::from_translation(Vec3::new(x, 0.85, z)),
            );
        }
    }
    // Spheres on pedestals near the doorways, crates in the end passages of the aisles.
    for (x, z) in [(-17.0, 2.2), (-17.0, -2.2), (17.0, 2.2), (17.0, -2.2)] {
        h.block(
            cube,
            mat::MARBLE,
            Vec3::new(x - 0.25, 0.0, z - 0.25),
            Vec3::new(x + 0.25, 1.0, z + 0.25),
        );
        h.put(
            ball,
            mat::BRONZE,
            Mat4::from_translation(Vec3::new(x, 1.3, z)),
        );
    }
    let mut rng = Rand::new(0xc4a7e5, 0);
    for end in [-1.0f32, 1.0] {
        for side in [-1.0f32, 1.0] {
            for _ in 0..3 {
                let s = rng.range(0.5, 0.9);
                let x = end * rng.range(18.6, 19.4);
                let z = side * rng.range(5.0, 7.2);
                let yaw = rng.range(-0.4, 0.4);
                h.put(
                    cube,
                    mat::WOOD,
                    Mat4::from_scale_rotation_translation(
                        Vec3::splat(s),
                        Quat::from_rotation_y(yaw),
                        Vec3::new(x, 0.5 * s, z),
                    ),
                );
            }
        }
    }

    let n = opts.lights.unwrap_or(DEFAULT_ATRIUM_LIGHTS);
    let mut camera = Camera::look_at(ATRIUM_CAMERA_POSITION, ATRIUM_CAMERA_TARGET);
    camera.far = 80.0;
    Scene {
        textures: vec![super::courtyard::banner_texture()],
        name: "atrium".into(),
        lights: layout_lights(
            n,
            opts.seed,
            opts.mix,
            opts.shadow_resolution,
            &lights::instance_boxes(&h.meshes, &h.instances),
        ),
        meshes: h.meshes,
        materials: materials(),
        instances: h.instances,
        camera,
        lighting: Default::default(),
        probes: if opts.default_probes {
            atrium_probes()
        } else {
            Vec::new()
        },
        animations: Default::default(),
    }
}

/// The atrium's reflection probes: one in the middle of each half of the nave, 3 m up (above
/// the shrubs, which would fill a lower probe's view of the floor's reflections), each
/// standing for its half of the hall (floor to roof, wall to wall).
pub fn atrium_probes() -> Vec<Probe> {
    let (hx, hz) = (0.5 * HALL_LENGTH, 0.5 * HALL_WIDTH);
    [-1.0f32, 1.0]
        .map(|side| {
            let lo = Vec3::new(if side < 0.0 { -hx } else { 0.0 }, 0.0, -hz);
            Probe::new(Vec3::new(side * 10.0, 3.0, 0.0), Vec3::ZERO)
                .with_box(lo, Vec3::new(hx, HALL_HEIGHT, HALL_WIDTH))
        })
        .to_vec()
}
