//! What a bare model file (no lights, no camera, no floor) gets: a camera that fills the frame
//! with the model, and with `Ground::Auto` a shadow-catching ground plane under a model that
//! has no floor of its own (`Ground::On` always, `Ground::Off` never).

use glam::Vec3;
use manyshadows_scene::loaders::{load_scene_with, write_obj, Ground, LoadOptions};
use manyshadows_scene::primitives::{cuboid, merge, plane};
use manyshadows_scene::Mesh;

use crate::common::{assert_frames, scene_of, temp_dir, write};

fn obj_of(dir: &std::path::Path, name: &str, mesh: &Mesh) -> std::path::PathBuf {
    let mut bytes = Vec::new();
    write_obj(mesh, &mut bytes).unwrap();
    write(dir, name, &bytes)
}

#[test]
fn the_framing_camera_fills_the_frame_with_any_shape() {
    let dir = temp_dir("framing");
    for (name, size) in [
        ("long.obj", Vec3::new(10.0, 1.0, 1.0)),
        ("tall.obj", Vec3::new(0.5, 6.0, 0.5)),
        ("flat.obj", Vec3::new(4.0, 0.01, 4.0)),
        ("cube.obj", Vec3::splat(2.0)),
    ] {
        let mut box_ = cuboid(size);
        box_.name = name.into();
        let loaded = scene_of(&obj_of(&dir, name, &box_));
        let (lo, hi) = loaded.scene.world_bounds(false).unwrap();
        assert_frames(&loaded.scene.camera, lo, hi);
    }
}

fn with_ground(ground: Ground) -> LoadOptions {
    LoadOptions {
        ground,
        ..LoadOptions::default()
    }
}

#[test]
fn a_model_without_a_floor_gets_a_ground_plane() {
    let dir = temp_dir("ground");
    let boxes = merge(&[
        (
            cuboid(Vec3::ONE),
            glam::Mat4::from_translation(Vec3::new(0.0, 2.0, 0.0)),
        ),
        (
            cuboid(Vec3::splat(0.5)),
            glam::Mat4::from_translation(Vec3::new(1.5, 1.0, 0.0)),
        ),
    ]);
    let bare = obj_of(&dir, "bare.obj", &boxes);
    let loaded = load_scene_with(&bare, &with_ground(Ground::Auto)).unwrap();
    let scene = &loaded.scene;
    let ground = scene.instances.last().unwrap();
    assert_eq!(scene.meshes[ground.mesh].name, "ground");
    assert!(!ground.casts_shadows);
    // Under the model, facing up, wider than it.
    let (lo, hi) = scene.world_bounds(false).unwrap();
    let model_lo = Vec3::new(-0.5, 0.75, -0.5);
    let y = ground.transform.w_axis.y;
    assert!(y < model_lo.y && y > model_lo.y - 0.01, "{y}");
    assert!(hi.x - lo.x > 3.0 * 2.25, "{lo} {hi}");
    assert_eq!(scene.meshes[ground.mesh].normals[0], Vec3::Y);
    let note = loaded
        .notes
        .iter()
        .find(|n| n.contains("ground plane"))
        .unwrap();
    assert!(
        note.contains("has no floor") && note.contains("--ground off"),
        "{note}"
    );
    // The camera frames the model, not the ground.
    let model = scene.instances.len() - 1;
    assert_eq!(model, 1);
    let (mlo, mhi) = (Vec3::new(-0.5, 0.75, -0.5), Vec3::new(1.75, 2.5, 0.5));
    assert_frames(&scene.camera, mlo, mhi);

    // Off: nothing; the library's default: nothing.
    for options in [with_ground(Ground::Off), LoadOptions::default()] {
        let loaded = load_scene_with(&bare, &options).unwrap();
        assert_eq!(loaded.scene.instances.len(), 1);
        assert!(loaded.notes.iter().all(|n| !n.contains("ground")));
    }
}

#[test]
fn a_model_with_a_floor_gets_none_unless_asked() {
    let dir = temp_dir("floor");
    // A room: a 10 × 10 floor under a box.
    let room = merge(&[
        (plane(10.0, 10.0, 2), glam::Mat4::IDENTITY),
        (
            cuboid(Vec3::ONE),
            glam::Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)),
        ),
    ]);
    let path = obj_of(&dir, "room.obj", &room);
    let auto = load_scene_with(&path, &with_ground(Ground::Auto)).unwrap();
    assert_eq!(auto.scene.instances.len(), 1, "{:?}", auto.notes);
    let on = load_scene_with(&path, &with_ground(Ground::On)).unwrap();
    assert_eq!(on.scene.instances.len(), 2);
    assert!(
        on.notes
            .iter()
            .any(|n| n.starts_with("asked for: added a ground plane")),
        "{:?}",
        on.notes
    );
    // A floor that is only a strip along one side is not a floor.
    let strip = merge(&[
        (plane(10.0, 1.0, 1), glam::Mat4::IDENTITY),
        (
            cuboid(Vec3::splat(10.0)),
            glam::Mat4::from_translation(Vec3::new(0.0, 5.5, 0.0)),
        ),
    ]);
    let path = obj_of(&dir, "strip.obj", &strip);
    let auto = load_scene_with(&path, &with_ground(Ground::Auto)).unwrap();
    assert_eq!(auto.scene.instances.len(), 2, "{:?}", auto.notes);
}

#[test]
fn added_lights_keep_the_models_own_and_seeded_lights_replace_them() {
    use manyshadows_scene::builtin::{LightMix, MAX_LIGHTS};
    use manyshadows_scene::loaders::{add_seeded_lights, seed_lights};
    let dir = temp_dir("added-lights");
    let bare = obj_of(&dir, "bare.obj", &cuboid(Vec3::ONE));
    let loaded = load_scene_with(&bare, &with_ground(Ground::Auto)).unwrap();
    let rig = loaded.scene.lights.clone();
    assert!(!rig.is_empty(), "a bare model gets a rig");

    // Added: the rig first, unchanged, then the layout `seed_lights` would have placed.
    let mut added = loaded.scene.clone();
    add_seeded_lights(&mut added, 16, 3, LightMix::All, None).unwrap();
    let mut seeded = loaded.scene.clone();
    seed_lights(&mut seeded, 16, 3, LightMix::All, None).unwrap();
    assert_eq!(added.lights.len(), rig.len() + 16);
    assert_eq!(
        &added.lights[..rig.len()],
        &rig[..],
        "the model's own lights are kept"
    );
    assert_eq!(
        &added.lights[rig.len()..],
        &seeded.lights[..],
        "the added lights are the seeded layout's"
    );

    // The total is what is checked against the limit, and the scene is left as it was.
    let mut over = loaded.scene.clone();
    let err = add_seeded_lights(&mut over, MAX_LIGHTS, 1, LightMix::All, None).unwrap_err();
    assert!(
        err.to_string().contains(&MAX_LIGHTS.to_string()),
        "the refusal names the limit: {err}"
    );
    assert_eq!(over.lights, rig, "a refused addition changes nothing");
}
