//! The measuring loop every `manyshadows bench …` shares, written once.
//!
//! A bench describes what it compares and how to report it; the harness does the rest:
//!
//! - [`Harness::start`]: checks `--repeats`, creates `--out-dir`, opens the GPU and names the
//!   adapter, and owns the progress bar and the notes (skipped configurations and the like).
//! - [`Harness::compare`]: for one configuration (a map count, a light count, a screen …) runs
//!   every [`Contender`] `warmup + repeats` times, **round-robin** (run *k* of every contender
//!   before run *k + 1* of any), so drift on the machine hits all of them alike; keeps the
//!   timed runs ([`Runs`]: medians of GPU time per stage and in total, CPU and wall time, the
//!   work counters of the last run) and the ratios of each median to the baseline's **from
//!   the same runs**.
//! - [`Harness::finish`]: prints the bench's table (notes and the run's peak resident memory
//!   appended), writes `results.txt`, `results.json` (`adapter`, `backend`, `warmup`,
//!   `repeats`, `notes`, `peak_resident_bytes`, then the bench's own fields and records) and
//!   draws the plots.
//!
//! What is measured is a [`Subject`]: a shadow generator alone ([`ShadowSubject`]: `bench
//! layered`, `bench omni`) or whole frames of a renderer ([`FrameSubject`]: `bench irregular`,
//! `bench lights`, `bench virtual`, `bench shadows`, `bench soft`, `bench stereo`, `bench
//! probes`, `bench estimate`; with a moving caster in `bench virtual`, `bench shadows` and
//! `bench probes`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use manyshadows::gpu::timing::{GpuTimer, GpuTimes, PipelineCounts, Stage};
use manyshadows::gpu_scene::instances::GpuScene;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::Scene;
use manyshadows::shadows::atlas::generator::ShadowGenerator;
use manyshadows::wgpu;
use manyshadows::ClusterStats;
use manyshadows::VirtualStats;
use manyshadows::{GpuContext, Renderer, ShadowStats};
use serde::Serialize;

use crate::args::GpuArgs;
use crate::bench::plot::{Panel, PlotPoint};

/// The options every comparison bench takes. Each `bench` subcommand sets its own default of
/// `--out-dir` and, where it differs, of `--repeats` (main.rs).
#[derive(Args, Debug, Clone)]
pub struct RunArgs {
    /// Timed runs of each method per configuration, interleaved round-robin with the other
    /// methods' runs so drift hits all alike (medians are reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Untimed runs of each method per configuration first (interleaved the same way).
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Where a bench writes and which GPU it measures.
#[derive(Args, Debug, Clone)]
pub struct OutputArgs {
    /// Directory for results.json, results.txt and the plots.
    #[arg(long)]
    pub out_dir: PathBuf,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Untimed and timed runs per contender and configuration.
#[derive(Clone, Copy, Debug, Serialize)]
pub(crate) struct Schedule {
    /// Untimed runs first.
    pub warmup: usize,
    /// Timed runs (medians are reported).
    pub repeats: usize,
}

impl Schedule {
    fn runs(&self) -> usize {
        self.warmup + self.repeats
    }
}

/// One run of a [`Subject`].
#[derive(Clone, Debug)]
pub(crate) struct Run<C> {
    /// GPU milliseconds per stage (timestamp queries); empty without them.
    pub stages: GpuTimes,
    /// CPU milliseconds to record and submit.
    pub cpu_ms: f64,
    /// Wall milliseconds until the results are back (the GPU is idle).
    pub wall_ms: f64,
    /// Work counters of this run.
    pub counters: C,
}

/// Something a bench times, one run at a time.
pub(crate) trait Subject {
    /// Work counters a run reports (kept from the last timed run).
    type Counters: Clone + Default;
    /// Progress-bar units one run counts for (e.g. the shadow maps it generates).
    fn weight(&self) -> u64 {
        1
    }
    /// One run; any error (a GPU validation error included) fails the benchmark, since numbers
    /// from an invalid pipeline would be meaningless.
    fn run(&mut self, ctx: &GpuContext) -> Result<Run<Self::Counters>>;
}

/// A labelled subject of a comparison.
pub(crate) struct Contender<S> {
    /// Its name in tables, plots and JSON (e.g. `layered:frustum`, `traditional@512`).
    pub label: String,
    /// What is run.
    pub subject: S,
}

/// The timed runs of one contender.
#[derive(Clone, Debug)]
pub(crate) struct Runs<C>(pub Vec<Run<C>>);

impl<C: Clone + Default> Runs<C> {
    /// Per run, the GPU milliseconds summed over its stages (runs without timestamps left out).
    pub fn gpu_runs(&self) -> Vec<f64> {
        self.0.iter().filter_map(|r| r.stages.total()).collect()
    }

