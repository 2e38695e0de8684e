//! `compare --frames N`: techniques scored over a sequence, each frame against the exact image
//! of that same frame.
//!
//! The sequence is `render --frames`' ([`crate::render::Sequence`]: the camera orbits or flies
//! a path, a caster circles). Each technique keeps one renderer for the whole sequence, so
//! what it carries from frame to frame (cached shadow maps, lights reused in reservoirs, the
//! denoiser's history) is what is scored; the exact renderer traces every cluster light of
//! every pixel each frame. Per frame: RMSE of the 8-bit RGB channels and ꟻLIP against the exact
//! frame, and the GPU time.
//!
//! A shadow-map technique with sampled lights (`--light-samples K`: the sampled lights'
//! visibility from its atlas or virtual pages) is scored twice: against the exact frame (where
//! the adapter traces rays), and against the same technique with every light, which isolates
//! the sampling's noise from the maps' own error. Without ray queries only the second runs.

use anyhow::{bail, Context, Result};
use manyshadows::{Fills, Frame, RayOptions, RenderSettings, Renderer, Technique};
use serde::Serialize;
use serde_json::json;

use crate::compare::args::CompareArgs;
use crate::compare::images::image_out;
use crate::compare::setup::{check_flags, load};
use crate::compare::soft::rmse_rgb;
use crate::render::{moving_instance, Sequence};

/// One technique's sequence.
#[derive(Serialize)]
struct Scored {
    technique: String,
    /// Against the exact frame (absent without ray queries).
    #[serde(flatten)]
    exact: Option<Against>,
    /// Sampled lights over shadow maps: against the same technique with every light.
    every_light: Option<Against>,
    /// Per frame: GPU ms of the whole frame (where timestamps exist).
    gpu_ms: Vec<Option<f64>>,
    /// With --misclassified: its hard mask against each frame's CPU reference.
    misclassified: Option<Misclassified>,
}

/// A technique's hard visibility masks against the CPU reference of each frame.
#[derive(Serialize, Default)]
struct Misclassified {
    /// Per frame: (pixel, light) pairs in reach misclassified outside the edge band (false
    /// shadow plus false light).
    outside_band: Vec<u64>,
    /// Per frame: the same as a share of the pairs in reach.
    fraction: Vec<f64>,
    /// The largest share, and its frame (from 1).
    max_fraction: f64,
    max_frame: u32,
}

impl Misclassified {
    fn push(&mut self, c: &manyshadows_reference::score::Counts) {
        let wrong = c.false_shadow + c.false_light;
        let share = wrong as f64 / c.in_reach.max(1) as f64;
        self.outside_band.push(wrong);
        self.fraction.push(share);
        if self.fraction.len() == 1 || share > self.max_fraction {
            self.max_fraction = share;
            self.max_frame = self.fraction.len() as u32;
        }
    }
}

/// One technique's frames against one reference's.
#[derive(Serialize, Default)]
struct Against {
    /// Per frame: RMSE (RGB, 0-255).
    rmse: Vec<f64>,
    /// Per frame: mean ꟻLIP.
    flip: Vec<f64>,
    mean_rmse: f64,
    max_rmse: f64,
    mean_flip: f64,
}

impl Against {
    fn push(&mut self, reference: &Frame, frame: &Frame) -> Result<()> {
        self.rmse.push(rmse_rgb(&reference.rgba, &frame.rgba));
        self.flip.push(
            manyshadows_reference::flip_rgba8(
                &reference.rgba,
                &frame.rgba,
                reference.width,
                reference.height,
            )?
            .mean,
        );
        Ok(())
    }

    fn finish(&mut self) {
        let n = self.rmse.len().max(1) as f64;
        self.mean_rmse = self.rmse.iter().sum::<f64>() / n;
        self.max_rmse = self.rmse.iter().copied().fold(0.0, f64::max);
        self.mean_flip = self.flip.iter().sum::<f64>() / n;
    }
}

