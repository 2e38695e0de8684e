//! The analytic test scenes `plane-spot`, `plane-point` and `plane-directional`: a thin square
//! occluder over a floor, lit by exactly one light.
//!
//! Why: with one convex occluder over a plane the shadow's outline can be computed exactly
//! (project the occluder's silhouette from the light onto `y = 0`), so shadow tests can score
//! every technique against geometry instead of against another renderer. Every number the
//! tests need is a `pub const` here, so tests and scenes cannot drift apart.
//!
//! The occluder is a **thin box** of `2 × 0.02 × 2` m centred at `(0, 2, 0)`, not a single quad:
//! it has volume, so it casts a shadow whichever side the light is on and whatever the
//! technique's face culling. Its silhouette edges therefore lie at `y = 2 ± 0.01`; the exact
//! shadow on the floor is the projection of the whole box (for lights above it, the convex hull
//! of the projections of its top and bottom squares). The floor is one quad (subdivisions 1),
//! so its depth is exact in every map.

use glam::Vec3;

use super::lights::{Tone, AMBIENT_FRACTION};
use super::options::BuiltinOptions;
use crate::model::{Attenuation, Camera, Instance, Light, LightKind, Material, Scene};
use crate::primitives;

/// Edge length of the square floor, centred at the origin at `y = 0`.
pub const FLOOR_SIZE: f32 = 20.0;
/// Centre of the occluder box.
pub const OCCLUDER_CENTER: Vec3 = Vec3::new(0.0, 2.0, 0.0);
/// Half the occluder's edge length in X and Z (the square is 2 × 2 m).
pub const OCCLUDER_HALF_SIZE: f32 = 1.0;
/// The occluder's full thickness in Y (it spans `y = 2 − 0.01 .. 2 + 0.01`).
pub const OCCLUDER_THICKNESS: f32 = 0.02;
/// Camera position of the analytic scenes (straight above the occluder).
pub const ANALYTIC_CAMERA_POSITION: Vec3 = Vec3::new(0.0, 12.0, 0.001);
/// Camera target of the analytic scenes.
pub const ANALYTIC_CAMERA_TARGET: Vec3 = Vec3::ZERO;
/// Camera up vector of the analytic scenes: `−Z`, because the camera looks almost straight
/// down, where `+Y` would be (nearly) parallel to the view direction and is rejected by
/// [`Camera::validate`]. World `−Z` is the top of the image, `+X` its right.
pub const ANALYTIC_CAMERA_UP: Vec3 = Vec3::NEG_Z;
/// Camera vertical field of view in degrees.
pub const ANALYTIC_CAMERA_FOV_DEG: f32 = 60.0;
/// Camera near plane.
pub const ANALYTIC_CAMERA_NEAR: f32 = 0.1;
/// Camera far plane.
pub const ANALYTIC_CAMERA_FAR: f32 = 50.0;
/// Default shadow-map resolution of the analytic scenes (every light type).
pub const ANALYTIC_SHADOW_RESOLUTION: u32 = 1024;
/// `plane-spot`: light position.
pub const PLANE_SPOT_POSITION: Vec3 = Vec3::new(0.0, 6.0, 0.0);
/// `plane-spot`: cone axis.
pub const PLANE_SPOT_DIRECTION: Vec3 = Vec3::new(0.0, -1.0, 0.0);
/// `plane-spot`: cone half-angle in degrees.
pub const PLANE_SPOT_CUTOFF_DEG: f32 = 40.0;
/// `plane-spot`: range.
pub const PLANE_SPOT_RANGE: f32 = 20.0;
/// `plane-point`: light position.
pub const PLANE_POINT_POSITION: Vec3 = Vec3::new(1.5, 4.0, 1.0);
/// `plane-point`: range.
pub const PLANE_POINT_RANGE: f32 = 20.0;
/// `plane-directional`: the light's direction before normalisation; the light uses
/// [`plane_directional_direction`].
pub const PLANE_DIRECTIONAL_DIRECTION_RAW: Vec3 = Vec3::new(0.6, -1.0, 0.4);
/// `plane-directional`: cascade count.
pub const PLANE_DIRECTIONAL_CASCADES: u32 = 2;
/// `plane-directional`: cascade split blend.
pub const PLANE_DIRECTIONAL_SPLIT_LAMBDA: f32 = 0.5;
/// Mesh index of the floor in the analytic scenes.
pub const FLOOR_MESH: usize = 0;
/// Mesh index of the occluder in the analytic scenes.
pub const OCCLUDER_MESH: usize = 1;

