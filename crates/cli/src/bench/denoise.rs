//! `manyshadows bench denoise`: sampled shadow rays and their denoiser over a sequence, each
//! frame scored against the exact image of that same frame.
//!
//! Three renderers see the same frames: every cluster light traced (the exact image), K
//! lights sampled per pixel as they are, and the same K denoised (`RayOptions::denoise`). The
//! camera turns `--orbit` degrees a frame around its target and a caster the camera sees
//! circles (unless `--still`), set alike on all three before each frame. Per frame: the RMSE
//! of each sampled image against the exact one (sRGB channels, 0–255) and GPU times. Per
//! light count: mean, first and last errors, median frame times and the denoised frame over
//! the plain one; across light counts, how the frames grow. Without `--reference` (`off`)
//! only the times are taken, for light counts whose exact frames take too long.
//!
//! With a shadow-map technique (`--technique virtual` or an atlas one) the sampled lights take
//! their visibility from its maps, and a fourth renderer draws the same technique with every
//! light: each sampled frame is scored against it too (the sampling's noise alone), and its
//! time and pages drawn are what sampling saves.

use anyhow::{bail, Result};
use clap::Args;
use manyshadows::scene::builtin::{self, LightMix};
use manyshadows::{Frame, RayOptions, RenderSettings, Renderer, Stage};
use serde::Serialize;

use crate::args::Clock;
use crate::bench::harness::{check_counts, check_scene, median, seeded_scene, Figure, Harness};

use crate::bench::denoise_table::{table, FrameRow, Record};

/// `manyshadows bench denoise --help`.
pub const LONG_ABOUT: &str = "\
Sampled shadow rays (--light-samples K) and their denoiser over a sequence of frames, each
frame scored against the exact image of the same frame (every cluster light traced).

