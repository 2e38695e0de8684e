//! `manyshadows render`: one frame to PNG, with the check of its shadow work before it is
//! drawn.

use std::path::Path;
use std::time::Instant;

use crate::args::{check_render_args, effective_atlas_max, render_settings, RenderArgs};
use crate::progress::spinner;
use crate::scenes::load_scene;
use crate::summary::{print_summary, summary};
use anyhow::{bail, Context, Result};
use manyshadows::scene::Scene;
use manyshadows::{GpuContext, Renderer, Technique};

pub(crate) fn render(args: &RenderArgs) -> Result<()> {
    let started = Instant::now();
    check_render_args(args)?;
    let pb = spinner("loading the scene");
    let scene = load_scene(args)?;
    pb.set_message("opening the GPU");
    let ctx = GpuContext::new(&args.gpu.request())?;
    let atlas_max = pb.suspend(|| effective_atlas_max(&ctx, args.atlas_max));
    let settings = render_settings(args, atlas_max);
    pb.set_message("uploading the scene and building pipelines");
    let mut renderer = Renderer::new(&ctx, &scene, settings)?;
    pb.set_message("estimating the frame");
    let estimate = renderer.estimate_frame();
    if !args.insist {
        pb.suspend(|| check_shadow_work(&renderer, &estimate))?;
    }
    if estimate.total_ms() > LONG_FRAME_MS {
        pb.suspend(|| {
            eprintln!(
                "estimate: {} this frame ({})",
                crate::summary::describe_estimate(&estimate),
                renderer.settings().technique
            )
        });
    }
    let clock = args.animation.clock(&scene, args.frames)?;
    let mover = moving_instance(args.move_instance, args.still, &scene, clock, || {
        Ok(scene.smallest_caster())
    })?;
    let path = crate::args::read_camera_path(args.camera_path.as_deref())?;
    let long = long_frame(&estimate);
    let mut frame = None;
    // Each frame's wall time (recording until its image is back), for --json.
    let mut walls = Vec::with_capacity(args.frames as usize);
    let sequence = Sequence {
        path: path.as_deref(),
        orbit: args.orbit,
        mover,
        clock,
    };
    for f in 0..args.frames {
        pb.set_message(format!("rendering frame {}/{}", f + 1, args.frames));
        sequence.step(f, &scene, &mut [&mut renderer])?;
        let fr = if args.stages || long {
            let t0 = std::time::Instant::now();
            let f = f + 1;
            pb.set_message(format!("frame {f}: G-buffer and light clusters"));
            renderer.render_reporting(&mut |part| {
                pb.suspend(|| {
                    eprintln!(
                        "frame {f:>3}: {} done after {:.1} s",
                        part.describe(),
                        t0.elapsed().as_secs_f64()
                    )
                });
                // What the GPU works on now.
                match part {
                    manyshadows::FramePart::Camera => pb.set_message(format!("frame {f}: shadows")),
                    manyshadows::FramePart::Shadows => {
                        pb.set_message(format!("frame {f}: lighting"))
                    }
                    _ => {}
                }
            })?
        } else {
            renderer.render()?
        };
        if args.frames > 1 {
            // The technique's own words for the frame (its declaration's report).
            let line = format!("frame {:>3}: {}", f + 1, fr.report.frame);
            pb.suspend(|| eprintln!("{line}"));
        }
        if let Some(dir) = &args.out_dir {
            let path = dir.join(format!("frame_{:04}.png", f + 1));
            pb.suspend(|| write_rgba_png(&path, fr.width, fr.height, &fr.rgba))?;
        }
        walls.push(fr.timings.wall_ms);
        frame = Some(fr);
    }
    let frame = frame.expect("at least one frame");
    pb.set_message("writing images");
    write_rgba_png(&args.out, frame.width, frame.height, &frame.rgba)?;
    if let Some(path) = &args.atlas_out {
        let depth = renderer.read_atlas()?;
        let (side, rgb) = manyshadows::shadows::image::atlas_picture(
            &depth,
            renderer.atlas().size,
            renderer.plan(),
        );
        image::save_buffer(path, &rgb, side, side, image::ExtendedColorType::Rgb8)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let (Some(dir), Some(vis)) = (&args.visibility_out, &frame.visibility) {
        write_visibility(dir, vis, &scene)?;
    }
    pb.finish_and_clear();
    if let Some(v) = &frame.virtual_maps {
        let asked = u64::from(args.per_technique.page_pool) << 20;
        if v.pool_bytes != asked {
            eprintln!(
                "note: --page-pool {} MiB is used as a {}² pool of {} pages, {:.2} MiB (a square \
                 of whole 128² pages{})",
                args.per_technique.page_pool,
                v.pool_side,
                v.pool_pages,
                v.pool_bytes as f64 / (1 << 20) as f64,
                if v.pool_bytes < asked && v.pool_side + 128 > ctx.limits().max_texture_dimension_2d
                {
                    format!(
                        ", and this adapter's largest texture is {}",
                        ctx.limits().max_texture_dimension_2d
                    )
                } else {
                    String::new()
                }
            );
        }
    }
    let mut summary = summary(
        &ctx,
        &scene,
        &renderer,
        &frame,
        &estimate,
        args,
        started.elapsed(),
    );
    if args.frames > 1 {
        summary["frames_wall_ms"] = serde_json::json!(walls);
    }
    print_summary(&summary);
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&summary)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

pub(crate) fn write_rgba_png(path: &Path, w: u32, h: u32, rgba: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    image::save_buffer(path, rgba, w, h, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("writing {}", path.display()))
}

pub(crate) fn write_visibility(
    dir: &Path,
    vis: &manyshadows::VisibilityMask,
    scene: &Scene,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let raw = dir.join("visibility.msvis");
    let file = std::fs::File::create(&raw).with_context(|| format!("writing {}", raw.display()))?;
    vis.write_raw(std::io::BufWriter::new(file))?;
    for (i, light) in scene.lights.iter().enumerate() {
        let path = dir.join(format!("light_{i:03}_{}.png", light.type_name()));
        image::save_buffer(
            &path,
            &vis.light_image(i as u32),
            vis.width,
            vis.height,
            image::ExtendedColorType::L8,
        )
        .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// How a `--frames` sequence changes from frame to frame (`render`, `compare --frames`).
pub(crate) struct Sequence<'a> {
    /// `--camera-path`: frame k takes camera k, the last stays.
    pub(crate) path: Option<&'a [[f32; 6]]>,
    /// `--orbit`: degrees the camera turns about its target per frame (without a path).
    pub(crate) orbit: f32,
    /// The instance that moves ([`moving_instance`]).
    pub(crate) mover: Option<usize>,
    /// A file's animation, played from frame to frame (`--animation`, `--time`, `--fps`).
    pub(crate) clock: Option<crate::args::Clock>,
}

impl Sequence<'_> {
    /// The moving instance at frame `f` and its transform there (none at frame 0): a step of
    /// 0.35 radians a frame along a circle 0.3 wide in the ground plane.
    fn moved_instance(&self, f: u32, scene: &Scene) -> Option<(usize, glam::Mat4)> {
        self.mover.filter(|_| f > 0).map(|k| {
            let a = f as f32 * 0.35;
            let offset = glam::Vec3::new(0.3 * a.cos() - 0.3, 0.0, 0.3 * a.sin());
            (
                k,
                glam::Mat4::from_translation(offset) * scene.instances[k].transform,
            )
        })
    }

    /// `scene` as its geometry stands at frame `f` (what [`Self::step`] sets on the
    /// renderers, less the camera): the moving instance moved and the animation posed, for
    /// the CPU reference of that frame.
    pub(crate) fn posed(&self, f: u32, scene: &Scene) -> Scene {
        let mut posed = scene.clone();
        if let Some(c) = self.clock {
            posed.set_time(c.playing, c.at(f));
        }
        if let Some((k, m)) = self.moved_instance(f, scene) {
            posed.instances[k].transform = m;
        }
        posed
    }

    /// Sets frame `f` (from 0) of `scene`'s sequence on every renderer alike: the path's
    /// camera, and after the first frame the moving instance one step further along its
    /// circle (0.3 wide in the ground plane, 0.35 radians a frame) and the camera turned.
    pub(crate) fn step(
        &self,
        f: u32,
        scene: &Scene,
        renderers: &mut [&mut Renderer],
    ) -> Result<()> {
        let Some(first) = renderers.first() else {
            return Ok(());
        };
        let mut cam = first.scene().camera;
        let mut moved = false;
        if let Some(path) = self.path.filter(|p| !p.is_empty()) {
            let c = path[(f as usize).min(path.len() - 1)];
            cam.position = glam::Vec3::new(c[0], c[1], c[2]);
            cam.target = glam::Vec3::new(c[3], c[4], c[5]);
            moved = true;
        } else if f > 0 && self.orbit != 0.0 {
            let turn = glam::Quat::from_axis_angle(cam.up.normalize(), self.orbit.to_radians());
            cam.position = cam.target + turn * (cam.position - cam.target);
            moved = true;
        }
        let instance = self.moved_instance(f, scene);
        // Frame 0 stands at the clock's start already (the scene was loaded there).
        let now = self.clock.filter(|_| f > 0);
        for r in renderers.iter_mut() {
            if let Some(c) = now {
                r.set_time(c.playing, c.at(f))?;
            }
            if let Some((k, m)) = instance {
                r.set_instance_transform(k, m)?;
            }
            if moved {
                r.set_camera(cam)?;
            }
        }
        Ok(())
    }
}

/// The instance a sequence moves: none with `--still`, `--move-instance` checked against the
/// scene, else `default`'s choice.
/// A scene whose file animates it moves as its animation says instead (`clock`), and an
/// instance the animation moves cannot be moved as well.
pub(crate) fn moving_instance(
    asked: Option<usize>,
    still: bool,
    scene: &manyshadows::scene::Scene,
    clock: Option<crate::args::Clock>,
    default: impl FnOnce() -> Result<Option<usize>>,
) -> Result<Option<usize>> {
    match asked {
        _ if still => Ok(None),
        Some(k) if k >= scene.instances.len() => bail!(
            "--move-instance {k}: the scene has {} instances",
            scene.instances.len()
        ),
        Some(k) if clock.is_some() && scene.animations.moving.iter().any(|m| m.instance == k) => {
            bail!("--move-instance {k}: the file's animation moves that instance already")
        }
        Some(k) => Ok(Some(k)),
        None if clock.is_some() => Ok(None),
        None => default(),
    }
}

/// Most (caster triangle, view) pairs a frame may take without `--insist`: 2 G, far above
/// what the default frame asks and below the frames that run for many minutes on a CPU
/// adapter (docs/benchmarks.md, "What a frame will cost: `bench estimate`").
pub(crate) const MAX_UNASKED_TRIANGLE_VIEWS: u64 = 2_000_000_000;

/// Most milliseconds a frame may be estimated to take on a CPU adapter (whose costs the
/// estimate was fitted on) without `--insist`: 10 minutes.
pub(crate) const MAX_UNASKED_FRAME_MS: f64 = 600_000.0;

/// An estimated frame past this says its estimate first and each part as it finishes: 2 s.
pub(crate) const LONG_FRAME_MS: f64 = 2_000.0;

/// Shadow work past which `render` says each part of a frame as it finishes (`--stages`).
const STAGED_TRIANGLE_VIEWS: u64 = MAX_UNASKED_TRIANGLE_VIEWS / 10;

/// Whether the frame's shadow work passes [`STAGED_TRIANGLE_VIEWS`] or its estimate
/// [`LONG_FRAME_MS`].
pub(crate) fn long_frame(estimate: &manyshadows::FrameEstimate) -> bool {
    estimate.work.triangle_views > STAGED_TRIANGLE_VIEWS || estimate.total_ms() > LONG_FRAME_MS
}

/// Refuses, before any frame is drawn, a frame whose per-view shadow work passes
/// [`MAX_UNASKED_TRIANGLE_VIEWS`], with the estimate and the techniques that scale, or whose
/// estimated time passes [`MAX_UNASKED_FRAME_MS`] on a CPU adapter, with the stage that costs
/// most and what would shrink it.
pub(crate) fn check_shadow_work(
    renderer: &Renderer,
    estimate: &manyshadows::FrameEstimate,
) -> Result<()> {
    // The per-view bound holds for the techniques whose work is per (triangle, view) pair:
    // atlas techniques and irregular maps (virtual maps and rays scale with pixels).
    let work = &estimate.work;
    let per_view = matches!(
        renderer.settings().technique.info().fills,
        manyshadows::Fills::Atlas | manyshadows::Fills::Mask
    );
    if !per_view || work.triangle_views <= MAX_UNASKED_TRIANGLE_VIEWS {
        return check_frame_time(renderer, estimate);
    }
    let technique = renderer.settings().technique;
    let g = |n: u64| format!("{:.1} G", n as f64 / 1e9);
    let culled: Vec<&str> = Technique::all()
        .into_iter()
        .filter(|t| {
            matches!(
                t.info().culling,
                manyshadows::Culling::Instances | manyshadows::Culling::Clusters
            ) && t.info().fills == manyshadows::Fills::Atlas
        })
        .map(|t| t.name())
        .collect();
    let viewless = scaling_techniques();
    let how = if technique.info().fills == manyshadows::Fills::Mask {
        "it tests every caster triangle against every light view's grid of samples"
    } else {
        "it culls per view only after every triangle reached the view"
    };
    bail!(
        "technique {technique} would take {} (caster triangle, view) pairs this frame ({} \
         views; {how}; estimated {}), more than the {} this command starts unasked. Techniques that cull \
         whole instances or clusters per view first take at most {} here ({}); {} scale with \
         pixels and lights instead of views. Pass --insist to render it anyway.",
        g(work.triangle_views),
        work.views,
        crate::summary::describe_estimate(estimate),
        g(MAX_UNASKED_TRIANGLE_VIEWS),
        g(work.after_instance_culling),
        culled.join(", "),
        viewless.join(", ")
    );
}

/// Techniques whose work is not per (triangle, view) pair but scales with pixels and lights:
/// virtual pages and rays.
fn scaling_techniques() -> Vec<&'static str> {
    Technique::all()
        .into_iter()
        .filter(|t| {
            matches!(
                t.info().fills,
                manyshadows::Fills::Pages | manyshadows::Fills::Rays
            )
        })
        .map(|t| t.name())
        .collect()
}

