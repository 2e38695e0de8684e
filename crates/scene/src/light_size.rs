//! How large lights are: the default size of the lights the built-in scenes and the seeded
//! layouts make ([`default_size`]), and [`LightSizes`], which overrides every light's size
//! (the CLI's `--light-size` and `--sun-size`).
//!
//! A light's [`size`](crate::model::Light::size) softens its shadows: a point light is a sphere
//! of that radius, a spot light a disc of that radius facing along its direction (world units),
//! a directional light a cone of that angular diameter in degrees; 0 is a point (hard shadows).
//!
//! **The default rule**: a spot or point light's radius is [`SIZE_PER_RANGE`] (2 %) of its
//! range, and a directional light is the sun, [`SUN_ANGULAR_DIAMETER_DEG`] (0.53°) across.
//! Why the range: it says how far a light is meant to reach, so the size follows the
//! neighbourhood the light is placed for, whatever the scene's scale or the light count: an
//! atrium arcade spot reaching 14 m is a 0.28 m lamp, a local light of a dense layout reaching
//! 1 m a 2 cm bulb. Their penumbrae are then a visible fraction of the shadows near the light
//! without blurring it out, and the size is a function of the light alone, so the same seed
//! still gives the same scene. The scenes that tests compare exactly (`cubes` and the analytic
//! `plane-*`) keep hard lights; lights read from files keep what the file says (0 when it says
//! nothing).

use crate::error::SceneError;
use crate::model::{Light, LightKind, MAX_ANGULAR_SIZE_DEG};

/// Radius of a built-in spot or point light as a fraction of its range.
pub const SIZE_PER_RANGE: f32 = 0.02;

/// Angular diameter of a built-in directional light, degrees: the sun's, seen from the earth.
pub const SUN_ANGULAR_DIAMETER_DEG: f32 = 0.53;

/// The size the built-in scenes and seeded layouts give a light of `kind` (see the module
/// docs): [`SIZE_PER_RANGE`] × range for a spot or point light, [`SUN_ANGULAR_DIAMETER_DEG`]
/// for a directional one.
pub fn default_size(kind: &LightKind) -> f32 {
    match *kind {
        LightKind::Directional { .. } => SUN_ANGULAR_DIAMETER_DEG,
        LightKind::Spot { range, .. } | LightKind::Point { range, .. } => SIZE_PER_RANGE * range,
    }
}

/// Sizes that replace every light's own: the radius of the spot and point lights and the
/// angular diameter of the directional ones, each kept as the light has it when `None`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightSizes {
    /// Radius of every spot and point light, world units; 0 makes them hard.
    pub radius: Option<f32>,
    /// Angular diameter of every directional light, degrees, below [`MAX_ANGULAR_SIZE_DEG`];
    /// 0 makes them hard.
    pub sun_deg: Option<f32>,
}

impl LightSizes {
    /// Every light a point: hard shadows.
    pub const HARD: Self = Self {
        radius: Some(0.0),
        sun_deg: Some(0.0),
    };

    /// Whether it changes nothing.
    pub fn is_none(&self) -> bool {
        self.radius.is_none() && self.sun_deg.is_none()
    }

    /// Checks the sizes a light may have: finite and ≥ 0, the angular diameter below
    /// [`MAX_ANGULAR_SIZE_DEG`]. Errors: [`SceneError::InvalidRequest`] naming the bad size.
    pub fn check(&self) -> Result<(), SceneError> {
        if let Some(r) = self.radius {
            if !(r.is_finite() && r >= 0.0) {
                return Err(SceneError::InvalidRequest(format!(
                    "light radius {r} must be a finite number >= 0 (world units; 0 = hard \
                     shadows)"
                )));
            }
        }
        if let Some(d) = self.sun_deg {
            if !(d.is_finite() && (0.0..MAX_ANGULAR_SIZE_DEG).contains(&d)) {
                return Err(SceneError::InvalidRequest(format!(
                    "sun size {d} must be an angular diameter in degrees, >= 0 and below \
                     {MAX_ANGULAR_SIZE_DEG} (the sun is {SUN_ANGULAR_DIAMETER_DEG}; 0 = hard \
                     shadows)"
                )));
            }
        }
        Ok(())
    }

    /// Sets the size of every light in `lights` that these sizes cover (unchecked: see
    /// [`check`](Self::check)).
    pub fn apply(&self, lights: &mut [Light]) {
        for l in lights {
            let size = match l.kind {
                LightKind::Directional { .. } => self.sun_deg,
                LightKind::Spot { .. } | LightKind::Point { .. } => self.radius,
            };
            if let Some(s) = size {
                l.size = s;
            }
        }
    }
}
