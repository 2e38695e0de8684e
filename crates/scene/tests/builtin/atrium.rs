//! The atrium: its triangles and instances, its lights along the arcades (few or many), and
//! its camera.

use manyshadows_scene::builtin::{self, atrium};
use manyshadows_scene::LightKind;

use crate::common::{build, count_types, light_position, with_lights};

#[test]
fn atrium_has_200k_triangles_in_many_instances_and_32_mixed_lights() {
    let scene = build("atrium");
    let tris = scene.triangle_count();
    assert!(tris >= 200_000, "atrium has only {tris} triangles");
    assert!(
        tris <= 400_000,
        "atrium grew to {tris} triangles (keep it renderable on a CPU)"
    );
    // Many instances of a few meshes, no giant mesh: per-view culling has work to do.
    assert!(
        scene.instances.len() >= 200,
        "{} instances",
        scene.instances.len()
    );
    assert!(scene.meshes.len() <= 20, "{} meshes", scene.meshes.len());
    let biggest = scene
        .instances
        .iter()
        .map(|i| scene.meshes[i.mesh].triangle_count())
        .max()
        .unwrap();
    assert!(
        biggest * 20 < tris,
        "one instance has {biggest} of {tris} triangles"
    );

    assert_eq!(scene.lights.len(), atrium::DEFAULT_ATRIUM_LIGHTS);
    assert_eq!(scene.lights.len(), 32);
    let (spot, point, directional) = count_types(&scene);
    assert_eq!(directional, 1, "one sun");
    assert!(spot > point && point >= 1, "spots {spot}, points {point}");
}

#[test]
fn atrium_lights_hang_along_the_arcades_with_moderate_ranges() {
    let (hx, hz) = (0.5 * atrium::HALL_LENGTH, 0.5 * atrium::HALL_WIDTH);
    for n in [32, builtin::LOCAL_LAYOUT_ABOVE] {
        let scene = builtin::build("atrium", &with_lights(n)).unwrap();
        let mut distinct = std::collections::HashSet::new();
        for l in &scene.lights {
            match l.kind {
                LightKind::Spot {
                    position,
                    direction,
                    range,
                    ..
                } => {
                    assert!(direction.y < -0.8, "spots point down: {direction}");
                    // ... and into the nave.
                    assert!(direction.z * position.z <= 0.0, "{position} {direction}");
                    assert!((position.z.abs() - atrium::ARCADE_Z).abs() < 0.01);
                    assert!(range <= 25.0, "range {range}");
                }
                LightKind::Point { position, range } => {
                    assert!(
                        position.z.abs() > atrium::ARCADE_Z,
                        "points light the aisles"
                    );
                    assert!(range <= 10.0, "range {range}");
                }
                LightKind::Directional { direction, .. } => {
                    assert!(direction.y < -0.5, "the sun shines down through the roof");
                }
            }
            if let Some(p) = light_position(&l.kind) {
                assert!(
                    p.x.abs() < hx && p.z.abs() < hz,
                    "light outside the hall: {p}"
                );
                assert!(
                    p.y > 0.5 && p.y < atrium::HALL_HEIGHT,
                    "light at height {}",
                    p.y
                );
                distinct.insert((p * 100.0).round().as_ivec3().to_array());
            }
        }
        let positioned = scene
            .lights
            .iter()
            .filter(|l| light_position(&l.kind).is_some())
            .count();
        assert_eq!(
            distinct.len(),
            positioned,
            "{n} lights: two lights share a position"
        );
        // Both storeys and both arcades get lights.
        let ys: Vec<f32> = scene
            .lights
            .iter()
            .filter_map(|l| light_position(&l.kind))
            .map(|p| p.y)
            .collect();
        assert!(
            ys.iter().any(|&y| y < atrium::GALLERY_Y) && ys.iter().any(|&y| y > atrium::GALLERY_Y)
        );
        let zs: Vec<f32> = scene
            .lights
            .iter()
            .filter_map(|l| light_position(&l.kind))
            .map(|p| p.z)
            .collect();
        assert!(zs.iter().any(|&z| z < 0.0) && zs.iter().any(|&z| z > 0.0));
    }
}

/// Above [`builtin::LOCAL_LAYOUT_ABOVE`] lights most are local: short, bounded ranges that
/// shrink as the count grows (so a pixel sees a similar number of lights at any count), inside
/// the hall, at distinct positions, and the same for the same seed.
#[test]
fn many_atrium_lights_are_local_with_bounded_ranges() {
    let (hx, hz) = (0.5 * atrium::HALL_LENGTH, 0.5 * atrium::HALL_WIDTH);
    let mut previous_mean = f32::INFINITY;
    for n in [100, 1000, 16384] {
        let scene = builtin::build("atrium", &with_lights(n)).unwrap();
        assert_eq!(scene.lights.len(), n);
        assert_eq!(
            scene.lights,
            builtin::build("atrium", &with_lights(n)).unwrap().lights,
            "the layout is seeded"
        );
        let mut distinct = std::collections::HashSet::new();
        let mut local = Vec::new();
        for l in &scene.lights {
            let Some(p) = light_position(&l.kind) else {
                continue;
            };
            assert!(
                p.x.abs() < hx && p.z.abs() < hz,
                "light outside the hall: {p}"
            );
            assert!(p.y > 0.0 && p.y < atrium::HALL_HEIGHT, "height {}", p.y);
            assert!(distinct.insert((p * 1000.0).round().as_ivec3().to_array()));
            let range = match l.kind {
                LightKind::Spot { range, .. } | LightKind::Point { range, .. } => range,
                LightKind::Directional { .. } => unreachable!(),
            };
            if range <= builtin::LOCAL_RANGE.1 {
                assert!(range >= builtin::LOCAL_RANGE.0, "range {range}");
                local.push(range);
            }
        }
        assert!(
            local.len() >= n - 40,
            "{} of {n} lights are local",
            local.len()
        );
        let mean = local.iter().sum::<f32>() / local.len() as f32;
        assert!(
            mean < previous_mean,
            "{n} lights: mean range {mean} did not shrink"
        );
        previous_mean = mean;
        assert!(scene.validate().is_ok());
    }
}

#[test]
fn atrium_camera_is_inside_the_hall_looking_down_the_nave() {
    let scene = build("atrium");
    let c = scene.camera;
    assert!(c.position.x.abs() < 0.5 * atrium::HALL_LENGTH);
    assert!(c.position.z.abs() < atrium::ARCADE_Z);
    assert!(c.position.y > 1.5 && c.position.y < atrium::GALLERY_Y);
    let forward = (c.target - c.position).normalize();
    assert!(forward.x > 0.9, "looks down the nave: {forward}");
}
