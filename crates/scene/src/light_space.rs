//! Light-space maths: every view-projection a shadow technique must fill.
//!
//! Seed 004 gives the three light types their projections, and this module follows it:
//!
//! - a **spot light** is one perspective view along its axis, its near and far planes pulled in
//!   as tight as the light allows ("the far plane can be decreased to match the light's area of
//!   influence"): far = the light's range;
//! - a **point light** is six cube-face views. Read the seed's 45° as the half-angle: each
//!   face's full field of view is **90°**, the only angle at which six frusta tile the sphere
//!   with no gaps and no overlaps;
//! - a **directional light** is orthographic, and, after the seed's terrain-renderer post,
//!   **cascaded**: the camera frustum is cut into slices (the practical split scheme,
//!   λ·logarithmic + (1−λ)·uniform) and each slice gets its own map, so texels near the camera
//!   are small and texels far away are large. One cascade is the plain single-map fallback.
//!
//! The trade-offs chosen here, and why:
//!
//! - **Near planes** are `max(range·0.002, 0.01)` ([`LIGHT_NEAR_FRACTION`], [`LIGHT_NEAR_MIN`]):
//!   a far/near ratio of 500 keeps depth precision usable across the whole range while clipping
//!   only occluders closer than 0.2 % of the range to the light.
//! - **Maps are a little wider than what they must cover**: [`PCF_MARGIN_TEXELS`] texels on
//!   every side of a spot cone and of a cascade's sphere (plus half a texel for snapping), so
//!   a 3×3 PCF kernel centred on the edge still reads inside the map.
//! - **Cascades are fitted with a bounding sphere, not a tight box.** A sphere's size does not
//!   change when the camera turns, so the texel size stays constant and the map's origin can be
//!   **snapped to whole texels**: shadows stay still instead of shimmering as the camera moves.
//!   The price is resolution (the sphere wastes the corners of the map). The sphere is the
//!   smallest one around the slice (centre on the view axis), its radius rounded up to 1/16 of
//!   its octave so float noise cannot change the texel size from frame to frame.
//! - **Cascades cover only the depth range the scene occupies**: the camera's near/far are
//!   clamped to the view depths of the scene's world bounds ([`view_depth_range`]), so no
//!   cascade is spent on empty space past the last object (or before the first).
//! - **Cascade depth ranges reach every shadow caster** in the scene's bounds, so an occluder
//!   outside a slice (a tall tower behind the camera) still casts into it.
//!
//! Conventions everywhere: right-handed views looking down −Z, wgpu clip depth 0..1, standard
//! depth (near → 0, far → 1, depth test `Less`).

use glam::{Mat4, Vec3, Vec4};

use crate::model::{Camera, LightKind, Scene};

/// Near plane of a spot or point light's projection, as a fraction of the light's range.
pub const LIGHT_NEAR_FRACTION: f32 = 0.002;

/// Smallest near plane of a spot or point light's projection, in world units.
pub const LIGHT_NEAR_MIN: f32 = 0.01;

/// Texels kept free around a spot cone and around a cascade's sphere so that a 3×3 PCF kernel
/// centred on the edge of what the map must cover still reads inside the map.
pub const PCF_MARGIN_TEXELS: f32 = 1.5;

/// Texels reserved around a cascade's sphere for snapping its centre to the texel grid
/// (rounding moves the centre by at most half a texel).
const SNAP_MARGIN_TEXELS: f32 = 0.5;

/// A cascade's radius is rounded up to a multiple of 1/`RADIUS_STEPS_PER_OCTAVE` of the power of
/// two below it (so at most 6.25 % of resolution is given up for a texel size that stays put).
const RADIUS_STEPS_PER_OCTAVE: f32 = 16.0;

/// Widest half field of view a spot map may get (the projection degenerates at 90°).
const MAX_SPOT_HALF_FOV_DEG: f32 = 89.5;

/// The six cube faces of a point light as `(look direction, up)`, in the order +X, −X, +Y,
/// −Y, +Z, −Z, with the cube-map up vectors of D3D, Vulkan and OpenGL.
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// Which part of a light a shadow view covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewKind {
    /// The single perspective view of a spot light.
    Spot,
    /// Cube face `0..6` of a point light, in the order +X, −X, +Y, −Y, +Z, −Z.
    CubeFace(u8),
    /// Cascade `0..count` of a directional light, nearest first.
    Cascade(u8),
    /// Hemisphere `0` (towards +Y) or `1` (towards −Y) of a point light's dual-paraboloid map.
    /// Its `view` looks down −Z at the hemisphere's pole; `proj` is the identity because the
    /// paraboloid warp is not a matrix (see [`paraboloid_project`]).
    Paraboloid(u8),
}

/// How point lights are shadowed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PointShadows {
    /// Six perspective cube faces of 90°.
    #[default]
    Cube,
    /// Two paraboloid hemispheres (seed 003), each map twice the light's per-face resolution
    /// so the texel at a hemisphere's pole matches a cube face's centre texel.
    DualParaboloid,
}

impl PointShadows {
    /// Both modes.
    pub const ALL: &'static [PointShadows] = &[PointShadows::Cube, PointShadows::DualParaboloid];

    /// CLI name.
    pub fn name(self) -> &'static str {
        match self {
            PointShadows::Cube => "cube",
            PointShadows::DualParaboloid => "dual-paraboloid",
        }
    }
}

impl std::str::FromStr for PointShadows {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        PointShadows::ALL
            .iter()
            .copied()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!("unknown point-shadow mode '{s}' (expected cube or dual-paraboloid)")
            })
    }
}

/// The paraboloid warp of a world point for a hemisphere view: `(x, y, depth, front)` where
/// `x, y` in −1..1 cover the hemisphere (the unit disk), `depth = (d − near)/(far − near)` of
/// the distance `d` to the light, and `front = −z/d` (≥ 0 inside the hemisphere). Matches
/// `paraboloid_clip` in the renderer's WGSL.
pub fn paraboloid_project(view: Mat4, near: f32, far: f32, p: Vec3) -> Vec4 {
    let v = view.transform_point3(p);
    let d = v.length();
    let n = v / d.max(1e-20);
    let front = -n.z;
    let k = 1.0 / (1.0 + front).max(1e-3);
    Vec4::new(n.x * k, n.y * k, (d - near) / (far - near), front)
}

