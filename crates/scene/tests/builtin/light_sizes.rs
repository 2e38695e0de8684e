//! Light sizes: the built-in scenes' lights follow the default rule (a spot or point light's
//! radius 2 % of its range, a sun 0.53°), the scenes tests compare exactly stay hard, and
//! `BuiltinOptions::light_sizes` overrides every light's size in every scene.

use manyshadows_scene::builtin::{self, cubes, BuiltinOptions, LightMix, SCENE_NAMES};
use manyshadows_scene::light_size::{
    default_size, LightSizes, SIZE_PER_RANGE, SUN_ANGULAR_DIAMETER_DEG,
};
use manyshadows_scene::{LightKind, Scene, SceneError};

use crate::common::build;

/// The scenes whose lights are hard (size 0) by default: golden images and exact outlines.
const HARD_SCENES: [&str; 4] = ["cubes", "plane-spot", "plane-point", "plane-directional"];

fn sized(name: &str, opts: BuiltinOptions) -> Scene {
    builtin::build(name, &opts).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn assert_default_sizes(what: &str, scene: &Scene) {
    assert!(!scene.lights.is_empty(), "{what}");
    for (i, l) in scene.lights.iter().enumerate() {
        let want = match l.kind {
            LightKind::Spot { range, .. } | LightKind::Point { range, .. } => {
                SIZE_PER_RANGE * range
            }
            LightKind::Directional { .. } => SUN_ANGULAR_DIAMETER_DEG,
        };
        assert_eq!(l.size, want, "{what}: light {i} ({})", l.type_name());
        assert_eq!(l.size, default_size(&l.kind));
        assert!(l.size > 0.0, "{what}: light {i}");
    }
}

#[test]
fn atrium_lights_are_sized_by_the_default_rule() {
    let scene = build("atrium");
    assert_default_sizes("atrium", &scene);
    // 32 lights on the arcade slots: lamps of 0.16 to 0.48 m radius, and the sun.
    let radii: Vec<f32> = scene
        .lights
        .iter()
        .filter(|l| l.type_name() != "directional")
        .map(|l| l.size)
        .collect();
    let (lo, hi) = radii
        .iter()
        .fold((f32::MAX, 0.0f32), |(a, b), &r| (a.min(r), b.max(r)));
    assert!(lo >= 0.15 && hi <= 0.5, "{lo}..{hi}");
    assert_eq!(
        scene
            .lights
            .iter()
            .filter(|l| l.type_name() == "directional")
            .map(|l| l.size)
            .collect::<Vec<_>>(),
        [0.53]
    );
    // Local lights of a dense layout are small, after their short ranges.
    let dense = sized(
        "atrium",
        BuiltinOptions {
            lights: Some(300),
            ..BuiltinOptions::default()
        },
    );
    assert_default_sizes("atrium, 300 lights", &dense);
}

#[test]
fn other_layouts_are_sized_by_the_default_rule_and_test_scenes_are_hard() {
    for name in SCENE_NAMES {
        let scene = build(name);
        if HARD_SCENES.contains(name) {
            assert!(scene.lights.iter().all(|l| l.size == 0.0), "{name}");
        } else {
            assert_default_sizes(name, &scene);
        }
    }
    for mix in [LightMix::All, LightMix::Point, LightMix::Directional] {
        let opts = || BuiltinOptions {
            lights: Some(80),
            mix,
            ..BuiltinOptions::default()
        };
        for name in ["terrain", "dragon", "courtyard"] {
            assert_default_sizes(&format!("{name}, 80 {mix}"), &sized(name, opts()));
        }
        // cubes stays hard with a seeded layout too.
        let scene = sized("cubes", opts());
        assert!(scene.lights.iter().all(|l| l.size == 0.0), "cubes {mix}");
    }
    assert!(cubes::cubes_default_lights(None)
        .iter()
        .all(|l| l.size == 0.0));
    // The generic layout (TOML and model files given --lights, files without lights).
    let cubes = build("cubes");
    let scattered = Scene {
        lights: builtin::scatter_lights(&cubes, 40, 7, LightMix::All, None),
        ..cubes
    };
    assert_default_sizes("scatter_lights", &scattered);
}

#[test]
fn light_sizes_override_every_light_and_keep_layouts_deterministic() {
    let both = LightSizes {
        radius: Some(0.1),
        sun_deg: Some(2.0),
    };
    for name in SCENE_NAMES {
        let opts = |light_sizes| BuiltinOptions {
            light_sizes,
            ..BuiltinOptions::default()
        };
        let plain = sized(name, opts(LightSizes::default()));
        let scene = sized(name, opts(both));
        assert_eq!(scene.lights.len(), plain.lights.len());
        for (a, b) in plain.lights.iter().zip(&scene.lights) {
            let want = match b.kind {
                LightKind::Directional { .. } => 2.0,
                _ => 0.1,
            };
            assert_eq!(b.size, want, "{name}");
            // Only the size changes.
            assert_eq!(a.kind, b.kind, "{name}");
            assert_eq!(a.diffuse, b.diffuse, "{name}");
        }
        let hard = sized(name, opts(LightSizes::HARD));
        assert!(hard.lights.iter().all(|l| l.size == 0.0), "{name}");
        // A part left out keeps the scene's own sizes.
        let suns = sized(
            name,
            opts(LightSizes {
                radius: None,
                sun_deg: Some(1.5),
            }),
        );
        for (a, b) in plain.lights.iter().zip(&suns.lights) {
            let want = match b.kind {
                LightKind::Directional { .. } => 1.5,
                _ => a.size,
            };
            assert_eq!(b.size, want, "{name}");
        }
    }
    // Same seed, same sizes (and everything else).
    let opts = || BuiltinOptions {
        lights: Some(100),
        seed: 9,
        ..BuiltinOptions::default()
    };
    assert_eq!(
        sized("atrium", opts()).lights,
        sized("atrium", opts()).lights
    );
}

#[test]
fn bad_light_sizes_are_refused() {
    for (radius, sun_deg, needle) in [
        (Some(-0.1), None, "light radius -0.1"),
        (Some(f32::NAN), None, "light radius NaN"),
        (Some(f32::INFINITY), None, "light radius inf"),
        (None, Some(30.0), "below 30"),
        (None, Some(-1.0), "sun size -1"),
        (None, Some(f32::NAN), "sun size NaN"),
    ] {
        let opts = BuiltinOptions {
            light_sizes: LightSizes { radius, sun_deg },
            ..BuiltinOptions::default()
        };
        match builtin::build("cubes", &opts) {
            Err(e @ SceneError::InvalidRequest(_)) => {
                assert!(e.to_string().contains(needle), "{e}")
            }
            other => panic!("{radius:?} {sun_deg:?}: {other:?}"),
        }
    }
    assert!(LightSizes::default().is_none() && !LightSizes::HARD.is_none());
    let just_under = LightSizes {
        radius: Some(0.0),
        sun_deg: Some(29.9),
    };
    just_under.check().unwrap();
}
