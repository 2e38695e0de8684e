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

use common::{base64, on_path, repo, serve, tmp, Browser};
use serde_json::json;

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
    let png = dir.join(format!("{name}.png"));
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args([
            "render",
            "--width",
            &W.to_string(),
            "--height",
            &H.to_string(),
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
    let mut browser = Browser::start(&chromium_dir, &[]);
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
