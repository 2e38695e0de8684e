//! `manyshadows`: render scenes lit by many shadow-casting lights to PNG, score and benchmark
//! shadow techniques, and describe the GPU.
//!
//! With no subcommand it renders (the `render` defaults: the `atrium` scene with 32 lights).
//! The program is this library and a two-line `main`, so that the window viewer (the separate
//! `manyshadows-view` program in `crates/viewer`, whose window and panel libraries the default
//! build skips) shares its scene loading and options, and its tests can render the frames it
//! must match. `manyshadows view` runs that program (building it once from the source tree).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use manyshadows::gpu::context::{describe_adapter, feature_use, list_adapters, requested_backends};
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::Scene;
use manyshadows::{
    AdapterRequest, CullMode, Frame, GpuContext, Pcf, RenderSettings, Renderer, ShadowBias,
    ShadowOptions, Technique,
};

mod bench;
mod compare;
mod harness;
mod irregular_bench;
mod lights_bench;
mod omni;
mod plot;
mod shadows_bench;
mod soak;
mod suite;
mod techniques;
mod viewer;
mod virtual_bench;

const ABOUT: &str = "Render scenes lit by many shadow-casting lights, headless, to PNG.";

const LONG_ABOUT: &str = "\
Render scenes lit by many shadow-casting lights, headless, to PNG.

Every frame is: a G-buffer pass, shadow generation into one depth atlas (one tile per shadow
view: 1 per spot light, 6 per point light, one per cascade of a directional light), then
deferred Phong lighting with percentage-closer filtering.

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
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    render: RenderArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
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
enum BenchCommand {
    /// Shadow-map generation time against the number of maps, for every technique and the
    /// seed's variants (simple, no-raster, skinned, instances, backface, combined). Writes
    /// results.txt, results.json and one plot per variant and resolution into --out-dir.
    #[command(mut_arg("repeats", |a| a.default_value("5")))]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-layered").required(false)))]
    Layered(Box<bench::LayeredArgs>),
    /// Point-light shadows in the atrium: cube maps (six passes, or one) against dual
    /// paraboloids (two passes, or one), for 1..N lights: GPU and CPU time per light and
    /// atlas memory per light, as a table, results.json and plots (seed 003's comparison).
    #[command(mut_arg("repeats", |a| a.default_value("5")))]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-omni").required(false)))]
    Omni(Box<omni::OmniArgs>),
    /// Alias-free irregular shadows against traditional shadow maps: frame GPU time by number
    /// of lights and screen resolution, as a table, results.json and plots.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-irregular").required(false)))]
    Irregular(Box<irregular_bench::IrregularArgs>),
    /// Whole frames from 16 to 16,384 lights with clustered shading: GPU time per stage
    /// (G-buffer, clusters, shadows, lighting; lighting also over every light up to
    /// --reference-up-to), lights per cluster, shadow-map fit and memory; table, results.json
    /// and one plot per scene and screen.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-lights").required(false)))]
    Lights(Box<lights_bench::LightsArgs>),
    /// Virtual shadow maps against the atlas path, 16 to 4,096 lights, interleaved in the same
    /// run: GPU time per stage, shadow memory kept, pages needed / rendered / denied; table,
    /// results.json and a plot.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-virtual").required(false)))]
    Virtual(Box<virtual_bench::VirtualArgs>),
    /// Every kind of shadow side by side from 64 to 16,384 lights, one caster moving: the
    /// atlas, virtual pages, and shadow rays (every cluster light, and K sampled lights per
    /// pixel) where the device has ray queries; GPU time per stage with the acceleration
    /// structure's rebuild apart, renderer setup time; table, results.json and a plot.
    #[command(mut_arg("repeats", |a| a.default_value("3")))]
    #[command(mut_arg("out_dir", |a| a.default_value("bench-shadows").required(false)))]
    Shadows(Box<shadows_bench::ShadowsArgs>),
    /// Thousands of frames in which the camera, a caster, a light and the light count change:
    /// resident memory after a warm-up against its baseline (fails past --max-growth-mib),
    /// frame times per interval, any failed frame; table and results.json.
    #[command(mut_arg("out_dir", |a| a.default_value("bench-soak")
        .required(false)
        .help("Directory for results.json and results.txt")))]
    Soak(Box<soak::SoakArgs>),
    /// The headline measurements in one command, for a GPU: `bench layered` (seed 000's
    /// sweep), `bench omni` and `bench shadows` at 1080p from 16 to 16,384 lights, each its own
    /// run; then suite.txt (their tables in order, each naming the adapter) and suite.json.
    /// `--quick` runs tiny sizes to check that everything runs.
    Suite(suite::SuiteArgs),
}

/// Adapter choice: `--backend`, `--adapter`, `--limits` (shared by every subcommand that
/// renders, and by the viewer).
#[derive(Args, Debug, Clone)]
pub struct GpuArgs {
    /// Graphics backend (default: WGPU_BACKEND, else the best adapter of any backend:
    /// hardware first, then Vulkan on the CPU, then OpenGL on the CPU).
    #[arg(long, value_enum)]
    backend: Option<Backend>,
    /// Use the adapter whose name contains this text (default: WGPU_ADAPTER_NAME).
    #[arg(long)]
    adapter: Option<String>,
    /// Create the device with smaller limits than the adapter's: `webgpu` = what a browser
    /// gives by default (8 storage buffers per stage, 8192² textures, 128 MiB storage
    /// bindings) — how the renderer behaves on a small device, without one.
    #[arg(long, value_enum)]
    limits: Option<Limits>,
}

