//! Files real exporters write that the loaders used to refuse: OBJ and MTL files in Latin-1,
//! materials without a name, glTF scenes without `nodes`; and coordinates that are not finite,
//! refused naming the mesh and the vertex.

use glam::Vec3;
use manyshadows_scene::loaders::{load_mesh, load_scene};
use manyshadows_scene::SceneError;
use serde_json::json;

use crate::common::{quad_doc, save_json, temp_dir, write};

#[test]
fn latin1_obj_and_mtl_load_with_their_names() {
    let dir = temp_dir("latin1");
    // "Matériau" and "Café" in Latin-1 (0xE9 is é), as older exporters write them.
    write(
        &dir,
        "m.mtl",
        b"# Mat\xe9riau rouge\nnewmtl Mat\xe9riau\nKd 1 0 0\n",
    );
    let obj = b"mtllib m.mtl\no Caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl Mat\xe9riau\nf 1 2 3\n";
    let p = write(&dir, "latin1.obj", obj);
    let loaded = load_scene(&p).unwrap_or_else(|e| panic!("{e}"));
    let scene = &loaded.scene;
    assert!(
        scene.meshes[0].name.ends_with("Café"),
        "{}",
        scene.meshes[0].name
    );
    assert_eq!(
        scene.materials[scene.instances[0].material].diffuse,
        Vec3::X
    );
    assert!(
        loaded.notes.iter().all(|n| !n.contains("material library")),
        "{:?}",
        loaded.notes
    );
    assert_eq!(load_mesh(&p).unwrap().len(), 1);
}

#[test]
fn materials_without_a_name_are_used() {
    let dir = temp_dir("unnamed_material");
    write(
        &dir,
        "m.mtl",
        b"newmtl\nKd 0 1 0\nmap_Kd\nnewmtl other\nKd 0 0 1\n",
    );
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl\nf 1 2 3\nusemtl other\nf 2 4 3\n";
    let p = write(&dir, "unnamed.obj", obj.as_bytes());
    let loaded = load_scene(&p).unwrap_or_else(|e| panic!("{e}"));
    let scene = &loaded.scene;
    let diffuse: Vec<Vec3> = scene
        .instances
        .iter()
        .map(|i| scene.materials[i.material].diffuse)
        .collect();
    assert_eq!(diffuse, vec![Vec3::Y, Vec3::Z], "{:?}", loaded.notes);
}

#[test]
fn gltf_scenes_without_nodes_are_empty_scenes() {
    let dir = temp_dir("no_nodes");
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    doc["scenes"] = json!([{ "name": "empty" }, { "nodes": [0] }]);
    doc["scene"] = json!(1);
    let p = save_json(&dir, "second.gltf", &doc);
    assert_eq!(load_scene(&p).unwrap().scene.meshes.len(), 1);
    // The empty scene as the default: no triangles, said as such (not a schema message).
    doc["scene"] = json!(0);
    let e = load_mesh(&save_json(&dir, "first.gltf", &doc))
        .unwrap_err()
        .to_string();
    assert!(e.contains("contains no triangles"), "{e}");
}

#[test]
fn non_finite_coordinates_name_the_mesh_and_the_vertex() {
    let dir = temp_dir("non_finite");
    // glTF: vertex 2 of the quad's positions is NaN (bytes 24..36 of the buffer).
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    let mut buf = crate::common::quad_buffer();
    buf[24..28].copy_from_slice(&f32::NAN.to_le_bytes());
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        crate::common::base64(&buf)
    ));
    let e = load_mesh(&save_json(&dir, "nan.gltf", &doc)).unwrap_err();
    match &e {
        SceneError::InvalidMesh { mesh, reason } => {
            assert!(mesh.contains("quad#0"), "{mesh}");
            assert!(
                reason.contains("vertex 2 has a non-finite position"),
                "{reason}"
            );
        }
        other => panic!("{other}"),
    }
    // A normal: vertex 1 (bytes 48 + 12 ..).
    let mut buf = crate::common::quad_buffer();
    buf[60..64].copy_from_slice(&f32::INFINITY.to_le_bytes());
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        crate::common::base64(&buf)
    ));
    let e = load_scene(&save_json(&dir, "inf.gltf", &doc))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("quad#0") && e.contains("vertex 1 has a non-finite normal"),
        "{e}"
    );
    // OBJ: the second vertex.
    let p = write(
        &dir,
        "nan.obj",
        b"o tri\nv 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = load_mesh(&p).unwrap_err().to_string();
    assert!(
        e.contains("nan.obj/tri") && e.contains("vertex 1 has a non-finite position"),
        "{e}"
    );
}
