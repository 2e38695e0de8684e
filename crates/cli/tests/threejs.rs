//! glTF files look as another viewer shows them: sample models written by this test (spheres
//! across metallic and roughness under a sun and a point light, a textured box, metallic and
//! roughness from a texture, a lamp of point lights with an emissive bulb and a sign whose
//! emission is a texture) render in `manyshadows render` within a mean ꟻLIP of
//! 0.1 of three.js (npm `three`, its `GLTFLoader` and `MeshStandardMaterial`, WebGL through
//! SwiftShader in headless Chromium). Both sides see the same file: its camera, its
//! `KHR_lights_punctual` lights in candela and lux, no shadows, the exposure ours metered
//! (three.js' `toneMappingExposure`), Khronos PBR Neutral, sRGB output.
//!
//! An independent check: three.js implements the glTF BRDF, light units and the tone map on
//! its own. Where the two are known to differ it is small: three.js (r187) adds a roughness
//! from the normal's screen derivatives, and compensates the specular lobe for multiple
//! scattering (rough metals come out brighter than the glTF specification's appendix B,
//! which ours follows); texture filtering differs at mip boundaries.
//!
//! Needs Chromium and three.js 0.187.0 in `target/npm/three-0.187.0/package` (or
//! `$MANYSHADOWS_THREE`): `cargo xtask test` installs both. The figures per model are printed
//! and written, with the images and ꟻLIP maps, to `target/test-artifacts/threejs/`.
//! `MANYSHADOWS_THREEJS_MODELS=a.glb,b.gltf` adds model files of one's own (loaded by our
//! loader, with its default lights and camera where they have none, and written again so that
//! three.js sees the same lights).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::models::{light, pbr, physical};
use common::{base64, repo, serve, tmp, Browser};
use glam::{Mat4, Quat, Vec3};
use manyshadows_scene::loaders::write_gltf;
use manyshadows_scene::primitives::{cuboid, cylinder, plane, uv_sphere};
use manyshadows_scene::{Camera, Instance, Light, LightKind, Material, Scene, Texture, TextureRef};
use serde_json::json;

const W: u32 = 400;
const H: u32 = 300;
const THREE_VERSION: &str = "0.187.0";
/// The renderer's colour of pixels without geometry (linear; `SKY` in renderer/uniforms.rs).
const SKY: [f32; 3] = [0.015, 0.018, 0.03];
/// The acceptance bound of issue 37.
const MAX_MEAN_FLIP: f64 = 0.1;

/// Tighter bounds per generated model, so that a feature broken on our side fails even where
/// the 0.1 would let it pass. Measured on llvmpipe (Vulkan and GL alike): spheres
/// 0.044, textured box 0.010, metallic-roughness map 0.028, lamp 0.012. Broken on purpose:
/// the BRDF's specular dropped gives spheres 0.117; the metallic-roughness texture ignored
/// gives 0.090 on its model; the emissive texture ignored gives the lamp 0.023.
const MODEL_BOUNDS: [(&str, f64); 4] = [
    ("spheres", 0.06),
    ("textured-box", 0.02),
    ("metal-rough-map", 0.045),
    ("lamp", 0.018),
];

fn three_dir() -> PathBuf {
    let dir = std::env::var_os("MANYSHADOWS_THREE")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join(format!("target/npm/three-{THREE_VERSION}/package")));
    assert!(
        dir.join("build/three.module.js").is_file(),
        "the three.js comparison needs three.js {THREE_VERSION} in {}: `cargo xtask test` \
         downloads it, or `npm pack three@{THREE_VERSION}` and unpack it there",
        dir.display()
    );
    dir
}

/// A point light of `cd` candela (per channel) with an explicit range.
fn point(position: Vec3, range: f32, cd: Vec3) -> Light {
    light(LightKind::Point { position, range }, cd)
}

/// A sun of `lux` (per channel) shining along `direction`.
fn sun(direction: Vec3, lux: Vec3) -> Light {
    light(
        LightKind::Directional {
            direction: direction.normalize(),
            cascades: 1,
            split_lambda: 0.5,
            cascade_resolution_scale: 1.0,
        },
        lux,
    )
}

