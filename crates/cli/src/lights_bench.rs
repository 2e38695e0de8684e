//! `manyshadows bench lights`: how a whole frame scales with the number of lights, from 16 to
//! 16,384, with clustered shading.
//!
//! Per scene, screen and light count it reports the GPU time of each stage (G-buffer, cluster
//! assignment, shadow generation, lighting), the lights per occupied cluster (mean and
//! maximum), how the shadow maps were fitted (full, reduced, unshadowed, off screen) and the
//! memory of the atlas and the cluster lists. Up to `--reference-up-to` lights it also times
//! the lighting pass looping over every light (`--light-loop all`) in the same run, so the
//! ratio clustered / all is measured, not inferred.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use manyshadows::clusters::LightLoop;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::{GpuContext, RenderSettings, Renderer, Technique};
use serde::Serialize;

use crate::bench::{ms, stage};
use crate::GpuArgs;

/// Arguments of `manyshadows bench lights`.
#[derive(Args, Debug, Clone)]
pub struct LightsArgs {
    /// Built-in scenes, comma-separated.
    #[arg(long, default_value = "atrium,dragon", value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Numbers of lights, comma-separated (1 to 16384 each).
    #[arg(
        long,
        default_value = "16,32,64,256,1024,4096,16384",
        value_delimiter = ','
    )]
    pub lights: Vec<usize>,
    /// Screen resolutions WxH, comma-separated.
    #[arg(long, default_value = "1280x720,1920x1080", value_delimiter = ',')]
    pub screens: Vec<String>,
    /// Light types of the seeded layout: all, spot, point or directional.
    #[arg(long, default_value = "all")]
    pub light_types: String,
    /// Shadow technique.
    #[arg(long, default_value = "traditional", value_parser = |s: &str| s.parse::<Technique>())]
    pub technique: Technique,
    /// Shadow-map side per view for every light (default: the layout's own).
    #[arg(long)]
    pub shadow_resolution: Option<u32>,
    /// Also time the lighting pass looping over every light, for counts up to this (0: never).
    #[arg(long, default_value_t = 1024)]
    pub reference_up_to: usize,
    /// Timed frames per configuration (medians are reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Untimed frames first.
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    /// Directory for results.json, results.txt and the plots.
    #[arg(long, default_value = "bench-lights")]
    pub out_dir: PathBuf,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Serialize, Default)]
struct Record {
    scene: String,
    screen: String,
    lights: usize,
    gbuffer_ms: Option<f64>,
    clusters_ms: Option<f64>,
    shadows_ms: Option<f64>,
    lighting_ms: Option<f64>,
    /// The lighting pass with every light in every pixel's loop (same run).
    lighting_all_ms: Option<f64>,
    lights_in_view: u32,
    occupied_clusters: u32,
    mean_lights_per_cluster: f64,
    max_lights_per_cluster: u32,
    overflowed_clusters: u32,
    shadow_views: usize,
    fit: manyshadows::shadow::FitReport,
    atlas_side: u32,
    atlas_mib: f64,
    cluster_lists_kib: f64,
    wall_ms: f64,
}

fn parse_screen(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once('x')
        .with_context(|| format!("--screens '{s}': expected WIDTHxHEIGHT, e.g. 1280x720"))?;
    let w: u32 = w
        .parse()
        .with_context(|| format!("--screens '{s}': bad width"))?;
    let h: u32 = h
        .parse()
        .with_context(|| format!("--screens '{s}': bad height"))?;
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        bail!("--screens '{s}': width and height must be 1..=8192");
    }
    Ok((w, h))
}

