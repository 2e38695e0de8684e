//! `manyshadows bench soak`: thousands of frames in which everything moves — the camera turns,
//! a shadow caster circles, a light circles, and the light count changes every so often — to
//! show that memory stays flat, no frame fails, and frame times stay stable.
//!
//! Memory is the process's resident set (`/proc/self/statm`): on the CPU adapters this project
//! runs on (lavapipe, llvmpipe) GPU buffers and textures live in process memory, so it covers
//! both; on a hardware GPU it covers the CPU side only. It is sampled after a warm-up (the
//! first frames allocate pipelines, caches and the largest light count's buffers), and the
//! verdict compares the last sample with that baseline.

use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use glam::{Mat4, Quat, Vec3};
use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::scene::LightKind;
use manyshadows::{RenderSettings, Renderer, Technique};
use serde::Serialize;

use crate::bench::harness::{median, Harness, OutputArgs};

/// Arguments of `manyshadows bench soak`.
#[derive(Args, Debug, Clone)]
pub struct SoakArgs {
    /// Built-in scene.
    #[arg(long, default_value = "cubes")]
    pub scene: String,
    /// Frames to render.
    #[arg(long, default_value_t = 2000)]
    pub frames: u32,
    /// Lights (every 250 frames the count drops to half for 50 frames, then comes back).
    #[arg(long, default_value_t = 64)]
    pub lights: usize,
    /// Shadow technique (default: the first that fills a page pool, virtual maps, whose page
    /// caching the soak exercises).
    #[arg(long, default_value_t = crate::techniques::first_filling(manyshadows::Fills::Pages), value_parser = |s: &str| s.parse::<Technique>())]
    pub technique: Technique,
    /// Keep unchanged shadow tiles / pages between frames.
    #[arg(long)]
    pub cache: bool,
    /// Image width.
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 90)]
    pub height: u32,
    /// Untimed frames before the memory baseline is taken.
    #[arg(long, default_value_t = 300)]
    pub warmup: u32,
    /// Resident-memory growth over the baseline that fails the run, MiB.
    #[arg(long, default_value_t = 64.0)]
    pub max_growth_mib: f64,
    #[command(flatten)]
    pub output: OutputArgs,
}

#[derive(Serialize)]
struct Sample {
    frame: u32,
    resident_mib: f64,
    /// Median wall ms per frame since the previous sample.
    frame_ms: f64,
    /// Median GPU ms per frame (sum of the stages) since the previous sample.
    gpu_ms: Option<f64>,
    lights: usize,
}

/// Resident memory of this process in MiB (Linux), `None` elsewhere.
fn resident_mib() -> Option<f64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0 / (1024.0 * 1024.0))
}