/// A grey backdrop: a floor and a wall behind, so the frame is mostly shaded surface.
fn backdrop(s: &mut Scene, floor_y: f32, wall_z: f32, size: f32) {
    let m = s.meshes.len();
    s.meshes.push(plane(size, size, 8));
    let mat = s.materials.len();
    s.materials.push(pbr(Vec3::splat(0.5), 0.0, 0.9));
    s.instances.push(Instance::caster(
        m,
        mat,
        Mat4::from_translation(Vec3::new(0.0, floor_y, 0.0)),
    ));
    s.instances.push(Instance::caster(
        m,
        mat,
        Mat4::from_translation(Vec3::new(0.0, floor_y + size * 0.5, wall_z))
            * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    ));
}

/// Five roughnesses (columns) by three metallics (rows), orange base colour.
fn spheres() -> Scene {
    let mut s = physical(
        "spheres",
        Camera::look_at(Vec3::new(0.0, 0.1, 4.4), Vec3::new(0.0, 0.0, 0.0)),
    );
    s.meshes.push(uv_sphere(0.42, 64, 32));
    for (row, metallic) in [0.0, 0.5, 1.0].into_iter().enumerate() {
        for (col, roughness) in [0.05, 0.25, 0.5, 0.75, 1.0].into_iter().enumerate() {
            let mat = s.materials.len();
            s.materials
                .push(pbr(Vec3::new(0.9, 0.45, 0.15), metallic, roughness));
            s.instances.push(Instance::caster(
                0,
                mat,
                Mat4::from_translation(Vec3::new(
                    (col as f32 - 2.0) * 1.0,
                    (1.0 - row as f32) * 1.0,
                    0.0,
                )),
            ));
        }
    }
    backdrop(&mut s, -1.6, -1.5, 14.0);
    s.lights = vec![
        sun(Vec3::new(-0.4, -0.6, -1.0), Vec3::splat(2.5)),
        point(Vec3::new(2.0, 2.5, 3.0), 20.0, Vec3::new(30.0, 28.0, 26.0)),
    ];
    s
}

/// A box with a checker texture (8 × 8 cells of two colours) turned towards the camera, on
/// the backdrop.
fn textured_box() -> Scene {
    let mut s = physical(
        "textured-box",
        Camera::look_at(Vec3::new(1.3, 1.1, 2.0), Vec3::new(0.0, 0.0, 0.0)),
    );
    s.textures
        .push(Texture::from_fn("checker", 128, 128, |x, y| {
            if (x / 16 + y / 16) % 2 == 0 {
                [220, 180, 60, 255]
            } else {
                [40, 90, 160, 255]
            }
        }));
    s.meshes.push(cuboid(Vec3::ONE));
    s.materials.push(Material {
        base_color_texture: Some(TextureRef::repeat(0)),
        ..pbr(Vec3::ONE, 0.0, 0.6)
    });
    s.instances.push(Instance::caster(
        0,
        0,
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(0.0, 0.0, 0.0)),
    ));
    backdrop(&mut s, -0.5, -2.0, 10.0);
    s.lights = vec![
        sun(Vec3::new(-0.5, -1.0, -0.4), Vec3::splat(3.0)),
        point(Vec3::new(1.6, 1.2, 1.4), 8.0, Vec3::new(4.0, 3.5, 3.0)),
    ];
    s
}

