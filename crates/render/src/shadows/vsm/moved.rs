//! Where moved shadow casters fall, on the CPU, for the virtual shadow maps' caching
//! ([`super::carry`]): a caster's bounding sphere (old and new) projected onto a face gives
//! the part of it whose kept pages are drawn anew (`VirtualFace::dirty`), and projected onto
//! the screen the pixels that are marked again when only casters moved.

use glam::{Mat4, Vec3};
use manyshadows_scene::Scene;

/// The normalized-device bounds (x, y) of a sphere seen through `view_proj`: its enclosing
/// cube's eight corners projected; `None` when a corner lies behind the eye.
fn projected_bounds(view_proj: Mat4, c: Vec3, r: f32) -> Option<(glam::Vec2, glam::Vec2)> {
    let mut lo = glam::Vec2::splat(f32::INFINITY);
    let mut hi = glam::Vec2::splat(f32::NEG_INFINITY);
    for k in 0..8 {
        let corner = c + Vec3::new(
            if k & 1 == 0 { -r } else { r },
            if k & 2 == 0 { -r } else { r },
            if k & 4 == 0 { -r } else { r },
        );
        let clip = view_proj * corner.extend(1.0);
        if clip.w.is_nan() || clip.w <= 1e-6 {
            return None;
        }
        let ndc = glam::Vec2::new(clip.x, clip.y) / clip.w;
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    Some((lo, hi))
}

/// The part of a face (uv, y down, as the page table lays pages out) that a sphere may cover:
/// its projected bounds clamped to the face, the whole face when the sphere reaches behind
/// the light's eye.
pub(crate) fn moved_rect(view_proj: Mat4, c: Vec3, r: f32) -> [f32; 4] {
    let Some((lo, hi)) = projected_bounds(view_proj, c, r) else {
        return [0.0, 0.0, 1.0, 1.0];
    };
    // Pages are whole cells of the face: clamp to it.
    [
        (0.5 + 0.5 * lo.x).max(0.0),
        (0.5 - 0.5 * hi.y).max(0.0),
        (0.5 + 0.5 * hi.x).min(1.0),
        (0.5 - 0.5 * lo.y).min(1.0),
    ]
}

/// The smallest rectangle holding both (an empty one, min > max, holds nothing).
pub(crate) fn union(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    let empty = |r: [f32; 4]| r[0] > r[2] || r[1] > r[3];
    match (empty(a), empty(b)) {
        (true, _) => b,
        (_, true) => a,
        _ => [
            a[0].min(b[0]),
            a[1].min(b[1]),
            a[2].max(b[2]),
            a[3].max(b[3]),
        ],
    }
}

/// Camera world → clip for a `width` x `height` screen, for [`screen_rect`].
pub(crate) fn camera_matrix(scene: &Scene, (width, height): (u32, u32)) -> Mat4 {
    let cam = &scene.camera;
    cam.projection(width as f32 / height.max(1) as f32) * cam.view()
}

/// The pixels (x0, y0, x1, y1, clamped to the viewport) a sphere may cover on screen: its
/// projected bounds, one pixel wider; the whole screen when it reaches behind the camera.
pub(crate) fn screen_rect(view_proj: Mat4, (w, h): (u32, u32), c: Vec3, r: f32) -> [u32; 4] {
    let Some((lo, hi)) = projected_bounds(view_proj, c, r) else {
        return [0, 0, w, h];
    };
    let (w_f, h_f) = (w as f32, h as f32);
    let clamp = |v: f32, max: u32| v.clamp(0.0, max as f32) as u32;
    [
        clamp(((0.5 + 0.5 * lo.x) * w_f).floor() - 1.0, w),
        clamp(((0.5 - 0.5 * hi.y) * h_f).floor() - 1.0, h),
        clamp(((0.5 + 0.5 * hi.x) * w_f).ceil() + 1.0, w),
        clamp(((0.5 - 0.5 * lo.y) * h_f).ceil() + 1.0, h),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadows::vsm::plan::NOTHING_MOVED;

    #[test]
    fn a_moved_sphere_marks_the_part_of_the_face_it_projects_to() {
        // An orthographic face over x, y in [-10, 10] looking down -Z.
        let vp = Mat4::orthographic_rh(-10.0, 10.0, -10.0, 10.0, 0.1, 100.0)
            * Mat4::look_at_rh(Vec3::new(0.0, 0.0, 50.0), Vec3::ZERO, Vec3::Y);
        let r = moved_rect(vp, Vec3::new(5.0, 5.0, 0.0), 1.0);
        // x 4..6 → u 0.7..0.8; y 4..6 → v (down) 0.2..0.3.
        for (got, want) in r.iter().zip([0.7, 0.2, 0.8, 0.3]) {
            assert!((got - want).abs() < 1e-5, "{r:?}");
        }
        // Behind a perspective eye: the whole face.
        let persp = Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0);
        assert_eq!(
            moved_rect(persp, Vec3::new(0.0, 0.0, 0.0), 1.0),
            [0.0, 0.0, 1.0, 1.0]
        );
        assert_eq!(union(NOTHING_MOVED, r), r);
        // The same sphere on a 100 × 100 screen: pixels 70..80 × 20..30, one pixel wider
        // (two where the float bounds round outwards).
        let px = screen_rect(vp, (100, 100), Vec3::new(5.0, 5.0, 0.0), 1.0);
        for (got, want) in px.iter().zip([69, 19, 81, 31]) {
            assert!(got.abs_diff(want) <= 1, "{px:?}");
        }
        assert!(
            px[0] < 70 && px[1] < 20 && px[2] > 80 && px[3] > 30,
            "{px:?}"
        );
        assert_eq!(
            screen_rect(persp, (100, 50), Vec3::ZERO, 1.0),
            [0, 0, 100, 50]
        );
        assert_eq!(
            union([0.0, 0.0, 0.1, 0.1], [0.5, 0.5, 0.6, 0.6]),
            [0.0, 0.0, 0.6, 0.6]
        );
    }
}
