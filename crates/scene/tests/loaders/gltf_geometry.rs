//! glTF geometry: node transforms baked into the meshes, external buffers and GLB, bad
//! accessors, and conformance (strips and fans, skipped points and lines, glTF 1.0, required
//! extensions).

use glam::Vec3;
use manyshadows_scene::loaders::{load_mesh, load_scene};
use manyshadows_scene::{Mesh, SceneError};
use serde_json::{json, Value};

use crate::common::{
    assert_normals_match_winding, assert_unit_normals, base64, embedded_gltf, gltf_json, load_one,
    quad_buffer, quad_doc, save_json, scene_of, temp_dir, write,
};

const QUAD: [Vec3; 4] = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];

#[test]
fn gltf_node_translation_is_baked() {
    let dir = temp_dir("gltf_translation");
    let json = embedded_gltf(r#"[ { "mesh": 0, "translation": [1, 2, 3] } ]"#);
    let m = load_one(&write(&dir, "quad.gltf", json.as_bytes()));
    let expect: Vec<Vec3> = QUAD.iter().map(|p| *p + Vec3::new(1.0, 2.0, 3.0)).collect();
    assert_eq!(m.positions, expect);
    assert_eq!(m.indices, vec![0, 1, 2, 0, 2, 3]);
    assert_eq!(m.normals, vec![Vec3::Z; 4]);
    assert!(m.name.contains("quad"), "{}", m.name);
}

#[test]
fn gltf_hierarchy_is_composed_and_normals_rotated() {
    let dir = temp_dir("gltf_hierarchy");
    // Parent: translate (10, 0, 0) and rotate +90° about X; child: uniform scale 2 with the quad,
    // and a second child with the non-indexed triangle.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let nodes = format!(
        r#"[ {{ "translation": [10, 0, 0], "rotation": [{s}, 0, 0, {s}], "children": [1, 2] }},
            {{ "mesh": 0, "scale": [2, 2, 2] }},
            {{ "mesh": 1 }} ]"#
    );
    let meshes = load_mesh(&write(&dir, "h.gltf", embedded_gltf(&nodes).as_bytes())).unwrap();
    assert_eq!(meshes.len(), 2);
    let rot = |p: Vec3| Vec3::new(p.x, -p.z, p.y); // +90° about X
    for (got, p) in meshes[0].positions.iter().zip(QUAD) {
        let want = Vec3::new(10.0, 0.0, 0.0) + rot(p * 2.0);
        assert!((*got - want).length() < 1e-5, "{got} vs {want}");
    }
    for n in &meshes[0].normals {
        assert!((*n - Vec3::NEG_Y).length() < 1e-5, "normal {n}"); // +Z rotated about X
    }
    // The non-indexed primitive gets 0..n indices and computed normals.
    let tri = &meshes[1];
    assert_eq!(tri.indices, vec![0, 1, 2]);
    assert!((tri.positions[1] - Vec3::new(12.0, 0.0, 0.0)).length() < 1e-5);
    assert_unit_normals(tri);
    assert_normals_match_winding(tri);
}

#[test]
fn gltf_mirroring_transform_keeps_outward_winding() {
    let dir = temp_dir("gltf_mirror");
    let json = embedded_gltf(r#"[ { "mesh": 0, "scale": [1, 1, -1] } ]"#);
    let m = load_one(&write(&dir, "m.gltf", json.as_bytes()));
    for n in &m.normals {
        assert!((*n - Vec3::NEG_Z).length() < 1e-6, "{n}");
    }
    assert_normals_match_winding(&m);
}

#[test]
fn gltf_external_buffer_and_glb() {
    let dir = temp_dir("gltf_external");
    let buf = quad_buffer();
    write(&dir, "quad data.bin", &buf);
    let nodes = r#"[ { "mesh": 0, "translation": [0, 0, 5] } ]"#;
    let json = gltf_json(nodes, Some("quad%20data.bin"), buf.len());
    let ext = load_one(&write(&dir, "ext.gltf", json.as_bytes()));

    // The same document as binary glTF: header, JSON chunk, BIN chunk (each 4-byte aligned).
    let mut json = gltf_json(nodes, None, buf.len()).into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = buf.clone();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    let from_glb = load_one(&write(&dir, "quad.GLB", &glb));
    assert_eq!(
        (&ext.positions, &ext.normals, &ext.indices),
        (&from_glb.positions, &from_glb.normals, &from_glb.indices)
    );
    assert_eq!(ext.positions[2], Vec3::new(1.0, 1.0, 5.0));

    // A truncated GLB fails cleanly.
    let e = load_mesh(&write(&dir, "cut.glb", &glb[..glb.len() - 20])).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e:?}");
}