/// Whether `t` takes its sampled lights' visibility from shadow maps (an atlas or pages).
fn samples_over_maps(t: Technique, rays: &RayOptions) -> bool {
    rays.light_samples > 0 && matches!(t.info().fills, Fills::Atlas | Fills::Pages)
}

/// The ray options `t` renders the sequence with: the sampled lights' where it can sample.
fn rays_of(t: Technique, sampled: RayOptions) -> RayOptions {
    if t.info().fills == Fills::Rays || samples_over_maps(t, &sampled) {
        sampled
    } else {
        RayOptions::default()
    }
}

/// The ray options the sequence's ray techniques render with (`--light-samples`, `--reuse`,
/// `--spatial`, `--denoise`, `--area-samples`, `--ray-seed`).
fn sampled_rays(args: &CompareArgs) -> RayOptions {
    args.per_technique.rays()
}

/// The flags only a sequence takes, refused without `--frames` past 1.
pub(super) fn check_sequence_flags(args: &CompareArgs) -> Result<()> {
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    if args.frames > MAX_FRAMES {
        bail!("--frames {}: at most {MAX_FRAMES}", args.frames);
    }
    if !args.orbit.is_finite() {
        bail!(
            "--orbit must be a finite number of degrees, not {}",
            args.orbit
        );
    }
    // The sampled rays' flags, checked as a ray technique reads them whatever the techniques
    // asked (and before any device): out of range is refused, not dropped for map techniques.
    if let Some(rays) = Technique::all()
        .into_iter()
        .find(|t| t.info().fills == Fills::Rays)
    {
        let mut check = RenderSettings::default();
        check.technique = rays;
        check.rays = sampled_rays(args);
        check.validate().map_err(crate::args::flag_error)?;
    }
    if args.per_technique.light_samples > 0 && !args.techniques.is_empty() {
        let can =
            |t: &Technique| matches!(t.info().fills, Fills::Rays | Fills::Atlas | Fills::Pages);
        if !args.techniques.iter().any(can) {
            let names: Vec<String> = args.techniques.iter().map(|t| t.to_string()).collect();
            bail!(
                "--light-samples {}: none of the techniques ({}) can sample lights (irregular maps \
                 answer every light in one mask); name raytraced, virtual or an atlas technique",
                args.per_technique.light_samples,
                names.join(", ")
            );
        }
    }
    if args.misclassified && args.per_technique.light_samples > 0 {
        bail!(
            "--misclassified scores hard visibility masks, which sampled lights \
             (--light-samples {}) do not keep; score it without --light-samples",
            args.per_technique.light_samples
        );
    }
    if args.frames == 1 {
        let used = [
            ("--misclassified", args.misclassified),
            ("--orbit", args.orbit != 0.0),
            ("--camera-path", args.camera_path.is_some()),
            ("--move-instance", args.move_instance.is_some()),
            ("--still", args.still),
            ("--light-samples", args.per_technique.light_samples != 0),
            ("--reuse", args.per_technique.reuse),
            (
                "--spatial",
                args.per_technique.spatial != manyshadows::SpatialReuse::Off,
            ),
            ("--denoise", args.per_technique.denoise),
        ];
        if let Some((name, _)) = used.iter().find(|(_, on)| *on) {
            bail!(
                "{name} scores a sequence: give --frames N (N > 1); one frame is scored against \
                 the CPU reference's visibility instead"
            );
        }
    }
    Ok(())
}

/// Most frames of a sequence.
const MAX_FRAMES: u32 = 10_000;

