//! The views of a point light: six 90° cube faces (the default), or two paraboloid
//! hemispheres (seed 003), and the choice between them ([`PointShadows`]).

use glam::{Mat4, Vec3, Vec4};

use super::common::light_depth_range;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light_space::testing::{in_clip, Rng};

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
}
