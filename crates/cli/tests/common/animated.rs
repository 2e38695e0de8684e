//! A glTF file that moves: a box sliding and turning over a ground under a sun and a point
//! light, both casting shadows, with one clip ("slide", LINEAR, 2 s), and the same scene
//! frozen at any time with the box placed by hand (written through the scene crate's glTF writer), the independent truth of where the
//! animation must have put it.
//!
//! The box's translation keys are x = −1.5, 1.5, −1.5 at 0, 1, 2 s (y = 0.5, resting on the
//! ground), its rotation keys 0, 0.9π and 1.8π about y at the same times: each step turns less
//! than half a circle, so the shorter arc glTF's LINEAR rotation takes is the one written, and
//! the angle is linear in time between keys.

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use manyshadows_scene::loaders::write_gltf;
use manyshadows_scene::primitives::{cuboid, plane};
use manyshadows_scene::{
    Attenuation, Camera, Instance, Light, LightKind, Lighting, Material, Pbr, Scene,
};
use serde_json::{json, Value};

/// The box's x and turn (radians) at `t` seconds, worked out from the keys above (looping at
/// 2 s).
pub fn box_pose(t: f32) -> (f32, f32) {
    let t = if t > 2.0 { t % 2.0 } else { t };
    let (u, x0, x1, a0) = if t <= 1.0 {
        (t, -1.5, 1.5, 0.0)
    } else {
        (t - 1.0, 1.5, -1.5, 0.9)
    };
    (x0 + (x1 - x0) * u, (a0 + 0.9 * u) * std::f32::consts::PI)
}

fn box_transform(t: f32) -> Mat4 {
    let (x, a) = box_pose(t);
    Mat4::from_translation(Vec3::new(x, 0.5, 0.0)) * Mat4::from_rotation_y(a)
}

fn shadowed(kind: LightKind, colour: f32) -> Light {
    Light {
        kind,
        ambient: Vec3::ZERO,
        diffuse: Vec3::splat(colour),
        specular: Vec3::splat(colour),
        attenuation: Attenuation {
            constant: 0.0,
            linear: 0.0,
            quadratic: 1.0,
        },
        casts_shadows: true,
        shadow_resolution: 1024,
        size: 0.0,
    }
}

/// The scene with the box where it stands at `t`.
fn scene_at(t: f32) -> Scene {
    let material = Material {
        diffuse: Vec3::splat(0.7),
        pbr: Some(Pbr {
            metallic: 0.0,
            roughness: 0.8,
        }),
        ..Material::default()
    };
    Scene {
        name: "slide".into(),
        lighting: Lighting::Physical,
        meshes: vec![plane(8.0, 8.0, 1), cuboid(Vec3::ONE)],
        materials: vec![material],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 0, box_transform(t)),
        ],
        lights: vec![
            // A sun rather than a spot: glTF spots fade from their inner to their outer cone,
            // which three.js draws and this renderer does not (a hard cone), and the three.js
            // comparison of these files is about where things stand.
            shadowed(
                LightKind::Directional {
                    direction: Vec3::new(-0.25, -1.0, -0.35).normalize(),
                    cascades: 2,
                    split_lambda: 0.5,
                    cascade_resolution_scale: 1.0,
                },
                2.5,
            ),
            shadowed(
                LightKind::Point {
                    position: Vec3::new(-2.5, 2.5, 2.0),
                    range: 40.0,
                },
                15.0,
            ),
        ],
        camera: Camera {
            position: Vec3::new(0.0, 5.0, 7.0),
            target: Vec3::new(0.0, 0.3, 0.0),
            ..Camera::default()
        },
        ..Default::default()
    }
}

/// Writes the scene frozen at `t` (the box placed by hand) as `dir/frozen-<t>.gltf`.
pub fn frozen(dir: &Path, t: f32) -> PathBuf {
    let path = dir.join(format!("frozen-{t}.gltf"));
    write_gltf(&scene_at(t), &path).unwrap();
    path
}

