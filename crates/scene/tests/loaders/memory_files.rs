//! Models loaded from files held in memory (`load_scene_from_memory`, what the web page does
//! with dropped files) load as the same files do from disk, and their paths resolve only among
//! the files given: a missing one is named with the files that were given, one that climbs out
//! of the model's folder is refused as on disk, and none reaches the disk.

use manyshadows_scene::loaders::{
    load_scene_from_memory, load_scene_with, write_gltf, LoadOptions, MemoryFiles,
};
use manyshadows_scene::primitives::cuboid;
use manyshadows_scene::{Camera, Instance, Material, Scene, Texture, TextureRef};
use serde_json::{json, Value};

use crate::common::{base64_decode, png, temp_dir, write};

/// A textured box with a light and a camera, as one `.gltf` (buffer and image embedded).
fn textured_box() -> Scene {
    let mut s = Scene {
        name: "box".into(),
        camera: Camera::look_at(glam::Vec3::new(2.0, 1.5, 3.0), glam::Vec3::ZERO),
        ..Default::default()
    };
    s.textures.push(Texture::from_fn("checker", 16, 16, |x, y| {
        if (x / 4 + y / 4) % 2 == 0 {
            [200, 40, 40, 255]
        } else {
            [20, 20, 220, 255]
        }
    }));
    s.meshes.push(cuboid(glam::Vec3::ONE));
    s.materials.push(Material {
        base_color_texture: Some(TextureRef::repeat(0)),
        ..Material::default()
    });
    s.instances
        .push(Instance::caster(0, 0, glam::Mat4::IDENTITY));
    s
}

/// The files of `textured_box` as an exporter writes them: `scene.gltf`, `scene.bin` and
/// `tex.png` (names relative to the model's folder).
fn split_files() -> Vec<(String, Vec<u8>)> {
    // One folder per call: the tests run in parallel.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = temp_dir(&format!("memory_split_{call}"));
    let embedded = dir.join("embedded.gltf");
    write_gltf(&textured_box(), &embedded).unwrap();
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&embedded).unwrap()).unwrap();
    let decode = |uri: &str| {
        let data = uri.split_once(',').unwrap().1;
        base64_decode(data)
    };
    let bin = decode(doc["buffers"][0]["uri"].as_str().unwrap());
    let image = decode(doc["images"][0]["uri"].as_str().unwrap());
    doc["buffers"][0]["uri"] = json!("scene.bin");
    doc["images"][0]["uri"] = json!("tex.png");
    let _ = std::fs::remove_dir_all(&dir);
    vec![
        ("scene.gltf".into(), serde_json::to_vec(&doc).unwrap()),
        ("scene.bin".into(), bin),
        ("tex.png".into(), image),
    ]
}

fn memory(files: &[(String, Vec<u8>)], folder: &str) -> MemoryFiles {
    let mut m = MemoryFiles::new();
    for (name, bytes) in files {
        m.insert(&format!("{folder}{name}"), bytes.clone()).unwrap();
    }
    m
}

