//! The fly camera: W/A/S/D move it, Q/E down and up, at a speed the mouse wheel changes; the
//! right mouse button held and dragged turns it (yaw and pitch). A camera script's line or a
//! followed light places it instead.

use std::collections::HashSet;

use glam::Vec3;
use manyshadows::scene::{Camera, Light, LightKind};
use winit::event::MouseScrollDelta;
use winit::keyboard::KeyCode;

/// The camera and the input that moves it.
pub(super) struct FlyCamera {
    pub(super) camera: Camera,
    yaw: f32,
    pitch: f32,
    speed: f32,
    /// The keys held down.
    keys: HashSet<KeyCode>,
    /// The right mouse button is held: cursor moves turn the camera.
    pub(super) looking: bool,
    last_cursor: Option<(f64, f64)>,
}

impl FlyCamera {
    /// Starts at `camera`, looking where it looks, at a speed of its distance to its target
    /// per second.
    pub(super) fn new(camera: Camera) -> FlyCamera {
        let dir = (camera.target - camera.position).normalize();
        FlyCamera {
            camera,
            yaw: dir.x.atan2(-dir.z),
            pitch: dir.y.clamp(-1.0, 1.0).asin(),
            speed: (camera.target - camera.position).length().max(0.5),
            keys: Default::default(),
            looking: false,
            last_cursor: None,
        }
    }

    /// A key pressed or released.
    pub(super) fn key(&mut self, code: KeyCode, pressed: bool) {
        if pressed {
            self.keys.insert(code);
        } else {
            self.keys.remove(&code);
        }
    }

    /// The right mouse button pressed or released.
    pub(super) fn look(&mut self, pressed: bool) {
        self.looking = pressed;
        self.last_cursor = None;
    }

    /// The cursor moved to `(x, y)` while looking: turn by how far it went.
    pub(super) fn cursor_moved(&mut self, x: f64, y: f64) {
        if let Some((lx, ly)) = self.last_cursor {
            self.yaw += (x - lx) as f32 * 0.004;
            self.pitch = (self.pitch - (y - ly) as f32 * 0.004).clamp(-1.5, 1.5);
        }
        self.last_cursor = Some((x, y));
    }

    /// The wheel turned: 1.2 times faster (or slower) per line.
    pub(super) fn wheel(&mut self, delta: MouseScrollDelta) {
        let lines = match delta {
            MouseScrollDelta::LineDelta(_, y) => y,
            MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
        };
        self.speed = (self.speed * 1.2f32.powf(lines)).clamp(0.01, 1000.0);
    }

    /// Moves by the keys held for `dt` seconds, looking along yaw and pitch.
    pub(super) fn fly(&mut self, dt: f32) {
        let forward = Vec3::new(
            self.yaw.sin() * self.pitch.cos(),
            self.pitch.sin(),
            -self.yaw.cos() * self.pitch.cos(),
        );
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        let mut step = Vec3::ZERO;
        for (k, d) in [
            (KeyCode::KeyW, forward),
            (KeyCode::KeyS, -forward),
            (KeyCode::KeyD, right),
            (KeyCode::KeyA, -right),
            (KeyCode::KeyE, Vec3::Y),
            (KeyCode::KeyQ, -Vec3::Y),
        ] {
            if self.keys.contains(&k) {
                step += d;
            }
        }
        let dist = (self.camera.target - self.camera.position)
            .length()
            .max(0.1);
        self.camera.position += step.normalize_or_zero() * self.speed * dt;
        self.camera.target = self.camera.position + forward * dist;
    }

    /// A script's camera, `PX PY PZ TX TY TZ`.
    pub(super) fn place(&mut self, c: [f32; 6]) {
        self.camera.position = Vec3::new(c[0], c[1], c[2]);
        self.camera.target = Vec3::new(c[3], c[4], c[5]);
    }

    /// At `light`: a spot's view along its direction, a point light's along the camera's
    /// own; a directional light has no place to be, the camera stays.
    pub(super) fn follow(&mut self, light: &Light) {
        let forward = (self.camera.target - self.camera.position).normalize_or_zero();
        match light.kind {
            LightKind::Spot {
                position,
                direction,
                ..
            } => {
                self.camera.position = position;
                self.camera.target = position + direction;
            }
            LightKind::Point { position, .. } => {
                self.camera.position = position;
                self.camera.target = position + forward;
            }
            LightKind::Directional { .. } => {}
        }
    }
}
