//! `manyshadows view`: runs the window viewer, the separate `manyshadows-view` program.
//!
//! Why separate: its window and panel libraries (winit, egui and their font and Wayland/X11
//! stacks) were a large share of the compile work of a first `cargo run --release`
//! (docs/decisions.md, "The viewer, a program of its own"), for a command most runs never
//! use. So the default build leaves them out, and `manyshadows view` runs `manyshadows-view`
//! from beside its own executable; from the source tree it builds it first (once, with the
//! same profile), so the command works as before with no second install step.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};
use clap::Args;

/// Everything after `view`, passed to `manyshadows-view` as it is (`--help` included).
#[derive(Args, Debug, Clone)]
pub(crate) struct ViewerArgs {
    /// The viewer's options (`manyshadows view --help` lists them).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    args: Vec<OsString>,
}

/// The viewer's executable name on this platform.
fn exe_name() -> String {
    format!("manyshadows-view{}", std::env::consts::EXE_SUFFIX)
}

/// The workspace this binary was built from, if it is still there.
fn source_tree() -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent()?.parent()?;
    root.join("crates/viewer/Cargo.toml")
        .is_file()
        .then(|| root.to_path_buf())
}

pub(crate) fn run(args: &ViewerArgs) -> Result<()> {
    let me = std::env::current_exe().context("finding this program's path")?;
    let dir = me.parent().context("this program has no directory")?;
    let viewer = dir.join(exe_name());
    if !viewer.is_file() {
        let Some(root) = source_tree() else {
            bail!(
                "the viewer is a separate program, {}, and it is not beside {}: build it with \
                 `cargo build --release -p manyshadows-viewer` in the manyshadows source tree \
                 (or `cargo install --path crates/viewer`)",
                exe_name(),
                me.display()
            );
        };
        // The profile this binary was built with: target/<profile dir>/manyshadows, where the
        // dev profile's directory is `debug`.
        let profile = match dir.file_name().and_then(|p| p.to_str()) {
            Some("debug") => "dev",
            Some(p) => p,
            None => "release",
        };
        eprintln!(
            "building the viewer once (its window and panel libraries; a few minutes on 2 cores): \
             cargo build --profile {profile} -p manyshadows-viewer"
        );
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let status = Command::new(cargo)
            .current_dir(&root)
            .args(["build", "--profile", profile, "-p", "manyshadows-viewer"])
            .env("CARGO_TARGET_DIR", dir.parent().unwrap_or(dir))
            .status()
            .context("running cargo to build the viewer")?;
        if !status.success() || !viewer.is_file() {
            bail!(
                "building the viewer failed ({status}); build it by hand with \
                 `cargo build --release -p manyshadows-viewer`"
            );
        }
    }
    let status = Command::new(&viewer)
        .args(&args.args)
        .status()
        .with_context(|| format!("running {}", viewer.display()))?;
    if !status.success() {
        // The viewer printed its own error.
        std::process::exit(status.code().unwrap_or(1));
    }
    Ok(())
}
