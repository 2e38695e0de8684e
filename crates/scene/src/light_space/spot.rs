//! The single perspective view of a spot light: its axis, a field of view widened past the
//! cone by the PCF margin, and near and far planes hugging the light's range.

use glam::{Mat4, Vec3};

use super::common::{light_depth_range, stable_up, PCF_MARGIN_TEXELS};

/// Widest half field of view a spot map may get (the projection degenerates at 90°).
const MAX_SPOT_HALF_FOV_DEG: f32 = 89.5;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light_space::testing::{clip, in_clip, Rng};

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
}