Three renderers see the same frames: exact, K lights sampled per pixel as they are, and the
same K denoised (the exact unshadowed light times the rays' shadow ratio, accumulated over
frames and filtered). The camera turns --orbit degrees a frame around its target and a shadow
caster the camera sees circles (--move-instance), unless --still. With the camera still
(--orbit 0) and the caster moving, it also finds how many frames the denoised shadow trails:
over the pixels the caster's motion changed, which of the last exact frames the denoised one
is closest to. Per frame: RMSE of the plain and the
denoised image against the exact one (sRGB channels, 0-255) and GPU times; per light count:
the mean, first and last errors, median GPU ms of each frame and the denoised frame over the
plain one (the same frames, interleaved); across light counts, how each frame grows. Writes
results.txt, results.json (every frame's numbers) and frames.png (error and time per frame).

With the default --technique (shadow rays) it needs ray queries (EXPERIMENTAL_RAY_QUERY:
Vulkan with Mesa 25's lavapipe, or a GPU driver that has them). With a shadow-map technique
(virtual maps or an atlas technique) the sampled lights' visibility comes from its maps (any
adapter), and a fourth renderer draws the same technique with every light: the sampled
frames are scored against it too (the sampling's noise alone), and the table sets its time,
pages drawn and own error against the exact frame beside them. The exact frames are still
traced where there are ray queries. --reference off skips the exact frames (times only), for
light counts whose exact frames take long on a CPU adapter. --reuse makes both sampled renderers reuse their
lights across frames (`render --reuse`): the plain column then shows reuse alone.

Examples:
  manyshadows bench denoise                                    # atrium, 1,024 lights, 60 frames
  manyshadows bench denoise --still --frames 8                 # a still camera converging
  manyshadows bench denoise --lights 1024,16384 --reference off --frames 10   # cost growth
  manyshadows bench denoise --reuse --still --orbit 0 --frames 32   # reuse, alone and denoised
  manyshadows bench denoise --technique virtual --reuse --still --frames 8   # over virtual maps";

/// Arguments of `manyshadows bench denoise`.
#[derive(Args, Debug, Clone)]
pub struct DenoiseArgs {
    /// Built-in scene.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// Numbers of lights, comma-separated (1 to 16384 each).
    #[arg(long, default_value = "1024", value_delimiter = ',')]
    pub lights: Vec<usize>,
    /// Frames of the sequence.
    #[arg(long, default_value_t = 60)]
    pub frames: u32,
    /// Degrees the camera turns around its target each frame (0: it stays). The default
    /// keeps the atrium's camera inside the hall for 60 frames (9 degrees; at 12 it passes
    /// into a column).
    #[arg(long, default_value_t = 0.15)]
    pub orbit: f32,
    /// Fly this path instead of orbiting: one camera per line, `PX PY PZ TX TY TZ` (as
    /// `render --camera-path`); frame k takes line k, the last stays.
    #[arg(long, value_name = "FILE")]
    pub camera_path: Option<std::path::PathBuf>,
    /// Move no caster (with --orbit 0: still frames, as `render --still`).
    #[arg(long)]
    pub still: bool,
    /// Play the scene's animation (a name, a number from 0, or `all`: `crowd`'s "sway",
    /// `walker`'s "walk") from 0 s, frame k at k / --fps, instead of circling a caster; and
    /// beside each light count, the same frames with the scene frozen at 0 s, whose error the
    /// moving one's is set against (the histories' following of bent surfaces).
    #[arg(long, value_name = "NAME|INDEX|all")]
    pub animation: Option<String>,
    /// With --animation: frames per second of animation time.
    #[arg(long, default_value_t = crate::args::DEFAULT_FPS)]
    pub fps: f32,
    /// The instance that circles (default: the nearest caster to the camera among the smaller
    /// half whose centre the camera sees, so that its shadow's motion is in the frames).
    #[arg(long)]
    pub move_instance: Option<usize>,
    /// Lights sampled per pixel (1 to 16).
    #[arg(long, default_value_t = 1)]
    pub light_samples: u32,
    /// Where the sampled lights' visibility comes from: shadow rays (the default), or virtual
    /// maps or an atlas technique (their shadow maps; scored against the same technique with
    /// every light as well). Irregular maps cannot sample.
    #[arg(long, default_value_t = crate::techniques::first_filling(manyshadows::Fills::Rays),
          value_parser = crate::args::parse_technique)]
    pub technique: manyshadows::Technique,
    /// Both sampled renderers reuse their lights across frames (`render --reuse`): the plain
    /// one then shows reuse alone, the denoised one reuse and the denoiser together.
    #[arg(long)]
    pub reuse: bool,
    /// With --reuse: spatial reuse too (`render --spatial`: off, biased or unbiased).
    #[arg(long, default_value = "off", value_parser = crate::args::parse_spatial)]
    pub spatial: manyshadows::SpatialReuse,
    /// Score against the exact image of every frame (on) or only time the frames (off).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub reference: String,
    /// Rays per side of the exact image's grid over each sized light (`render
    /// --area-samples`, 1 to 16). The exact image's penumbrae carry its own sampling noise,
    /// which every score against it includes (docs/techniques.md, "The exact image's own
    /// noise"); 8 takes 16 × the reference's rays.
    #[arg(long, default_value_t = manyshadows::DEFAULT_AREA_SAMPLES,
          value_parser = clap::value_parser!(u32).range(1..=16))]
    pub reference_area_samples: u32,
    /// Cluster tile side in pixels for all three renderers (`render --cluster-tile`; by
    /// default chosen as there: 16 where the slot pool holds every cluster of that grid, else
    /// 32). The lighting loop of the denoised frame visits each pixel's cluster lights, so
    /// the growth from 1,024 to 16,384 lights depends on it (docs/techniques.md, "Ray-traced
    /// shadows: `--technique raytraced`").
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub cluster_tile: Option<u32>,
    /// Image width.
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    #[command(flatten)]
    pub output: crate::bench::harness::OutputArgs,
}

#[derive(Serialize)]
struct Fields<'a> {
    scene: &'a str,
    width: u32,
    height: u32,
    orbit_degrees_per_frame: f32,
    caster_moves: bool,
    light_samples: u32,
    /// Where the sampled lights' visibility comes from.
    technique: String,
    reuse: bool,
    spatial: &'static str,
    /// Rays per side of the exact image's grid over each sized light.
    reference_area_samples: u32,
    records: Vec<Record>,
}

fn rmse_rgb(a: &Frame, b: &Frame) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (p, q) in a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)) {
        for c in 0..3 {
            sum += (f64::from(p[c]) - f64::from(q[c])).powi(2);
        }
        n += 3;
    }
    (sum / n.max(1) as f64).sqrt()
}