/// Renders and scores the sequence of `args.scene`; returns the JSON report.
pub(super) fn run_sequence(args: &CompareArgs) -> Result<serde_json::Value> {
    check_flags(args)?;
    check_sequence_flags(args)?;
    let pb = crate::progress::spinner("loading the scene");
    let scene = load(args)?;
    let path = crate::args::read_camera_path(args.camera_path.as_deref())?;
    let clock = args.animation.clock(&scene, args.frames)?;
    let mover = moving_instance(args.move_instance, args.still, &scene, clock, || {
        Ok(scene.smallest_caster())
    })?;
    pb.set_message("opening the GPU");
    let ctx = manyshadows::GpuContext::new(&args.gpu.request())?;
    let args = CompareArgs {
        atlas_max: pb.suspend(|| crate::args::effective_atlas_max(&ctx, args.atlas_max)),
        ..args.clone()
    };
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let settings = |t: Technique, rays: RayOptions| -> RenderSettings {
        // The frame people see: PCF as the technique's default, no visibility masks.
        crate::compare::setup::settings(&args, t, false)
            .with_pcf(manyshadows::Pcf::default())
            .with_visibility(args.misclassified)
            .with_rays(rays)
    };
    let named = !args.techniques.is_empty();
    let asked = if named {
        args.techniques.clone()
    } else {
        Technique::all()
    };
    let sampled = sampled_rays(&args);
    pb.set_message("building the exact renderer");
    let exact_technique = crate::techniques::first_filling(Fills::Rays);
    let exact = match Renderer::new(
        &ctx,
        &scene,
        settings(exact_technique, RayOptions::default()),
    ) {
        Ok(r) => Some(r),
        // Sampled lights over shadow maps still have their every-light frames to be scored
        // against, and with --misclassified every technique its masks.
        Err(e) if args.misclassified || asked.iter().any(|&t| samples_over_maps(t, &sampled)) => {
            pb.suspend(|| {
                eprintln!(
                    "note: no exact frames ({exact_technique}: {e}); {}",
                    if args.misclassified {
                        "each technique's masks are scored against each frame's CPU reference \
                         (--misclassified), its frames against no exact image"
                    } else {
                        "the sampled shadow-map techniques are scored against their own frames \
                         with every light only"
                    }
                )
            });
            None
        }
        Err(e) => {
            return Err(anyhow::Error::from(e).context(format!(
                "the exact frames of a sequence trace every light with {exact_technique}, which \
                 needs ray queries (EXPERIMENTAL_RAY_QUERY: Vulkan with Mesa 25's lavapipe, or a \
                 GPU driver that has them); without them, --light-samples K scores sampled \
                 lights over shadow maps against the same maps with every light"
            )))
        }
    };
    let mut contenders: Vec<Contender> = Vec::new();
    for t in asked {
        pb.set_message(format!("building {t}"));
        // Without exact frames a technique is still scored by its masks (--misclassified).
        if exact.is_none() && !samples_over_maps(t, &sampled) && !args.misclassified {
            if named {
                bail!(
                    "technique {t}: nothing to score it against without ray queries (only \
                     sampled lights over shadow maps have their every-light frames)"
                );
            }
            continue;
        }
        let rays = rays_of(t, sampled);
        let made = Renderer::new(&ctx, &scene, settings(t, rays)).map(|r| {
            let e = r.estimate_frame();
            (r, e)
        });
        let checked = made.map_err(anyhow::Error::from).and_then(|(r, e)| {
            if !args.insist {
                crate::render::check_shadow_work(&r, &e)?;
            }
            // Sampled lights over shadow maps: the same technique with every light as well.
            let every = samples_over_maps(t, &sampled)
                .then(|| Renderer::new(&ctx, &scene, settings(t, RayOptions::default())))
                .transpose()
                .context("with every light")?;
            Ok((r, every))
        });
        match checked {
            Ok((r, every)) => contenders.push(Contender {
                name: label(t, &args),
                renderer: r,
                every,
            }),
            Err(e) if !named => pb.suspend(|| eprintln!("note: {t} left out: {e:#}")),
            Err(e) => return Err(e.context(format!("technique {t}"))),
        }
    }
    pb.finish_and_clear();
    if contenders.is_empty() {
        bail!("no technique could run on this adapter");
    }
    let sequence = Sequence {
        path: path.as_deref(),
        orbit: args.orbit,
        mover,
        clock,
    };
    let renderers = contenders
        .iter()
        .map(|c| 1 + u64::from(c.every.is_some()))
        .sum::<u64>()
        + u64::from(exact.is_some());
    let bar = crate::progress::bar(u64::from(args.frames) * renderers, "frames");
    let mut exact = exact;
    let mut scored: Vec<Scored> = contenders
        .iter()
        .map(|c| Scored {
            technique: c.name.clone(),
            exact: exact.as_ref().map(|_| Against::default()),
            every_light: c.every.as_ref().map(|_| Against::default()),
            gpu_ms: Vec::new(),
            misclassified: args.misclassified.then(Misclassified::default),
        })
        .collect();
    let mut last: Vec<Frame> = Vec::new();
    // Where stderr is no terminal (a log) the bar draws nothing: a line every tenth instead.
    let plain = !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let started = std::time::Instant::now();
    for f in 0..args.frames {
        {
            let mut all: Vec<&mut Renderer> = exact
                .iter_mut()
                .chain(
                    contenders
                        .iter_mut()
                        .flat_map(|c| std::iter::once(&mut c.renderer).chain(c.every.as_mut())),
                )
                .collect();
            sequence.step(f, &scene, &mut all)?;
        }
        bar.set_message(format!("frame {}/{}: exact", f + 1, args.frames));
        let e = exact.as_mut().map(|r| r.render()).transpose()?;
        bar.inc(u64::from(e.is_some()));
        last.clear();
        for (c, s) in contenders.iter_mut().zip(&mut scored) {
            bar.set_message(format!("frame {}/{}: {}", f + 1, args.frames, c.name));
            let fr = c.renderer.render()?;
            bar.inc(1);
            if let (Some(e), Some(a)) = (&e, s.exact.as_mut()) {
                a.push(e, &fr)?;
            }
            if let (Some(every), Some(a)) = (c.every.as_mut(), s.every_light.as_mut()) {
                let ev = every.render()?;
                bar.inc(1);
                a.push(&ev, &fr)?;
            }
            s.gpu_ms.push(fr.timings.gpu_ms.total());
            last.push(fr);
        }
        if args.misclassified {
            bar.set_message(format!("frame {}/{}: CPU reference", f + 1, args.frames));
            misclassified(&args, &sequence, f, &scene, &contenders, &last, &mut scored)?;
        }
        if let Some(e) = e.filter(|_| f + 1 == args.frames) {
            image_out(
                &args.out_dir.join("exact-last.png"),
                e.width,
                e.height,
                &e.rgba,
            )?;
        }
        if plain && (f + 1) % args.frames.div_ceil(10) == 0 {
            let t = started.elapsed().as_secs_f64();
            let left = t / f64::from(f + 1) * f64::from(args.frames - f - 1);
            eprintln!(
                "frame {}/{} scored after {t:.0} s, ~{left:.0} s left",
                f + 1,
                args.frames
            );
        }
    }
    bar.finish_and_clear();
    for (s, fr) in scored.iter_mut().zip(&last) {
        s.exact
            .iter_mut()
            .chain(s.every_light.as_mut())
            .for_each(Against::finish);
        let file = format!("{}-last.png", s.technique);
        image_out(&args.out_dir.join(file), fr.width, fr.height, &fr.rgba)?;
    }
    let exact_name = exact.as_ref().map(|_| exact_technique);
    let moving = match clock {
        Some(c) => format!(
            "animation {} at {} fps from {} s",
            scene.animations.describe(c.playing),
            c.fps,
            c.start
        ),
        None => mover.map_or("no caster moving".to_string(), |k| {
            format!("instance {k} circling")
        }),
    };
    print_table(&args, &ctx.info.name, exact_name, &moving, &scored);
    let plot = args.out_dir.join("sequence.png");
    plot_sequence(&plot, &args, &scored)?;
    eprintln!(
        "wrote      {} (sequence.png, exact-last.png, <technique>-last.png)",
        args.out_dir.display()
    );
    let report = json!({
        "scene": scene.name,
        "adapter": ctx.info.name,
        "width": args.width,
        "height": args.height,
        "frames": args.frames,
        "probes": scene.probes.len(),
        "orbit_degrees_per_frame": args.orbit,
        "camera_path": args.camera_path,
        "moving_instance": mover,
        "light_samples": args.per_technique.light_samples,
        "reuse": args.per_technique.reuse,
        "spatial": args.per_technique.spatial.name(),
        "denoise": args.per_technique.denoise,
        "exact": exact_name.map(|t| t.to_string()),
        "techniques": scored,
    });
    if let Some(p) = &args.json {
        crate::compare::report::write_json(p, &report)?;
    }
    Ok(report)
}

