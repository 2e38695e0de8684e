//! `manyshadows bench lights`: how a whole frame scales with the number of lights, from 16 to
//! 16,384, with clustered shading.
//!
//! Per scene, screen and light count it reports the GPU time of each stage (G-buffer, cluster
//! assignment, shadow generation, lighting), the lights per occupied cluster (mean and
//! maximum), how the shadow maps were fitted (full, reduced, unshadowed, off screen) and the
//! memory of the atlas and the cluster lists. Up to `--reference-up-to` lights it also times
//! the lighting pass looping over every light (`--light-loop all`) in the same run, frame by
//! frame interleaved with the clustered one (see [`crate::bench::harness`]), so the ratio clustered /
//! all is measured, not inferred.

use anyhow::Result;
use clap::Args;
use manyshadows::scene::builtin::{self, LightMix};
use manyshadows::LightLoop;
use manyshadows::Stage;
use manyshadows::{RenderSettings, Renderer, Technique};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, check_scene, ms, parse_screen, seeded_scene, Contender, Figure, FrameSubject,
    Harness, RunArgs,
};
use crate::bench::plot::series;

/// Arguments of `manyshadows bench lights`.
#[derive(Args, Debug, Clone)]
pub struct LightsArgs {
    /// Built-in scenes, comma-separated.
    #[arg(long, default_value = "atrium,dragon", value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Numbers of lights, comma-separated (1 to 16384 each).
    #[arg(
        long,
        default_value = "16,32,64,256,1024,4096,16384",
        value_delimiter = ','
    )]
    pub lights: Vec<usize>,
    /// Screen resolutions WxH, comma-separated.
    #[arg(long, default_value = "1280x720,1920x1080", value_delimiter = ',')]
    pub screens: Vec<String>,
    /// Light types of the seeded layout: all, spot, point or directional.
    #[arg(long, default_value = "all")]
    pub light_types: String,
    /// Shadow technique.
    #[arg(long, default_value_t = Technique::default(), value_parser = |s: &str| s.parse::<Technique>())]
    pub technique: Technique,
    /// Shadow-map side per view for every light (default: the layout's own).
    #[arg(long)]
    pub shadow_resolution: Option<u32>,
    /// Also time the lighting pass looping over every light, for counts up to this (0: never).
    #[arg(long, default_value_t = 1024)]
    pub reference_up_to: usize,
    #[command(flatten)]
    pub run: RunArgs,
}

#[derive(Serialize, Default)]
struct Record {
    scene: String,
    screen: String,
    lights: usize,
    gbuffer_ms: Option<f64>,
    clusters_ms: Option<f64>,
    shadows_ms: Option<f64>,
    lighting_ms: Option<f64>,
    /// The lighting pass with every light in every pixel's loop (same run).
    lighting_all_ms: Option<f64>,
    lights_in_view: u32,
    occupied_clusters: u32,
    mean_lights_per_cluster: f64,
    max_lights_per_cluster: u32,
    overflowed_clusters: u32,
    shadow_views: usize,
    fit: manyshadows::shadows::plan::FitReport,
    atlas_side: u32,
    atlas_mib: f64,
    cluster_lists_kib: f64,
    /// Median wall ms of a clustered frame, until its image is back on the CPU.
    wall_ms: f64,
}

/// Runs `manyshadows bench lights`.
pub fn lights(args: &LightsArgs) -> Result<()> {
    check_counts("--lights", &args.lights, builtin::MAX_LIGHTS, "")?;
    for s in &args.scenes {
        check_scene("--scenes", s)?;
    }
    let screens: Vec<(String, (u32, u32))> = args
        .screens
        .iter()
        .map(|s| parse_screen(s).map(|d| (s.clone(), d)))
        .collect::<Result<_>>()?;
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    let h = Harness::start(&args.run)?;
    // Each count renders clustered, and up to --reference-up-to also with every light.
    let loops = |n: usize| -> &'static [(&'static str, LightLoop)] {
        if n <= args.reference_up_to {
            &[("clustered", LightLoop::Clustered), ("all", LightLoop::All)]
        } else {
            &[("clustered", LightLoop::Clustered)]
        }
    };
    let per_group: u64 = args
        .lights
        .iter()
        .map(|&n| h.units(loops(n).len(), 1))
        .sum();
    h.plan(per_group * (args.scenes.len() * screens.len()) as u64);
    let mut records = Vec::new();
    for scene_name in &args.scenes {
        for (screen, (w, h_px)) in &screens {
            for &n in &args.lights {
                h.message(format!("{scene_name}, {screen}, {n} lights"));
                let scene = seeded_scene(scene_name, n, mix, args.shadow_resolution)?;
                let contenders = loops(n)
                    .iter()
                    .map(|&(label, light_loop)| {
                        // Every repeat draws its maps anew (the scene does not change).
                        let settings = RenderSettings::default()
                            .with_width(*w)
                            .with_height(*h_px)
                            .with_technique(args.technique)
                            .with_light_loop(light_loop)
                            .with_cache_shadows(false);
                        Ok(Contender {
                            label: label.into(),
                            subject: FrameSubject::new(Renderer::new(&h.ctx, &scene, settings)?),
                        })
                    })
                    .collect::<Result<Vec<_>>>()?;
                let out = h.compare(contenders, None)?;
                let lighting_all_ms = out.get(1).and_then(|o| o.runs.stage(Stage::Lighting));
                let clustered = &out[0];
                let runs = &clustered.runs;
                let c = runs.counters().clusters.unwrap_or_default();
                let plan = clustered.subject.renderer.plan();
                let side = plan.layout.size;
                records.push(Record {
                    scene: scene_name.clone(),
                    screen: screen.clone(),
                    lights: n,
                    gbuffer_ms: runs.stage(Stage::GBuffer),
                    clusters_ms: runs.stage(Stage::Clusters),
                    shadows_ms: runs.stage(Stage::Shadows),
                    lighting_ms: runs.stage(Stage::Lighting),
                    lighting_all_ms,
                    lights_in_view: c.lights_in_view,
                    occupied_clusters: c.occupied,
                    mean_lights_per_cluster: c.mean_lights,
                    max_lights_per_cluster: c.max_lights,
                    overflowed_clusters: c.overflowed,
                    shadow_views: plan.views.len(),
                    fit: plan.fit,
                    atlas_side: side,
                    atlas_mib: (side as f64).powi(2) * 4.0 / (1024.0 * 1024.0),
                    cluster_lists_kib: c.pool_bytes as f64 / 1024.0,
                    wall_ms: runs.wall_ms(),
                });
            }
        }
    }
    let table = table(&records, &h.adapter, args);
    let figures = figures(&records, args);
    let fields = serde_json::json!({
        "light_types": args.light_types,
        "technique": args.technique.name(),
        "records": records,
    });
    h.finish(table, fields, figures)
}