/// `--virtual-marking`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum VirtualMarking {
    /// By 4x4-pixel tiles, per pixel where the tile's bounds leave it uncertain.
    Tiles,
    /// Every (pixel, light) pair.
    Pixels,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum Limits {
    /// WebGPU's default limits.
    Webgpu,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum Backend {
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl GpuArgs {
    /// The adapter request these options describe.
    pub fn request(&self) -> AdapterRequest {
        AdapterRequest::default()
            .with_backends(self.backend.map(|b| match b {
                Backend::Vulkan => wgpu_backends("vulkan"),
                Backend::Gl => wgpu_backends("gl"),
                Backend::Metal => wgpu_backends("metal"),
                Backend::Dx12 => wgpu_backends("dx12"),
            }))
            .with_name(self.adapter.clone())
            .with_limits(self.limits.map(|l| match l {
                Limits::Webgpu => manyshadows::webgpu_default_limits(),
            }))
    }
}

/// `on` / `off` (also yes/no, true/false, 1/0).
pub(crate) fn parse_on_off(s: &str) -> Result<bool, String> {
    match s.trim().to_ascii_lowercase().as_str() {
        "on" | "yes" | "true" | "1" => Ok(true),
        "off" | "no" | "false" | "0" => Ok(false),
        _ => Err(format!("'{s}' is neither on nor off")),
    }
}

fn wgpu_backends(name: &str) -> manyshadows::wgpu::Backends {
    manyshadows::wgpu::Backends::from_comma_list(name)
}

#[derive(Args, Debug, Clone)]
pub(crate) struct RenderArgs {
    /// Built-in scene name, a TOML scene file (see docs/SCENE_FORMAT.md), or a model file
    /// (.gltf/.glb with its materials, textures, KHR_lights_punctual lights and camera; .obj
    /// with its MTL; .ply/.ply.gz), rendered with its own lights and camera (8 seeded lights
    /// and a framing camera when it has none). Built-ins: atrium, terrain, dragon, cubes,
    /// courtyard (textures and alpha-masked foliage, lattice, banners), courtyard-opaque,
    /// plane-spot, plane-point, plane-directional.
    #[arg(long, default_value = "atrium")]
    scene: String,
    /// Shadow technique (--help lists them all, with what each fills and needs).
    #[arg(long, default_value_t = Technique::default(), value_parser = parse_technique, long_help = techniques::help())]
    technique: Technique,
    /// Per-view triangle culling of the single-pass techniques: none, frustum, backface
    /// (closed meshes only, so shadows never change) or all. The default technique, one pass
    /// per view, culls whole instances on the CPU and ignores it.
    #[arg(long, default_value = "all", value_parser = parse_cull)]
    cull: CullMode,
    /// Point-light shadows: cube (six 90° faces) or dual-paraboloid (two hemispheres, each
    /// map twice the per-face resolution; needs finely tessellated geometry, see --subdivide).
    /// `--help` under --technique says which techniques render which.
    #[arg(long, default_value = "cube", value_parser = parse_point_shadows)]
    point_shadows: PointShadows,
    /// Split every triangle into four this many times before rendering (4^N triangles), e.g.
    /// to give dual-paraboloid maps the fine geometry their non-linear warp needs.
    #[arg(long, default_value_t = 0)]
    subdivide: u32,
    /// Render this many frames; with more than one, one shadow caster (see --move-instance)
    /// moves a little each frame and a line per frame reports the shadow work. The last frame
    /// is written.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    /// Draw every shadow map anew each frame. By default the atlas tiles of views that saw no
    /// change since the last frame are kept (seed 004's caching; with --technique virtual,
    /// the pages of unchanged faces away from moved casters); with --frames, each frame's line
    /// shows how many views (pages) it redrew.
    #[arg(long, conflicts_with = "shadow_budget")]
    no_cache: bool,
    /// Keep what did not change between frames: the default (kept for older command lines).
    #[arg(long, hide = true, conflicts_with = "no_cache")]
    cache: bool,

    /// At most N shadow views drawn per frame (atlas techniques; needs the caching): the views
    /// that changed wait their turn, new tiles and larger (nearer, more important) views
    /// first; a waiting view is served from its older depth where its tile holds it (counted
    /// stale, with the age of the oldest) and unshadowed until drawn where it holds nothing
    /// yet (counted waiting). With --frames, each frame's line says how many of each
    #[arg(long, value_name = "N")]
    shadow_budget: Option<u32>,
    /// Render even a frame whose shadow work is far beyond the rest (more than 2 G
    /// triangle-view pairs, e.g. a technique that sends every triangle to each of thousands
    /// of views): without it such a frame is refused with its estimate and the techniques that
    /// scale, before anything is drawn.
    #[arg(long)]
    insist: bool,
    /// With --frames > 1, turn the camera this many degrees per frame around its target (about
    /// its up axis). The shadow plan follows: cascades refit, lights that leave the screen
    /// give up their maps and lights that enter it get them.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    orbit: f32,
    /// The instance that moves when --frames > 1 (default: the smallest shadow caster).
    #[arg(long)]
    move_instance: Option<usize>,
    /// Number of lights, placed by a seeded layout (default: the scene's own lights).
    #[arg(long)]
    lights: Option<usize>,
    /// Seed of the light layout.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Light types the layout uses: all (mixed), spot, point or directional.
    #[arg(long, default_value = "all")]
    light_types: String,
    /// Mesh file for the dragon scene (.obj, .gltf/.glb, .ply, .ply.gz); without it a
    /// procedural stand-in of ~35k triangles is used.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Shadow-map resolution per view (texels per side) for every light.
    #[arg(long)]
    shadow_resolution: Option<u32>,
    /// Camera position and target, `PX,PY,PZ,TX,TY,TZ` (default: the scene's camera).
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
    camera: Option<[f32; 6]>,
    /// Image width.
    #[arg(long, default_value_t = 1280)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Percentage-closer filtering: off, 2x2 or 3x3.
    #[arg(long, default_value = "2x2", value_parser = parse_pcf)]
    pcf: Pcf,
    /// Receiver bias towards the light, in shadow texels.
    #[arg(long, default_value_t = ShadowBias::default().constant)]
    bias_constant: f32,
    /// Receiver bias towards the light per unit of tan(angle between normal and light), texels.
    #[arg(long, default_value_t = ShadowBias::default().slope)]
    bias_slope: f32,
    /// Receiver offset along the surface normal, texels.
    #[arg(long, default_value_t = ShadowBias::default().normal_offset)]
    bias_normal: f32,
    /// Alpha-tested casters in the shadow passes: on (holes in foliage, lattices and banners
    /// let light through) or off (they cast as solid cards, as a renderer that ignores alpha
    /// would draw them; the camera still sees the holes).
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    shadow_alpha: bool,
    /// Largest shadow-atlas side in texels (clamped to the adapter's limit).
    #[arg(long, default_value_t = manyshadows::DEFAULT_MAX_ATLAS_SIZE)]
    atlas_max: u32,
    /// Fail when the shadow maps don't fit the atlas. By default maps that don't fit degrade by
    /// importance: lights that reach nothing on screen get no maps, the least important lights
    /// (smallest angle at the camera) get smaller maps first, and as a last resort no shadows;
    /// the summary counts each.
    #[arg(long)]
    strict_atlas: bool,
    /// Grid side (texels) of each light view for --technique irregular (default: the view's
    /// shadow resolution, at most 512). Changes speed, not the result.
    #[arg(long)]
    irregular_grid: Option<u32>,
    /// Multimap hash of --technique irregular: N texels share a list head (seed 001's
    /// equalising hash; default: one list per texel). Changes speed, not the result.
    #[arg(long)]
    irregular_hash: Option<u32>,
    /// Page pool of --technique virtual, MiB of 32-bit depth: the largest square of whole 128²
    /// pages that fits (256 = an 8192² pool of 4,096 pages, 512 = 11520² of 8,100 pages), at
    /// most the adapter's largest texture; the summary says when that is less than asked.
    /// Pages that do not fit fall back to coarser levels, counted in the summary.
    #[arg(long, default_value_t = (manyshadows::shadows::vsm::plan::DEFAULT_POOL_BYTES >> 20) as u32)]
    page_pool: u32,
    /// Largest virtual side of a face for --technique virtual (rounded to a power of two and
    /// clamped to 128..=16384 texels).
    #[arg(long, default_value_t = manyshadows::shadows::vsm::plan::MAX_SIDE)]
    virtual_side: u32,
    /// Shadow texels per screen pixel that --technique virtual aims for (1 = no texel wider
    /// than the pixel footprint; 2 = twice as fine, four times the pages; 0.7 about 0.6 times
    /// the pages, with more misclassified pixels where pixels are wide): point lights' cube
    /// faces get it, spot and directional lights' faces it times --virtual-directed-lod.
    #[arg(long, default_value_t = manyshadows::shadows::vsm::plan::DEFAULT_LOD)]
    virtual_lod: f32,
    /// Factor on --virtual-lod for the faces of spot and directional lights (0.8 by default:
    /// their texels up to 1.25 pixels, which costs them few misclassified pixels while point
    /// lights' cube faces, seeing walls near the light, keep --virtual-lod; 1 gives every face
    /// --virtual-lod).
    #[arg(long, default_value_t = manyshadows::shadows::vsm::plan::DEFAULT_DIRECTED_LOD)]
    virtual_directed_lod: f32,
    /// --technique virtual's receiver bias as a fraction of --bias-constant, --bias-slope and
    /// --bias-normal (those count texels; a virtual page's texels match the screen pixel, and
    /// a whole texel of bias leaks light at contacts: 0.5 by default, 0 to 16).
    #[arg(long, default_value_t = manyshadows::shadows::vsm::plan::DEFAULT_BIAS_SCALE)]
    virtual_bias: f32,
    /// How --technique virtual finds the pages the samples need: `tiles` bounds the samples
    /// of 4x4-pixel tiles and marks a light's page once where every sample needing one needs
    /// the same page, per pixel elsewhere; `pixels` marks every (pixel, light) pair. The same
    /// pages either way (the summary's `marking` line says how the tiles went); `pixels` is
    /// for measuring.
    #[arg(long, value_enum, default_value_t = VirtualMarking::Tiles)]
    virtual_marking: VirtualMarking,
    /// With shadow rays (a technique that casts them, see --technique): trace K lights per
    /// pixel, picked among the pixel's cluster lights by importance (their unshadowed
    /// contribution) and weighted so the image stays unbiased — noisy, at a cost that does
    /// not grow with the light count. 0 (default) traces every cluster light: exact.
    #[arg(long, default_value_t = 0)]
    light_samples: u32,
    /// Seed of --light-samples' choices (the same seed gives the same image).
    #[arg(long, default_value_t = 0)]
    ray_seed: u32,
    /// Which lights each pixel visits: clustered (the lights assigned to its cluster of a
    /// tiles x depth-slices grid, built on the GPU each frame) or all (every light: the
    /// reference the clustered image must equal, and slow past a few hundred lights).
    #[arg(long, default_value = "clustered", value_parser = parse_light_loop)]
    light_loop: manyshadows::LightLoop,
    /// Cluster tile side in pixels.
    #[arg(long, default_value_t = manyshadows::ClusterOptions::default().tile)]
    cluster_tile: u32,
    /// Exponential depth slices of the cluster grid (1 to 256).
    #[arg(long, default_value_t = manyshadows::ClusterOptions::default().slices)]
    cluster_slices: u32,
    /// Output image.
    #[arg(long, short, default_value = "frame.png")]
    out: PathBuf,
    /// Also write the shadow atlas as a picture (linearized depth, tiles outlined).
    #[arg(long)]
    atlas_out: Option<PathBuf>,
    /// Also write the hard visibility mask into this directory: visibility.msvis (raw bits,
    /// format in the renderer's visibility module docs) and one PNG per light (white = lit).
    #[arg(long)]
    visibility_out: Option<PathBuf>,
    /// Also write the summary as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    gpu: GpuArgs,
}

impl Default for RenderArgs {
    fn default() -> Self {
        let cli = Cli::parse_from(["manyshadows"]);
        cli.render
    }
}

/// A technique name (as `--technique` takes it).
pub fn parse_technique(s: &str) -> Result<Technique, String> {
    s.parse()
}

/// `cube` or `dual-paraboloid`.
pub fn parse_point_shadows(s: &str) -> Result<PointShadows, String> {
    s.parse()
}

fn parse_cull(s: &str) -> Result<CullMode, String> {
    s.parse()
}

/// `PX,PY,PZ,TX,TY,TZ`: six finite numbers.
pub fn parse_camera(s: &str) -> Result<[f32; 6], String> {
    let v: Vec<f32> = s
        .split([',', ' '])
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f32>().map_err(|e| format!("'{t}': {e}")))
        .collect::<Result<_, _>>()?;
    match <[f32; 6]>::try_from(v.as_slice()) {
        Ok(a) if a.iter().all(|x| x.is_finite()) => {
            if a[..3] == a[3..] {
                Err("the camera position and target must differ".into())
            } else {
                Ok(a)
            }
        }
        Ok(_) => Err("camera coordinates must be finite".into()),
        Err(_) => Err(format!(
            "expected six numbers PX,PY,PZ,TX,TY,TZ, got {}",
            v.len()
        )),
    }
}

/// `off`, `2x2` or `3x3`.
pub fn parse_pcf(s: &str) -> Result<Pcf, String> {
    s.parse()
}

fn parse_light_loop(s: &str) -> Result<manyshadows::LightLoop, String> {
    s.parse()
}

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
        Some(Command::Render(args)) => render(&args),
        Some(Command::Info(args)) => info(&args),
        Some(Command::View(args)) => viewer::run(&args),
        Some(Command::Compare(args)) => compare::run(&args),
        Some(Command::Bench(BenchCommand::Layered(args))) => bench::layered(&args),
        Some(Command::Bench(BenchCommand::Omni(args))) => omni::omni(&args),
        Some(Command::Bench(BenchCommand::Irregular(args))) => irregular_bench::irregular(&args),
        Some(Command::Bench(BenchCommand::Lights(args))) => lights_bench::lights(&args),
        Some(Command::Bench(BenchCommand::Virtual(args))) => virtual_bench::virtual_maps(&args),
        Some(Command::Bench(BenchCommand::Soak(args))) => soak::soak(&args),
        Some(Command::Bench(BenchCommand::Shadows(args))) => shadows_bench::shadows(&args),
        Some(Command::Bench(BenchCommand::Suite(args))) => suite::suite(&args),
        None => render(&cli.render),
    }
}

