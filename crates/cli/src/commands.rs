//! The tree of commands (clap): `render` (the default), `info`, `view`, `compare` and the
//! benches, each with the arguments its own module defines.

use clap::{Parser, Subcommand};

use crate::args::{GpuArgs, RenderArgs};
use crate::{bench, compare, viewer};

pub(crate) const ABOUT: &str = "Render scenes lit by many shadow-casting lights, headless, to PNG.";

pub(crate) const LONG_ABOUT: &str = "\
Render scenes lit by many shadow-casting lights, headless, to PNG.

Every frame is: a G-buffer pass, shadow generation into one depth atlas (one tile per shadow
view: 1 per spot light, 6 per point light, one per cascade of a directional light), then
deferred lighting with percentage-closer filtering: Phong for the built-in and TOML scenes,
the glTF BRDF with an automatic exposure and Khronos PBR Neutral for glTF files (--shading,
--exposure, --tone-map choose).

Run with no arguments to render the built-in `atrium` (a two-storey hall, >200k triangles)
with 32 lights of all three types to frame.png.

Examples:
  manyshadows                                   # atrium, 32 lights -> frame.png
  manyshadows render --scene dragon --lights 16 --atlas-out atlas.png
  manyshadows render --scene my_scene.toml --visibility-out vis/
  manyshadows render --scene terrain --pcf 3x3 --width 1920 --height 1080
  manyshadows info                              # adapters, limits, features used

Environment: WGPU_BACKEND=vulkan|gl picks the backend, WGPU_ADAPTER_NAME=substring the
adapter; RUST_LOG=info shows more detail.";

#[derive(Parser, Debug)]
#[command(name = "manyshadows", version, about = ABOUT, long_about = LONG_ABOUT)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
    #[command(flatten)]
    pub(crate) render: RenderArgs,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Render a scene to PNG (the default when no subcommand is given).
    Render(Box<RenderArgs>),
    /// List the graphics adapters, the one that would be chosen, its limits and the optional
    /// features the renderer uses.
    Info(GpuArgs),
    /// Score every shadow technique against an exact CPU ray-traced reference.
    #[command(long_about = compare::LONG_ABOUT)]
    Compare(Box<compare::CompareArgs>),
    /// Benchmarks with tables, JSON and plots (`bench layered`: seed 000's experiments). Each
    /// comparison runs its methods round-robin after a warm-up and reports medians and ratios
    /// from the same runs.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Fly through a scene in a window: switch technique, point shadows, PCF, light count and
    /// caching at run time, with GPU time per stage on screen. Runs on a CPU adapter too (under
    /// Xvfb without a desktop). This is the `manyshadows-view` program (`--help` shows its
    /// options); from the source tree it is built on first use.
    #[command(disable_help_flag = true)]
    View(viewer::ViewerArgs),
}