/// Metallic and roughness from a texture (glTF's metallicRoughnessTexture: green roughness,
/// blue metallic) times factors of 1: a sphere and a box banded metal / dielectric, roughness
/// rising across them.
fn metal_rough_map() -> Scene {
    let mut s = physical(
        "metal-rough-map",
        Camera::look_at(Vec3::new(0.0, 0.6, 3.2), Vec3::new(0.0, 0.0, 0.0)),
    );
    s.textures
        .push(Texture::from_fn("metal-rough", 128, 128, |x, y| {
            let metal = if (y / 32) % 2 == 0 { 255 } else { 0 };
            let rough = (40 + x * 215 / 127) as u8;
            [0, rough, metal, 255]
        }));
    s.meshes.push(uv_sphere(0.6, 64, 32));
    s.meshes.push(cuboid(Vec3::splat(0.9)));
    s.materials.push(Material {
        metallic_roughness_texture: Some(TextureRef::repeat(0)),
        ..pbr(Vec3::new(0.95, 0.7, 0.3), 1.0, 1.0)
    });
    s.instances.push(Instance::caster(
        0,
        0,
        Mat4::from_translation(Vec3::new(-0.7, 0.0, 0.0)),
    ));
    s.instances.push(Instance::caster(
        1,
        0,
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.6), Vec3::new(0.8, -0.1, 0.0)),
    ));
    backdrop(&mut s, -0.6, -1.5, 10.0);
    s.lights = vec![
        sun(Vec3::new(-0.3, -0.5, -1.0), Vec3::splat(3.0)),
        point(Vec3::new(1.0, 1.5, 2.0), 10.0, Vec3::new(12.0, 11.0, 10.0)),
        point(Vec3::new(-1.5, 0.5, 1.5), 10.0, Vec3::new(4.0, 5.0, 7.0)),
    ];
    s
}

/// A floor lamp: a pole, an open shade, an emissive bulb with a warm point light in it, and
/// four coloured point lights around, in front of the backdrop with a sign on it whose
/// emission comes from a texture.
fn lamp() -> Scene {
    let mut s = physical(
        "lamp",
        Camera::look_at(Vec3::new(0.0, 1.2, 2.8), Vec3::new(0.0, 0.95, 0.0)),
    );
    let pole = s.meshes.len();
    s.meshes.push(cylinder(0.03, 1.5, 24));
    let shade = s.meshes.len();
    s.meshes.push(cylinder(0.3, 0.35, 48));
    let bulb = s.meshes.len();
    s.meshes.push(uv_sphere(0.08, 32, 16));
    s.materials.push(pbr(Vec3::splat(0.6), 1.0, 0.35)); // brushed metal
    s.materials.push(Material {
        double_sided: true,
        ..pbr(Vec3::new(0.85, 0.8, 0.7), 0.0, 0.8) // fabric
    });
    s.materials.push(Material {
        emissive: Vec3::new(4.0, 3.4, 2.4),
        ..pbr(Vec3::ONE, 0.0, 0.5)
    });
    s.instances.push(Instance::caster(
        pole,
        0,
        Mat4::from_translation(Vec3::Y * 0.75),
    ));
    s.instances.push(Instance::caster(
        shade,
        1,
        Mat4::from_translation(Vec3::Y * 1.55),
    ));
    s.instances.push(Instance::caster(
        bulb,
        2,
        Mat4::from_translation(Vec3::Y * 1.45),
    ));
    // A glowing sign on the wall: emission from a texture (bars of three colours on black).
    s.textures.push(Texture::from_fn("sign", 64, 32, |x, y| {
        let on = (4..28).contains(&y) && x % 16 >= 3 && x % 16 < 13;
        match (on, x / 16 % 3) {
            (false, _) => [0, 0, 0, 255],
            (true, 0) => [255, 80, 40, 255],
            (true, 1) => [60, 255, 120, 255],
            (true, _) => [70, 120, 255, 255],
        }
    }));
    let sign = s.meshes.len();
    s.meshes.push(cuboid(Vec3::new(0.8, 0.4, 0.02)));
    let sign_material = s.materials.len();
    s.materials.push(Material {
        emissive: Vec3::splat(3.0),
        emissive_texture: Some(TextureRef::repeat(s.textures.len() - 1)),
        ..pbr(Vec3::splat(0.05), 0.0, 0.6)
    });
    s.instances.push(Instance::caster(
        sign,
        sign_material,
        Mat4::from_translation(Vec3::new(-0.8, 1.6, -1.15)),
    ));
    backdrop(&mut s, 0.0, -1.2, 8.0);
    s.lights = vec![
        point(Vec3::new(0.0, 1.45, 0.0), 6.0, Vec3::new(3.0, 2.6, 1.9)),
        point(Vec3::new(-1.3, 0.4, 0.6), 4.0, Vec3::new(1.5, 0.2, 0.2)),
        point(Vec3::new(1.3, 0.4, 0.6), 4.0, Vec3::new(0.2, 0.4, 1.6)),
        point(Vec3::new(-0.9, 2.0, -0.5), 4.0, Vec3::new(0.3, 1.2, 0.3)),
        point(Vec3::new(0.9, 2.0, 1.0), 5.0, Vec3::new(1.0, 0.9, 0.5)),
    ];
    s
}