/// The caster that moves: of the 16 casters nearest the camera, no larger than the median and
/// with their centre well inside the camera's view, the one whose move (by its size, upwards)
/// changes the most pixels of a 160 × 90 frame, at least 20 (a caster may hide behind others;
/// the smallest caster of the atrium is out of sight, and moving it changed no pixel).
fn seen_caster(
    ctx: &manyshadows::GpuContext,
    scene: &manyshadows::scene::Scene,
) -> Result<Option<usize>> {
    let (w, h) = (160u32, 90u32);
    let view_proj = scene.camera.projection(w as f32 / h as f32) * scene.camera.view();
    let casters: Vec<(usize, glam::Vec3, f32)> = scene
        .instances
        .iter()
        .enumerate()
        .filter(|(_, i)| i.casts_shadows)
        .filter_map(|(k, i)| {
            let (lo, hi) = scene.meshes.get(i.mesh)?.bounds()?;
            let centre = i.transform.transform_point3(0.5 * (lo + hi));
            Some((k, centre, caster_size(scene, k)))
        })
        .collect();
    let mut sizes: Vec<f32> = casters.iter().map(|c| c.2).collect();
    sizes.sort_by(f32::total_cmp);
    let Some(&median) = sizes.get(sizes.len() / 2) else {
        return Ok(None);
    };
    let mut near: Vec<&(usize, glam::Vec3, f32)> = casters
        .iter()
        .filter(|c| c.2 <= median && c.2 > 0.0)
        .filter(|c| {
            let clip = view_proj * c.1.extend(1.0);
            clip.w > 0.0
                && (glam::Vec2::new(clip.x, clip.y) / clip.w)
                    .abs()
                    .max_element()
                    < 0.8
        })
        .collect();
    let d = |c: &&(usize, glam::Vec3, f32)| c.1.distance(scene.camera.position);
    near.sort_by(|a, b| d(a).total_cmp(&d(b)));
    let mut r = Renderer::new(ctx, scene, RenderSettings::new(w, h))?;
    let base = r.render()?.rgba;
    let mut best = (None, 19usize);
    for &&(k, _, size) in near.iter().take(16) {
        let t = scene.instances[k].transform;
        r.set_instance_transform(k, glam::Mat4::from_translation(glam::Vec3::Y * size) * t)?;
        let moved = r.render()?.rgba;
        r.set_instance_transform(k, t)?;
        let changed = base
            .chunks_exact(4)
            .zip(moved.chunks_exact(4))
            .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 8))
            .count();
        if changed > best.1 {
            best = (Some(k), changed);
        }
    }
    Ok(best.0)
}

/// An instance's size: its mesh's bounding-box diagonal times its largest scale.
fn caster_size(scene: &manyshadows::scene::Scene, k: usize) -> f32 {
    let i = &scene.instances[k];
    scene
        .meshes
        .get(i.mesh)
        .and_then(|m| m.bounds())
        .map_or(0.0, |(lo, hi)| {
            (hi - lo).length() * i.transform.to_scale_rotation_translation().0.max_element()
        })
}

/// Exact frames a trail is looked for in.
const TRAIL_FRAMES: usize = 3;

/// How many frames behind the moving caster's shadow the denoised frame `denoised` is: over
/// the pixels where the exact frame `exact` differs from the one before (`past[0]`) by more
/// than 8 levels, the k (0 to [`TRAIL_FRAMES`]) whose exact frame, `exact` or `past[k - 1]`,
/// the denoised one is closest to. None until enough frames are kept or where fewer than 50
/// pixels changed.
fn trail(denoised: &[u8], exact: &[u8], past: &std::collections::VecDeque<Vec<u8>>) -> Option<u32> {
    if past.len() < TRAIL_FRAMES {
        return None;
    }
    let changed: Vec<usize> = (0..exact.len() / 4)
        .filter(|&i| (0..3).any(|c| exact[4 * i + c].abs_diff(past[0][4 * i + c]) > 8))
        .collect();
    if changed.len() < 50 {
        return None;
    }
    let error = |other: &[u8]| -> f64 {
        changed
            .iter()
            .flat_map(|&i| (0..3).map(move |c| 4 * i + c))
            .map(|k| (f64::from(denoised[k]) - f64::from(other[k])).powi(2))
            .sum()
    };
    let mut best = (0u32, error(exact));
    for (k, frame) in past.iter().enumerate() {
        let e = error(frame);
        if e < best.1 {
            best = (k as u32 + 1, e);
        }
    }
    Some(best.0)
}