/// Writes the animated file as `dir/slide.gltf`: the scene at rest (t = 0) with the box's node
/// given translation and rotation keys.
pub fn animated(dir: &Path) -> PathBuf {
    let path = dir.join("slide.gltf");
    write_gltf(&scene_at(0.0), &path).unwrap();
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    // The box's node: the one drawing the second mesh written (the cuboid, 24 vertices).
    let vertices = |mesh: &Value| -> Option<u64> {
        let m = &doc["meshes"][mesh.as_u64()? as usize];
        let position = m["primitives"][0]["attributes"]["POSITION"].as_u64()?;
        doc["accessors"][position as usize]["count"].as_u64()
    };
    let node = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| vertices(&n["mesh"]) == Some(24))
        .expect("the box's node");
    // An animated node carries translation, rotation and scale, never a matrix.
    let n = doc["nodes"][node].as_object_mut().unwrap();
    n.remove("matrix");
    n.insert("translation".into(), json!([-1.5, 0.5, 0.0]));
    let mut bin: Vec<u8> = Vec::new();
    let mut floats = |v: &[f32]| {
        let at = bin.len();
        bin.extend(v.iter().flat_map(|f| f.to_le_bytes()));
        (at, v.len() * 4)
    };
    let q = |a: f32| Quat::from_rotation_y(a * std::f32::consts::PI).to_array();
    let times = floats(&[0.0, 1.0, 2.0]);
    let moves = floats(&[-1.5, 0.5, 0.0, 1.5, 0.5, 0.0, -1.5, 0.5, 0.0]);
    let turns = floats(&[q(0.0), q(0.9), q(1.8)].concat());
    let buffer = doc["buffers"].as_array().unwrap().len();
    let view0 = doc["bufferViews"].as_array().unwrap().len();
    let accessor0 = doc["accessors"].as_array().unwrap().len();
    std::fs::write(dir.join("slide-keys.bin"), &bin).unwrap();
    doc["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "uri": "slide-keys.bin", "byteLength": bin.len() }));
    for (k, ((at, len), (count, kind))) in [times, moves, turns]
        .into_iter()
        .zip([(3, "SCALAR"), (3, "VEC3"), (3, "VEC4")])
        .enumerate()
    {
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": buffer, "byteOffset": at, "byteLength": len }));
        let mut a =
            json!({ "bufferView": view0 + k, "componentType": 5126, "count": count, "type": kind });
        if k == 0 {
            a["min"] = json!([0.0]);
            a["max"] = json!([2.0]);
        }
        doc["accessors"].as_array_mut().unwrap().push(a);
    }
    doc["animations"] = json!([{
        "name": "slide",
        "samplers": [
            { "input": accessor0, "output": accessor0 + 1, "interpolation": "LINEAR" },
            { "input": accessor0, "output": accessor0 + 2, "interpolation": "LINEAR" }
        ],
        "channels": [
            { "sampler": 0, "target": { "node": node, "path": "translation" } },
            { "sampler": 1, "target": { "node": node, "path": "rotation" } }
        ]
    }]);
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    path
}

/// The bending tube's pivot: its upper joint, 1 above the lower one, which stands at the base.
const PIVOT: Vec3 = Vec3::new(0.5, 1.0, 0.0);

/// The upper joint's turn about z at `t` seconds (radians): 0 → 60° over the first second, back
/// to 0 at 2 s (LINEAR keys 0, 60°, 0 at 0, 1, 2 s).
pub fn bend_angle(t: f32) -> f32 {
    let t = if t > 2.0 { t % 2.0 } else { t };
    let u = if t <= 1.0 { t } else { 2.0 - t };
    (60.0 * u).to_radians()
}