fn spinner(msg: &str) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{elapsed}]").expect("valid template"),
    );
    pb.enable_steady_tick(Duration::from_millis(120));
    pb.set_message(msg.to_string());
    pb
}

/// Loads a scene as `render` does: a built-in name, a TOML file or a model file, with `lights`
/// seeded lights instead of its own when given and the camera at `camera` (`PX,PY,PZ,TX,TY,TZ`)
/// when given (what the viewer shows).
pub fn load_scene_for_view(
    scene: &str,
    mesh: Option<PathBuf>,
    lights: Option<usize>,
    seed: u64,
    camera: Option<[f32; 6]>,
) -> Result<Scene> {
    load_scene(&RenderArgs {
        scene: scene.to_string(),
        mesh,
        lights,
        seed,
        camera,
        ..RenderArgs::default()
    })
}

/// Loads a built-in scene or a TOML file, applying `--lights`/`--seed`/`--light-types`.
pub(crate) fn load_scene(args: &RenderArgs) -> Result<Scene> {
    let mut scene = load_scene_unsubdivided(args)?;
    if args.subdivide > 0 {
        scene.subdivide(args.subdivide)?;
    }
    if let Some(c) = args.camera {
        scene.camera.position = glam::Vec3::new(c[0], c[1], c[2]);
        scene.camera.target = glam::Vec3::new(c[3], c[4], c[5]);
    }
    Ok(scene)
}

