//! Lights: their kinds (directional with cascades, spot, point), Phong colours, distance
//! attenuation, shadow resolution and size (what softens their shadows), and the checks a
//! scene's lights must pass.

use glam::Vec3;

/// Distance attenuation `1 / (constant + linear·d + quadratic·d²)` (seed 004).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Attenuation {
    /// Constant term.
    pub constant: f32,
    /// Linear term (per world unit).
    pub linear: f32,
    /// Quadratic term (per world unit squared).
    pub quadratic: f32,
}

impl Attenuation {
    /// No fall-off with distance (used for directional lights).
    pub const NONE: Self = Self {
        constant: 1.0,
        linear: 0.0,
        quadratic: 0.0,
    };

    /// A common fit for a light of reach `range`: the attenuation is about 1/100 at `range`
    /// (linear 4.5/range, quadratic 75/range²), as in widely used tables for Phong lights.
    pub fn for_range(range: f32) -> Self {
        let r = range.max(1e-3);
        Self {
            constant: 1.0,
            linear: 4.5 / r,
            quadratic: 75.0 / (r * r),
        }
    }

    /// The attenuation factor at distance `d`.
    pub fn factor(&self, d: f32) -> f32 {
        1.0 / (self.constant + self.linear * d + self.quadratic * d * d).max(1e-6)
    }
}

/// The type-specific part of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Parallel rays, like the sun. Shadows by cascaded orthographic maps.
    Directional {
        /// Direction the light travels (from the light towards the scene), unit length.
        direction: Vec3,
        /// Number of shadow cascades, 1–4.
        cascades: u32,
        /// Split scheme blend: 0 = uniform splits, 1 = logarithmic (the "practical" scheme).
        split_lambda: f32,
        /// Resolution of each cascade relative to the previous one (seed 004: e.g. 0.5 gives
        /// 100 %, 50 %, 25 % of `shadow_resolution`); 1 = every cascade at full resolution.
        cascade_resolution_scale: f32,
    },
    /// A cone of light from a point.
    Spot {
        /// Light position.
        position: Vec3,
        /// Axis of the cone (from the light outwards), unit length.
        direction: Vec3,
        /// Half-angle of the cone in degrees (the angle between the axis and the cone's side).
        cutoff_deg: f32,
        /// Distance beyond which the light has no effect.
        range: f32,
    },
    /// Light in all directions from a point. Shadows by six cube-face views.
    Point {
        /// Light position.
        position: Vec3,
        /// Distance beyond which the light has no effect.
        range: f32,
    },
}

/// Largest magnitude of a world coordinate, a light's range or size (world units): the
/// shaders square distances in f32, which stays finite (and a position keeps some precision)
/// well inside this; a scene past it is refused rather than rendered as infinities.
pub const MAX_COORDINATE: f32 = 1e9;

/// Largest angular diameter of a directional light, degrees (a cone of 90° half-angle would
/// light from the whole hemisphere; soft-shadow filters are meant for the sun's half degree).
pub const MAX_ANGULAR_SIZE_DEG: f32 = 30.0;

/// A light source with Phong colours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Type and geometry.
    pub kind: LightKind,
    /// Ambient colour.
    pub ambient: Vec3,
    /// Diffuse colour.
    pub diffuse: Vec3,
    /// Specular colour.
    pub specular: Vec3,
    /// Distance attenuation (ignored for directional lights).
    pub attenuation: Attenuation,
    /// Whether the light casts shadows.
    pub casts_shadows: bool,
    /// Requested shadow-map resolution in texels (per face / per cascade); the renderer may
    /// shrink it to fit the atlas and says so.
    pub shadow_resolution: u32,
    /// The light's size, which softens its shadows: 0 is a point (hard shadows). A point
    /// light is a sphere of this radius and a spot light a disc of this radius facing along
    /// its direction (world units); a directional light is a cone of this angular diameter in
    /// degrees (the sun: about 0.53).
    pub size: f32,
}

impl Light {
    /// The smallest sphere `(centre, radius)` around everything the light reaches: the ball of
    /// its range for a point light, the sector (cone within its range) for a spot light;
    /// `None` for a directional light, which reaches everywhere.
    ///
    /// For a spot of half-angle θ and range R the sphere is centred on the axis: at
    /// `R / (2 cos θ)` with that radius when θ ≤ 45° (apex and rim on the sphere), else at
    /// `R cos θ` with radius `R sin θ` (the rim circle is its equator).
    pub fn bounding_sphere(&self) -> Option<(Vec3, f32)> {
        match self.kind {
            LightKind::Directional { .. } => None,
            LightKind::Point { position, range } => Some((position, range)),
            LightKind::Spot {
                position,
                direction,
                cutoff_deg,
                range,
            } => {
                let dir = direction.normalize_or(Vec3::NEG_Y);
                let theta = cutoff_deg.to_radians();
                if theta <= std::f32::consts::FRAC_PI_4 {
                    let r = range / (2.0 * theta.cos());
                    Some((position + dir * r, r))
                } else {
                    Some((position + dir * (range * theta.cos()), range * theta.sin()))
                }
            }
        }
    }

