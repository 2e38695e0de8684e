//! The dragon: the stand-in mesh, the ring of lights around it, and a user mesh in its place.

use std::f32::consts::TAU;

use glam::{Mat4, Vec2, Vec3};
use manyshadows_scene::builtin::{self, dragon, BuiltinOptions, LightMix};
use manyshadows_scene::{primitives, LightKind, Mesh, SceneError};

use crate::common::{build, count_types, with_lights};

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
