//! `manyshadows bench soft`: what soft shadows cost. Whole frames of the same scene and lights
//! rendered with the lights' sizes (percentage-closer soft shadows: a blocker search and a
//! filter of `--taps` taps each per shadowed pixel and sized light) against the same lights
//! rendered hard (size 0, the default 2×2 PCF), per technique and light count, interleaved
//! frame by frame in one run (see [`crate::bench::harness`]), so the ratio PCSS / hard is measured,
//! not inferred.
//!
//! The shadow maps are the same both ways (PCSS reads the depth the hard test reads); the
//! filter runs in the lighting pass, so the lighting stage carries the difference. Virtual
//! maps may also make coarser pages resident for penumbrae wider than `--max-penumbra`.

use anyhow::{bail, Result};
use clap::Args;
use manyshadows::scene::builtin::{self, LightMix};
use manyshadows::scene::Scene;
use manyshadows::{RenderSettings, Renderer, SoftShadows, Stage, Technique};
use serde::Serialize;

use crate::args::LightSizeArgs;
use crate::bench::harness::{
    check_counts, check_scene, ms, seeded_scene, Contender, FrameCounters, FrameSubject, Harness,
    RunArgs, Runs,
};

/// `manyshadows bench soft --help`.
pub const LONG_ABOUT: &str = "\
What soft shadows cost: whole frames with percentage-closer soft shadows (PCSS) against the
same frames with hard shadows (the lights at size 0, 2x2 PCF), per technique and light count.

For each shadowed pixel and sized light, PCSS reads --taps depths to find the blockers (their
mean distance sets the penumbra's width) and compares --taps more over that width; a hard
light takes one 2x2 comparison. The shadow maps are the same both ways: the difference is in
the lighting pass (and, for virtual maps, any coarser pages a wide penumbra asks for). Every
contender of a technique and light count renders frame by frame in turn (round-robin, after
--warmup frames), shadow maps redrawn every frame; the table gives median GPU ms per stage and
the ratio of each frame to the hard frame of the same run.

The lights keep the scene's sizes (the built-in scenes: 2% of each light's range, the sun
0.53 degrees) unless --light-size / --sun-size say otherwise; a size changes how wide the
penumbrae are, not how many taps are read.

Examples:
  manyshadows bench soft                                         # atrium, 64 and 1,024 lights, 1280x720
  manyshadows bench soft --width 640 --height 360 --taps 8,16,32 # what the taps cost
  manyshadows bench soft --techniques virtual --lights 4096 --light-size 0.2";

/// Arguments of `manyshadows bench soft`.
#[derive(Args, Debug, Clone)]
pub struct SoftArgs {
    /// Built-in scene.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// Numbers of lights, comma-separated (1 to 16384 each).
    #[arg(long, default_value = "64,1024", value_delimiter = ',')]
    pub lights: Vec<usize>,
    /// Light types of the seeded layout: all, spot, point or directional.
    #[arg(long, default_value = "all")]
    pub light_types: String,
    /// Techniques, comma-separated (default: the registry's default atlas technique and the
    /// techniques that fill a page pool).
    #[arg(long, value_delimiter = ',', value_parser = crate::args::parse_technique)]
    pub techniques: Vec<Technique>,
    /// Taps of the blocker search and of the filter, comma-separated: one PCSS contender per
    /// entry, `N` for N of each or `B/F` (1 to 64 each; the renderer's default is 16).
    #[arg(long, default_value = "16", value_delimiter = ',', value_parser = parse_tap_pair)]
    pub taps: Vec<(u32, u32)>,
    /// Largest penumbra radius, shadow texels (1 to 256).
    #[arg(long, default_value_t = SoftShadows::default().max_penumbra)]
    pub max_penumbra: f32,
    #[command(flatten)]
    pub light_sizes: LightSizeArgs,
    /// Image width.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    #[command(flatten)]
    pub run: RunArgs,
}