/// A tube of radius 0.2 and height 2 standing at x 0.5 (rings every 0.25, 16 sides, open
/// ends), with each vertex's weight on the upper joint: 0 below y 0.5, 1 above 1.5, linear
/// between.
fn tube() -> (manyshadows_scene::Mesh, Vec<f32>) {
    let (rings, sides) = (9u32, 16u32);
    let mut mesh = manyshadows_scene::Mesh {
        name: "tube".into(),
        ..Default::default()
    };
    let mut upper = Vec::new();
    for r in 0..rings {
        let y = r as f32 * 0.25;
        for k in 0..sides {
            let a = k as f32 / sides as f32 * std::f32::consts::TAU;
            let n = Vec3::new(a.cos(), 0.0, -a.sin());
            mesh.positions.push(Vec3::new(PIVOT.x, y, 0.0) + 0.2 * n);
            mesh.normals.push(n);
            upper.push(((y - 0.5) / 1.0).clamp(0.0, 1.0));
        }
    }
    for r in 0..rings - 1 {
        for k in 0..sides {
            let (a, b) = (r * sides + k, r * sides + (k + 1) % sides);
            let (c, d) = (a + sides, b + sides);
            mesh.indices.extend([a, b, d, a, d, c]);
        }
    }
    (mesh, upper)
}

/// The tube's vertices and normals bent by hand: each is its weighted blend of itself and its
/// turn about the pivot (the linear blend skinning does, written out without matrices).
pub fn bent_tube(t: f32) -> manyshadows_scene::Mesh {
    let (mut mesh, upper) = tube();
    let turn = Quat::from_rotation_z(bend_angle(t));
    for ((p, n), w) in mesh.positions.iter_mut().zip(&mut mesh.normals).zip(&upper) {
        let turned = PIVOT + turn * (*p - PIVOT);
        *p = *p * (1.0 - w) + turned * *w;
        *n = (*n * (1.0 - w) + (turn * *n) * *w).normalize();
    }
    mesh
}

/// The scene with the tube bent as at `t`.
fn tube_scene(t: f32) -> Scene {
    let mut scene = scene_at(0.0);
    scene.name = "bend".into();
    scene.meshes[1] = bent_tube(t);
    scene.instances[1].transform = Mat4::IDENTITY;
    scene.materials[0].double_sided = true;
    scene
}

/// Writes the scene with the tube bent by hand as at `t`, `dir/bent-<t>.gltf`.
pub fn bent(dir: &Path, t: f32) -> PathBuf {
    let path = dir.join(format!("bent-{t}.gltf"));
    write_gltf(&tube_scene(t), &path).unwrap();
    path
}

