//! Every shadow view of a scene: each shadow-casting light's views, in light order, made by
//! the spot, point and cascade modules.

use glam::Mat4;

use super::cascades::{cascade_splits, directional_fit, slice_bounding_sphere, view_depth_range};
use super::point::{cube_face_views, paraboloid_views, PointShadows};
use super::spot::spot_view;
use super::view::{ShadowView, ViewKind};
use crate::model::{LightKind, Scene};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light_space::cascades::frustum_slice_corners;
    use crate::light_space::common::box_corners;
    use crate::light_space::spot::spot_half_fov;
    use crate::light_space::testing::{clip, in_clip, light, sun, test_scene};
    use glam::Vec3;

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
