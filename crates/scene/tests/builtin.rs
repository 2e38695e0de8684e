//! Tests of the built-in scenes, their seeded light layouts and the procedural primitives.
//!
//! The scenes are test and benchmark fixtures for the whole project, so what other code relies
//! on is pinned here: triangle and instance counts, light counts and types, determinism per
//! seed, the exact parameters of the analytic scenes, and the winding/normal conventions of
//! every generated mesh.

use std::collections::HashMap;
use std::f32::consts::TAU;

use glam::{Mat4, Vec2, Vec3};
use manyshadows_scene::builtin::{
    self, atrium, dragon, terrain, BuiltinOptions, LightCounts, LightMix, MAX_LIGHTS, SCENE_NAMES,
};
use manyshadows_scene::{primitives, LightKind, Mesh, Scene, SceneError};

fn build(name: &str) -> Scene {
    builtin::build(name, &BuiltinOptions::default())
        .unwrap_or_else(|e| panic!("scene {name} failed to build: {e}"))
}

fn with_lights(n: usize) -> BuiltinOptions {
    BuiltinOptions {
        lights: Some(n),
        ..BuiltinOptions::default()
    }
}

fn count_types(scene: &Scene) -> (usize, usize, usize) {
    let mut c = (0, 0, 0);
    for l in &scene.lights {
        match l.kind {
            LightKind::Spot { .. } => c.0 += 1,
            LightKind::Point { .. } => c.1 += 1,
            LightKind::Directional { .. } => c.2 += 1,
        }
    }
    c
}

fn light_position(kind: &LightKind) -> Option<Vec3> {
    match *kind {
        LightKind::Spot { position, .. } | LightKind::Point { position, .. } => Some(position),
        LightKind::Directional { .. } => None,
    }
}

// ---------------------------------------------------------------------------------------------
// Every scene

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

// ---------------------------------------------------------------------------------------------
// atrium

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

// ---------------------------------------------------------------------------------------------
// terrain

#[test]
fn terrain_is_a_251_square_grid_with_600_objects_on_it() {
    let scene = build("terrain");
    let grid = &scene.meshes[terrain::TERRAIN_MESH];
    assert_eq!(grid.positions.len(), 251 * 251);
    assert_eq!(grid.triangle_count(), 125_000);
    let (lo, hi) = grid.bounds().unwrap();
    assert_eq!((lo.x, lo.z, hi.x, hi.z), (-50.0, -50.0, 50.0, 50.0));
    assert!(
        hi.y - lo.y > 4.0,
        "the ground should not be flat: {lo} {hi}"
    );
    let terrain_instances: Vec<_> = scene
        .instances
        .iter()
        .filter(|i| i.mesh == terrain::TERRAIN_MESH)
        .collect();
    assert_eq!(terrain_instances.len(), 1);

    let objects: Vec<_> = scene
        .instances
        .iter()
        .filter(|i| i.mesh != terrain::TERRAIN_MESH)
        .collect();
    assert_eq!(objects.len(), 600);
    let mut per_mesh: HashMap<usize, usize> = HashMap::new();
    for o in &objects {
        *per_mesh.entry(o.mesh).or_default() += 1;
    }
    let mut counts: Vec<usize> = per_mesh.values().copied().collect();
    counts.sort();
    assert_eq!(counts, vec![50, 150, 200, 200]);
    for o in &objects {
        let t = o.transform.w_axis.truncate();
        assert!(t.x.abs() < 50.0 && t.z.abs() < 50.0);
        let ground = terrain::surface_height(t.x, t.z);
        assert!(
            t.y <= ground && t.y > ground - 0.5,
            "object at {t} floats or sinks (ground {ground})"
        );
    }

    assert_eq!(scene.lights.len(), terrain::DEFAULT_TERRAIN_LIGHTS);
    let (spot, point, directional) = count_types(&scene);
    assert_eq!(directional, 1);
    assert!(spot >= 1 && point >= 1);
    for l in &scene.lights {
        if let LightKind::Directional { cascades, .. } = l.kind {
            assert_eq!(cascades, 3);
        }
        if let Some(p) = light_position(&l.kind) {
            assert!(
                p.y > terrain::surface_height(p.x, p.z) + 1.0,
                "light under ground at {p}"
            );
        }
    }
    // The camera is above the ground it looks across.
    let c = scene.camera.position;
    assert!(c.y > terrain::surface_height(c.x, c.z) + 10.0);
}

