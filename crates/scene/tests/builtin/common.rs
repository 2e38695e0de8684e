//! What the built-in scene tests share: building a scene, light options and counting lights.

use glam::Vec3;
use manyshadows_scene::builtin::{self, BuiltinOptions};
use manyshadows_scene::{LightKind, Scene};

pub(crate) fn build(name: &str) -> Scene {
    builtin::build(name, &BuiltinOptions::default())
        .unwrap_or_else(|e| panic!("scene {name} failed to build: {e}"))
}

pub(crate) fn with_lights(n: usize) -> BuiltinOptions {
    BuiltinOptions {
        lights: Some(n),
        ..BuiltinOptions::default()
    }
}

pub(crate) fn count_types(scene: &Scene) -> (usize, usize, usize) {
    let mut c = (0, 0, 0);
    for l in &scene.lights {
        match l.kind {
            LightKind::Spot { .. } => c.0 += 1,
            LightKind::Point { .. } => c.1 += 1,
            LightKind::Directional { .. } => c.2 += 1,
        }
    }
    c
}

pub(crate) fn light_position(kind: &LightKind) -> Option<Vec3> {
    match *kind {
        LightKind::Spot { position, .. } | LightKind::Point { position, .. } => Some(position),
        LightKind::Directional { .. } => None,
    }
}
