//! The cascades of a directional light: the camera's depth range cut into slices (the
//! practical split scheme), each slice's bounding sphere, and the orthographic fit around it
//! whose origin snaps to whole texels.

use glam::{Mat4, Vec3};

use super::common::{box_corners, stable_up, PCF_MARGIN_TEXELS};
use crate::model::Camera;

/// Texels reserved around a cascade's sphere for snapping its centre to the texel grid
/// (rounding moves the centre by at most half a texel).
const SNAP_MARGIN_TEXELS: f32 = 0.5;

/// A cascade's radius is rounded up to a multiple of 1/`RADIUS_STEPS_PER_OCTAVE` of the power of
/// two below it (so at most 6.25 % of resolution is given up for a texel size that stays put).
const RADIUS_STEPS_PER_OCTAVE: f32 = 16.0;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light_space::testing::test_scene;

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
}
