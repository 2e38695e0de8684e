//! `manyshadows`: render scenes lit by many shadow-casting lights to PNG, score and benchmark
//! shadow techniques, and describe the GPU.
//!
//! With no subcommand it renders (the `render` defaults: the `atrium` scene with 32 lights).
//! The program is this library and a two-line `main`, so that the window viewer (the separate
//! `manyshadows-view` program in `crates/viewer`, whose window and panel libraries the default
//! build skips) shares its scene loading and options, and its tests can render the frames it
//! must match. `manyshadows view` runs that program (building it once from the source tree).

use anyhow::Result;
use clap::Parser;

use crate::commands::{BenchCommand, Cli, Command};

pub use args::{
    parse_camera, parse_camera_path, parse_ground, parse_pcf, parse_point_shadows,
    parse_probe_passes, parse_technique, GpuArgs, LightSizeArgs, LookArgs, ModelArgs, SoftArgs,
};
pub use scenes::{load_scene_for_view, ViewScene};
pub use technique_args::{parse_spatial, TechniqueArgs, VirtualMarking};

/// Why a frame of `renderer` would take far longer than the rest (its per-view shadow work
/// past `render`'s bound, with the estimate and the techniques that scale), or `None`: what
/// `render` and `compare` refuse without `--insist`, for the viewer to say on its panel.
pub fn shadow_work_refusal(renderer: &manyshadows::Renderer) -> Option<String> {
    render::check_shadow_work(renderer, &renderer.estimate_frame())
        .err()
        .map(|e| e.to_string())
}

mod args;
mod bench;
mod commands;
mod compare;
mod info;
mod light_args;
mod progress;
mod render;
mod scenes;
mod summary;
mod technique_args;
mod techniques;
mod viewer;

/// The GL backend probes for a Wayland display, and libwayland prints a misleading
/// "XDG_RUNTIME_DIR is invalid" error on headless machines where that variable is unset. Give
/// it a private, empty runtime directory so the probe fails quietly.
fn quiet_wayland_probe() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
        return;
    }
    let dir = std::env::temp_dir().join("manyshadows-runtime");
    if std::fs::create_dir_all(&dir).is_ok() {
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
        }
        // Still single-threaded here: nothing else reads the environment concurrently.
        std::env::set_var("XDG_RUNTIME_DIR", &dir);
    }
}

/// Runs the `manyshadows` program with the process's arguments (its `main`).
pub fn main() {
    quiet_wayland_probe();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    if let Err(e) = run(std::env::args_os()) {
        eprintln!("error: {}", report(&e));
        std::process::exit(1);
    }
}

/// An error and its causes on one line, each cause once: a cause whose text the message
/// already holds (errors that print their source, as `cannot read x: <os error>` does) is not
/// repeated.
pub fn report(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if msg.contains(&c) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(&c);
    }
    msg
}

/// Runs the program with `args` (the program name first, as `std::env::args_os` gives):
/// parses them (a usage error exits the process, as clap does) and carries the command out.
pub fn run(args: impl IntoIterator<Item = std::ffi::OsString>) -> Result<()> {
    let cli = Cli::parse_from(args);
    match cli.command {
        Some(Command::Render(args)) => render::render(&args),
        Some(Command::Info(args)) => info::info(&args),
        Some(Command::View(args)) => viewer::run(&args),
        Some(Command::Compare(args)) => compare::run(&args),
        Some(Command::Bench(BenchCommand::Layered(args))) => bench::layered::layered(&args),
        Some(Command::Bench(BenchCommand::Omni(args))) => bench::omni::omni(&args),
        Some(Command::Bench(BenchCommand::Irregular(args))) => bench::irregular::irregular(&args),
        Some(Command::Bench(BenchCommand::Lights(args))) => bench::lights::lights(&args),
        Some(Command::Bench(BenchCommand::Virtual(args))) => {
            bench::virtual_maps::virtual_maps(&args)
        }
        Some(Command::Bench(BenchCommand::Soak(args))) => bench::soak::soak(&args),
        Some(Command::Bench(BenchCommand::Shadows(args))) => bench::shadows::shadows(&args),
        Some(Command::Bench(BenchCommand::Soft(args))) => bench::soft::soft(&args),
        Some(Command::Bench(BenchCommand::Stereo(args))) => bench::stereo::stereo(&args),
        Some(Command::Bench(BenchCommand::Probes(args))) => bench::probes::probes(&args),
        Some(Command::Bench(BenchCommand::Animation(args))) => bench::animation::animation(&args),
        Some(Command::Bench(BenchCommand::Estimate(args))) => bench::estimate::estimate(&args),
        Some(Command::Bench(BenchCommand::Denoise(args))) => bench::denoise::denoise(&args),
        Some(Command::Bench(BenchCommand::Suite(args))) => bench::suite::suite(&args),
        None => render::render(&cli.render),
    }
}
