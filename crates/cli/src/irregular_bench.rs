//! `manyshadows bench irregular`: the cost of alias-free (irregular) shadows against
//! `traditional` shadow maps, by number of lights and screen resolution, whole frames.
//!
//! Irregular shadow maps replace the shadow-map lookup in the lighting pass with a
//! per-pixel mask, so the fair measure is the frame's GPU time (G-buffer + shadows + lighting),
//! reported beside the shadow stage alone. `traditional@R` renders every light's maps at R²
//! per view (`@512`: equal grid resolution, `@2048`: the best quality that still fits the
//! atlas for a few dozen lights; the renderer shrinks maps that do not fit and says so).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::{GpuContext, RenderSettings, Renderer, Technique};
use serde::Serialize;

use crate::bench::{median, PlotPoint};
use crate::GpuArgs;

/// Arguments of `manyshadows bench irregular`.
#[derive(Args, Debug, Clone)]
pub struct IrregularArgs {
    /// Built-in scene.
    #[arg(long, default_value = "dragon")]
    pub scene: String,
    /// Light types of the seeded layout: all, spot, point or directional.
    #[arg(long, default_value = "all")]
    pub light_types: String,
    /// Numbers of lights, comma-separated.
    #[arg(long, default_value = "1,4,16,64", value_delimiter = ',')]
    pub lights: Vec<usize>,
    /// Screen resolutions WxH, comma-separated.
    #[arg(long, default_value = "1280x720,1920x1080", value_delimiter = ',')]
    pub screens: Vec<String>,
    /// Methods, comma-separated: `irregular` or `traditional@RES` (shadow-map side per view).
    #[arg(
        long,
        default_value = "irregular,traditional@512,traditional@2048",
        value_delimiter = ','
    )]
    pub methods: Vec<String>,
    /// Timed frames per configuration and method (medians are reported).
    #[arg(long, default_value = "3")]
    pub repeats: usize,
    /// Untimed frames first.
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    /// Directory for results.json, results.txt and the plots.
    #[arg(long, default_value = "bench-irregular")]
    pub out_dir: PathBuf,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Serialize)]
struct Record {
    screen: String,
    lights: usize,
    method: String,
    frame_gpu_ms: Option<f64>,
    shadow_gpu_ms: Option<f64>,
    frame_ms_runs: Vec<f64>,
    ratio_vs_traditional_512: Option<f64>,
    shadow_maps_shrunk: u32,
}

fn parse_screen(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once('x')
        .with_context(|| format!("--screens '{s}': expected WIDTHxHEIGHT, e.g. 1280x720"))?;
    let (w, h): (u32, u32) = (
        w.parse()
            .with_context(|| format!("--screens '{s}': bad width"))?,
        h.parse()
            .with_context(|| format!("--screens '{s}': bad height"))?,
    );
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        bail!("--screens '{s}': width and height must be 1..=8192");
    }
    Ok((w, h))
}

fn parse_method(s: &str) -> Result<(Technique, Option<u32>)> {
    match s.split_once('@') {
        None if s == "irregular" => Ok((Technique::Irregular, None)),
        Some(("traditional", r)) => {
            let r: u32 = r
                .parse()
                .with_context(|| format!("method '{s}': bad resolution"))?;
            if !(16..=8192).contains(&r) {
                bail!("method '{s}': resolution must be 16..=8192");
            }
            Ok((Technique::Traditional, Some(r)))
        }
        _ => bail!("unknown method '{s}' (irregular or traditional@RES, e.g. traditional@512)"),
    }
}

