//! Whole glTF scenes: materials, images, lights and camera mapped as documented, and the
//! default lights and camera of a file without them (glTF and PLY).

use glam::{Mat4, Quat, Vec3};
use manyshadows_scene::builtin::{
    DIRECTIONAL_CASCADES, DIRECTIONAL_SHADOW_RESOLUTION, DIRECTIONAL_SPLIT_LAMBDA,
    POINT_SHADOW_RESOLUTION, SPOT_SHADOW_RESOLUTION,
};
use manyshadows_scene::loaders::{write_ply_ascii, GLTF_SIZE_EXTRA};
use manyshadows_scene::{AlphaMode, Attenuation, LightKind, Lighting, Texture, TextureRef, Wrap};
use serde_json::{json, Value};

use crate::common::{
    assert_frames, base64, close, garbage, load_one, png, pyramid, quad_doc, save_json, scene_of,
    temp_dir, write,
};

#[test]
fn gltf_materials_map_to_phong() {
    let dir = temp_dir("gltf_materials");
    let image = Texture::from_fn("checker", 4, 2, |x, y| {
        [x as u8 * 60, y as u8 * 120, 33, 100 + 20 * x as u8]
    });
    let uri = format!("data:image/png;base64,{}", base64(&png(&image)));
    let mut doc = quad_doc(json!([{ "mesh": 0 }, { "mesh": 2 }]));
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    let mut second = doc["meshes"][0].clone();
    second["primitives"][0]["material"] = json!(1);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    doc["meshes"].as_array_mut().unwrap().push(second);
    doc["images"] = json!([{ "uri": uri }]);
    doc["samplers"] = json!([{ "wrapS": 33071, "wrapT": 33648 }]);
    doc["textures"] = json!([{ "source": 0, "sampler": 0 }, { "source": 0 }]);
    doc["materials"] = json!([
        {
            "name": "leaves",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.4, 0.2, 0.5],
                "metallicFactor": 0.5,
                "roughnessFactor": 0.5,
                "baseColorTexture": { "index": 0, "texCoord": 1 }
            },
            "normalTexture": { "index": 1 },
            "alphaMode": "MASK",
            "alphaCutoff": 0.3,
            "doubleSided": true
        },
        {
            "name": "glass",
            "pbrMetallicRoughness": {
                "baseColorTexture": {
                    "index": 1,
                    "extensions": { "KHR_texture_transform": { "scale": [2, 2] } }
                }
            },
            "alphaMode": "BLEND",
            "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 } }
        }
    ]);
    let loaded = scene_of(&save_json(&dir, "materials.gltf", &doc));
    let scene = &loaded.scene;
    assert_eq!(scene.meshes.len(), 2);
    // One image, decoded once for three uses.
    assert_eq!(scene.textures.len(), 1);
    assert_eq!(scene.textures[0].rgba, image.rgba);

    let leaves = scene.materials[scene.instances[0].material];
    let base = Vec3::new(0.8, 0.4, 0.2);
    assert_eq!(leaves.diffuse, base);
    assert_eq!(leaves.ambient, base);
    assert!(close(
        leaves.specular,
        Vec3::splat(0.04).lerp(base, 0.5),
        1e-6
    ));
    // α = 0.5² = 0.25: 2/α² − 2 = 30.
    assert!(
        (leaves.shininess - 30.0).abs() < 1e-4,
        "{}",
        leaves.shininess
    );
    assert_eq!(leaves.base_alpha, 0.5);
    assert_eq!(leaves.alpha_mode, AlphaMode::Mask);
    assert_eq!(leaves.alpha_cutoff, 0.3);
    assert!(leaves.double_sided);
    assert_eq!(
        leaves.base_color_texture,
        Some(TextureRef {
            texture: 0,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::MirroredRepeat
        })
    );
    assert_eq!(leaves.normal_texture, Some(TextureRef::repeat(0)));

    // glTF defaults: white, metallic 1, roughness 1.
    let glass = scene.materials[scene.instances[1].material];
    assert_eq!(glass.diffuse, Vec3::ONE);
    assert_eq!(glass.specular, Vec3::ONE);
    assert_eq!(glass.shininess, 1.0);
    assert_eq!(glass.alpha_mode, AlphaMode::Blend);
    assert!(!glass.double_sided);
    assert_eq!(glass.base_color_texture, Some(TextureRef::repeat(0)));

    let notes = loaded.notes.join("\n");
    assert!(
        notes.contains("material 'leaves': its base-colour texture uses texture-coordinate set 1"),
        "{notes}"
    );
    // One note for the extension it ignores; KHR_texture_transform is applied (to no
    // texture coordinates here), so it gets none.
    assert!(
        notes.contains(
            "the file uses the extension KHR_materials_transmission (on 1 of its materials), \
             which this loader ignores"
        ),
        "{notes}"
    );
    assert!(!notes.contains("KHR_texture_transform"), "{notes}");
    // Texture coordinates: none in this file.
    assert!(scene.meshes[0].uvs.is_empty());
}