#[test]
fn gltf_bad_accessor_is_an_error_not_a_panic() {
    let dir = temp_dir("gltf_bad_accessor");
    let good = embedded_gltf(r#"[ { "mesh": 0 } ]"#);
    let cases = [
        // Index accessor reaching past its buffer view.
        good.replace(
            r#""componentType": 5123, "count": 6"#,
            r#""componentType": 5123, "count": 60"#,
        ),
        // Positions declared as unsigned ints (bytes and shorts are KHR_mesh_quantization's).
        good.replacen(
            r#""componentType": 5126, "count": 4, "type": "VEC3""#,
            r#""componentType": 5125, "count": 4, "type": "VEC3""#,
            1,
        ),
        // A stride smaller than one element.
        good.replace(
            r#""byteLength": 96 }"#,
            r#""byteLength": 96, "byteStride": 4 }"#,
        ),
        // Index referring to a missing vertex.
        good.replace(
            r#""bufferView": 1, "componentType": 5123, "count": 6"#,
            r#""bufferView": 0, "byteOffset": 12, "componentType": 5123, "count": 6"#,
        ),
        // A node that is its own child.
        good.replace(
            r#"[ { "mesh": 0 } ]"#,
            r#"[ { "mesh": 0, "children": [0] } ]"#,
        ),
    ];
    let reasons = [
        "outside its buffer",
        "expected Vec3",
        "stride",
        "out of range",
        "reached twice",
    ];
    for (i, (json, reason)) in cases.iter().zip(reasons).enumerate() {
        assert_ne!(json, &good, "case {i} did not change the document");
        match load_mesh(&write(&dir, &format!("bad{i}.gltf"), json.as_bytes())) {
            Err(e) => assert!(e.to_string().contains(reason), "case {i}: {e}"),
            Ok(m) => panic!("case {i} loaded: {m:?}"),
        }
    }
    // The untouched document loads.
    load_one(&write(&dir, "good.gltf", good.as_bytes()));
}

/// A glTF document of one mesh with one primitive over `positions` (VEC3 floats), with
/// optional u32 `indices` and the given `mode`, embedded.
fn primitive_doc(positions: &[Vec3], indices: Option<&[u32]>, mode: u32) -> Value {
    let mut bin: Vec<u8> = positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let pos_len = bin.len();
    let (lo, hi) = positions
        .iter()
        .fold((positions[0], positions[0]), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let mut accessors = vec![json!({
        "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3",
        "min": lo.to_array(), "max": hi.to_array()
    })];
    let mut views = vec![json!({ "buffer": 0, "byteOffset": 0, "byteLength": pos_len })];
    let mut primitive = json!({ "attributes": { "POSITION": 0 }, "mode": mode });
    if let Some(idx) = indices {
        bin.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
        views.push(json!({ "buffer": 0, "byteOffset": pos_len, "byteLength": 4 * idx.len() }));
        accessors.push(json!({
            "bufferView": 1, "componentType": 5125, "count": idx.len(), "type": "SCALAR"
        }));
        primitive["indices"] = json!(1);
    }
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "name": "m", "primitives": [primitive] }],
        "buffers": [{
            "byteLength": bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64(&bin)),
        }],
        "bufferViews": views,
        "accessors": accessors,
    })
}

