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

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

const W: u32 = 480;
const H: u32 = 270;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("manyshadows-web-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn on_path(tool: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|p| {
        std::env::split_paths(&p)
            .map(|d| d.join(tool))
            .find(|f| f.is_file())
    })
}

/// Chromium: `$MANYSHADOWS_CHROMIUM`, else `chromium` or `chromium-browser` on the PATH.
fn chromium() -> PathBuf {
    if let Some(p) = std::env::var_os("MANYSHADOWS_CHROMIUM") {
        return p.into();
    }
    ["chromium", "chromium-browser"]
        .iter()
        .find_map(|t| on_path(t))
        .expect("the web page test needs Chromium: install it with `apt-get install -y chromium`")
}

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

/// Serves `web/` (and the built module under `/pkg/`) on a free local port.
fn serve(pkg: PathBuf) -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let web = repo().join("web");
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let (web, pkg) = (web.clone(), pkg.clone());
            std::thread::spawn(move || answer(stream, &web, &pkg));
        }
    });
    port
}

fn answer(mut stream: TcpStream, web: &Path, pkg: &Path) {
    let mut line = String::new();
    if BufReader::new(&stream).read_line(&mut line).is_err() {
        return;
    }
    let path = line.split_whitespace().nth(1).unwrap_or("/");
    let path = path.split('?').next().unwrap_or("/");
    let file = match path {
        "/" => Some(web.join("index.html")),
        p if p.starts_with("/pkg/") && !p.contains("..") => Some(pkg.join(&p[5..])),
        _ => None,
    };
    let (status, kind, body) = match file.and_then(|f| Some((std::fs::read(&f).ok()?, f))) {
        Some((body, f)) => {
            let kind = match f.extension().and_then(|e| e.to_str()) {
                Some("html") => "text/html; charset=utf-8",
                Some("js") => "text/javascript",
                Some("wasm") => "application/wasm",
                _ => "application/octet-stream",
            };
            ("200 OK", kind, body)
        }
        None => ("404 Not Found", "text/plain", b"not found".to_vec()),
    };
    let _ = write!(
        stream,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
        body.len()
    );
    let _ = stream.write_all(&body);
}