/// `manyshadows render` of `file`: the RGBA pixels and the summary's exposure scale.
fn render_ours(file: &Path, out: &Path, extra: &[&str]) -> (Vec<u8>, f32) {
    let json = out.with_extension("json");
    let run = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .arg("render")
        .arg("--scene")
        .arg(file)
        .args(["--ground", "off", "--shadows", "off"])
        .args(extra)
        .args(["--width", &W.to_string(), "--height", &H.to_string()])
        .arg("--out")
        .arg(out)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "render {}: {}",
        file.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let look = &summary["look"];
    assert_eq!(
        (look["shading"].as_str(), look["tone_map"].as_str()),
        (Some("pbr"), Some("neutral")),
        "a glTF file is shaded with the glTF BRDF and PBR Neutral by default: {look}"
    );
    assert!(
        look["metered"].is_number(),
        "a glTF file's exposure is metered by default: {look}"
    );
    let exposure = look["exposure_scale"].as_f64().unwrap() as f32;
    (image::open(out).unwrap().to_rgba8().into_raw(), exposure)
}

/// three.js' frame of the model served at `url`, RGBA.
fn render_three(
    browser: &mut Browser,
    url: &str,
    exposure: f32,
    time: Option<f32>,
) -> (Vec<u8>, String) {
    let call = format!(
        "window.threejs.render({}, {W}, {H}, {exposure}, {}, {})",
        json!(url),
        json!(SKY),
        json!(time)
    );
    let r = browser.eval(&call, 300);
    let png = base64(r["png"].as_str().unwrap_or_else(|| panic!("{call}: {r}")));
    let img = image::load_from_memory(&png).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (W, H), "three.js' canvas size");
    (img.into_raw(), r["revision"].to_string())
}

fn save_rgba(path: &Path, rgba: &[u8]) {
    image::RgbaImage::from_raw(W, H, rgba.to_vec())
        .unwrap()
        .save(path)
        .unwrap();
}

/// The models to compare: the generated ones and any from `MANYSHADOWS_THREEJS_MODELS`
/// (loaded, defaults added, written again), as (name, glb path).
fn models(dir: &Path) -> Vec<(String, PathBuf)> {
    let mut scenes = vec![spheres(), textured_box(), metal_rough_map(), lamp()];
    if let Some(list) = std::env::var_os("MANYSHADOWS_THREEJS_MODELS") {
        for p in std::env::split_paths(&list.to_string_lossy().replace(',', ":")) {
            let loaded = manyshadows_scene::loaders::load_scene(&p)
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            let mut scene = loaded.scene;
            scene.name = p
                .file_stem()
                .map_or("model".into(), |s| s.to_string_lossy().into_owned());
            scenes.push(scene);
        }
    }
    scenes
        .into_iter()
        .map(|s| {
            let path = dir.join(format!("{}.glb", s.name));
            write_gltf(&s, &path).unwrap_or_else(|e| panic!("{}: {e}", s.name));
            (s.name.clone(), path)
        })
        .collect()
}

