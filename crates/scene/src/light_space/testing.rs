//! What the light-space unit tests share: a small deterministic generator, clip-space checks
//! and a test scene (a ground, a cube and a tall tower) with lights.

use glam::{Mat4, Vec3, Vec4};

use super::common::box_corners;
use crate::model::{Attenuation, Camera, Instance, Light, LightKind, Material, Mesh, Scene};

/// A small deterministic generator (xorshift64*), uniform in [0, 1).
pub(super) struct Rng(pub(super) u64);
impl Rng {
    pub(super) fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }
    pub(super) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    pub(super) fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if (0.01..=1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
}

pub(super) fn clip(m: Mat4, p: Vec3) -> Vec3 {
    let c = m * p.extend(1.0);
    assert!(
        c.w > 0.0,
        "point {p} is behind the projection (w = {})",
        c.w
    );
    c.truncate() / c.w
}

/// Inside the clip volume (xy in [-1, 1], depth in [0, 1]), with a small tolerance.
pub(super) fn in_clip(m: Mat4, p: Vec3, eps: f32) -> bool {
    let c: Vec4 = m * p.extend(1.0);
    if c.w <= 0.0 {
        return false;
    }
    let n = c.truncate() / c.w;
    n.x.abs() <= 1.0 + eps && n.y.abs() <= 1.0 + eps && n.z >= -eps && n.z <= 1.0 + eps
}

pub(super) fn light(kind: LightKind, resolution: u32) -> Light {
    Light {
        kind,
        ambient: Vec3::splat(0.1),
        diffuse: Vec3::ONE,
        specular: Vec3::ONE,
        attenuation: Attenuation::NONE,
        casts_shadows: true,
        shadow_resolution: resolution,
        size: 0.0,
    }
}

/// A mesh that is just the 8 corners of a box (bounds are all these tests need).
pub(super) fn box_mesh(lo: Vec3, hi: Vec3) -> Mesh {
    Mesh {
        name: "box".into(),
        positions: box_corners(lo, hi).to_vec(),
        normals: vec![Vec3::Y; 8],
        indices: vec![],
        uvs: vec![],
    }
}

/// A 100 × 100 ground (receiver only), a cube at the origin and a tall tower off to the
/// side (both casters), seen by a camera 10 units back and 5 up.
pub(super) fn test_scene(lights: Vec<Light>) -> Scene {
    let instance = |mesh, casts_shadows| Instance {
        mesh,
        material: 0,
        transform: Mat4::IDENTITY,
        casts_shadows,
    };
    Scene {
        textures: Vec::new(),
        name: "test".into(),
        meshes: vec![
            box_mesh(Vec3::new(-50.0, -0.1, -50.0), Vec3::new(50.0, 0.0, 50.0)),
            box_mesh(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0)),
            box_mesh(Vec3::new(30.0, 0.0, 30.0), Vec3::new(34.0, 60.0, 34.0)),
        ],
        materials: vec![Material::default()],
        instances: vec![instance(0, false), instance(1, true), instance(2, true)],
        lights,
        camera: Camera::look_at(Vec3::new(0.0, 5.0, 10.0), Vec3::ZERO),
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}

pub(super) fn sun(cascades: u32, resolution: u32) -> Light {
    light(
        LightKind::Directional {
            direction: Vec3::new(-0.4, -1.0, -0.3).normalize(),
            cascades,
            split_lambda: 0.7,
            cascade_resolution_scale: 1.0,
        },
        resolution,
    )
}