#[test]
fn terrain_surface_height_follows_the_triangles() {
    let scene = build("terrain");
    let grid = &scene.meshes[terrain::TERRAIN_MESH];
    // Exact at vertices.
    for &idx in &[0usize, 1, 251, 300, 31_000, 251 * 251 - 1] {
        let p = grid.positions[idx];
        let h = terrain::surface_height(p.x, p.z);
        assert!((h - p.y).abs() < 1e-5, "vertex {idx}: {h} vs {}", p.y);
    }
    // On the triangle's plane at each triangle's centroid.
    for tri in grid.indices.chunks_exact(3).step_by(997) {
        let [a, b, c] = [0, 1, 2].map(|k| grid.positions[tri[k] as usize]);
        let centroid = (a + b + c) / 3.0;
        let h = terrain::surface_height(centroid.x, centroid.z);
        assert!((h - centroid.y).abs() < 1e-3, "{h} vs {}", centroid.y);
    }
}

// ---------------------------------------------------------------------------------------------
// dragon

#[test]
fn dragon_stand_in_has_35k_triangles_and_stands_2m_tall() {
    let mesh = dragon::dragon_stand_in();
    mesh.validate().unwrap();
    let tris = mesh.triangle_count();
    assert!((30_000..=40_000).contains(&tris), "{tris} triangles");
    let scene = build("dragon");
    let model = &scene.instances[1];
    let (lo, hi) = scene.meshes[model.mesh].bounds().unwrap();
    let (lo, hi) = (
        model.transform.transform_point3(lo),
        model.transform.transform_point3(hi),
    );
    assert!(lo.y.abs() < 1e-4, "sits on the floor: {lo}");
    assert!(
        (hi.y - dragon::DRAGON_HEIGHT).abs() < 1e-3,
        "2 m tall: {hi}"
    );
    assert!(
        (lo.x + hi.x).abs() < 1e-3 && (lo.z + hi.z).abs() < 1e-3,
        "centred: {lo} {hi}"
    );
    assert_eq!(
        scene.triangle_count(),
        tris + scene.meshes[0].triangle_count()
    );
}

#[test]
fn dragon_is_ringed_by_exactly_n_spots() {
    for n in [1usize, 8, 32] {
        let scene = builtin::build("dragon", &with_lights(n)).unwrap();
        assert_eq!(count_types(&scene), (n, 0, 0), "n = {n}");
        let mut angles = Vec::new();
        for l in &scene.lights {
            let LightKind::Spot {
                position,
                direction,
                ..
            } = l.kind
            else {
                unreachable!()
            };
            assert!((position.y - dragon::RING_HEIGHT).abs() < 1e-4);
            let radial = Vec2::new(position.x, position.z).length();
            assert!((radial - dragon::RING_RADIUS).abs() < 1e-4);
            let to_target = (dragon::RING_TARGET - position).normalize();
            assert!(direction.dot(to_target) > 0.9999, "aims at the model");
            angles.push(position.z.atan2(position.x).rem_euclid(TAU));
        }
        angles.sort_by(f32::total_cmp);
        for k in 0..n {
            let next = if k + 1 < n {
                angles[k + 1]
            } else {
                angles[0] + TAU
            };
            let gap = next - angles[k];
            assert!(
                (gap - TAU / n as f32).abs() < 1e-3,
                "n = {n}: uneven ring, gap {gap}"
            );
        }
    }
    assert_eq!(build("dragon").lights.len(), dragon::DEFAULT_RING_LIGHTS);
}

#[test]
fn dragon_ring_takes_point_or_directional_mix() {
    for (mix, want) in [
        (LightMix::Point, (0, 8, 0)),
        (LightMix::Directional, (0, 0, 8)),
    ] {
        let opts = BuiltinOptions {
            mix,
            ..BuiltinOptions::default()
        };
        let scene = builtin::build("dragon", &opts).unwrap();
        assert_eq!(count_types(&scene), want);
    }
}

#[test]
fn dragon_normalises_a_user_mesh_and_rejects_a_broken_one() {
    let mut mesh = primitives::merge(&[(
        primitives::cuboid(Vec3::new(10.0, 40.0, 20.0)),
        Mat4::from_translation(Vec3::new(100.0, 50.0, -7.0)),
    )]);
    mesh.normals.clear(); // A loader may hand us a mesh without normals.
    let opts = BuiltinOptions {
        mesh: Some(mesh),
        ..BuiltinOptions::default()
    };
    let scene = builtin::build("dragon", &opts).unwrap();
    let model = &scene.instances[1];
    assert_eq!(scene.meshes[model.mesh].normals.len(), 24);
    let (lo, hi) = scene.world_bounds(false).unwrap();
    assert!((hi.y - 2.0).abs() < 1e-4 && lo.y.abs() < 1e-4, "{lo} {hi}");
    let (mlo, mhi) = scene.meshes[model.mesh].bounds().unwrap();
    let (mlo, mhi) = (
        model.transform.transform_point3(mlo),
        model.transform.transform_point3(mhi),
    );
    assert!((mlo.x + mhi.x).abs() < 1e-4 && (mlo.z + mhi.z).abs() < 1e-4);
    assert!(
        (mhi.z - mlo.z - 1.0).abs() < 1e-4,
        "uniform scale: 20 m deep becomes 1 m"
    );

    let broken = Mesh {
        uvs: Vec::new(),
        name: "broken".into(),
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: vec![Vec3::Z; 3],
        indices: vec![0, 1, 7],
    };
    let opts = BuiltinOptions {
        mesh: Some(broken),
        ..BuiltinOptions::default()
    };
    assert!(matches!(
        builtin::build("dragon", &opts),
        Err(SceneError::InvalidMesh { .. })
    ));
    let empty = BuiltinOptions {
        mesh: Some(Mesh::default()),
        ..BuiltinOptions::default()
    };
    assert!(builtin::build("dragon", &empty).is_err());
}