/// Writes the bending file, `dir/bend.gltf`: the straight tube skinned to two joints (the
/// lower at the tube's base, the upper 1 above it, its child), and one clip, "bend", turning
/// the upper joint about z by 0, 60° and 0 at 0, 1 and 2 s.
pub fn bending(dir: &Path) -> PathBuf {
    let path = dir.join("bend.gltf");
    write_gltf(&tube_scene(0.0), &path).unwrap();
    let (_, upper) = tube();
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let node = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| {
            let m = &doc["meshes"][n["mesh"].as_u64().unwrap_or(u64::MAX) as usize];
            let p = m["primitives"][0]["attributes"]["POSITION"].as_u64();
            p.is_some_and(|p| doc["accessors"][p as usize]["count"] == 9 * 16)
        })
        .expect("the tube's node");
    let mesh = doc["nodes"][node]["mesh"].as_u64().unwrap() as usize;
    let mut bin: Vec<u8> = Vec::new();
    let mut chunk = |bytes: Vec<u8>| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let at = bin.len();
        bin.extend(&bytes);
        (at, bytes.len())
    };
    let f32s = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let joints: Vec<u8> = upper
        .iter()
        .flat_map(|_| [0u16, 1, 0, 0])
        .flat_map(u16::to_le_bytes)
        .collect();
    let weights: Vec<f32> = upper.iter().flat_map(|&w| [1.0 - w, w, 0.0, 0.0]).collect();
    let base = Vec3::new(PIVOT.x, 0.0, 0.0);
    let ibm: Vec<f32> = [
        Mat4::from_translation(-base),
        Mat4::from_translation(-PIVOT),
    ]
    .iter()
    .flat_map(|m| m.to_cols_array())
    .collect();
    let q = |deg: f32| Quat::from_rotation_z(deg.to_radians()).to_array();
    let views = [
        chunk(joints),
        chunk(f32s(&weights)),
        chunk(f32s(&ibm)),
        chunk(f32s(&[0.0, 1.0, 2.0])),
        chunk(f32s(&[q(0.0), q(60.0), q(0.0)].concat())),
    ];
    std::fs::write(dir.join("bend-skin.bin"), &bin).unwrap();
    let buffer = doc["buffers"].as_array().unwrap().len();
    doc["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "uri": "bend-skin.bin", "byteLength": bin.len() }));
    let view0 = doc["bufferViews"].as_array().unwrap().len();
    let a0 = doc["accessors"].as_array().unwrap().len();
    let n = upper.len();
    let kinds = [
        (5123, n, "VEC4"),
        (5126, n, "VEC4"),
        (5126, 2, "MAT4"),
        (5126, 3, "SCALAR"),
        (5126, 3, "VEC4"),
    ];
    for (k, ((at, len), (component, count, kind))) in views.into_iter().zip(kinds).enumerate() {
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": buffer, "byteOffset": at, "byteLength": len }));
        let mut a = json!({ "bufferView": view0 + k, "componentType": component, "count": count, "type": kind });
        if k == 3 {
            a["min"] = json!([0.0]);
            a["max"] = json!([2.0]);
        }
        doc["accessors"].as_array_mut().unwrap().push(a);
    }
    let attributes = &mut doc["meshes"][mesh]["primitives"][0]["attributes"];
    attributes["JOINTS_0"] = json!(a0);
    attributes["WEIGHTS_0"] = json!(a0 + 1);
    // The joints: the lower at the base, the upper its child 1 above; a root of the scene.
    let lower = doc["nodes"].as_array().unwrap().len();
    doc["nodes"].as_array_mut().unwrap().extend([
        json!({ "name": "lower", "translation": base.to_array(), "children": [lower + 1] }),
        json!({ "name": "upper", "translation": [0.0, 1.0, 0.0] }),
    ]);
    doc["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!(lower));
    doc["nodes"][node]["skin"] = json!(0);
    doc["skins"] = json!([{ "joints": [lower, lower + 1], "inverseBindMatrices": a0 + 2 }]);
    doc["animations"] = json!([{
        "name": "bend",
        "samplers": [{ "input": a0 + 3, "output": a0 + 4, "interpolation": "LINEAR" }],
        "channels": [{ "sampler": 0, "target": { "node": lower + 1, "path": "rotation" } }]
    }]);
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    path
}

/// The card's one morph target's weight at `t`: 0 → 1 over the first second, back to 0 at 2 s
/// (LINEAR keys 0, 1, 0 at 0, 1, 2 s).
pub fn morph_weight(t: f32) -> f32 {
    let t = if t > 2.0 { t % 2.0 } else { t };
    if t <= 1.0 {
        t
    } else {
        2.0 - t
    }
}

/// A standing card, 1 wide and 1.5 tall at x 0 to 1 (a 6 × 8 grid facing +z), and its morph
/// target's displacement: its top curls 0.8 towards +z, (y / 1.5)² of that at height y.
fn card() -> (manyshadows_scene::Mesh, Vec<Vec3>) {
    let (nx, ny) = (6u32, 8u32);
    let mut mesh = manyshadows_scene::Mesh {
        name: "card".into(),
        ..Default::default()
    };
    let mut delta = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (i as f32 / nx as f32, 1.5 * j as f32 / ny as f32);
            mesh.positions.push(Vec3::new(x, y, 0.0));
            mesh.normals.push(Vec3::Z);
            delta.push(Vec3::new(0.0, 0.0, 0.8 * (y / 1.5).powi(2)));
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let a = j * (nx + 1) + i;
            let (b, c, d) = (a + 1, a + nx + 1, a + nx + 2);
            mesh.indices.extend([a, b, d, a, d, c]);
        }
    }
    (mesh, delta)
}

