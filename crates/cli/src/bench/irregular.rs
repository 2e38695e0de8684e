//! `manyshadows bench irregular`: the cost of alias-free (irregular) shadows against
//! `traditional` shadow maps, by number of lights and screen resolution, whole frames.
//!
//! Irregular shadow maps replace the shadow-map lookup in the lighting pass with a
//! per-pixel mask, so the fair measure is the frame's GPU time (G-buffer + shadows + lighting),
//! reported beside the shadow stage alone. `traditional@R` renders every light's maps at R²
//! per view (`@512`: equal grid resolution, `@2048`: the best quality that still fits the
//! atlas for a few dozen lights; the renderer shrinks maps that do not fit and says so).
//! The methods of one screen and light count render interleaved, frame by frame (see
//! [`crate::bench::harness`]), so drift on the machine hits all of them alike.

use anyhow::{bail, Context, Result};
use clap::Args;
use manyshadows::scene::builtin::LightMix;
use manyshadows::Stage;
use manyshadows::{RenderSettings, Renderer, Technique};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, ms, parse_screen, seeded_scene, Contender, Figure, FrameSubject, Harness, RunArgs,
};
use crate::bench::plot::PlotPoint;

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
    /// Methods, comma-separated: a technique that fills no atlas by name, or an atlas technique
    /// at a shadow-map side per view (`TECHNIQUE@RES`). Default: the exact techniques, and the
    /// default technique at 512 and 2048 (the first of these is every ratio's baseline).
    #[arg(
        long,
        default_values_t = crate::techniques::exact_methods(),
        value_delimiter = ','
    )]
    pub methods: Vec<String>,
    #[command(flatten)]
    pub run: RunArgs,
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

fn parse_method(s: &str) -> Result<(Technique, Option<u32>)> {
    let (name, res) = match s.split_once('@') {
        Some((n, r)) => (n, Some(r)),
        None => (s, None),
    };
    let technique: Technique = name.parse().map_err(anyhow::Error::msg)?;
    let atlas = technique.info().fills == manyshadows::Fills::Atlas;
    match (atlas, res) {
        (false, None) => Ok((technique, None)),
        (true, Some(r)) => {
            let r: u32 = r
                .parse()
                .with_context(|| format!("method '{s}': bad resolution"))?;
            if !(16..=8192).contains(&r) {
                bail!("method '{s}': resolution must be 16..=8192");
            }
            Ok((technique, Some(r)))
        }
        (true, None) => bail!("method '{s}': an atlas technique needs a resolution, e.g. {s}@512"),
        (false, Some(_)) => {
            bail!("method '{s}': {technique} has no shadow-map resolution; name it alone")
        }
    }
}

/// Runs `manyshadows bench irregular`.
pub fn irregular(args: &IrregularArgs) -> Result<()> {
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
    check_counts("--lights", &args.lights, 512, "")?;
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    let h = Harness::start(&args.run)?;
    h.plan(h.units(screens.len() * args.lights.len() * methods.len(), 1));
    let mut records = Vec::new();
    for (screen, (w, h_px)) in &screens {
        for &n in &args.lights {
            h.message(format!("{screen}, {n} lights"));
            let mut contenders = Vec::new();
            for (name, (technique, res)) in &methods {
                let scene = seeded_scene(&args.scene, n, mix, *res)?;
                // Every repeat draws its maps anew (the scene does not change).
                let settings = RenderSettings::default()
                    .with_width(*w)
                    .with_height(*h_px)
                    .with_technique(*technique)
                    .with_cache_shadows(false);
                contenders.push(Contender {
                    label: name.clone(),
                    subject: FrameSubject::new(Renderer::new(&h.ctx, &scene, settings)?),
                });
            }
            for o in h.compare(contenders, Some(&format!("{}@512", Technique::default())))? {
                records.push(Record {
                    screen: screen.clone(),
                    lights: n,
                    method: o.label,
                    frame_gpu_ms: o.runs.gpu_ms(),
                    shadow_gpu_ms: o.runs.stage(Stage::Shadows),
                    frame_ms_runs: o.runs.gpu_runs(),
                    ratio_vs_traditional_512: o.gpu_ratio,
                    shadow_maps_shrunk: o.subject.renderer.plan().layout.shrink_steps,
                });
            }
        }
    }
    use std::fmt::Write;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "== bench irregular: scene {}, lights of type {}; median GPU ms per frame (ratio to {}@512), shadow stage\n   adapter: {}",
        args.scene,
        args.light_types,
        Technique::default(),
        h.adapter
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
            ms(r.frame_gpu_ms),
            r.ratio_vs_traditional_512
                .map_or(String::new(), |v| format!("{v:.2}")),
            ms(r.shadow_gpu_ms),
            if r.shadow_maps_shrunk > 0 {
                format!("{}x per side", 1u32 << r.shadow_maps_shrunk)
            } else {
                "-".into()
            }
        );
    }
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
    let fields = serde_json::json!({
        "scene": args.scene,
        "light_types": args.light_types,
        "records": records,
    });
    h.finish(
        text,
        fields,
        vec![Figure::ByMethod {
            prefix: "irregular",
            x_name: "lights",
            second: "shadow-stage GPU ms",
            points,
        }],
    )
}