/// Runs `manyshadows bench lights`.
pub fn lights(args: &LightsArgs) -> Result<()> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    if let Some(&n) = args
        .lights
        .iter()
        .find(|&&n| n == 0 || n > builtin::MAX_LIGHTS)
    {
        bail!(
            "--lights {n}: each count must be 1..={}",
            builtin::MAX_LIGHTS
        );
    }
    for s in &args.scenes {
        if !builtin::SCENE_NAMES.contains(&s.as_str()) {
            bail!(
                "--scenes {s}: not a built-in scene ({})",
                builtin::SCENE_NAMES.join(", ")
            );
        }
    }
    let screens: Vec<(String, (u32, u32))> = args
        .screens
        .iter()
        .map(|s| parse_screen(s).map(|d| (s.clone(), d)))
        .collect::<Result<_>>()?;
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let ctx = GpuContext::new(&args.gpu.request())?;
    let adapter = manyshadows::context::describe_adapter(&ctx.info);
    eprintln!("adapter: {adapter}");
    let frames = (args.warmup + args.repeats) as u64;
    let total: u64 = args
        .lights
        .iter()
        .map(|&n| {
            if n <= args.reference_up_to {
                2 * frames
            } else {
                frames
            }
        })
        .sum::<u64>()
        * (args.scenes.len() * screens.len()) as u64;
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {msg} [{elapsed}, ~{eta} left]")
            .expect("valid template"),
    );
    let mut records = Vec::new();
    for scene_name in &args.scenes {
        for (screen, (w, h)) in &screens {
            for &n in &args.lights {
                pb.set_message(format!("{scene_name}, {screen}, {n} lights"));
                let scene = builtin::build(
                    scene_name,
                    &BuiltinOptions {
                        lights: Some(n),
                        seed: 1,
                        mix,
                        shadow_resolution: args.shadow_resolution,
                        ..Default::default()
                    },
                )?;
                let settings = RenderSettings {
                    width: *w,
                    height: *h,
                    technique: args.technique,
                    ..Default::default()
                };
                let run = |light_loop: LightLoop| -> Result<(Vec<manyshadows::Frame>, f64, _)> {
                    let started = std::time::Instant::now();
                    let mut r = Renderer::new(
                        &ctx,
                        &scene,
                        RenderSettings {
                            light_loop,
                            ..settings.clone()
                        },
                    )?;
                    let mut timed = Vec::new();
                    for rep in 0..args.warmup + args.repeats {
                        let f = r.render()?;
                        if rep >= args.warmup {
                            timed.push(f);
                        }
                        pb.inc(1);
                    }
                    let plan = r.plan().clone();
                    Ok((timed, started.elapsed().as_secs_f64() * 1e3, plan))
                };
                let (timed, wall_ms, plan) = run(LightLoop::Clustered)?;
                let lighting_all_ms = if n <= args.reference_up_to {
                    stage(&run(LightLoop::All)?.0, "lighting")
                } else {
                    None
                };
                let c = timed.last().and_then(|f| f.clusters).unwrap_or_default();
                let side = plan.layout.size;
                records.push(Record {
                    scene: scene_name.clone(),
                    screen: screen.clone(),
                    lights: n,
                    gbuffer_ms: stage(&timed, "gbuffer"),
                    clusters_ms: stage(&timed, "clusters"),
                    shadows_ms: stage(&timed, "shadows"),
                    lighting_ms: stage(&timed, "lighting"),
                    lighting_all_ms,
                    lights_in_view: c.lights_in_view,
                    occupied_clusters: c.occupied,
                    mean_lights_per_cluster: c.mean_lights,
                    max_lights_per_cluster: c.max_lights,
                    overflowed_clusters: c.overflowed,
                    shadow_views: plan.views.len(),
                    fit: plan.fit,
                    atlas_side: side,
                    atlas_mib: (side as f64).powi(2) * 4.0 / (1024.0 * 1024.0),
                    cluster_lists_kib: c.pool_bytes as f64 / 1024.0,
                    wall_ms,
                });
            }
        }
    }
    pb.finish_and_clear();
    let text = table(&records, &adapter, args);
    print!("{text}");
    std::fs::write(args.out_dir.join("results.txt"), &text)?;
    let json = serde_json::json!({
        "adapter": adapter,
        "light_types": args.light_types,
        "technique": args.technique.name(),
        "repeats": args.repeats,
        "warmup": args.warmup,
        "records": records,
    });
    std::fs::write(
        args.out_dir.join("results.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    for path in plots(&records, &adapter, args)? {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

fn table(records: &[Record], adapter: &str, args: &LightsArgs) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "== bench lights: median GPU ms per stage over {} frames, technique {}, light types {}\n   adapter: {adapter}",
        args.repeats,
        args.technique.name(),
        args.light_types
    );
    let _ = writeln!(
        t,
        "{:<8} {:>10} {:>6} | {:>8} {:>8} {:>9} {:>9} {:>10} | {:>6} {:>5} {:>4} | {:>6} {:>22} {:>7} {:>8}",
        "scene", "screen", "lights", "gbuffer", "clusters", "shadows", "lighting", "light(all)",
        "mean", "max", "ovf", "views", "full/reduced/none/off", "atlas", "lists"
    );
    for r in records {
        let _ = writeln!(
            t,
            "{:<8} {:>10} {:>6} | {:>8} {:>8} {:>9} {:>9} {:>10} | {:>6.1} {:>5} {:>4} | {:>6} {:>22} {:>5}Mi {:>6}Ki",
            r.scene,
            r.screen,
            r.lights,
            ms(r.gbuffer_ms),
            ms(r.clusters_ms),
            ms(r.shadows_ms),
            ms(r.lighting_ms),
            r.lighting_all_ms.map_or("-".into(), |v| format!("{v:.1}")),
            r.mean_lights_per_cluster,
            r.max_lights_per_cluster,
            r.overflowed_clusters,
            r.shadow_views,
            format!(
                "{}/{}/{}/{}",
                r.fit.full, r.fit.reduced, r.fit.unshadowed, r.fit.off_screen
            ),
            r.atlas_mib.round(),
            r.cluster_lists_kib.round(),
        );
    }
    let _ = writeln!(
        t,
        "   mean/max: lights per occupied cluster; ovf: clusters whose list did not fit the pool \
         (they loop over every light); fit: shadowed lights with full / reduced maps, left \
         unshadowed, off screen."
    );
    t
}