#[test]
fn a_gltf_with_its_bin_and_image_loads_from_memory_as_from_disk() {
    let files = split_files();
    let dir = temp_dir("memory_disk");
    for (name, bytes) in &files {
        write(&dir, name, bytes);
    }
    let disk = load_scene_with(&dir.join("scene.gltf"), &LoadOptions::default()).unwrap();
    let mem = load_scene_from_memory(
        &memory(&files, "export/"),
        "export/scene.gltf",
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(mem.scene.textures.len(), 1, "{:?}", mem.notes);
    assert_eq!(format!("{:?}", mem.scene), format!("{:?}", disk.scene));
    assert_eq!(mem.notes, disk.notes);
}

#[test]
fn an_obj_with_its_library_and_texture_loads_from_memory_as_from_disk() {
    let image = Texture::from_fn("t", 2, 2, |x, _| [10 + 100 * x as u8, 20, 30, 255]);
    let files: Vec<(String, Vec<u8>)> = vec![
        (
            "m.obj".into(),
            b"mtllib lib/m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
              usemtl red\nf 1/1 2/2 3/3\n"
                .to_vec(),
        ),
        (
            "lib/m.mtl".into(),
            b"newmtl red\nKd 1 0 0\nmap_Kd ../tex/t.png\n".to_vec(),
        ),
        ("tex/t.png".into(), png(&image)),
    ];
    let dir = temp_dir("memory_obj");
    for (name, bytes) in &files {
        std::fs::create_dir_all(dir.join(name).parent().unwrap()).unwrap();
        write(&dir, name, bytes);
    }
    let disk = load_scene_with(&dir.join("m.obj"), &LoadOptions::default()).unwrap();
    let mem =
        load_scene_from_memory(&memory(&files, ""), "m.obj", &LoadOptions::default()).unwrap();
    assert_eq!(mem.scene.textures.len(), 1, "{:?}", mem.notes);
    assert_eq!(format!("{:?}", mem.scene), format!("{:?}", disk.scene));
}

#[test]
fn paths_resolve_only_among_the_files_given() {
    let files = split_files();
    // Without its .bin: the buffer's path is named, with the files that were given.
    let without: Vec<_> = files
        .iter()
        .filter(|(n, _)| n != "scene.bin")
        .cloned()
        .collect();
    let e = load_scene_from_memory(
        &memory(&without, "export/"),
        "export/scene.gltf",
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("export/scene.bin")
            && e.contains("not among the files given (export/scene.gltf, export/tex.png)"),
        "{e}"
    );
    // A URI that climbs out of the model's folder: refused by name, as on disk.
    let mut doc: Value = serde_json::from_slice(&files[0].1).unwrap();
    doc["buffers"][0]["uri"] = json!("../scene.bin");
    let mut m = memory(&files, "export/");
    m.insert("export/escape.gltf", serde_json::to_vec(&doc).unwrap())
        .unwrap();
    m.insert("scene.bin", files[1].1.clone()).unwrap();
    let e = load_scene_from_memory(&m, "export/escape.gltf", &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'../scene.bin'") && e.contains("--allow-outside-paths"),
        "{e}"
    );
    // Allowed out of the folder, it still resolves among the files given, never on disk.
    let allow = LoadOptions {
        allow_outside_paths: true,
        ..Default::default()
    };
    assert!(load_scene_from_memory(&m, "export/escape.gltf", &allow).is_ok());
    let on_disk = temp_dir("memory_not_disk");
    let outside = write(&on_disk, "scene.bin", &files[1].1);
    doc["buffers"][0]["uri"] = json!(outside.to_str().unwrap().replace('\\', "/"));
    m.insert("export/absolute.gltf", serde_json::to_vec(&doc).unwrap())
        .unwrap();
    let e = load_scene_from_memory(&m, "export/absolute.gltf", &allow)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not among the files given"), "{e}");
    // The model itself must be among them.
    let e = load_scene_from_memory(&m, "export/other.glb", &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("export/other.glb") && e.contains("not among"),
        "{e}"
    );
}

/// `files` as a zip archive (deflated), each under `folder`.
fn zipped(files: &[(String, Vec<u8>)], folder: &str) -> Vec<u8> {
    use std::io::Write;
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in files {
        w.start_file(format!("{folder}{name}"), options).unwrap();
        w.write_all(bytes).unwrap();
    }
    w.finish().unwrap().into_inner()
}

#[test]
fn a_zip_of_the_files_loads_as_the_files_do() {
    let files = split_files();
    let mut m = MemoryFiles::new();
    let added = m
        .insert_zip("drop/export.zip", &zipped(&files, "export/"))
        .unwrap();
    assert_eq!(added, 3);
    assert_eq!(
        m.names().collect::<Vec<_>>(),
        [
            "drop/export/scene.bin",
            "drop/export/scene.gltf",
            "drop/export/tex.png"
        ]
    );
    let from_zip =
        load_scene_from_memory(&m, "drop/export/scene.gltf", &LoadOptions::default()).unwrap();
    let plain = load_scene_from_memory(
        &memory(&files, "export/"),
        "export/scene.gltf",
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(
        format!("{:?}", from_zip.scene),
        format!("{:?}", plain.scene)
    );

    // An entry that climbs out of the archive's folder, and what is not a zip: refused by name.
    let evil = zipped(&[("../../outside.bin".to_string(), vec![1, 2, 3])], "");
    let e = MemoryFiles::new()
        .insert_zip("drop/evil.zip", &evil)
        .unwrap_err();
    assert!(
        e.contains("drop/evil.zip") && e.contains("../../outside.bin"),
        "{e}"
    );
    let e = MemoryFiles::new()
        .insert_zip("notes.zip", b"PK but not really")
        .unwrap_err();
    assert!(
        e.contains("notes.zip") && e.contains("not a zip archive"),
        "{e}"
    );
}