    /// Median of [`Runs::gpu_runs`]; `None` without timestamp queries.
    pub fn gpu_ms(&self) -> Option<f64> {
        median_of(&self.gpu_runs())
    }

    /// Median GPU milliseconds of one stage; `None` if no run timed it.
    pub fn stage(&self, stage: Stage) -> Option<f64> {
        let v: Vec<f64> = self.0.iter().filter_map(|r| r.stages.get(stage)).collect();
        median_of(&v)
    }

    /// Per run, the CPU milliseconds.
    pub fn cpu_runs(&self) -> Vec<f64> {
        self.0.iter().map(|r| r.cpu_ms).collect()
    }

    /// Median CPU milliseconds.
    pub fn cpu_ms(&self) -> f64 {
        median(&self.cpu_runs())
    }

    /// Per run, the wall milliseconds.
    pub fn wall_runs(&self) -> Vec<f64> {
        self.0.iter().map(|r| r.wall_ms).collect()
    }

    /// Median wall milliseconds.
    pub fn wall_ms(&self) -> f64 {
        median(&self.wall_runs())
    }

    /// The counters of the last timed run.
    pub fn counters(&self) -> C {
        self.0
            .last()
            .map(|r| r.counters.clone())
            .unwrap_or_default()
    }
}

/// A contender after [`Harness::compare`]: its runs and its ratios to the baseline's medians,
/// measured in the same interleaved runs (`None` without a baseline or a time).
pub(crate) struct Outcome<S: Subject> {
    /// The contender's label.
    pub label: String,
    /// The subject (for what it knows beyond timings: its plan, atlas, …).
    pub subject: S,
    /// The timed runs.
    pub runs: Runs<S::Counters>,
    /// Median total GPU time over the baseline's.
    pub gpu_ratio: Option<f64>,
    /// Median CPU time over the baseline's.
    pub cpu_ratio: Option<f64>,
    /// Median wall time over the baseline's.
    pub wall_ratio: Option<f64>,
}

/// A figure [`Harness::finish`] draws.
pub(crate) enum Figure {
    /// Time against a count, one line per method, one PNG per (variant, resolution):
    /// `<prefix>-<variant>[-<resolution>].png` (see [`crate::bench::plot::plots`]).
    ByMethod {
        /// File-name prefix and the bench's name in titles.
        prefix: &'static str,
        /// The count on the x axis (plural, e.g. `shadow maps`).
        x_name: &'static str,
        /// What the lower panels show (e.g. [`crate::bench::plot::CPU_TIME`]).
        second: &'static str,
        /// The records' medians.
        points: Vec<PlotPoint>,
    },
    /// Four panels on one picture (see [`crate::bench::plot::panels`]); the adapter is added to the
    /// title.
    Panels {
        /// File name inside `--out-dir`.
        file: String,
        /// Title, before the adapter.
        title: String,
        /// The count on the x axis.
        x_name: &'static str,
        /// The panels.
        panels: Vec<Panel>,
    },
}

/// What `results.json` holds: the harness's fields, then the bench's.
#[derive(Serialize)]
struct Document<'a, F: Serialize> {
    adapter: &'a str,
    backend: String,
    #[serde(flatten)]
    schedule: Option<Schedule>,
    notes: &'a [String],
    /// The run's peak resident memory, bytes (Linux: `VmHWM`; null elsewhere).
    peak_resident_bytes: Option<u64>,
    #[serde(flatten)]
    fields: F,
}

/// A benchmark in progress: the GPU, the progress bar, the notes.
pub(crate) struct Harness {
    /// The GPU.
    pub ctx: GpuContext,
    /// The adapter, described for tables and plot titles.
    pub adapter: String,
    schedule: Option<Schedule>,
    out_dir: PathBuf,
    pb: ProgressBar,
    notes: std::cell::RefCell<Vec<String>>,
    /// Stderr is not a terminal (a log file, CI, a remote runner): the bar draws nothing
    /// there, so each configuration is printed as a line instead, with the time so far.
    plain: bool,
    started: std::time::Instant,
}

impl Harness {
    /// Checks `--repeats`, creates `--out-dir`, opens the GPU and prints the adapter.
    pub fn start(args: &RunArgs) -> Result<Self> {
        if args.repeats == 0 {
            bail!("--repeats must be at least 1");
        }
        let schedule = Schedule {
            warmup: args.warmup,
            repeats: args.repeats,
        };
        Self::open(&args.output, Some(schedule))
    }

