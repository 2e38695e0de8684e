//! `manyshadows view` in a real window: an X server (Xvfb) gives the CPU adapters a window
//! system; the viewer flies a scripted camera path, and a screenshot of the screen (`xwd`)
//! must show the frame `render` makes for the script's last camera. Needs the `xvfb` and
//! `x11-apps` packages (`.ci/run` installs them); without them the test fails and says so.

#[path = "../../cli/tests/common/animated.rs"]
#[allow(dead_code)]
mod animated;
mod window;

use std::process::Command;

use window::{render, render_with, save, tmp, view, views_drawn, xvfb};

const W: u32 = 320;
const H: u32 = 240;

#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn the_window_shows_the_frame_render_makes() {
    let (_server, display) = xvfb();
    let dir = tmp("script");
    // Three cameras flying in; the last one stays.
    let last = "2,3,7,0,0.5,0";
    std::fs::write(
        dir.join("path.txt"),
        format!(
            "# cubes fly-in\n0 4 9 0 1 0\n1 3.5 8 0 1 0\n{}\n",
            last.replace(',', " ")
        ),
    )
    .unwrap();
    // The script's last camera has been on screen for a few frames by frame 6.
    let shot = view(
        &display,
        &[
            "--scene",
            "cubes",
            "--width",
            &W.to_string(),
            "--height",
            &H.to_string(),
            "--script",
            dir.join("path.txt").to_str().unwrap(),
            "--hide-panel",
        ],
        6,
        (W, H),
    );

    let reference = render(&dir, last, (W, H));
    save(&shot, (W, H), "viewer-screenshot.png");
    let mean = shot
        .iter()
        .map(|p| p.iter().map(|&c| c as u64).sum::<u64>())
        .sum::<u64>() as f64
        / (3 * shot.len()) as f64;
    assert!(mean > 30.0, "the window is black (mean level {mean:.1})");
    // Measured: identical on lavapipe and llvmpipe (0 pixels off); a pixel may be 2 levels
    // off before it counts, and 0.5 % may differ (a display server that dithers or scales).
    let off = shot
        .iter()
        .zip(reference.pixels())
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b.0[c]) > 2))
        .count();
    eprintln!("window vs render: {off} of {} pixels differ", shot.len());
    assert!(
        off * 200 <= shot.len(),
        "the window shows a different frame: {off} pixels differ (screenshot in \
         target/test-artifacts/viewer-screenshot.png)"
    );
}

