//! TOML scene-file tests.

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use manyshadows_scene::loaders::write_obj;
use manyshadows_scene::scene_file::{self, load_scene_file, parse_scene_str};
use manyshadows_scene::{Attenuation, LightKind, Material, Mesh, Scene, SceneError};

fn example_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/example_scene.toml")
}

fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "manyshadows-scenefile-{}-{test}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    parse_scene_str(text, Path::new("."))
}

/// The parse error's message (panics on success or another kind of error).
fn parse_err(text: &str) -> String {
    match parse(text) {
        Err(e @ SceneError::Parse { .. }) => e.to_string(),
        other => panic!("expected a Parse error, got {other:?}"),
    }
}

const BASE: &str = r#"
[[mesh]]
name = "floor"
primitive = "plane"
size = [10, 10]

[[mesh]]
name = "box"
primitive = "cube"
size = 1
"#;

#[test]
fn example_scene_parses() {
    let scene = load_scene_file(&example_path()).unwrap();
    scene.validate().unwrap();
    assert_eq!(scene.name, "example");
    assert_eq!(scene.meshes.len(), 3);
    assert_eq!(scene.instances.len(), 3);
    // Two named materials plus the default one (the ball names none).
    assert_eq!(scene.materials.len(), 3);
    assert_eq!(scene.materials[2], Material::default());
    assert_eq!(scene.instances[2].material, 2);
    assert!(!scene.instances[0].casts_shadows);
    assert!(scene.instances[1].casts_shadows);
    let types: Vec<_> = scene.lights.iter().map(|l| l.type_name()).collect();
    assert_eq!(types, ["spot", "point", "directional"]);
    assert!(scene.triangle_count() > 12);

    // Floor: 20 x 20 in XZ, centred.
    let (lo, hi) = scene.meshes[0].bounds().unwrap();
    assert!((lo - Vec3::new(-10.0, 0.0, -10.0)).length() < 1e-4, "{lo}");
    assert!((hi - Vec3::new(10.0, 0.0, 10.0)).length() < 1e-4, "{hi}");

    // Sizes: the spot and the sun say theirs, the point light is hard by default.
    let sizes: Vec<f32> = scene.lights.iter().map(|l| l.size).collect();
    assert_eq!(sizes, [0.15, 0.0, 0.53]);

    // The spot light took its defaults.
    let spot = &scene.lights[0];
    assert_eq!(spot.shadow_resolution, 1024);
    assert_eq!(spot.attenuation, Attenuation::for_range(20.0));
    assert_eq!(spot.specular, spot.diffuse);
    assert_eq!(spot.ambient, Vec3::ZERO);
    // The point light kept its explicit attenuation and resolution.
    let point = &scene.lights[1];
    assert_eq!(point.shadow_resolution, 512);
    assert_eq!(
        point.attenuation,
        Attenuation {
            constant: 1.0,
            linear: 0.2,
            quadratic: 0.05
        }
    );
    // The directional light: normalized direction, its own defaults.
    let sun = &scene.lights[2];
    assert_eq!(sun.shadow_resolution, 2048);
    assert_eq!(sun.attenuation, Attenuation::NONE);
    match sun.kind {
        LightKind::Directional {
            direction,
            cascades,
            split_lambda,
            cascade_resolution_scale,
        } => {
            assert_eq!(
                cascade_resolution_scale, 1.0,
                "default: every cascade at full size"
            );
            assert!((direction.length() - 1.0).abs() < 1e-6);
            assert!(direction.y < 0.0);
            assert_eq!((cascades, split_lambda), (4, 0.8));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn format_doc_contains_the_example_verbatim() {
    let example = std::fs::read_to_string(example_path()).unwrap();
    let doc_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/SCENE_FORMAT.md");
    let doc = std::fs::read_to_string(doc_path).unwrap();
    assert!(
        doc.contains(&format!("```toml\n{example}```")),
        "docs/SCENE_FORMAT.md no longer shows docs/example_scene.toml verbatim"
    );
}

#[test]
fn defaults_for_an_almost_empty_scene() {
    let scene = parse("").unwrap();
    assert_eq!(scene.name, "untitled");
    assert!(scene.meshes.is_empty() && scene.lights.is_empty() && scene.instances.is_empty());
    assert_eq!(scene.camera, manyshadows_scene::Camera::default());
}

#[test]
fn unknown_field_error_names_the_field_and_line() {
    let msg = parse_err("[[material]]\nname = \"m\"\ncolour = [1, 0, 0]\n");
    assert!(msg.contains("colour"), "{msg}");
    assert!(msg.contains("line 3"), "{msg}");

    let msg = parse_err(&format!(
        "{BASE}[[instance]]\nmesh = \"box\"\ntranslation = [1, 2, 3]\n"
    ));
    assert!(msg.contains("translation"), "{msg}");

    let msg = parse_err("[camera]\nposition = [0, 1, 2]\ntarget = [0, 0, 0]\nfov = 60\n");
    assert!(msg.contains("fov"), "{msg}");

    let msg = parse_err("nmae = \"x\"\n");
    assert!(msg.contains("nmae"), "{msg}");
}

#[test]
fn unknown_mesh_and_material_names_are_named() {
    let msg = parse_err(&format!("{BASE}\n[[instance]]\nmesh = \"flor\"\n"));
    assert!(msg.contains("'flor'"), "{msg}");
    assert!(msg.contains("'floor'"), "lists the defined meshes: {msg}");
    assert!(msg.contains("line 12"), "{msg}");

    let msg = parse_err(&format!(
        "{BASE}[[instance]]\nmesh = \"box\"\nmaterial = \"marble\"\n"
    ));
    assert!(msg.contains("'marble'"), "{msg}");
}

#[test]
fn duplicate_names_are_errors() {
    let msg = parse_err(&format!(
        "{BASE}[[mesh]]\nname = \"box\"\nprimitive = \"sphere\"\nradius = 1\n"
    ));
    assert!(msg.contains("duplicate mesh name 'box'"), "{msg}");
    let msg = parse_err("[[material]]\nname = \"a\"\n[[material]]\nname = \"a\"\n");
    assert!(msg.contains("duplicate material name 'a'"), "{msg}");
}

#[test]
fn bad_light_type_is_parse_error() {
    let msg = parse_err("[[light]]\ntype = \"spott\"\nposition = [0, 1, 0]\n");
    assert!(msg.contains("spott"), "{msg}");
    assert!(msg.contains("directional"), "lists the valid types: {msg}");
}

#[test]
fn light_keys_must_fit_the_type() {
    let msg = parse_err(
        "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nrange = 5\ncutoff_deg = 20\n",
    );
    assert!(msg.contains("cutoff_deg") && msg.contains("point"), "{msg}");
    let msg =
        parse_err("[[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\nrange = 5\ncutoff_deg = 20\n");
    assert!(msg.contains("needs `direction`"), "{msg}");
    let msg = parse_err("[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nrange = 5\n");
    assert!(msg.contains("range"), "{msg}");
}

#[test]
fn negative_range_is_rejected() {
    let text = "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nrange = 5\n\
                [[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\n\
                cutoff_deg = 30\nrange = -5\n";
    match parse(text) {
        Err(SceneError::InvalidLight { index, reason }) => {
            assert_eq!(index, 1);
            assert!(reason.contains("range"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn malformed_toml_is_parse_error() {
    for text in [
        "[[mesh]\nname = \"x\"\n",
        "name = \n",
        "[camera]\nposition = [0, 1\n",
        "name = \"a\"\nname = \"b\"\n",
        "[[light]]\ntype = \"point\"\nposition = [0, 1]\nrange = 5\n",
        "[[light]]\ntype = \"point\"\nposition = \"here\"\nrange = 5\n",
    ] {
        let e = parse(text).unwrap_err();
        assert!(matches!(e, SceneError::Parse { .. }), "{text:?}: {e:?}");
        assert!(e.to_string().contains("line"), "{e}");
    }
}

#[test]
fn nan_values_are_rejected() {
    let e = parse("[[light]]\ntype = \"point\"\nposition = [nan, 1, 0]\nrange = 5\n").unwrap_err();
    assert!(
        matches!(e, SceneError::InvalidLight { index: 0, .. }),
        "{e:?}"
    );

    let e = parse(&format!(
        "{BASE}[[instance]]\nmesh = \"box\"\ntranslate = [0, nan, 0]\n"
    ))
    .unwrap_err();
    assert!(
        matches!(e, SceneError::InvalidInstance { index: 0, .. }),
        "{e:?}"
    );

    let e = parse("[[material]]\nname = \"m\"\nshininess = nan\n[[mesh]]\nname = \"b\"\nprimitive = \"cube\"\nsize = 1\n[[instance]]\nmesh = \"b\"\nmaterial = \"m\"\n").unwrap_err();
    assert!(
        matches!(e, SceneError::InvalidMaterial { index: 0, .. }),
        "{e:?}"
    );

    let msg = parse_err("[[mesh]]\nname = \"s\"\nprimitive = \"sphere\"\nradius = nan\n");
    assert!(msg.contains("radius"), "{msg}");

    let e = parse("[camera]\nposition = [0, 1, 2]\ntarget = [0, 0, inf]\n").unwrap_err();
    assert!(matches!(e, SceneError::InvalidCamera(_)), "{e:?}");
}

#[test]
fn primitive_parameters_are_checked() {
    let msg = parse_err("[[mesh]]\nname = \"s\"\nprimitive = \"sphere\"\n");
    assert!(msg.contains("needs `radius`"), "{msg}");
    let msg =
        parse_err("[[mesh]]\nname = \"p\"\nprimitive = \"plane\"\nsize = [1, 1]\nradius = 2\n");
    assert!(msg.contains("radius") && msg.contains("plane"), "{msg}");
    let msg = parse_err("[[mesh]]\nname = \"p\"\nprimitive = \"plane\"\nsize = [1, 2, 3]\n");
    assert!(msg.contains("size"), "{msg}");
    let msg = parse_err("[[mesh]]\nname = \"c\"\nprimitive = \"cube\"\nsize = [1, -2, 3]\n");
    assert!(msg.contains("size"), "{msg}");
    let msg = parse_err("[[mesh]]\nname = \"c\"\nprimitive = \"cylinder\"\nradius = 1\nheight = 2\nsegments = 100000\n");
    assert!(msg.contains("segments") && msg.contains("1024"), "{msg}");
    let msg = parse_err("[[mesh]]\nname = \"t\"\nprimitive = \"teapot\"\n");
    assert!(msg.contains("teapot"), "{msg}");
    let msg = parse_err("[[mesh]]\nname = \"x\"\n");
    assert!(msg.contains("file") && msg.contains("primitive"), "{msg}");
    let msg =
        parse_err("[[mesh]]\nname = \"x\"\nfile = \"a.obj\"\nprimitive = \"cube\"\nsize = 1\n");
    assert!(msg.contains("not both"), "{msg}");

    let scene = parse(
        "[[mesh]]\nname = \"c\"\nprimitive = \"cylinder\"\nradius = 0.5\nheight = 3\n\
         [[mesh]]\nname = \"s\"\nprimitive = \"sphere\"\nradius = 2\nsegments = 8\nrings = 4\n",
    )
    .unwrap();
    let (lo, hi) = scene.meshes[0].bounds().unwrap();
    assert!(
        lo.y.abs() < 1e-5 && (hi.y - 3.0).abs() < 1e-5,
        "cylinder base at y = 0: {lo} {hi}"
    );
    let (lo, hi) = scene.meshes[1].bounds().unwrap();
    assert!(
        (hi.y - 2.0).abs() < 1e-4 && (lo.y + 2.0).abs() < 1e-4,
        "{lo} {hi}"
    );
}

#[test]
fn instance_transform_order_and_scale_forms() {
    let text = format!(
        "{BASE}[[instance]]\nmesh = \"box\"\nrotate_deg = [90, 90, 0]\n\
         [[instance]]\nmesh = \"box\"\ntranslate = [1, 2, 3]\nrotate_deg = [0, 0, 90]\nscale = [2, 3, 4]\n\
         [[instance]]\nmesh = \"box\"\nscale = 0.5\ncasts_shadows = false\n"
    );
    let scene = parse(&text).unwrap();
    // X first, then Y: [0, 1, 0] -> [0, 0, 1] -> [1, 0, 0].
    let p = scene.instances[0].transform.transform_point3(Vec3::Y);
    assert!((p - Vec3::X).length() < 1e-5, "{p}");
    // Scale, then rotate 90° about Z, then translate: [1, 0, 0] -> [2, 0, 0] -> [0, 2, 0] -> [1, 4, 3].
    let p = scene.instances[1].transform.transform_point3(Vec3::X);
    assert!((p - Vec3::new(1.0, 4.0, 3.0)).length() < 1e-5, "{p}");
    assert_eq!(
        scene.instances[2].transform,
        Mat4::from_scale(Vec3::splat(0.5))
    );
    assert!(!scene.instances[2].casts_shadows);
    // Default material appended once for the three instances.
    assert_eq!(scene.materials, vec![Material::default()]);

    let msg = parse_err(&format!(
        "{BASE}[[instance]]\nmesh = \"box\"\nscale = [1, 2]\n"
    ));
    assert!(msg.contains("scale"), "{msg}");
    let e = parse(&format!("{BASE}[[instance]]\nmesh = \"box\"\nscale = 0\n")).unwrap_err();
    assert!(matches!(e, SceneError::InvalidInstance { .. }), "{e:?}");
}

#[test]
fn mesh_files_are_loaded_relative_and_merged() {
    let dir = temp_dir("mesh_file");
    std::fs::create_dir_all(dir.join("models")).unwrap();
    let tri = |z: f32| Mesh {
        uvs: Vec::new(),
        name: "t".into(),
        positions: vec![
            Vec3::new(0.0, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(0.0, 1.0, z),
        ],
        normals: vec![Vec3::Z; 3],
        indices: vec![0, 1, 2],
    };
    // Two objects in one OBJ file.
    let mut obj = Vec::new();
    write_obj(&tri(0.0), &mut obj).unwrap();
    let mut second = Vec::new();
    write_obj(&tri(5.0), &mut second).unwrap();
    let second = String::from_utf8(second)
        .unwrap()
        .replace("o t", "o u")
        .replace("f 1//1 2//2 3//3", "f 4//4 5//5 6//6");
    obj.extend_from_slice(second.as_bytes());
    std::fs::write(dir.join("models/two.obj"), obj).unwrap();

    let scene_path = dir.join("scene.toml");
    std::fs::write(
        &scene_path,
        "[[mesh]]\nname = \"pair\"\nfile = \"models/two.obj\"\n[[instance]]\nmesh = \"pair\"\n",
    )
    .unwrap();
    let scene = load_scene_file(&scene_path).unwrap();
    assert_eq!(scene.name, "scene");
    assert_eq!(scene.meshes.len(), 1);
    let m = &scene.meshes[0];
    assert_eq!(m.name, "pair");
    assert_eq!(m.triangle_count(), 2);
    assert_eq!(m.indices, vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(m.positions[4], Vec3::new(1.0, 0.0, 5.0));

    // A missing mesh file is the loader's Io error, naming the file.
    std::fs::write(
        &scene_path,
        "[[mesh]]\nname = \"gone\"\nfile = \"models/gone.ply\"\n",
    )
    .unwrap();
    let e = load_scene_file(&scene_path).unwrap_err();
    assert!(
        matches!(e, SceneError::Io { .. }) && e.to_string().contains("gone.ply"),
        "{e:?}"
    );
    let msg = parse_err("[[mesh]]\nname = \"x\"\nfile = \"a.obj\"\nradius = 1\n");
    assert!(msg.contains("radius"), "{msg}");
}

#[test]
fn missing_scene_file_is_io_error() {
    let e = load_scene_file(Path::new("/nonexistent/manyshadows/scene.toml")).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }), "{e:?}");
}

#[test]
fn limits_are_enforced() {
    // Instances.
    let mut text = String::from(BASE);
    for _ in 0..=scene_file::MAX_INSTANCES {
        text.push_str("[[instance]]\nmesh = \"box\"\n");
    }
    match parse(&text) {
        Err(e @ SceneError::TooLarge { .. }) => assert!(e.to_string().contains("100000"), "{e}"),
        other => panic!("{other:?}"),
    }
    // Lights.
    let mut text = String::new();
    for _ in 0..=scene_file::MAX_LIGHTS {
        text.push_str("[[light]]\ntype=\"point\"\nposition=[0,1,0]\nrange=1\n");
    }
    assert!(matches!(parse(&text), Err(SceneError::TooLarge { .. })));
    // File size (text and file).
    let big = "#".repeat(scene_file::MAX_SCENE_FILE_BYTES as usize + 1);
    assert!(matches!(parse(&big), Err(SceneError::TooLarge { .. })));
    let dir = temp_dir("limits");
    let p = dir.join("big.toml");
    std::fs::write(&p, &big).unwrap();
    let r = load_scene_file(&p);
    let _ = std::fs::remove_file(&p);
    assert!(matches!(r, Err(SceneError::TooLarge { .. })), "{r:?}");
}

/// `size`: read per light, 0 when absent, refused (a `Parse` error naming the light's entry,
/// its line and the key) when negative or not finite, or when a directional light's angular
/// diameter reaches 30 degrees (`MAX_ANGULAR_SIZE_DEG`).
#[test]
fn light_size_is_read_defaulted_and_checked() {
    let lights = |sizes: [&str; 3]| {
        format!(
            "[[light]]\ntype = \"spot\"\nposition = [0, 4, 0]\ndirection = [0, -1, 0]\n\
             cutoff_deg = 30\nrange = 10\n{}\n\
             [[light]]\ntype = \"point\"\nposition = [1, 2, 0]\nrange = 5\n{}\n\
             [[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\n{}\n",
            sizes[0], sizes[1], sizes[2]
        )
    };
    let scene = parse(&lights(["size = 0.25", "size = 1", "size = 0.53"])).unwrap();
    let sizes: Vec<f32> = scene.lights.iter().map(|l| l.size).collect();
    assert_eq!(sizes, [0.25, 1.0, 0.53]);
    let scene = parse(&lights(["", "", ""])).unwrap();
    assert!(scene.lights.iter().all(|l| l.size == 0.0), "default: hard");

    for (sizes, light, line, needle) in [
        (["size = -0.1", "", ""], 0, 1, "radius in world units"),
        (["", "size = nan", ""], 1, 8, "finite number >= 0"),
        (["", "size = inf", ""], 1, 8, "finite number >= 0"),
        (["", "", "size = -1"], 2, 13, "angular diameter in degrees"),
        (["", "", "size = 30"], 2, 13, "below 30"),
    ] {
        let msg = parse_err(&lights(sizes));
        assert!(msg.contains(&format!("[[light]] {light}")), "{msg}");
        assert!(msg.contains(&format!("line {line}")), "{msg}");
        assert!(msg.contains("`size`") && msg.contains(needle), "{msg}");
    }
    let msg =
        parse_err("[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nrange = 5\nsize = \"big\"\n");
    assert!(msg.contains("size"), "{msg}");
}

#[test]
fn cull_back_faces_is_read_and_defaults_to_two_sided() {
    let text = "[[material]]\nname = \"shell\"\ncull_back_faces = true\n[[material]]\nname = \"m\"\n\
                [[mesh]]\nname = \"b\"\nprimitive = \"cube\"\nsize = 1\n\
                [[instance]]\nmesh = \"b\"\nmaterial = \"shell\"\n[[instance]]\nmesh = \"b\"\nmaterial = \"m\"\n";
    let s = parse(text).unwrap();
    assert!(s.materials[0].cull_back_faces);
    assert!(!s.materials[1].cull_back_faces);
    let e = parse_err("[[material]]\nname = \"m\"\ncull_back_faces = 1\n");
    assert!(e.contains("cull_back_faces") || e.contains("bool"), "{e}");
}
