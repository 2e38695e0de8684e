//! The cubes scene, and the generic seeded light layout (`scatter_lights`).

use manyshadows_scene::builtin::{self, BuiltinOptions, LightCounts, LightMix};
use manyshadows_scene::Scene;

use crate::common::{build, count_types, light_position};

#[test]
fn cubes_is_small_with_one_light_of_each_type() {
    let scene = build("cubes");
    assert!(scene.triangle_count() < 5000, "{}", scene.triangle_count());
    assert_eq!(count_types(&scene), (1, 1, 1));
    assert_eq!(scene, build("cubes"));
    // Its default lights are fixed, not seeded: golden images must not move with --seed.
    let other = builtin::build(
        "cubes",
        &BuiltinOptions {
            seed: 99,
            ..BuiltinOptions::default()
        },
    )
    .unwrap();
    assert_eq!(scene, other);
}

#[test]
fn scatter_lights_spreads_a_seeded_layout_inside_the_bounds() {
    let scene = build("terrain");
    let (lo, hi) = scene.world_bounds(false).unwrap();
    let a = builtin::scatter_lights(&scene, 100, 3, LightMix::All, None);
    assert_eq!(
        a,
        builtin::scatter_lights(&scene, 100, 3, LightMix::All, None)
    );
    assert_ne!(
        a,
        builtin::scatter_lights(&scene, 100, 4, LightMix::All, None)
    );
    assert_eq!(a.len(), 100);
    let split = LightCounts::split(100, LightMix::All);
    let mut s = scene.clone();
    s.lights = a.clone();
    assert_eq!(
        count_types(&s),
        (split.spot, split.point, split.directional)
    );
    s.validate().unwrap();
    let mut quadrants = [0; 4];
    for l in &a {
        if let Some(p) = light_position(&l.kind) {
            assert!(p.x > lo.x && p.x < hi.x && p.z > lo.z && p.z < hi.z, "{p}");
            assert!(p.y > lo.y, "{p}");
            quadrants[(p.x > 0.5 * (lo.x + hi.x)) as usize * 2
                + (p.z > 0.5 * (lo.z + hi.z)) as usize] += 1;
        }
    }
    assert!(
        quadrants.iter().all(|&q| q >= 15),
        "uneven spread: {quadrants:?}"
    );
    // A scene with no geometry still gets a usable layout.
    let empty = Scene::default();
    let lights = builtin::scatter_lights(&empty, 10, 1, LightMix::All, Some(128));
    assert_eq!(lights.len(), 10);
    assert!(lights.iter().all(|l| l.shadow_resolution == 128));
    let mut s = empty;
    s.lights = lights;
    s.validate().unwrap();
}
