//! `manyshadows bench shadows`: every kind of shadow side by side as the lights grow — the
//! default technique's atlas, the first technique of the registry that fills a page pool (virtual
//! maps), and the first that casts shadow rays, tracing every cluster light and `K` sampled
//! lights per pixel — interleaved frame by frame in one run (see [`crate::bench::harness`]).
//!
//! One shadow caster moves a little every frame (back and forth), as in a scene that lives: the
//! rays' top-level acceleration structure is rebuilt each frame (its own stage, `accel`), the
//! atlas and the pages are redrawn as without caching. The bottom-level structures are built
//! once with the renderer; `setup_ms` is each renderer's construction (pipelines, buffers and,
//! for rays, the BLAS build), waited for.

use anyhow::{bail, Result};
use clap::Args;
use manyshadows::scene::builtin::{self, LightMix};
use manyshadows::{Fills, RayOptions, RenderSettings, Renderer, Stage, Technique};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, check_scene, ms, seeded_scene, Contender, Figure, FrameCounters, FrameSubject,
    Harness, RunArgs, Runs,
};
use crate::bench::plot::series;

/// Arguments of `manyshadows bench shadows`.
#[derive(Args, Debug, Clone)]
pub struct ShadowsArgs {
    /// Built-in scene.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// Numbers of lights, comma-separated (1 to 16384 each).
    #[arg(long, default_value = "64,256,1024,4096,16384", value_delimiter = ',')]
    pub lights: Vec<usize>,
    /// Light types of the seeded layout: all, spot, point or directional.
    #[arg(long, default_value = "all")]
    pub light_types: String,
    /// Image width.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Sampled lights per pixel of the ray contenders besides the exact one, comma-separated
    /// (1 to 16 each; empty: none).
    #[arg(long, default_value = "4", value_delimiter = ',')]
    pub light_samples: Vec<u32>,
    #[command(flatten)]
    pub run: RunArgs,
}

/// A renderer whose smallest shadow caster moves back and forth by 5 cm every frame.
#[derive(Serialize, Default, Clone)]
struct Side {
    label: String,
    technique: String,
    light_samples: u32,
    /// Wall ms to build the renderer (pipelines, buffers, acceleration structures).
    setup_ms: f64,
    pages_ms: Option<f64>,
    accel_ms: Option<f64>,
    shadows_ms: Option<f64>,
    lighting_ms: Option<f64>,
    /// Median over the frames of the stages' sum.
    frame_ms: Option<f64>,
    /// Frame over the atlas's, same run.
    ratio: Option<f64>,
}

#[derive(Serialize)]
struct Record {
    lights: usize,
    sides: Vec<Side>,
}

/// Runs `manyshadows bench shadows`.
pub fn shadows(args: &ShadowsArgs) -> Result<()> {
    check_counts("--lights", &args.lights, builtin::MAX_LIGHTS, "")?;
    check_scene("--scene", &args.scene)?;
    for &k in &args.light_samples {
        if !(1..=16).contains(&k) {
            bail!("--light-samples {k}: each must be 1 to 16");
        }
    }
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    let h = Harness::start(&args.run)?;
    let atlas = Technique::default();
    let pages = crate::techniques::filling(Fills::Pages).first().copied();
    let rays = crate::techniques::filling(Fills::Rays)
        .first()
        .copied()
        .filter(|t| t.info().unmet(&h.ctx).is_empty());
    if rays.is_none() {
        h.note(format!(
            "no shadow rays here: {} lacks what the ray techniques need",
            h.adapter
        ));
    }
    // (label, technique, light samples)
    let mut methods: Vec<(String, Technique, u32)> = vec![("atlas".into(), atlas, 0)];
    if let Some(p) = pages {
        methods.push(("pages".into(), p, 0));
    }
    if let Some(r) = rays {
        methods.push(("rays".into(), r, 0));
        for &k in &args.light_samples {
            methods.push((format!("rays K={k}"), r, k));
        }
    }
    h.plan(h.units(methods.len() * args.lights.len(), 1));
    let mut records = Vec::new();
    for &n in &args.lights {
        h.message(format!("{}, {n} lights", args.scene));
        let scene = seeded_scene(&args.scene, n, mix, None)?;
        let caster = scene
            .smallest_caster()
            .map(|k| (k, scene.instances[k].transform));
        let mut contenders = Vec::new();
        let mut setup = Vec::new();
        for (label, technique, k) in &methods {
            // Every repeat draws its maps anew (the moving caster aside, nothing changes).
            let settings = RenderSettings::new(args.width, args.height)
                .with_technique(*technique)
                .with_rays(RayOptions::default().with_light_samples(*k))
                .with_cache_shadows(false);
            let t = std::time::Instant::now();
            let renderer = Renderer::new(&h.ctx, &scene, settings)?;
            h.ctx.wait_idle()?;
            setup.push(t.elapsed().as_secs_f64() * 1e3);
            contenders.push(Contender {
                label: label.clone(),
                subject: FrameSubject::moving(renderer, caster),
            });
        }
        let out = h.compare(contenders, Some("atlas"))?;
        let sides = out
            .iter()
            .zip(&methods)
            .zip(&setup)
            .map(|((o, (label, technique, k)), &setup_ms)| {
                side(label, *technique, *k, setup_ms, &o.runs, o.gpu_ratio)
            })
            .collect();
        records.push(Record { lights: n, sides });
    }
    let table = table(&records, &h.adapter, args);
    let figure = figure(&records, args);
    let fields = serde_json::json!({
        "scene": args.scene,
        "screen": [args.width, args.height],
        "light_types": args.light_types,
        "records": records,
    });
    h.finish(table, fields, vec![figure])
}

