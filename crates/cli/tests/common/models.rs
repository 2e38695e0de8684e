//! Pieces of the glTF models the browser tests write: physically lit scenes, glTF
//! metallic-roughness materials, lights in candela and lux.

use glam::Vec3;
use manyshadows_scene::{Attenuation, Camera, Light, LightKind, Lighting, Material, Pbr, Scene};

/// A light of `colour` (candela or lux per channel), inverse-square, casting no shadow.
pub fn light(kind: LightKind, colour: Vec3) -> Light {
    Light {
        kind,
        ambient: Vec3::ZERO,
        diffuse: colour,
        specular: colour,
        attenuation: Attenuation {
            constant: 0.0,
            linear: 0.0,
            quadratic: 1.0,
        },
        casts_shadows: false,
        shadow_resolution: 512,
        size: 0.0,
    }
}

/// A glTF metallic-roughness material of base colour `base`.
pub fn pbr(base: Vec3, metallic: f32, roughness: f32) -> Material {
    Material {
        diffuse: base,
        pbr: Some(Pbr {
            metallic,
            roughness,
        }),
        ..Material::default()
    }
}

/// An empty scene lit in physical units (glTF's), seen by `camera`.
pub fn physical(name: &str, camera: Camera) -> Scene {
    Scene {
        name: name.into(),
        lighting: Lighting::Physical,
        camera,
        ..Default::default()
    }
}
