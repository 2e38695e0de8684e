//! `cargo xtask web`: builds the web page (the renderer for wasm32 and its bindings, into
//! web/pkg, with what that needs installed first) and serves web/ on a local port. The built
//! page is a static folder: web/index.html and web/pkg/ are all a static host needs.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use crate::setup::{Install, Outcome, Setup};

/// Builds the page and serves it on `127.0.0.1:port` until interrupted.
pub(crate) fn build_and_serve(root: &Path, port: u16, no_install: bool) -> ExitCode {
    let mut setup = Setup::new(root, no_install);
    for (what, install) in [
        (
            "the wasm32-unknown-unknown target",
            Install::RustupTarget("wasm32-unknown-unknown"),
        ),
        ("wasm-bindgen-cli", Install::WasmBindgen),
    ] {
        match setup.ensure(&install) {
            Outcome::Present => println!("  ok       {what}"),
            Outcome::Installed => println!("  installed {what}"),
            Outcome::Missing(why) => {
                eprintln!("cannot build the page: {what} is missing ({why})");
                return ExitCode::FAILURE;
            }
        }
    }
    // Its own target directory, as the page's test uses: the wasm build does not evict the
    // native one.
    let status = Command::new("bash")
        .arg(root.join("web/build.sh"))
        .arg(root.join("web/pkg"))
        .current_dir(root)
        .env("CARGO_TARGET_DIR", root.join("target/web"))
        .status();
    if !matches!(status, Ok(s) if s.success()) {
        eprintln!("web/build.sh failed (see above)");
        return ExitCode::FAILURE;
    }
    let listener = match TcpListener::bind(("127.0.0.1", port)) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("cannot serve on 127.0.0.1:{port}: {e} (another port: --port N)");
            return ExitCode::FAILURE;
        }
    };
    let web = root.join("web");
    println!(
        "\nserving {} at http://127.0.0.1:{port}/ (Ctrl-C stops it)\n\
         open it in a browser with WebGPU (Chrome, Edge; Firefox 141+; Safari 26+) and drop a \
         model on the page; files put in web/ open with ?model=NAME",
        web.display()
    );
    for stream in listener.incoming().flatten() {
        let web = web.clone();
        std::thread::spawn(move || answer(stream, &web));
    }
    ExitCode::SUCCESS
}

/// Answers one GET with a file under `web` (`/` is index.html); nothing outside it.
fn answer(mut stream: TcpStream, web: &Path) {
    let mut line = String::new();
    if BufReader::new(&stream).read_line(&mut line).is_err() {
        return;
    }
    let path = line.split_whitespace().nth(1).unwrap_or("/");
    let path = path.split(['?', '#']).next().unwrap_or("/");
    let file: Option<PathBuf> = if path == "/" {
        Some(web.join("index.html"))
    } else {
        let rel = percent_decoded(path.trim_start_matches('/'));
        rel.filter(|r| !r.split('/').any(|c| c == ".." || c.is_empty()))
            .map(|r| web.join(r))
    };
    let body = file.as_ref().and_then(|f| std::fs::read(f).ok());
    let reply = match (&file, body) {
        (Some(f), Some(body)) => {
            let mut head = format!(
                "HTTP/1.1 200 OK\r\nContent-Type: {}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
                content_type(f),
                body.len()
            )
            .into_bytes();
            head.extend_from_slice(&body);
            head
        }
        _ => b"HTTP/1.1 404 Not Found\r\nContent-Length: 9\r\nConnection: close\r\n\r\nnot found"
            .to_vec(),
    };
    let _ = stream.write_all(&reply);
}

fn percent_decoded(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

fn content_type(f: &Path) -> &'static str {
    match f
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .as_deref()
    {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript",
        Some("wasm") => "application/wasm",
        Some("json" | "gltf") => "application/json",
        Some("png") => "image/png",
        Some("jpg" | "jpeg") => "image/jpeg",
        _ => "application/octet-stream",
    }
}
