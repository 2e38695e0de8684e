//! `cargo xtask test`: the project's one test command on a fresh machine.
//!
//! It checks what the tests need beyond Rust itself — Vulkan on the CPU (Mesa's lavapipe), an
//! X server and screenshot tool for the viewer's tests, Chromium, the wasm32 target and
//! `wasm-bindgen-cli` at the version `Cargo.lock` pins for the web page's test — installs
//! what is missing where it can (`apt-get` as root, `rustup`, `cargo install`) and says
//! exactly what it could not. Then it runs the whole suite once per GPU backend
//! (`WGPU_BACKEND=vulkan`, then `gl`) with `--no-fail-fast`, the tests that need those tools
//! included (`--include-ignored`; plain `cargo test` reports them as ignored, with the
//! reason), and ends with one summary: passed, failed, ignored per backend, and every test
//! skipped by name because a tool could not be had.
//!
//! Why a Rust program and not a shell script: it is what `cargo` runs on every platform the
//! project builds on, it reads `Cargo.lock` for the wasm-bindgen version itself, and it can
//! count test results instead of scrolling them past. It has no dependencies, so it builds in
//! seconds before anything else.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

const USAGE: &str = "\
cargo xtask test [--no-install] [--backend vulkan|gl|both] [-- <extra test arguments>]

  Installs what the tests need (as root: apt-get; rustup; cargo install), then runs
  `cargo test --release --workspace --no-fail-fast -- --include-ignored` once with
  WGPU_BACKEND=vulkan and once with WGPU_BACKEND=gl, and prints one summary.

  --no-install    only check: tests whose tools are missing are skipped by name
  --backend B     run only Vulkan or only OpenGL (default: both; Vulkan is skipped, and
                  said so, where lavapipe cannot be had)";

/// A tool the tests need, how to tell it is there and how to get it.
struct Prerequisite {
    what: &'static str,
    /// Which tests need it (for messages).
    needed_by: &'static str,
    install: Install,
    /// Tests to skip (libtest `--skip` filters, matched exactly) when it is missing.
    skip: &'static [&'static str],
}

enum Install {
    /// Debian packages; present when every one is installed.
    Apt(&'static [&'static str]),
    /// Mesa's Vulkan (lavapipe) and OpenGL (llvmpipe) drivers at this major version or newer
    /// (25: ray queries, mesh shaders, multiview in lavapipe); on Debian 12 (bookworm) from
    /// its backports suite, which is added to apt's sources when missing. When only an older
    /// Mesa can be had it is installed instead and said: the ray-traced technique is then
    /// refused by name and its tests check that refusal.
    Mesa(u32),
    /// A rustup target.
    RustupTarget(&'static str),
    /// `wasm-bindgen-cli` at the version of the `wasm-bindgen` crate in Cargo.lock.
    WasmBindgen,
    /// An npm package's published tarball, checked against the registry's SHA-1 and unpacked
    /// into `target/npm/NAME-VERSION/package` (with curl, tar and sha1sum: no Node needed).
    NpmTarball {
        name: &'static str,
        version: &'static str,
        sha1: &'static str,
    },
}

const VIEWER_TESTS: &[&str] = &[
    "the_window_shows_the_frame_render_makes",
    "the_panel_draws_over_the_frame",
    "animation_with_caching_redraws_only_what_moved",
    "the_virtual_maps_page_pool_is_shown",
    "a_shadow_budget_caps_the_views_each_frame_draws",
    "a_frame_of_minutes_is_refused_at_start",
    "sampled_rays_are_denoised_in_the_window",
    "the_window_shows_both_stereo_eyes_as_render_does",
    "the_window_shows_the_probes_as_render_does",
    "the_window_takes_the_soft_shadow_taps_as_render_does",
];
const WEB_TESTS: &[&str] = &["the_page_renders_the_native_frame_and_its_controls_work"];
const THREE_TESTS: &[&str] = &["gltf_models_render_as_three_js_renders_them"];