    /// [`Harness::start`] for a bench that compares nothing (`bench soak`): no schedule.
    pub fn start_unscheduled(args: &OutputArgs) -> Result<Self> {
        Self::open(args, None)
    }

    fn open(args: &OutputArgs, schedule: Option<Schedule>) -> Result<Self> {
        let (gpu, out_dir) = (&args.gpu, &args.out_dir);
        std::fs::create_dir_all(out_dir)
            .with_context(|| format!("creating {}", out_dir.display()))?;
        let ctx = GpuContext::new(&gpu.request())?;
        let adapter = manyshadows::gpu::context::describe_adapter(&ctx.info);
        eprintln!("adapter: {adapter}");
        let pb = ProgressBar::hidden();
        pb.set_style(
            ProgressStyle::with_template("{bar:40} {percent:>3}% {msg} [{elapsed}, ~{eta} left]")
                .expect("valid template"),
        );
        Ok(Self {
            ctx,
            adapter,
            schedule,
            out_dir: out_dir.to_path_buf(),
            pb,
            notes: Default::default(),
            plain: !std::io::IsTerminal::is_terminal(&std::io::stderr()),
            started: std::time::Instant::now(),
        })
    }

    /// Progress-bar units that `contenders` subjects of `weight` take in one [`Harness::compare`].
    pub fn units(&self, contenders: usize, weight: u64) -> u64 {
        let runs = self.schedule.map_or(1, |s| s.runs());
        contenders as u64 * weight * runs as u64
    }

    /// Shows the progress bar for `total` units of work.
    pub fn plan(&self, total: u64) {
        self.pb.set_length(total);
        self.pb
            .set_draw_target(indicatif::ProgressDrawTarget::stderr());
    }

    /// What is being measured now, beside the bar (a line of its own where stderr is no
    /// terminal: no silent minutes in a log).
    pub fn message(&self, msg: String) {
        if self.plain {
            let (done, total) = (self.pb.position(), self.pb.length().unwrap_or(0));
            eprintln!(
                "[{:>6.1} s, {}%] {msg}",
                self.started.elapsed().as_secs_f64(),
                (done * 100).checked_div(total).unwrap_or(0)
            );
        }
        self.pb.set_message(msg);
    }

    /// Counts `units` of work as done (work outside [`Harness::compare`], or skipped).
    pub fn advance(&self, units: u64) {
        self.pb.inc(units);
    }

    /// Says something about the run now (above the bar) and in the results.
    pub fn note(&self, note: String) {
        self.pb.suspend(|| eprintln!("{note}"));
        self.notes.borrow_mut().push(note);
    }

    /// Runs every contender `warmup + repeats` times, interleaved round-robin, and returns
    /// their timed runs with ratios to the contender labelled `baseline`.
    pub fn compare<S: Subject>(
        &self,
        contenders: Vec<Contender<S>>,
        baseline: Option<&str>,
    ) -> Result<Vec<Outcome<S>>> {
        let schedule = self
            .schedule
            .context("a bench without a schedule compares nothing")?;
        let (labels, mut subjects): (Vec<String>, Vec<S>) =
            contenders.into_iter().map(|c| (c.label, c.subject)).unzip();
        let mut runs: Vec<Vec<Run<S::Counters>>> = subjects.iter().map(|_| Vec::new()).collect();
        for rep in 0..schedule.runs() {
            for (subject, runs) in subjects.iter_mut().zip(&mut runs) {
                let run = subject.run(&self.ctx)?;
                if rep >= schedule.warmup {
                    runs.push(run);
                }
                self.pb.inc(subject.weight());
            }
        }
        let runs: Vec<Runs<S::Counters>> = runs.into_iter().map(Runs).collect();
        let base = baseline
            .and_then(|b| labels.iter().position(|l| l == b))
            .map(|b| runs[b].clone());
        let base_gpu = base.as_ref().and_then(|b| b.gpu_ms());
        let base_cpu = base.as_ref().map(|b| b.cpu_ms());
        let base_wall = base.as_ref().map(|b| b.wall_ms());
        let out = labels
            .into_iter()
            .zip(subjects)
            .zip(runs)
            .map(|((label, subject), runs)| Outcome {
                label,
                gpu_ratio: ratio(runs.gpu_ms(), base_gpu),
                cpu_ratio: ratio(Some(runs.cpu_ms()), base_cpu),
                wall_ratio: ratio(Some(runs.wall_ms()), base_wall),
                subject,
                runs,
            })
            .collect();
        Ok(out)
    }