/// Runs `manyshadows bench soak`.
pub fn soak(args: &SoakArgs) -> Result<()> {
    if args.frames == 0 || args.warmup >= args.frames {
        bail!("--frames must be larger than --warmup ({})", args.warmup);
    }
    if args.lights == 0 || args.lights > builtin::MAX_LIGHTS {
        bail!("--lights must be 1..={}", builtin::MAX_LIGHTS);
    }
    if resident_mib().is_none() {
        bail!("bench soak reads /proc/self/statm, which this system does not have");
    }
    let scene = builtin::build(
        &args.scene,
        &BuiltinOptions {
            lights: Some(args.lights),
            ..Default::default()
        },
    )?;
    let fewer = builtin::build(
        &args.scene,
        &BuiltinOptions {
            lights: Some(args.lights.div_ceil(2)),
            seed: 2,
            ..Default::default()
        },
    )?
    .lights;
    let h = Harness::start_unscheduled(&args.output)?;
    let mut r = Renderer::new(
        &h.ctx,
        &scene,
        RenderSettings::default()
            .with_width(args.width)
            .with_height(args.height)
            .with_technique(args.technique)
            .with_cache_shadows(args.cache),
    )?;
    // The smallest shadow caster circles; light 0 circles if it has a position.
    let mover = scene
        .instances
        .iter()
        .enumerate()
        .filter(|(_, i)| i.casts_shadows)
        .min_by(|a, b| {
            let size = |i: &manyshadows::scene::Instance| {
                scene.meshes[i.mesh]
                    .bounds()
                    .map_or(f32::MAX, |(lo, hi)| (hi - lo).length())
            };
            size(a.1).total_cmp(&size(b.1))
        })
        .map(|(k, _)| k);
    h.plan(u64::from(args.frames));
    let every = (args.frames / 20).max(1);
    let mut samples = Vec::new();
    let (mut walls, mut gpus) = (Vec::new(), Vec::new());
    let mut baseline = None;
    for f in 0..args.frames {
        let t = f as f32;
        let mut cam = r.scene().camera;
        let turn = Quat::from_axis_angle(cam.up.normalize(), 0.5f32.to_radians());
        cam.position = cam.target + turn * (cam.position - cam.target);
        r.set_camera(cam)?;
        if let Some(k) = mover {
            let a = t * 0.05;
            let offset = Vec3::new(0.5 * a.cos() - 0.5, 0.0, 0.5 * a.sin());
            r.set_instance_transform(
                k,
                Mat4::from_translation(offset) * scene.instances[k].transform,
            )?;
        }
        // Fewer lights for 50 frames out of every 250, then all of them again.
        let phase = f % 250;
        if phase == 200 {
            r.set_lights(fewer.clone())?;
        } else if phase == 0 && f > 0 {
            r.set_lights(scene.lights.clone())?;
        }
        if phase < 200 {
            let mut light = scene.lights[0];
            if let LightKind::Spot { position, .. } | LightKind::Point { position, .. } =
                &mut light.kind
            {
                *position += Vec3::new(0.3 * (t * 0.03).cos(), 0.0, 0.3 * (t * 0.03).sin());
            }
            r.set_light(0, light)?;
        }
        let started = Instant::now();
        let frame = r
            .render()
            .with_context(|| format!("frame {} of the soak failed", f + 1))?;
        walls.push(started.elapsed().as_secs_f64() * 1e3);
        if !frame.timings.gpu_ms.is_empty() {
            gpus.push(frame.timings.gpu_ms.iter().map(|(_, v)| v).sum::<f64>());
        }
        h.advance(1);
        if f + 1 == args.warmup {
            baseline = resident_mib();
            walls.clear();
            gpus.clear();
        }
        if f + 1 > args.warmup && ((f + 1) % every == 0 || f + 1 == args.frames) {
            let rss = resident_mib().unwrap_or(0.0);
            h.message(format!("frame {}, {rss:.0} MiB resident", f + 1));
            samples.push(Sample {
                frame: f + 1,
                resident_mib: rss,
                frame_ms: median(&walls),
                gpu_ms: (!gpus.is_empty()).then(|| median(&gpus)),
                lights: r.scene().lights.len(),
            });
            walls.clear();
            gpus.clear();
        }
    }
    let baseline = baseline.unwrap_or(0.0);
    let last = samples.last().map_or(baseline, |s| s.resident_mib);
    let peak = samples
        .iter()
        .map(|s| s.resident_mib)
        .fold(baseline, f64::max);
    let growth = last - baseline;
    let frame_ms: Vec<f64> = samples.iter().map(|s| s.frame_ms).collect();
    let (fastest, slowest) = frame_ms
        .iter()
        .fold((f64::MAX, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let mut text = format!(
        "== bench soak: {} frames of {} ({} lights, half of them 50 frames in 250), {} at {}x{}{}; camera, a caster and a light move every frame\n   adapter: {}\n",
        args.frames,
        args.scene,
        args.lights,
        args.technique,
        args.width,
        args.height,
        if args.cache { ", caching" } else { "" },
        h.adapter
    );
    text += &format!(
        "{:>7} {:>12} {:>10} {:>10} {:>7}\n",
        "frame", "resident MiB", "wall ms", "GPU ms", "lights"
    );
    text += &format!(
        "{:>7} {:>12.1} {:>10} {:>10} {:>7}   (baseline after {} warm-up frames)\n",
        args.warmup, baseline, "", "", "", args.warmup
    );
    for s in &samples {
        text += &format!(
            "{:>7} {:>12.1} {:>10.2} {:>10} {:>7}\n",
            s.frame,
            s.resident_mib,
            s.frame_ms,
            s.gpu_ms.map_or("n/a".into(), |v| format!("{v:.2}")),
            s.lights
        );
    }
    text += &format!(
        "   resident memory: baseline {baseline:.1} MiB, peak {peak:.1}, last {last:.1} ({growth:+.1} MiB); median wall ms per sample interval {fastest:.2}..{slowest:.2}\n"
    );
    let fields = serde_json::json!({
        "scene": args.scene,
        "technique": args.technique.name(),
        "cache": args.cache,
        "frames": args.frames,
        "warmup": args.warmup,
        "baseline_resident_mib": baseline,
        "peak_resident_mib": peak,
        "growth_mib": growth,
        "samples": samples,
    });
    h.finish(text, fields, Vec::new())?;
    if growth > args.max_growth_mib {
        bail!(
            "resident memory grew {growth:.1} MiB over the soak (more than --max-growth-mib {})",
            args.max_growth_mib
        );
    }
    Ok(())
}