/// three.js, the independent renderer the glTF look is checked against (its version is
/// also in crates/cli/tests/threejs.rs).
const THREE: Install = Install::NpmTarball {
    name: "three",
    version: "0.187.0",
    sha1: "face29ee2de9bcc31a1b573a76f224e35e0b2894",
};

fn prerequisites() -> Vec<Prerequisite> {
    vec![
        Prerequisite {
            what: "Vulkan and OpenGL on the CPU (Mesa 25 lavapipe and llvmpipe, ray queries)",
            needed_by: "the Vulkan run of the suite and its ray-traced tests",
            install: Install::Mesa(25),
            skip: &[],
        },
        Prerequisite {
            what: "a C++ compiler (g++)",
            needed_by: "the build: the reference crate's FLIP (nv-flip compiles NVIDIA's C++)",
            install: Install::Apt(&["g++"]),
            skip: &[],
        },
        Prerequisite {
            what: "an X server and screenshots (Xvfb, xwd, X client libraries)",
            needed_by: "the viewer's window tests",
            install: Install::Apt(&[
                "xvfb",
                "x11-apps",
                "libxkbcommon-x11-0",
                "libx11-xcb1",
                "libxcursor1",
                "libxrandr2",
                "libxi6",
            ]),
            skip: VIEWER_TESTS,
        },
        Prerequisite {
            what: "Chromium",
            needed_by: "the web page's test",
            install: Install::Apt(&["chromium"]),
            skip: WEB_TESTS,
        },
        Prerequisite {
            what: "Chromium (WebGL through SwiftShader), curl",
            needed_by: "the three.js comparison",
            install: Install::Apt(&["chromium", "curl", "ca-certificates"]),
            skip: THREE_TESTS,
        },
        Prerequisite {
            what: "three.js 0.187.0 (npm tarball into target/npm)",
            needed_by: "the three.js comparison",
            install: THREE,
            skip: THREE_TESTS,
        },
        Prerequisite {
            what: "the wasm32-unknown-unknown target",
            needed_by: "the web page's test",
            install: Install::RustupTarget("wasm32-unknown-unknown"),
            skip: WEB_TESTS,
        },
        Prerequisite {
            what: "wasm-bindgen-cli",
            needed_by: "the web page's test",
            install: Install::WasmBindgen,
            skip: WEB_TESTS,
        },
    ]
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (ours, extra) = match args.iter().position(|a| a == "--") {
        Some(i) => (&args[..i], args[i + 1..].to_vec()),
        None => (&args[..], Vec::new()),
    };
    let mut no_install = false;
    let mut backends = vec!["vulkan", "gl"];
    let mut it = ours.iter();
    match it.next().map(String::as_str) {
        Some("test") => {}
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        other => {
            eprintln!(
                "unknown task {}\n\n{USAGE}",
                other.map_or("(none)".into(), |o| format!("'{o}'"))
            );
            return ExitCode::from(2);
        }
    }
    while let Some(a) = it.next() {
        match a.as_str() {
            "--no-install" => no_install = true,
            "--backend" => match it.next().map(String::as_str) {
                Some("vulkan") => backends = vec!["vulkan"],
                Some("gl") => backends = vec!["gl"],
                Some("both") => {}
                other => {
                    eprintln!("--backend takes vulkan, gl or both, not {other:?}\n\n{USAGE}");
                    return ExitCode::from(2);
                }
            },
            "-h" | "--help" => {
                println!("{USAGE}");
                return ExitCode::SUCCESS;
            }
            other => {
                eprintln!("unknown option '{other}'\n\n{USAGE}");
                return ExitCode::from(2);
            }
        }
    }
    let root = workspace_root();
    let started = std::time::Instant::now();

    // 1. What the tests need.
    let mut setup = Setup::new(&root, no_install);
    let mut report = Vec::new();
    let mut skip: Vec<&str> = Vec::new();
    let mut lavapipe = true;
    for p in prerequisites() {
        let outcome = setup.ensure(&p.install);
        let line = match &outcome {
            Outcome::Present => format!("  ok       {}", p.what),
            Outcome::Installed => format!("  installed {}", p.what),
            Outcome::Missing(why) => {
                skip.extend(p.skip);
                if matches!(p.install, Install::Mesa(_)) && !dpkg_installed("mesa-vulkan-drivers") {
                    lavapipe = false;
                }
                format!("  MISSING  {} ({why}); skipped: {}", p.what, p.needed_by)
            }
        };
        println!("{line}");
        report.push(line);
    }
    skip.sort_unstable();
    skip.dedup();

    // 2. Quiet runs: libwayland prints an error per GL adapter probe without a runtime
    // directory; a private one silences it.
    let xdg = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|p| p.is_absolute())
        .unwrap_or_else(|| {
            let dir = std::env::temp_dir().join(format!("manyshadows-xdg-{}", std::process::id()));
            let _ = std::fs::create_dir_all(&dir);
            dir
        });

    // 3. The suite, once per backend.
    let mut results: BTreeMap<&str, Counts> = BTreeMap::new();
    for backend in backends {
        if backend == "vulkan" && !lavapipe {
            println!("\n=== not running the suite on Vulkan: no Vulkan driver (see above) ===");
            continue;
        }
        println!("\n=== cargo test --release --workspace with WGPU_BACKEND={backend} ===");
        let refusals = root.join(format!("target/xtask/refusals-{backend}.tsv"));
        let _ = std::fs::create_dir_all(refusals.parent().expect("in target/xtask"));
        let _ = std::fs::remove_file(&refusals);
        let mut cmd = test_command(backend, &skip, &extra);
        cmd.current_dir(&root)
            .env("XDG_RUNTIME_DIR", &xdg)
            .env(manyshadows_testkit::REFUSALS_VAR, &refusals);
        let mut counts = run_counting(cmd);
        counts.refusals = std::fs::read_to_string(&refusals)
            .map(|t| manyshadows_testkit::read_refusals(&t))
            .unwrap_or_default();
        results.insert(backend, counts);
    }

    // 4. One summary.
    let minutes = started.elapsed().as_secs_f64() / 60.0;
    println!("\n=== summary ({minutes:.1} min) ===");
    for line in &report {
        println!("{line}");
    }
    let mut ok = !results.is_empty();
    for (backend, c) in &results {
        println!(
            "  {backend:6}  {} passed, {} failed, {} ignored{}",
            c.passed,
            c.failed,
            c.ignored,
            if c.exit_ok {
                ""
            } else {
                " (cargo test failed)"
            }
        );
        for f in &c.failures {
            println!("          FAILED {f}");
        }
        if c.refusals.is_empty() {
            println!("          no test checked a refusal instead of running");
        } else {
            println!(
                "          {} tests checked a refusal instead of running (this backend lacks \
                 what they need):",
                c.refusals.len()
            );
            for (test, need, _) in &c.refusals {
                println!("            {test} (no {need})");
            }
        }
        ok &= c.failed == 0 && c.exit_ok;
    }
    for name in &skip {
        println!("  skipped by name: {name}");
    }
    if results.is_empty() {
        println!("  no backend ran");
    }
    if ok {
        println!("  result: every test that ran passed");
        ExitCode::SUCCESS
    } else {
        println!("  result: FAILED");
        ExitCode::FAILURE
    }
}

fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

/// The workspace root: the directory above this crate.
fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

enum Outcome {
    Present,
    Installed,
    Missing(String),
}

/// Installs prerequisites, remembering what it learnt (root or not, apt updated).
struct Setup {
    root: PathBuf,
    no_install: bool,
    apt_updated: bool,
}

impl Setup {
    fn new(root: &Path, no_install: bool) -> Self {
        Self {
            root: root.to_path_buf(),
            no_install,
            apt_updated: false,
        }
    }

    fn ensure(&mut self, install: &Install) -> Outcome {
        match install {
            Install::Apt(pkgs) => {
                let missing: Vec<&str> = pkgs
                    .iter()
                    .copied()
                    .filter(|p| !dpkg_installed(p))
                    .collect();
                if missing.is_empty() {
                    return Outcome::Present;
                }
                if self.no_install {
                    return Outcome::Missing(format!(
                        "not installed: {}; --no-install",
                        missing.join(" ")
                    ));
                }
                if !is_root() {
                    return Outcome::Missing(format!(
                        "not installed: {}; run as root, or `sudo apt-get install -y {}`",
                        missing.join(" "),
                        missing.join(" ")
                    ));
                }
                if !on_path("apt-get") {
                    return Outcome::Missing(format!(
                        "not installed: {}; this machine has no apt-get",
                        missing.join(" ")
                    ));
                }
                if !self.apt_updated {
                    self.apt_updated = true;
                    if let Err(e) = quiet("apt-get", &["update"], &[]) {
                        return Outcome::Missing(format!("apt-get update failed: {e}"));
                    }
                }
                let mut args = vec!["install", "-y"];
                args.extend(&missing);
                match quiet("apt-get", &args, &[("DEBIAN_FRONTEND", "noninteractive")]) {
                    Ok(()) if missing.iter().all(|p| dpkg_installed(p)) => Outcome::Installed,
                    Ok(()) => Outcome::Missing("apt-get ran but the packages are not there".into()),
                    Err(e) => Outcome::Missing(format!("apt-get install failed: {e}")),
                }
            }
            Install::Mesa(major) => self.mesa(*major),
            Install::RustupTarget(target) => {
                let installed = output("rustup", &["target", "list", "--installed"])
                    .is_some_and(|o| o.lines().any(|l| l.trim() == *target));
                if installed {
                    return Outcome::Present;
                }
                if self.no_install {
                    return Outcome::Missing(format!("`rustup target add {target}`; --no-install"));
                }
                match quiet("rustup", &["target", "add", target], &[]) {
                    Ok(()) => Outcome::Installed,
                    Err(e) => Outcome::Missing(format!("`rustup target add {target}` failed: {e}")),
                }
            }
            Install::NpmTarball {
                name,
                version,
                sha1,
            } => self.npm_tarball(name, version, sha1),
            Install::WasmBindgen => {
                let Some(version) = locked_version(&self.root, "wasm-bindgen") else {
                    return Outcome::Missing("no wasm-bindgen in Cargo.lock".into());
                };
                let want = format!("wasm-bindgen {version}");
                let have =
                    || output("wasm-bindgen", &["--version"]).is_some_and(|o| o.trim() == want);
                if have() {
                    return Outcome::Present;
                }
                if self.no_install {
                    return Outcome::Missing(format!(
                        "`cargo install wasm-bindgen-cli --version {version}`; --no-install"
                    ));
                }
                println!(
                    "  installing wasm-bindgen-cli {version} (cargo install: a few minutes) ..."
                );
                match quiet(
                    &cargo(),
                    &["install", "wasm-bindgen-cli", "--version", &version],
                    &[],
                ) {
                    Ok(()) if have() => Outcome::Installed,
                    Ok(()) => Outcome::Missing(format!(
                        "installed, but `wasm-bindgen --version` is not {version}: is ~/.cargo/bin on PATH?"
                    )),
                    Err(e) => Outcome::Missing(format!("cargo install failed: {e}")),
                }
            }
        }
    }
}

