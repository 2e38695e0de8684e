//! `manyshadows bench probes`: reflection probes' faces drawn one G-buffer pass per face
//! against every face in one layered pass and each probe's six faces in one multiview pass
//! (seed 000 proposes layered rendering for reflection cube maps as for shadow maps), by probe
//! count and face size; whole frames with a caster moving, so every frame redraws every face.
//!
//! The contenders of one probe count and face size render interleaved, frame by frame (see
//! [`crate::bench::harness`]). The probes stage holds the faces' G-buffers (one pass each, or one
//! pass and a copy of each tile) and their lighting (the same in both).

use anyhow::Result;
use clap::Args;
use manyshadows::scene::builtin::LightMix;
use manyshadows::{ProbePasses, RenderSettings, Renderer, Stage};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, check_scene, ms, ratio, seeded_scene, Contender, Figure, FrameSubject, Harness,
    RunArgs,
};
use crate::bench::plot::PlotPoint;

/// Arguments of `manyshadows bench probes`.
#[derive(Args, Debug, Clone)]
pub struct ProbesArgs {
    /// Built-in scene.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// Numbers of probes, comma-separated (seeded along the scene's longest side, at most 64).
    #[arg(long, default_value = "1,4,16", value_delimiter = ',')]
    pub probes: Vec<usize>,
    /// Face sides in texels, comma-separated (8 to 1024).
    #[arg(long, default_value = "64,128", value_delimiter = ',')]
    pub sides: Vec<u32>,
    /// Lights of the seeded layout.
    #[arg(long, default_value_t = 8)]
    pub lights: usize,
    /// The camera's frame (WxH).
    #[arg(long, default_value = "320x180")]
    pub screen: String,
    #[command(flatten)]
    pub run: RunArgs,
}

#[derive(Serialize)]
struct Record {
    probes: usize,
    side: u32,
    method: String,
    probes_gpu_ms: Option<f64>,
    frame_gpu_ms: Option<f64>,
    cpu_record_ms: f64,
    probes_ratio_vs_per_face: Option<f64>,
    probes_ms_runs: Vec<f64>,
}

/// Runs `manyshadows bench probes`.
pub fn probes(args: &ProbesArgs) -> Result<()> {
    check_scene("--scene", &args.scene)?;
    check_counts(
        "--probes",
        &args.probes,
        manyshadows::scene::Probe::MAX_COUNT,
        "",
    )?;
    check_counts("--lights", &[args.lights], 4096, "")?;
    if let Some(s) = args
        .sides
        .iter()
        .find(|s| !(8..=manyshadows::scene::Probe::MAX_RESOLUTION).contains(*s))
    {
        anyhow::bail!("--sides {s}: a probe face is 8 to 1024 texels on a side");
    }
    let (w, hh) = crate::bench::harness::parse_screen(&args.screen)?;
    let h = Harness::start(&args.run)?;
    let ways: Vec<ProbePasses> = ProbePasses::ALL
        .iter()
        .copied()
        .filter(|&p| match Renderer::probe_passes_unmet(&h.ctx, p) {
            Some(why) => {
                h.note(format!("{p} left out: {} lacks {why}", h.adapter));
                false
            }
            None => true,
        })
        .collect();
    let base_name = ProbePasses::PerFace.name();
    h.plan(h.units(args.probes.len() * args.sides.len() * ways.len(), 1));
    let mut records = Vec::new();
    let base_scene = seeded_scene(&args.scene, args.lights, LightMix::All, None)?;
    let caster = base_scene.smallest_caster();
    for &n in &args.probes {
        for &side in &args.sides {
            h.message(format!("{n} probes of {side}²"));
            let mut scene = base_scene.clone();
            scene.probes = scene.seeded_probes(n, side);
            let mut contenders = Vec::new();
            for &way in &ways {
                let settings = RenderSettings::default()
                    .with_width(w)
                    .with_height(hh)
                    .with_probe_passes(way);
                let moving = caster.map(|k| (k, scene.instances[k].transform));
                contenders.push(Contender {
                    label: way.name().to_string(),
                    subject: FrameSubject::moving(Renderer::new(&h.ctx, &scene, settings)?, moving),
                });
            }
            let outcomes = h.compare(contenders, Some(base_name))?;
            let base = outcomes
                .iter()
                .find(|o| o.label == base_name)
                .and_then(|o| o.runs.stage(Stage::Probes));
            for o in outcomes {
                let probes = o.runs.stage(Stage::Probes);
                records.push(Record {
                    probes: n,
                    side,
                    method: o.label,
                    probes_gpu_ms: probes,
                    frame_gpu_ms: o.runs.gpu_ms(),
                    cpu_record_ms: o.runs.cpu_ms(),
                    probes_ratio_vs_per_face: ratio(probes, base),
                    probes_ms_runs: o
                        .runs
                        .0
                        .iter()
                        .filter_map(|r| r.stages.get(Stage::Probes))
                        .collect(),
                });
            }
        }
    }
    use std::fmt::Write;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "== bench probes: scene {}, {} lights, a caster moving (every face redrawn each frame), camera {}; median GPU ms (ratio to {base_name}), CPU ms to record\n   adapter: {}",
        args.scene, args.lights, args.screen, h.adapter
    );
    let _ = writeln!(
        text,
        "{:>6} | {:>5} | {:<10} | {:>10} | {:>6} | {:>9} | {:>7}",
        "probes", "side", "method", "probes ms", "ratio", "frame ms", "CPU ms"
    );
    for r in &records {
        let _ = writeln!(
            text,
            "{:>6} | {:>5} | {:<10} | {:>10} | {:>6} | {:>9} | {:>7.2}",
            r.probes,
            r.side,
            r.method,
            ms(r.probes_gpu_ms),
            r.probes_ratio_vs_per_face
                .map_or(String::new(), |v| format!("{v:.2}")),
            ms(r.frame_gpu_ms),
            r.cpu_record_ms
        );
    }
    let points: Vec<PlotPoint> = records
        .iter()
        .map(|r| PlotPoint {
            variant: format!("{}x{}", r.side, r.side),
            resolution: 0,
            maps: r.probes,
            method: r.method.clone(),
            gpu_ms: r.probes_gpu_ms,
            cpu_ms: r.cpu_record_ms,
        })
        .collect();
    let fields = serde_json::json!({
        "scene": args.scene,
        "lights": args.lights,
        "screen": args.screen,
        "records": records,
    });
    h.finish(
        text,
        fields,
        vec![Figure::ByMethod {
            prefix: "probes",
            x_name: "probes",
            second: crate::bench::plot::CPU_TIME,
            points,
        }],
    )
}