#[test]
fn the_viewer_without_a_display_says_what_to_do() {
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
        .args(["--scene", "cubes", "--exit-after", "1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("Xvfb"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // Bad arguments are refused before any window opens.
    for (args, needle) in [
        (&["--follow", "9"][..], "--follow 9: the scene has 3 lights"),
        (&["--show-visibility", "3"][..], "--show-visibility 3"),
        (
            &["--script", "no-such-script.txt"][..],
            "no-such-script.txt",
        ),
        (&["--width", "0"][..], "at least 1"),
        (&["--time", "1"][..], "--time: scene cubes has no animation"),
        (&["--speed", "-1"][..], "--speed -1"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
            .args(["--scene", "cubes"])
            .args(args)
            .env_remove("DISPLAY")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}

/// With the panel, the atlas picture and light 1's visibility: the panel covers its corner
/// (differs from the frame) and the frame between the windows is `render`'s.
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn the_panel_draws_over_the_frame() {
    let (_server, display) = xvfb();
    let dir = tmp("panel");
    let size = (960, 640);
    let camera = "2,3,7,0,0.5,0";
    let shot = view(
        &display,
        &[
            "--scene",
            "cubes",
            "--width",
            "960",
            "--height",
            "640",
            "--camera",
            camera,
            "--show-atlas",
            "--show-visibility",
            "1",
        ],
        3,
        size,
    );
    save(&shot, size, "viewer-panel.png");
    let reference = render(&dir, camera, size);
    let differs = |x0: u32, y0: u32, x1: u32, y1: u32| {
        let mut n = 0;
        for y in y0..y1 {
            for x in x0..x1 {
                let a = shot[(y * size.0 + x) as usize];
                let b = reference.get_pixel(x, y).0;
                n += usize::from((0..3).any(|c| a[c].abs_diff(b[c]) > 2));
            }
        }
        n as f64 / ((x1 - x0) * (y1 - y0)) as f64
    };
    // The panel's title bar and first rows (measured: the whole 200×60 corner differs).
    let panel = differs(16, 8, 216, 68);
    // Bottom middle, between the panel and the picture windows (measured: 0). Clear of the
    // panel's shadow: with the sampled-lights slider for map techniques the panel reaches
    // y 548 on GL (one more line there: no pipeline statistics), x 425.
    let frame = differs(450, 575, 600, 640);
    // The atlas and visibility windows anchored on the right (measured: all differ).
    let pictures = differs(720, 60, 940, 300).min(differs(720, 460, 940, 620));
    eprintln!("panel corner {panel:.3} differs, pictures {pictures:.3}, frame corner {frame:.3}");
    assert!(
        pictures > 0.5,
        "no atlas or visibility picture ({pictures:.3})"
    );
    assert!(
        panel > 0.5,
        "no panel drawn ({panel:.3} of its corner differs)"
    );
    assert!(
        frame < 0.005,
        "the frame under the panel is not render's ({frame:.3})"
    );
}

/// Caching is the default: with `--animate`, after the first frame only the maps that see the
/// moving caster or belong to the swaying light are redrawn, so every later frame draws some
/// views but not all; without `--animate` a still scene redraws none; with `--no-cache` every
/// frame draws every view.
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn animation_with_caching_redraws_only_what_moved() {
    let (_server, display) = xvfb();
    let drawn = |extra: &[&str]| -> Vec<(u64, u64)> {
        let out = Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
            .args(["--scene", "cubes", "--width", "160", "--height", "120"])
            .args(["--hide-panel", "--exit-after", "5"])
            .args(extra)
            .env("DISPLAY", &display)
            .output()
            .expect("run the viewer");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        views_drawn(&stdout)
    };
    let animated = drawn(&["--animate"]);
    let still = drawn(&[]);
    eprintln!("animated {animated:?}, still {still:?}");
    assert_eq!(animated.len(), 5, "{animated:?}");
    assert_eq!(
        animated[0].0, animated[0].1,
        "the first frame draws every view"
    );
    for &(k, v) in &animated[1..] {
        assert!(k > 0 && k < v, "animated frame drew {k} of {v} views");
    }
    assert_eq!(still.len(), 5, "{still:?}");
    assert!(
        still[1..].iter().all(|&(k, _)| k == 0),
        "a still scene redrew views: {still:?}"
    );
    let anew = drawn(&["--no-cache"]);
    assert_eq!(anew.len(), 5, "{anew:?}");
    assert!(
        anew.iter().all(|&(k, v)| k == v),
        "--no-cache kept views: {anew:?}"
    );
}

/// Virtual shadow maps have no atlas: the same window shows their page pool — pages in use
/// (grey and black) at the top of the picture, the rest of the pool unused (dark blue).
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn the_virtual_maps_page_pool_is_shown() {
    let (_server, display) = xvfb();
    let size = (960, 640);
    let shot = view(
        &display,
        &[
            "--scene",
            "cubes",
            "--technique",
            "virtual",
            "--width",
            "960",
            "--height",
            "640",
            "--show-atlas",
        ],
        3,
        size,
    );
    save(&shot, size, "viewer-page-pool.png");
    // The picture's window is anchored top right (measured: a 256² picture at x 619–875,
    // y 67–323 on Xvfb). Its lower part is the unused pool: dark blue (10, 12, 40).
    let px = |x: u32, y: u32| shot[(y * size.0 + x) as usize];
    let unused = (200..300)
        .flat_map(|y| (640..860).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let p = px(x, y);
            p[0].abs_diff(10) <= 2 && p[1].abs_diff(12) <= 2 && p[2].abs_diff(40) <= 2
        })
        .count();
    // Its first rows hold the pages in use: not all dark blue.
    let used = (70..78)
        .flat_map(|y| (630..860).map(move |x| (x, y)))
        .filter(|&(x, y)| px(x, y)[2] != 40)
        .count();
    eprintln!("page pool picture: {unused} unused-blue pixels below, {used} in the first rows");
    assert!(unused > 20_000, "no unused pool shown ({unused} of 22,000)");
    assert!(used > 500, "no pages in use shown ({used})");
}

/// A shadow budget in the viewer: no presented frame draws more views than the budget, and a
/// still scene is finished within ceil(views / budget) frames, after which nothing is drawn.
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn a_shadow_budget_caps_the_views_each_frame_draws() {
    let (_server, display) = xvfb();
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
        .args(["--scene", "cubes", "--width", "160", "--height", "120"])
        .args(["--shadow-budget", "3", "--hide-panel", "--exit-after", "12"])
        .env("DISPLAY", &display)
        .output()
        .expect("run the viewer");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let drawn = views_drawn(&stdout);
    eprintln!("{drawn:?}");
    assert_eq!(drawn.len(), 12, "{stdout}");
    let views = drawn[0].1;
    assert!(views > 3, "{drawn:?}");
    assert!(drawn.iter().all(|&(k, _)| k <= 3), "{drawn:?}");
    let total: u64 = drawn.iter().map(|&(k, _)| k).sum();
    assert_eq!(total, views, "every view drawn once, then none: {drawn:?}");
}

/// A technique whose frame would take minutes (irregular maps at 16,384 lights: every caster
/// triangle against each of some 36,000 light views: 9.2 G pairs) is refused at start with its estimate, as
/// `render` refuses it, instead of a window that freezes.
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn a_frame_of_minutes_is_refused_at_start() {
    let (_server, display) = xvfb();
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
        .args(["--lights", "16384", "--technique", "irregular"])
        .args(["--width", "160", "--height", "120", "--exit-after", "1"])
        .env("DISPLAY", &display)
        .output()
        .expect("run the viewer");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("technique irregular would take")
            && stderr.contains("G (caster triangle, view) pairs")
            && stderr.contains("--insist"),
        "{stderr}"
    );
}

/// Shadow rays sampled and denoised in the window as `render` does them: the cubes under 48
/// lights, one light traced per pixel. After 8 presented frames of a still camera the window
/// with `--denoise` must be far closer to every light traced (`render`) than the window
/// without it (measured on lavapipe: 0.99 against 14.50, RMSE of 8-bit channels), and so must
/// the window with `--reuse` (its lights reused across the frames, no filter: 5.96). Without ray
/// queries (OpenGL) the technique is refused naming the feature.
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn sampled_rays_are_denoised_in_the_window() {
    let (_server, display) = xvfb();
    let (w, h) = (W.to_string(), H.to_string());
    let base = [
        "--scene",
        "cubes",
        "--lights",
        "48",
        "--technique",
        "raytraced",
        "--light-samples",
        "1",
        "--width",
        w.as_str(),
        "--height",
        h.as_str(),
        "--hide-panel",
    ];
    let ctx = manyshadows::GpuContext::new(&Default::default()).expect("adapter");
    let unmet = manyshadows::Technique::RAYTRACED.info().unmet(&ctx);
    let rays_here = unmet.is_empty();
    if let Some(need) = unmet.first() {
        manyshadows_testkit::refused(&need.name(), "the viewer's ray-traced shadows");
    }
    if !rays_here {
        let out = Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
            .args(base)
            .args(["--exit-after", "1"])
            .env("DISPLAY", &display)
            .output()
            .expect("run the viewer");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains("EXPERIMENTAL_RAY_QUERY"),
            "{stderr}"
        );
        return;
    }
    let mut with = base.to_vec();
    with.push("--denoise");
    let denoised = view(&display, &with, 8, (W, H));
    let mut reusing = base.to_vec();
    reusing.push("--reuse");
    let reused = view(&display, &reusing, 8, (W, H));
    let plain = view(&display, &base, 2, (W, H));
    let dir = tmp("denoise");
    let png = dir.join("exact.png");
    let args = [
        "manyshadows",
        "render",
        "--scene",
        "cubes",
        "--lights",
        "48",
        "--technique",
        "raytraced",
        "--width",
        &w,
        "--height",
        &h,
        "--out",
        png.to_str().unwrap(),
    ];
    manyshadows_cli::run(args.map(std::ffi::OsString::from)).expect("manyshadows render");
    let exact = image::open(&png).unwrap().to_rgb8();
    let rmse = |shot: &[[u8; 3]]| {
        let sum: f64 = shot
            .iter()
            .zip(exact.pixels())
            .flat_map(|(a, b)| (0..3).map(move |c| (f64::from(a[c]) - f64::from(b.0[c])).powi(2)))
            .sum();
        (sum / (3 * shot.len()) as f64).sqrt()
    };
    let (d, r, p) = (rmse(&denoised), rmse(&reused), rmse(&plain));
    save(&denoised, (W, H), "viewer-denoised.png");
    eprintln!("window against every light traced: denoised {d:.2}, reused {r:.2}, plain {p:.2}");
    assert!(d < 0.5 * p, "denoised {d:.2} against plain {p:.2}");
    assert!(r < 0.5 * p, "reused {r:.2} against plain {p:.2}");
}

/// `--stereo` in the window: the two eyes side by side, the frame `render --stereo` makes
/// (each eye half the window).
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn the_window_shows_both_stereo_eyes_as_render_does() {
    let (_server, display) = xvfb();
    let dir = tmp("stereo");
    let camera = "2,3,7,0,0.5,0";
    let shot = view(
        &display,
        &[
            "--scene",
            "cubes",
            "--width",
            &W.to_string(),
            "--height",
            &H.to_string(),
            "--camera",
            camera,
            "--stereo",
            "0.6",
            "--hide-panel",
        ],
        3,
        (W, H),
    );
    let png = dir.join("stereo.png");
    let args = [
        "manyshadows",
        "render",
        "--scene",
        "cubes",
        "--camera",
        camera,
        "--width",
        &(W / 2).to_string(),
        "--height",
        &H.to_string(),
        "--stereo",
        "0.6",
        "--out",
        png.to_str().unwrap(),
    ];
    manyshadows_cli::run(args.map(std::ffi::OsString::from)).expect("manyshadows render");
    let reference = image::open(&png).unwrap().to_rgb8();
    assert_eq!(reference.dimensions(), (W, H));
    save(&shot, (W, H), "viewer-stereo.png");
    let off = shot
        .iter()
        .zip(reference.pixels())
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b.0[c]) > 2))
        .count();
    // The halves differ (two eyes, not one picture twice).
    let half = W as usize / 2;
    let eyes_differ = (0..H as usize)
        .flat_map(|y| (0..half).map(move |x| (x, y)))
        .filter(|&(x, y)| shot[y * W as usize + x] != shot[y * W as usize + x + half])
        .count();
    eprintln!(
        "stereo window vs render: {off} of {} pixels differ; the eyes differ in {eyes_differ}",
        shot.len()
    );
    assert!(
        eyes_differ > 500,
        "the two eyes look the same ({eyes_differ} pixels differ)"
    );
    assert!(
        off * 200 <= shot.len(),
        "the stereo window shows a different frame: {off} pixels differ (screenshot in \
         target/test-artifacts/viewer-stereo.png)"
    );
}

