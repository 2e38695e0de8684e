//! The glTF writer: a written scene loads back the same, an empty one is refused on load.

use glam::{Mat4, Quat, Vec2, Vec3};
use manyshadows_scene::loaders::{load_scene, write_gltf, GLTF_SIZE_EXTRA, PHONG_PER_LUX};
use manyshadows_scene::{
    AlphaMode, Attenuation, Camera, Instance, Light, LightKind, Lighting, Material, Pbr, Scene,
    Texture, TextureRef, Wrap,
};

use crate::common::{close, pyramid, scene_of, temp_dir};

/// A scene with everything the writer writes: textured and masked materials, meshes with and
/// without texture coordinates, a transformed instance, every light type, a camera.
fn writer_scene() -> Scene {
    let card = manyshadows_scene::primitives::card(2.0, 3.0, Vec2::new(2.0, 1.0));
    let cube = manyshadows_scene::primitives::cuboid(Vec3::new(1.0, 2.0, 0.5));
    let mut plain = pyramid();
    plain.name = "plain".into();
    let leaves = Texture::from_fn("leaves", 8, 4, |x, y| {
        [
            x as u8 * 30,
            y as u8 * 60,
            90,
            if (x + y) % 3 == 0 { 0 } else { 255 },
        ]
    });
    let bumps = Texture::from_fn("bumps", 2, 2, |x, y| {
        [128 + x as u8, 127 + y as u8, 250, 255]
    });
    let masked = Material {
        base_color_texture: Some(TextureRef {
            texture: 0,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::MirroredRepeat,
        }),
        base_alpha: 0.8,
        ..Material::matte(Vec3::new(0.3, 0.7, 0.2)).masked(0.3)
    };
    let grey = Material {
        ambient: Vec3::splat(0.6),
        diffuse: Vec3::splat(0.6),
        specular: Vec3::splat(0.25),
        shininess: 32.0,
        normal_texture: Some(TextureRef::repeat(1)),
        ..Material::default()
    };
    let blend = Material {
        alpha_mode: AlphaMode::Blend,
        base_color_texture: Some(TextureRef::repeat(0)),
        ..Material::matte(Vec3::new(0.9, 0.1, 0.1))
    };
    let moved = Mat4::from_scale_rotation_translation(
        Vec3::splat(1.5),
        Quat::from_rotation_y(0.7),
        Vec3::new(3.0, 0.0, -2.0),
    );
    let light = |kind, colour: Vec3| Light {
        kind,
        ambient: Vec3::ZERO,
        diffuse: colour,
        specular: colour,
        attenuation: Attenuation {
            constant: 1.0,
            linear: 0.0,
            quadratic: 1.0,
        },
        casts_shadows: true,
        shadow_resolution: 512,
        size: 0.0,
    };
    let sized = |size: f32, l: Light| Light { size, ..l };
    Scene {
        name: "writer".into(),
        meshes: vec![card, cube, plain],
        materials: vec![masked, grey, blend],
        textures: vec![leaves, bumps],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 1, Mat4::IDENTITY),
            Instance::caster(2, 2, Mat4::IDENTITY),
            Instance::caster(1, 0, moved),
        ],
        lights: vec![
            sized(
                0.25,
                light(
                    LightKind::Spot {
                        position: Vec3::new(1.0, 5.0, 2.0),
                        direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
                        cutoff_deg: 35.0,
                        range: 12.5,
                    },
                    Vec3::new(2.0, 1.5, 0.5),
                ),
            ),
            sized(
                0.12,
                light(
                    LightKind::Point {
                        position: Vec3::new(-2.0, 3.0, 0.5),
                        range: 6.0,
                    },
                    Vec3::new(0.3, 0.3, 0.4),
                ),
            ),
            sized(
                0.53,
                light(
                    LightKind::Directional {
                        direction: Vec3::new(0.0, 0.0, 1.0),
                        cascades: 3,
                        split_lambda: 0.75,
                        cascade_resolution_scale: 1.0,
                    },
                    Vec3::new(1.0, 0.95, 0.9),
                ),
            ),
            light(
                LightKind::Spot {
                    position: Vec3::new(0.0, 4.0, 0.0),
                    direction: Vec3::NEG_Y,
                    cutoff_deg: 80.0,
                    range: 3.0,
                },
                Vec3::ZERO,
            ),
        ],
        camera: Camera {
            position: Vec3::new(4.0, 3.0, 6.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::new(0.1, 1.0, 0.0),
            fov_y_deg: 50.0,
            near: 0.2,
            far: 300.0,
        },
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}

