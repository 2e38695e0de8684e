//! `manyshadows bench estimate`: how well each technique's frame estimate
//! ([`Renderer::estimate_frame`]) predicts the frame. Per scene, screen, light count, light
//! size and method it renders whole frames (shadows redrawn every frame) and sets the GPU
//! milliseconds of each stage beside the estimate made before the first frame; the table gives
//! the ratio of the two, whose goal is within 3× either way (docs/benchmarks.md, "What a frame
//! will cost: `bench estimate`").

use anyhow::{bail, Result};
use clap::Args;
use manyshadows::scene::builtin::{self, LightMix};
use manyshadows::{FrameEstimate, RenderSettings, Renderer, Stage, Technique};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, check_scene, ms, parse_screen, seeded_scene, Contender, FrameSubject, Harness,
    RunArgs,
};

/// `manyshadows bench estimate --help`.
pub const LONG_ABOUT: &str = "\
How well each technique's estimate of its frame predicts the frame.

Before a frame is drawn, the renderer counts its work (pixels and camera triangles; the
(pixel, light) pairs in reach, from a coarse grid of camera rays; the (caster triangle, view)
pairs and atlas texels of the shadow maps; the rays of ray-traced shadows) and prices it with
costs per unit measured on lavapipe. `render`, `view` and `compare` say that estimate before
a long frame and refuse one past 10 minutes unless --insist. This bench renders each
configuration (warm-up, then --repeats frames with every shadow map redrawn) and sets the
measured GPU milliseconds per stage beside the estimate: `x` is measured over estimated.

A method is a technique's name (as --technique takes it), or NAME:kN for a technique that traces
shadow rays, with N sampled lights per pixel (--light-samples N). Configurations estimated past
--max-seconds are skipped (and listed).

Examples:
  manyshadows bench estimate                                   # 3 scenes, 8/64/1,024 lights, 320x180
  manyshadows bench estimate --methods virtual --sizes soft,hard
  manyshadows bench estimate --scenes dragon --screens 640x360";

/// Arguments of `manyshadows bench estimate`.
#[derive(Args, Debug, Clone)]
pub struct EstimateArgs {
    /// Built-in scenes, comma-separated.
    #[arg(
        long,
        default_value = "atrium,courtyard,terrain",
        value_delimiter = ','
    )]
    pub scenes: Vec<String>,
    /// Numbers of lights, comma-separated (1 to 16384 each).
    #[arg(long, default_value = "8,64,1024", value_delimiter = ',')]
    pub lights: Vec<usize>,
    /// Screen resolutions WxH, comma-separated.
    #[arg(long, default_value = "320x180", value_delimiter = ',')]
    pub screens: Vec<String>,
    /// Light sizes: `soft` (the scene's sizes) and/or `hard` (every light at size 0).
    #[arg(long, default_value = "soft", value_delimiter = ',')]
    pub sizes: Vec<String>,
    /// Methods, comma-separated: technique names, or NAME:kN for a technique that traces
    /// shadow rays with N sampled lights per pixel (default: every technique, and each that
    /// traces rays also at k1; those the adapter cannot run are skipped with a note).
    #[arg(long, value_delimiter = ',')]
    pub methods: Vec<String>,
    /// Skip configurations whose frame is estimated past this many seconds.
    #[arg(long, default_value_t = 60.0)]
    pub max_seconds: f64,
    /// Count and price each configuration's work without rendering it (the table's measured
    /// columns stay empty): to see the estimates, or to refit the costs against the
    /// measurements of an earlier run's results.json.
    #[arg(long)]
    pub estimate_only: bool,
    #[command(flatten)]
    pub run: RunArgs,
}

#[derive(Serialize)]
struct Record {
    scene: String,
    screen: String,
    lights: usize,
    sizes: String,
    method: String,
    /// The estimate, with the work it counted.
    estimate: FrameEstimate,
    /// Measured GPU ms: G-buffer, clusters, shadows (pages and acceleration structure
    /// included), lighting (denoise included); `None` when skipped.
    measured: Option<[f64; 4]>,
}

impl Record {
    fn measured_total(&self) -> Option<f64> {
        self.measured.map(|m| m.iter().sum())
    }
}

/// A method: the technique and its sampled lights per pixel.
fn parse_method(s: &str) -> Result<(Technique, u32)> {
    let (name, k) = match s.split_once(":k") {
        Some((n, k)) => (
            n,
            k.parse::<u32>()
                .ok()
                .filter(|k| (1..=64).contains(k))
                .ok_or_else(|| anyhow::anyhow!("--methods '{s}': N of :kN must be 1 to 64"))?,
        ),
        None => (s, 0),
    };
    let t = crate::args::parse_technique(name).map_err(anyhow::Error::msg)?;
    if k > 0 && t.info().fills != manyshadows::Fills::Rays {
        bail!("--methods '{s}': :kN samples lights with shadow rays; {t} traces none");
    }
    Ok((t, k))
}

