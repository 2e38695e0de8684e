//! Every scene: builds and validates, scene names, light counts, mixes, seeds and shadow
//! resolutions.

use manyshadows_scene::builtin::{
    self, BuiltinOptions, LightCounts, LightMix, MAX_LIGHTS, SCENE_NAMES,
};
use manyshadows_scene::{LightKind, SceneError};

use crate::common::{build, count_types, with_lights};

#[test]
fn every_scene_builds_and_validates() {
    for &name in SCENE_NAMES {
        let scene = build(name);
        scene.validate().unwrap();
        assert_eq!(scene.name, name);
        assert!(!scene.instances.is_empty(), "{name} has no geometry");
        assert!(scene.triangle_count() > 0, "{name} has no triangles");
        assert!(!scene.lights.is_empty(), "{name} has no lights by default");
        for l in &scene.lights {
            assert!(
                l.casts_shadows,
                "{name}: every built-in light casts shadows"
            );
            assert!(
                l.diffuse.max_element() > 0.1,
                "{name}: light too dim: {:?}",
                l.diffuse
            );
            assert!(
                l.ambient.max_element() < 0.2 * l.diffuse.max_element(),
                "{name}: ambient must stay small next to diffuse"
            );
        }
        // The camera looks at something: the scene's bounds are in front of it.
        let (lo, hi) = scene.world_bounds(false).unwrap();
        let center = 0.5 * (lo + hi);
        let forward = (scene.camera.target - scene.camera.position).normalize();
        assert!(
            forward.dot(center - scene.camera.position) > 0.0,
            "{name}: the camera looks away from the scene"
        );
    }
}