/// `plane-directional`: the light's unit direction, `normalize(0.3, −1, 0.2)`.
pub fn plane_directional_direction() -> Vec3 {
    PLANE_DIRECTIONAL_DIRECTION_RAW.normalize()
}

/// The light of an analytic scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnalyticLight {
    /// `plane-spot`.
    Spot,
    /// `plane-point`.
    Point,
    /// `plane-directional`.
    Directional,
}

impl AnalyticLight {
    /// The scene name.
    pub fn scene_name(self) -> &'static str {
        match self {
            AnalyticLight::Spot => "plane-spot",
            AnalyticLight::Point => "plane-point",
            AnalyticLight::Directional => "plane-directional",
        }
    }

    /// The scene's one light, exactly as specified by the constants above.
    pub fn light(self, shadow_resolution: Option<u32>) -> Light {
        let resolution = shadow_resolution.unwrap_or(ANALYTIC_SHADOW_RESOLUTION);
        let tone = Tone {
            color: Vec3::ONE,
            brightness: 0.85,
        };
        // Bright enough directly under the light (the floor at y = 0).
        let (kind, attenuation) = match self {
            AnalyticLight::Spot => (
                LightKind::Spot {
                    position: PLANE_SPOT_POSITION,
                    direction: PLANE_SPOT_DIRECTION,
                    cutoff_deg: PLANE_SPOT_CUTOFF_DEG,
                    range: PLANE_SPOT_RANGE,
                },
                Attenuation::for_range(PLANE_SPOT_RANGE),
            ),
            AnalyticLight::Point => (
                LightKind::Point {
                    position: PLANE_POINT_POSITION,
                    range: PLANE_POINT_RANGE,
                },
                Attenuation::for_range(PLANE_POINT_RANGE),
            ),
            AnalyticLight::Directional => (
                LightKind::Directional {
                    direction: plane_directional_direction(),
                    cascades: PLANE_DIRECTIONAL_CASCADES,
                    split_lambda: PLANE_DIRECTIONAL_SPLIT_LAMBDA,
                    cascade_resolution_scale: 1.0,
                },
                Attenuation::NONE,
            ),
        };
        let key = match kind {
            LightKind::Spot { position, .. } | LightKind::Point { position, .. } => position.y,
            LightKind::Directional { .. } => 0.0,
        };
        let gain = tone.brightness / attenuation.factor(key);
        Light {
            kind,
            ambient: tone.color * (AMBIENT_FRACTION * gain),
            diffuse: tone.color * gain,
            specular: tone.color * (0.5 * gain),
            attenuation,
            casts_shadows: true,
            shadow_resolution: resolution,
            // A point: the exact outline is that of a hard shadow.
            size: 0.0,
        }
    }
}

/// The camera of the analytic scenes.
pub fn analytic_camera() -> Camera {
    Camera {
        position: ANALYTIC_CAMERA_POSITION,
        target: ANALYTIC_CAMERA_TARGET,
        up: ANALYTIC_CAMERA_UP,
        fov_y_deg: ANALYTIC_CAMERA_FOV_DEG,
        near: ANALYTIC_CAMERA_NEAR,
        far: ANALYTIC_CAMERA_FAR,
    }
}

/// Builds an analytic scene. `opts.lights`, `opts.mix`, `opts.seed` and `opts.mesh` are
/// ignored: the scene is exactly one light over the fixed geometry.
pub(crate) fn build(which: AnalyticLight, opts: &BuiltinOptions) -> Scene {
    let floor = primitives::plane(FLOOR_SIZE, FLOOR_SIZE, 1);
    let occluder = primitives::cuboid(Vec3::new(
        2.0 * OCCLUDER_HALF_SIZE,
        OCCLUDER_THICKNESS,
        2.0 * OCCLUDER_HALF_SIZE,
    ));
    let mut floor = floor;
    floor.name = "floor".into();
    let mut occluder = occluder;
    occluder.name = "occluder".into();
    Scene {
        textures: Vec::new(),
        name: which.scene_name().into(),
        meshes: vec![floor, occluder],
        materials: vec![
            Material::matte(Vec3::splat(0.85)),
            Material::matte(Vec3::new(0.75, 0.3, 0.2)),
        ],
        instances: vec![
            Instance::caster(FLOOR_MESH, 0, glam::Mat4::IDENTITY),
            Instance::caster(
                OCCLUDER_MESH,
                1,
                glam::Mat4::from_translation(OCCLUDER_CENTER),
            ),
        ],
        lights: vec![which.light(opts.shadow_resolution)],
        camera: analytic_camera(),
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}
