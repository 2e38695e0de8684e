//! `manyshadows bench virtual`: virtual shadow maps against the atlas path, frame by frame in
//! the same run, from 16 to 4,096 lights.
//!
//! For every light count it renders the same scene and camera with the atlas technique
//! (`--atlas-technique`, default `traditional`, default atlas cap) and with `--technique
//! virtual` (default pool), interleaved frame by frame so drift on the machine hits both
//! alike, and reports the median GPU time per stage, the shadow memory each keeps (atlas,
//! or page pool plus page table), and for the virtual maps the pages needed, rendered and
//! denied, and the faces; for the atlas the views and how they were fitted.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::vsm::{VirtualOptions, VirtualStats};
use manyshadows::{GpuContext, RenderSettings, Renderer, Technique};
use serde::Serialize;

use crate::bench::{ms, stage};
use crate::GpuArgs;

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
    #[arg(long, default_value = "traditional", value_parser = |s: &str| s.parse::<Technique>())]
    pub atlas_technique: Technique,
    /// Page pool of the virtual maps, MiB.
    #[arg(long, default_value_t = (manyshadows::vsm::DEFAULT_POOL_BYTES >> 20) as u32)]
    pub page_pool: u32,
    /// Timed frames per configuration (medians are reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Untimed frames first.
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    /// Directory for results.json, results.txt and the plot.
    #[arg(long, default_value = "bench-virtual")]
    pub out_dir: PathBuf,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Serialize, Default, Clone)]
struct Side {
    gbuffer_ms: Option<f64>,
    clusters_ms: Option<f64>,
    /// Virtual maps only: page marking and allocation.
    pages_ms: Option<f64>,
    shadows_ms: Option<f64>,
    lighting_ms: Option<f64>,
    /// Sum of the stages' medians.
    frame_ms: Option<f64>,
    /// Shadow memory kept by the technique: the atlas, or the pool plus the page table.
    shadow_mib: f64,
}

#[derive(Serialize)]
struct Record {
    lights: usize,
    atlas: Side,
    atlas_views: usize,
    atlas_fit: manyshadows::shadow::FitReport,
    atlas_side: u32,
    virtual_maps: Side,
    stats: VirtualStats,
}

fn side(frames: &[manyshadows::Frame], shadow_mib: f64) -> Side {
    let mut s = Side {
        gbuffer_ms: stage(frames, "gbuffer"),
        clusters_ms: stage(frames, "clusters"),
        pages_ms: stage(frames, "pages"),
        shadows_ms: stage(frames, "shadows"),
        lighting_ms: stage(frames, "lighting"),
        frame_ms: None,
        shadow_mib,
    };
    let parts = [
        s.gbuffer_ms,
        s.clusters_ms,
        s.pages_ms,
        s.shadows_ms,
        s.lighting_ms,
    ];
    if s.gbuffer_ms.is_some() {
        s.frame_ms = Some(parts.iter().flatten().sum());
    }
    s
}

const MIB: f64 = 1024.0 * 1024.0;