/// The two hemisphere views of a point light: `(views, near, far)`, hemisphere 0 looking
/// towards +Y, 1 towards −Y.
pub fn paraboloid_views(position: Vec3, range: f32) -> ([Mat4; 2], f32, f32) {
    let (near, far) = light_depth_range(range);
    let views = [Vec3::Y, Vec3::NEG_Y].map(|dir| Mat4::look_to_rh(position, dir, Vec3::Z));
    (views, near, far)
}

/// The six planes `(normal, d)` (`normal·p + d ≥ 0` inside, normals unit length) of a
/// view-projection's frustum in wgpu clip space (depth 0..1).
pub fn frustum_planes(view_proj: Mat4) -> [Vec4; 6] {
    let r0 = view_proj.row(0);
    let r1 = view_proj.row(1);
    let r2 = view_proj.row(2);
    let r3 = view_proj.row(3);
    let planes = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2];
    planes.map(|p| {
        let len = p.truncate().length();
        if len > 0.0 {
            p / len
        } else {
            p
        }
    })
}

/// True if a sphere is at least partly inside the frustum given by [`frustum_planes`].
pub fn sphere_in_planes(planes: &[Vec4; 6], center: Vec3, radius: f32) -> bool {
    planes
        .iter()
        .all(|p| p.truncate().dot(center) + p.w >= -radius)
}

impl ShadowView {
    /// True if a world-space sphere may cover part of this view (conservative).
    pub fn sphere_visible(&self, center: Vec3, radius: f32) -> bool {
        match self.kind {
            ViewKind::Paraboloid(_) => {
                let inv = self.view.inverse();
                let eye = inv.w_axis.truncate();
                let axis = inv.transform_vector3(Vec3::NEG_Z);
                let d = center - eye;
                let dist = d.length();
                dist - radius <= self.far && dist + radius >= self.near && d.dot(axis) >= -radius
            }
            _ => sphere_in_planes(&frustum_planes(self.view_proj), center, radius),
        }
    }
}

/// One view-projection that a shadow technique renders into one atlas tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowView {
    /// Index of the light in [`Scene::lights`].
    pub light: usize,
    /// Which part of the light this view covers.
    pub kind: ViewKind,
    /// World → light view.
    pub view: Mat4,
    /// Light view → clip (wgpu conventions: depth 0..1, right-handed view looking down −Z).
    pub proj: Mat4,
    /// `proj * view`.
    pub view_proj: Mat4,
    /// Near plane distance of the projection (light view space).
    pub near: f32,
    /// Far plane distance of the projection (light view space).
    pub far: f32,
    /// True for orthographic projections (directional cascades).
    pub orthographic: bool,
    /// Texel resolution of the square tile this view wants.
    pub resolution: u32,
    /// For cascades: camera view-space distance at which this cascade ends (the lighting pass
    /// picks the first cascade whose `split_far` exceeds the pixel's depth). 0 otherwise.
    pub split_far: f32,
    /// World-space size of one texel: for orthographic views the texel width; for
    /// perspective views the texel width at distance 1 from the light (multiply by distance).
    pub texel_world: f32,
}

/// The orthographic fit of one directional-light cascade (see [`directional_fit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalFit {
    /// World → light view (a rotation, then a translation that is a whole number of texels
    /// across the light's direction).
    pub view: Mat4,
    /// Light view → clip, orthographic, symmetric about the view axis.
    pub proj: Mat4,
    /// Near plane distance (light view space).
    pub near: f32,
    /// Far plane distance (light view space).
    pub far: f32,
    /// World-space width of one texel.
    pub texel_world: f32,
}

/// Near and far planes of a spot or point light of reach `range`: `near = max(range·0.002,
/// 0.01)` (but at most half the range, for absurdly short lights), `far = range`.
pub fn light_depth_range(range: f32) -> (f32, f32) {
    let near = (range * LIGHT_NEAR_FRACTION)
        .max(LIGHT_NEAR_MIN)
        .min(range * 0.5);
    (near, range)
}

/// A world axis that is not (nearly) parallel to `dir`: +Y, or +Z when `dir` is within about
/// 8° of vertical. Used as the up vector of light views.
pub fn stable_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// Half field of view (radians) of a spot light's map: the cone's half-angle widened so that
/// [`PCF_MARGIN_TEXELS`] texels lie outside the cone on every side, i.e.
/// `tan(half) = tan(cutoff) · res / (res − 3)`. Tiny maps (≤ 6 texels) give at most a quarter
/// of the map on each side to the margin.
pub fn spot_half_fov(cutoff_deg: f32, resolution: u32) -> f32 {
    let max_half = MAX_SPOT_HALF_FOV_DEG.to_radians();
    let cutoff = cutoff_deg.to_radians().clamp(1e-4, max_half);
    let res = resolution.max(1) as f32;
    let usable = (res - 2.0 * PCF_MARGIN_TEXELS).max(0.5 * res);
    (cutoff.tan() * res / usable).atan().min(max_half)
}

/// Perspective view of a spot light: field of view 2·cutoff (plus a small margin so PCF at the
/// cone's edge stays inside), near/far hugging the light's range.
///
/// Returns `(view, proj, near, far)`. The field of view is `2 ·` [`spot_half_fov`], the aspect
/// 1, the planes those of [`light_depth_range`], the up vector [`stable_up`].
pub fn spot_view(
    position: Vec3,
    direction: Vec3,
    cutoff_deg: f32,
    range: f32,
    resolution: u32,
) -> (Mat4, Mat4, f32, f32) {
    let dir = direction.try_normalize().unwrap_or(Vec3::NEG_Z);
    let (near, far) = light_depth_range(range);
    let view = Mat4::look_to_rh(position, dir, stable_up(dir));
    let proj = Mat4::perspective_rh(2.0 * spot_half_fov(cutoff_deg, resolution), 1.0, near, far);
    (view, proj, near, far)
}

