//! OBJ: geometry (triangulation, objects, normals, the writer, bad faces) and the MTL
//! materials (missing libraries, `map_d` masks, bump maps).

use glam::{Vec2, Vec3};
use manyshadows_scene::loaders::{load_mesh, write_obj};
use manyshadows_scene::{AlphaMode, Material, SceneError, Texture};

use crate::common::{
    assert_normals_match_winding, assert_unit_normals, load_one, png, pyramid, scene_of, temp_dir,
    write, CUBE_NORMALS, CUBE_QUADS, CUBE_V,
};

#[test]
fn obj_cube_without_normals_gets_flat_faces() {
    let dir = temp_dir("obj_no_normals");
    let mut text = String::from(CUBE_V);
    for q in CUBE_QUADS {
        text += &format!(
            "f {} {} {}\nf {} {} {}\n",
            q[0], q[1], q[2], q[0], q[2], q[3]
        );
    }
    let m = load_one(&write(&dir, "cube.obj", text.as_bytes()));
    assert_eq!(m.triangle_count(), 12);
    // The eight shared corners meet at 90°, beyond the crease angle: three vertices each.
    assert_eq!(m.positions.len(), 24);
    assert_unit_normals(&m);
    assert_normals_match_winding(&m);
    for n in &m.normals {
        assert!(CUBE_NORMALS.contains(n), "{n} is not a face normal");
    }
    m.validate().unwrap();
}

#[test]
fn obj_cube_with_normals_keeps_them_aligned() {
    let dir = temp_dir("obj_normals");
    let mut text = String::from(CUBE_V);
    for n in CUBE_NORMALS {
        text += &format!("vn {} {} {}\n", n.x, n.y, n.z);
    }
    for (f, q) in CUBE_QUADS.iter().enumerate() {
        let n = f + 1;
        text += &format!(
            "f {}//{n} {}//{n} {}//{n}\nf {}//{n} {}//{n} {}//{n}\n",
            q[0], q[1], q[2], q[0], q[2], q[3]
        );
    }
    let m = load_one(&write(&dir, "cube_n.obj", text.as_bytes()));
    assert_eq!(m.triangle_count(), 12);
    assert_unit_normals(&m);
    assert_normals_match_winding(&m);
    // Each vertex's normal is exactly one of the file's face normals (none were recomputed).
    for n in &m.normals {
        assert!(CUBE_NORMALS.contains(n), "{n}");
    }
}

#[test]
fn obj_quads_are_triangulated() {
    let dir = temp_dir("obj_quads");
    let mut text = String::from(CUBE_V);
    for q in CUBE_QUADS {
        text += &format!("f {} {} {} {}\n", q[0], q[1], q[2], q[3]);
    }
    let m = load_one(&write(&dir, "quads.OBJ", text.as_bytes()));
    assert_eq!(m.triangle_count(), 12);
    assert_normals_match_winding(&m);
    // Every quad's four corners appear among the triangles.
    for q in CUBE_QUADS {
        for v in q {
            let p = m.positions.iter().position(|p| {
                let c = CUBE_V.lines().nth(v as usize - 1).unwrap();
                let xyz: Vec<f32> = c[2..].split(' ').map(|s| s.parse().unwrap()).collect();
                *p == Vec3::new(xyz[0], xyz[1], xyz[2])
            });
            assert!(m.indices.contains(&(p.unwrap() as u32)));
        }
    }
}

#[test]
fn obj_objects_become_separate_meshes() {
    let dir = temp_dir("obj_objects");
    let text = "o first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\
                o second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\nf 4 5 7\nf 5 6 7\n";
    let meshes = load_mesh(&write(&dir, "two.obj", text.as_bytes())).unwrap();
    assert_eq!(meshes.len(), 2);
    assert_eq!(meshes[0].triangle_count(), 1);
    assert_eq!(meshes[1].triangle_count(), 2);
    assert!(meshes[1].name.contains("second"), "{}", meshes[1].name);
}

#[test]
fn obj_writer_round_trips() {
    let dir = temp_dir("obj_round_trip");
    let m = pyramid();
    let mut bytes = Vec::new();
    write_obj(&m, &mut bytes).unwrap();
    let back = load_one(&write(&dir, "pyramid.obj", &bytes));
    assert_eq!(back.triangle_count(), m.triangle_count());
    // tobj re-indexes; compare the triangles' corner positions and normals.
    for (t0, t1) in m.indices.chunks(3).zip(back.indices.chunks(3)) {
        for k in 0..3 {
            assert_eq!(m.positions[t0[k] as usize], back.positions[t1[k] as usize]);
            assert_eq!(m.normals[t0[k] as usize], back.normals[t1[k] as usize]);
        }
    }
}