/// `--probes` and `--probe-passes` in the window: the atrium with two reflection probes whose
/// faces are drawn GPU-driven shows the frame `render` makes with the same flags, and its
/// reflective floor differs from the frame without probes.
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn the_window_shows_the_probes_as_render_does() {
    let (_server, display) = xvfb();
    let dir = tmp("probes");
    let probes = ["--probes", "2", "--probe-passes", "gpu-driven"];
    let common = [
        "--scene",
        "atrium",
        "--lights",
        "8",
        "--width",
        &W.to_string(),
        "--height",
        &H.to_string(),
    ];
    let shot = view(
        &display,
        &[&common[..], &probes[..], &["--hide-panel"]].concat(),
        3,
        (W, H),
    );
    save(&shot, (W, H), "viewer-probes.png");
    let rendered = |name: &str, extra: &[&str]| {
        let png = dir.join(name);
        let args: Vec<&str> = [
            &["manyshadows", "render"][..],
            &common[..],
            extra,
            &["--out", png.to_str().unwrap()],
        ]
        .concat();
        manyshadows_cli::run(args.into_iter().map(std::ffi::OsString::from))
            .expect("manyshadows render");
        image::open(&png).unwrap().to_rgb8()
    };
    let off = |image: &image::RgbImage| {
        shot.iter()
            .zip(image.pixels())
            .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b.0[c]) > 2))
            .count()
    };
    let with = off(&rendered("with.png", &probes));
    let without = off(&rendered("without.png", &["--probes", "0"]));
    eprintln!(
        "probes window vs render: {with} of {} pixels differ; vs render without probes: \
         {without}",
        shot.len()
    );
    assert!(
        with * 200 <= shot.len(),
        "the window's probes differ from render's: {with} pixels"
    );
    assert!(
        without > 100,
        "the probes change nothing in the window ({without} pixels)"
    );
}