/// Frame `f`'s hard masks (`frames`, one per contender) against the CPU reference traced from
/// the first contender's G-buffer through the scene as it stands at that frame.
fn misclassified(
    args: &CompareArgs,
    sequence: &Sequence,
    f: u32,
    scene: &manyshadows::scene::Scene,
    contenders: &[Contender],
    frames: &[Frame],
    scored: &mut [Scored],
) -> Result<()> {
    let Some(first) = contenders.first() else {
        return Ok(());
    };
    let posed = sequence.posed(f, scene);
    let tracer = manyshadows_reference::Tracer::with_rule(&posed, args.single_sided_shadows)?;
    let hidden =
        indicatif::MultiProgress::with_draw_target(indicatif::ProgressDrawTarget::hidden());
    let r = crate::compare::reference::trace_reference(
        &hidden,
        &first.renderer,
        &tracer,
        &posed,
        args.edge_band,
    )?;
    for (fr, s) in frames.iter().zip(scored.iter_mut()) {
        let Some(m) = s.misclassified.as_mut() else {
            continue;
        };
        let vis = fr.visibility.as_ref().with_context(|| {
            format!("{}: the renderer returned no visibility mask", s.technique)
        })?;
        let mask = crate::compare::scoring::mask_of(vis);
        let score = manyshadows_reference::score::score(&r.vis, &r.band, &mask)?;
        m.push(&score.total(|_| true));
    }
    Ok(())
}

