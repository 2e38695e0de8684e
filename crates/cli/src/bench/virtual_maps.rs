//! `manyshadows bench virtual`: virtual shadow maps against the atlas path, frame by frame in
//! the same run, from 16 to 4,096 lights.
//!
//! For every light count it renders the same scene and camera with the atlas technique
//! (`--atlas-technique`, default `traditional`, default atlas cap) and with `--technique
//! virtual` (default pool), interleaved frame by frame so drift on the machine hits both
//! alike, and reports the median GPU time per stage, the shadow memory each keeps (atlas,
//! or page pool plus page table), and for the virtual maps the pages asked for, rendered and
//! denied, and the faces; for the atlas the views and how they were fitted.

use anyhow::{bail, Context, Result};
use clap::Args;
use manyshadows::scene::builtin::{self, LightMix};
use manyshadows::Stage;
use manyshadows::{RenderSettings, Renderer, Technique};
use manyshadows::{VirtualOptions, VirtualStats};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, check_scene, ms, seeded_scene, Contender, Figure, FrameCounters, FrameSubject,
    Harness, RunArgs, Runs,
};
use crate::bench::plot::series;

/// Arguments of `manyshadows bench virtual`.
#[derive(Args, Debug, Clone)]
pub struct VirtualArgs {
    /// Built-in scene.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// Numbers of lights, comma-separated (1 to 16384 each).
    #[arg(long, default_value = "16,64,256,1024,4096", value_delimiter = ',')]
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
    /// The atlas technique to compare with.
    #[arg(long, default_value_t = Technique::default(), value_parser = |s: &str| s.parse::<Technique>())]
    pub atlas_technique: Technique,
    /// The paged technique to measure against it.
    #[arg(long, default_value_t = crate::techniques::first_filling(manyshadows::Fills::Pages), value_parser = |s: &str| s.parse::<Technique>())]
    pub technique: Technique,
    /// Page pool of the virtual maps, MiB. Default: as many bytes as the atlas keeps at
    /// each light count (equal memory: 64 MiB at 16 lights of the atrium, 256 MiB from 64
    /// up), at least one page.
    #[arg(long)]
    pub page_pool: Option<u32>,
    /// Virtual faces no coarser than the atlas's tiles (`on`, default) or as the screen asks
    /// (`off`; `render --virtual-atlas-floor`).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub virtual_atlas_floor: String,
    /// Both paths keep what did not change (the atlas its unchanged views, the virtual maps
    /// their pages away from the change) while the scene's smallest caster moves each frame:
    /// what a frame costs when one thing moves, instead of every map drawn anew
    #[arg(long)]
    pub cache: bool,
    #[command(flatten)]
    pub run: RunArgs,
}

#[derive(Serialize, Default, Clone)]
struct Side {
    gbuffer_ms: Option<f64>,
    clusters_ms: Option<f64>,
    /// Virtual maps only: page marking and allocation.
    pages_ms: Option<f64>,
    shadows_ms: Option<f64>,
    lighting_ms: Option<f64>,
    /// Median over the frames of the stages' sum.
    frame_ms: Option<f64>,
    /// Shadow memory kept by the technique: the atlas, or the pool plus the page table (and
    /// last frame's table with caching).
    shadow_mib: f64,
}

#[derive(Serialize)]
struct Record {
    lights: usize,
    atlas: Side,
    atlas_views: usize,
    atlas_fit: manyshadows::shadows::plan::FitReport,
    atlas_side: u32,
    virtual_maps: Side,
    /// Median frame GPU time of the virtual maps over the atlas's, from the same run.
    frame_ratio_virtual_vs_atlas: Option<f64>,
    stats: VirtualStats,
}

fn side(runs: &Runs<FrameCounters>, shadow_mib: f64) -> Side {
    Side {
        gbuffer_ms: runs.stage(Stage::GBuffer),
        clusters_ms: runs.stage(Stage::Clusters),
        pages_ms: runs.stage(Stage::Pages),
        shadows_ms: runs.stage(Stage::Shadows),
        lighting_ms: runs.stage(Stage::Lighting),
        frame_ms: runs.gpu_ms(),
        shadow_mib,
    }
}

const MIB: f64 = 1024.0 * 1024.0;