/// `--soft-taps` and `--max-penumbra` in the window: the cubes under sized lights with 2 + 2
/// taps and penumbrae of at most 8 texels show the frame `render` makes with the same flags,
/// which differs from the default taps' frame (so the flags reach the renderer).
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn the_window_takes_the_soft_shadow_taps_as_render_does() {
    let (_server, display) = xvfb();
    let dir = tmp("soft-taps");
    let camera = "2,3,7,0,0.5,0";
    let soft = [
        "--light-size",
        "0.4",
        "--soft-taps",
        "2,2",
        "--max-penumbra",
        "8",
    ];
    let (w, h) = (W.to_string(), H.to_string());
    let shot = view(
        &display,
        &[
            &[
                "--scene",
                "cubes",
                "--width",
                &w,
                "--height",
                &h,
                "--camera",
                camera,
                "--hide-panel",
            ][..],
            &soft[..],
        ]
        .concat(),
        3,
        (W, H),
    );
    let reference = render_with(&dir, "soft.png", camera, (W, H), &soft);
    let default_taps = render_with(
        &dir,
        "default-taps.png",
        camera,
        (W, H),
        &["--light-size", "0.4"],
    );
    save(&shot, (W, H), "viewer-soft-taps.png");
    let differing = |img: &image::RgbImage| {
        shot.iter()
            .zip(img.pixels())
            .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b.0[c]) > 2))
            .count()
    };
    let (off, from_default) = (differing(&reference), differing(&default_taps));
    eprintln!(
        "soft taps window vs render: {off} of {} pixels differ; vs the default taps' frame \
         {from_default}",
        shot.len()
    );
    assert!(
        from_default > 200,
        "the taps change too few pixels to tell: {from_default}"
    );
    assert!(
        off * 200 <= shot.len(),
        "the window shows a different frame: {off} pixels differ (screenshot in \
         target/test-artifacts/viewer-soft-taps.png)"
    );
}