/// One contender's medians.
#[derive(Serialize, Clone)]
struct Side {
    /// `hard` or `pcss-<taps>`.
    method: String,
    /// Taps of the search and of the filter; 0 for hard.
    blocker_taps: u32,
    filter_taps: u32,
    pages_ms: Option<f64>,
    shadows_ms: Option<f64>,
    lighting_ms: Option<f64>,
    /// Median over the frames of the stages' sum.
    frame_ms: Option<f64>,
    /// Frame over the hard frame's, same run.
    ratio: Option<f64>,
    /// Lighting over the hard frame's lighting, same run's medians.
    lighting_ratio: Option<f64>,
}

#[derive(Serialize)]
struct Record {
    technique: String,
    lights: usize,
    /// Lights with a size (spot and point radius, sun diameter) in the PCSS frames.
    sized_lights: usize,
    sides: Vec<Side>,
}

/// Runs `manyshadows bench soft`.
pub fn soft(args: &SoftArgs) -> Result<()> {
    check_counts("--lights", &args.lights, builtin::MAX_LIGHTS, "")?;
    check_scene("--scene", &args.scene)?;
    if args.taps.is_empty() {
        bail!("--taps needs at least one count");
    }
    for &(b, f) in &args.taps {
        SoftShadows::default()
            .with_blocker_taps(b)
            .with_filter_taps(f)
            .validate()
            .map_err(|e| anyhow::anyhow!("--taps {}: {e}", tap_label(b, f)))?;
    }
    SoftShadows::default()
        .with_max_penumbra(args.max_penumbra)
        .validate()
        .map_err(|e| anyhow::anyhow!("--max-penumbra: {e}"))?;
    let sizes = args.light_sizes.sizes()?;
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    let h = Harness::start(&args.run)?;
    let asked = if args.techniques.is_empty() {
        std::iter::once(Technique::default())
            .chain(
                Technique::all()
                    .into_iter()
                    .filter(|t| t.info().fills == manyshadows::Fills::Pages),
            )
            .collect()
    } else {
        args.techniques.clone()
    };
    let mut techniques: Vec<Technique> = Vec::new();
    for &t in &asked {
        if techniques.contains(&t) {
            continue;
        }
        if !t.info().soft_shadows {
            h.note(format!("{t} renders sized lights hard: not measured"));
            continue;
        }
        if let Some(why) = t.info().unmet(&h.ctx).first() {
            h.note(format!("{t} does not run here: it needs {}", why.name()));
            continue;
        }
        techniques.push(t);
    }
    let contenders = 1 + args.taps.len();
    h.plan(h.units(contenders * techniques.len() * args.lights.len(), 1));
    let mut records = Vec::new();
    for &n in &args.lights {
        let mut scene = seeded_scene(&args.scene, n, mix, None)?;
        sizes.apply(&mut scene.lights);
        let sized_lights = scene.lights.iter().filter(|l| l.size > 0.0).count();
        if sized_lights == 0 {
            h.note(format!(
                "{} with {n} lights has no sized light: PCSS and hard are the same frame",
                args.scene
            ));
        }
        let mut hard = scene.clone();
        for l in &mut hard.lights {
            l.size = 0.0;
        }
        for &technique in &techniques {
            h.message(format!("{}, {n} lights, {technique}", args.scene));
            let out = h.compare(
                contenders_for(&h, args, technique, &scene, &hard)?,
                Some("hard"),
            )?;
            let base_lighting = out[0].runs.stage(Stage::Lighting);
            // The contenders: hard, then one per `--taps` entry in order.
            let taps = std::iter::once((0, 0)).chain(args.taps.iter().copied());
            let sides = out
                .iter()
                .zip(taps)
                .map(|(o, t)| side(&o.label, t, &o.runs, o.gpu_ratio, base_lighting))
                .collect();
            records.push(Record {
                technique: technique.name().into(),
                lights: n,
                sized_lights,
                sides,
            });
        }
    }
    let table = table(&records, &h.adapter, args);
    let fields = serde_json::json!({
        "scene": args.scene,
        "screen": [args.width, args.height],
        "light_types": args.light_types,
        "max_penumbra": args.max_penumbra,
        "records": records,
    });
    h.finish(table, fields, Vec::new())
}