/// Runs `manyshadows bench irregular`.
pub fn irregular(args: &IrregularArgs) -> Result<()> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    let screens: Vec<(String, (u32, u32))> = args
        .screens
        .iter()
        .map(|s| parse_screen(s).map(|d| (s.clone(), d)))
        .collect::<Result<_>>()?;
    let methods: Vec<(String, (Technique, Option<u32>))> = args
        .methods
        .iter()
        .map(|m| parse_method(m).map(|p| (m.clone(), p)))
        .collect::<Result<_>>()?;
    if let Some(&n) = args.lights.iter().find(|&&n| n == 0 || n > 512) {
        bail!("--lights {n}: each count must be 1..=512");
    }
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let ctx = GpuContext::new(&args.gpu.request())?;
    let adapter = manyshadows::context::describe_adapter(&ctx.info);
    eprintln!("adapter: {adapter}");
    let total =
        (screens.len() * args.lights.len() * methods.len() * (args.repeats + args.warmup)) as u64;
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {msg} [{elapsed}, ~{eta} left]")
            .expect("valid template"),
    );
    let mut records = Vec::new();
    for (screen, (w, h)) in &screens {
        for &n in &args.lights {
            pb.set_message(format!("{screen}, {n} lights"));
            let mut per_method: Vec<(String, Vec<f64>, Vec<f64>, u32)> = Vec::new();
            for (name, (technique, res)) in &methods {
                let scene = builtin::build(
                    &args.scene,
                    &BuiltinOptions {
                        lights: Some(n),
                        seed: 1,
                        mix,
                        shadow_resolution: *res,
                        ..Default::default()
                    },
                )?;
                let settings = RenderSettings {
                    width: *w,
                    height: *h,
                    technique: *technique,
                    ..Default::default()
                };
                let mut r = Renderer::new(&ctx, &scene, settings)?;
                let shrunk = r.plan().layout.shrink_steps;
                let (mut frame_ms, mut shadow_ms) = (Vec::new(), Vec::new());
                for rep in 0..args.warmup + args.repeats {
                    let f = r.render()?;
                    if rep >= args.warmup && !f.timings.gpu_ms.is_empty() {
                        frame_ms.push(f.timings.gpu_ms.iter().map(|(_, v)| v).sum());
                        shadow_ms.extend(
                            f.timings
                                .gpu_ms
                                .iter()
                                .filter(|(k, _)| k == "shadows")
                                .map(|(_, v)| *v),
                        );
                    }
                    pb.inc(1);
                }
                per_method.push((name.clone(), frame_ms, shadow_ms, shrunk));
            }
            let med = |v: &Vec<f64>| (!v.is_empty()).then(|| median(v));
            let base = per_method
                .iter()
                .find(|m| m.0 == "traditional@512")
                .and_then(|m| med(&m.1));
            for (name, frame_ms, shadow_ms, shrunk) in per_method {
                let f = med(&frame_ms);
                records.push(Record {
                    screen: screen.clone(),
                    lights: n,
                    method: name,
                    frame_gpu_ms: f,
                    shadow_gpu_ms: med(&shadow_ms),
                    frame_ms_runs: frame_ms,
                    ratio_vs_traditional_512: f.zip(base).map(|(a, b)| a / b),
                    shadow_maps_shrunk: shrunk,
                });
            }
        }
    }
    pb.finish_and_clear();
    use std::fmt::Write;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "== bench irregular: scene {}, lights of type {}; median GPU ms per frame (ratio to traditional@512), shadow stage\n   adapter: {adapter}",
        args.scene, args.light_types
    );
    let _ = writeln!(
        text,
        "{:>10} | {:>6} | {:<18} | {:>10} | {:>8} | {:>10} | maps shrunk",
        "screen", "lights", "method", "frame ms", "ratio", "shadow ms"
    );
    for r in &records {
        let _ = writeln!(
            text,
            "{:>10} | {:>6} | {:<18} | {:>10} | {:>8} | {:>10} | {}",
            r.screen,
            r.lights,
            r.method,
            r.frame_gpu_ms.map_or("n/a".into(), |v| format!("{v:.1}")),
            r.ratio_vs_traditional_512
                .map_or(String::new(), |v| format!("{v:.2}")),
            r.shadow_gpu_ms.map_or("n/a".into(), |v| format!("{v:.1}")),
            if r.shadow_maps_shrunk > 0 {
                format!("{}x per side", 1u32 << r.shadow_maps_shrunk)
            } else {
                "-".into()
            }
        );
    }
    print!("{text}");
    std::fs::write(args.out_dir.join("results.txt"), &text)?;
    let json = serde_json::json!({
        "adapter": adapter,
        "scene": args.scene,
        "light_types": args.light_types,
        "repeats": args.repeats,
        "records": records,
    });
    std::fs::write(
        args.out_dir.join("results.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let points: Vec<PlotPoint> = records
        .iter()
        .map(|r| PlotPoint {
            variant: r.screen.clone(),
            resolution: 0,
            maps: r.lights,
            method: r.method.clone(),
            gpu_ms: r.frame_gpu_ms,
            // The lower panels show the shadow stage alone.
            cpu_ms: r.shadow_gpu_ms.unwrap_or(f64::NAN),
        })
        .collect();
    for p in crate::plot::plots(
        &points,
        &adapter,
        &args.out_dir,
        "irregular",
        "lights",
        "shadow-stage GPU ms",
    )? {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