/// The six 90° cube-face views of a point light (+X, −X, +Y, −Y, +Z, −Z) with the cube-map up
/// vectors, and the shared projection; returns `(views, proj, near, far)`.
///
/// Every direction from the light lies in the frustum of the face of its major axis (see
/// [`cube_face_for`]). Note that a right-handed look-at with the cube-map up vectors renders
/// each face flipped vertically relative to a cube texture's texel layout: the up vector's
/// side lands on clip +Y, wgpu's top row, where the cube-map convention (made for GL's
/// bottom-up framebuffer) puts it on the bottom row. That does not matter here: faces live in
/// atlas tiles and are always read back through the same `view_proj`, never sampled as a cube
/// texture.
pub fn cube_face_views(position: Vec3, range: f32) -> ([Mat4; 6], Mat4, f32, f32) {
    let (near, far) = light_depth_range(range);
    let views = CUBE_FACES.map(|(dir, up)| Mat4::look_to_rh(position, dir, up));
    let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far);
    (views, proj, near, far)
}

/// The cube face (index into [`CUBE_FACES`]) whose frustum holds direction `v` from the
/// light: the face of `v`'s major axis (ties go to X, then Y).
pub fn cube_face_for(v: Vec3) -> u8 {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        if v.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if v.y >= 0.0 {
            2
        } else {
            3
        }
    } else if v.z >= 0.0 {
        4
    } else {
        5
    }
}

/// Cascade split distances `count + 1` values from `near` to `far`: the practical scheme,
/// λ·logarithmic + (1−λ)·uniform.
///
/// `split_i = λ·near·(far/near)^(i/n) + (1−λ)·(near + (far−near)·i/n)`; the first value is
/// `near` and the last `far`, exactly. A `count` of 0 is treated as 1; `near` must be > 0 for
/// the logarithmic part (a smaller value is raised to 1e-6 in it).
pub fn cascade_splits(near: f32, far: f32, count: u32, lambda: f32) -> Vec<f32> {
    let n = count.max(1);
    let log_near = near.max(1e-6);
    let ratio = far / log_near;
    let mut splits: Vec<f32> = (0..=n)
        .map(|i| {
            let t = i as f32 / n as f32;
            let log = log_near * ratio.powf(t);
            let uniform = near + (far - near) * t;
            lambda * log + (1.0 - lambda) * uniform
        })
        .collect();
    splits[0] = near;
    splits[n as usize] = far;
    splits
}

/// The camera view depths (distance along the view axis) that hold geometry: the camera's
/// `(near, far)` clamped to the nearest and farthest view depth of the corners of `bounds`
/// (the scene's world bounds). Falls back to the camera's own planes when there is no geometry
/// or none of it lies between them.
///
/// Cascades are split over this range so that none is spent on empty space beyond the last
/// object (or, with the camera outside the scene, before the first).
pub fn view_depth_range(camera: &Camera, bounds: Option<(Vec3, Vec3)>) -> (f32, f32) {
    let (near, far) = (camera.near, camera.far);
    let Some((lo, hi)) = bounds else {
        return (near, far);
    };
    let view = camera.view();
    let (dmin, dmax) = box_corners(lo, hi)
        .iter()
        .map(|&c| -view.transform_point3(c).z)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), d| {
            (a.min(d), b.max(d))
        });
    let (near_eff, far_eff) = (dmin.max(near), dmax.min(far));
    if far_eff > near_eff && far_eff.is_finite() {
        (near_eff, far_eff)
    } else {
        (near, far)
    }
}

/// The 8 world-space corners of the slice of the camera frustum between view depths `near`
/// and `far` (`aspect` = width / height): near corners first, each as (−x −y, +x −y, −x +y,
/// +x +y).
pub fn frustum_slice_corners(camera: &Camera, aspect: f32, near: f32, far: f32) -> [Vec3; 8] {
    let inv_view = camera.view().inverse();
    let tan_y = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let tan_x = tan_y * aspect;
    std::array::from_fn(|i| {
        let d = if i < 4 { near } else { far };
        let sx = if i & 1 == 0 { -1.0 } else { 1.0 };
        let sy = if i & 2 == 0 { -1.0 } else { 1.0 };
        inv_view.transform_point3(Vec3::new(sx * tan_x * d, sy * tan_y * d, -d))
    })
}

/// The smallest sphere around the slice of the camera frustum between view depths `near` and
/// `far`, as `(world centre, radius)`, the radius rounded up to 1/16 of its octave.
///
/// It is computed in camera view space, where it depends only on the field of view, `aspect`
/// and the two depths, so it is exactly the same size however the camera moves or turns. By
/// symmetry its centre is on the view axis, at the depth where the near and far corners are
/// equally far away (or on the far plane when that is nearer).
pub fn slice_bounding_sphere(camera: &Camera, aspect: f32, near: f32, far: f32) -> (Vec3, f32) {
    let tan_y = (camera.fov_y_deg.to_radians() * 0.5).tan();
    // Squared corner distance from the axis per unit depth.
    let k2 = tan_y * tan_y * (1.0 + aspect * aspect);
    let depth = (0.5 * (near + far) * (1.0 + k2)).min(far);
    let to_near = ((depth - near).powi(2) + k2 * near * near).sqrt();
    let to_far = ((far - depth).powi(2) + k2 * far * far).sqrt();
    let radius = round_up_radius(to_near.max(to_far));
    let centre = camera
        .view()
        .inverse()
        .transform_point3(Vec3::new(0.0, 0.0, -depth));
    (centre, radius)
}

/// Rounds `r` up to a multiple of 1/16 of the power of two at or below it.
fn round_up_radius(r: f32) -> f32 {
    if !(r > 0.0 && r.is_finite()) {
        return 1.0;
    }
    let step = r.log2().floor().exp2() / RADIUS_STEPS_PER_OCTAVE;
    (r / step).ceil() * step
}