/// The hard frame (`hard`, the baseline) and one PCSS frame per `--taps` count of `technique`.
fn contenders_for(
    h: &Harness,
    args: &SoftArgs,
    technique: Technique,
    sized: &Scene,
    hard: &Scene,
) -> Result<Vec<Contender<FrameSubject>>> {
    // Every repeat draws its maps anew (the scene does not change).
    let base = RenderSettings::default()
        .with_width(args.width)
        .with_height(args.height)
        .with_technique(technique)
        .with_cache_shadows(false);
    let mut out = vec![Contender {
        label: "hard".into(),
        subject: FrameSubject::new(
            Renderer::new(&h.ctx, hard, base.clone()).map_err(crate::args::flag_error)?,
        ),
    }];
    for &(b, f) in &args.taps {
        let soft = SoftShadows::default()
            .with_blocker_taps(b)
            .with_filter_taps(f)
            .with_max_penumbra(args.max_penumbra);
        let settings = base.clone().with_soft(soft);
        out.push(Contender {
            label: format!("pcss-{}", tap_label(b, f)),
            subject: FrameSubject::new(
                Renderer::new(&h.ctx, sized, settings).map_err(crate::args::flag_error)?,
            ),
        });
    }
    Ok(out)
}

/// `--taps`' entry: `N` (both) or `B/F`.
fn parse_tap_pair(s: &str) -> Result<(u32, u32), String> {
    crate::light_args::tap_pair(s, '/', "taps as N (search and filter) or B/F (e.g. 32/16)")
}

/// `16` for 16 of each, `32/16` otherwise.
fn tap_label(b: u32, f: u32) -> String {
    if b == f {
        b.to_string()
    } else {
        format!("{b}/{f}")
    }
}

fn side(
    label: &str,
    taps: (u32, u32),
    runs: &Runs<FrameCounters>,
    ratio: Option<f64>,
    base_lighting: Option<f64>,
) -> Side {
    let lighting_ms = runs.stage(Stage::Lighting);
    Side {
        method: label.into(),
        blocker_taps: taps.0,
        filter_taps: taps.1,
        pages_ms: runs.stage(Stage::Pages),
        shadows_ms: runs.stage(Stage::Shadows),
        lighting_ms,
        frame_ms: runs.gpu_ms(),
        ratio,
        lighting_ratio: lighting_ms.zip(base_lighting).map(|(a, b)| a / b),
    }
}

fn table(records: &[Record], adapter: &str, args: &SoftArgs) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "== bench soft: {} at {}x{}, light types {}; median GPU ms over {} frames, PCSS and hard \
         in the same run\n   adapter: {adapter}",
        args.scene, args.width, args.height, args.light_types, args.run.repeats
    );
    let _ = writeln!(
        t,
        "{:<12} {:>6} {:>6} | {:<11} | {:>9} {:>9} {:>9} | {:>6} {:>8}",
        "technique",
        "lights",
        "sized",
        "method",
        "shadows",
        "lighting",
        "frame",
        "ratio",
        "lighting"
    );
    for r in records {
        for s in &r.sides {
            let shadows = match (s.pages_ms, s.shadows_ms) {
                (Some(p), Some(sh)) => Some(p + sh),
                (p, sh) => p.or(sh),
            };
            let ratio = |v: Option<f64>| v.map_or("n/a".into(), |v| format!("{v:.2}"));
            let _ = writeln!(
                t,
                "{:<12} {:>6} {:>6} | {:<11} | {:>9} {:>9} {:>9} | {:>6} {:>8}",
                r.technique,
                r.lights,
                r.sized_lights,
                s.method,
                ms(shadows),
                ms(s.lighting_ms),
                ms(s.frame_ms),
                ratio(s.ratio),
                ratio(s.lighting_ratio),
            );
        }
    }
    let _ = writeln!(
        t,
        "   hard: every light at size 0, 2x2 PCF; pcss-B/F (pcss-N: N of each): the lights' \
         sizes, B depths of the blocker search and F filter taps; shadows: the maps (virtual: pages + their drawing); frame: sum of the \
         stages; ratio: frame / the hard frame, lighting: lighting / the hard lighting, same run."
    );
    t
}
