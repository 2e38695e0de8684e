//! What the browser tests share: headless Chromium driven over the DevTools protocol on a
//! pipe, a small file server, temporary folders, base64.

#![allow(dead_code)]

pub mod animated;
pub mod models;

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("manyshadows-web-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn on_path(tool: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|p| {
        std::env::split_paths(&p)
            .map(|d| d.join(tool))
            .find(|f| f.is_file())
    })
}

/// Chromium: `$MANYSHADOWS_CHROMIUM`, else `chromium` or `chromium-browser` on the PATH.
pub fn chromium() -> PathBuf {
    if let Some(p) = std::env::var_os("MANYSHADOWS_CHROMIUM") {
        return p.into();
    }
    ["chromium", "chromium-browser"]
        .iter()
        .find_map(|t| on_path(t))
        .expect("the web page test needs Chromium: install it with `apt-get install -y chromium`")
}

/// Serves files on a free local port: `/` is `index` and `/PREFIX/...` the file under the
/// folder mounted at `PREFIX` (paths with `..` are refused).
pub fn serve(index: PathBuf, mounts: Vec<(&'static str, PathBuf)>) -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let (index, mounts) = (index.clone(), mounts.clone());
            std::thread::spawn(move || answer(stream, &index, &mounts));
        }
    });
    port
}

fn answer(mut stream: TcpStream, index: &Path, mounts: &[(&'static str, PathBuf)]) {
    let mut line = String::new();
    if BufReader::new(&stream).read_line(&mut line).is_err() {
        return;
    }
    let path = line.split_whitespace().nth(1).unwrap_or("/");
    let path = path.split('?').next().unwrap_or("/");
    let file = if path == "/" {
        Some(index.to_path_buf())
    } else if path.contains("..") {
        None
    } else {
        mounts.iter().find_map(|(prefix, dir)| {
            let rest = path
                .strip_prefix('/')?
                .strip_prefix(prefix)?
                .strip_prefix('/')?;
            Some(dir.join(rest))
        })
    };
    let (status, kind, body) = match file.and_then(|f| Some((std::fs::read(&f).ok()?, f))) {
        Some((body, f)) => {
            let kind = match f.extension().and_then(|e| e.to_str()) {
                Some("html") => "text/html; charset=utf-8",
                Some("js") => "text/javascript",
                Some("wasm") => "application/wasm",
                Some("glb") => "model/gltf-binary",
                Some("gltf") | Some("json") => "application/json",
                Some("png") => "image/png",
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
pub struct Browser {
    child: Child,
    to: ChildStdin,
    from: Receiver<Value>,
    next_id: u64,
    session: String,
    /// Console lines and exceptions of the page, for failure messages.
    pub log: Vec<String>,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Browser {
    /// Starts Chromium with its profile in `dir` and `extra` flags.
    pub fn start(dir: &Path, extra: &[&str]) -> Browser {
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
            .args(extra)
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
    pub fn call(&mut self, method: &str, params: Value, secs: u64) -> Value {
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
    pub fn eval(&mut self, expr: &str, secs: u64) -> Value {
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

    /// Opens `url` and waits until `ready` (a JavaScript expression) is true in the page.
    pub fn open(&mut self, url: &str, ready: &str) {
        self.call("Page.navigate", json!({"url": url}), 30);
        let start = Instant::now();
        while self.eval(ready, 30) != json!(true) {
            assert!(
                start.elapsed() < Duration::from_secs(120),
                "the page did not get ready ({ready}) within 120 s\npage log:\n{}",
                self.log.join("\n")
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

/// Standard base64 (the DevTools protocol's screenshots and the page's pixels).
pub fn base64(s: &str) -> Vec<u8> {
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

/// Standard base64 with padding (files handed to a page): the inverse of [`base64`].
pub fn encode_base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let n = (chunk[0] as u32) << 16
            | (*chunk.get(1).unwrap_or(&0) as u32) << 8
            | *chunk.get(2).unwrap_or(&0) as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}