#[test]
fn written_gltf_loads_back_the_same_scene() {
    let dir = temp_dir("write_gltf");
    let original = writer_scene();
    original.validate().unwrap();
    for name in ["scene.gltf", "scene.GLB"] {
        let path = dir.join(name);
        write_gltf(&original, &path).unwrap();
        let loaded = scene_of(&path);
        assert!(
            !loaded.notes.iter().any(|n| n.contains("no lights")),
            "{name}: {:?}",
            loaded.notes
        );
        let scene = &loaded.scene;
        assert_eq!(scene.meshes.len(), original.instances.len(), "{name}");

        for (i, inst) in original.instances.iter().enumerate() {
            let want = &original.meshes[inst.mesh];
            let got = &scene.meshes[scene.instances[i].mesh];
            assert_eq!(got.indices, want.indices, "{name} mesh {i}");
            assert_eq!(got.uvs, want.uvs, "{name} mesh {i}");
            let normal_matrix = glam::Mat3::from_mat4(inst.transform).inverse().transpose();
            for (g, w) in got.positions.iter().zip(&want.positions) {
                assert!(
                    close(*g, inst.transform.transform_point3(*w), 1e-5),
                    "{name} mesh {i}"
                );
            }
            for (g, w) in got.normals.iter().zip(&want.normals) {
                assert!(
                    close(*g, (normal_matrix * *w).normalize(), 1e-5),
                    "{name} mesh {i}"
                );
            }
            assert_eq!(got.positions.len(), want.positions.len());

            // Materials: the fields glTF carries.
            let (a, b) = (
                original.materials[inst.material],
                scene.materials[scene.instances[i].material],
            );
            assert_eq!(b.diffuse, a.diffuse, "{name} mesh {i}");
            assert_eq!(b.base_alpha, a.base_alpha);
            assert_eq!(b.alpha_mode, a.alpha_mode);
            if a.alpha_mode == AlphaMode::Mask {
                assert_eq!(b.alpha_cutoff, a.alpha_cutoff);
            }
            assert_eq!(b.double_sided, a.double_sided);
            assert!(
                (b.shininess - a.shininess).abs() < 1e-5 * a.shininess,
                "{} vs {}",
                b.shininess,
                a.shininess
            );
            for (x, y) in [
                (a.base_color_texture, b.base_color_texture),
                (a.normal_texture, b.normal_texture),
            ] {
                match (x, y) {
                    (None, None) => {}
                    (Some(x), Some(y)) => {
                        assert_eq!((x.wrap_s, x.wrap_t), (y.wrap_s, y.wrap_t));
                        let (tx, ty) = (&original.textures[x.texture], &scene.textures[y.texture]);
                        assert_eq!((tx.width, tx.height), (ty.width, ty.height));
                        assert_eq!(tx.rgba, ty.rgba, "{name}: texture pixels");
                    }
                    other => panic!("{name} mesh {i}: {other:?}"),
                }
            }
        }
        // Grey diffuse with grey specular is representable exactly.
        let grey = scene.materials[scene.instances[1].material];
        assert!(
            close(grey.specular, Vec3::splat(0.25), 1e-5),
            "{}",
            grey.specular
        );

        // Lights.
        assert_eq!(scene.lights.len(), original.lights.len());
        // A Phong scene's light units are 10 cd (or lx) each: the glTF is physical.
        assert_eq!(scene.lighting, Lighting::Physical);
        for (a, b) in original.lights.iter().zip(&scene.lights) {
            assert_eq!(a.type_name(), b.type_name());
            assert_eq!(a.size, b.size, "{name}: the size, through extras");
            let physical = a.diffuse / PHONG_PER_LUX;
            assert!(
                close(physical, b.diffuse, 1e-4),
                "{} vs {}",
                physical,
                b.diffuse
            );
            assert!(close(physical, b.specular, 1e-4));
            match (a.kind, b.kind) {
                (
                    LightKind::Spot {
                        position: p0,
                        direction: d0,
                        cutoff_deg: c0,
                        range: r0,
                    },
                    LightKind::Spot {
                        position: p1,
                        direction: d1,
                        cutoff_deg: c1,
                        range: r1,
                    },
                ) => {
                    assert!(close(p0, p1, 1e-5) && close(d0, d1, 1e-5), "{d0} vs {d1}");
                    assert!((c0 - c1).abs() < 1e-5 * c0, "{c0} vs {c1}");
                    assert_eq!(r0, r1);
                }
                (
                    LightKind::Point {
                        position: p0,
                        range: r0,
                    },
                    LightKind::Point {
                        position: p1,
                        range: r1,
                    },
                ) => {
                    assert!(close(p0, p1, 1e-5));
                    assert_eq!(r0, r1);
                }
                (
                    LightKind::Directional { direction: d0, .. },
                    LightKind::Directional { direction: d1, .. },
                ) => assert!(close(d0, d1, 1e-5), "{d0} vs {d1}"),
                other => panic!("{other:?}"),
            }
        }

        // Camera: same eye, direction and view; glTF has no target distance.
        let (a, b) = (original.camera, scene.camera);
        assert!(close(a.position, b.position, 1e-5));
        let dir_a = (a.target - a.position).normalize();
        let dir_b = (b.target - b.position).normalize();
        assert!(close(dir_a, dir_b, 1e-5), "{dir_a} vs {dir_b}");
        assert!((a.fov_y_deg - b.fov_y_deg).abs() < 1e-5 * a.fov_y_deg);
        assert_eq!((a.near, a.far), (b.near, b.far));
        let (va, vb) = (a.view(), b.view());
        for (x, y) in va.to_cols_array().iter().zip(vb.to_cols_array()) {
            assert!((x - y).abs() < 1e-5, "{va} vs {vb}");
        }
    }
}

