//! `manyshadows bench stereo`: a stereo frame's two G-buffers drawn in one pass against one
//! pass per eye (seed 000 calls stereo "a particularly good candidate" for layered rendering,
//! since both eyes see nearly the same triangles), with one mono eye beside them for scale.
//!
//! Every contender renders the same scene and lights; shadows are kept between frames (the
//! scene does not change), so after the warm-up a frame is G-buffer, clusters and lighting,
//! and the G-buffer stage is where the ways differ. The contenders of one scene and eye size
//! render interleaved, frame by frame (see [`crate::bench::harness`]).

use anyhow::Result;
use clap::Args;
use manyshadows::scene::builtin::LightMix;
use manyshadows::{EyePasses, RenderSettings, Renderer, Stage, Stereo};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, check_scene, ms, parse_screen, ratio, seeded_scene, Contender, Figure,
    FrameSubject, Harness, RunArgs,
};
use crate::bench::plot::PlotPoint;

/// Arguments of `manyshadows bench stereo`.
#[derive(Args, Debug, Clone)]
pub struct StereoArgs {
    /// Built-in scenes, comma-separated.
    #[arg(long, default_value = "atrium,dragon", value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Each eye's resolution WxH, comma-separated (a stereo frame is twice as wide).
    #[arg(
        long,
        default_value = "320x180,640x360,1280x720",
        value_delimiter = ','
    )]
    pub eyes: Vec<String>,
    /// Lights of the seeded layout (their shadows are drawn once and kept).
    #[arg(long, default_value_t = 8)]
    pub lights: usize,
    /// Eye separation in world units (the built-in scenes are in metres).
    #[arg(long, default_value_t = 0.065, allow_hyphen_values = true)]
    pub separation: f32,
    #[command(flatten)]
    pub run: RunArgs,
}

#[derive(Serialize)]
struct Record {
    scene: String,
    eye: String,
    method: String,
    gbuffer_gpu_ms: Option<f64>,
    frame_gpu_ms: Option<f64>,
    cpu_record_ms: f64,
    gbuffer_ratio_vs_per_eye: Option<f64>,
    frame_ratio_vs_per_eye: Option<f64>,
    gbuffer_runs: Vec<f64>,
}

/// The label of the baseline.
const BASELINE: &str = "per-eye";

/// Runs `manyshadows bench stereo`.
pub fn stereo(args: &StereoArgs) -> Result<()> {
    for s in &args.scenes {
        check_scene("--scenes", s)?;
    }
    check_counts("--lights", &[args.lights], 4096, "")?;
    if !(args.separation.is_finite() && args.separation >= 0.0) {
        anyhow::bail!("--separation must be a finite distance of at least 0");
    }
    let eyes: Vec<(String, (u32, u32))> = args
        .eyes
        .iter()
        .map(|s| parse_screen(s).map(|d| (s.clone(), d)))
        .collect::<Result<_>>()?;
    let h = Harness::start(&args.run)?;
    // The ways this adapter can draw, baseline first; the others are noted.
    let ways: Vec<EyePasses> = EyePasses::ALL
        .iter()
        .copied()
        .filter(|&p| match Renderer::stereo_unmet(&h.ctx, p) {
            Some(why) => {
                h.note(format!("{p} left out: {} lacks {why}", h.adapter));
                false
            }
            None => true,
        })
        .collect();
    h.plan(h.units(args.scenes.len() * eyes.len() * (ways.len() + 1), 1));
    let mut records = Vec::new();
    for scene_name in &args.scenes {
        let scene = seeded_scene(scene_name, args.lights, LightMix::All, None)?;
        for (eye, (w, hh)) in &eyes {
            h.message(format!("{scene_name}, eyes of {eye}"));
            let base = RenderSettings::default().with_height(*hh);
            let mut contenders = vec![Contender {
                label: "mono (one eye)".to_string(),
                subject: FrameSubject::new(Renderer::new(
                    &h.ctx,
                    &scene,
                    base.clone().with_width(*w),
                )?),
            }];
            for &way in &ways {
                let settings = base
                    .clone()
                    .with_width(2 * w)
                    .with_stereo(Some(Stereo::new(args.separation).with_passes(way)));
                contenders.push(Contender {
                    label: way.name().to_string(),
                    subject: FrameSubject::new(Renderer::new(&h.ctx, &scene, settings)?),
                });
            }
            let outcomes = h.compare(contenders, Some(BASELINE))?;
            let base_gbuffer = outcomes
                .iter()
                .find(|o| o.label == BASELINE)
                .and_then(|o| o.runs.stage(Stage::GBuffer));
            for o in outcomes {
                let gbuffer = o.runs.stage(Stage::GBuffer);
                records.push(Record {
                    scene: scene_name.clone(),
                    eye: eye.clone(),
                    method: o.label,
                    gbuffer_gpu_ms: gbuffer,
                    frame_gpu_ms: o.runs.gpu_ms(),
                    cpu_record_ms: o.runs.cpu_ms(),
                    gbuffer_ratio_vs_per_eye: ratio(gbuffer, base_gbuffer),
                    frame_ratio_vs_per_eye: o.gpu_ratio,
                    gbuffer_runs: o
                        .runs
                        .0
                        .iter()
                        .filter_map(|r| r.stages.get(Stage::GBuffer))
                        .collect(),
                });
            }
        }
    }
    use std::fmt::Write;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "== bench stereo: {} lights, eyes {} apart; median GPU ms (ratio to {BASELINE}), CPU ms to record\n   adapter: {}",
        args.lights, args.separation, h.adapter
    );
    let _ = writeln!(
        text,
        "{:<10} | {:>9} | {:<15} | {:>11} | {:>6} | {:>9} | {:>6} | {:>7}",
        "scene", "eye", "method", "G-buffer ms", "ratio", "frame ms", "ratio", "CPU ms"
    );
    let r2 = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.2}"));
    for r in &records {
        let _ = writeln!(
            text,
            "{:<10} | {:>9} | {:<15} | {:>11} | {:>6} | {:>9} | {:>6} | {:>7.2}",
            r.scene,
            r.eye,
            r.method,
            ms(r.gbuffer_gpu_ms),
            r2(r.gbuffer_ratio_vs_per_eye),
            ms(r.frame_gpu_ms),
            r2(r.frame_ratio_vs_per_eye),
            r.cpu_record_ms
        );
    }
    let points: Vec<PlotPoint> = records
        .iter()
        .map(|r| PlotPoint {
            variant: r.scene.clone(),
            resolution: 0,
            maps: parse_screen(&r.eye).map_or(0, |(w, _)| w as usize),
            method: r.method.clone(),
            gpu_ms: r.gbuffer_gpu_ms,
            // The lower panels show the whole frame.
            cpu_ms: r.frame_gpu_ms.unwrap_or(f64::NAN),
        })
        .collect();
    let fields = serde_json::json!({
        "lights": args.lights,
        "separation": args.separation,
        "records": records,
    });
    h.finish(
        text,
        fields,
        vec![Figure::ByMethod {
            prefix: "stereo",
            x_name: "eye width (pixels)",
            second: "whole-frame GPU ms",
            points,
        }],
    )
}