    /// Prints `table` (with the notes), writes `results.txt`, `results.json` (the harness's
    /// fields, then `fields`) and the figures into `--out-dir`.
    pub fn finish(
        self,
        mut table: String,
        fields: impl Serialize,
        figures: Vec<Figure>,
    ) -> Result<()> {
        self.pb.finish_and_clear();
        let notes = self.notes.take();
        for n in &notes {
            table += &format!("note: {n}\n");
        }
        let peak = crate::summary::peak_resident_bytes();
        if let Some(peak) = peak {
            table += &format!(
                "memory: peak resident {} over the whole run (every configuration measured)\n",
                crate::summary::describe_bytes(peak)
            );
        }
        print!("{table}");
        std::fs::write(self.out_dir.join("results.txt"), &table)?;
        let doc = Document {
            adapter: &self.adapter,
            backend: format!("{:?}", self.ctx.info.backend),
            schedule: self.schedule,
            notes: &notes,
            peak_resident_bytes: peak,
            fields,
        };
        let json_path = self.out_dir.join("results.json");
        std::fs::write(&json_path, serde_json::to_string_pretty(&doc)?)?;
        eprintln!("wrote {}", json_path.display());
        for figure in figures {
            let written = match figure {
                Figure::ByMethod {
                    prefix,
                    x_name,
                    second,
                    points,
                } => crate::bench::plot::plots(
                    &points,
                    &self.adapter,
                    &self.out_dir,
                    prefix,
                    x_name,
                    second,
                )?,
                Figure::Panels {
                    file,
                    title,
                    x_name,
                    panels,
                } => {
                    let path = self.out_dir.join(file);
                    crate::bench::plot::panels(
                        &path,
                        &format!("{title} — {}", self.adapter),
                        x_name,
                        &panels,
                    )?;
                    vec![path]
                }
            };
            for p in written {
                eprintln!("wrote {}", p.display());
            }
        }
        Ok(())
    }
}

/// `a / base` where both exist.
pub(crate) fn ratio(a: Option<f64>, base: Option<f64>) -> Option<f64> {
    a.zip(base).map(|(a, b)| a / b)
}

/// The median (`NaN` of nothing).
pub(crate) fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// The median, `None` of nothing.
fn median_of(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| median(v))
}

/// Milliseconds for a table cell, `n/a` when not measured.
pub(crate) fn ms(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.1}"))
}

/// Fails unless every count is in `1..=max` (`flag` names the option, `why` may explain max).
pub(crate) fn check_counts(flag: &str, counts: &[usize], max: usize, why: &str) -> Result<()> {
    if let Some(&n) = counts.iter().find(|&&n| n == 0 || n > max) {
        bail!("{flag} {n}: each count must be 1..={max}{why}");
    }
    Ok(())
}

/// Fails unless `name` is a built-in scene.
pub(crate) fn check_scene(flag: &str, name: &str) -> Result<()> {
    if !builtin::SCENE_NAMES.contains(&name) {
        bail!(
            "{flag} {name}: not a built-in scene ({})",
            builtin::SCENE_NAMES.join(", ")
        );
    }
    Ok(())
}

/// A built-in scene with `lights` seeded lights of `mix` (seed 1, the same layout in every
/// bench), each with `shadow_resolution` texels per view where given.
pub(crate) fn seeded_scene(
    name: &str,
    lights: usize,
    mix: LightMix,
    shadow_resolution: Option<u32>,
) -> Result<Scene> {
    Ok(builtin::build(
        name,
        &BuiltinOptions {
            lights: Some(lights),
            seed: 1,
            mix,
            shadow_resolution,
            ..Default::default()
        },
    )?)
}

/// `WIDTHxHEIGHT` of `--screens`.
pub(crate) fn parse_screen(s: &str) -> Result<(u32, u32)> {
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

/// Shadow-map generation alone: one [`ShadowGenerator::generate`] per run, timed by a
/// timestamp span (`shadows`) around it; CPU time is recording and submitting, wall time
/// until the GPU is idle. Counters: the generator's [`ShadowStats`].
pub(crate) struct ShadowSubject<'a> {
    /// The generator.
    pub gen: ShadowGenerator,
    gpu: &'a GpuScene,
    timer: GpuTimer,
    weight: u64,
}