/// Runs `manyshadows bench virtual`.
pub fn virtual_maps(args: &VirtualArgs) -> Result<()> {
    check_counts("--lights", &args.lights, builtin::MAX_LIGHTS, "")?;
    crate::techniques::require_atlas("--atlas-technique", args.atlas_technique)?;
    if args.technique.info().fills != manyshadows::Fills::Pages {
        bail!(
            "--technique {}: pick a technique that fills a page pool ({})",
            args.technique,
            crate::techniques::names(&crate::techniques::filling(manyshadows::Fills::Pages))
        );
    }
    check_scene("--scene", &args.scene)?;
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    let h = Harness::start(&args.run)?;
    h.plan(h.units(2 * args.lights.len(), 1));
    let mut records = Vec::new();
    for &n in &args.lights {
        h.message(format!("{}, {n} lights", args.scene));
        let scene = seeded_scene(&args.scene, n, mix, None)?;
        let base = RenderSettings::default()
            .with_width(args.width)
            .with_height(args.height)
            .with_cache_shadows(args.cache);
        let caster = if args.cache {
            let k = scene
                .smallest_caster()
                .context("--cache moves a caster: the scene has none")?;
            Some((k, scene.instances[k].transform))
        } else {
            None
        };
        let atlas = base.clone().with_technique(args.atlas_technique);
        let atlas_renderer = Renderer::new(&h.ctx, &scene, atlas)?;
        // Equal memory unless --page-pool says otherwise: the pool gets the atlas's bytes.
        let pool_bytes = match args.page_pool {
            Some(mib) => u64::from(mib) << 20,
            None => (u64::from(atlas_renderer.plan().layout.size).pow(2) * 4)
                .max(VirtualOptions::PAGE_BYTES),
        };
        let virt = base.with_technique(args.technique).with_virtual_maps(
            VirtualOptions::default()
                .with_pool_bytes(pool_bytes)
                .with_atlas_floor(args.virtual_atlas_floor == "on"),
        );
        let contenders = vec![
            Contender {
                label: "atlas".into(),
                subject: FrameSubject::moving(atlas_renderer, caster),
            },
            Contender {
                label: "virtual".into(),
                // A pool out of range names --page-pool, as render does.
                subject: FrameSubject::moving(
                    Renderer::new(&h.ctx, &scene, virt).map_err(crate::args::flag_error)?,
                    caster,
                ),
            },
        ];
        let [a, v]: [_; 2] = h
            .compare(contenders, Some("atlas"))?
            .try_into()
            .map_err(|_| anyhow::anyhow!("two contenders, two outcomes"))?;
        let stats = v
            .runs
            .counters()
            .virtual_maps
            .context("the virtual renderer reported no page counters")?;
        let plan = a.subject.renderer.plan();
        let atlas_bytes = (plan.layout.size as f64).powi(2) * 4.0;
        records.push(Record {
            lights: n,
            atlas: side(&a.runs, atlas_bytes / MIB),
            atlas_views: plan.views.len(),
            atlas_fit: plan.fit,
            atlas_side: plan.layout.size,
            virtual_maps: side(&v.runs, stats.kept_bytes() as f64 / MIB),
            frame_ratio_virtual_vs_atlas: v.gpu_ratio,
            stats,
        });
    }
    let table = table(&records, &h.adapter, args);
    let figure = figure(&records, args);
    let fields = serde_json::json!({
        "scene": args.scene,
        "screen": [args.width, args.height],
        "light_types": args.light_types,
        "atlas_technique": args.atlas_technique.name(),
        "cache": args.cache,
        "page_pool_mib": args.page_pool,
        "virtual_atlas_floor": args.virtual_atlas_floor,
        "records": records,
    });
    h.finish(table, fields, vec![figure])
}