#[test]
#[ignore = "needs Chromium and three.js: run `cargo xtask test`, which installs them"]
fn gltf_models_render_as_three_js_renders_them() {
    let three = three_dir();
    let dir = tmp("threejs");
    let artifacts = repo().join("target/test-artifacts/threejs");
    std::fs::create_dir_all(&artifacts).unwrap();
    let models = models(&dir);
    let port = serve(
        repo().join("crates/cli/tests/threejs/index.html"),
        vec![("three", three), ("models", dir.clone())],
    );
    let mut browser = Browser::start(
        &tmp("threejs-chromium"),
        &["--enable-unsafe-swiftshader", "--use-angle=swiftshader"],
    );
    browser.open(
        &format!("http://127.0.0.1:{port}/"),
        "window.threejs !== undefined && window.threejs.ready === true",
    );
    let mut lines = vec![format!(
        "{:<16} {:>10} {:>10} {:>8}",
        "model", "mean FLIP", "exposure", "EV100"
    )];
    let mut failures = Vec::new();
    for (name, glb) in &models {
        let (ours, exposure) = render_ours(glb, &artifacts.join(format!("{name}-ours.png")), &[]);
        let url = format!("/models/{}", glb.file_name().unwrap().to_string_lossy());
        let (theirs, revision) = render_three(&mut browser, &url, exposure, None);
        save_rgba(&artifacts.join(format!("{name}-three.png")), &theirs);
        let flip = manyshadows_reference::flip_rgba8(&theirs, &ours, W, H).unwrap();
        image::RgbImage::from_raw(W, H, flip.error_map.clone())
            .unwrap()
            .save(artifacts.join(format!("{name}-flip.png")))
            .unwrap();
        // Side by side: ours, three.js, the ꟻLIP map.
        let mut side = image::RgbImage::new(W * 3, H);
        for (k, img) in [&ours, &theirs].into_iter().enumerate() {
            for (i, p) in img.chunks(4).enumerate() {
                let (x, y) = (i as u32 % W, i as u32 / W);
                side.put_pixel(x + k as u32 * W, y, image::Rgb([p[0], p[1], p[2]]));
            }
        }
        for (i, p) in flip.error_map.chunks(3).enumerate() {
            let (x, y) = (i as u32 % W, i as u32 / W);
            side.put_pixel(x + 2 * W, y, image::Rgb([p[0], p[1], p[2]]));
        }
        side.save(artifacts.join(format!("{name}-side.png")))
            .unwrap();
        let ev100 = (1.0 / (1.2 * exposure)).log2();
        lines.push(format!(
            "{name:<16} {:>10.4} {exposure:>10.5} {ev100:>8.2}   (three.js r{})",
            flip.mean,
            revision.trim_matches('"')
        ));
        let bound = MODEL_BOUNDS
            .iter()
            .find(|(m, _)| m == name)
            .map_or(MAX_MEAN_FLIP, |&(_, b)| b);
        if flip.mean.is_nan() || flip.mean > bound {
            failures.push(format!(
                "{name}: mean ꟻLIP {:.4} (bound {bound})",
                flip.mean
            ));
        }
        // Not a blank frame on either side: the generated models are lit.
        let generated =
            ["spheres", "textured-box", "metal-rough-map", "lamp"].contains(&name.as_str());
        for (who, img) in [("ours", &ours), ("three.js", &theirs)]
            .into_iter()
            .filter(|_| generated)
        {
            let lit = img
                .chunks(4)
                .filter(|p| p[..3].iter().any(|&c| c > 60))
                .count();
            assert!(
                lit > (W * H / 10) as usize,
                "{name}: {who} has only {lit} lit pixels"
            );
        }
    }
    let table = lines.join("\n");
    eprintln!("{table}");
    std::fs::write(artifacts.join("figures.txt"), format!("{table}\n")).unwrap();
    assert!(
        failures.is_empty(),
        "over their mean ꟻLIP bounds against three.js (the issue's {MAX_MEAN_FLIP}, tighter for \
         the generated models): {failures:?} (images in {})\n{table}",
        artifacts.display()
    );
}

/// Besides the bound on the whole frame (mean ꟻLIP at each time), one where things
/// move: the mean ꟻLIP over the pixels where three.js' own frames at the three times differ.
/// Measured (llvmpipe against SwiftShader): 0.0017–0.0151; our frame at rest against three.js
/// mid-way gives 0.22–0.38 there, so a pose missed or wrong fails it.
const MOVING_BOUND: f64 = 0.05;