impl Setup {
    /// See [`Install::NpmTarball`].
    fn npm_tarball(&self, name: &str, version: &str, sha1: &str) -> Outcome {
        let dir = self.root.join(format!("target/npm/{name}-{version}"));
        if dir.join("package/package.json").is_file() {
            return Outcome::Present;
        }
        let url = format!("https://registry.npmjs.org/{name}/-/{name}-{version}.tgz");
        if self.no_install {
            return Outcome::Missing(format!("not in {}; --no-install", dir.display()));
        }
        if !on_path("curl") || !on_path("tar") || !on_path("sha1sum") {
            return Outcome::Missing("needs curl, tar and sha1sum".into());
        }
        let _ = std::fs::create_dir_all(&dir);
        let tgz = dir.join("package.tgz");
        let tgz_s = tgz.to_string_lossy().into_owned();
        if let Err(e) = quiet("curl", &["-fsSL", "--retry", "3", "-o", &tgz_s, &url], &[]) {
            return Outcome::Missing(format!("downloading {url} failed: {e}"));
        }
        let got = output("sha1sum", &[&tgz_s]).unwrap_or_default();
        if got.split_whitespace().next() != Some(sha1) {
            let _ = std::fs::remove_file(&tgz);
            return Outcome::Missing(format!(
                "{url} has SHA-1 {}, not the registry's {sha1}",
                got.split_whitespace().next().unwrap_or("?")
            ));
        }
        let dir_s = dir.to_string_lossy().into_owned();
        match quiet("tar", &["xzf", &tgz_s, "-C", &dir_s], &[]) {
            Ok(()) if dir.join("package/package.json").is_file() => {
                let _ = std::fs::remove_file(&tgz);
                Outcome::Installed
            }
            Ok(()) => Outcome::Missing(format!("{url} has no package/package.json")),
            Err(e) => Outcome::Missing(format!("unpacking {url} failed: {e}")),
        }
    }
}

