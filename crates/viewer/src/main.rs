//! `manyshadows-view` (also run as `manyshadows view`): the renderer in a window, with a fly
//! camera and a panel. A program of its own so that the default build of `manyshadows` leaves
//! out the window and panel libraries (see `crates/cli/src/viewer.rs`).

mod view;

use clap::Parser;

#[derive(Parser, Debug)]
#[command(
    name = "manyshadows view",
    version,
    about = "Fly through a scene in a window: switch technique, point shadows, PCF, light \
             count and caching at run time, with GPU time per stage on screen. Runs on a CPU \
             adapter too (under Xvfb without a desktop).",
    after_help = format!("Controls: {}", view::CONTROLS)
)]
struct Cli {
    #[command(flatten)]
    view: view::ViewArgs,
}

fn main() {
    // As in `manyshadows`: a runtime directory keeps libwayland's GL probe quiet.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    if let Err(e) = view::run(&cli.view) {
        eprintln!("error: {}", manyshadows_cli::report(&e));
        std::process::exit(1);
    }
}