fn side(
    label: &str,
    technique: Technique,
    k: u32,
    setup_ms: f64,
    runs: &Runs<FrameCounters>,
    ratio: Option<f64>,
) -> Side {
    Side {
        label: label.into(),
        technique: technique.name().into(),
        light_samples: k,
        setup_ms,
        pages_ms: runs.stage(Stage::Pages),
        accel_ms: runs.stage(Stage::Accel),
        shadows_ms: runs.stage(Stage::Shadows),
        lighting_ms: runs.stage(Stage::Lighting),
        frame_ms: runs.gpu_ms(),
        ratio,
    }
}

fn table(records: &[Record], adapter: &str, args: &ShadowsArgs) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "== bench shadows: {} at {}x{}, light types {}; median GPU ms over {} frames, one caster \
         moving, every method in the same run\n   adapter: {adapter}",
        args.scene, args.width, args.height, args.light_types, args.run.repeats
    );
    let _ = writeln!(
        t,
        "{:>6} | {:<11} {:<12} | {:>9} {:>8} {:>9} {:>9} {:>9} | {:>6}",
        "lights", "method", "technique", "setup", "accel", "shadows", "lighting", "frame", "ratio"
    );
    for r in records {
        for s in &r.sides {
            let shadows = match (s.pages_ms, s.shadows_ms) {
                (Some(p), Some(sh)) => Some(p + sh),
                (p, sh) => p.or(sh),
            };
            let _ = writeln!(
                t,
                "{:>6} | {:<11} {:<12} | {:>9.0} {:>8} {:>9} {:>9} {:>9} | {:>6}",
                r.lights,
                s.label,
                s.technique,
                s.setup_ms,
                ms(s.accel_ms),
                ms(shadows),
                ms(s.lighting_ms),
                ms(s.frame_ms),
                s.ratio.map_or("n/a".into(), |v| format!("{v:.2}")),
            );
        }
    }
    let _ = writeln!(
        t,
        "   setup: wall ms to build the renderer (with, for rays, the per-mesh acceleration \
         structures); accel: the per-frame top-level structure rebuild; shadows: the atlas, or \
         pages + their drawing; the rays are cast in the lighting pass; frame: sum of the \
         stages; ratio: frame / the atlas's frame."
    );
    t
}

fn figure(records: &[Record], args: &ShadowsArgs) -> Figure {
    let labels: Vec<String> = records
        .first()
        .map(|r| r.sides.iter().map(|s| s.label.clone()).collect())
        .unwrap_or_default();
    let rows: Vec<&Record> = records.iter().collect();
    let by = |f: fn(&Side) -> Option<f64>| {
        labels
            .iter()
            .map(|l| {
                series(
                    l,
                    &rows,
                    |r| r.lights,
                    |r| r.sides.iter().find(|s| &s.label == l).and_then(f),
                )
            })
            .collect::<Vec<_>>()
    };
    let panels = vec![
        (
            "GPU ms per frame".to_string(),
            "ms".to_string(),
            by(|s| s.frame_ms),
        ),
        (
            "GPU ms: lighting pass".to_string(),
            "ms".to_string(),
            by(|s| s.lighting_ms),
        ),
        (
            "GPU ms: shadow work before lighting".to_string(),
            "ms".to_string(),
            by(|s| match (s.pages_ms, s.shadows_ms, s.accel_ms) {
                (None, None, None) => None,
                (p, sh, a) => Some(p.unwrap_or(0.0) + sh.unwrap_or(0.0) + a.unwrap_or(0.0)),
            }),
        ),
        (
            "renderer setup".to_string(),
            "ms".to_string(),
            by(|s| Some(s.setup_ms)),
        ),
    ];
    Figure::Panels {
        file: format!("shadows-{}-{}x{}.png", args.scene, args.width, args.height),
        title: format!(
            "bench shadows: {}, {}x{}",
            args.scene, args.width, args.height
        ),
        x_name: "lights",
        panels,
    }
}