/// The time half of [`check_shadow_work`].
fn check_frame_time(renderer: &Renderer, e: &manyshadows::FrameEstimate) -> Result<()> {
    if !e.calibrated || e.total_ms() <= MAX_UNASKED_FRAME_MS {
        return Ok(());
    }
    let technique = renderer.settings().technique;
    let w = &e.work;
    let m = |n: u64| format!("{:.1} M", n as f64 / 1e6);
    let advice = if e.shadows_ms >= e.lighting_ms.max(e.gbuffer_ms) {
        let scaling = scaling_techniques();
        format!(
            "most of it making shadows ({} (caster triangle, view) pairs, {} (pixel, light) \
             samples): fewer lights, or a technique whose shadows scale with pixels ({})",
            m(w.triangle_views),
            m(w.pixel_lights),
            scaling.join(", ")
        )
    } else if e.lighting_ms >= e.gbuffer_ms {
        let rays = if w.rays > 0 && renderer.settings().rays.light_samples == 0 {
            "; --light-samples K traces K rays per pixel instead of one per light in reach"
        } else {
            ""
        };
        format!(
            "most of it lighting {} (pixel, light) pairs in reach ({} shadow rays): fewer \
             pixels or lights{rays}",
            m(w.pixel_lights),
            m(w.rays)
        )
    } else {
        format!(
            "most of it the camera's {} triangles over {} pixels: fewer pixels",
            m(w.triangles),
            m(w.pixels)
        )
    };
    bail!(
        "technique {technique} is estimated at {} for this frame, more than the {} min this \
         command starts unasked; {advice}. Pass --insist to render it anyway.",
        crate::summary::describe_estimate(e),
        MAX_UNASKED_FRAME_MS / 60_000.0
    );
}
