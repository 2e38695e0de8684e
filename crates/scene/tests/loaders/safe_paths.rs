//! Paths a model file names stay inside its folder: glTF buffer and image URIs, OBJ `mtllib`
//! and MTL texture paths that are absolute, climb out with `..` or lead out through a symbolic
//! link are refused by name (buffers: an error; images, libraries, textures: a note), unless
//! `LoadOptions::allow_outside_paths` (`--allow-outside-paths`) lets them through.

use manyshadows_scene::loaders::{load_mesh, load_mesh_with, load_scene_with, LoadOptions};
use manyshadows_scene::Texture;
use serde_json::json;

use crate::common::{gltf_json, png, quad_buffer, quad_doc, save_json, temp_dir, write};

const ALLOW: LoadOptions = LoadOptions {
    allow_outside_paths: true,
    ground: manyshadows_scene::loaders::Ground::Off,
};

#[test]
fn gltf_buffers_outside_the_folder_are_refused_by_name() {
    let dir = temp_dir("outside_buffers");
    let model = dir.join("model");
    std::fs::create_dir_all(model.join("sub")).unwrap();
    let buf = quad_buffer();
    let outside = write(&dir, "secret.bin", &buf);
    write(&model.join("sub"), "q.bin", &buf);
    let nodes = r#"[{ "mesh": 0 }]"#;
    // Inside (below) the folder: loaded.
    let inside = write(
        &model,
        "in.gltf",
        gltf_json(nodes, Some("sub/q.bin"), buf.len()).as_bytes(),
    );
    assert_eq!(load_mesh(&inside).unwrap().len(), 1);
    let absolute = outside.to_str().unwrap().replace('\\', "/");
    for (name, uri) in [
        ("abs.gltf", absolute.clone()),
        ("file.gltf", format!("file://{absolute}")),
        ("up.gltf", "../secret.bin".to_string()),
        ("deep.gltf", "sub/../../secret.bin".to_string()),
        ("passwd.gltf", "/etc/passwd".to_string()),
        ("hostname.gltf", "../../../../etc/hostname".to_string()),
    ] {
        let p = write(&model, name, gltf_json(nodes, Some(&uri), 144).as_bytes());
        let e = load_mesh(&p).unwrap_err().to_string();
        assert!(
            e.contains(&format!("'{uri}'")) && e.contains("--allow-outside-paths"),
            "{name}: {e}"
        );
    }
    // Allowed: the outside buffer is read.
    for name in ["abs.gltf", "up.gltf"] {
        assert_eq!(
            load_mesh_with(&model.join(name), &ALLOW).unwrap().len(),
            1,
            "{name}"
        );
    }
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_out_of_the_folder_is_refused() {
    let dir = temp_dir("outside_link");
    let model = dir.join("model");
    std::fs::create_dir_all(&model).unwrap();
    let buf = quad_buffer();
    let outside = write(&dir, "secret.bin", &buf);
    std::os::unix::fs::symlink(&outside, model.join("link.bin")).unwrap();
    let p = write(
        &model,
        "m.gltf",
        gltf_json(r#"[{ "mesh": 0 }]"#, Some("link.bin"), buf.len()).as_bytes(),
    );
    let e = load_mesh(&p).unwrap_err().to_string();
    assert!(
        e.contains("symbolic link") && e.contains("--allow-outside-paths"),
        "{e}"
    );
    assert!(load_mesh_with(&p, &ALLOW).is_ok());
}

#[test]
fn gltf_images_outside_the_folder_are_left_out_with_one_note() {
    let dir = temp_dir("outside_images");
    let model = dir.join("model");
    std::fs::create_dir_all(&model).unwrap();
    let image = Texture::from_fn("img", 2, 2, |x, y| [x as u8 * 200, y as u8 * 200, 9, 255]);
    write(&dir, "img.png", &png(&image));
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    doc["images"] = json!([{ "uri": "../img.png" }]);
    doc["textures"] = json!([{ "source": 0 }]);
    doc["materials"] = json!([{
        "name": "m", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } }
    }]);
    let p = save_json(&model, "m.gltf", &doc);
    let loaded = load_scene_with(&p, &LoadOptions::default()).unwrap();
    assert!(loaded.scene.textures.is_empty());
    let about: Vec<&String> = loaded
        .notes
        .iter()
        .filter(|n| n.contains("../img.png"))
        .collect();
    assert_eq!(about.len(), 1, "{:?}", loaded.notes);
    assert!(about[0].contains("--allow-outside-paths"), "{}", about[0]);
    let allowed = load_scene_with(&p, &ALLOW).unwrap();
    assert_eq!(allowed.scene.textures.len(), 1);
    assert_eq!(allowed.scene.textures[0].rgba, image.rgba);
}

#[test]
fn obj_libraries_and_textures_outside_the_folder_are_left_out_with_a_note() {
    let dir = temp_dir("outside_obj");
    let model = dir.join("model");
    std::fs::create_dir_all(model.join("mtl")).unwrap();
    let image = Texture::from_fn("t", 1, 1, |_, _| [10, 20, 30, 255]);
    write(&dir, "tex.png", &png(&image));
    write(&model, "tex.png", &png(&image));
    write(&dir, "out.mtl", b"newmtl red\nKd 1 0 0\n");
    // A library in a subfolder whose texture climbs back to the model's folder: fine; one
    // that climbs above it, or names an absolute path: refused.
    let absolute = dir.join("tex.png").to_str().unwrap().replace('\\', "/");
    write(
        &model.join("mtl"),
        "in.mtl",
        format!(
            "newmtl ok\nKd 0 1 0\nmap_Kd ../tex.png\nnewmtl up\nmap_Kd ../../tex.png\n\
             newmtl abs\nmap_Kd {absolute}\n"
        )
        .as_bytes(),
    );
    let obj = "mtllib ../out.mtl\nmtllib mtl/in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n\
               usemtl red\nf 1 2 3\nusemtl ok\nf 1 3 2\nusemtl up\nf 2 1 3\nusemtl abs\nf 2 3 1\n";
    let p = write(&model, "m.obj", obj.as_bytes());
    let loaded = load_scene_with(&p, &LoadOptions::default()).unwrap();
    let notes = loaded.notes.join("\n");
    for name in ["'../out.mtl'", "'../../tex.png'", &format!("'{absolute}'")] {
        let n = loaded.notes.iter().filter(|n| n.contains(name)).count();
        assert_eq!(n, 1, "{name}: {notes}");
    }
    assert!(notes.contains("--allow-outside-paths"), "{notes}");
    // Only the texture inside the folder was read.
    assert_eq!(loaded.scene.textures.len(), 1, "{notes}");
    let allowed = load_scene_with(&p, &ALLOW).unwrap();
    assert!(
        allowed
            .scene
            .materials
            .iter()
            .any(|m| m.diffuse == glam::Vec3::X),
        "{:?}",
        allowed.notes
    );
    assert!(
        !allowed.notes.iter().any(|n| n.contains("tex.png")),
        "{:?}",
        allowed.notes
    );
}