fn plots(records: &[Record], adapter: &str, args: &LightsArgs) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    for scene in &args.scenes {
        for screen in &args.screens {
            let rows: Vec<&Record> = records
                .iter()
                .filter(|r| &r.scene == scene && &r.screen == screen)
                .collect();
            let series = |name: &str, f: &dyn Fn(&Record) -> Option<f64>| {
                (
                    name.to_string(),
                    rows.iter()
                        .filter_map(|r| f(r).map(|v| (r.lights as f64, v)))
                        .collect::<Vec<_>>(),
                )
            };
            let specs = vec![
                (
                    "GPU ms per stage".to_string(),
                    "ms".to_string(),
                    vec![
                        series("gbuffer", &|r| r.gbuffer_ms),
                        series("clusters", &|r| r.clusters_ms),
                        series("shadows", &|r| r.shadows_ms),
                        series("lighting", &|r| r.lighting_ms),
                    ],
                ),
                (
                    "lighting pass: clustered vs every light".to_string(),
                    "ms".to_string(),
                    vec![
                        series("clustered", &|r| r.lighting_ms),
                        series("every light", &|r| r.lighting_all_ms),
                    ],
                ),
                (
                    "lights per occupied cluster".to_string(),
                    "lights".to_string(),
                    vec![
                        series("mean", &|r| Some(r.mean_lights_per_cluster)),
                        series("max", &|r| Some(r.max_lights_per_cluster as f64)),
                    ],
                ),
                (
                    "shadowed lights by map fit".to_string(),
                    "lights".to_string(),
                    vec![
                        series("full resolution", &|r| Some(r.fit.full as f64)),
                        series("reduced", &|r| Some(r.fit.reduced as f64)),
                        series("unshadowed", &|r| Some(r.fit.unshadowed as f64)),
                        series("off screen", &|r| Some(r.fit.off_screen as f64)),
                    ],
                ),
            ];
            let path = args.out_dir.join(format!("lights-{scene}-{screen}.png"));
            crate::plot::panels(
                &path,
                &format!("bench lights: {scene}, {screen} — {adapter}"),
                "lights",
                &specs,
            )?;
            written.push(path);
        }
    }
    Ok(written)
}
