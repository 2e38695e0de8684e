//! What the tests need beyond Rust, and how `cargo xtask test` gets it: Debian packages
//! (`apt-get` as root), Mesa 25 from Debian 12's backports, a rustup target,
//! `wasm-bindgen-cli` at `Cargo.lock`'s version, an npm tarball checked against the registry's
//! SHA-1; and the small commands it asks the system with.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::cargo;

/// A tool the tests need, how to tell it is there and how to get it.
pub(crate) struct Prerequisite {
    pub(crate) what: &'static str,
    /// Which tests need it (for messages).
    pub(crate) needed_by: &'static str,
    pub(crate) install: Install,
    /// Tests to skip (libtest `--skip` filters, matched exactly) when it is missing.
    pub(crate) skip: &'static [&'static str],
}

pub(crate) enum Install {
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

pub(crate) enum Outcome {
    Present,
    Installed,
    Missing(String),
}

/// Installs prerequisites, remembering what it learnt (root or not, apt updated).
pub(crate) struct Setup {
    root: PathBuf,
    no_install: bool,
    apt_updated: bool,
}

impl Setup {
    pub(crate) fn new(root: &Path, no_install: bool) -> Self {
        Self {
            root: root.to_path_buf(),
            no_install,
            apt_updated: false,
        }
    }

    pub(crate) fn ensure(&mut self, install: &Install) -> Outcome {
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
pub(crate) fn locked_version(root: &Path, crate_name: &str) -> Option<String> {
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

pub(crate) fn dpkg_installed(pkg: &str) -> bool {
    output("dpkg-query", &["-W", "-f=${Status}", pkg])
        .is_some_and(|s| s.contains("install ok installed"))
}

pub(crate) fn is_root() -> bool {
    output("id", &["-u"]).is_some_and(|s| s.trim() == "0")
}

pub(crate) fn on_path(tool: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(tool).is_file()))
}

/// A command's stdout when it runs and succeeds.
pub(crate) fn output(program: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(program).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Runs a set-up command with its output hidden unless it fails (then its last lines are the
/// error).
pub(crate) fn quiet(program: &str, args: &[&str], env: &[(&str, &str)]) -> Result<(), String> {
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