/// Orthographic fit of a directional light (travelling along `direction`) around the sphere
/// `(centre, radius)`, its depth range stretched to hold every corner of `casters` (the
/// world bounds of the shadow casters, if any).
///
/// The map is `2·half` wide, with `half = radius · res / (res − 4)`: two texels on each side
/// beyond the sphere, half a texel for snapping and [`PCF_MARGIN_TEXELS`] for filtering. The
/// light's rotation depends only on `direction`; the sphere's centre, in light space, is
/// rounded to whole texels across the light, so a world point's texel moves by whole texels
/// when the camera moves and the shadow's edges do not crawl. Tiny maps (≤ 8 texels) give at
/// most a quarter of the map on each side to the margin.
pub fn directional_fit(
    direction: Vec3,
    centre: Vec3,
    radius: f32,
    casters: Option<(Vec3, Vec3)>,
    resolution: u32,
) -> DirectionalFit {
    let dir = direction.try_normalize().unwrap_or(Vec3::NEG_Y);
    let rotation = Mat4::look_to_rh(Vec3::ZERO, dir, stable_up(dir));
    let res = resolution.max(1) as f32;
    let usable = (res - 2.0 * (SNAP_MARGIN_TEXELS + PCF_MARGIN_TEXELS)).max(0.5 * res);
    let half = radius * res / usable;
    let texel = 2.0 * half / res;

    let c = rotation.transform_point3(centre);
    let (cx, cy) = ((c.x / texel).round() * texel, (c.y / texel).round() * texel);

    // Depths along the light's direction (`dot(p, dir)`, which is −z after `rotation`).
    let mut dmin = -c.z - radius;
    let mut dmax = -c.z + radius;
    if let Some((lo, hi)) = casters {
        for corner in box_corners(lo, hi) {
            let d = corner.dot(dir);
            dmin = dmin.min(d);
            dmax = dmax.max(d);
        }
    }
    // Slack against rounding, relative to the range and to the distance from the origin.
    let pad = 1e-3 * (dmax - dmin) + 1e-5 * dmin.abs().max(dmax.abs()) + 1e-4;
    // The eye sits `2·pad` before the nearest depth; the planes are `pad` outside the range.
    let eye = dmin - 2.0 * pad;
    let view = Mat4::from_translation(Vec3::new(-cx, -cy, eye)) * rotation;
    let (near, far) = (pad, dmax - eye + pad);
    let proj = Mat4::orthographic_rh(-half, half, -half, half, near, far);
    DirectionalFit {
        view,
        proj,
        near,
        far,
        texel_world: texel,
    }
}

/// Every shadow view of every shadow-casting light in `scene`, in light order (a spot light
/// gives 1 view, a point light 6, a directional light one per cascade), each with the light's
/// requested resolution. `aspect` is the camera image's width / height.
///
/// Directional cascades split the depth range of [`view_depth_range`] with
/// [`cascade_splits`], fit each slice with [`slice_bounding_sphere`] and [`directional_fit`]
/// (depth range reaching every caster in `scene.world_bounds(true)`). With no geometry at all
/// they cover the camera's own near..far.
pub fn shadow_views(scene: &Scene, aspect: f32) -> Vec<ShadowView> {
    shadow_views_with(scene, aspect, PointShadows::Cube)
}

/// [`shadow_views`] with a choice of point-light shadows.
pub fn shadow_views_with(scene: &Scene, aspect: f32, points: PointShadows) -> Vec<ShadowView> {
    let aspect = if aspect.is_finite() && aspect > 0.0 {
        aspect
    } else {
        1.0
    };
    let has_directional = scene
        .lights
        .iter()
        .any(|l| l.casts_shadows && matches!(l.kind, LightKind::Directional { .. }));
    // Only directional lights need the (O(instances)) scene bounds.
    let (depth_range, casters) = if has_directional {
        (
            view_depth_range(&scene.camera, scene.world_bounds(false)),
            scene.world_bounds(true),
        )
    } else {
        ((scene.camera.near, scene.camera.far), None)
    };

    let mut out = Vec::new();
    for (index, light) in scene.lights.iter().enumerate() {
        if !light.casts_shadows {
            continue;
        }
        let resolution = light.shadow_resolution;
        let perspective = |kind, view, proj: Mat4, near, far| ShadowView {
            light: index,
            kind,
            view,
            proj,
            view_proj: proj * view,
            near,
            far,
            orthographic: false,
            resolution,
            split_far: 0.0,
            // proj.y_axis.y = 1 / tan(half fov).
            texel_world: 2.0 / (proj.y_axis.y * resolution.max(1) as f32),
        };
        match light.kind {
            LightKind::Spot {
                position,
                direction,
                cutoff_deg,
                range,
            } => {
                let (view, proj, near, far) =
                    spot_view(position, direction, cutoff_deg, range, resolution);
                out.push(perspective(ViewKind::Spot, view, proj, near, far));
            }
            LightKind::Point { position, range } if points == PointShadows::DualParaboloid => {
                let (views, near, far) = paraboloid_views(position, range);
                let resolution = resolution.saturating_mul(2).max(1);
                for (h, view) in views.into_iter().enumerate() {
                    out.push(ShadowView {
                        light: index,
                        kind: ViewKind::Paraboloid(h as u8),
                        view,
                        proj: Mat4::IDENTITY,
                        view_proj: view,
                        near,
                        far,
                        orthographic: false,
                        resolution,
                        split_far: 0.0,
                        // Largest texel, at the pole: 2 NDC units span 4 world units at
                        // distance 1 there (x = v/(1+1)).
                        texel_world: 4.0 / resolution as f32,
                    });
                }
            }
            LightKind::Point { position, range } => {
                let (views, proj, near, far) = cube_face_views(position, range);
                for (face, view) in views.into_iter().enumerate() {
                    out.push(perspective(
                        ViewKind::CubeFace(face as u8),
                        view,
                        proj,
                        near,
                        far,
                    ));
                }
            }
            LightKind::Directional {
                direction,
                cascades,
                split_lambda,
                cascade_resolution_scale,
            } => {
                let count = cascades.clamp(1, u8::MAX as u32);
                let splits = cascade_splits(depth_range.0, depth_range.1, count, split_lambda);
                for (i, pair) in splits.windows(2).enumerate() {
                    // Per-cascade resolution (seed 004): each cascade `scale` times the last.
                    let resolution = ((resolution as f32
                        * cascade_resolution_scale
                            .clamp(f32::MIN_POSITIVE, 1.0)
                            .powi(i as i32))
                    .round() as u32)
                        .max(1);
                    let (centre, radius) =
                        slice_bounding_sphere(&scene.camera, aspect, pair[0], pair[1]);
                    let fit = directional_fit(direction, centre, radius, casters, resolution);
                    out.push(ShadowView {
                        light: index,
                        kind: ViewKind::Cascade(i as u8),
                        view: fit.view,
                        proj: fit.proj,
                        view_proj: fit.proj * fit.view,
                        near: fit.near,
                        far: fit.far,
                        orthographic: true,
                        resolution,
                        split_far: pair[1],
                        texel_world: fit.texel_world,
                    });
                }
            }
        }
    }
    out
}