/// Runs `manyshadows bench virtual`.
pub fn virtual_maps(args: &VirtualArgs) -> Result<()> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    if let Some(&n) = args
        .lights
        .iter()
        .find(|&&n| n == 0 || n > builtin::MAX_LIGHTS)
    {
        bail!(
            "--lights {n}: each count must be 1..={}",
            builtin::MAX_LIGHTS
        );
    }
    if matches!(
        args.atlas_technique,
        Technique::Virtual | Technique::Irregular
    ) {
        bail!(
            "--atlas-technique {}: pick a technique that fills the atlas (traditional, \
             layered, multiview, gpu-driven, compute)",
            args.atlas_technique
        );
    }
    if !builtin::SCENE_NAMES.contains(&args.scene.as_str()) {
        bail!(
            "--scene {}: not a built-in scene ({})",
            args.scene,
            builtin::SCENE_NAMES.join(", ")
        );
    }
    if args.page_pool == 0 {
        bail!("--page-pool must be at least 1 MiB");
    }
    let mix: LightMix = args.light_types.parse().map_err(anyhow::Error::msg)?;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let ctx = GpuContext::new(&args.gpu.request())?;
    let adapter = manyshadows::context::describe_adapter(&ctx.info);
    eprintln!("adapter: {adapter}");
    let frames = (args.warmup + args.repeats) as u64;
    let pb = ProgressBar::new(2 * frames * args.lights.len() as u64);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {msg} [{elapsed}, ~{eta} left]")
            .expect("valid template"),
    );
    let mut records = Vec::new();
    for &n in &args.lights {
        pb.set_message(format!("{}, {n} lights", args.scene));
        let scene = builtin::build(
            &args.scene,
            &BuiltinOptions {
                lights: Some(n),
                seed: 1,
                mix,
                ..Default::default()
            },
        )?;
        let base = RenderSettings {
            width: args.width,
            height: args.height,
            ..Default::default()
        };
        let mut atlas = Renderer::new(
            &ctx,
            &scene,
            RenderSettings {
                technique: args.atlas_technique,
                ..base.clone()
            },
        )?;
        let mut virt = Renderer::new(
            &ctx,
            &scene,
            RenderSettings {
                technique: Technique::Virtual,
                virtual_maps: VirtualOptions {
                    pool_bytes: u64::from(args.page_pool) << 20,
                    ..Default::default()
                },
                ..base
            },
        )?;
        let (mut a_frames, mut v_frames) = (Vec::new(), Vec::new());
        for rep in 0..args.warmup + args.repeats {
            let a = atlas.render()?;
            pb.inc(1);
            let v = virt.render()?;
            pb.inc(1);
            if rep >= args.warmup {
                a_frames.push(a);
                v_frames.push(v);
            }
        }
        let stats = v_frames
            .last()
            .and_then(|f| f.virtual_maps)
            .context("the virtual renderer reported no page counters")?;
        let plan = atlas.plan();
        let atlas_bytes = (plan.layout.size as f64).powi(2) * 4.0;
        records.push(Record {
            lights: n,
            atlas: side(&a_frames, atlas_bytes / MIB),
            atlas_views: plan.views.len(),
            atlas_fit: plan.fit,
            atlas_side: plan.layout.size,
            virtual_maps: side(
                &v_frames,
                (stats.pool_bytes + stats.table_bytes) as f64 / MIB,
            ),
            stats,
        });
    }
    pb.finish_and_clear();
    let text = table(&records, &adapter, args);
    print!("{text}");
    std::fs::write(args.out_dir.join("results.txt"), &text)?;
    let json = serde_json::json!({
        "adapter": adapter,
        "scene": args.scene,
        "screen": [args.width, args.height],
        "light_types": args.light_types,
        "atlas_technique": args.atlas_technique.name(),
        "repeats": args.repeats,
        "warmup": args.warmup,
        "records": records,
    });
    std::fs::write(
        args.out_dir.join("results.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let path = plot(&records, &adapter, args)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

fn table(records: &[Record], adapter: &str, args: &VirtualArgs) -> String {
    use std::fmt::Write;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "== bench virtual: {} at {}x{}, light types {}; median GPU ms over {} frames, {} vs virtual in the same run\n   adapter: {adapter}",
        args.scene, args.width, args.height, args.light_types, args.repeats, args.atlas_technique
    );
    let _ = writeln!(
        t,
        "{:>6} | {:>9} {:>9} {:>8} {:>7} | {:>8} {:>9} {:>9} {:>8} {:>7} | {:>6} | {:>6} {:>7} {:>6} {:>6}",
        "lights", "shadows", "lighting", "frame", "MiB",
        "pages", "shadows", "lighting", "frame", "MiB",
        "ratio",
        "faces", "needed", "drawn", "denied"
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
        let ratio = match (r.virtual_maps.frame_ms, r.atlas.frame_ms) {
            (Some(v), Some(a)) if a > 0.0 => format!("{:.2}", v / a),
            _ => "n/a".into(),
        };
        let _ = writeln!(
            t,
            "{:>6} | {:>9} {:>9} {:>8} {:>7.0} | {:>8} {:>9} {:>9} {:>8} {:>7.0} | {:>6} | {:>6} {:>7} {:>6} {:>6}",
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
            r.stats.needed_total(),
            r.stats.resident,
            r.stats.denied,
        );
    }
    let _ = writeln!(
        t,
        "   frame: sum of the stages (G-buffer, clusters, pages, shadows, lighting); ratio: \
         virtual / atlas; MiB: shadow memory kept (atlas, or page pool + page table); needed / \
         drawn / denied: pages (denied ones fell back to coarser levels)."
    );
    t
}

fn plot(records: &[Record], adapter: &str, args: &VirtualArgs) -> Result<PathBuf> {
    let series = |name: &str, f: &dyn Fn(&Record) -> Option<f64>| {
        (
            name.to_string(),
            records
                .iter()
                .filter_map(|r| f(r).map(|v| (r.lights as f64, v)))
                .collect::<Vec<_>>(),
        )
    };
    let specs = vec![
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
                series("needed", &|r| Some(r.stats.needed_total() as f64)),
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
    let path = args.out_dir.join(format!(
        "virtual-{}-{}x{}.png",
        args.scene, args.width, args.height
    ));
    crate::plot::panels(
        &path,
        &format!(
            "bench virtual: {}, {}x{} — {adapter}",
            args.scene, args.width, args.height
        ),
        "lights",
        &specs,
    )?;
    Ok(path)
}