impl<'a> ShadowSubject<'a> {
    /// Times `gen` on `gpu`; a run counts `weight` progress units (e.g. its maps).
    pub fn new(ctx: &GpuContext, gen: ShadowGenerator, gpu: &'a GpuScene, weight: u64) -> Self {
        Self {
            gen,
            gpu,
            timer: GpuTimer::new(ctx),
            weight,
        }
    }

    /// One more, untimed run with pipeline-statistics queries for up to `passes` passes;
    /// `None` where the adapter has none.
    pub fn pipeline_statistics(
        &mut self,
        ctx: &GpuContext,
        passes: u32,
    ) -> Result<Option<PipelineCounts>> {
        let mut timer = GpuTimer::new(ctx);
        let on = timer.enable_statistics(ctx, passes);
        let (_, counts) = generate(ctx, &mut self.gen, self.gpu, &mut timer)?;
        Ok(if on { counts } else { None })
    }
}

/// One generation, timed by `timer`, inside an error scope.
fn generate(
    ctx: &GpuContext,
    gen: &mut ShadowGenerator,
    gpu: &GpuScene,
    timer: &mut GpuTimer,
) -> Result<(Run<ShadowStats>, Option<PipelineCounts>)> {
    let out = ctx.scoped(&format!("benchmarking {}", gen.technique()), || {
        timer.reset();
        let span = timer.span(Stage::Shadows);
        let start = Instant::now();
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bench.encoder"),
            });
        let stats = gen.generate(ctx, gpu, &mut encoder, timer, span);
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        ctx.wait_idle()?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let run = Run {
            stages: timer.read(ctx)?,
            cpu_ms,
            wall_ms,
            counters: stats,
        };
        Ok((run, timer.read_statistics(ctx)?))
    })?;
    Ok(out)
}

impl Subject for ShadowSubject<'_> {
    type Counters = ShadowStats;

    fn weight(&self) -> u64 {
        self.weight
    }

    fn run(&mut self, ctx: &GpuContext) -> Result<Run<ShadowStats>> {
        Ok(generate(ctx, &mut self.gen, self.gpu, &mut self.timer)?.0)
    }
}

/// What a frame counts besides time.
#[derive(Clone, Debug, Default)]
pub(crate) struct FrameCounters {
    /// Light clusters (`None` when every pixel loops over every light).
    pub clusters: Option<ClusterStats>,
    /// Virtual shadow maps (`None` for other techniques).
    pub virtual_maps: Option<VirtualStats>,
}

/// Whole frames of a [`Renderer`]: stages as the renderer times them (`gbuffer`, `clusters`,
/// `pages`, `shadows`, `lighting`), CPU time recording and submitting, wall time until the
/// image is back. With a moving caster, that instance moves by 0.05 back and forth before
/// each frame.
pub(crate) struct FrameSubject {
    /// The renderer.
    pub renderer: Renderer,
    /// The moving instance and its transform at rest.
    caster: Option<(usize, glam::Mat4)>,
    frame: u32,
}

impl FrameSubject {
    /// Frames of an unchanging scene.
    pub fn new(renderer: Renderer) -> Self {
        Self::moving(renderer, None)
    }

    /// Frames in which `caster` (instance, transform at rest), if any, moves.
    pub fn moving(renderer: Renderer, caster: Option<(usize, glam::Mat4)>) -> Self {
        Self {
            renderer,
            caster,
            frame: 0,
        }
    }
}

impl Subject for FrameSubject {
    type Counters = FrameCounters;

    fn run(&mut self, _ctx: &GpuContext) -> Result<Run<FrameCounters>> {
        if let Some((k, base)) = self.caster {
            self.frame += 1;
            let dx = if self.frame.is_multiple_of(2) {
                0.0
            } else {
                0.05
            };
            self.renderer.set_instance_transform(
                k,
                glam::Mat4::from_translation(glam::Vec3::new(dx, 0.0, 0.0)) * base,
            )?;
        }
        let f = self.renderer.render()?;
        Ok(Run {
            stages: f.timings.gpu_ms,
            cpu_ms: f.timings.cpu_record_ms,
            wall_ms: f.timings.wall_ms,
            counters: FrameCounters {
                clusters: f.clusters,
                virtual_maps: f.virtual_maps,
            },
        })
    }
}
