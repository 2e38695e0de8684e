//! Culling: whether a sphere may lie inside a frustum (its six planes) or inside a shadow
//! view, the paraboloid hemispheres included.

use glam::{Mat4, Vec3, Vec4};

use super::view::{ShadowView, ViewKind};

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
        self.sphere_test()(center, radius)
    }

    /// [`ShadowView::sphere_visible`] with the view's planes (or paraboloid axis) computed
    /// once, for testing many spheres against one view.
    pub fn sphere_test(&self) -> impl Fn(Vec3, f32) -> bool + '_ {
        enum Test {
            Planes([Vec4; 6]),
            Hemisphere { eye: Vec3, axis: Vec3 },
        }
        let test = match self.kind {
            ViewKind::Paraboloid(_) => {
                let inv = self.view.inverse();
                Test::Hemisphere {
                    eye: inv.w_axis.truncate(),
                    axis: inv.transform_vector3(Vec3::NEG_Z),
                }
            }
            _ => Test::Planes(frustum_planes(self.view_proj)),
        };
        move |center, radius| match &test {
            Test::Hemisphere { eye, axis } => {
                let d = center - *eye;
                let dist = d.length();
                dist - radius <= self.far && dist + radius >= self.near && d.dot(*axis) >= -radius
            }
            Test::Planes(planes) => sphere_in_planes(planes, center, radius),
        }
    }
}