/// A light's size goes into its `extras` only when it has one: a hard light's entry is plain
/// `KHR_lights_punctual`.
#[test]
fn written_gltf_has_size_extras_only_for_sized_lights() {
    let dir = temp_dir("write_sizes");
    let path = dir.join("sizes.gltf");
    write_gltf(&writer_scene(), &path).unwrap();
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let lights = doc["extensions"]["KHR_lights_punctual"]["lights"]
        .as_array()
        .unwrap();
    let extras: Vec<Option<f32>> = lights
        .iter()
        .map(|l| {
            l.get("extras")
                .map(|e| e[GLTF_SIZE_EXTRA].as_f64().unwrap() as f32)
        })
        .collect();
    assert_eq!(
        extras,
        [Some(0.25), Some(0.12), Some(0.53), None],
        "{lights:?}"
    );
}

#[test]
fn written_gltf_of_an_empty_scene_is_refused_on_load() {
    // Nothing to draw is a clear error on load, not a panic on write.
    let dir = temp_dir("write_empty");
    let path = dir.join("empty.gltf");
    write_gltf(&Scene::default(), &path).unwrap();
    let e = load_scene(&path).unwrap_err();
    assert!(e.to_string().contains("no triangles"), "{e}");
}

/// A physical scene's lights are written in their own units and its materials' metallic,
/// roughness and emission (above 1 through `KHR_materials_emissive_strength`) load back.
#[test]
fn physical_lights_and_pbr_materials_round_trip() {
    let dir = temp_dir("gltf_writer_physical");
    let mut scene = Scene {
        name: "physical".into(),
        meshes: vec![manyshadows_scene::primitives::cuboid(Vec3::ONE)],
        textures: vec![
            Texture::from_fn("metal-rough", 4, 4, |x, y| {
                [0, (x * 60) as u8, (y * 60) as u8, 255]
            }),
            Texture::from_fn("glow", 4, 4, |x, _| [255, (x * 60) as u8, 0, 255]),
        ],
        materials: vec![
            Material {
                diffuse: Vec3::new(0.9, 0.5, 0.2),
                pbr: Some(Pbr {
                    metallic: 0.75,
                    roughness: 0.3,
                }),
                emissive: Vec3::new(8.0, 4.0, 0.0),
                metallic_roughness_texture: Some(TextureRef::repeat(0)),
                emissive_texture: Some(TextureRef::repeat(1)),
                ..Material::default()
            },
            Material {
                emissive: Vec3::new(0.5, 0.25, 0.0),
                ..Material::default()
            },
        ],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(0, 1, Mat4::from_translation(Vec3::X * 3.0)),
        ],
        lights: vec![Light {
            kind: LightKind::Point {
                position: Vec3::new(0.0, 3.0, 0.0),
                range: 12.0,
            },
            ambient: Vec3::ZERO,
            diffuse: Vec3::splat(250.0),
            specular: Vec3::splat(250.0),
            attenuation: Attenuation {
                constant: 1.0,
                linear: 0.0,
                quadratic: 1.0,
            },
            casts_shadows: true,
            shadow_resolution: 512,
            size: 0.0,
        }],
        lighting: Lighting::Physical,
        ..Default::default()
    };
    scene.camera = Camera::look_at(Vec3::new(4.0, 3.0, 5.0), Vec3::ZERO);
    let path = dir.join("physical.gltf");
    write_gltf(&scene, &path).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert!(
        json["extensionsUsed"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e == "KHR_materials_emissive_strength"),
        "{}",
        json["extensionsUsed"]
    );
    let loaded = scene_of(&path);
    assert!(
        !loaded.notes.iter().any(|n| n.contains("emissive")),
        "{:?}",
        loaded.notes
    );
    let s = loaded.scene;
    assert_eq!(s.lighting, Lighting::Physical);
    assert!(close(s.lights[0].diffuse, Vec3::splat(250.0), 1e-6));
    let m0 = s.materials[s.instances[0].material];
    let m1 = s.materials[s.instances[1].material];
    let p = m0
        .pbr
        .expect("glTF materials carry their metallic-roughness parameters");
    assert!(
        (p.metallic - 0.75).abs() < 1e-6 && (p.roughness - 0.3).abs() < 1e-6,
        "{p:?}"
    );
    assert!(
        close(m0.emissive, Vec3::new(8.0, 4.0, 0.0), 1e-6),
        "{}",
        m0.emissive
    );
    assert!(
        close(m1.emissive, Vec3::new(0.5, 0.25, 0.0), 1e-6),
        "{}",
        m1.emissive
    );
    // The metallic-roughness and emissive textures come back as written, texel for texel.
    let texel_of = |r: Option<TextureRef>| {
        let t = &s.textures[r.expect("the texture is read back").texture];
        (t.width, t.height, t.rgba.to_vec())
    };
    assert_eq!(
        texel_of(m0.metallic_roughness_texture),
        (4, 4, scene.textures[0].rgba.to_vec())
    );
    assert_eq!(
        texel_of(m0.emissive_texture),
        (4, 4, scene.textures[1].rgba.to_vec())
    );
    assert!(m1.metallic_roughness_texture.is_none() && m1.emissive_texture.is_none());
}