    /// Checks the light is usable (finite, positive ranges, sane angles and resolution); the
    /// reason names what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        validate_light(self)
    }

    /// A short name of the light's type: `"directional"`, `"spot"` or `"point"`.
    pub fn type_name(&self) -> &'static str {
        match self.kind {
            LightKind::Directional { .. } => "directional",
            LightKind::Spot { .. } => "spot",
            LightKind::Point { .. } => "point",
        }
    }
}

/// Why `l` is not a light the renderer can use (non-finite or out-of-range fields), if it is not.
pub(crate) fn validate_light(l: &Light) -> Result<(), String> {
    if !(l.ambient.is_finite() && l.diffuse.is_finite() && l.specular.is_finite()) {
        return Err("colours must be finite".into());
    }
    let a = l.attenuation;
    if !(a.constant.is_finite() && a.linear.is_finite() && a.quadratic.is_finite())
        || a.constant < 0.0
        || a.linear < 0.0
        || a.quadratic < 0.0
        || a.constant + a.linear + a.quadratic <= 0.0
    {
        return Err("attenuation terms must be finite, non-negative and not all zero".into());
    }
    if l.casts_shadows && !(1..=16384).contains(&l.shadow_resolution) {
        return Err(format!(
            "shadow_resolution {} must be between 1 and 16384",
            l.shadow_resolution
        ));
    }
    if !(l.size.is_finite() && l.size >= 0.0) {
        return Err(format!("size {} must be finite and >= 0", l.size));
    }
    if matches!(l.kind, LightKind::Directional { .. }) && l.size >= MAX_ANGULAR_SIZE_DEG {
        return Err(format!(
            "size {} of a directional light is an angular diameter in degrees and must be \
             below {MAX_ANGULAR_SIZE_DEG}",
            l.size
        ));
    }
    let unit = |v: Vec3, what: &str| -> Result<(), String> {
        if !v.is_finite() || v.length_squared() < 1e-12 {
            Err(format!("{what} must be a finite non-zero vector"))
        } else {
            Ok(())
        }
    };
    let range_ok = |r: f32| -> Result<(), String> {
        if r.is_finite() && r > 0.0 && r <= MAX_COORDINATE {
            Ok(())
        } else {
            Err(format!(
                "range {r} must be finite, > 0 and at most {MAX_COORDINATE:e}"
            ))
        }
    };
    let position_ok = |p: Vec3| -> Result<(), String> {
        if p.is_finite() && p.abs().max_element() <= MAX_COORDINATE {
            Ok(())
        } else {
            Err(format!(
                "position {p} must be finite, each coordinate at most {MAX_COORDINATE:e} in magnitude"
            ))
        }
    };
    if !matches!(l.kind, LightKind::Directional { .. }) && l.size > MAX_COORDINATE {
        return Err(format!(
            "size {} must be at most {MAX_COORDINATE:e}",
            l.size
        ));
    }
    match l.kind {
        LightKind::Directional {
            direction,
            cascades,
            split_lambda,
            cascade_resolution_scale,
        } => {
            if !(cascade_resolution_scale > 0.0 && cascade_resolution_scale <= 1.0) {
                return Err(format!(
                    "cascade_resolution_scale {cascade_resolution_scale} must be in (0, 1]"
                ));
            }
            unit(direction, "direction")?;
            if !(1..=4).contains(&cascades) {
                return Err(format!("cascades {cascades} must be 1 to 4"));
            }
            if !(0.0..=1.0).contains(&split_lambda) {
                return Err(format!("split_lambda {split_lambda} must be in 0..=1"));
            }
        }
        LightKind::Spot {
            position,
            direction,
            cutoff_deg,
            range,
        } => {
            position_ok(position)?;
            unit(direction, "direction")?;
            if !(cutoff_deg > 0.0 && cutoff_deg < 89.0) {
                return Err(format!(
                    "cutoff_deg {cutoff_deg} must be between 0 and 89 degrees (use a point light for wider cones)"
                ));
            }
            range_ok(range)?;
        }
        LightKind::Point { position, range } => {
            position_ok(position)?;
            range_ok(range)?;
        }
    }
    Ok(())
}