#[test]
fn unknown_scene_error_lists_every_name() {
    let err = builtin::build("sponza", &BuiltinOptions::default()).unwrap_err();
    assert!(matches!(err, SceneError::UnknownScene { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("sponza"), "{msg}");
    for name in SCENE_NAMES {
        assert!(msg.contains(name), "error does not list {name}: {msg}");
    }
}

#[test]
fn zero_lights_is_a_valid_dark_scene() {
    for name in ["atrium", "terrain", "dragon", "cubes"] {
        let scene = builtin::build(name, &with_lights(0)).unwrap();
        assert!(scene.lights.is_empty(), "{name}");
        scene.validate().unwrap();
    }
}

#[test]
fn more_than_max_lights_is_an_error_and_max_is_fine() {
    for name in ["atrium", "dragon", "plane-spot"] {
        let err = builtin::build(name, &with_lights(MAX_LIGHTS + 1)).unwrap_err();
        assert!(matches!(err, SceneError::InvalidRequest(_)), "{err:?}");
        assert!(err.to_string().contains(&MAX_LIGHTS.to_string()), "{err}");
    }
    assert!(builtin::check_light_count(MAX_LIGHTS).is_ok());
    for name in ["atrium", "terrain", "dragon"] {
        let scene = builtin::build(name, &with_lights(MAX_LIGHTS)).unwrap();
        assert_eq!(scene.lights.len(), MAX_LIGHTS, "{name}");
    }
}

#[test]
fn same_seed_same_scene_different_seed_different_lights() {
    let opts = |seed, lights| BuiltinOptions {
        seed,
        lights,
        ..BuiltinOptions::default()
    };
    for (name, lights) in [
        ("atrium", None),
        ("terrain", None),
        ("dragon", None),
        ("cubes", Some(5)),
        ("atrium", Some(200)),
    ] {
        let a = builtin::build(name, &opts(7, lights)).unwrap();
        let b = builtin::build(name, &opts(7, lights)).unwrap();
        assert_eq!(a, b, "{name}: same seed must give the same scene");
        let c = builtin::build(name, &opts(8, lights)).unwrap();
        assert_ne!(
            a.lights, c.lights,
            "{name}: another seed must move the lights"
        );
        assert_eq!(a.lights.len(), c.lights.len(), "{name}");
        // Geometry does not depend on the seed, so benchmarks compare the same triangles.
        assert_eq!(a.meshes, c.meshes, "{name}");
        assert_eq!(a.instances, c.instances, "{name}");
    }
}

#[test]
fn light_mix_parses_and_rejects_nonsense() {
    for (s, m) in [
        ("all", LightMix::All),
        ("mixed", LightMix::All),
        ("Spot", LightMix::Spot),
        (" point ", LightMix::Point),
        ("directional", LightMix::Directional),
    ] {
        assert_eq!(s.parse::<LightMix>().unwrap(), m, "{s}");
    }
    for m in [
        LightMix::All,
        LightMix::Spot,
        LightMix::Point,
        LightMix::Directional,
    ] {
        assert_eq!(m.to_string().parse::<LightMix>().unwrap(), m);
    }
    assert_eq!(LightMix::default(), LightMix::All);
    let err = "sun".parse::<LightMix>().unwrap_err().to_string();
    assert!(err.contains("sun"), "{err}");
    for name in LightMix::NAMES {
        assert!(err.contains(name), "{err}");
    }
}

#[test]
fn light_counts_split_like_a_real_scene() {
    assert_eq!(
        LightCounts::split(32, LightMix::All),
        LightCounts {
            spot: 21,
            point: 10,
            directional: 1
        }
    );
    assert_eq!(LightCounts::split(0, LightMix::All).total(), 0);
    assert_eq!(LightCounts::split(1, LightMix::All).spot, 1);
    for n in 0..300 {
        let c = LightCounts::split(n, LightMix::All);
        assert_eq!(c.total(), n);
        assert!(c.directional <= 2, "n = {n}: {c:?}");
        if n >= 3 {
            assert!(
                c.spot >= 1 && c.point >= 1 && c.directional >= 1,
                "n = {n}: {c:?}"
            );
        }
        if n >= 20 {
            let spot = c.spot as f32 / n as f32;
            let point = c.point as f32 / n as f32;
            assert!((0.55..=0.7).contains(&spot), "n = {n}: {c:?}");
            assert!((0.25..=0.36).contains(&point), "n = {n}: {c:?}");
        }
    }
    for (mix, want) in [
        (LightMix::Spot, (7, 0, 0)),
        (LightMix::Point, (0, 7, 0)),
        (LightMix::Directional, (0, 0, 7)),
    ] {
        let c = LightCounts::split(7, mix);
        assert_eq!((c.spot, c.point, c.directional), want);
    }
}

#[test]
fn single_type_mixes_give_only_that_type() {
    for name in ["atrium", "terrain", "dragon", "cubes"] {
        for (mix, want) in [
            (LightMix::Spot, (9, 0, 0)),
            (LightMix::Point, (0, 9, 0)),
            (LightMix::Directional, (0, 0, 9)),
        ] {
            let opts = BuiltinOptions {
                lights: Some(9),
                mix,
                ..BuiltinOptions::default()
            };
            let scene = builtin::build(name, &opts).unwrap();
            assert_eq!(count_types(&scene), want, "{name} {mix}");
        }
    }
}

#[test]
fn default_shadow_resolutions_and_the_override() {
    let scene = build("atrium");
    for l in &scene.lights {
        let want = match l.kind {
            LightKind::Spot { .. } => 512,
            LightKind::Point { .. } => 256,
            LightKind::Directional {
                cascades,
                split_lambda,
                ..
            } => {
                assert_eq!(cascades, 3);
                assert_eq!(split_lambda, 0.75);
                1024
            }
        };
        assert_eq!(l.shadow_resolution, want, "{}", l.type_name());
    }
    for name in SCENE_NAMES {
        let opts = BuiltinOptions {
            shadow_resolution: Some(333),
            ..BuiltinOptions::default()
        };
        let scene = builtin::build(name, &opts).unwrap();
        assert!(
            scene.lights.iter().all(|l| l.shadow_resolution == 333),
            "{name}"
        );
    }
    for bad in [0, 16385] {
        let opts = BuiltinOptions {
            shadow_resolution: Some(bad),
            ..BuiltinOptions::default()
        };
        let err = builtin::build("cubes", &opts).unwrap_err();
        assert!(matches!(err, SceneError::InvalidRequest(_)), "{err:?}");
    }
}