#[test]
fn obj_nan_vertex_is_invalid_mesh() {
    let dir = temp_dir("obj_nan");
    let p = write(&dir, "nan.obj", b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let e = load_mesh(&p).unwrap_err();
    assert!(matches!(e, SceneError::InvalidMesh { .. }), "{e:?}");
    assert!(e.to_string().contains("non-finite"), "{e}");
}

#[test]
fn obj_out_of_range_face_is_an_error() {
    let dir = temp_dir("obj_range");
    let p = write(&dir, "range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    assert!(load_mesh(&p).is_err());
}

fn grey_png(width: u32, height: u32, f: impl Fn(u32, u32) -> u8) -> Vec<u8> {
    let mut out = Vec::new();
    image::GrayImage::from_fn(width, height, |x, y| image::Luma([f(x, y)]))
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
                            usemtl leaf\nf 1/1/1 2/2/1 3/3/1\n";

#[test]
fn obj_with_missing_or_empty_mtl_gets_default_materials_and_a_note() {
    let dir = temp_dir("obj_mtl_missing");
    let missing = write(
        &dir,
        "missing.obj",
        format!("mtllib nowhere.mtl\n{TRIANGLE_OBJ}").as_bytes(),
    );
    write(&dir, "empty.mtl", b"");
    let empty = write(
        &dir,
        "empty.obj",
        format!("mtllib empty.mtl\n{TRIANGLE_OBJ}").as_bytes(),
    );
    for (path, says) in [(missing, "could not be read"), (empty, "is empty")] {
        let loaded = scene_of(&path);
        let scene = &loaded.scene;
        assert_eq!(scene.meshes.len(), 1);
        assert_eq!(scene.materials, vec![Material::default()]);
        assert!(scene.textures.is_empty());
        assert!(
            loaded
                .notes
                .iter()
                .any(|n| n.contains(says) && n.contains(".mtl") && n.contains("default materials")),
            "{}: {:?}",
            path.display(),
            loaded.notes
        );
        // v is flipped to glTF's convention.
        assert_eq!(
            scene.meshes[0].uvs,
            vec![
                Vec2::new(0.0, 1.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 0.0)
            ]
        );
    }
}

#[test]
fn obj_map_d_becomes_the_alpha_of_a_masked_material() {
    let dir = temp_dir("obj_map_d");
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    let colour = Texture::from_fn("leaf", 4, 4, |x, y| [x as u8 * 50, y as u8 * 60, 200, 255]);
    write(&dir, "textures/leaf.png", &png(&colour));
    let mask = |x: u32, y: u32| (x * 70 + y * 13) as u8;
    write(&dir, "textures/leaf mask.png", &grey_png(4, 4, mask));
    write(
        &dir,
        "scene.mtl",
        b"newmtl leaf\nKa 0 0 0\nKd 0.5 0.6 0.7\nKs 0.1 0.1 0.1\nNs 20\nd 0.5\n\
          map_Kd -bm 1.0 -s 1 1 1 textures\\leaf.png\nmap_d textures/leaf mask.png\n",
    );
    let path = write(
        &dir,
        "scene.obj",
        format!("mtllib scene.mtl\no leaf\n{TRIANGLE_OBJ}").as_bytes(),
    );
    let loaded = scene_of(&path);
    assert!(
        !loaded.notes.iter().any(|n| n.contains("leaf")),
        "{:?}",
        loaded.notes
    );
    let scene = &loaded.scene;
    let m = scene.materials[scene.instances[0].material];
    assert_eq!(m.diffuse, Vec3::new(0.5, 0.6, 0.7));
    assert_eq!(m.ambient, m.diffuse, "black Ka means Kd");
    assert_eq!(m.specular, Vec3::splat(0.1));
    assert_eq!(m.shininess, 20.0);
    assert_eq!(m.alpha_mode, AlphaMode::Mask);
    assert_eq!(m.alpha_cutoff, 0.5);
    assert!(m.double_sided);
    assert_eq!(m.base_alpha, 1.0, "d without map_d is ignored");
    let t = &scene.textures[m.base_color_texture.unwrap().texture];
    assert_eq!((t.width, t.height), (4, 4));
    for y in 0..4 {
        for x in 0..4 {
            let [r, g, b, a] = t.texel(x, y);
            assert_eq!([r, g, b], colour.texel(x, y)[..3], "texel ({x}, {y})");
            assert_eq!(a, mask(x, y), "texel ({x}, {y})");
        }
    }
}

#[test]
fn obj_bump_maps_are_normal_maps_only_in_colour() {
    let dir = temp_dir("obj_bump");
    let normal_map = Texture::from_fn("n", 2, 2, |x, _| [128 + x as u8, 128, 255, 255]);
    write(&dir, "normal.png", &png(&normal_map));
    write(
        &dir,
        "height.png",
        &grey_png(2, 2, |x, y| (x * 100 + y) as u8),
    );
    write(
        &dir,
        "m.mtl",
        b"newmtl leaf\nKd 1 1 1\nnorm normal.png\n\nnewmtl stone\nKd 1 1 1\n\
          map_bump -bm 0.3 height.png\n\nnewmtl lost\nmap_Kd nothere.jpg\n",
    );
    let obj = format!(
        "mtllib m.mtl\no a\n{TRIANGLE_OBJ}o b\nusemtl stone\nf 1/1/1 3/3/1 2/2/1\n\
         o c\nusemtl lost\nf 1/1/1 2/2/1 3/3/1\n"
    );
    let loaded = scene_of(&write(&dir, "m.obj", obj.as_bytes()));
    let scene = &loaded.scene;
    assert_eq!(scene.meshes.len(), 3);
    let material = |i: usize| scene.materials[scene.instances[i].material];
    let leaf = material(0);
    let t = leaf.normal_texture.expect("a colour normal map is used");
    assert_eq!(scene.textures[t.texture].rgba, normal_map.rgba);
    assert_eq!(material(1).normal_texture, None);
    assert_eq!(material(2).base_color_texture, None);
    let notes = loaded.notes.join("\n");
    assert!(
        notes.contains("greyscale bump maps") && notes.contains("'stone'"),
        "{notes}"
    );
    assert!(
        notes.contains("material 'lost': map_Kd 'nothere.jpg' could not be used"),
        "{notes}"
    );
}