fn load_scene_unsubdivided(args: &RenderArgs) -> Result<Scene> {
    let mix: LightMix = args.light_types.parse()?;
    let path = Path::new(&args.scene);
    let lower = args.scene.to_ascii_lowercase();
    let model = [".obj", ".gltf", ".glb", ".ply", ".ply.gz"]
        .iter()
        .any(|ext| lower.ends_with(ext));
    // A built-in name wins over a same-named file in the working directory.
    let is_file = lower.ends_with(".toml")
        || model
        || (path.is_file() && !builtin::SCENE_NAMES.contains(&args.scene.as_str()));
    if is_file {
        let mut scene = if model {
            // A model file is a scene of its own: its materials, textures, lights and camera
            // (defaults added where it has none, and said).
            let loaded = manyshadows::scene::loaders::load_scene(path)?;
            for note in &loaded.notes {
                eprintln!("note: {}: {note}", path.display());
            }
            loaded.scene
        } else {
            manyshadows::scene::scene_file::load_scene_file(path)?
        };
        if let Some(n) = args.lights {
            if n > builtin::MAX_LIGHTS {
                bail!(
                    "--lights {n} is more than the supported {}",
                    builtin::MAX_LIGHTS
                );
            }
            scene.lights =
                builtin::scatter_lights(&scene, n, args.seed, mix, args.shadow_resolution);
        } else if let Some(r) = args.shadow_resolution {
            for l in &mut scene.lights {
                l.shadow_resolution = r;
            }
        }
        return Ok(scene);
    }
    let mesh = match &args.mesh {
        Some(p) => {
            let meshes = manyshadows::scene::loaders::load_mesh(p)?;
            Some(manyshadows::scene::primitives::merge(
                &meshes
                    .into_iter()
                    .map(|m| (m, glam::Mat4::IDENTITY))
                    .collect::<Vec<_>>(),
            ))
        }
        None => None,
    };
    let opts = BuiltinOptions {
        lights: args.lights,
        seed: args.seed,
        mix,
        mesh,
        shadow_resolution: args.shadow_resolution,
    };
    Ok(builtin::build(&args.scene, &opts)?)
}

/// Refuses option values that could only be changed silently; checked before anything is
/// loaded or uploaded.
fn check_render_args(args: &RenderArgs) -> Result<()> {
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    // The renderer checks every option's range itself; asking it here refuses a bad value
    // before anything is loaded, and names the flag that set it.
    render_settings(args, args.atlas_max)
        .validate()
        .map_err(flag_error)
}