/// Mesa's driver packages the suite uses (Vulkan lavapipe, OpenGL llvmpipe through EGL/GLX).
const MESA_PACKAGES: &[&str] = &[
    "mesa-vulkan-drivers",
    "libgl1-mesa-dri",
    "libegl-mesa0",
    "libglx-mesa0",
    "libgbm1",
];

/// The major version of an installed Debian package (`25` of `25.0.7-2~bpo12+1`).
fn installed_major(pkg: &str) -> Option<u32> {
    if !dpkg_installed(pkg) {
        return None;
    }
    let v = output("dpkg-query", &["-W", "-f=${Version}", pkg])?;
    let v = v.split_once(':').map_or(v.as_str(), |(_, v)| v);
    v.split('.').next()?.trim().parse().ok()
}

impl Setup {
    /// Mesa at `major` or newer; see [`Install::Mesa`].
    fn mesa(&mut self, major: u32) -> Outcome {
        let have = || {
            ["mesa-vulkan-drivers", "libgl1-mesa-dri"]
                .iter()
                .map(|p| installed_major(p))
                .min()
                .flatten()
        };
        if have().is_some_and(|m| m >= major) {
            return Outcome::Present;
        }
        let now = match have() {
            Some(m) => format!("Mesa {m} is installed"),
            None => "Mesa's drivers are not installed".into(),
        };
        if self.no_install {
            return Outcome::Missing(format!("{now}; --no-install"));
        }
        if !is_root() || !on_path("apt-get") {
            return Outcome::Missing(format!(
                "{now}; run as root on Debian/Ubuntu, or install Mesa {major}+ yourself \
                 (Debian 12: the bookworm-backports suite)"
            ));
        }
        // Debian 12 has Mesa 25 in its backports suite only.
        let codename = std::fs::read_to_string("/etc/os-release")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find_map(|l| l.strip_prefix("VERSION_CODENAME=").map(str::to_string))
            })
            .unwrap_or_default();
        let mut suite = None;
        if codename == "bookworm" {
            let list = Path::new("/etc/apt/sources.list.d/bookworm-backports.list");
            let known = std::fs::read_dir("/etc/apt/sources.list.d")
                .into_iter()
                .flatten()
                .flatten()
                .any(|e| {
                    std::fs::read_to_string(e.path())
                        .is_ok_and(|s| s.contains("bookworm-backports"))
                })
                || std::fs::read_to_string("/etc/apt/sources.list")
                    .is_ok_and(|s| s.contains("bookworm-backports"));
            if !known {
                if let Err(e) = std::fs::write(
                    list,
                    "deb http://deb.debian.org/debian bookworm-backports main\n",
                ) {
                    return Outcome::Missing(format!("{now}; cannot add bookworm-backports: {e}"));
                }
                self.apt_updated = false;
            }
            suite = Some("bookworm-backports");
        }
        if !self.apt_updated {
            self.apt_updated = true;
            if let Err(e) = quiet("apt-get", &["update"], &[]) {
                return Outcome::Missing(format!("{now}; apt-get update failed: {e}"));
            }
        }
        let mut args = vec!["install", "-y"];
        if let Some(s) = suite {
            args.extend(["-t", s]);
        }
        args.extend(MESA_PACKAGES);
        let env = [("DEBIAN_FRONTEND", "noninteractive")];
        if let Err(e) = quiet("apt-get", &args, &env) {
            // The backports may be unreachable: the distribution's own Mesa still runs the
            // suite (without ray queries).
            let mut plain = vec!["install", "-y"];
            plain.extend(MESA_PACKAGES);
            let _ = quiet("apt-get", &plain, &env);
            return Outcome::Missing(format!(
                "apt-get could not install Mesa {major}+ ({e}); {}",
                match have() {
                    Some(m) => format!("Mesa {m} installed instead: no ray queries"),
                    None => "no Mesa driver installed".into(),
                }
            ));
        }
        match have() {
            Some(m) if m >= major => Outcome::Installed,
            Some(m) => Outcome::Missing(format!(
                "apt-get installed Mesa {m}, older than {major}: no ray queries"
            )),
            None => Outcome::Missing("apt-get ran but Mesa's drivers are not there".into()),
        }
    }
}