#[test]
fn gltf_bad_images_leave_materials_untextured_with_a_note() {
    let dir = temp_dir("gltf_bad_image");
    let mut doc = quad_doc(json!([{ "mesh": 0 }]));
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let garbage_png = base64(b"\x89PNG\r\n\x1a\n this is not really a PNG file");
    let cases = [
        json!({ "uri": format!("data:image/png;base64,{garbage_png}") }),
        json!({ "uri": format!("data:image/png;base64,{}", base64(&garbage(300, 9))) }),
        json!({ "uri": "data:image/png;base64,@@not base64@@" }),
        json!({ "uri": "missing.png" }),
        json!({ "uri": "https://example.com/remote.png" }),
        json!({ "uri": "data:image/png,plain" }),
        json!({ "bufferView": 0, "mimeType": "image/png" }),
        json!({ "bufferView": 0 }),
    ];
    for (i, image) in cases.into_iter().enumerate() {
        doc["images"] = json!([image]);
        doc["textures"] = json!([{ "source": 0 }]);
        doc["materials"] = json!([{
            "name": "broken",
            "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } }
        }]);
        let path = save_json(&dir, &format!("bad{i}.gltf"), &doc);
        let loaded = scene_of(&path);
        let m = loaded.scene.materials[loaded.scene.instances[0].material];
        assert_eq!(m.base_color_texture, None, "case {i}");
        assert!(loaded.scene.textures.is_empty(), "case {i}");
        assert!(
            loaded
                .notes
                .iter()
                .any(|n| n.contains("material 'broken'") && n.contains("could not be used")),
            "case {i}: {:?}",
            loaded.notes
        );
        // Geometry alone does not look at images.
        load_one(&path);
    }
}

/// Three lights under a rotated parent, a camera, the quad: the documented mappings.
fn lights_doc() -> Value {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let mut doc = quad_doc(json!([
        { "mesh": 0 },
        { "name": "spot", "translation": [1, 2, 3], "rotation": [-s, 0, 0, s],
          "extensions": { "KHR_lights_punctual": { "light": 0 } } },
        { "name": "parent", "rotation": [0, s, 0, s], "children": [3, 4] },
        { "name": "sun", "rotation": [-0.38268343, 0, 0, 0.9238795],
          "extensions": { "KHR_lights_punctual": { "light": 1 } } },
        { "name": "bulb", "translation": [-1, 4, 0],
          "extensions": { "KHR_lights_punctual": { "light": 2 } } },
        { "translation": [0, 0, 9], "extensions": { "KHR_lights_punctual": { "light": 3 } } },
        { "translation": [0, 0, -9], "extensions": { "KHR_lights_punctual": { "light": 4 } } },
        { "translation": [2, 0, 0], "rotation": [0, 0, 0, 1],
          "extensions": { "KHR_lights_punctual": { "light": 5 } } }
    ]));
    doc["scenes"][0]["nodes"] = json!([0, 1, 2, 5, 6, 7]);
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "name": "spot", "type": "spot", "color": [1.0, 0.5, 0.25], "intensity": 0.5,
          "spot": { "innerConeAngle": 0.3, "outerConeAngle": 0.5 } },
        { "name": "sun", "type": "directional", "color": [1.0, 0.9, 0.8], "intensity": 30 },
        { "name": "bulb", "type": "point", "intensity": 100, "range": 7.5 },
        { "name": "bright", "type": "point", "intensity": 1000 },
        { "name": "off", "type": "point", "intensity": 0 },
        { "name": "wide", "type": "spot", "spot": { "outerConeAngle": 1.5707964 } }
    ] } });
    doc
}