/// A renderer error about an option, with the CLI flag that sets the option in front.
pub(crate) fn flag_error(e: manyshadows::RenderError) -> anyhow::Error {
    const FLAGS: &[(&str, &str)] = &[
        ("width", "--width"),
        ("height", "--height"),
        ("max_atlas_size", "--atlas-max"),
        ("bias.constant", "--bias-constant"),
        ("bias.slope", "--bias-slope"),
        ("bias.normal_offset", "--bias-normal"),
        ("clusters.tile", "--cluster-tile"),
        ("clusters.slices", "--cluster-slices"),
        ("irregular.grid", "--irregular-grid"),
        ("irregular.hash", "--irregular-hash"),
        ("virtual_maps.pool_bytes", "--page-pool (MiB)"),
        ("virtual_maps.lod", "--virtual-lod"),
        ("virtual_maps.directed_lod", "--virtual-directed-lod"),
        ("virtual_maps.bias_scale", "--virtual-bias"),
        ("virtual_maps.max_side", "--virtual-side"),
        ("rays.light_samples", "--light-samples"),
        ("shadow_budget", "--shadow-budget"),
    ];
    if let manyshadows::RenderError::InvalidOption { option, .. } = &e {
        if let Some((_, flag)) = FLAGS.iter().find(|(o, _)| o == option) {
            return anyhow::anyhow!("{flag}: {e}");
        }
    }
    e.into()
}

/// The atlas side `--atlas-max` really allows on this adapter (a power of two, at most the
/// adapter's texture limit), with a note on stderr when it is not the number given.
pub(crate) fn effective_atlas_max(ctx: &GpuContext, requested: u32) -> u32 {
    let limit = ctx.limits().max_texture_dimension_2d;
    let capped = requested.min(limit);
    let side = 1u32 << (31 - capped.leading_zeros());
    if side != requested {
        eprintln!(
            "note: --atlas-max {requested} is used as {side} (atlas sides are powers of two{})",
            if requested > limit {
                format!(", and this adapter's largest texture is {limit}")
            } else {
                String::new()
            }
        );
    }
    side
}

/// The renderer settings `args` ask for, with the atlas cap already checked against the
/// adapter.
pub(crate) fn render_settings(args: &RenderArgs, atlas_max: u32) -> RenderSettings {
    RenderSettings::default()
        .with_width(args.width)
        .with_height(args.height)
        .with_technique(args.technique)
        .with_shadow(ShadowOptions::default().with_cull(args.cull).with_casters(
            manyshadows::CasterOptions::default().with_ignore_masks(!args.shadow_alpha),
        ))
        .with_cache_shadows(!args.no_cache)
        .with_shadow_budget(args.shadow_budget)
        .with_point_shadows(args.point_shadows)
        .with_pcf(args.pcf)
        .with_bias(ShadowBias::new(
            args.bias_constant,
            args.bias_slope,
            args.bias_normal,
        ))
        .with_max_atlas_size(Some(atlas_max))
        .with_fit(if args.strict_atlas {
            FitPolicy::Strict
        } else {
            FitPolicy::Prioritize
        })
        .with_visibility(args.visibility_out.is_some())
        .with_irregular(
            manyshadows::IrregularOptions::default()
                .with_grid(args.irregular_grid)
                .with_hash(args.irregular_hash),
        )
        .with_virtual_maps(
            manyshadows::VirtualOptions::default()
                .with_pool_bytes(u64::from(args.page_pool) << 20)
                .with_max_side(args.virtual_side)
                .with_lod(args.virtual_lod)
                .with_directed_lod(args.virtual_directed_lod)
                .with_bias_scale(args.virtual_bias)
                .with_tile_marking(args.virtual_marking == VirtualMarking::Tiles),
        )
        .with_rays(
            manyshadows::RayOptions::default()
                .with_light_samples(args.light_samples)
                .with_seed(args.ray_seed),
        )
        .with_light_loop(args.light_loop)
        .with_clusters(
            manyshadows::ClusterOptions::default()
                .with_tile(args.cluster_tile)
                .with_slices(args.cluster_slices),
        )
}

