//! glTF node animations: the clips read, the instances they move, where those stand at a time
//! (against the rotation worked out by hand), and channels that cannot play dropped with a
//! note naming them.

use glam::{Quat, Vec3};
use manyshadows_scene::animation::{Interpolation, Playing, Property};
use serde_json::json;

use super::common::*;

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The quad document with node 0 (no mesh) the parent of node 1 (the quad, 2 along x), and one
/// clip, "spin": node 0 turns 90° about y over a second (LINEAR), node 1 rises 1 along y
/// (STEP at 0.5 s), plus the bad channels `bad` names (each a channel of node 1).
fn animated(bad: &[&str]) -> serde_json::Value {
    let mut doc = quad_doc(json!([
        { "children": [1] },
        { "mesh": 0, "translation": [2.0, 0.0, 0.0] }
    ]));
    let quarter = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors: Vec<serde_json::Value> = Vec::new();
    let first_accessor = doc["accessors"].as_array().unwrap().len();
    let first_view = doc["bufferViews"].as_array().unwrap().len();
    let mut add = |data: Vec<u8>, count: usize, kind: &str| {
        views.push(json!({ "buffer": 1, "byteOffset": bin.len(), "byteLength": data.len() }));
        accessors.push(json!({
            "bufferView": first_view + views.len() - 1, "componentType": 5126,
            "count": count, "type": kind
        }));
        bin.extend(data);
        first_accessor + accessors.len() - 1
    };
    let times = add(floats(&[0.0, 1.0]), 2, "SCALAR");
    let turns = add(
        floats(&[0., 0., 0., 1., quarter.x, quarter.y, quarter.z, quarter.w]),
        2,
        "VEC4",
    );
    let step_times = add(floats(&[0.0, 0.5]), 2, "SCALAR");
    let rises = add(floats(&[2., 0., 0., 2., 1., 0.]), 2, "VEC3");
    let mut samplers = vec![
        json!({ "input": times, "output": turns, "interpolation": "LINEAR" }),
        json!({ "input": step_times, "output": rises, "interpolation": "STEP" }),
    ];
    let mut channels = vec![
        json!({ "sampler": 0, "target": { "node": 0, "path": "rotation" } }),
        json!({ "sampler": 1, "target": { "node": 1, "path": "translation" } }),
    ];
    for b in bad {
        let sampler = match *b {
            "nan" => {
                let t = add(floats(&[0.0, f32::NAN]), 2, "SCALAR");
                json!({ "input": t, "output": rises })
            }
            "backwards" => {
                let t = add(floats(&[1.0, 0.5]), 2, "SCALAR");
                json!({ "input": t, "output": rises })
            }
            "cubic count" => {
                json!({ "input": times, "output": rises, "interpolation": "CUBICSPLINE" })
            }
            _ => unreachable!(),
        };
        samplers.push(sampler);
        channels.push(json!({
            "sampler": samplers.len() - 1, "target": { "node": 1, "path": "scale" }
        }));
    }
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    doc["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "uri": uri, "byteLength": bin.len() }));
    doc["bufferViews"].as_array_mut().unwrap().extend(views);
    doc["accessors"].as_array_mut().unwrap().extend(accessors);
    doc["animations"] = json!([{ "name": "spin", "samplers": samplers, "channels": channels }]);
    doc
}

#[test]
fn an_animated_node_moves_the_meshes_under_it() {
    let dir = temp_dir("gltf_animation_moves");
    let loaded = scene_of(&save_json(&dir, "spin.gltf", &animated(&[])));
    let scene = &loaded.scene;
    let anim = &scene.animations;
    assert_eq!(anim.clips.len(), 1, "{:?}", loaded.notes);
    assert_eq!(anim.clips[0].name, "spin");
    assert_eq!(anim.clips[0].duration(), 1.0);
    let kinds: Vec<_> = anim.clips[0]
        .channels
        .iter()
        .map(|c| (c.node, c.property, c.interpolation))
        .collect();
    assert_eq!(
        kinds,
        [
            (0, Property::Rotation, Interpolation::Linear),
            (1, Property::Translation, Interpolation::Step)
        ]
    );
    // The quad (instance 0) moves, through node 1; the ground plane added beside it does not.
    assert_eq!(anim.moving.len(), 1);
    assert_eq!((anim.moving[0].instance, anim.moving[0].node), (0, 1));
    // Its vertices are baked at rest: the unit quad shifted 2 along x.
    let quad = &scene.meshes[scene.instances[0].mesh];
    assert!(quad.positions.contains(&Vec3::new(3.0, 1.0, 0.0)));
    let at = |t: f32, p: Vec3| {
        let pose = anim.pose(Playing::One(0), t);
        assert_eq!(pose.len(), 1);
        pose[0].1.transform_point3(p)
    };
    // At rest (t = 0) it stays where it was drawn.
    assert!(close(
        at(0.0, Vec3::new(3.0, 1.0, 0.0)),
        Vec3::new(3.0, 1.0, 0.0),
        1e-6
    ));
    // At 1 s: risen by 1 (the step at 0.5 s), then turned 90° about y: (x, y, z) → (z, y, −x).
    let p = at(1.0, Vec3::new(3.0, 1.0, 0.0));
    assert!(close(p, Vec3::new(0.0, 2.0, -3.0), 1e-5), "{p}");
    // At 0.25 s: a quarter of the turn (22.5°) and not yet risen.
    let a = 22.5f32.to_radians();
    let p = at(0.25, Vec3::new(3.0, 1.0, 0.0));
    assert!(
        close(p, Vec3::new(3.0 * a.cos(), 1.0, -3.0 * a.sin()), 1e-5),
        "{p}"
    );
    // Looping: 1.25 s plays as 0.25 s.
    assert!(close(at(1.25, Vec3::new(3.0, 1.0, 0.0)), p, 1e-5));
}

#[test]
fn channels_that_cannot_play_are_dropped_with_a_note() {
    let dir = temp_dir("gltf_animation_bad");
    let loaded = scene_of(&save_json(
        &dir,
        "bad.gltf",
        &animated(&["nan", "backwards", "cubic count"]),
    ));
    let notes = loaded.notes.join("\n");
    for (channel, why) in [
        (2, "a key time is not finite"),
        (3, "its key times do not increase"),
        (4, "it has 2 key times but 2 values (6 expected)"),
    ] {
        let said = format!("channel {channel} (node 1 scale): {why}");
        assert!(
            notes.contains(&said),
            "no note saying '{said}' in:\n{notes}"
        );
    }
    // The two good channels still play.
    let anim = &loaded.scene.animations;
    assert_eq!(anim.clips[0].channels.len(), 2);
    assert_eq!(anim.choose("spin"), Ok(Playing::One(0)));
}

#[test]
fn a_file_without_animations_moves_nothing() {
    let dir = temp_dir("gltf_animation_none");
    let loaded = scene_of(&save_json(
        &dir,
        "still.gltf",
        &quad_doc(json!([{ "mesh": 0 }])),
    ));
    assert!(loaded.scene.animations.is_empty());
    assert!(loaded.scene.animations.choose("0").is_err());
}

/// The quad skinned to one joint (node 1, standing 2 above the origin, no inverse bind
/// matrices: the identity), every vertex on joint `joint` with weight 1.
fn skinned_quad(joint: u16) -> serde_json::Value {
    let mut doc = quad_doc(json!([
        { "mesh": 0, "skin": 0 },
        { "translation": [0.0, 2.0, 0.0] }
    ]));
    let mut bin: Vec<u8> = (0..4)
        .flat_map(|_| [joint, 0, 0, 0])
        .flat_map(u16::to_le_bytes)
        .collect();
    bin.extend(floats(&[1.0, 0.0, 0.0, 0.0].repeat(4)));
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    doc["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "uri": uri, "byteLength": bin.len() }));
    let views = doc["bufferViews"].as_array().unwrap().len();
    doc["bufferViews"].as_array_mut().unwrap().extend([
        json!({ "buffer": 1, "byteOffset": 0, "byteLength": 32 }),
        json!({ "buffer": 1, "byteOffset": 32, "byteLength": 64 }),
    ]);
    let accessors = doc["accessors"].as_array().unwrap().len();
    doc["accessors"].as_array_mut().unwrap().extend([
        json!({ "bufferView": views, "componentType": 5123, "count": 4, "type": "VEC4" }),
        json!({ "bufferView": views + 1, "componentType": 5126, "count": 4, "type": "VEC4" }),
    ]);
    let attributes = &mut doc["meshes"][0]["primitives"][0]["attributes"];
    attributes["JOINTS_0"] = json!(accessors);
    attributes["WEIGHTS_0"] = json!(accessors + 1);
    doc["skins"] = json!([{ "joints": [1] }]);
    doc
}

#[test]
fn a_skin_places_its_mesh_by_its_joints_and_a_bad_one_is_refused() {
    let dir = temp_dir("gltf_skin");
    let loaded = scene_of(&save_json(&dir, "skinned.gltf", &skinned_quad(0)));
    let scene = &loaded.scene;
    assert_eq!(scene.animations.skins.len(), 1, "{:?}", loaded.notes);
    // The node's own transform plays no part; the joint 2 above lifts every vertex by 2.
    let quad = &scene.meshes[scene.animations.skins[0].mesh];
    assert!(
        quad.positions.contains(&Vec3::new(1.0, 3.0, 0.0)),
        "{:?}",
        quad.positions
    );
    assert_eq!(scene.instances[0].transform, glam::Mat4::IDENTITY);
    // A vertex naming a joint the skin lacks: refused, naming the skin and the vertex.
    let path = save_json(&dir, "bad-skin.gltf", &skinned_quad(3));
    let err = manyshadows_scene::loaders::load_scene(&path)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("glTF skin 0 of mesh")
            && err.contains("vertex 0 names joint 3 of a skin of 1 joints"),
        "{err}"
    );
}

/// Eight joints a vertex (`JOINTS_1`, `WEIGHTS_1`): the first set puts weight 1 on joint 0
/// (2 above the origin), the second weight 1 on joint 1 (4 above); normalized over both, each
/// vertex takes half of each, so it stands 3 above.
#[test]
fn a_second_set_of_joints_counts_with_the_first() {
    let dir = temp_dir("gltf_skin_eight");
    let mut doc = skinned_quad(0);
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "translation": [0.0, 4.0, 0.0] }));
    doc["skins"] = json!([{ "joints": [1, 2] }]);
    let mut bin: Vec<u8> = (0..4)
        .flat_map(|_| [1u16, 0, 0, 0])
        .flat_map(u16::to_le_bytes)
        .collect();
    bin.extend(floats(&[1.0, 0.0, 0.0, 0.0].repeat(4)));
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let buffer = doc["buffers"].as_array().unwrap().len();
    doc["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "uri": uri, "byteLength": bin.len() }));
    let views = doc["bufferViews"].as_array().unwrap().len();
    doc["bufferViews"].as_array_mut().unwrap().extend([
        json!({ "buffer": buffer, "byteOffset": 0, "byteLength": 32 }),
        json!({ "buffer": buffer, "byteOffset": 32, "byteLength": 64 }),
    ]);
    let accessors = doc["accessors"].as_array().unwrap().len();
    doc["accessors"].as_array_mut().unwrap().extend([
        json!({ "bufferView": views, "componentType": 5123, "count": 4, "type": "VEC4" }),
        json!({ "bufferView": views + 1, "componentType": 5126, "count": 4, "type": "VEC4" }),
    ]);
    let attributes = &mut doc["meshes"][0]["primitives"][0]["attributes"];
    attributes["JOINTS_1"] = json!(accessors);
    attributes["WEIGHTS_1"] = json!(accessors + 1);
    let loaded = scene_of(&save_json(&dir, "eight.gltf", &doc));
    let scene = &loaded.scene;
    let quad = &scene.meshes[scene.animations.skins[0].mesh];
    assert!(
        quad.positions.contains(&Vec3::new(1.0, 4.0, 0.0)),
        "{:?}",
        quad.positions
    );
}