#[test]
fn gltf_lights_map_to_the_documented_physical_values() {
    let dir = temp_dir("gltf_lights");
    let loaded = scene_of(&save_json(&dir, "lights.gltf", &lights_doc()));
    assert_eq!(loaded.scene.lighting, Lighting::Physical);
    let lights = &loaded.scene.lights;
    assert_eq!(lights.len(), 6, "{lights:?}");
    assert!(
        !loaded.notes.iter().any(|n| n.contains("no lights")),
        "{:?}",
        loaded.notes
    );
    // The quad spans (0,0,0)..(1,1,0): diagonal √2.
    let diagonal = 2f32.sqrt();
    let inverse_square = Attenuation {
        constant: 1.0,
        linear: 0.0,
        quadratic: 1.0,
    };
    for l in lights {
        assert_eq!(l.ambient, Vec3::ZERO);
        assert_eq!(l.specular, l.diffuse);
        assert!(l.casts_shadows);
        assert_eq!(l.size, 0.0, "punctual: hard without a size in extras");
        l.validate().unwrap();
    }

    // Spot: −90° about X turns −Z into −Y; colour × intensity (candela); range where a
    // tenth of it, 0.05 / (1 + d²), is 1/256; cutoff = outer angle.
    let spot = lights[0];
    let LightKind::Spot {
        position,
        direction,
        cutoff_deg,
        range,
    } = spot.kind
    else {
        panic!("{spot:?}")
    };
    assert!(close(position, Vec3::new(1.0, 2.0, 3.0), 1e-6));
    assert!(close(direction, Vec3::NEG_Y, 1e-6), "{direction}");
    assert!((cutoff_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    assert!(close(spot.diffuse, Vec3::new(1.0, 0.5, 0.25) * 0.5, 1e-6));
    assert!(
        (range - (256.0f32 * 0.05 - 1.0).sqrt()).abs() < 1e-4,
        "{range}"
    );
    assert_eq!(spot.attenuation, inverse_square);
    assert_eq!(spot.shadow_resolution, SPOT_SHADOW_RESOLUTION);

    // Directional, under a parent turned +90° about Y: world rotation = parent · child.
    let sun = lights[1];
    let want = Quat::from_xyzw(
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
    ) * Quat::from_xyzw(-0.38268343, 0.0, 0.0, 0.9238795)
        * Vec3::NEG_Z;
    assert_eq!(
        sun.kind,
        LightKind::Directional {
            direction: match sun.kind {
                LightKind::Directional { direction, .. } => direction,
                _ => panic!("{sun:?}"),
            },
            cascades: DIRECTIONAL_CASCADES,
            split_lambda: DIRECTIONAL_SPLIT_LAMBDA,
            cascade_resolution_scale: 1.0,
        }
    );
    if let LightKind::Directional { direction, .. } = sun.kind {
        assert!(close(direction, want, 1e-5), "{direction} vs {want}");
    }
    assert!(close(sun.diffuse, Vec3::new(30.0, 27.0, 24.0), 1e-5));
    assert_eq!(sun.attenuation, Attenuation::NONE);
    assert_eq!(sun.shadow_resolution, DIRECTIONAL_SHADOW_RESOLUTION);

    // Point with a range (its parent's rotation turns its translation).
    let bulb = lights[2];
    let LightKind::Point { position, range } = bulb.kind else {
        panic!("{bulb:?}")
    };
    assert!(
        close(position, Vec3::new(0.0, 4.0, 1.0), 1e-6),
        "{position}"
    );
    assert_eq!(range, 7.5);
    assert!(close(bulb.diffuse, Vec3::splat(100.0), 1e-5));
    assert_eq!(bulb.attenuation, inverse_square);
    assert_eq!(bulb.shadow_resolution, POINT_SHADOW_RESOLUTION);

    // Bright point without a range: clamped to 4 × the diagonal; a dark one: at least 0.1.
    let LightKind::Point { range, .. } = lights[3].kind else {
        panic!()
    };
    assert!((range - 4.0 * diagonal).abs() < 1e-5, "{range}");
    let off = lights[4];
    assert_eq!(off.diffuse, Vec3::ZERO);
    let LightKind::Point { range, .. } = off.kind else {
        panic!()
    };
    assert_eq!(range, 0.1);

    // A 90° glTF cone is clamped just inside this renderer's limit.
    let LightKind::Spot {
        cutoff_deg,
        direction,
        ..
    } = lights[5].kind
    else {
        panic!()
    };
    assert!(cutoff_deg < 89.0 && cutoff_deg > 88.9, "{cutoff_deg}");
    assert_eq!(direction, Vec3::NEG_Z);
}

/// A light's size comes from `extras.manyshadows_size` on its `KHR_lights_punctual` entry, in
/// the units of `Light::size`; a value no light of its type can have is a note and a point.
#[test]
fn gltf_light_size_comes_from_extras() {
    let dir = temp_dir("gltf_light_sizes");
    let mut doc = lights_doc();
    let lights = &mut doc["extensions"]["KHR_lights_punctual"]["lights"];
    for (i, size) in [
        (0, json!(0.3)),
        (1, json!(0.53)),
        (2, json!("big")),
        (3, json!(-1)),
        (4, json!(2)),
    ] {
        lights[i]["extras"] = json!({ GLTF_SIZE_EXTRA: size });
    }
    lights[5]["extras"] = json!({ "other": 1 });
    let loaded = scene_of(&save_json(&dir, "sizes.gltf", &doc));
    let sizes: Vec<f32> = loaded.scene.lights.iter().map(|l| l.size).collect();
    assert_eq!(sizes, [0.3, 0.53, 0.0, 0.0, 2.0, 0.0]);
    for (name, value) in [("bulb", "\"big\""), ("bright", "-1")] {
        assert!(
            loaded
                .notes
                .iter()
                .any(|n| n.contains(&format!("light '{name}'"))
                    && n.contains(&format!("{GLTF_SIZE_EXTRA} = {value}"))
                    && n.contains("radius")),
            "{name}: {:?}",
            loaded.notes
        );
    }
    loaded.scene.validate().unwrap();

    // A directional light's size is an angular diameter below 30 degrees.
    let mut doc = lights_doc();
    doc["extensions"]["KHR_lights_punctual"]["lights"][1]["extras"] =
        json!({ GLTF_SIZE_EXTRA: 30 });
    let loaded = scene_of(&save_json(&dir, "wide-sun.gltf", &doc));
    assert_eq!(loaded.scene.lights[1].size, 0.0);
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("light 'sun'") && n.contains("angular diameter")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn gltf_camera_node_maps_to_the_documented_camera() {
    let dir = temp_dir("gltf_camera");
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let mut doc = quad_doc(json!([
        { "mesh": 0 },
        { "name": "ortho", "camera": 1 },
        { "name": "eye", "translation": [0, 2, 10], "rotation": [0, s, 0, s], "camera": 0 }
    ]));
    doc["scenes"][0]["nodes"] = json!([0, 1, 2]);
    doc["cameras"] = json!([
        { "name": "main", "type": "perspective",
          "perspective": { "yfov": 0.8, "znear": 0.05, "zfar": 500, "aspectRatio": 1.5 } },
        { "name": "top", "type": "orthographic",
          "orthographic": { "xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10 } }
    ]);
    let loaded = scene_of(&save_json(&dir, "camera.gltf", &doc));
    let c = loaded.scene.camera;
    let position = Vec3::new(0.0, 2.0, 10.0);
    // +90° about Y turns −Z into −X.
    let centre = Vec3::new(0.5, 0.5, 0.0);
    let distance = (centre - position).length();
    assert!(close(c.position, position, 1e-6));
    assert!(
        close(c.target, position + Vec3::NEG_X * distance, 1e-5),
        "{}",
        c.target
    );
    assert!(close(c.up, Vec3::Y, 1e-6));
    assert!((c.fov_y_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!((c.near, c.far), (0.05, 500.0));
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("camera 'top' is orthographic") && n.contains("'main' is used")),
        "{:?}",
        loaded.notes
    );

    // Infinite projection: far = near + 4 × the diagonal.
    doc["cameras"][0]["perspective"] = json!({ "yfov": 0.8, "znear": 0.05 });
    let c = scene_of(&save_json(&dir, "infinite.gltf", &doc))
        .scene
        .camera;
    assert!(
        (c.far - (0.05 + 4.0 * 2f32.sqrt())).abs() < 1e-5,
        "{}",
        c.far
    );

    // Only an orthographic camera: the default camera, and a note.
    doc["nodes"][2].as_object_mut().unwrap().remove("camera");
    let loaded = scene_of(&save_json(&dir, "ortho.gltf", &doc));
    let _ = centre;
    let (lo, hi) = loaded.scene.world_bounds(false).unwrap();
    assert_frames(&loaded.scene.camera, lo, hi);
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("orthographic") && n.contains("the default camera is used")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn files_without_lights_or_camera_get_defaults_and_a_note() {
    let dir = temp_dir("defaults");
    let gltf = save_json(&dir, "plain.gltf", &quad_doc(json!([{ "mesh": 0 }])));
    let mut ply = Vec::new();
    write_ply_ascii(&pyramid(), &mut ply).unwrap();
    let ply = write(&dir, "pyramid.ply", &ply);
    for path in [gltf, ply] {
        let loaded = scene_of(&path);
        let scene = &loaded.scene;
        assert_eq!(scene.lights.len(), 8);
        let count = |t: &str| scene.lights.iter().filter(|l| l.type_name() == t).count();
        assert_eq!(
            (count("spot"), count("point"), count("directional")),
            (0, 5, 3)
        );
        assert!(
            loaded.notes.contains(
                &"the file has no lights: added a light rig of 8 (key, fill and rim directional \
                  lights, 5 coloured point lights around the model)"
                    .to_string()
            ),
            "{:?}",
            loaded.notes
        );
        let (lo, hi) = scene.world_bounds(false).unwrap();
        // The rig lights the side the camera sees: key and fill come from the camera's side
        // (and from above), the rim from behind; no light stands inside the model.
        let towards_camera = (scene.camera.position - scene.camera.target).normalize();
        let from: Vec<f32> = scene
            .lights
            .iter()
            .filter_map(|l| match l.kind {
                LightKind::Directional { direction, .. } => Some(-direction.dot(towards_camera)),
                _ => None,
            })
            .collect();
        assert!(from[0] > 0.3 && from[1] > 0.3 && from[2] < 0.0, "{from:?}");
        for l in &scene.lights {
            if let LightKind::Point { position, .. } = l.kind {
                let inside = position.cmpge(lo).all() && position.cmple(hi).all();
                assert!(!inside, "a rig light inside the model's bounds: {position}");
            }
        }
        assert_frames(&scene.camera, lo, hi);
        let diagonal = (hi - lo).length();
        assert!((scene.camera.near - diagonal / 1000.0).abs() < 1e-7);
        let distance = (scene.camera.position - scene.camera.target).length();
        assert!((scene.camera.far - (4.0 * diagonal + distance)).abs() < 1e-4);
        // One identity instance per mesh, casting shadows.
        for (i, inst) in scene.instances.iter().enumerate() {
            assert_eq!(inst.mesh, i);
            assert_eq!(inst.transform, Mat4::IDENTITY);
            assert!(inst.casts_shadows);
        }
        scene.validate().unwrap();
    }
}