/// Headless Chromium driven over the DevTools protocol on a pipe (fds 3 and 4, mapped by the
/// shell onto the child's stdin and stdout).
struct Browser {
    child: Child,
    to: ChildStdin,
    from: Receiver<Value>,
    next_id: u64,
    session: String,
    /// Console lines and exceptions of the page, for failure messages.
    log: Vec<String>,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Browser {
    fn start(dir: &Path) -> Browser {
        let exe = chromium();
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(r#"exec "$0" "$@" 3<&0 4>&1 </dev/null >/dev/null"#)
            .arg(&exe)
            .args([
                "--headless=new",
                "--no-sandbox",
                "--enable-unsafe-webgpu",
                // The same software adapter everywhere (it would take a Vulkan driver if it
                // found one it likes, and give other pixels).
                "--use-webgpu-adapter=swiftshader",
                "--remote-debugging-pipe",
                "--no-first-run",
                "--disable-extensions",
                "--window-size=1000,700",
                "--hide-scrollbars",
            ])
            .arg(format!("--user-data-dir={}", dir.join("profile").display()))
            .arg("about:blank")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(std::fs::File::create(dir.join("chromium.log")).unwrap())
            .spawn()
            .unwrap_or_else(|e| panic!("start {}: {e}", exe.display()));
        let to = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, from) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(stdout);
            let mut buf = Vec::new();
            while let Ok(n) = reader.read_until(0, &mut buf) {
                if n == 0 {
                    break;
                }
                buf.pop_if(|b| *b == 0);
                if let Ok(v) = serde_json::from_slice::<Value>(&buf) {
                    if tx.send(v).is_err() {
                        break;
                    }
                }
                buf.clear();
            }
        });
        let mut b = Browser {
            child,
            to,
            from,
            next_id: 0,
            session: String::new(),
            log: Vec::new(),
        };
        let targets = b.call("Target.getTargets", json!({}), 60);
        let page = targets["targetInfos"]
            .as_array()
            .and_then(|t| t.iter().find(|t| t["type"] == "page"))
            .unwrap_or_else(|| panic!("Chromium shows no page: {targets}"))["targetId"]
            .clone();
        let attached = b.call(
            "Target.attachToTarget",
            json!({"targetId": page, "flatten": true}),
            30,
        );
        b.session = attached["sessionId"].as_str().unwrap().to_string();
        b.call("Runtime.enable", json!({}), 30);
        b.call("Page.enable", json!({}), 30);
        b
    }

    /// Sends a command (to the page once attached) and waits up to `secs` for its answer.
    fn call(&mut self, method: &str, params: Value, secs: u64) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if !self.session.is_empty() {
            msg["sessionId"] = json!(self.session);
        }
        let mut bytes = serde_json::to_vec(&msg).unwrap();
        bytes.push(0);
        self.to
            .write_all(&bytes)
            .and_then(|_| self.to.flush())
            .unwrap_or_else(|e| panic!("Chromium closed its pipe: {e}"));
        let deadline = Instant::now() + Duration::from_secs(secs);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.from.recv_timeout(left) {
                Ok(v) if v["id"] == id => {
                    if let Some(e) = v.get("error") {
                        panic!("{method}: {e}\npage log:\n{}", self.log.join("\n"));
                    }
                    return v["result"].clone();
                }
                Ok(v) => self.note(&v),
                Err(RecvTimeoutError::Timeout) => panic!(
                    "{method}: no answer from Chromium within {secs} s\npage log:\n{}",
                    self.log.join("\n")
                ),
                Err(RecvTimeoutError::Disconnected) => {
                    panic!("Chromium exited\npage log:\n{}", self.log.join("\n"))
                }
            }
        }
    }

    fn note(&mut self, v: &Value) {
        match v["method"].as_str() {
            Some("Runtime.consoleAPICalled") => {
                let args: Vec<String> = v["params"]["args"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|a| a["value"].to_string())
                    .collect();
                self.log.push(format!("console: {}", args.join(" ")));
            }
            Some("Runtime.exceptionThrown") => self
                .log
                .push(format!("exception: {}", v["params"]["exceptionDetails"])),
            _ => {}
        }
    }

    /// Evaluates `expr` in the page, awaiting a promise, and returns its value.
    fn eval(&mut self, expr: &str, secs: u64) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expr, "awaitPromise": true, "returnByValue": true}),
            secs,
        );
        if let Some(e) = r.get("exceptionDetails") {
            panic!("{expr}: {e}\npage log:\n{}", self.log.join("\n"));
        }
        r["result"]["value"].clone()
    }

    /// Opens `url` and waits for the page's script to have started.
    fn open(&mut self, url: &str) {
        // The old page's handle must not answer for the new one.
        self.eval("delete window.manyshadows", 30);
        self.call("Page.navigate", json!({"url": url}), 30);
        let start = Instant::now();
        while self.eval("typeof window.manyshadows", 30) != "object" {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "the page's script did not start within 60 s\npage log:\n{}",
                self.log.join("\n")
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// The last frame the page computed, RGBA.
    fn frame(&mut self) -> Vec<u8> {
        let b64 = self.eval("window.manyshadows.frameBase64()", 60);
        base64(b64.as_str().expect("frameBase64 returns a string"))
    }
}

/// Standard base64 (the DevTools protocol's screenshots and the page's pixels).
fn base64(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {}", c as char),
    };
    let bytes: Vec<u8> = s.bytes().filter(|&c| c != b'=').collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= (val(c) as u32) << (18 - 6 * i);
        }
        out.extend_from_slice(&acc.to_be_bytes()[1..chunk.len()]);
    }
    out
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
    let port = serve(pkg.clone());
    let mut browser = Browser::start(&chromium_dir);
    let dir = tmp("native");

    // The atrium's 32 lights with the compute rasterizer, as `render` makes it. (The other
    // techniques rasterize with the browser's fixed-function pipeline, and SwiftShader puts
    // extra depth into point lights' cube faces; see README "In a web page".)
    browser.open(&format!(
        "http://127.0.0.1:{port}/?w={W}&h={H}&technique=compute"
    ));
    let status = browser.eval("window.manyshadows.ready", 900);
    let info = browser.eval("window.manyshadows.info()", 10);
    eprintln!("page: {status}\n{}", info.as_str().unwrap_or(""));
    assert!(
        !status.as_str().unwrap_or("").starts_with("not applied"),
        "the page failed: {status}\npage log:\n{}",
        browser.log.join("\n")
    );
    let first = browser.frame();
    let native = render_native(
        &dir,
        "atrium",
        &["--scene", "atrium", "--technique", "compute"],
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
        browser.frame() == first,
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
    assert!(browser.frame() == first, "{set} changed the frame");

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
    let cubes = browser.frame();
    let native = render_native(&dir, "cubes", &["--scene", "cubes", "--pcf", "3x3"]);
    let off = differing(&cubes, &native);
    eprintln!("page vs render (cubes, traditional, PCF 3x3): {off} pixels differ");
    // Measured: 93 against lavapipe and llvmpipe; bound 200.
    assert!(off <= 200, "{off} pixels differ");

    // The orbit slider moves only the camera; back at 0° the frame is the same again.
    browser.eval("window.manyshadows.set({orbit: '40'})", 600);
    let turned = browser.frame();
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
        browser.frame() == cubes,
        "orbit back to 0° gives another frame"
    );

    // Bad sizes in the URL: the page says why instead of rendering.
    for (query, needle) in [
        ("w=abc", "width 'abc' is not a whole number"),
        ("w=320&h=5000", "height 5000 must be between 1 and 2048"),
    ] {
        browser.open(&format!("http://127.0.0.1:{port}/?{query}"));
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