/// A technique's renderer over the sequence, and where it samples lights over shadow maps,
/// the same technique with every light.
struct Contender {
    name: String,
    renderer: Renderer,
    every: Option<Renderer>,
}

/// The technique's row name: with its ray options when it samples lights.
fn label(t: Technique, args: &CompareArgs) -> String {
    let rays = sampled_rays(args);
    if rays.light_samples == 0 || rays_of(t, rays).light_samples == 0 {
        return t.to_string();
    }
    let mut s = format!("{t}-k{}", args.per_technique.light_samples);
    if args.per_technique.reuse {
        s.push_str("-reuse");
    }
    if args.per_technique.spatial != manyshadows::SpatialReuse::Off {
        s.push_str("-spatial-");
        s.push_str(args.per_technique.spatial.name());
    }
    if args.per_technique.denoise {
        s.push_str("-denoise");
    }
    s
}

fn print_table(
    args: &CompareArgs,
    adapter: &str,
    exact: Option<Technique>,
    caster: &str,
    scored: &[Scored],
) {
    let camera = match (&args.camera_path, args.orbit) {
        (Some(p), _) => format!("camera along {}", p.display()),
        (None, o) if o != 0.0 => format!("camera turning {o}° a frame"),
        _ => "camera still".to_string(),
    };
    let against = match exact {
        Some(t) => format!("each against every cluster light traced by {t}"),
        None => "no exact frames (no ray queries)".to_string(),
    };
    println!(
        "{} frames of {}x{}, {camera}, {caster}; {against} ({adapter})",
        args.frames, args.width, args.height
    );
    println!(
        "{:<40} {:>10} {:>8} {:>8} {:>8} {:>10} {:>12}",
        "technique", "mean RMSE", "first", "last", "max", "mean FLIP", "median GPU ms"
    );
    for s in scored {
        let mut ms: Vec<f64> = s.gpu_ms.iter().flatten().copied().collect();
        ms.sort_by(f64::total_cmp);
        let median = ms
            .get(ms.len() / 2)
            .map_or("n/a".to_string(), |m| format!("{m:.1}"));
        let rows = s.exact.iter().map(|a| (s.technique.clone(), a)).chain(
            s.every_light
                .iter()
                .map(|a| (format!("{} vs every light", s.technique), a)),
        );
        for (k, (name, a)) in rows.enumerate() {
            println!(
                "{:<40} {:>10.2} {:>8.2} {:>8.2} {:>8.2} {:>10.4} {:>12}",
                name,
                a.mean_rmse,
                a.rmse.first().copied().unwrap_or(0.0),
                a.rmse.last().copied().unwrap_or(0.0),
                a.max_rmse,
                a.mean_flip,
                if k == 0 { median.as_str() } else { "" }
            );
        }
    }
    if scored.iter().any(|s| s.misclassified.is_some()) {
        println!(
            "{:<40} {:>10} {:>8} {:>8} {:>14}",
            "hard mask vs each frame's CPU reference", "mean", "first", "last", "max (frame)"
        );
        for s in scored {
            let Some(m) = &s.misclassified else { continue };
            let pct = |v: Option<&f64>| v.map_or("-".to_string(), |v| format!("{:.3}%", 100.0 * v));
            let mean = m.fraction.iter().sum::<f64>() / m.fraction.len().max(1) as f64;
            println!(
                "{:<40} {:>10} {:>8} {:>8} {:>14}",
                s.technique,
                pct(Some(&mean)),
                pct(m.fraction.first()),
                pct(m.fraction.last()),
                format!("{} ({})", pct(Some(&m.max_fraction)), m.max_frame)
            );
        }
        println!(
            "misclassified: false shadow and false light outside the edge band, as a share of \
             the (pixel, light) pairs in reach"
        );
    }
    let mut footer = "RMSE of the 8-bit RGB channels (0-255) and FLIP".to_string();
    if exact.is_some() {
        footer.push_str(" against the exact frame of each frame");
    }
    if scored.iter().any(|s| s.every_light.is_some()) {
        footer.push_str(
            "; \"vs every light\": against the same technique's frame with every light (the \
             sampling's noise alone)",
        );
    }
    println!("{footer}");
}