/// A glTF file's animation in the window: paused at 0.5 s, the window shows `render --time
/// 0.5`'s frame; playing, each frame's line says a later time and the shadow views that see
/// the box are redrawn (some, not all, after the first frame).
#[test]
#[ignore = "needs Xvfb and xwd: run `cargo xtask test`, which installs them"]
fn the_window_plays_a_files_animation() {
    let (_server, display) = xvfb();
    let dir = tmp("animation");
    let file = animated::animated(&dir);
    let file = file.to_str().unwrap();
    let size = (W, H);
    let (w, h) = (W.to_string(), H.to_string());
    let frame = ["--scene", file, "--width", &w, "--height", &h];
    let shot = view(
        &display,
        &[&frame[..], &["--time", "0.5", "--paused", "--hide-panel"]].concat(),
        3,
        size,
    );
    save(&shot, size, "viewer-animation.png");
    let png = dir.join("render.png");
    manyshadows_cli::run(
        [
            &["manyshadows", "render"][..],
            &frame[..],
            &["--time", "0.5", "--out", png.to_str().unwrap()],
        ]
        .concat()
        .iter()
        .map(std::ffi::OsString::from),
    )
    .expect("manyshadows render");
    let reference = image::open(&png).unwrap().to_rgb8();
    let off = shot
        .iter()
        .zip(reference.pixels())
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b.0[c]) > 2))
        .count();
    eprintln!(
        "paused window vs render --time 0.5: {off} of {} pixels differ",
        shot.len()
    );
    assert!(
        off * 200 <= shot.len(),
        "{off} pixels differ (target/test-artifacts/viewer-animation.png)"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_manyshadows-view"))
        .args(frame)
        .args(["--hide-panel", "--exit-after", "5", "--speed", "0.5"])
        .env("DISPLAY", &display)
        .output()
        .expect("run the viewer");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let times: Vec<f32> = stdout
        .lines()
        .filter_map(|l| {
            l.split_once("; animation at ")?
                .1
                .strip_suffix(" s")?
                .parse()
                .ok()
        })
        .collect();
    let drawn = views_drawn(&stdout);
    eprintln!("times {times:?}, views drawn {drawn:?}");
    assert_eq!(times.len(), 5, "{stdout}");
    assert!(
        times.windows(2).all(|w| w[1] > w[0]),
        "time does not run: {times:?}"
    );
    for &(k, v) in &drawn[1..] {
        assert!(
            k > 0 && k < v,
            "a moving box redraws some views, not all: {drawn:?}"
        );
    }
}
