//! `manyshadows bench omni`: point-light shadows in the atrium, cube maps against dual
//! paraboloids (seed 003), in several passes and in one.
//!
//! For each number of point lights, every method generates the shadow maps `warmup + repeats`
//! times (interleaved); reported: median GPU and CPU time, per light, and the atlas memory per
//! light. Methods are `MODE:TECHNIQUE` with MODE `cube` or `dp`: `cube:traditional` (six
//! passes per light), `cube:layered` / `cube:multiview` / `cube:gpu-driven` (one pass or
//! draw for all), `dp:traditional` (two passes per light), `dp:layered` (one draw).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::timing::GpuTimer;
use manyshadows::{
    GpuContext, GpuScene, RenderError, ShadowGenerator, ShadowOptions, ShadowPlan, Technique,
};
use serde::Serialize;

use crate::bench::{median, run_once, PlotPoint, Timed};
use crate::GpuArgs;

/// Arguments of `manyshadows bench omni`.
#[derive(Args, Debug, Clone)]
pub struct OmniArgs {
    /// Numbers of point lights, comma-separated.
    #[arg(long, default_value = "1,2,4,8,16", value_delimiter = ',')]
    pub lights: Vec<usize>,
    /// Shadow resolution per cube face (dual-paraboloid maps are twice this per side).
    #[arg(long, default_value_t = 256)]
    pub resolution: u32,
    /// Methods, comma-separated `MODE:TECHNIQUE` (MODE: cube or dp).
    #[arg(
        long,
        default_value = "cube:traditional,cube:layered,cube:multiview,cube:gpu-driven,dp:traditional,dp:layered",
        value_delimiter = ','
    )]
    pub methods: Vec<String>,
    /// Split every triangle this many times first (dual paraboloids need fine geometry; the
    /// timing then includes the larger triangle count for every method).
    #[arg(long, default_value_t = 0)]
    pub subdivide: u32,
    /// Timed runs per configuration and method.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Untimed runs first.
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    /// Directory for results.json, results.txt and the plots.
    #[arg(long, default_value = "bench-omni")]
    pub out_dir: PathBuf,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Serialize)]
struct Record {
    lights: usize,
    method: String,
    views: usize,
    atlas_size: u32,
    memory_bytes_per_light: f64,
    gpu_ms: Option<f64>,
    gpu_ms_per_light: Option<f64>,
    cpu_ms: f64,
    cpu_ms_per_light: f64,
    gpu_ms_runs: Vec<f64>,
    cpu_ms_runs: Vec<f64>,
    gpu_ratio_vs_cube_traditional: Option<f64>,
}

fn parse_method(s: &str) -> Result<(PointShadows, Technique)> {
    let (mode, t) = s
        .split_once(':')
        .with_context(|| format!("method '{s}': expected MODE:TECHNIQUE, e.g. dp:layered"))?;
    let mode = match mode {
        "cube" => PointShadows::Cube,
        "dp" | "dual-paraboloid" => PointShadows::DualParaboloid,
        other => bail!("method '{s}': unknown mode '{other}' (cube or dp)"),
    };
    let technique: Technique = t.parse().map_err(anyhow::Error::msg)?;
    if technique == Technique::Irregular {
        bail!("method '{s}': {}", manyshadows::shadow::IRREGULAR_NO_ATLAS);
    }
    Ok((mode, technique))
}

fn label(mode: PointShadows, t: Technique) -> String {
    let m = if mode == PointShadows::Cube {
        "cube"
    } else {
        "dp"
    };
    format!("{m}:{}", t.name())
}