fn table(records: &[Record], adapter: &str, args: &LightsArgs) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "== bench lights: median GPU ms per stage over {} frames, technique {}, light types {}\n   adapter: {adapter}",
        args.run.repeats,
        args.technique.name(),
        args.light_types
    );
    let _ = writeln!(
        t,
        "{:<8} {:>10} {:>6} | {:>8} {:>8} {:>9} {:>9} {:>10} | {:>6} {:>5} {:>4} | {:>6} {:>22} {:>7} {:>8}",
        "scene", "screen", "lights", "gbuffer", "clusters", "shadows", "lighting", "light(all)",
        "mean", "max", "ovf", "views", "full/reduced/none/off", "atlas", "lists"
    );
    for r in records {
        let _ = writeln!(
            t,
            "{:<8} {:>10} {:>6} | {:>8} {:>8} {:>9} {:>9} {:>10} | {:>6.1} {:>5} {:>4} | {:>6} {:>22} {:>5}Mi {:>6}Ki",
            r.scene,
            r.screen,
            r.lights,
            ms(r.gbuffer_ms),
            ms(r.clusters_ms),
            ms(r.shadows_ms),
            ms(r.lighting_ms),
            r.lighting_all_ms.map_or("-".into(), |v| format!("{v:.1}")),
            r.mean_lights_per_cluster,
            r.max_lights_per_cluster,
            r.overflowed_clusters,
            r.shadow_views,
            format!(
                "{}/{}/{}/{}",
                r.fit.full, r.fit.reduced, r.fit.unshadowed, r.fit.off_screen
            ),
            r.atlas_mib.round(),
            r.cluster_lists_kib.round(),
        );
    }
    let _ = writeln!(
        t,
        "   mean/max: lights per occupied cluster; ovf: clusters whose list did not fit the pool \
         (they loop over every light); fit: shadowed lights with full / reduced maps, left \
         unshadowed, off screen."
    );
    t
}

fn figures(records: &[Record], args: &LightsArgs) -> Vec<Figure> {
    let mut figures = Vec::new();
    for scene in &args.scenes {
        for screen in &args.screens {
            let rows: Vec<&Record> = records
                .iter()
                .filter(|r| &r.scene == scene && &r.screen == screen)
                .collect();
            let series = |name: &str, f: &dyn Fn(&Record) -> Option<f64>| {
                series(name, &rows, |r| r.lights, f)
            };
            let panels = vec![
                (
                    "GPU ms per stage".to_string(),
                    "ms".to_string(),
                    vec![
                        series("gbuffer", &|r| r.gbuffer_ms),
                        series("clusters", &|r| r.clusters_ms),
                        series("shadows", &|r| r.shadows_ms),
                        series("lighting", &|r| r.lighting_ms),
                    ],
                ),
                (
                    "lighting pass: clustered vs every light".to_string(),
                    "ms".to_string(),
                    vec![
                        series("clustered", &|r| r.lighting_ms),
                        series("every light", &|r| r.lighting_all_ms),
                    ],
                ),
                (
                    "lights per occupied cluster".to_string(),
                    "lights".to_string(),
                    vec![
                        series("mean", &|r| Some(r.mean_lights_per_cluster)),
                        series("max", &|r| Some(r.max_lights_per_cluster as f64)),
                    ],
                ),
                (
                    "shadowed lights by map fit".to_string(),
                    "lights".to_string(),
                    vec![
                        series("full resolution", &|r| Some(r.fit.full as f64)),
                        series("reduced", &|r| Some(r.fit.reduced as f64)),
                        series("unshadowed", &|r| Some(r.fit.unshadowed as f64)),
                        series("off screen", &|r| Some(r.fit.off_screen as f64)),
                    ],
                ),
            ];
            figures.push(Figure::Panels {
                file: format!("lights-{scene}-{screen}.png"),
                title: format!("bench lights: {scene}, {screen}"),
                x_name: "lights",
                panels,
            });
        }
    }
    figures
}