#[test]
fn gltf_strips_and_fans_equal_their_triangle_lists() {
    let dir = temp_dir("gltf_strip_fan");
    // A bent ribbon (so normals are not all equal) and a bent fan.
    let ribbon: Vec<Vec3> = (0..7)
        .map(|i| Vec3::new((i / 2) as f32, (i % 2) as f32, 0.3 * (i as f32).sin()))
        .collect();
    let load = |name: &str, doc: Value| load_one(&save_json(&dir, name, &doc));

    // glTF 2.0 §3.7.2.1: strip triangle i = (v_i, v_{i+1+i%2}, v_{i+2-i%2}).
    let strip_list: Vec<u32> = vec![0, 1, 2, 1, 3, 2, 2, 3, 4, 3, 5, 4, 4, 5, 6];
    let list = load(
        "strip_list.gltf",
        primitive_doc(&ribbon, Some(&strip_list), 4),
    );
    let order: Vec<u32> = (0..7).collect();
    for (name, doc) in [
        ("strip.gltf", primitive_doc(&ribbon, None, 5)),
        (
            "strip_indexed.gltf",
            primitive_doc(&ribbon, Some(&order), 5),
        ),
    ] {
        let strip = load(name, doc);
        assert_eq!(
            strip,
            Mesh {
                name: strip.name.clone(),
                ..list.clone()
            },
            "{name}"
        );
    }
    assert_normals_match_winding(&list);

    // Fan triangle i = (v_{i+1}, v_{i+2}, v_0).
    let mut fan_points = vec![Vec3::new(0.0, 0.0, 0.5)];
    for k in 0..6 {
        let a = k as f32 * 0.6;
        fan_points.push(Vec3::new(a.cos(), a.sin(), 0.0));
    }
    let fan_list: Vec<u32> = vec![1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5, 0, 5, 6, 0];
    let list = load(
        "fan_list.gltf",
        primitive_doc(&fan_points, Some(&fan_list), 4),
    );
    for (name, doc) in [
        ("fan.gltf", primitive_doc(&fan_points, None, 6)),
        (
            "fan_indexed.gltf",
            primitive_doc(&fan_points, Some(&order), 6),
        ),
    ] {
        let fan = load(name, doc);
        assert_eq!(
            fan,
            Mesh {
                name: fan.name.clone(),
                ..list.clone()
            },
            "{name}"
        );
    }
    assert_normals_match_winding(&list);
    assert_eq!(list.triangle_count(), 5);
}

#[test]
fn gltf_lines_and_points_are_skipped_with_a_note() {
    let dir = temp_dir("gltf_lines");
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    let triangle = doc["meshes"][0]["primitives"][0].clone();
    let mut lines = triangle.clone();
    lines["mode"] = json!(1);
    doc["meshes"][0]["primitives"] = json!([triangle, lines]);
    let loaded = scene_of(&save_json(&dir, "lines.gltf", &doc));
    assert_eq!(loaded.scene.meshes.len(), 1);
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("1 point or line primitive(s) skipped")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn gltf_1_0_is_refused_with_a_clear_message() {
    let dir = temp_dir("gltf1");
    let old = json!({
        "asset": { "version": "1.0" },
        "meshes": { "box": { "primitives": [] } },
        "nodes": { "root": { "meshes": ["box"] } },
        "scene": "default",
        "scenes": { "default": { "nodes": ["root"] } }
    });
    // Also a 2.0-looking version with 1.0's dictionaries.
    let mut dictionaries = old.clone();
    dictionaries["asset"]["version"] = json!("2.0");
    let json_text = old.to_string();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&1u32.to_le_bytes());
    glb.extend_from_slice(&(20 + json_text.len() as u32).to_le_bytes());
    glb.extend_from_slice(&(json_text.len() as u32).to_le_bytes());
    glb.extend_from_slice(&0u32.to_le_bytes());
    glb.extend_from_slice(json_text.as_bytes());
    let files = [
        write(&dir, "old.gltf", json_text.as_bytes()),
        save_json(&dir, "dict.gltf", &dictionaries),
        write(&dir, "old.glb", &glb),
    ];
    for p in &files {
        for result in [load_mesh(p).map(|_| ()), load_scene(p).map(|_| ())] {
            match result {
                Err(SceneError::Parse { reason, .. }) => {
                    assert!(reason.contains("glTF 1.0 is not supported"), "{reason}");
                    assert!(reason.contains("convert"), "{reason}");
                }
                other => panic!("{}: {other:?}", p.display()),
            }
        }
    }
}

#[test]
fn gltf_required_extensions_are_named() {
    let dir = temp_dir("gltf_required");
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    doc["extensionsUsed"] = json!(["KHR_texture_basisu"]);
    doc["extensionsRequired"] = json!(["KHR_texture_basisu"]);
    let e = load_scene(&save_json(&dir, "basisu.gltf", &doc)).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e:?}");
    assert!(e.to_string().contains("KHR_texture_basisu"), "{e}");

    // A required texture transform is read (no note); a required PBR material extension is
    // ignored, with a note.
    doc["extensionsUsed"] = json!(["KHR_texture_transform"]);
    doc["extensionsRequired"] = json!(["KHR_texture_transform"]);
    let loaded = scene_of(&save_json(&dir, "transform.gltf", &doc));
    assert!(
        loaded
            .notes
            .iter()
            .all(|n| !n.contains("KHR_texture_transform")),
        "{:?}",
        loaded.notes
    );
    doc["extensionsUsed"] = json!(["KHR_materials_volume"]);
    doc["extensionsRequired"] = json!(["KHR_materials_volume"]);
    let loaded = scene_of(&save_json(&dir, "volume.gltf", &doc));
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("KHR_materials_volume") && n.contains("requires it")),
        "{:?}",
        loaded.notes
    );
}