/// The scene with the card curled by `w` of its target (normals as the file gives them: the
/// target has no normal displacements, so they stay +z).
fn card_scene(w: f32) -> Scene {
    let mut scene = scene_at(0.0);
    scene.name = "curl".into();
    let (mut mesh, delta) = card();
    for (p, d) in mesh.positions.iter_mut().zip(&delta) {
        *p += *d * w;
    }
    scene.meshes[1] = mesh;
    scene.instances[1].transform = Mat4::IDENTITY;
    scene.materials[0].double_sided = true;
    scene
}

/// Writes the scene with the card curled by hand as at `t`, `dir/curled-<t>.gltf`.
pub fn curled(dir: &Path, t: f32) -> PathBuf {
    let path = dir.join(format!("curled-{t}.gltf"));
    write_gltf(&card_scene(morph_weight(t)), &path).unwrap();
    path
}

/// Writes the morphing file, `dir/curl.gltf`: the flat card with one morph target and one
/// clip, "curl", driving its weight 0, 1, 0 at 0, 1, 2 s.
pub fn curling(dir: &Path) -> PathBuf {
    let path = dir.join("curl.gltf");
    write_gltf(&card_scene(0.0), &path).unwrap();
    let (mesh, delta) = card();
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let node = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| {
            let m = &doc["meshes"][n["mesh"].as_u64().unwrap_or(u64::MAX) as usize];
            let p = m["primitives"][0]["attributes"]["POSITION"].as_u64();
            p.is_some_and(|p| doc["accessors"][p as usize]["count"] == mesh.positions.len())
        })
        .expect("the card's node");
    let m = doc["nodes"][node]["mesh"].as_u64().unwrap() as usize;
    let f32s = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let deltas: Vec<f32> = delta.iter().flat_map(|d| d.to_array()).collect();
    let mut bin = f32s(&deltas);
    let keys = bin.len();
    bin.extend(f32s(&[0.0, 1.0, 2.0]));
    let weights = bin.len();
    bin.extend(f32s(&[0.0, 1.0, 0.0]));
    std::fs::write(dir.join("curl-morph.bin"), &bin).unwrap();
    let buffer = doc["buffers"].as_array().unwrap().len();
    doc["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "uri": "curl-morph.bin", "byteLength": bin.len() }));
    let view0 = doc["bufferViews"].as_array().unwrap().len();
    let a0 = doc["accessors"].as_array().unwrap().len();
    let (lo, hi) = delta.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(l, h), d| (l.min(*d), h.max(*d)),
    );
    for (k, (at, len, count, kind)) in [
        (0, keys, delta.len(), "VEC3"),
        (keys, 12, 3, "SCALAR"),
        (weights, 12, 3, "SCALAR"),
    ]
    .into_iter()
    .enumerate()
    {
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": buffer, "byteOffset": at, "byteLength": len }));
        let mut a =
            json!({ "bufferView": view0 + k, "componentType": 5126, "count": count, "type": kind });
        match k {
            0 => {
                a["min"] = json!(lo.to_array());
                a["max"] = json!(hi.to_array());
            }
            1 => {
                a["min"] = json!([0.0]);
                a["max"] = json!([2.0]);
            }
            _ => {}
        }
        doc["accessors"].as_array_mut().unwrap().push(a);
    }
    doc["meshes"][m]["primitives"][0]["targets"] = json!([{ "POSITION": a0 }]);
    doc["meshes"][m]["weights"] = json!([0.0]);
    doc["animations"] = json!([{
        "name": "curl",
        "samplers": [{ "input": a0 + 1, "output": a0 + 2, "interpolation": "LINEAR" }],
        "channels": [{ "sampler": 0, "target": { "node": node, "path": "weights" } }]
    }]);
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    path
}