/// glTF files that move (tests/common/animated.rs: a box sliding and turning, a node
/// animation; a tube skinned to two joints bending; a card curled by a morph target) render at
/// 0 s, mid-way and near the end as three.js' `AnimationMixer` poses them at those times,
/// shadows off in both: the same pose, skin and morph from the same file, read and evaluated
/// by each side on its own. Whole frames within the mean ꟻLIP 0.1 (measured 0.0228–
/// 0.0229), and the moving pixels within [`MOVING_BOUND`].
/// The glTF file `path` (its animations, skins and morph targets untouched) with the lights
/// and camera our loader gives it where it has none, written as `dir/<stem>-lit.glb`, so that
/// three.js sees what we light it with; and the length of its first animation in seconds.
fn with_our_lights(path: &Path, dir: &Path) -> (String, PathBuf, f32) {
    use manyshadows_scene::animation::Playing;
    let loaded = manyshadows_scene::loaders::load_scene(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let duration = loaded.scene.animations.duration(Playing::One(0));
    assert!(duration > 0.0, "{}: no animation to play", path.display());
    let stem = path
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().into_owned());
    // Our lights and camera, written by our writer (its light units), to be spliced in.
    let ours_path = dir.join(format!("{stem}-ours.gltf"));
    write_gltf(&loaded.scene, &ours_path).unwrap();
    let ours: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&ours_path).unwrap()).unwrap();
    let bytes = std::fs::read(path).unwrap();
    let (mut doc, bin) = if bytes.starts_with(b"glTF") {
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        let rest = &bytes[20 + json_len..];
        let bin = (rest.len() >= 8).then(|| {
            let n = u32::from_le_bytes(rest[0..4].try_into().unwrap()) as usize;
            rest[8..8 + n].to_vec()
        });
        (doc, bin)
    } else {
        (serde_json::from_slice(&bytes).unwrap(), None)
    };
    let has_lights = doc["extensions"]["KHR_lights_punctual"]["lights"]
        .as_array()
        .is_some_and(|l| !l.is_empty());
    let has_camera = doc["cameras"].as_array().is_some_and(|c| !c.is_empty());
    let first_node = doc["nodes"].as_array().map_or(0, Vec::len);
    let mut added = Vec::new();
    for node in ours["nodes"].as_array().unwrap() {
        let light = node["extensions"]["KHR_lights_punctual"].is_object();
        let camera = node["camera"].is_number();
        if (light && !has_lights) || (camera && !has_camera) {
            added.push(node.clone());
        }
    }
    if !has_lights {
        doc["extensions"]["KHR_lights_punctual"]["lights"] =
            ours["extensions"]["KHR_lights_punctual"]["lights"].clone();
        let used = doc["extensionsUsed"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        let mut used: Vec<serde_json::Value> = used;
        used.push(json!("KHR_lights_punctual"));
        doc["extensionsUsed"] = json!(used);
    }
    if !has_camera {
        doc["cameras"] = ours["cameras"].clone();
    }
    let scene = doc["scene"].as_u64().unwrap_or(0) as usize;
    for (k, node) in added.into_iter().enumerate() {
        doc["nodes"].as_array_mut().unwrap().push(node);
        doc["scenes"][scene]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(first_node + k));
    }
    let out = dir.join(format!("{stem}-lit.glb"));
    let mut json_bytes = serde_json::to_vec(&doc).unwrap();
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    let mut glb = Vec::new();
    let bin = bin.map(|mut b| {
        while b.len() % 4 != 0 {
            b.push(0);
        }
        b
    });
    let total = 12 + 8 + json_bytes.len() + bin.as_ref().map_or(0, |b| 8 + b.len());
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json_bytes);
    if let Some(b) = &bin {
        glb.extend_from_slice(&(b.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"BIN\0");
        glb.extend_from_slice(b);
    }
    std::fs::write(&out, glb).unwrap();
    (stem, out, duration)
}