fn table(records: &[Record], adapter: &str, args: &VirtualArgs) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "== bench virtual: {} at {}x{}, light types {}; median GPU ms over {} frames, {} vs virtual in the same run{}; {}\n   adapter: {adapter}",
        args.scene, args.width, args.height, args.light_types, args.run.repeats, args.atlas_technique,
        if args.cache { "; --cache: both keep what did not change while the smallest caster moves each frame" } else { "; every map drawn anew each frame" },
        match args.page_pool {
            Some(mib) => format!("page pool {mib} MiB"),
            None => "page pool as large as the atlas (equal memory)".to_string(),
        }
    );
    let _ = writeln!(
        t,
        "{:>6} | {:>9} {:>9} {:>8} {:>7} | {:>8} {:>9} {:>9} {:>8} {:>7} | {:>6} | {:>6} {:>7} {:>8} {:>6} {:>6}",
        "lights", "shadows", "lighting", "frame", "MiB",
        "pages", "shadows", "lighting", "frame", "MiB",
        "ratio",
        "faces", "asked", "resident", "drawn", "denied"
    );
    let _ = writeln!(
        t,
        "{:>6} | {:^37} | {:^46} | {:>6} |",
        "",
        format!("atlas ({})", args.atlas_technique),
        "virtual",
        "frame"
    );
    for r in records {
        let ratio = r
            .frame_ratio_virtual_vs_atlas
            .map_or("n/a".into(), |v| format!("{v:.2}"));
        let _ = writeln!(
            t,
            "{:>6} | {:>9} {:>9} {:>8} {:>7.0} | {:>8} {:>9} {:>9} {:>8} {:>7.0} | {:>6} | {:>6} {:>7} {:>8} {:>6} {:>6}",
            r.lights,
            ms(r.atlas.shadows_ms),
            ms(r.atlas.lighting_ms),
            ms(r.atlas.frame_ms),
            r.atlas.shadow_mib,
            ms(r.virtual_maps.pages_ms),
            ms(r.virtual_maps.shadows_ms),
            ms(r.virtual_maps.lighting_ms),
            ms(r.virtual_maps.frame_ms),
            r.virtual_maps.shadow_mib,
            ratio,
            r.stats.fit.faces,
            r.stats.asked_total(),
            r.stats.resident,
            r.stats.drawn,
            r.stats.denied,
        );
    }
    let _ = writeln!(
        t,
        "   frame: sum of the stages (G-buffer, clusters, pages, shadows, lighting); ratio: \
         virtual / atlas; MiB: shadow memory kept (atlas, or page pool + page table, + last frame's table with caching); asked / \
         resident / drawn / denied: pages of the last measured frame (asked: by a sample; \
         drawn: this frame, the rest of the resident ones kept; denied ones fell back to \
         coarser levels)."
    );
    t
}

fn figure(records: &[Record], args: &VirtualArgs) -> Figure {
    let rows: Vec<&Record> = records.iter().collect();
    let series =
        |name: &str, f: &dyn Fn(&Record) -> Option<f64>| series(name, &rows, |r| r.lights, f);
    let panels = vec![
        (
            "GPU ms per frame".to_string(),
            "ms".to_string(),
            vec![
                series("atlas", &|r| r.atlas.frame_ms),
                series("virtual", &|r| r.virtual_maps.frame_ms),
            ],
        ),
        (
            "GPU ms: shadow stages".to_string(),
            "ms".to_string(),
            vec![
                series("atlas shadows", &|r| r.atlas.shadows_ms),
                series("virtual pages", &|r| r.virtual_maps.pages_ms),
                series("virtual shadows", &|r| r.virtual_maps.shadows_ms),
            ],
        ),
        (
            "pages".to_string(),
            "pages".to_string(),
            vec![
                series("asked", &|r| Some(r.stats.asked_total() as f64)),
                series("rendered", &|r| Some(r.stats.resident as f64)),
                series("denied", &|r| Some(r.stats.denied as f64)),
                series("pool", &|r| Some(r.stats.pool_pages as f64)),
            ],
        ),
        (
            "shadow memory kept".to_string(),
            "MiB".to_string(),
            vec![
                series("atlas", &|r| Some(r.atlas.shadow_mib)),
                series("page pool + table", &|r| Some(r.virtual_maps.shadow_mib)),
            ],
        ),
    ];
    Figure::Panels {
        file: format!("virtual-{}-{}x{}.png", args.scene, args.width, args.height),
        title: format!(
            "bench virtual: {}, {}x{}",
            args.scene, args.width, args.height
        ),
        x_name: "lights",
        panels,
    }
}