fn plot_sequence(path: &std::path::Path, args: &CompareArgs, scored: &[Scored]) -> Result<()> {
    // Each technique's line against the exact frames, and against its every-light frames.
    let lines = || {
        scored.iter().flat_map(|s| {
            s.exact.iter().map(|a| (s.technique.clone(), a)).chain(
                s.every_light
                    .iter()
                    .map(|a| (format!("{} vs every light", s.technique), a)),
            )
        })
    };
    let series = |pick: &dyn Fn(&Against, usize) -> f64| -> Vec<crate::bench::plot::Series> {
        lines()
            .map(|(name, a)| {
                let points = (0..a.rmse.len())
                    .map(|k| ((k + 1) as f64, pick(a, k)))
                    .collect();
                (name, points)
            })
            .collect()
    };
    let times: Vec<crate::bench::plot::Series> = scored
        .iter()
        .map(|s| {
            let points = (0..s.gpu_ms.len())
                .filter_map(|k| s.gpu_ms[k].map(|v| ((k + 1) as f64, v)))
                .collect();
            (s.technique.clone(), points)
        })
        .collect();
    crate::bench::plot::panels(
        path,
        &format!(
            "compare --frames {}: {} {}x{}",
            args.frames, args.scene, args.width, args.height
        ),
        "frame",
        &[
            (
                "RMSE against the reference frame".to_string(),
                "RMSE (0-255)".to_string(),
                series(&|a, k| a.rmse[k]),
            ),
            (
                "FLIP against the reference frame".to_string(),
                "mean FLIP".to_string(),
                series(&|a, k| a.flip[k]),
            ),
            ("GPU time per frame".to_string(), "ms".to_string(), times),
        ],
    )
}