fn mean(v: impl Iterator<Item = f64>) -> Option<f64> {
    let v: Vec<f64> = v.collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// One light count's renderers and the rows of its frames so far.
struct Sequence {
    lights: usize,
    /// The scene's own instance transforms and camera (what the frames move from).
    scene: manyshadows::scene::Scene,
    plain: Renderer,
    denoised: Renderer,
    exact: Option<Renderer>,
    /// Shadow maps: the same technique with every light.
    every: Option<Renderer>,
    /// The caster that circles, and the circle's radius.
    mover: Option<usize>,
    radius: f32,
    rows: Vec<FrameRow>,
    /// The last exact frames, newest first (for the trail).
    past: std::collections::VecDeque<Vec<u8>>,
    /// The animation played (`--animation`), if this sequence moves with it.
    clock: Option<Clock>,
    /// With --animation: whether this sequence plays it ("moving") or holds it ("frozen").
    animation: Option<&'static str>,
}

impl Sequence {
    /// `clock`: the animation the frames play (`None`: none plays); `frozen`: the animation
    /// whose first frame this sequence holds throughout, as the moving one's twin.
    fn new(
        h: &Harness,
        args: &DenoiseArgs,
        n: usize,
        reference: bool,
        (clock, frozen): (Option<Clock>, Option<Clock>),
    ) -> Result<Self> {
        let mut scene = seeded_scene(&args.scene, n, LightMix::All, None)?;
        // Animated or frozen, the frames start from the pose at 0 s.
        if let Some(c) = clock.or(frozen) {
            scene.set_time(c.playing, c.start);
        }
        let base = RenderSettings::new(args.width, args.height)
            .with_technique(args.technique)
            .with_clusters(match args.cluster_tile {
                Some(t) => manyshadows::ClusterOptions::default().with_tile(t),
                None => manyshadows::ClusterOptions::default(),
            });
        let sampled = RayOptions::default()
            .with_light_samples(args.light_samples)
            .with_reuse(args.reuse)
            .with_spatial(args.spatial);
        let make = |rays: RayOptions| Renderer::new(&h.ctx, &scene, base.clone().with_rays(rays));
        let plain = make(sampled)?;
        let denoised = make(sampled.with_denoise(true))?;
        let maps = args.technique.info().fills != manyshadows::Fills::Rays;
        let exact_rays = RayOptions::default().with_area_samples(args.reference_area_samples);
        let rays = crate::techniques::first_filling(manyshadows::Fills::Rays);
        let exact = match (reference, maps) {
            (false, _) => None,
            (true, false) => Some(make(exact_rays)?),
            // Over shadow maps the exact frames need ray queries, which the adapter may lack.
            (true, true) => match Renderer::new(
                &h.ctx,
                &scene,
                base.clone().with_technique(rays).with_rays(exact_rays),
            ) {
                Ok(r) => Some(r),
                Err(e) => {
                    h.note(format!(
                        "{n} lights: no exact frames ({rays}: {e}); scored against every light \
                         through the same maps only"
                    ));
                    None
                }
            },
        };
        let every = maps.then(|| make(RayOptions::default())).transpose()?;
        let still = args.still || frozen.is_some();
        let mover =
            crate::render::moving_instance(args.move_instance, still, &scene, clock, || {
                seen_caster(&h.ctx, &scene)
            })?;
        let radius = mover.map_or(0.0, |k| 0.5 * caster_size(&scene, k));
        match mover {
            Some(k) => h.note(format!(
                "{n} lights: instance {k} circles (radius {radius:.2})"
            )),
            None if !still && clock.is_none() => h.note(format!(
                "{n} lights: no caster near the camera moves a pixel when moved: none moves"
            )),
            None => {}
        }
        Ok(Self {
            lights: n,
            scene,
            plain,
            denoised,
            exact,
            every,
            mover,
            radius,
            rows: Vec::new(),
            past: Default::default(),
            clock,
            animation: match (clock, frozen) {
                (Some(_), _) => Some("moving"),
                (None, Some(_)) => Some("frozen"),
                (None, None) => None,
            },
        })
    }

    /// Frame `f` (from 0): the camera and caster set alike on every renderer, each rendered,
    /// the row kept.
    fn frame(
        &mut self,
        h: &Harness,
        args: &DenoiseArgs,
        path: Option<&[[f32; 6]]>,
        f: u32,
    ) -> Result<()> {
        let scene = &self.scene;
        let mut renderers: Vec<&mut Renderer> = vec![&mut self.plain, &mut self.denoised];
        renderers.extend(self.exact.as_mut());
        renderers.extend(self.every.as_mut());
        if let Some(path) = path {
            let c = path[(f as usize).min(path.len() - 1)];
            let mut cam = scene.camera;
            cam.position = glam::Vec3::new(c[0], c[1], c[2]);
            cam.target = glam::Vec3::new(c[3], c[4], c[5]);
            for r in renderers.iter_mut() {
                r.set_camera(cam)?;
            }
        }
        if self.clock.is_some() {
            let sequence = crate::render::Sequence {
                path: None,
                orbit: 0.0,
                mover: None,
                clock: self.clock,
            };
            sequence.step(f, scene, &mut renderers)?;
        }
        if f > 0 {
            for r in renderers.iter_mut() {
                if let Some(k) = self.mover {
                    // A circle in the ground plane of half the caster's size, a step of 0.35
                    // radians a frame.
                    let a = f as f32 * 0.35;
                    let offset = self.radius * glam::Vec3::new(a.cos() - 1.0, 0.0, a.sin());
                    r.set_instance_transform(
                        k,
                        glam::Mat4::from_translation(offset) * scene.instances[k].transform,
                    )?;
                }
                if args.orbit != 0.0 && path.is_none() {
                    let mut cam = scene.camera;
                    let turn = glam::Quat::from_axis_angle(
                        cam.up.normalize(),
                        (args.orbit * f as f32).to_radians(),
                    );
                    cam.position = cam.target + turn * (cam.position - cam.target);
                    r.set_camera(cam)?;
                }
            }
        }
        let p = self.plain.render()?;
        h.advance(1);
        let d = self.denoised.render()?;
        h.advance(1);
        // The renderers that may be absent: rendered and counted where present.
        let optional = |r: Option<&mut Renderer>| -> Result<Option<Frame>> {
            let Some(r) = r else { return Ok(None) };
            let f = r.render()?;
            h.advance(1);
            Ok(Some(f))
        };
        let e = optional(self.exact.as_mut())?;
        let every = optional(self.every.as_mut())?;
        let pages = |f: &Frame| f.virtual_maps.as_ref().map(|v| v.drawn);
        let trail_frames = match &e {
            Some(e) if args.orbit == 0.0 && !args.still && path.is_none() => {
                let t = trail(&d.rgba, &e.rgba, &self.past);
                self.past.push_front(e.rgba.clone());
                self.past.truncate(TRAIL_FRAMES);
                t
            }
            _ => None,
        };
        self.rows.push(FrameRow {
            frame: f + 1,
            trail_frames,
            plain_rmse: e.as_ref().map(|e| rmse_rgb(&p, e)),
            denoised_rmse: e.as_ref().map(|e| rmse_rgb(&d, e)),
            plain_ms: p.timings.gpu_ms.total(),
            denoised_ms: d.timings.gpu_ms.total(),
            denoised_lighting_ms: d.timings.gpu_ms.get(Stage::Lighting),
            denoise_ms: d.timings.gpu_ms.get(Stage::Denoise),
            exact_ms: e.as_ref().and_then(|e| e.timings.gpu_ms.total()),
            plain_every_rmse: every.as_ref().map(|e| rmse_rgb(&p, e)),
            denoised_every_rmse: every.as_ref().map(|e| rmse_rgb(&d, e)),
            every_ms: every.as_ref().and_then(|e| e.timings.gpu_ms.total()),
            every_exact_rmse: every.as_ref().zip(e.as_ref()).map(|(v, e)| rmse_rgb(v, e)),
            denoised_pages: pages(&d),
            every_pages: every.as_ref().and_then(pages),
        });
        Ok(())
    }

    fn record(self) -> Record {
        let rows = self.rows;
        let med = |v: Vec<f64>| (!v.is_empty()).then(|| median(&v));
        let plain_median_ms = med(rows.iter().filter_map(|r| r.plain_ms).collect());
        let denoised_median_ms = med(rows.iter().filter_map(|r| r.denoised_ms).collect());
        Record {
            lights: self.lights,
            animation: self.animation,
            plain_mean_rmse: mean(rows.iter().filter_map(|r| r.plain_rmse)),
            denoised_mean_rmse: mean(rows.iter().filter_map(|r| r.denoised_rmse)),
            cost_ratio: crate::bench::harness::ratio(denoised_median_ms, plain_median_ms),
            cost_ratio_paired: med(rows
                .iter()
                .filter_map(|r| crate::bench::harness::ratio(r.denoised_ms, r.plain_ms))
                .collect()),
            denoise_median_ms: med(rows.iter().filter_map(|r| r.denoise_ms).collect()),
            mean_trail_frames: mean(rows.iter().filter_map(|r| r.trail_frames.map(f64::from))),
            plain_every_mean_rmse: mean(rows.iter().filter_map(|r| r.plain_every_rmse)),
            denoised_every_mean_rmse: mean(rows.iter().filter_map(|r| r.denoised_every_rmse)),
            every_median_ms: med(rows.iter().filter_map(|r| r.every_ms).collect()),
            every_exact_mean_rmse: mean(rows.iter().filter_map(|r| r.every_exact_rmse)),
            denoised_over_every_paired: med(rows
                .iter()
                .filter_map(|r| crate::bench::harness::ratio(r.denoised_ms, r.every_ms))
                .collect()),
            denoised_mean_pages: mean(rows.iter().filter_map(|r| r.denoised_pages.map(f64::from))),
            every_mean_pages: mean(rows.iter().filter_map(|r| r.every_pages.map(f64::from))),
            plain_median_ms,
            denoised_median_ms,
            frames: rows,
        }
    }
}

/// The clock of `--animation` on the scene (checked: a scene without animations, an unknown
/// name, a rate that is not a positive number, are refused by name), frames from 0 s.
fn animation_clock(args: &DenoiseArgs) -> Result<Option<Clock>> {
    let Some(asked) = &args.animation else {
        return Ok(None);
    };
    if !(args.fps.is_finite() && args.fps > 0.0 && args.fps <= 10_000.0) {
        bail!(
            "--fps {}: must be a number of frames per second above 0, at most 10,000",
            args.fps
        );
    }
    if args.move_instance.is_some() {
        bail!(
            "--move-instance: with --animation the scene's animation moves it, no caster circles"
        );
    }
    let scene = seeded_scene(&args.scene, 1, LightMix::All, None)?;
    let flags = crate::args::AnimationArgs {
        animation: Some(asked.clone()),
        time: None,
        fps: Some(args.fps),
    };
    flags.clock(&scene, args.frames.max(2))
}

/// Runs `manyshadows bench denoise`.
pub fn denoise(args: &DenoiseArgs) -> Result<()> {
    check_counts("--lights", &args.lights, builtin::MAX_LIGHTS, "")?;
    check_scene("--scene", &args.scene)?;
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    if !args.orbit.is_finite() {
        bail!("--orbit must be a finite number of degrees");
    }
    let reference = args.reference == "on";
    if !matches!(
        args.technique.info().fills,
        manyshadows::Fills::Rays | manyshadows::Fills::Atlas | manyshadows::Fills::Pages
    ) {
        bail!(
            "--technique {}: it cannot sample lights (irregular maps answer every light in one \
             mask); use raytraced, virtual or an atlas technique",
            args.technique
        );
    }
    let maps = args.technique.info().fills != manyshadows::Fills::Rays;
    let path = crate::args::read_camera_path(args.camera_path.as_deref())?;
    let h = Harness::start_unscheduled(&args.output)?;
    let per_frame = 2 + u64::from(reference) + u64::from(maps);
    let twins = if args.animation.is_some() { 2 } else { 1 };
    h.plan(args.lights.len() as u64 * u64::from(args.frames) * per_frame * twins);
    // Every light count's renderers first, then the frames in turn across them (frame 1 of
    // each count, frame 2 of each, ...), so that a drift of the machine's speed during the run
    // weighs on every count alike and the growth between counts is a same-run ratio.
    let clock = animation_clock(args)?;
    let mut sequences = Vec::new();
    for &n in &args.lights {
        h.message(format!("{}, {n} lights: building", args.scene));
        sequences.push(Sequence::new(&h, args, n, reference, (clock, None))?);
        if clock.is_some() {
            sequences.push(Sequence::new(&h, args, n, reference, (None, clock))?);
        }
    }
    for f in 0..args.frames {
        for q in sequences.iter_mut() {
            h.message(format!(
                "{}, {} lights{}: frame {}/{}",
                args.scene,
                q.lights,
                q.animation.map_or(String::new(), |a| format!(", {a}")),
                f + 1,
                args.frames
            ));
            q.frame(&h, args, path.as_deref(), f)?;
        }
    }
    let records: Vec<Record> = sequences.into_iter().map(Sequence::record).collect();
    let table = table(
        &heading(args, &h.adapter),
        args.reuse,
        args.reference_area_samples,
        &records,
    );
    type Pick = fn(&FrameRow) -> Option<f64>;
    let per_frame = |picks: &[(&str, Pick)]| {
        let mut series = Vec::new();
        for r in &records {
            for (name, pick) in picks {
                let points: Vec<(f64, f64)> = r
                    .frames
                    .iter()
                    .filter_map(|x| pick(x).map(|v| (f64::from(x.frame), v)))
                    .collect();
                if !points.is_empty() {
                    series.push((
                        format!(
                            "{} lights{}, K = {} {name}",
                            r.lights,
                            r.animation.map_or(String::new(), |a| format!(" {a}")),
                            args.light_samples
                        ),
                        points,
                    ));
                }
            }
        }
        series
    };
    let figures = vec![Figure::Panels {
        file: "frames.png".to_string(),
        title: format!(
            "bench denoise: {} {}x{}, {} frames",
            args.scene, args.width, args.height, args.frames
        ),
        x_name: "frame",
        panels: vec![
            (
                "RMSE against every light (traced, or through the same maps)".to_string(),
                "RMSE (0-255)".to_string(),
                per_frame(&[
                    ("plain", |x| x.plain_rmse),
                    ("denoised", |x| x.denoised_rmse),
                    ("plain vs every light (same maps)", |x| x.plain_every_rmse),
                    ("denoised vs every light (same maps)", |x| {
                        x.denoised_every_rmse
                    }),
                ]),
            ),
            (
                "GPU time per frame".to_string(),
                "ms".to_string(),
                per_frame(&[
                    ("plain", |x| x.plain_ms),
                    ("denoised", |x| x.denoised_ms),
                    ("every light (same maps)", |x| x.every_ms),
                ]),
            ),
        ],
    }];
    h.finish(
        table,
        Fields {
            scene: &args.scene,
            width: args.width,
            height: args.height,
            orbit_degrees_per_frame: args.orbit,
            caster_moves: !args.still,
            light_samples: args.light_samples,
            technique: args.technique.to_string(),
            reuse: args.reuse,
            spatial: args.spatial.name(),
            reference_area_samples: args.reference_area_samples,
            records,
        },
        figures,
    )
}

/// The first lines of results.txt: what ran, on which adapter.
fn heading(args: &DenoiseArgs, adapter: &str) -> String {
    let camera = match &args.camera_path {
        Some(p) => format!("camera along {}", p.display()),
        None => format!("camera {} deg/frame", args.orbit),
    };
    format!(
        "== bench denoise: {} at {}x{}, {} frames, {camera}, {}; K = {}, visibility from {}{}\n   adapter: {adapter}\n",
        args.scene,
        args.width,
        args.height,
        args.frames,
        if args.still {
            "no caster moving"
        } else {
            "a caster circling"
        },
        args.light_samples,
        match args.technique.info().fills {
            manyshadows::Fills::Rays => "shadow rays".to_string(),
            _ => format!("{}'s shadow maps", args.technique),
        },
        match (args.reuse, args.spatial) {
            (false, _) => String::new(),
            (true, manyshadows::SpatialReuse::Off) =>
                ", lights reused across frames (plain: reuse alone)".to_string(),
            (true, m) => format!(
                ", lights reused across frames and between neighbours ({}; plain: without the denoiser)",
                m.name()
            ),
        }
    )
}