fn render(args: &RenderArgs) -> Result<()> {
    let started = Instant::now();
    check_render_args(args)?;
    let pb = spinner("loading the scene");
    let scene = load_scene(args)?;
    pb.set_message("opening the GPU");
    let ctx = GpuContext::new(&args.gpu.request())?;
    let atlas_max = pb.suspend(|| effective_atlas_max(&ctx, args.atlas_max));
    let settings = render_settings(args, atlas_max);
    pb.set_message("uploading the scene and building pipelines");
    let mut renderer = Renderer::new(&ctx, &scene, settings)?;
    if !args.insist {
        pb.suspend(|| check_shadow_work(&renderer))?;
    }
    let mover = match args.move_instance {
        Some(k) if k >= scene.instances.len() => bail!(
            "--move-instance {k}: the scene has {} instances",
            scene.instances.len()
        ),
        Some(k) => Some(k),
        None => scene.smallest_caster(),
    };
    let mut frame = None;
    for f in 0..args.frames {
        pb.set_message(format!("rendering frame {}/{}", f + 1, args.frames));
        if f > 0 {
            if let Some(k) = mover {
                // A small circle in the ground plane, one step per frame.
                let a = f as f32 * 0.35;
                let offset = glam::Vec3::new(0.3 * a.cos() - 0.3, 0.0, 0.3 * a.sin());
                renderer.set_instance_transform(
                    k,
                    glam::Mat4::from_translation(offset) * scene.instances[k].transform,
                )?;
            }
            if args.orbit != 0.0 {
                let mut cam = renderer.scene().camera;
                let turn = glam::Quat::from_axis_angle(cam.up.normalize(), args.orbit.to_radians());
                cam.position = cam.target + turn * (cam.position - cam.target);
                renderer.set_camera(cam)?;
            }
        }
        let fr = renderer.render()?;
        if args.frames > 1 {
            let shadow_ms = fr
                .timings
                .gpu_ms
                .get(manyshadows::Stage::Shadows)
                .map_or("n/a".to_string(), |v| format!("{v:.2} ms"));
            let line = match &fr.virtual_maps {
                Some(v) => format!(
                    "frame {:>3}: {:>4} of {} resident pages drawn ({} kept), shadow GPU time {shadow_ms}",
                    f + 1,
                    v.drawn,
                    v.resident,
                    v.kept
                ),
                None => {
                    let st = &fr.shadow_stats;
                    let waiting = if args.shadow_budget.is_some() {
                        format!(
                            " ({} stale, oldest {} frames; {} waiting, unshadowed)",
                            st.views_stale, st.stale_frames, st.views_waiting
                        )
                    } else {
                        String::new()
                    };
                    format!(
                        "frame {:>3}: {:>4} of {} shadow views redrawn{waiting}, shadow GPU time {shadow_ms}",
                        f + 1,
                        st.views_drawn,
                        renderer.plan().views.len()
                    )
                }
            };
            pb.suspend(|| eprintln!("{line}"));
        }
        frame = Some(fr);
    }
    let frame = frame.expect("at least one frame");
    pb.set_message("writing images");
    write_rgba_png(&args.out, frame.width, frame.height, &frame.rgba)?;
    if let Some(path) = &args.atlas_out {
        let depth = renderer.read_atlas()?;
        let (side, rgb) = manyshadows::shadows::image::atlas_picture(
            &depth,
            renderer.atlas().size,
            renderer.plan(),
        );
        image::save_buffer(path, &rgb, side, side, image::ExtendedColorType::Rgb8)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let (Some(dir), Some(vis)) = (&args.visibility_out, &frame.visibility) {
        write_visibility(dir, vis, &scene)?;
    }
    pb.finish_and_clear();
    if let Some(v) = &frame.virtual_maps {
        let asked = u64::from(args.page_pool) << 20;
        if v.pool_bytes != asked {
            eprintln!(
                "note: --page-pool {} MiB is used as a {}² pool of {} pages, {:.2} MiB (a square \
                 of whole 128² pages{})",
                args.page_pool,
                v.pool_side,
                v.pool_pages,
                v.pool_bytes as f64 / (1 << 20) as f64,
                if v.pool_bytes < asked && v.pool_side + 128 > ctx.limits().max_texture_dimension_2d
                {
                    format!(
                        ", and this adapter's largest texture is {}",
                        ctx.limits().max_texture_dimension_2d
                    )
                } else {
                    String::new()
                }
            );
        }
    }
    let summary = summary(&ctx, &scene, &renderer, &frame, args, started.elapsed());
    print_summary(&summary);
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&summary)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn write_rgba_png(path: &Path, w: u32, h: u32, rgba: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    image::save_buffer(path, rgba, w, h, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("writing {}", path.display()))
}

fn write_visibility(dir: &Path, vis: &manyshadows::VisibilityMask, scene: &Scene) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let raw = dir.join("visibility.msvis");
    let file = std::fs::File::create(&raw).with_context(|| format!("writing {}", raw.display()))?;
    vis.write_raw(std::io::BufWriter::new(file))?;
    for (i, light) in scene.lights.iter().enumerate() {
        let path = dir.join(format!("light_{i:03}_{}.png", light.type_name()));
        image::save_buffer(
            &path,
            &vis.light_image(i as u32),
            vis.width,
            vis.height,
            image::ExtendedColorType::L8,
        )
        .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn summary(
    ctx: &GpuContext,
    scene: &Scene,
    r: &Renderer,
    frame: &Frame,
    args: &RenderArgs,
    total: Duration,
) -> serde_json::Value {
    let count = |t: &str| scene.lights.iter().filter(|l| l.type_name() == t).count();
    let plan = r.plan();
    serde_json::json!({
        "adapter": describe_adapter(&ctx.info),
        "backend": format!("{:?}", ctx.info.backend),
        "scene": scene.name,
        "technique": r.settings().technique.name(),
        "pcf": r.settings().pcf.name(),
        "resolution": [frame.width, frame.height],
        "triangles": r.triangles(),
        "instances": scene.instances.len(),
        "lights": { "total": scene.lights.len(), "spot": count("spot"), "point": count("point"), "directional": count("directional"),
                    "shadowed": scene.lights.iter().filter(|l| l.casts_shadows).count() },
        "shadow_views": r.virtual_plan().map_or(plan.views.len(), |v| v.views.len()),
        "atlas": { "size": plan.layout.size, "fill": plan.fill(), "shrink_steps": plan.layout.shrink_steps, "fit": plan.fit },
        "shadow_work": { "passes": frame.shadow_stats.passes, "draws": frame.shadow_stats.draws, "views_drawn": frame.shadow_stats.views_drawn,
                         "views_stale": frame.shadow_stats.views_stale, "stale_frames": frame.shadow_stats.stale_frames,
                         "views_waiting": frame.shadow_stats.views_waiting,
                         "culled_draws": frame.shadow_stats.culled, "triangles": frame.shadow_stats.triangles },
        "light_loop": r.settings().light_loop.name(),
        "clusters": frame.clusters,
        "virtual": frame.virtual_maps,
        "gpu_ms": frame.timings.gpu_ms,
        "cpu_record_ms": frame.timings.cpu_record_ms,
        "frame_wall_ms": frame.timings.wall_ms,
        "total_wall_ms": total.as_secs_f64() * 1e3,
        "output": args.out,
    })
}

/// Most (caster triangle, view) pairs a frame may take without `--insist`: 2 G. The layered
/// technique with the atrium's 16,384 lights asks 9.4 G and ran past ten minutes on lavapipe;
/// the default frame asks 21.6 M.
const MAX_UNASKED_TRIANGLE_VIEWS: u64 = 2_000_000_000;

/// Refuses, before any frame is drawn, a frame whose per-view shadow work passes
/// [`MAX_UNASKED_TRIANGLE_VIEWS`], with the estimate and the techniques that scale.
fn check_shadow_work(renderer: &Renderer) -> Result<()> {
    let Some(work) = renderer.shadow_work() else {
        return Ok(());
    };
    if work.triangle_views <= MAX_UNASKED_TRIANGLE_VIEWS {
        return Ok(());
    }
    let technique = renderer.settings().technique;
    let g = |n: u64| format!("{:.1} G", n as f64 / 1e9);
    let culled: Vec<&str> = Technique::all()
        .into_iter()
        .filter(|t| {
            matches!(
                t.info().culling,
                manyshadows::Culling::Instances | manyshadows::Culling::Clusters
            ) && t.info().fills == manyshadows::Fills::Atlas
        })
        .map(|t| t.name())
        .collect();
    let viewless: Vec<&str> = Technique::all()
        .into_iter()
        .filter(|t| t.info().fills != manyshadows::Fills::Atlas)
        .map(|t| t.name())
        .collect();
    bail!(
        "technique {technique} would take {} (caster triangle, view) pairs this frame ({} \
         views; it culls per view only after every triangle reached the view), more than the \
         {} this command starts unasked. Techniques that cull whole instances or clusters per \
         view first take at most {} here ({}); {} scale with pixels and lights instead of \
         views. Pass --insist to render it anyway.",
        g(work.triangle_views),
        work.views,
        g(MAX_UNASKED_TRIANGLE_VIEWS),
        g(work.after_instance_culling),
        culled.join(", "),
        viewless.join(", ")
    );
}

fn print_summary(s: &serde_json::Value) {
    let l = &s["lights"];
    let a = &s["atlas"];
    let w = &s["shadow_work"];
    println!("adapter      {}", s["adapter"].as_str().unwrap_or("?"));
    println!(
        "scene        {} ({} triangles, {} instances)",
        s["scene"].as_str().unwrap_or("?"),
        s["triangles"],
        s["instances"]
    );
    println!(
        "lights       {} ({} spot, {} point, {} directional; {} shadowed)",
        l["total"], l["spot"], l["point"], l["directional"], l["shadowed"]
    );
    println!(
        "shadows      {} views, technique {}, PCF {}",
        s["shadow_views"],
        s["technique"].as_str().unwrap_or("?"),
        s["pcf"].as_str().unwrap_or("?")
    );
    let v = &s["virtual"];
    if v.is_object() {
        let fit = &v["fit"];
        let capped = fit["capped_side"].as_u64().unwrap_or(0);
        let prev = v["prev_table_bytes"].as_u64().unwrap_or(0);
        println!(
            "virtual      {} faces of {} lights ({} off screen, no faces; {} faces needed by a sample, the rest get no pages), page table {} entries ({} KiB{}){}",
            fit["faces"], fit["lights"], fit["off_screen"], v["faces_in_use"], fit["table_entries"],
            v["table_bytes"].as_u64().unwrap_or(0) / 1024,
            if prev > 0 { format!(", and {} KiB for last frame's, kept for caching", prev / 1024) } else { String::new() },
            if capped > 0 { format!(", virtual sides capped at {capped}² to fit it") } else { String::new() }
        );
        let per_level = |key: &str| -> String {
            v[key]
                .as_array()
                .map(|a| a.iter().map(|x| x.to_string()).collect::<Vec<_>>())
                .unwrap_or_default()
                .join("/")
        };
        let denied = v["denied"].as_u64().unwrap_or(0);
        let unshadowed = v["unshadowed_faces"].as_u64().unwrap_or(0);
        let quarter = v["quarter_faces"].as_u64().unwrap_or(0);
        let mut tail = String::new();
        if denied > 0 {
            tail += &format!(
                "; {denied} pages did not fit the pool, their samples used coarser levels"
            );
        }
        if quarter > 0 {
            tail += &format!("; {quarter} faces share pool pages four to one at half resolution (the pool has fewer pages than faces in use)");
        }
        if unshadowed > 0 {
            tail += &format!("; {unshadowed} faces had no room even for a quarter page: unshadowed; raise --page-pool");
        }
        println!(
            "pages        {} resident in a pool of {} ({} drawn, {} kept from the last frame; {}x{} texels, {} MiB); asked by samples per level (coarsest first) {} (with their ancestors {}){tail}",
            v["resident"], v["pool_pages"], v["drawn"], v["kept"], v["pool_side"], v["pool_side"],
            v["pool_bytes"].as_u64().unwrap_or(0) >> 20,
            per_level("asked"),
            per_level("needed"),
        );
        let t = &v["tiles"];
        let count = |k: &str| t[k].as_u64().unwrap_or(0);
        if count("empty") + count("one_page") + count("known_page") + count("per_pixel") > 0 {
            println!(
                "marking      by 4x4-pixel tiles, (tile, light) pairs: {} need no page, {} one page marked once, {} a known page checked per pixel, {} marked per pixel ({} tiles whole)",
                count("empty"),
                count("one_page"),
                count("known_page"),
                count("per_pixel"),
                count("whole_tiles"),
            );
        }
    } else {
        let shrink = a["shrink_steps"].as_u64().unwrap_or(0);
        println!(
            "atlas        {0}x{0}, {1:.0}% filled{2}",
            a["size"],
            a["fill"].as_f64().unwrap_or(0.0) * 100.0,
            if shrink > 0 {
                format!(", maps shrunk {}x per side to fit", 1u64 << shrink)
            } else {
                String::new()
            }
        );
        let fit = &a["fit"];
        if fit["reduced"].as_u64().unwrap_or(0)
            + fit["unshadowed"].as_u64().unwrap_or(0)
            + fit["off_screen"].as_u64().unwrap_or(0)
            > 0
        {
            println!(
                "shadow fit   {} lights at full resolution, {} with smaller maps, {} unshadowed (no room), {} off screen (no maps needed)",
                fit["full"], fit["reduced"], fit["unshadowed"], fit["off_screen"]
            );
        }
    }
    // What the triangle count is: drawn (after instance or cluster culling), or handed to a
    // stage that culls each (triangle, view) itself.
    let culling = s["technique"]
        .as_str()
        .and_then(|t| t.parse::<Technique>().ok())
        .map(|t| t.info().culling);
    let what = match culling {
        Some(manyshadows::Culling::VertexStage) => {
            "triangle-views submitted (each culled per view in the vertex stage)"
        }
        Some(manyshadows::Culling::Threads) => {
            "triangle-views submitted (each culled per view by its setup thread)"
        }
        Some(manyshadows::Culling::Clusters) => {
            "triangle-views submitted (clusters culled per view in compute before drawing)"
        }
        _ => "triangles drawn",
    };
    let fills = s["technique"]
        .as_str()
        .and_then(|t| t.parse::<Technique>().ok())
        .map(|t| t.info().fills);
    match fills {
        // Pages are chosen, culled and drawn on the GPU: their counts are the pages line's.
        Some(manyshadows::Fills::Pages) => println!(
            "shadow work  {} pages drawn ({} kept from the last frame): {} (cluster, page) \
             pairs past the cluster cull, {} triangles drawn (culled per page on the GPU: \
             clusters, then triangles where the adapter counts draws)",
            s["virtual"]["drawn"],
            s["virtual"]["kept"],
            s["virtual"]["cluster_draws"],
            s["virtual"]["triangles"]
        ),
        Some(manyshadows::Fills::Rays) => println!(
            "shadow work  no shadow map: one ray per pixel and light of its cluster (or per \
             sampled light) in the lighting pass; {} top-level structure build(s)",
            w["passes"]
        ),
        _ => println!(
            "shadow work  {} passes, {} draws ({} instance-views culled on the CPU), {} {what}",
            w["passes"], w["draws"], w["culled_draws"], w["triangles"]
        ),
    }
    let c = &s["clusters"];
    if c.is_object() {
        let overflow = c["overflowed"].as_u64().unwrap_or(0);
        println!(
            "clusters     {}x{}x{} grid, {} occupied, lights per cluster {:.1} mean / {} max, {} of {} lights in view{}",
            c["tiles"][0], c["tiles"][1], c["slices"], c["occupied"],
            c["mean_lights"].as_f64().unwrap_or(0.0), c["max_lights"], c["lights_in_view"], l["total"],
            if overflow > 0 {
                format!("; {overflow} clusters overflowed the {} KiB list pool and looped over every light", c["pool_bytes"].as_u64().unwrap_or(0) / 1024)
            } else {
                String::new()
            }
        );
    } else {
        println!("clusters     off (every pixel loops over every light)");
    }
    match s["gpu_ms"].as_object() {
        Some(m) if !m.is_empty() => {
            let parts: Vec<String> = m
                .iter()
                .map(|(k, v)| format!("{k} {:.2} ms", v.as_f64().unwrap_or(0.0)))
                .collect();
            println!("GPU time     {}", parts.join(", "));
        }
        _ => println!("GPU time     (no timestamp queries on this adapter)"),
    }
    println!(
        "CPU record   {:.2} ms; frame wall {:.1} ms; total {:.1} s",
        s["cpu_record_ms"].as_f64().unwrap_or(0.0),
        s["frame_wall_ms"].as_f64().unwrap_or(0.0),
        s["total_wall_ms"].as_f64().unwrap_or(0.0) / 1e3
    );
    println!("wrote        {}", s["output"].as_str().unwrap_or("?"));
}

fn info(args: &GpuArgs) -> Result<()> {
    let req = args.request();
    let backends = requested_backends(&req);
    println!("backends searched: {backends:?}");
    let adapters = list_adapters(&req);
    if adapters.is_empty() {
        println!("adapters: none");
    } else {
        println!("adapters (best first):");
        for a in &adapters {
            println!("  - {}", describe_adapter(a));
        }
    }
    let ctx = GpuContext::new(&req)?;
    println!("chosen: {}", describe_adapter(&ctx.info));
    let l = ctx.limits();
    println!("limits:");
    println!(
        "  max_texture_dimension_2d        {}",
        l.max_texture_dimension_2d
    );
    println!(
        "  max_texture_array_layers        {}",
        l.max_texture_array_layers
    );
    println!(
        "  max_storage_buffer_binding_size {}",
        l.max_storage_buffer_binding_size
    );
    println!("  max_buffer_size                 {}", l.max_buffer_size);
    println!(
        "  max_storage_buffers_per_stage   {}",
        l.max_storage_buffers_per_shader_stage
    );
    println!(
        "  max_compute_workgroup_size      {}x{}x{}",
        l.max_compute_workgroup_size_x,
        l.max_compute_workgroup_size_y,
        l.max_compute_workgroup_size_z
    );
    println!(
        "  max_compute_invocations/group   {}",
        l.max_compute_invocations_per_workgroup
    );
    println!(
        "  max_multiview_view_count        {}",
        l.max_multiview_view_count
    );
    println!("optional features:");
    for f in feature_use(ctx.adapter.features()) {
        println!(
            "  [{}] {:<28} {}",
            if f.available { "x" } else { " " },
            f.name,
            f.purpose
        );
    }
    for (f, name) in manyshadows::gpu::context::UNUSED_EXPERIMENTAL {
        println!(
            "  [{}] {:<28} offered by the driver, not used yet",
            if ctx.adapter.features().contains(*f) {
                "x"
            } else {
                " "
            },
            name
        );
    }
    println!(
        "  max_tlas_instance_count         {}",
        l.max_tlas_instance_count
    );
    println!("techniques (what this device lacks for each):");
    for t in Technique::all() {
        let unmet: Vec<String> = t.info().unmet(&ctx).iter().map(|n| n.name()).collect();
        println!(
            "  {:<12} {}",
            t.name(),
            if unmet.is_empty() {
                "runs here".to_string()
            } else {
                format!("needs {}", unmet.join(", "))
            }
        );
    }
    println!(
        "shadow atlas: up to {0}x{0} (default cap {1})",
        l.max_texture_dimension_2d
            .min(manyshadows::DEFAULT_MAX_ATLAS_SIZE),
        manyshadows::DEFAULT_MAX_ATLAS_SIZE
    );
    Ok(())
}
