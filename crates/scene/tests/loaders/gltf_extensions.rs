//! glTF extensions: `EXT_mesh_gpu_instancing` as instances, `KHR_texture_transform` baked into
//! texture coordinates, `KHR_mesh_quantization`'s integer attributes, and one note for each
//! extension the loader ignores (required ones that it cannot ignore refused by name).

use glam::{Mat4, Quat, Vec2, Vec3};
use manyshadows_scene::loaders::{load_mesh, load_scene};
use manyshadows_scene::Texture;
use serde_json::{json, Value};

use crate::common::{base64, close, gltf_json, png, quad_buffer, save_json, scene_of, temp_dir};

/// The quad document with `extra` appended to its buffer, and where `extra` starts.
fn quad_doc_with(nodes: Value, extra: &[u8]) -> (Value, usize) {
    let mut buf = quad_buffer();
    let at = buf.len();
    buf.extend_from_slice(extra);
    let uri = format!("data:application/octet-stream;base64,{}", base64(&buf));
    let doc = serde_json::from_str(&gltf_json(&nodes.to_string(), Some(&uri), buf.len())).unwrap();
    (doc, at)
}

/// Adds a buffer view of `len` bytes at `offset` and an accessor over it; its index.
fn add_accessor(
    doc: &mut Value,
    offset: usize,
    len: usize,
    component: u32,
    count: usize,
    ty: &str,
) -> usize {
    let views = doc["bufferViews"].as_array_mut().unwrap();
    views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": len }));
    let view = views.len() - 1;
    let accessors = doc["accessors"].as_array_mut().unwrap();
    accessors.push(
        json!({ "bufferView": view, "componentType": component, "count": count, "type": ty }),
    );
    accessors.len() - 1
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

#[test]
fn gpu_instancing_makes_one_instance_per_instance() {
    let dir = temp_dir("instancing");
    let translations = [
        Vec3::ZERO,
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(4.0, 0.0, 1.0),
    ];
    let rotations = [
        Quat::IDENTITY,
        Quat::from_rotation_y(1.0),
        Quat::from_rotation_x(-0.5),
    ];
    let scales = [Vec3::ONE, Vec3::ONE, Vec3::new(2.0, 1.0, 3.0)];
    let mut extra = floats(
        &translations
            .iter()
            .flat_map(|t| t.to_array())
            .collect::<Vec<_>>(),
    );
    extra.extend(floats(
        &rotations
            .iter()
            .flat_map(|q| q.to_array())
            .collect::<Vec<_>>(),
    ));
    extra.extend(floats(
        &scales.iter().flat_map(|s| s.to_array()).collect::<Vec<_>>(),
    ));
    let (mut doc, at) = quad_doc_with(json!([{ "mesh": 0, "translation": [0, 10, 0] }]), &extra);
    let t = add_accessor(&mut doc, at, 36, 5126, 3, "VEC3");
    let r = add_accessor(&mut doc, at + 36, 48, 5126, 3, "VEC4");
    let s = add_accessor(&mut doc, at + 84, 36, 5126, 3, "VEC3");
    doc["nodes"][0]["extensions"] = json!({ "EXT_mesh_gpu_instancing": {
        "attributes": { "TRANSLATION": t, "ROTATION": r, "SCALE": s }
    }});
    doc["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    doc["extensionsRequired"] = json!(["EXT_mesh_gpu_instancing"]);
    let path = save_json(&dir, "instanced.gltf", &doc);
    let want: Vec<Mat4> = (0..3)
        .map(|i| {
            Mat4::from_translation(Vec3::new(0.0, 10.0, 0.0))
                * Mat4::from_scale_rotation_translation(scales[i], rotations[i], translations[i])
        })
        .collect();

    let loaded = scene_of(&path);
    let scene = &loaded.scene;
    assert_eq!(scene.meshes.len(), 1, "one mesh, in its own coordinates");
    assert_eq!(scene.meshes[0].positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(scene.instances.len(), 3);
    for (inst, want) in scene.instances.iter().zip(&want) {
        assert_eq!(inst.mesh, 0);
        assert!(
            inst.transform.abs_diff_eq(*want, 1e-5),
            "{:?} vs {want:?}",
            inst.transform
        );
    }
    assert!(
        loaded
            .notes
            .iter()
            .all(|n| !n.contains("EXT_mesh_gpu_instancing")),
        "{:?}",
        loaded.notes
    );

    // Geometry only: each instance baked.
    let meshes = load_mesh(&path).unwrap();
    assert_eq!(meshes.len(), 3);
    for (m, want) in meshes.iter().zip(&want) {
        assert!(close(
            m.positions[2],
            want.transform_point3(Vec3::new(1.0, 1.0, 0.0)),
            1e-5
        ));
    }

    // An instance scaled to nothing is left out, with a note.
    let mut extra = extra.clone();
    extra[84 + 12..84 + 24].copy_from_slice(&floats(&[0.0, 0.0, 0.0]));
    let (mut doc2, _) = quad_doc_with(json!([{ "mesh": 0 }]), &extra);
    doc2["bufferViews"] = doc["bufferViews"].clone();
    doc2["accessors"] = doc["accessors"].clone();
    doc2["nodes"][0]["extensions"] = doc["nodes"][0]["extensions"].clone();
    let loaded = scene_of(&save_json(&dir, "zero.gltf", &doc2));
    assert_eq!(loaded.scene.instances.len(), 2);
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("1 of its 3 instances")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn texture_transforms_are_baked_into_texture_coordinates() {
    let dir = temp_dir("texture_transform");
    let uvs = [0f32, 0., 1., 0., 1., 1., 0., 1.];
    let (mut doc, at) = quad_doc_with(json!([{ "mesh": 0 }, { "mesh": 2 }]), &floats(&uvs));
    let uv = add_accessor(&mut doc, at, 32, 5126, 4, "VEC2");
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let mut second = doc["meshes"][0].clone();
    second["primitives"][0]["material"] = json!(1);
    doc["meshes"].as_array_mut().unwrap().push(second);
    let image = Texture::from_fn("t", 2, 2, |x, y| [x as u8 * 90, y as u8 * 90, 7, 255]);
    doc["images"] = json!([{ "uri": format!("data:image/png;base64,{}", base64(&png(&image))) }]);
    doc["textures"] = json!([{ "source": 0 }]);
    let transform = json!({ "KHR_texture_transform": {
        "offset": [0.5, 0.25], "rotation": std::f32::consts::FRAC_PI_2, "scale": [2, 3]
    }});
    doc["materials"] = json!([
        { "name": "moved", "pbrMetallicRoughness": {
            "baseColorTexture": { "index": 0, "extensions": transform } } },
        { "name": "mixed",
          "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "extensions": transform } },
          "normalTexture": { "index": 0, "extensions": { "KHR_texture_transform": { "scale": [4, 4] } } } }
    ]);
    doc["extensionsUsed"] = json!(["KHR_texture_transform"]);
    let loaded = scene_of(&save_json(&dir, "transform.gltf", &doc));
    // Scale first, then the rotation by π/2 as the extension applies it ((x, y) → (y, −x)),
    // then the offset.
    let want: Vec<Vec2> = uvs
        .chunks(2)
        .map(|c| Vec2::new(0.5 + 3.0 * c[1], 0.25 - 2.0 * c[0]))
        .collect();
    for mesh in &loaded.scene.meshes {
        for (got, want) in mesh.uvs.iter().zip(&want) {
            assert!(
                (*got - *want).length() < 1e-5,
                "{}: {got} vs {want}",
                mesh.name
            );
        }
    }
    let notes: Vec<&String> = loaded
        .notes
        .iter()
        .filter(|n| n.contains("KHR_texture_transform"))
        .collect();
    assert_eq!(notes.len(), 1, "{:?}", loaded.notes);
    assert!(
        notes[0].contains("'mixed'") && notes[0].contains("base colour's is applied"),
        "{}",
        notes[0]
    );
}

#[test]
fn each_ignored_extension_gets_one_note() {
    let dir = temp_dir("extension_notes");
    let (mut doc, _) = quad_doc_with(
        json!([{ "mesh": 0, "extensions": { "EXT_node_thing": {} } }]),
        &[],
    );
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    doc["materials"] = json!([
        { "extensions": { "KHR_materials_sheen": {}, "KHR_materials_clearcoat": {} } },
        { "extensions": { "KHR_materials_sheen": {} } },
        { "extensions": { "KHR_materials_sheen": {} } }
    ]);
    doc["extensionsUsed"] = json!([
        "KHR_materials_sheen",
        "KHR_materials_clearcoat",
        "EXT_node_thing"
    ]);
    doc["extensionsRequired"] = json!(["KHR_materials_sheen"]);
    let loaded = scene_of(&save_json(&dir, "notes.gltf", &doc));
    for name in [
        "KHR_materials_sheen",
        "KHR_materials_clearcoat",
        "EXT_node_thing",
    ] {
        let n: Vec<&String> = loaded.notes.iter().filter(|n| n.contains(name)).collect();
        assert_eq!(n.len(), 1, "{name}: {:?}", loaded.notes);
    }
    assert!(
        loaded.notes.iter().any(
            |n| n.contains("KHR_materials_sheen (on 3 of its materials)")
                && n.contains("although the file requires it")
        ),
        "{:?}",
        loaded.notes
    );
    // A requirement that cannot be ignored is refused, by name.
    doc["extensionsRequired"] = json!(["EXT_texture_webp"]);
    let e = load_scene(&save_json(&dir, "webp.gltf", &doc))
        .unwrap_err()
        .to_string();
    assert!(e.contains("EXT_texture_webp"), "{e}");
}

#[test]
fn quantized_attributes_are_read_as_the_extension_defines() {
    let dir = temp_dir("quantization");
    // The unit quad with positions as unsigned shorts (1000 = one unit, the node scales them
    // back), normals as normalized signed bytes and texture coordinates as normalized
    // unsigned shorts: what KHR_mesh_quantization (and gltfpack) writes.
    let mut data = Vec::new();
    for p in [[0u16, 0, 0], [1000, 0, 0], [1000, 1000, 0], [0, 1000, 0]] {
        for c in p {
            data.extend_from_slice(&c.to_le_bytes());
        }
        data.extend_from_slice(&[0, 0]); // each element padded to 4 bytes
    }
    for _ in 0..4 {
        data.extend_from_slice(&[0, 0, 127, 0]);
    }
    for uv in [[0u16, 0], [65535, 0], [65535, 65535], [0, 65535]] {
        for c in uv {
            data.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        data.extend_from_slice(&i.to_le_bytes());
    }
    let uri = format!("data:application/octet-stream;base64,{}", base64(&data));
    let doc = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "scale": [0.001, 0.001, 0.001] }],
        "meshes": [{ "name": "q", "primitives": [{
            "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3 }] }],
        "buffers": [{ "uri": uri, "byteLength": data.len() }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 32, "byteStride": 8 },
            { "buffer": 0, "byteOffset": 32, "byteLength": 16, "byteStride": 4 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 16 },
            { "buffer": 0, "byteOffset": 64, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5123, "count": 4, "type": "VEC3",
              "min": [0, 0, 0], "max": [1000, 1000, 0] },
            { "bufferView": 1, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5123, "normalized": true, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    let loaded = scene_of(&save_json(&dir, "quantized.gltf", &doc));
    let m = &loaded.scene.meshes[0];
    let want = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
    for (p, w) in m.positions.iter().zip(want) {
        assert!(close(*p, w, 1e-6), "{p} vs {w}");
    }
    assert!(
        m.normals.iter().all(|n| close(*n, Vec3::Z, 1e-6)),
        "{:?}",
        m.normals
    );
    assert_eq!(m.uvs, vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
    assert!(
        loaded.notes.iter().all(|n| !n.contains("quantization")),
        "{:?}",
        loaded.notes
    );
}