#[test]
#[ignore = "needs Chromium and three.js: run `cargo xtask test`, which installs them"]
fn animated_files_render_as_three_js_plays_them() {
    let three = three_dir();
    let dir = tmp("threejs-animated");
    let artifacts = repo().join("target/test-artifacts/threejs");
    std::fs::create_dir_all(&artifacts).unwrap();
    let mut files = vec![
        (
            "slide".to_string(),
            common::animated::animated(&dir),
            [0.0f32, 0.5, 1.9],
            true,
        ),
        (
            "bend".to_string(),
            common::animated::bending(&dir),
            [0.0, 0.5, 1.9],
            true,
        ),
        (
            "curl".to_string(),
            common::animated::curling(&dir),
            [0.0, 0.5, 1.9],
            true,
        ),
    ];
    // Animated files of one's own (`MANYSHADOWS_THREEJS_ANIMATED=Fox.glb,...`), given our
    // loader's lights and camera where they have none: their first animation at its start,
    // middle and near its end, held to the whole frame's bound only.
    if let Some(list) = std::env::var_os("MANYSHADOWS_THREEJS_ANIMATED") {
        for p in std::env::split_paths(&list.to_string_lossy().replace(',', ":")) {
            let (name, lit, duration) = with_our_lights(&p, &dir);
            let times = [0.0, 0.5 * duration, 0.95 * duration];
            files.push((name, lit, times, false));
        }
    }
    let port = serve(
        repo().join("crates/cli/tests/threejs/index.html"),
        vec![("three", three), ("models", dir.clone())],
    );
    let mut browser = Browser::start(
        &tmp("threejs-animated-chromium"),
        &["--enable-unsafe-swiftshader", "--use-angle=swiftshader"],
    );
    browser.open(
        &format!("http://127.0.0.1:{port}/"),
        "window.threejs !== undefined && window.threejs.ready === true",
    );
    let mut lines = vec![format!(
        "{:<8} {:>6} {:>10} {:>14}",
        "file", "time", "mean FLIP", "moving pixels"
    )];
    let mut failures = Vec::new();
    for (name, file, times, generated) in &files {
        let generated = *generated;
        let url = format!("/models/{}", file.file_name().unwrap().to_string_lossy());
        let frames: Vec<(Vec<u8>, Vec<u8>)> = times
            .iter()
            .map(|t| {
                let out = artifacts.join(format!("{name}-{t}-ours.png"));
                let (ours, exposure) = render_ours(file, &out, &["--time", &t.to_string()]);
                let (theirs, _) = render_three(&mut browser, &url, exposure, Some(*t));
                save_rgba(&artifacts.join(format!("{name}-{t}-three.png")), &theirs);
                (ours, theirs)
            })
            .collect();
        // Where three.js' own frames differ from one time to another: what moved.
        let moving: Vec<bool> = (0..(W * H) as usize)
            .map(|i| {
                let px = |k: usize| &frames[k].1[4 * i..4 * i + 3];
                px(0) != px(1) || px(1) != px(2) || px(0) != px(2)
            })
            .collect();
        let region = moving.iter().filter(|&&m| m).count();
        assert!(region > 100, "{name}: three.js moved only {region} pixels");
        let over_moving = |reference: &[u8], test: &[u8]| {
            let flip = manyshadows_reference::flip_rgba8(reference, test, W, H).unwrap();
            let sum: f64 = flip
                .errors
                .iter()
                .zip(&moving)
                .filter(|(_, &m)| m)
                .map(|(&e, _)| e as f64)
                .sum();
            (flip.mean, sum / region as f64)
        };
        for (t, (ours, theirs)) in times.iter().zip(&frames) {
            let (mean, moved) = over_moving(theirs, ours);
            lines.push(format!("{name:<8} {t:>6.2} {mean:>10.4} {moved:>14.4}"));
            let moving_bound = if generated {
                MOVING_BOUND
            } else {
                f64::INFINITY
            };
            if mean.is_nan() || mean > MAX_MEAN_FLIP || moved.is_nan() || moved > moving_bound {
                failures.push(format!(
                    "{name} at {t} s: mean ꟻLIP {mean:.4} (bound {MAX_MEAN_FLIP}), over the \
                     {region} moving pixels {moved:.4} (bound {MOVING_BOUND})"
                ));
            }
        }
        // The pose matters: our frame at rest against three.js' mid-way, over the same pixels.
        let (_, crossed) = over_moving(&frames[1].1, &frames[0].0);
        lines.push(format!(
            "{name:<8} ours at 0 s against three.js at 0.5 s, moving pixels: {crossed:.4}"
        ));
        if generated && crossed <= MOVING_BOUND {
            failures.push(format!(
                "{name}: a frame at the wrong time passes ({crossed:.4})"
            ));
        }
    }
    let table = lines.join("\n");
    eprintln!("{table}");
    std::fs::write(artifacts.join("figures-animated.txt"), format!("{table}\n")).unwrap();
    assert!(
        failures.is_empty(),
        "against three.js' AnimationMixer: {failures:?} (images in {})\n{table}",
        artifacts.display()
    );
}