#[derive(Subcommand, Debug)]
pub(crate) enum BenchCommand {
    /// Shadow-map generation time against the number of maps, for every technique and the
    /// seed's variants (simple, no-raster, skinned, instances, backface, combined). Writes
    /// results.txt, results.json and one plot per variant and resolution into --out-dir.
    #[command(mut_arg("repeats", |a| a.default_value("5")))]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-layered").required(false)))]
    Layered(Box<bench::layered::LayeredArgs>),
    /// Point-light shadows in the atrium: cube maps (six passes, or one) against dual
    /// paraboloids (two passes, or one), for 1..N lights: GPU and CPU time per light and
    /// atlas memory per light, as a table, results.json and plots (seed 003's comparison).
    #[command(mut_arg("repeats", |a| a.default_value("5")))]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-omni").required(false)))]
    Omni(Box<bench::omni::OmniArgs>),
    /// Alias-free irregular shadows against traditional shadow maps: frame GPU time by number
    /// of lights and screen resolution, as a table, results.json and plots.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-irregular").required(false)))]
    Irregular(Box<bench::irregular::IrregularArgs>),
    /// Whole frames from 16 to 16,384 lights with clustered shading: GPU time per stage
    /// (G-buffer, clusters, shadows, lighting; lighting also over every light up to
    /// --reference-up-to), lights per cluster, shadow-map fit and memory; table, results.json
    /// and one plot per scene and screen.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-lights").required(false)))]
    Lights(Box<bench::lights::LightsArgs>),
    /// Virtual shadow maps against the atlas path, 16 to 4,096 lights, interleaved in the same
    /// run: GPU time per stage, shadow memory kept, pages needed / rendered / denied; table,
    /// results.json and a plot.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-virtual").required(false)))]
    Virtual(Box<bench::virtual_maps::VirtualArgs>),
    /// Every kind of shadow side by side from 64 to 16,384 lights, one caster moving: the
    /// atlas, virtual pages, and shadow rays (every cluster light, and K sampled lights per
    /// pixel) where the device has ray queries; GPU time per stage with the acceleration
    /// structure's rebuild apart, renderer setup time; table, results.json and a plot.
    #[command(mut_arg("repeats", |a| a.default_value("3")))]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-shadows").required(false)))]
    Shadows(Box<bench::shadows::ShadowsArgs>),
    /// What soft shadows cost: whole frames with percentage-closer soft shadows against the
    /// same lights rendered hard (2x2 PCF), per technique (traditional and virtual) and light
    /// count, interleaved in the same run; GPU time per stage and ratios; table and
    /// results.json.
    #[command(long_about = bench::soft::LONG_ABOUT)]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-soft").required(false)))]
    Soft(Box<bench::soft::SoftArgs>),
    /// Sampled shadow rays and their denoiser over a sequence (the camera turning, a caster
    /// moving), each frame scored against the exact image of that frame: RMSE per frame, GPU
    /// time of the plain and the denoised frames and their ratio, per light count; table,
    /// results.json and a plot.
    #[command(long_about = bench::denoise::LONG_ABOUT)]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-denoise").required(false)))]
    Denoise(Box<bench::denoise::DenoiseArgs>),
    /// How well each technique's estimate of its frame (made before drawing it, as `render`,
    /// `view` and `compare` say it) predicts the measured frame: per scene, light count and
    /// method, GPU ms per stage estimated and measured and their ratio; table and results.json.
    #[command(long_about = bench::estimate::LONG_ABOUT)]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-estimate").required(false)))]
    Estimate(Box<bench::estimate::EstimateArgs>),
    /// Reflection probes' faces: one G-buffer pass per face against every face in one layered
    /// pass, six faces per multiview pass, and triangle clusters culled per face on the GPU
    /// (indirect multi-draws), per probe count and face size, a caster moving so every face is
    /// redrawn; probes stage and whole-frame GPU time, CPU time, ratios; table, results.json
    /// and a plot.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-probes").required(false)))]
    Probes(Box<bench::probes::ProbesArgs>),
    /// Scenes that move as authored (the skinned `crowd`, or an animated glTF file) per
    /// technique against the same scene frozen, same runs: whole-frame and shadow GPU time,
    /// views or pages redrawn a frame, CPU time of the pose; table and results.json.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-animation").required(false)))]
    Animation(Box<bench::animation::AnimationArgs>),
    /// Stereo frames: both eyes' G-buffers in one layered or multiview pass against one pass
    /// per eye (and one mono eye for scale), per scene and eye size; G-buffer and whole-frame
    /// GPU time, CPU time, ratios to per-eye; table, results.json and a plot.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-stereo").required(false)))]
    Stereo(Box<bench::stereo::StereoArgs>),
    /// Thousands of frames in which the camera, a caster, a light and the light count change:
    /// resident memory after a warm-up against its baseline (fails past --max-growth-mib),
    /// frame times per interval, any failed frame; table and results.json.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-soak")
        .required(false)
        .help("Directory for results.json and results.txt")))]
    Soak(Box<bench::soak::SoakArgs>),
    /// The headline measurements in one command, for a GPU: `bench layered` (seed 000's
    /// sweep), `bench omni` and `bench shadows` at 1080p from 16 to 16,384 lights, each its own
    /// run; then suite.txt (their tables in order, each naming the adapter) and suite.json.
    /// `--quick` runs tiny sizes to check that everything runs.
    Suite(bench::suite::SuiteArgs),
}
