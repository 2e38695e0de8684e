//! The window's test kit: an X server (Xvfb), the viewer run on it, screenshots (`xwd`) and
//! the frames `render` makes to hold them against.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub(crate) fn tmp(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("manyshadows-viewer-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Kills the child when dropped (a failing assertion must not leave an X server behind).
pub(crate) struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn require(tool: &str, package: &str) {
    let found = std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).any(|d| d.join(tool).is_file()))
        .unwrap_or(false);
    assert!(
        found,
        "the viewer test needs `{tool}`: install it with `apt-get install -y {package}`"
    );
}

/// Starts Xvfb on a display it picks itself (`-displayfd`: no race with other X servers or
/// parallel tests); returns it and the display name. Once in a full run the third viewer of
/// a test found no X server (cause not pinned down: a server writing its display number once
/// more after a reset was ruled out, it does not); so, defensively, `-noreset` keeps it as it
/// is between the test's viewers and its stdout is drained until it exits, never a closed
/// pipe to write into.
pub(crate) fn xvfb() -> (Killed, String) {
    require("Xvfb", "xvfb");
    require("xwd", "x11-apps");
    let mut child = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "1024x768x24",
            "-nolisten",
            "tcp",
            "-noreset",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start Xvfb");
    let stdout = child.stdout.take().unwrap();
    let server = Killed(child);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut reader = BufReader::new(stdout);
        let mut line = String::new();
        let _ = reader.read_line(&mut line);
        let _ = tx.send(line);
        // Keep the pipe open until the server exits.
        let _ = std::io::copy(&mut reader, &mut std::io::sink());
    });
    let line = rx
        .recv_timeout(Duration::from_secs(20))
        .expect("Xvfb did not report its display within 20 s");
    let n: u32 = line
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("Xvfb reported display '{line}'"));
    (server, format!(":{n}"))
}

/// The screen's top-left `w`×`h` pixels as RGB, from `xwd -root` (ZPixmap, 32 bits per
/// pixel, the depth-24 visual Xvfb gives).
fn screenshot(display: &str, (w, h): (u32, u32)) -> Vec<[u8; 3]> {
    let out = Command::new("xwd")
        .args(["-root", "-silent", "-display", display])
        .output()
        .expect("run xwd");
    assert!(out.status.success(), "xwd failed: {:?}", out);
    let d = out.stdout;
    let u = |i: usize| u32::from_be_bytes(d[4 * i..4 * i + 4].try_into().unwrap());
    let (header, width, bpp, bpl, byte_order, ncolors) = (
        u(0) as usize,
        u(4),
        u(11),
        u(12) as usize,
        u(7),
        u(19) as usize,
    );
    assert_eq!(bpp, 32, "xwd: {bpp} bits per pixel");
    assert!(width >= w);
    let base = header + ncolors * 12;
    let mut px = Vec::new();
    for y in 0..h as usize {
        for x in 0..w as usize {
            let o = base + y * bpl + 4 * x;
            let b: [u8; 4] = d[o..o + 4].try_into().unwrap();
            let v = if byte_order == 0 {
                u32::from_le_bytes(b)
            } else {
                u32::from_be_bytes(b)
            };
            px.push([(v >> 16) as u8, (v >> 8) as u8, v as u8]);
        }
    }
    px
}

/// Runs the viewer on `display` with `args` until it has presented `frames` frames, then
/// takes a screenshot of the top-left `size` pixels and closes it.
pub(crate) fn view(display: &str, args: &[&str], frames: u64, size: (u32, u32)) -> Vec<[u8; 3]> {
    let mut viewer = Killed(
        Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
            .args(args)
            .args(["--exit-after", "100000"])
            .env("DISPLAY", display)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start the viewer"),
    );
    let stdout = viewer.0.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let start = Instant::now();
    let mut shown = 0;
    while shown < frames {
        match lines.next() {
            Some(Ok(l)) if l.starts_with("presented frame ") => {
                // "presented frame N: K of V shadow views drawn"
                let rest = &l["presented frame ".len()..];
                shown = rest[..rest.find(':').unwrap_or(rest.len())]
                    .parse()
                    .unwrap();
            }
            Some(Ok(_)) => {}
            _ => {
                let _ = viewer.0.kill();
                let mut err = String::new();
                if let Some(mut e) = viewer.0.stderr.take() {
                    let _ = std::io::Read::read_to_string(&mut e, &mut err);
                }
                panic!("the viewer stopped before frame {frames}: {err}");
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "{frames} frames took over 300 s"
        );
    }
    screenshot(display, size)
}

pub(crate) fn render(dir: &Path, camera: &str, size: (u32, u32)) -> image::RgbImage {
    render_with(dir, "render.png", camera, size, &[])
}

/// `render` with `extra` flags, written to `name` in `dir`.
pub(crate) fn render_with(
    dir: &Path,
    name: &str,
    camera: &str,
    (w, h): (u32, u32),
    extra: &[&str],
) -> image::RgbImage {
    // `manyshadows render`, run in this process through the CLI's library (the same code as
    // the program).
    let png = dir.join(name);
    let (w, h, out) = (
        w.to_string(),
        h.to_string(),
        png.to_str().unwrap().to_string(),
    );
    let args = [
        &[
            "manyshadows",
            "render",
            "--scene",
            "cubes",
            "--camera",
            camera,
            "--width",
            &w,
            "--height",
            &h,
            "--out",
            &out,
        ][..],
        extra,
    ]
    .concat();
    manyshadows_cli::run(args.iter().map(std::ffi::OsString::from)).expect("manyshadows render");
    image::open(&png).unwrap().to_rgb8()
}

pub(crate) fn save(shot: &[[u8; 3]], (w, h): (u32, u32), name: &str) {
    let artifacts = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/test-artifacts");
    std::fs::create_dir_all(&artifacts).unwrap();
    let mut img = image::RgbImage::new(w, h);
    for (i, p) in shot.iter().enumerate() {
        img.put_pixel(i as u32 % w, i as u32 / w, image::Rgb(*p));
    }
    img.save(artifacts.join(name)).unwrap();
}

/// (K, V) of each "presented frame N: K of V shadow views drawn" line.
pub(crate) fn views_drawn(stdout: &str) -> Vec<(u64, u64)> {
    stdout
        .lines()
        .filter_map(|l| {
            let (_, rest) = l.split_once(": ")?;
            let mut w = rest.split_whitespace();
            let k = w.next()?.parse().ok()?;
            let v = w.nth(1)?.parse().ok()?;
            Some((k, v))
        })
        .collect()
}