// ---------------------------------------------------------------------------------------------
// analytic scenes

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

// ---------------------------------------------------------------------------------------------
// cubes and the generic layout

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

// ---------------------------------------------------------------------------------------------
// primitives

/// Every triangle's geometric normal agrees with its vertex normals (CCW seen from outside),
/// and no triangle is degenerate.
fn assert_winding_matches_normals(mesh: &Mesh) {
    mesh.validate().unwrap();
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        let g = (b - a).cross(c - a);
        assert!(
            g.length_squared() > 0.0,
            "{}: triangle {t} is degenerate",
            mesh.name
        );
        let n: Vec3 = [0, 1, 2]
            .map(|k| mesh.normals[tri[k] as usize])
            .iter()
            .sum();
        assert!(
            g.dot(n) > 0.0,
            "{}: triangle {t} is wound against its normals",
            mesh.name
        );
    }
    for n in &mesh.normals {
        assert!(
            (n.length() - 1.0).abs() < 1e-3,
            "{}: normal {n} not unit",
            mesh.name
        );
    }
}

/// For a closed convex-ish mesh: every triangle faces away from the mesh's centre.
fn assert_outward_from_center(mesh: &Mesh) {
    let (lo, hi) = mesh.bounds().unwrap();
    let center = 0.5 * (lo + hi);
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        let g = (b - a).cross(c - a);
        let centroid = (a + b + c) / 3.0;
        assert!(
            g.dot(centroid - center) > 0.0,
            "{}: triangle {t} faces inwards",
            mesh.name
        );
    }
}

/// Closed and consistently wound: every edge (matched by position, since sharp edges split
/// vertices) is used exactly once in each direction.
fn assert_watertight(mesh: &Mesh) {
    let key = |p: Vec3| (p * 1e4).round().as_ivec3().to_array();
    let mut edges: HashMap<([i32; 3], [i32; 3]), i32> = HashMap::new();
    for tri in mesh.indices.chunks_exact(3) {
        for k in 0..3 {
            let a = key(mesh.positions[tri[k] as usize]);
            let b = key(mesh.positions[tri[(k + 1) % 3] as usize]);
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "{}: edge {a:?}->{b:?} used {n} times", mesh.name);
        assert_eq!(
            edges.get(&(b, a)),
            Some(&1),
            "{}: edge {a:?}->{b:?} is open",
            mesh.name
        );
    }
}

#[test]
fn closed_primitives_are_watertight_with_outward_normals() {
    let cuboid = primitives::cuboid(Vec3::new(1.0, 2.0, 3.0));
    assert_eq!((cuboid.positions.len(), cuboid.triangle_count()), (24, 12));
    let sphere = primitives::uv_sphere(1.5, 24, 12);
    assert_eq!(sphere.triangle_count(), 2 * 24 * 11);
    let cylinder = primitives::cylinder(0.5, 2.0, 20);
    assert_eq!(cylinder.triangle_count(), 4 * 20);
    let (lo, hi) = cylinder.bounds().unwrap();
    assert!(
        lo.y.abs() < 1e-6 && (hi.y - 2.0).abs() < 1e-6,
        "base at y = 0"
    );
    let cone = primitives::cone(1.0, 2.0, 16);
    assert_eq!(cone.triangle_count(), 2 * 16);
    for mesh in [&cuboid, &sphere, &cylinder, &cone] {
        assert_winding_matches_normals(mesh);
        assert_outward_from_center(mesh);
        assert_watertight(mesh);
    }
    // Tessellation arguments are clamped, never invalid.
    for mesh in [
        primitives::uv_sphere(1.0, 0, 0),
        primitives::cylinder(1.0, 1.0, 0),
        primitives::plane(1.0, 1.0, 0),
    ] {
        assert_winding_matches_normals(&mesh);
        assert!(mesh.triangle_count() > 0);
    }
}

