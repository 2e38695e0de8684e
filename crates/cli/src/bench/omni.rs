//! `manyshadows bench omni`: point-light shadows in the atrium, cube maps against dual
//! paraboloids (seed 003), in several passes and in one.
//!
//! For each number of point lights, every method generates the shadow maps `warmup + repeats`
//! times (interleaved); reported: median GPU and CPU time, per light, and the atlas memory per
//! light. Methods are `MODE:TECHNIQUE` with MODE `cube` or `dp`: `cube:traditional` (six
//! passes per light), `cube:layered` / `cube:multiview` / `cube:gpu-driven` (one pass or
//! draw for all), `dp:traditional` (two passes per light), `dp:layered` (one draw).

use anyhow::{bail, Context, Result};
use clap::Args;
use manyshadows::gpu_scene::instances::GpuScene;
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::shadows::atlas::generator::ShadowGenerator;
use manyshadows::shadows::plan::ShadowPlan;
use manyshadows::{RenderError, ShadowOptions, Technique};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, seeded_scene, Contender, Figure, Harness, RunArgs, ShadowSubject,
};
use crate::bench::plot::{PlotPoint, CPU_TIME};

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
        default_values_t = crate::techniques::omni_methods(),
        value_delimiter = ','
    )]
    pub methods: Vec<String>,
    /// Split every triangle this many times first (dual paraboloids need fine geometry; the
    /// timing then includes the larger triangle count for every method).
    #[arg(long, default_value_t = 0)]
    pub subdivide: u32,
    #[command(flatten)]
    pub run: RunArgs,
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
    let (mode, t) = s.split_once(':').with_context(|| {
        format!(
            "method '{s}': expected MODE:TECHNIQUE, e.g. {}",
            crate::techniques::omni_methods().join(" or ")
        )
    })?;
    let mode = match mode {
        "cube" => PointShadows::Cube,
        "dp" | "dual-paraboloid" => PointShadows::DualParaboloid,
        other => bail!("method '{s}': unknown mode '{other}' (cube or dp)"),
    };
    let technique: Technique = t.parse().map_err(anyhow::Error::msg)?;
    crate::techniques::require_atlas(&format!("method '{s}'"), technique)?;
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
    check_counts(
        "--lights",
        &args.lights,
        682,
        " (6 views per cube light, 4096 views)",
    )?;
    if !(16..=4096).contains(&args.resolution) {
        bail!("--resolution {}: must be 16..=4096 texels", args.resolution);
    }
    let methods: Vec<(PointShadows, Technique)> = args
        .methods
        .iter()
        .map(|m| parse_method(m))
        .collect::<Result<_>>()?;
    let h = Harness::start(&args.run)?;
    let ctx = &h.ctx;
    let max_atlas = manyshadows::DEFAULT_MAX_ATLAS_SIZE.min(ctx.limits().max_texture_dimension_2d);
    h.plan(
        args.lights
            .iter()
            .map(|&n| h.units(methods.len(), n as u64))
            .sum(),
    );
    let mut records: Vec<Record> = Vec::new();
    for &n in &args.lights {
        h.message(format!("{n} point lights"));
        let mut scene = seeded_scene("atrium", n, LightMix::Point, Some(args.resolution))?;
        scene.subdivide(args.subdivide)?;
        let gpu = GpuScene::new(ctx, &scene)?;
        let mut contenders = Vec::new();
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
                ShadowGenerator::new(ctx, &scene, &gpu, plan, t.info(), ShadowOptions::default())
            });
            match made {
                Ok(g) => contenders.push(Contender {
                    label: name,
                    subject: ShadowSubject::new(ctx, g, &gpu, n as u64),
                }),
                Err(e) if e.is_unsupported() || matches!(e, RenderError::Atlas(_)) => {
                    h.note(format!("{n} lights: {name} skipped: {e}"));
                    h.advance(h.units(1, n as u64));
                }
                Err(e) => return Err(e.into()),
            }
        }
        for o in h.compare(contenders, Some(&format!("cube:{}", Technique::default())))? {
            let g = &o.subject.gen;
            let texels: u64 = g
                .plan
                .layout
                .tiles
                .iter()
                .map(|t| t.size as u64 * t.size as u64)
                .sum();
            let gpu_ms = o.runs.gpu_ms();
            let cpu_ms = o.runs.cpu_ms();
            records.push(Record {
                lights: n,
                method: o.label,
                views: g.plan.views.len(),
                atlas_size: g.atlas.size,
                memory_bytes_per_light: (texels * 4) as f64 / n as f64,
                gpu_ms,
                gpu_ms_per_light: gpu_ms.map(|v| v / n as f64),
                cpu_ms,
                cpu_ms_per_light: cpu_ms / n as f64,
                gpu_ms_runs: o.runs.gpu_runs(),
                cpu_ms_runs: o.runs.cpu_runs(),
                gpu_ratio_vs_cube_traditional: o.gpu_ratio,
            });
        }
    }

    use std::fmt::Write;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "== bench omni: atrium ({} triangles), point lights, {}² per cube face ({}² per paraboloid)\n   adapter: {}",
        builtin::build("atrium", &BuiltinOptions { lights: Some(0), ..Default::default() })
            .map(|s| s.triangle_count())
            .unwrap_or(0)
            * 4usize.pow(args.subdivide),
        args.resolution,
        args.resolution * 2,
        h.adapter
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
    let fields = serde_json::json!({
        "resolution_per_cube_face": args.resolution,
        "subdivide": args.subdivide,
        "records": records,
    });
    h.finish(
        text,
        fields,
        vec![Figure::ByMethod {
            prefix: "omni",
            x_name: "point lights",
            second: CPU_TIME,
            points,
        }],
    )
}