/// Runs `manyshadows bench estimate`.
pub fn estimate(args: &EstimateArgs) -> Result<()> {
    check_counts("--lights", &args.lights, builtin::MAX_LIGHTS, "")?;
    for s in &args.scenes {
        check_scene("--scenes", s)?;
    }
    for s in &args.sizes {
        if s != "soft" && s != "hard" {
            bail!("--sizes '{s}': expected soft or hard");
        }
    }
    if args.max_seconds.is_nan() || args.max_seconds <= 0.0 {
        bail!("--max-seconds must be positive");
    }
    let screens: Vec<(String, (u32, u32))> = args
        .screens
        .iter()
        .map(|s| parse_screen(s).map(|d| (s.clone(), d)))
        .collect::<Result<_>>()?;
    let methods: Vec<String> = if args.methods.is_empty() {
        let mut m: Vec<String> = Technique::all()
            .iter()
            .map(|t| t.name().to_string())
            .collect();
        if let Some(t) = Technique::all()
            .into_iter()
            .find(|t| t.info().fills == manyshadows::Fills::Rays)
        {
            m.push(format!("{}:k1", t.name()));
        }
        m
    } else {
        args.methods.clone()
    };
    let parsed: Vec<(String, (Technique, u32))> = methods
        .iter()
        .map(|m| parse_method(m).map(|p| (m.clone(), p)))
        .collect::<Result<_>>()?;
    let h = Harness::start(&args.run)?;
    let per = h.units(1, 1);
    let configs =
        args.scenes.len() * screens.len() * args.lights.len() * args.sizes.len() * parsed.len();
    h.plan(per * configs as u64);
    let mut records = Vec::new();
    for scene_name in &args.scenes {
        for &n in &args.lights {
            let soft_scene = seeded_scene(scene_name, n, LightMix::All, None)?;
            for sizes in &args.sizes {
                let mut scene = soft_scene.clone();
                if sizes == "hard" {
                    scene.lights.iter_mut().for_each(|l| l.size = 0.0);
                }
                for (screen, (w, h_px)) in &screens {
                    for (label, (technique, k)) in &parsed {
                        let what = format!("{scene_name}, {screen}, {n} lights, {sizes}, {label}");
                        h.message(what.clone());
                        let mut settings = RenderSettings::default()
                            .with_width(*w)
                            .with_height(*h_px)
                            .with_technique(*technique)
                            .with_cache_shadows(false);
                        settings.rays.light_samples = *k;
                        let renderer = match Renderer::new(&h.ctx, &scene, settings) {
                            Ok(r) => r,
                            Err(e) => {
                                h.note(format!("{what}: skipped: {e}"));
                                h.advance(per);
                                continue;
                            }
                        };
                        let estimate = renderer.estimate_frame();
                        let mut record = Record {
                            scene: scene_name.clone(),
                            screen: screen.clone(),
                            lights: n,
                            sizes: sizes.clone(),
                            method: label.clone(),
                            estimate,
                            measured: None,
                        };
                        if args.estimate_only {
                            h.advance(per);
                            records.push(record);
                            continue;
                        }
                        if estimate.total_ms() > args.max_seconds * 1e3 {
                            h.note(format!(
                                "{what}: skipped: estimated {:.0} s, past --max-seconds",
                                estimate.total_ms() / 1e3
                            ));
                            h.advance(per);
                            records.push(record);
                            continue;
                        }
                        let out = h.compare(
                            vec![Contender {
                                label: label.clone(),
                                subject: FrameSubject::new(renderer),
                            }],
                            None,
                        )?;
                        let runs = &out[0].runs;
                        let st = |s: &[Stage]| s.iter().filter_map(|&s| runs.stage(s)).sum();
                        record.measured = Some([
                            st(&[Stage::GBuffer]),
                            st(&[Stage::Clusters]),
                            st(&[Stage::Pages, Stage::Accel, Stage::Shadows]),
                            st(&[Stage::Lighting, Stage::Denoise]),
                        ]);
                        records.push(record);
                    }
                }
            }
        }
    }
    let table = table(&records, &h.adapter, args);
    let fields = serde_json::json!({ "records": records });
    h.finish(table, fields, Vec::new())
}

fn table(records: &[Record], adapter: &str, args: &EstimateArgs) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "== bench estimate: each frame's estimate (before drawing) against the median of {} frames, GPU ms\n   adapter: {adapter}",
        args.run.repeats
    );
    let _ = writeln!(
        t,
        "{:<9} {:>8} {:>6} {:<4} {:<14} | {:>17} {:>17} {:>17} {:>17} | {:>9} {:>9} {:>6}",
        "scene",
        "screen",
        "lights",
        "size",
        "method",
        "gbuffer est/meas",
        "clusters",
        "shadows",
        "lighting",
        "frame est",
        "measured",
        "x"
    );
    let pair = |e: f64, m: Option<f64>| format!("{:>8}/{:<8}", format!("{e:.1}"), ms(m));
    let mut worst: f64 = 1.0;
    for r in records {
        let m = r.measured;
        let e = &r.estimate;
        let x = r.measured_total().map(|m| m / e.total_ms());
        if let Some(x) = x {
            worst = worst.max(x.max(1.0 / x));
        }
        let _ = writeln!(
            t,
            "{:<9} {:>8} {:>6} {:<4} {:<14} | {} {} {} {} | {:>9.1} {:>9} {:>6}",
            r.scene,
            r.screen,
            r.lights,
            r.sizes,
            r.method,
            pair(e.gbuffer_ms, m.map(|m| m[0])),
            pair(e.clusters_ms, m.map(|m| m[1])),
            pair(e.shadows_ms, m.map(|m| m[2])),
            pair(e.lighting_ms, m.map(|m| m[3])),
            e.total_ms(),
            ms(r.measured_total()),
            x.map_or("skip".into(), |x| format!("{x:.2}")),
        );
    }
    let _ = writeln!(
        t,
        "   x: measured frame / estimated frame; the furthest from 1 in this run: {worst:.2}x \
         (either way). Shadows include virtual pages and the acceleration structure; lighting \
         includes the denoiser."
    );
    t
}