#[test]
fn tubes_and_columns_are_closed_and_wound_outwards() {
    let torus = primitives::torus(2.0, 0.5, 32, 12);
    assert_eq!(torus.triangle_count(), 2 * 32 * 12);
    let knot = primitives::torus_knot(2, 3, 2.0, 0.3, 200, 12);
    assert_eq!(knot.triangle_count(), 2 * 200 * 12);
    let column = primitives::column(0.3, 4.4, 16);
    let stand_in = dragon::dragon_stand_in();
    for mesh in [&torus, &knot, &column, &stand_in] {
        assert_winding_matches_normals(mesh);
        assert_watertight(mesh);
    }
    // The torus's tube normals point away from its core circle.
    for (p, n) in torus.positions.iter().zip(&torus.normals) {
        let core = Vec3::new(p.x, 0.0, p.z).normalize() * 2.0;
        assert!(n.dot(*p - core) > 0.0);
    }
    let (lo, hi) = column.bounds().unwrap();
    assert!(lo.y.abs() < 1e-6 && (hi.y - 4.4).abs() < 1e-5);
    assert!((hi.x - 0.48).abs() < 1e-5, "plinth 3.2 r wide: {hi}");
}

#[test]
fn plane_and_heightfield_face_up_and_interpolate_exactly() {
    let plane = primitives::plane(4.0, 2.0, 3);
    assert_eq!(plane.positions.len(), 16);
    assert_eq!(plane.triangle_count(), 18);
    assert_winding_matches_normals(&plane);
    assert!(plane.normals.iter().all(|&n| n == Vec3::Y));
    assert_eq!(
        plane.bounds().unwrap(),
        (Vec3::new(-2.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 1.0))
    );
    let f = |x: f32, z: f32| 0.3 * x * x - 0.2 * z + 0.1 * x * z;
    let field = primitives::heightfield(4.0, 4.0, 8, f);
    assert_winding_matches_normals(&field);
    let grid = |i: u32, j: u32| field.positions[(i * 9 + j) as usize].y;
    for tri in field.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| field.positions[tri[k] as usize]);
        let p = 0.2 * a + 0.3 * b + 0.5 * c;
        let h = primitives::heightfield_height(4.0, 4.0, 8, grid, p.x, p.z);
        assert!((h - p.y).abs() < 1e-5, "{h} vs {}", p.y);
    }
}

#[test]
fn arch_has_a_clear_round_opening_and_outward_faces() {
    let (w, h, r, d) = (4.0, 1.9, 1.6, 0.7);
    let arch = primitives::arch(w, h, r, d, 48);
    assert_winding_matches_normals(&arch);
    let (lo, hi) = arch.bounds().unwrap();
    assert!(
        (lo - Vec3::new(-2.0, 0.0, -0.35)).abs().max_element() < 1e-5,
        "{lo}"
    );
    assert!(
        (hi - Vec3::new(2.0, 1.9, 0.35)).abs().max_element() < 1e-5,
        "{hi}"
    );
    for p in &arch.positions {
        assert!(
            Vec2::new(p.x, p.y).length() > r - 1e-4,
            "vertex {p} inside the opening"
        );
    }
    // Every triangle faces away from the block's interior: its centroid pushed a little along
    // the normal leaves the solid (outside the box or inside the opening).
    let inside = |p: Vec3| {
        p.x.abs() < 0.5 * w
            && p.y > 0.0
            && p.y < h
            && p.z.abs() < 0.5 * d
            && Vec2::new(p.x, p.y).length() > r
    };
    for tri in arch.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| arch.positions[tri[k] as usize]);
        let n = (b - a).cross(c - a).normalize();
        let centroid = (a + b + c) / 3.0;
        assert!(inside(centroid - 1e-3 * n), "behind the face is solid");
        assert!(
            !inside(centroid + 1e-3 * n),
            "in front of the face is empty"
        );
    }
}

#[test]
fn merge_bakes_transforms_and_keeps_mirrored_meshes_outward() {
    let cube = primitives::cuboid(Vec3::ONE);
    let mirrored = Mat4::from_scale(Vec3::new(-2.0, 1.0, 1.0));
    let moved = Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0));
    let merged = primitives::merge(&[(cube.clone(), mirrored), (cube.clone(), moved)]);
    assert_eq!(merged.positions.len(), 48);
    assert_eq!(merged.triangle_count(), 24);
    assert_winding_matches_normals(&merged);
    let (lo, hi) = merged.bounds().unwrap();
    assert_eq!((lo.x, hi.x), (-1.0, 5.5));
    let first = primitives::merge(&[(cube, mirrored)]);
    assert_outward_from_center(&first);
}

#[test]
fn every_mesh_of_every_scene_is_wound_outwards() {
    for &name in SCENE_NAMES {
        let scene = build(name);
        for mesh in &scene.meshes {
            assert_winding_matches_normals(mesh);
        }
    }
}
