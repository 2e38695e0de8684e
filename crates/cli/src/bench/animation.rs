//! `manyshadows bench animation`: scenes that move as authored (the built-in skinned `crowd`,
//! or an animated glTF file), per technique, against the same scene frozen, in the same runs:
//! whole-frame and shadow GPU time, the views or pages each frame redraws (caching follows what
//! moved), and what bending the skinned and morphed meshes costs: on the GPU (the default:
//! the CPU evaluates the joints' matrices and morph weights, a compute pass bends the
//! vertices, timed as the `deform` stage) or on the CPU (every vertex bent and uploaded),
//! `--deform` choosing, both in one run with `--deform both`.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Result};
use clap::Args;
use manyshadows::scene::animation::Playing;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::{Deform, GpuContext, RenderSettings, Renderer, Stage, Technique};
use serde::Serialize;

use crate::bench::harness::{check_counts, ms, ratio, Contender, Harness, Run, RunArgs, Subject};

/// Arguments of `manyshadows bench animation`.
#[derive(Args, Debug, Clone)]
pub struct AnimationArgs {
    /// The built-in `crowd`, or an animated glTF file (its first animation plays).
    #[arg(long, default_value = "crowd")]
    pub scene: String,
    /// Tubes of the crowd (1 to 4096).
    #[arg(long, default_value_t = builtin::crowd::DEFAULT_COUNT)]
    pub crowd: usize,
    /// Lights of the seeded layout (a file keeps its own, or the rig it is given, without it).
    #[arg(long)]
    pub lights: Option<usize>,
    /// Techniques, comma-separated [default: every technique this adapter runs].
    #[arg(long, value_delimiter = ',')]
    pub techniques: Vec<Technique>,
    /// Seconds of animation between frames (1/30 s by default).
    #[arg(long, default_value_t = 1.0 / 30.0)]
    pub step: f32,
    /// The camera's frame (WxH).
    #[arg(long, default_value = "640x360")]
    pub screen: String,
    /// Where the skinned and morphed meshes are bent: `gpu` (a compute pass), `cpu` (every
    /// vertex on the CPU, uploaded), or `both` (each, beside the frozen scene, same runs).
    #[arg(long, default_value = "gpu")]
    pub deform: String,
    #[command(flatten)]
    pub run: RunArgs,
}

/// What a frame of an animated scene did.
#[derive(Clone, Debug, Default)]
pub(crate) struct Counters {
    /// Views (atlas techniques) or pages (virtual maps) drawn.
    drawn: u64,
    /// Of how many (views planned, pages resident).
    of: u64,
    /// CPU milliseconds evaluating the pose and handing it to the renderer.
    pose_ms: f64,
}

/// The contenders' states: label, where meshes bend (`None`: frozen).
const STATES: [(&str, Option<Deform>); 3] = [
    ("animated", Some(Deform::Gpu)),
    ("animated-cpu", Some(Deform::Cpu)),
    ("frozen", None),
];

/// Frames of a renderer whose scene moves by `step` seconds of its animation before each
/// (0: frozen).
struct Animated {
    renderer: Renderer,
    step: f32,
    time: f32,
}

impl Subject for Animated {
    type Counters = Counters;

    fn run(&mut self, _ctx: &GpuContext) -> Result<Run<Counters>> {
        let t0 = Instant::now();
        if self.step > 0.0 {
            self.time += self.step;
            self.renderer.set_time(Playing::One(0), self.time)?;
        }
        let pose_ms = t0.elapsed().as_secs_f64() * 1e3;
        let f = self.renderer.render()?;
        let (drawn, of) = match &f.virtual_maps {
            Some(v) => (u64::from(v.drawn), u64::from(v.resident)),
            None => (
                u64::from(f.shadow_stats.views_drawn),
                self.renderer.shadow_views() as u64,
            ),
        };
        Ok(Run {
            stages: f.timings.gpu_ms,
            cpu_ms: f.timings.cpu_record_ms,
            wall_ms: f.timings.wall_ms,
            counters: Counters { drawn, of, pose_ms },
        })
    }
}