/// Runs `manyshadows bench omni`.
pub fn omni(args: &OmniArgs) -> Result<()> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    if let Some(&n) = args.lights.iter().find(|&&n| n == 0 || n > 682) {
        bail!("--lights {n}: each count must be 1..=682 (6 views per cube light, 4096 views)");
    }
    if !(16..=4096).contains(&args.resolution) {
        bail!("--resolution {}: must be 16..=4096 texels", args.resolution);
    }
    let methods: Vec<(PointShadows, Technique)> = args
        .methods
        .iter()
        .map(|m| parse_method(m))
        .collect::<Result<_>>()?;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let ctx = GpuContext::new(&args.gpu.request())?;
    let adapter = manyshadows::context::describe_adapter(&ctx.info);
    let max_atlas =
        manyshadows::shadow::DEFAULT_MAX_ATLAS_SIZE.min(ctx.limits().max_texture_dimension_2d);
    eprintln!("adapter: {adapter}");
    let total: u64 = args.lights.iter().map(|&n| n as u64).sum::<u64>()
        * methods.len() as u64
        * (args.repeats + args.warmup) as u64;
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {msg} [{elapsed}, ~{eta} left]")
            .expect("valid template"),
    );
    let mut records: Vec<Record> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    for &n in &args.lights {
        pb.set_message(format!("{n} point lights"));
        let mut scene = builtin::build(
            "atrium",
            &BuiltinOptions {
                lights: Some(n),
                seed: 1,
                mix: LightMix::Point,
                shadow_resolution: Some(args.resolution),
                ..Default::default()
            },
        )?;
        scene.subdivide(args.subdivide)?;
        let gpu = GpuScene::new(&ctx, &scene)?;
        let mut gens: Vec<(String, ShadowGenerator, GpuTimer, u64)> = Vec::new();
        for &(mode, t) in &methods {
            let name = label(mode, t);
            let made = ctx.scoped(&format!("building {name}"), || {
                let plan = ShadowPlan::with_points(
                    &scene,
                    16.0 / 9.0,
                    max_atlas,
                    FitPolicy::Strict,
                    mode,
                )?;
                let texels: u64 = plan
                    .layout
                    .tiles
                    .iter()
                    .map(|t| t.size as u64 * t.size as u64)
                    .sum();
                ShadowGenerator::new(&ctx, &scene, &gpu, plan, t, ShadowOptions::default())
                    .map(|g| (g, texels))
            });
            match made {
                Ok((g, texels)) => gens.push((name, g, GpuTimer::new(&ctx), texels)),
                Err(e @ (RenderError::Unsupported(_) | RenderError::Atlas(_))) => {
                    let note = format!("{n} lights: {name} skipped: {e}");
                    pb.suspend(|| eprintln!("{note}"));
                    notes.push(note);
                    pb.inc(n as u64 * (args.repeats + args.warmup) as u64);
                }
                Err(e) => return Err(e.into()),
            }
        }
        let mut runs: Vec<Vec<Timed>> = gens.iter().map(|_| Vec::new()).collect();
        for rep in 0..args.warmup + args.repeats {
            for (k, (_, g, timer, _)) in gens.iter_mut().enumerate() {
                let (t, _) = run_once(&ctx, g, &gpu, timer)?;
                if rep >= args.warmup {
                    runs[k].push(t);
                }
                pb.inc(n as u64);
            }
        }
        let med = |k: usize, f: &dyn Fn(&Timed) -> Option<f64>| -> Option<f64> {
            let v: Vec<f64> = runs[k].iter().filter_map(f).collect();
            (!v.is_empty()).then(|| median(&v))
        };
        let base = gens
            .iter()
            .position(|(name, ..)| name == "cube:traditional");
        let base_gpu = base.and_then(|b| med(b, &|t| t.gpu_ms));
        for (k, (name, g, _, texels)) in gens.iter().enumerate() {
            let gpu_ms = med(k, &|t| t.gpu_ms);
            let cpu_ms = med(k, &|t| Some(t.cpu_ms)).unwrap_or(f64::NAN);
            records.push(Record {
                lights: n,
                method: name.clone(),
                views: g.plan.views.len(),
                atlas_size: g.atlas.size,
                memory_bytes_per_light: (*texels * 4) as f64 / n as f64,
                gpu_ms,
                gpu_ms_per_light: gpu_ms.map(|v| v / n as f64),
                cpu_ms,
                cpu_ms_per_light: cpu_ms / n as f64,
                gpu_ms_runs: runs[k].iter().filter_map(|t| t.gpu_ms).collect(),
                cpu_ms_runs: runs[k].iter().map(|t| t.cpu_ms).collect(),
                gpu_ratio_vs_cube_traditional: gpu_ms.zip(base_gpu).map(|(a, b)| a / b),
            });
        }
    }
    pb.finish_and_clear();

    use std::fmt::Write;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "== bench omni: atrium ({} triangles), point lights, {}² per cube face ({}² per paraboloid)\n   adapter: {adapter}",
        builtin::build("atrium", &BuiltinOptions { lights: Some(0), ..Default::default() })
            .map(|s| s.triangle_count())
            .unwrap_or(0)
            * 4usize.pow(args.subdivide),
        args.resolution,
        args.resolution * 2
    );
    let _ = writeln!(
        text,
        "{:>6} | {:<18} | {:>5} | {:>10} | {:>9} | {:>8} | {:>10} | {:>8}",
        "lights", "method", "views", "GPU ms", "per light", "vs cube6", "CPU ms", "MiB/light"
    );
    for r in &records {
        let _ = writeln!(
            text,
            "{:>6} | {:<18} | {:>5} | {:>10} | {:>9} | {:>8} | {:>10.2} | {:>8.2}",
            r.lights,
            r.method,
            r.views,
            r.gpu_ms.map_or("n/a".into(), |v| format!("{v:.2}")),
            r.gpu_ms_per_light
                .map_or("n/a".into(), |v| format!("{v:.2}")),
            r.gpu_ratio_vs_cube_traditional
                .map_or("".into(), |v| format!("{v:.2}")),
            r.cpu_ms,
            r.memory_bytes_per_light / (1024.0 * 1024.0)
        );
    }
    for n in &notes {
        let _ = writeln!(text, "note: {n}");
    }
    print!("{text}");
    std::fs::write(args.out_dir.join("results.txt"), &text)?;
    let json = serde_json::json!({
        "adapter": adapter,
        "backend": format!("{:?}", ctx.info.backend),
        "resolution_per_cube_face": args.resolution,
        "subdivide": args.subdivide,
        "repeats": args.repeats,
        "warmup": args.warmup,
        "notes": notes,
        "records": records,
    });
    let json_path = args.out_dir.join("results.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&json)?)?;
    let points: Vec<PlotPoint> = records
        .iter()
        .map(|r| PlotPoint {
            variant: "atrium".into(),
            resolution: args.resolution,
            maps: r.lights,
            method: r.method.clone(),
            gpu_ms: r.gpu_ms,
            cpu_ms: r.cpu_ms,
        })
        .collect();
    for p in crate::plot::plots(
        &points,
        &adapter,
        &args.out_dir,
        "omni",
        "point lights",
        crate::plot::CPU_TIME,
    )? {
        eprintln!("wrote {}", p.display());
    }
    eprintln!("wrote {}", json_path.display());
    Ok(())
}