/// The 8 corners of the box `lo..hi`.
fn box_corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Attenuation, Instance, Light, Material, Mesh};
    use glam::Vec4;

    /// A small deterministic generator (xorshift64*), uniform in [0, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
        fn unit_vector(&mut self) -> Vec3 {
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

    fn clip(m: Mat4, p: Vec3) -> Vec3 {
        let c = m * p.extend(1.0);
        assert!(
            c.w > 0.0,
            "point {p} is behind the projection (w = {})",
            c.w
        );
        c.truncate() / c.w
    }

    /// Inside the clip volume (xy in [-1, 1], depth in [0, 1]), with a small tolerance.
    fn in_clip(m: Mat4, p: Vec3, eps: f32) -> bool {
        let c: Vec4 = m * p.extend(1.0);
        if c.w <= 0.0 {
            return false;
        }
        let n = c.truncate() / c.w;
        n.x.abs() <= 1.0 + eps && n.y.abs() <= 1.0 + eps && n.z >= -eps && n.z <= 1.0 + eps
    }

    fn light(kind: LightKind, resolution: u32) -> Light {
        Light {
            kind,
            ambient: Vec3::splat(0.1),
            diffuse: Vec3::ONE,
            specular: Vec3::ONE,
            attenuation: Attenuation::NONE,
            casts_shadows: true,
            shadow_resolution: resolution,
        }
    }

    /// A mesh that is just the 8 corners of a box (bounds are all these tests need).
    fn box_mesh(lo: Vec3, hi: Vec3) -> Mesh {
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
    fn test_scene(lights: Vec<Light>) -> Scene {
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
        }
    }

    #[test]
    fn cascades_can_halve_their_resolution_one_after_another() {
        let mut scene = test_scene(vec![sun(3, 1024)]);
        if let LightKind::Directional {
            cascade_resolution_scale,
            ..
        } = &mut scene.lights[0].kind
        {
            *cascade_resolution_scale = 0.5;
        }
        let views = shadow_views(&scene, 1.5);
        let res: Vec<u32> = views.iter().map(|v| v.resolution).collect();
        assert_eq!(res, vec![1024, 512, 256]);
        // A coarser cascade covers the same slice with bigger texels.
        assert!(views[1].texel_world > views[0].texel_world);
    }

    fn sun(cascades: u32, resolution: u32) -> Light {
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

    #[test]
    fn spot_frustum_holds_the_cone_within_range_and_nothing_else() {
        let pos = Vec3::new(1.0, 4.0, -2.0);
        let dir = Vec3::new(0.3, -1.0, 0.2).normalize();
        let (cutoff_deg, range, res) = (30.0f32, 12.0f32, 512u32);
        let (view, proj, near, far) = spot_view(pos, dir, cutoff_deg, range, res);
        let m = proj * view;
        assert_eq!(far, range);
        let up = stable_up(dir);
        let side = dir.cross(up).normalize();
        let up = side.cross(dir);
        let mut rng = Rng(7);
        for _ in 0..2000 {
            // A random direction inside the cone, at a random distance inside the range.
            let angle = rng.range(0.0, cutoff_deg.to_radians());
            let turn = rng.range(0.0, std::f32::consts::TAU);
            let d = dir * angle.cos() + (side * turn.cos() + up * turn.sin()) * angle.sin();
            // View depth is dist·cos(angle): keep it inside near..range.
            let p = pos + d * rng.range(near * 1.2 / angle.cos(), range * 0.999);
            assert!(
                in_clip(m, p, 0.0),
                "inside the cone but outside the map: {p}"
            );
            // Beyond the range along the same ray: depth > 1.
            let beyond = pos + d * (range * 1.01 / d.dot(dir));
            assert!(clip(m, beyond).z > 1.0, "beyond range but inside: {beyond}");
        }
        // The cone's edge, straight across, sits at least PCF_MARGIN_TEXELS inside the map edge.
        let edge = pos
            + (dir * cutoff_deg.to_radians().cos() + side * cutoff_deg.to_radians().sin()) * 5.0;
        let x = clip(m, edge).x.abs();
        // 1.5 texels on each side: room for a 3×3 PCF kernel centred on the edge.
        let margin_ndc = 2.0 * 1.5 / res as f32;
        assert!(
            x <= 1.0 - margin_ndc + 1e-4 && x > 1.0 - margin_ndc - 1e-3,
            "cone edge at ndc {x}"
        );
        // Outside the cone (beyond the square frustum's corner angle): excluded.
        let corner_angle = (spot_half_fov(cutoff_deg, res).tan() * 2f32.sqrt()).atan();
        for _ in 0..2000 {
            let angle = rng.range(corner_angle + 0.01, std::f32::consts::PI);
            let turn = rng.range(0.0, std::f32::consts::TAU);
            let d = dir * angle.cos() + (side * turn.cos() + up * turn.sin()) * angle.sin();
            let p = pos + d * rng.range(near * 2.0, range * 0.9);
            assert!(
                !in_clip(m, p, 0.0),
                "outside the cone but inside the map: angle {angle}"
            );
        }
        // Straight across, a little past the margin, is outside too.
        let half = spot_half_fov(cutoff_deg, res);
        let out = pos + (dir * (half + 0.01).cos() + side * (half + 0.01).sin()) * 5.0;
        assert!(!in_clip(m, out, 0.0));
    }

    #[test]
    fn spot_near_and_far_hug_the_range() {
        let pos = Vec3::ZERO;
        let (view, proj, near, far) = spot_view(pos, Vec3::NEG_Z, 20.0, 25.0, 256);
        assert_eq!(far, 25.0);
        assert_eq!(near, (25.0f32 * 0.002).max(0.01));
        let m = proj * view;
        assert!((clip(m, Vec3::new(0.0, 0.0, -near)).z).abs() < 1e-5);
        assert!((clip(m, Vec3::new(0.0, 0.0, -far)).z - 1.0).abs() < 1e-5);
        assert!(in_clip(m, Vec3::new(0.0, 0.0, -24.99), 0.0));
        assert!(!in_clip(m, Vec3::new(0.0, 0.0, -25.01), 0.0));
        assert!(!in_clip(m, Vec3::new(0.0, 0.0, -near * 0.9), 0.0));
        // Short lights hit the 0.01 floor; long ones scale.
        assert_eq!(spot_view(pos, Vec3::X, 20.0, 1.0, 256).2, 0.01);
        assert_eq!(spot_view(pos, Vec3::X, 20.0, 1000.0, 256).2, 2.0);
    }

    #[test]
    fn spot_up_vector_avoids_the_axis() {
        // Straight down: +Y would be parallel, so the view must still be finite and orthonormal.
        for dir in [
            Vec3::NEG_Y,
            Vec3::Y,
            Vec3::new(0.01, -1.0, 0.0).normalize(),
            Vec3::X,
        ] {
            let (view, ..) = spot_view(Vec3::ONE, dir, 30.0, 10.0, 128);
            assert!(view.is_finite(), "{dir}");
            assert!(
                (view.row(2).truncate() + dir).length() < 1e-5,
                "view must look down {dir}"
            );
        }
    }

    #[test]
    fn cube_faces_select_the_major_axis() {
        let pos = Vec3::new(3.0, -1.0, 2.0);
        let range = 15.0;
        let (views, proj, near, far) = cube_face_views(pos, range);
        assert!((near - 0.03).abs() < 1e-7 && far == 15.0);
        let mut rng = Rng(99);
        let mut tested = 0;
        while tested < 5000 {
            let d = rng.unit_vector();
            // Skip near-ties between two axes, where the point is on two faces' shared edge.
            let mut a = d.abs().to_array();
            a.sort_by(f32::total_cmp);
            if a[2] - a[1] < 1e-3 {
                continue;
            }
            tested += 1;
            let p = pos + d * rng.range(near * 2.0 / a[2].max(1e-3), range * 0.99);
            let major = {
                let (i, v) = d
                    .to_array()
                    .into_iter()
                    .enumerate()
                    .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))
                    .unwrap();
                (2 * i + usize::from(v < 0.0)) as u8
            };
            assert_eq!(cube_face_for(d), major);
            for (face, view) in views.iter().enumerate() {
                let inside = in_clip(proj * *view, p, 0.0);
                assert_eq!(
                    inside,
                    face as u8 == major,
                    "direction {d}: face {face} inside = {inside}, major face {major}"
                );
            }
        }
    }

    #[test]
    fn cube_faces_use_the_cube_map_up_vectors() {
        let (views, ..) = cube_face_views(Vec3::new(1.0, 2.0, 3.0), 10.0);
        let expected = [
            (Vec3::X, Vec3::NEG_Y),
            (Vec3::NEG_X, Vec3::NEG_Y),
            (Vec3::Y, Vec3::Z),
            (Vec3::NEG_Y, Vec3::NEG_Z),
            (Vec3::Z, Vec3::NEG_Y),
            (Vec3::NEG_Z, Vec3::NEG_Y),
        ];
        for (face, (view, (look, up))) in views.iter().zip(expected).enumerate() {
            // Row 1 of a view matrix is the view's +Y in world space, row 2 is −(look direction).
            assert!(
                (view.row(1).truncate() - up).length() < 1e-6,
                "face {face} up"
            );
            assert!(
                (view.row(2).truncate() + look).length() < 1e-6,
                "face {face} look"
            );
            assert!(
                (view.transform_point3(Vec3::new(1.0, 2.0, 3.0))).length() < 1e-5,
                "face {face} eye"
            );
        }
    }

    #[test]
    fn cube_faces_cover_the_whole_sphere() {
        let (views, proj, ..) = cube_face_views(Vec3::ZERO, 10.0);
        let inside_count = |d: Vec3| {
            views
                .iter()
                .filter(|v| in_clip(proj * **v, d * 5.0, 1e-5))
                .count()
        };
        // A Fibonacci sphere, plus the awkward directions: axes, edges and corners of the cube.
        let n = 4000;
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        let mut dirs: Vec<Vec3> = (0..n)
            .map(|i| {
                let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let r = (1.0 - y * y).sqrt();
                let t = golden * i as f32;
                Vec3::new(r * t.cos(), y, r * t.sin())
            })
            .collect();
        for x in -1..=1 {
            for y in -1..=1 {
                for z in -1..=1 {
                    if (x, y, z) != (0, 0, 0) {
                        dirs.push(Vec3::new(x as f32, y as f32, z as f32).normalize());
                    }
                }
            }
        }
        for d in dirs {
            assert!(inside_count(d) >= 1, "direction {d} is on no face");
        }
    }

    #[test]
    fn cascade_splits_follow_the_practical_scheme() {
        let (near, far) = (0.5f32, 120.0f32);
        for &count in &[1u32, 2, 3, 4] {
            for &lambda in &[0.0f32, 0.3, 0.75, 1.0] {
                let s = cascade_splits(near, far, count, lambda);
                assert_eq!(s.len(), count as usize + 1);
                assert_eq!(s[0], near);
                assert_eq!(*s.last().unwrap(), far);
                assert!(s.windows(2).all(|w| w[1] > w[0]), "not increasing: {s:?}");
            }
            let uniform = cascade_splits(near, far, count, 0.0);
            let log = cascade_splits(near, far, count, 1.0);
            for i in 0..=count as usize {
                let t = i as f64 / count as f64;
                let u = near as f64 + (far as f64 - near as f64) * t;
                let l = (near as f64).ln() * (1.0 - t) + (far as f64).ln() * t;
                assert!(
                    (uniform[i] as f64 - u).abs() < 1e-4 * u,
                    "uniform {i}: {} vs {u}",
                    uniform[i]
                );
                assert!(
                    (log[i] as f64 - l.exp()).abs() < 1e-4 * l.exp(),
                    "log {i}: {} vs {}",
                    log[i],
                    l.exp()
                );
            }
        }
        // The blend is exactly that: λ·log + (1−λ)·uniform.
        let (u, l, b) = (
            cascade_splits(near, far, 3, 0.0),
            cascade_splits(near, far, 3, 1.0),
            cascade_splits(near, far, 3, 0.25),
        );
        assert!((b[1] - (0.25 * l[1] + 0.75 * u[1])).abs() < 1e-4);
    }

    #[test]
    fn slice_sphere_is_tight_and_ignores_how_the_camera_turns() {
        let mut camera = Camera::look_at(Vec3::new(2.0, 3.0, 4.0), Vec3::ZERO);
        let aspect = 1.7;
        for (near, far) in [(0.1f32, 3.0f32), (3.0, 12.0), (12.0, 80.0), (5.0, 5.5)] {
            let (centre, radius) = slice_bounding_sphere(&camera, aspect, near, far);
            let corners = frustum_slice_corners(&camera, aspect, near, far);
            let reach = corners
                .iter()
                .map(|c| c.distance(centre))
                .fold(0.0f32, f32::max);
            assert!(
                reach <= radius * (1.0 + 1e-5),
                "a corner is outside the sphere: {reach} > {radius}"
            );
            // Rounded up by at most 1/16 of the smallest sphere's radius.
            // ... to a whole number of 1/16ths of its octave, so it is stable under float noise.
            let step = radius.log2().floor().exp2() / 16.0;
            assert_eq!(
                (radius / step).fract(),
                0.0,
                "radius {radius} is not a multiple of {step}"
            );
            assert!(
                radius <= reach * (1.0 + 1.0 / 16.0) + 1e-6,
                "radius {radius} vs reach {reach}"
            );
            // And the centre is the smallest sphere's: moving it any way reaches further (the
            // reach is convex in the centre, so a local minimum is the minimum).
            let view = camera.view();
            for axis in [view.row(0), view.row(1), view.row(2)].map(|r| r.truncate()) {
                for step in [-0.01f32, 0.01] {
                    let moved = centre + axis * step * far;
                    let reach2 = corners
                        .iter()
                        .map(|c| c.distance(moved))
                        .fold(0.0f32, f32::max);
                    assert!(
                        reach2 >= reach * (1.0 - 1e-5),
                        "({near}, {far}): {reach2} < {reach}"
                    );
                }
            }
            // Turning and moving the camera leaves the radius exactly unchanged.
            for target in [Vec3::new(5.0, -1.0, 0.0), Vec3::new(-3.0, 7.0, 2.0)] {
                let mut turned = camera;
                turned.position += Vec3::new(0.3, -0.2, 1.1);
                turned.target = target;
                assert_eq!(slice_bounding_sphere(&turned, aspect, near, far).1, radius);
            }
        }
        camera.fov_y_deg = 100.0;
        let (_, wide) = slice_bounding_sphere(&camera, aspect, 1.0, 2.0);
        assert!(wide.is_finite() && wide > 0.0);
    }

    #[test]
    fn view_depth_range_clamps_to_the_scene() {
        let scene = test_scene(vec![]);
        let (near, far) = view_depth_range(&scene.camera, scene.world_bounds(false));
        let view = scene.camera.view();
        let (lo, hi) = scene.world_bounds(false).unwrap();
        let deepest = box_corners(lo, hi)
            .iter()
            .map(|&c| -view.transform_point3(c).z)
            .fold(f32::MIN, f32::max);
        assert_eq!(
            near, scene.camera.near,
            "the camera is inside the bounds' depth range"
        );
        assert!(
            (far - deepest).abs() < 1e-4 && far < scene.camera.far,
            "far {far}, deepest corner {deepest}"
        );
        // A camera whose far plane is nearer than the scene keeps its far plane.
        let mut short = scene.camera;
        short.far = 20.0;
        assert_eq!(
            view_depth_range(&short, scene.world_bounds(false)),
            (short.near, 20.0)
        );
        // A camera far outside the scene starts at the nearest corner, not at its near plane.
        let mut distant = scene.camera;
        distant.position = Vec3::new(0.0, 5.0, 150.0);
        distant.far = 500.0;
        let view = distant.view();
        let nearest = box_corners(lo, hi)
            .iter()
            .map(|&c| -view.transform_point3(c).z)
            .fold(f32::MAX, f32::min);
        let (n, f) = view_depth_range(&distant, scene.world_bounds(false));
        assert!(
            nearest > 90.0 && (n - nearest).abs() < 1e-3 && f < 500.0,
            "({n}, {f}), nearest corner {nearest}"
        );
        // No geometry: the camera's own planes.
        assert_eq!(
            view_depth_range(&scene.camera, None),
            (scene.camera.near, scene.camera.far)
        );
    }

    #[test]
    fn cascades_cover_their_slices_and_every_caster() {
        let scene = test_scene(vec![sun(3, 1024)]);
        let aspect = 16.0 / 9.0;
        let views = shadow_views(&scene, aspect);
        assert_eq!(views.len(), 3);
        let (near, far) = view_depth_range(&scene.camera, scene.world_bounds(false));
        let splits = cascade_splits(near, far, 3, 0.7);
        let (lo, hi) = scene.world_bounds(true).unwrap();
        for (i, v) in views.iter().enumerate() {
            assert_eq!(v.kind, ViewKind::Cascade(i as u8));
            assert!(v.orthographic);
            assert_eq!(v.split_far, splits[i + 1]);
            assert_eq!(v.view_proj, v.proj * v.view);
            for c in frustum_slice_corners(&scene.camera, aspect, splits[i], splits[i + 1]) {
                assert!(
                    in_clip(v.view_proj, c, 1e-5),
                    "cascade {i}: slice corner {c} outside, clip {}",
                    clip(v.view_proj, c)
                );
            }
            for c in box_corners(lo, hi) {
                let z = clip(v.view_proj, c).z;
                assert!(
                    (0.0..=1.0).contains(&z),
                    "cascade {i}: caster corner {c} at depth {z}"
                );
            }
            // The texel size matches the projection's width.
            assert!((v.texel_world - 2.0 / (v.proj.x_axis.x * 1024.0)).abs() < 1e-6);
        }
        // Nearer cascades have smaller texels.
        assert!(
            views[0].texel_world < views[1].texel_world
                && views[1].texel_world < views[2].texel_world
        );
    }

    #[test]
    fn cascade_texels_snap_when_the_camera_moves() {
        let mut scene = test_scene(vec![sun(3, 1024)]);
        let aspect = 1.5;
        let before = shadow_views(&scene, aspect);
        let right = scene.camera.view().row(0).truncate();
        let points = [
            Vec3::new(0.3, 0.0, 0.7),
            Vec3::new(-3.0, 1.0, -8.0),
            Vec3::new(5.5, 0.2, -20.0),
        ];
        let mut moved_whole_texels = false;
        for step in [0.37f32, 0.81, 3.37, 10.63] {
            let mut moved = scene.clone();
            let delta = right * step * before[0].texel_world;
            moved.camera.position += delta;
            moved.camera.target += delta;
            let after = shadow_views(&moved, aspect);
            for (b, a) in before.iter().zip(&after) {
                assert_eq!(
                    b.texel_world, a.texel_world,
                    "texel size changed with a sideways move"
                );
                for p in points {
                    let texel = |m: Mat4| (clip(m, p).truncate() * 0.5 + 0.5) * 1024.0;
                    let shift = texel(a.view_proj) - texel(b.view_proj);
                    let frac = (shift - shift.round()).abs();
                    assert!(
                        frac.max_element() < 0.02,
                        "{:?}, move {step} texels: point {p} shifted by {shift} texels",
                        b.kind
                    );
                    moved_whole_texels |= shift.round() != glam::Vec2::ZERO;
                }
            }
        }
        assert!(
            moved_whole_texels,
            "the moves should shift some cascade by whole texels"
        );
        scene.camera.position += right * 1e-4;
        assert!(shadow_views(&scene, aspect)
            .iter()
            .all(|v| v.view_proj.is_finite()));
    }

    #[test]
    fn empty_scene_still_gets_finite_cascades() {
        let mut scene = test_scene(vec![sun(2, 512)]);
        scene.instances.clear();
        let views = shadow_views(&scene, 1.0);
        assert_eq!(views.len(), 2);
        for v in &views {
            assert!(v.view_proj.is_finite() && v.far > v.near && v.texel_world > 0.0);
        }
        assert_eq!(views[1].split_far, scene.camera.far);
        // A straight-down sun uses the other up vector and is still finite.
        scene.lights[0].kind = LightKind::Directional {
            direction: Vec3::NEG_Y,
            cascades: 1,
            split_lambda: 0.5,
            cascade_resolution_scale: 1.0,
        };
        assert!(shadow_views(&scene, 1.0)[0].view_proj.is_finite());
    }

    #[test]
    fn shadow_views_count_and_fill_every_light() {
        let spot = light(
            LightKind::Spot {
                position: Vec3::new(0.0, 6.0, 0.0),
                direction: Vec3::NEG_Y,
                cutoff_deg: 25.0,
                range: 20.0,
            },
            512,
        );
        let point = light(
            LightKind::Point {
                position: Vec3::new(2.0, 3.0, 1.0),
                range: 10.0,
            },
            256,
        );
        let mut unshadowed = point;
        unshadowed.casts_shadows = false;
        let scene = test_scene(vec![spot, unshadowed, point, sun(3, 1024)]);
        let views = shadow_views(&scene, 1.0);
        assert_eq!(views.len(), 10);
        let kinds: Vec<(usize, ViewKind)> = views.iter().map(|v| (v.light, v.kind)).collect();
        let mut expected = vec![(0, ViewKind::Spot)];
        expected.extend((0..6).map(|f| (2, ViewKind::CubeFace(f))));
        expected.extend((0..3).map(|c| (3, ViewKind::Cascade(c))));
        assert_eq!(kinds, expected);
        for v in &views {
            assert_eq!(v.view_proj, v.proj * v.view);
            assert!(v.near > 0.0 && v.far > v.near);
            assert_eq!(v.resolution, scene.lights[v.light].shadow_resolution);
            assert_eq!(v.orthographic, matches!(v.kind, ViewKind::Cascade(_)));
            assert_eq!(v.split_far > 0.0, matches!(v.kind, ViewKind::Cascade(_)));
        }
        let half = spot_half_fov(25.0, 512);
        assert!((views[0].texel_world - 2.0 * half.tan() / 512.0).abs() < 1e-7);
        assert!((views[1].texel_world - 2.0 / 256.0).abs() < 1e-7);
        assert!((views[1].near - 0.02).abs() < 1e-7 && views[1].far == 10.0);
    }
}