#[derive(Serialize)]
struct Record {
    technique: String,
    /// Its shadows are rays (no views or pages to count).
    rays: bool,
    state: &'static str,
    /// Where its meshes bend (`None`: frozen).
    deform: Option<&'static str>,
    frame_gpu_ms: Option<f64>,
    /// The GPU's bending pass (`deform` stage; meshes bent on the GPU only).
    deform_gpu_ms: Option<f64>,
    /// Ray-traced shadows' acceleration structures built (`accel` stage: the bent meshes'
    /// bottom-level ones again, and the top-level one).
    accel_gpu_ms: Option<f64>,
    shadows_gpu_ms: Option<f64>,
    frame_ratio_vs_frozen: Option<f64>,
    drawn: u64,
    of: u64,
    pose_cpu_ms: f64,
    cpu_record_ms: f64,
}

/// Runs `manyshadows bench animation`.
pub fn animation(args: &AnimationArgs) -> Result<()> {
    check_counts("--crowd", &[args.crowd], builtin::crowd::MAX_COUNT, "")?;
    if let Some(n) = args.lights {
        check_counts("--lights", &[n], builtin::MAX_LIGHTS, "")?;
    }
    if !(args.step.is_finite() && args.step > 0.0 && args.step <= 10.0) {
        bail!(
            "--step {}: seconds between frames, above 0 and at most 10",
            args.step
        );
    }
    if !["gpu", "cpu", "both"].contains(&args.deform.as_str()) {
        bail!(
            "--deform {}: where meshes bend, gpu, cpu or both",
            args.deform
        );
    }
    let (w, h) = crate::bench::harness::parse_screen(&args.screen)?;
    let scene = if args.scene == "crowd" {
        let opts = BuiltinOptions {
            lights: Some(args.lights.unwrap_or(256)),
            mix: LightMix::All,
            ..BuiltinOptions::default()
        };
        builtin::crowd::build_with(args.crowd, &opts)
    } else {
        let ra = crate::args::RenderArgs {
            scene: args.scene.clone(),
            lights: args.lights,
            ..crate::args::RenderArgs::default()
        };
        crate::scenes::load_scene(&ra)?
    };
    if scene.animations.is_empty() {
        bail!(
            "--scene {}: nothing in it moves (the built-in `crowd`, or a glTF file with an \
             animation)",
            args.scene
        );
    }
    let scene = Arc::new(scene);
    let hh = Harness::start(&args.run)?;
    let asked = if args.techniques.is_empty() {
        Technique::all()
    } else {
        args.techniques.clone()
    };
    let techniques: Vec<Technique> = asked
        .into_iter()
        .filter(|t| {
            let unmet = t.info().unmet(&hh.ctx);
            if !unmet.is_empty() {
                let names: Vec<String> = unmet.iter().map(|n| n.name()).collect();
                hh.note(format!(
                    "{t} left out: {} lacks {}",
                    hh.adapter,
                    names.join(", ")
                ));
            }
            unmet.is_empty()
        })
        .collect();
    let states = if args.deform == "both" { 3 } else { 2 };
    hh.plan(hh.units(states * techniques.len(), 1));
    let mut records = Vec::new();
    for t in techniques {
        hh.message(format!("{t}"));
        let settings = RenderSettings::default()
            .with_width(w)
            .with_height(h)
            .with_technique(t);
        let contenders = STATES
            .into_iter()
            .filter(|(_, d)| match (args.deform.as_str(), d) {
                (_, None) | ("both", _) => true,
                ("cpu", Some(d)) => *d == Deform::Cpu,
                (_, Some(d)) => *d == Deform::Gpu,
            })
            .map(|(state, deform)| {
                let mut settings = settings.clone();
                settings.deform = deform.unwrap_or_default();
                Ok(Contender {
                    label: state.to_string(),
                    subject: Animated {
                        renderer: Renderer::new(&hh.ctx, &scene, settings)?,
                        step: if deform.is_some() { args.step } else { 0.0 },
                        time: 0.0,
                    },
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let outcomes = hh.compare(contenders, Some("frozen"))?;
        let frozen = outcomes
            .iter()
            .find(|o| o.label == "frozen")
            .and_then(|o| o.runs.gpu_ms());
        for o in outcomes {
            let runs = &o.runs.0;
            let median = |f: &dyn Fn(&Counters) -> f64| {
                let mut v: Vec<f64> = runs.iter().map(|r| f(&r.counters)).collect();
                v.sort_by(|a, b| a.total_cmp(b));
                v.get(v.len() / 2).copied().unwrap_or(0.0)
            };
            records.push(Record {
                technique: t.name().to_string(),
                rays: t.info().fills == manyshadows::Fills::Rays,
                state: STATES
                    .iter()
                    .find(|(l, _)| *l == o.label)
                    .map_or("frozen", |(l, _)| l),
                deform: STATES
                    .iter()
                    .find(|(l, _)| *l == o.label)
                    .and_then(|(_, d)| *d)
                    .map(|d| if d == Deform::Gpu { "gpu" } else { "cpu" }),
                frame_gpu_ms: o.runs.gpu_ms(),
                deform_gpu_ms: o.runs.stage(Stage::Deform),
                accel_gpu_ms: o.runs.stage(Stage::Accel),
                shadows_gpu_ms: o.runs.stage(Stage::Shadows),
                frame_ratio_vs_frozen: ratio(o.runs.gpu_ms(), frozen),
                drawn: median(&|c| c.drawn as f64) as u64,
                of: median(&|c| c.of as f64) as u64,
                pose_cpu_ms: median(&|c| c.pose_ms),
                cpu_record_ms: o.runs.cpu_ms(),
            });
        }
    }
    use std::fmt::Write;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "== bench animation: {} ({} instances, {} lights), camera {}, {:.4} s of animation a \
         frame against the same scene frozen (`animated`: meshes bent on the GPU, \
         `animated-cpu`: on the CPU); median GPU ms, the GPU's bending pass, ray tracing's \
         structures built, views or pages drawn a frame, CPU ms of the pose\n   adapter: {}",
        scene.name,
        scene.instances.len(),
        scene.lights.len(),
        args.screen,
        args.step,
        hh.adapter
    );
    let _ = writeln!(
        text,
        "{:<12} | {:<12} | {:>9} | {:>9} | {:>10} | {:>8} | {:>6} | {:>15} | {:>8} | {:>7}",
        "technique",
        "state",
        "frame ms",
        "deform ms",
        "shadows ms",
        "accel ms",
        "ratio",
        "drawn a frame",
        "pose ms",
        "CPU ms"
    );
    for r in &records {
        let _ = writeln!(
            text,
            "{:<12} | {:<12} | {:>9} | {:>9} | {:>10} | {:>8} | {:>6} | {:>15} | {:>8.2} | {:>7.2}",
            r.technique,
            r.state,
            ms(r.frame_gpu_ms),
            ms(r.deform_gpu_ms),
            ms(r.shadows_gpu_ms),
            ms(r.accel_gpu_ms),
            r.frame_ratio_vs_frozen
                .map_or(String::new(), |v| format!("{v:.2}")),
            if r.rays {
                "(rays)".to_string()
            } else {
                format!("{} of {}", r.drawn, r.of)
            },
            r.pose_cpu_ms,
            r.cpu_record_ms
        );
    }
    let fields = serde_json::json!({
        "scene": scene.name,
        "instances": scene.instances.len(),
        "lights": scene.lights.len(),
        "step_s": args.step,
        "screen": args.screen,
        "records": records,
    });
    hh.finish(text, fields, Vec::new())
}