/// The version of `crate_name` in the workspace's Cargo.lock.
fn locked_version(root: &Path, crate_name: &str) -> Option<String> {
    let lock = std::fs::read_to_string(root.join("Cargo.lock")).ok()?;
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line.trim() == format!("name = \"{crate_name}\"") {
            let v = lines.next()?.trim();
            return v
                .strip_prefix("version = \"")
                .and_then(|v| v.strip_suffix('"'))
                .map(str::to_string);
        }
    }
    None
}

fn dpkg_installed(pkg: &str) -> bool {
    output("dpkg-query", &["-W", "-f=${Status}", pkg])
        .is_some_and(|s| s.contains("install ok installed"))
}

fn is_root() -> bool {
    output("id", &["-u"]).is_some_and(|s| s.trim() == "0")
}

fn on_path(tool: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(tool).is_file()))
}

/// A command's stdout when it runs and succeeds.
fn output(program: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(program).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Runs a set-up command with its output hidden unless it fails (then its last lines are the
/// error).
fn quiet(program: &str, args: &[&str], env: &[(&str, &str)]) -> Result<(), String> {
    let out = Command::new(program)
        .args(args)
        .envs(env.iter().copied())
        .output()
        .map_err(|e| format!("cannot run {program}: {e}"))?;
    if out.status.success() {
        return Ok(());
    }
    let err = String::from_utf8_lossy(&out.stderr);
    let tail: Vec<&str> = err.lines().rev().take(5).collect();
    Err(tail.into_iter().rev().collect::<Vec<_>>().join(" / "))
}

/// What each backend of the run must offer, by the names wgpu gives them (read by the tests
/// through `manyshadows_testkit`): a test that would only check a refusal for one of them
/// fails instead. The Vulkan run is on Mesa 25's lavapipe (installed above: ray queries,
/// multiview with six views per pass, clip distances, indirect execution); the OpenGL run on
/// llvmpipe's GL, whose wgpu device has clip distances and indirect execution but neither
/// ray queries nor multiview.
fn expected_features(backend: &str) -> &'static [&'static str] {
    match backend {
        "vulkan" => &[
            "EXPERIMENTAL_RAY_QUERY",
            "MULTIVIEW",
            "CLIP_DISTANCES",
            "INDIRECT_EXECUTION",
        ],
        "gl" => &["CLIP_DISTANCES", "INDIRECT_EXECUTION"],
        _ => &[],
    }
}

/// The suite's command on `backend`: every test, the ignored ones included, but those in
/// `skip` (libtest takes `--skip` once per name and `--exact` once: a repeated `--exact` is
/// refused, and every test binary would fail to start), then `extra`.
fn test_command(backend: &str, skip: &[&str], extra: &[String]) -> Command {
    let mut cmd = Command::new(cargo());
    cmd.args(["test", "--release", "--workspace", "--no-fail-fast", "--"])
        .arg("--include-ignored")
        .env("WGPU_BACKEND", backend)
        .env(
            manyshadows_testkit::EXPECT_VAR,
            expected_features(backend).join(","),
        );
    for name in skip {
        cmd.args(["--skip", name]);
    }
    if !skip.is_empty() {
        cmd.arg("--exact");
    }
    cmd.args(extra);
    cmd
}

/// Test counts of one run.
#[derive(Default)]
struct Counts {
    passed: u64,
    failed: u64,
    ignored: u64,
    failures: Vec<String>,
    exit_ok: bool,
    /// Tests that checked a refusal instead of running: (test, requirement, message).
    refusals: Vec<(String, String, String)>,
}

/// Runs `cmd`, passing its output through, and adds up libtest's result lines.
fn run_counting(mut cmd: Command) -> Counts {
    let mut c = Counts::default();
    cmd.stdout(Stdio::piped());
    let mut child = match cmd.spawn() {
        Ok(child) => child,
        Err(e) => {
            println!("cannot run cargo: {e}");
            return c;
        }
    };
    let stdout = child.stdout.take().expect("piped");
    for line in BufReader::new(stdout).lines().map_while(Result::ok) {
        println!("{line}");
        if let Some(rest) = line.strip_prefix("test result: ") {
            let number = |key: &str| {
                rest.split(';')
                    .find_map(|part| part.trim().strip_suffix(key))
                    .and_then(|n| n.trim().rsplit(' ').next()?.parse::<u64>().ok())
                    .unwrap_or(0)
            };
            c.passed += number(" passed");
            c.failed += number(" failed");
            c.ignored += number(" ignored");
        } else if let Some(name) = line
            .strip_prefix("test ")
            .and_then(|l| l.strip_suffix(" ... FAILED"))
        {
            c.failures.push(name.to_string());
        }
    }
    c.exit_ok = child.wait().is_ok_and(|s| s.success());
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_locked_wasm_bindgen_version() {
        let v = locked_version(&workspace_root(), "wasm-bindgen").expect("in Cargo.lock");
        assert!(v.starts_with("0.2."), "{v}");
        assert_eq!(
            locked_version(&workspace_root(), "no-such-crate-here"),
            None
        );
    }

    /// The `#[test]` functions of a test file: (name, its attributes, its body up to the next
    /// test).
    fn tests_of(text: &str) -> Vec<(String, String, String)> {
        let starts: Vec<usize> = text.match_indices("#[test]").map(|(i, _)| i).collect();
        starts
            .iter()
            .enumerate()
            .map(|(k, &at)| {
                let end = starts.get(k + 1).copied().unwrap_or(text.len());
                let chunk = &text[at..end];
                let fn_at = chunk.find("fn ").expect("a test function");
                let name: String = chunk[fn_at + 3..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                (name, chunk[..fn_at].to_string(), chunk[fn_at..].to_string())
            })
            .collect()
    }

    #[test]
    fn every_test_that_needs_a_tool_is_ignored_and_listed_and_every_listed_test_does() {
        // Both ways: a name xtask skips must be a real test marked #[ignore = "..."] (or a
        // renamed test would run without its tools, or never be skipped), and a test that
        // starts what a tool gives (Xvfb, Chromium) must be ignored by plain `cargo test` and
        // listed here (or it would fail wherever the tool is missing instead of being skipped
        // by name).
        let root = workspace_root();
        for (file, names, needs_tool) in [
            ("crates/viewer/tests/viewer.rs", VIEWER_TESTS, "xvfb()"),
            ("crates/cli/tests/web.rs", WEB_TESTS, "Browser::start("),
            (
                "crates/cli/tests/threejs.rs",
                THREE_TESTS,
                "Browser::start(",
            ),
        ] {
            let text = std::fs::read_to_string(root.join(file)).unwrap();
            let tests = tests_of(&text);
            for name in names {
                let (_, attrs, _) = tests
                    .iter()
                    .find(|(n, _, _)| n == name)
                    .unwrap_or_else(|| panic!("{file} has no test {name}"));
                assert!(
                    attrs.contains("#[ignore = \""),
                    "{file}: {name} must be #[ignore = \"needs ...\"]"
                );
            }
            let mut using = 0;
            for (name, attrs, body) in &tests {
                if !body.contains(needs_tool) {
                    continue;
                }
                using += 1;
                assert!(
                    attrs.contains("#[ignore = \"") && names.contains(&name.as_str()),
                    "{file}: {name} calls {needs_tool}: it must be #[ignore = \"needs ...\"] and \
                     listed for xtask to skip by name where the tool is missing"
                );
            }
            assert!(
                using > 0,
                "{file}: no test calls {needs_tool} (is the marker stale?)"
            );
        }
    }

    #[test]
    fn the_test_command_skips_by_exact_name_with_one_exact_flag() {
        let args = |cmd: &Command| -> Vec<String> {
            cmd.get_args()
                .map(|a| a.to_string_lossy().into_owned())
                .collect()
        };
        let env = |cmd: &Command, key: &str| {
            cmd.get_envs()
                .find(|(k, _)| *k == key)
                .and_then(|(_, v)| v)
                .map(|v| v.to_string_lossy().into_owned())
        };
        let skip = ["a_test", "another_test", "a_third"];
        let extra = vec!["--test-threads".to_string(), "2".to_string()];
        let cmd = test_command("vulkan", &skip, &extra);
        let a = args(&cmd);
        // libtest refuses a flag given twice ("Option 'exact' given more than once").
        assert_eq!(a.iter().filter(|x| *x == "--exact").count(), 1, "{a:?}");
        for name in skip {
            assert!(
                a.windows(2).any(|w| w[0] == "--skip" && w[1] == name),
                "{name} not skipped: {a:?}"
            );
        }
        let sep = a.iter().position(|x| x == "--").expect("--");
        assert!(a[sep + 1..].contains(&"--include-ignored".to_string()));
        assert_eq!(&a[a.len() - 2..], &extra[..], "extra arguments last");
        assert_eq!(env(&cmd, "WGPU_BACKEND").as_deref(), Some("vulkan"));
        let expect = env(&cmd, manyshadows_testkit::EXPECT_VAR).expect("expectations");
        assert!(expect.contains("EXPERIMENTAL_RAY_QUERY"), "{expect}");
        assert!(expect.contains("MULTIVIEW"), "{expect}");
        let gl = test_command("gl", &[], &[]);
        assert!(
            !args(&gl).contains(&"--exact".to_string()),
            "nothing to skip"
        );
        let expect = env(&gl, manyshadows_testkit::EXPECT_VAR).expect("expectations");
        assert!(
            !expect.contains("RAY_QUERY"),
            "llvmpipe GL has no ray queries: {expect}"
        );
    }
}
