//! The analytic scenes, exactly as specified.

use glam::Vec3;
use manyshadows_scene::builtin::{self, BuiltinOptions};
use manyshadows_scene::LightKind;

use crate::common::with_lights;

#[test]
fn analytic_scenes_are_exactly_as_specified() {
    for name in ["plane-spot", "plane-point", "plane-directional"] {
        // The light count option is ignored: exactly one light, always.
        for opts in [BuiltinOptions::default(), with_lights(5)] {
            let scene = builtin::build(name, &opts).unwrap();
            assert_eq!(scene.lights.len(), 1, "{name}");
            let l = scene.lights[0];
            assert_eq!(l.shadow_resolution, 1024);
            assert_eq!(scene.triangle_count(), 2 + 12);
            match (name, l.kind) {
                (
                    "plane-spot",
                    LightKind::Spot {
                        position,
                        direction,
                        cutoff_deg,
                        range,
                    },
                ) => {
                    assert_eq!(position, Vec3::new(0.0, 6.0, 0.0));
                    assert_eq!(direction, Vec3::new(0.0, -1.0, 0.0));
                    assert_eq!((cutoff_deg, range), (40.0, 20.0));
                }
                ("plane-point", LightKind::Point { position, range }) => {
                    assert_eq!(position, Vec3::new(1.5, 4.0, 1.0));
                    assert_eq!(range, 20.0);
                }
                (
                    "plane-directional",
                    LightKind::Directional {
                        direction,
                        cascades,
                        split_lambda,
                        ..
                    },
                ) => {
                    assert_eq!(direction, Vec3::new(0.6, -1.0, 0.4).normalize());
                    assert_eq!((cascades, split_lambda), (2, 0.5));
                }
                other => panic!("wrong light {other:?}"),
            }
            let c = scene.camera;
            assert_eq!(c.position, Vec3::new(0.0, 12.0, 0.001));
            assert_eq!(c.target, Vec3::ZERO);
            assert_eq!((c.fov_y_deg, c.near, c.far), (60.0, 0.1, 50.0));

            // Floor: one quad, 20 × 20 at y = 0.
            let floor = &scene.instances[builtin::FLOOR_MESH];
            assert_eq!(scene.meshes[floor.mesh].triangle_count(), 2);
            let (lo, hi) = scene.meshes[floor.mesh].bounds().unwrap();
            let (lo, hi) = (
                floor.transform.transform_point3(lo),
                floor.transform.transform_point3(hi),
            );
            assert_eq!(
                (lo, hi),
                (Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 0.0, 10.0))
            );
            // Occluder: 2 × 0.02 × 2 centred at (0, 2, 0).
            let occ = &scene.instances[builtin::OCCLUDER_MESH];
            let (lo, hi) = scene.meshes[occ.mesh].bounds().unwrap();
            let (lo, hi) = (
                occ.transform.transform_point3(lo),
                occ.transform.transform_point3(hi),
            );
            let half = Vec3::new(
                builtin::OCCLUDER_HALF_SIZE,
                0.5 * builtin::OCCLUDER_THICKNESS,
                builtin::OCCLUDER_HALF_SIZE,
            );
            assert!((lo - (builtin::OCCLUDER_CENTER - half)).abs().max_element() < 1e-6);
            assert!((hi - (builtin::OCCLUDER_CENTER + half)).abs().max_element() < 1e-6);
            assert_eq!(builtin::OCCLUDER_CENTER, Vec3::new(0.0, 2.0, 0.0));
            assert_eq!(
                (builtin::OCCLUDER_HALF_SIZE, builtin::OCCLUDER_THICKNESS),
                (1.0, 0.02)
            );
            assert!(scene.instances.iter().all(|i| i.casts_shadows));
        }
    }
}
