//! `manyshadows compare`: every shadow technique scored against the exact CPU reference.
//!
//! One frame's G-buffer is read back; `manyshadows-reference` casts a ray from each pixel's
//! surface point to each light through a BVH of every shadow-casting triangle. Each technique
//! (at each requested shadow resolution) then renders the same frame, and its hard visibility
//! mask is scored against the reference: false shadow and false light among the pixels a light
//! reaches, with errors in the edge band reported apart, plus the shadow-texel footprint in
//! screen pixels (perspective aliasing). Results: a table, optional JSON, difference images.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use manyshadows::gpu::context::describe_adapter;
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::Scene;
use manyshadows::{GpuContext, Pcf, RenderSettings, Renderer, ShadowBias, Technique};
use manyshadows_reference::aliasing::{self, Footprints, PlannedViews};
use manyshadows_reference::score::{self, class, Counts};
use manyshadows_reference::{Mask, ReferenceVisibility, SurfacePoint, Surfaces, Tracer};
use serde_json::json;

use crate::args::{GpuArgs, RenderArgs};

/// Most (pixel, light) pairs one comparison may trace: about a minute of rays on two cores.
const MAX_RAYS: u64 = 200_000_000;
/// Most (pixel, light) pairs the GPU reference traces: 1920×1080 × 2,048 lights.
const MAX_GPU_RAYS: u64 = 1920 * 1080 * 2048;

/// Who traces the reference.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceTracer {
    /// The CPU (obvhs BVH, watertight triangle test): the default truth.
    Cpu,
    /// The GPU, with ray queries (the technique that fills rays, every light of every pixel):
    /// the same rays from the same points, practical at 1080p × 1,024 lights.
    Gpu,
}
/// Largest edge band accepted, pixels.
const MAX_EDGE_BAND: u32 = 64;
/// Brightness the frame keeps under the difference colours.
const DIM: f32 = 0.35;

/// The options of `manyshadows compare`.
#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// Built-in scene name or a TOML scene file (as for `render`); several, comma-separated,
    /// are scored one after the other, each into its own sub-directory of --out-dir (e.g.
    /// `atrium,plane-spot,plane-point,plane-directional`).
    #[arg(long = "scene", default_value = "atrium", value_delimiter = ',')]
    scenes: Vec<String>,
    #[arg(skip)]
    scene: String,
    /// Techniques to score, comma-separated (default: every technique).
    #[arg(long, value_delimiter = ',', value_parser = crate::args::parse_technique)]
    techniques: Vec<Technique>,
    /// Number of lights, placed by a seeded layout. Default: 8 for the atrium (a quick run),
    /// otherwise the scene's own lights.
    #[arg(long)]
    lights: Option<usize>,
    /// Seed of the light layout.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Light types the layout uses: all (mixed), spot, point or directional.
    #[arg(long, default_value = "all")]
    light_types: String,
    /// Point-light shadows: cube or dual-paraboloid (scored by the same reference).
    #[arg(long, default_value = "cube", value_parser = crate::args::parse_point_shadows)]
    point_shadows: manyshadows::scene::light_space::PointShadows,
    /// Split every triangle into four this many times first (as for `render`).
    #[arg(long, default_value_t = 0)]
    subdivide: u32,
    /// Mesh file for the dragon scene.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Shadow-map resolutions to score, comma-separated; every technique runs at each
    /// (default: the scene's own resolutions).
    #[arg(long, value_delimiter = ',')]
    shadow_resolutions: Vec<u32>,
    /// Image width.
    #[arg(long, default_value_t = 960)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 540)]
    height: u32,
    /// Half-width of the edge band in pixels (Chebyshev distance to a reference edge).
    #[arg(long, default_value_t = 2)]
    edge_band: u32,
    /// Receiver bias towards the light, in shadow texels.
    #[arg(long, default_value_t = ShadowBias::default().constant, allow_negative_numbers = true)]
    bias_constant: f32,
    /// Receiver bias towards the light per unit of tan(angle between normal and light), texels.
    #[arg(long, default_value_t = ShadowBias::default().slope, allow_negative_numbers = true)]
    bias_slope: f32,
    /// Receiver offset along the surface normal, texels.
    #[arg(long, default_value_t = ShadowBias::default().normal_offset, allow_negative_numbers = true)]
    bias_normal: f32,
    /// Alpha-tested casters in the shadow passes: on (holes in foliage, lattices and banners
    /// let light through, as in the reference) or off (they cast as solid cards, what a
    /// renderer that ignores alpha would draw; the reference keeps its holes, so this scores
    /// that mistake).
    #[arg(long, default_value = "on", value_parser = crate::args::parse_on_off, action = clap::ArgAction::Set)]
    shadow_alpha: bool,
    /// Largest shadow-atlas side in texels (clamped to the adapter's limit).
    #[arg(long, default_value_t = manyshadows::DEFAULT_MAX_ATLAS_SIZE)]
    atlas_max: u32,
    /// Fail when the shadow maps don't fit the atlas, instead of shrinking them.
    #[arg(long)]
    strict_atlas: bool,
    /// Page pool of --techniques virtual, MiB (compare at equal memory by setting it to the
    /// atlas size the other variants report).
    #[arg(long, default_value_t = (manyshadows::shadows::vsm::plan::DEFAULT_POOL_BYTES >> 20) as u32)]
    page_pool: u32,
    /// Shadow texels per screen pixel that --techniques virtual aims for (see render --help).
    #[arg(long, default_value_t = manyshadows::shadows::vsm::plan::DEFAULT_LOD)]
    virtual_lod: f32,
    /// Factor on --virtual-lod for spot and directional lights' faces (see render --help).
    #[arg(long, default_value_t = manyshadows::shadows::vsm::plan::DEFAULT_DIRECTED_LOD)]
    virtual_directed_lod: f32,
    /// --techniques virtual's receiver bias as a fraction of the --bias-* texels (see render
    /// --help).
    #[arg(long, default_value_t = manyshadows::shadows::vsm::plan::DEFAULT_BIAS_SCALE)]
    virtual_bias: f32,
    /// Who traces the exact reference: cpu (default, the truth every technique is scored
    /// against) or gpu (ray queries; needs EXPERIMENTAL_RAY_QUERY, for frames and light counts
    /// the CPU would take too long for).
    #[arg(long, value_enum, default_value_t = ReferenceTracer::Cpu)]
    reference: ReferenceTracer,
    /// Directory for the frame, the difference images and reference.msvis.
    #[arg(long, default_value = "compare")]
    out_dir: PathBuf,
    /// Also write every number as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Also write one difference image per light and technique.
    #[arg(long)]
    per_light_images: bool,
    #[command(flatten)]
    gpu: GpuArgs,
}

/// `manyshadows compare --help`.
pub const LONG_ABOUT: &str = "\
Score every shadow technique against an exact CPU ray-traced reference.

For each pixel of one frame, the reference casts a ray from the pixel's own G-buffer point
(moved 1e-4 x max(1, |p|) along its normal) to every light that reaches it, through a BVH of
all shadow-casting triangles. Each technique renders the same frame and its hard visibility
mask (no PCF) is compared with the reference, per light type:

  false shadow  the reference sees the light, the technique shadows the pixel
  false light   the reference is shadowed, the technique lights the pixel
  edge band     pixels within --edge-band pixels of a reference shadow edge (outline, spot
                cone, range, contact line); errors there are reported apart
  footprint     screen pixels one shadow texel spans at the pixel (perspective aliasing)

Fractions are of the (pixel, light) pairs within a light's reach whose normal faces it;
pixels facing away (the light adds nothing to them) are counted apart in the JSON
(back_facing_*). Writes the lit frame,
one difference image per technique (red = false shadow, green = false light; dark red and
dark green inside the edge band; over the dimmed frame) and reference.msvis to --out-dir.

Examples:
  manyshadows compare                                          # atrium, 8 lights, all techniques
  manyshadows compare --scene plane-spot --shadow-resolutions 256,1024,2048
  manyshadows compare --scene atrium --lights 16 --shadow-resolutions 512 --json q.json";

/// Atrium lights when `--lights` is not given: a run of well under a minute on two cores.
const ATRIUM_DEFAULT_LIGHTS: usize = 8;

/// One technique at one shadow resolution.
struct Variant {
    technique: Technique,
    resolution: Option<u32>,
}

impl Variant {
    fn label(&self) -> String {
        match self.resolution {
            Some(r) => format!("{}-{r}", self.technique.name()),
            None => self.technique.name().to_string(),
        }
    }
}

/// Runs the comparison of every `--scene`.
pub fn run(args: &CompareArgs) -> Result<()> {
    if args.scenes.is_empty() {
        bail!("--scene needs at least one scene");
    }
    if args.atlas_max < manyshadows::scene::atlas::MIN_TILE {
        bail!(
            "--atlas-max {}: the atlas must hold at least one {}-texel tile",
            args.atlas_max,
            manyshadows::scene::atlas::MIN_TILE
        );
    }
    if let [one] = args.scenes.as_slice() {
        let mut a = args.clone();
        a.scene = one.clone();
        return run_scene(&a).map(|_| ());
    }
    let mut reports = Vec::new();
    for name in &args.scenes {
        let mut a = args.clone();
        a.scene = name.clone();
        let stem = Path::new(name)
            .file_stem()
            .map_or(name.clone(), |s| s.to_string_lossy().into_owned());
        a.out_dir = args.out_dir.join(&stem);
        a.json = None;
        println!("\n=== scene {name} (images in {}) ===", a.out_dir.display());
        reports.push(run_scene(&a)?);
    }
    if let Some(path) = &args.json {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        std::fs::write(
            path,
            serde_json::to_string_pretty(&json!({ "scenes": reports }))?,
        )
        .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Scores the techniques on `args.scene`; returns the JSON report.
fn run_scene(args: &CompareArgs) -> Result<serde_json::Value> {
    let started = Instant::now();
    if args.edge_band > MAX_EDGE_BAND {
        bail!(
            "--edge-band {} is more than the supported {MAX_EDGE_BAND} pixels",
            args.edge_band
        );
    }
    for &r in &args.shadow_resolutions {
        if !(1..=16384).contains(&r) {
            bail!("--shadow-resolutions: {r} must be between 1 and 16384 texels");
        }
    }
    for (name, v) in [
        ("--bias-constant", args.bias_constant),
        ("--bias-slope", args.bias_slope),
        ("--bias-normal", args.bias_normal),
    ] {
        if !v.is_finite() {
            bail!("{name} must be a finite number of texels, not {v}");
        }
    }
    let multi = MultiProgress::new();
    let pb = multi.add(crate::progress::spinner("loading the scene"));
    let scene = load(args)?;
    let pixels = args.width as u64 * args.height as u64;
    let max_rays = match args.reference {
        ReferenceTracer::Cpu => MAX_RAYS,
        ReferenceTracer::Gpu => MAX_GPU_RAYS,
    };
    if pixels * scene.lights.len() as u64 > max_rays {
        bail!(
            "{}x{} pixels x {} lights is more than {max_rays} reference rays; use fewer lights \
             or a smaller frame{}",
            args.width,
            args.height,
            scene.lights.len(),
            if args.reference == ReferenceTracer::Cpu {
                ", or --reference gpu"
            } else {
                ""
            }
        );
    }
    let mut techniques: Vec<Technique> = Vec::new();
    let asked = if args.techniques.is_empty() {
        Technique::all()
    } else {
        args.techniques.clone()
    };
    for t in asked {
        if !techniques.contains(&t) {
            techniques.push(t);
        }
    }
    let resolutions: Vec<Option<u32>> = if args.shadow_resolutions.is_empty() {
        vec![None]
    } else {
        args.shadow_resolutions.iter().map(|&r| Some(r)).collect()
    };
    let variants: Vec<Variant> = techniques
        .iter()
        .flat_map(|&technique| {
            resolutions.iter().map(move |&resolution| Variant {
                technique,
                resolution,
            })
        })
        .collect();

    pb.set_message("opening the GPU");
    let ctx = GpuContext::new(&args.gpu.request())?;
    let args = &CompareArgs {
        atlas_max: pb.suspend(|| crate::args::effective_atlas_max(&ctx, args.atlas_max)),
        ..args.clone()
    };
    pb.set_message("building the BVH of the shadow casters");
    let t = Instant::now();
    let tracer = Tracer::new(&scene)?;
    let bvh_ms = t.elapsed().as_secs_f64() * 1e3;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    pb.finish_and_clear();

    let bar = multi.add(ProgressBar::new(variants.len() as u64));
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed}]")
            .expect("valid template"),
    );
    let mut reference: Option<Reference> = None;
    let mut results = Vec::new();
    let mut skipped: Vec<(String, String)> = Vec::new();
    for v in &variants {
        bar.set_message(format!("rendering {}", v.label()));
        let scene_v = with_resolution(&scene, v.resolution);
        let mut renderer = match Renderer::new(&ctx, &scene_v, settings(args, v.technique)) {
            Ok(r) => r,
            // Asked for every technique: run those this adapter can, say which it cannot.
            Err(e) if e.is_unsupported() && args.techniques.is_empty() => {
                skipped.push((v.label(), e.to_string()));
                bar.inc(1);
                continue;
            }
            // A setting out of range names the flag that set it, as `render` does.
            Err(e) => return Err(crate::args::flag_error(e)),
        };
        let frame = renderer.render()?;
        if reference.is_none() {
            bar.set_message("ray tracing the reference");
            let r = match args.reference {
                ReferenceTracer::Cpu => {
                    trace_reference(&multi, &renderer, &tracer, &scene, args.edge_band)?
                }
                ReferenceTracer::Gpu => {
                    gpu_reference(&ctx, &renderer, &scene, args, args.edge_band)?
                }
            };
            image_out(
                &args.out_dir.join("frame.png"),
                frame.width,
                frame.height,
                &frame.rgba,
            )?;
            write_msvis(&args.out_dir.join("reference.msvis"), &r.vis.lit)?;
            reference = Some(r);
        }
        let r = reference.as_ref().expect("computed above");
        bar.set_message(format!("scoring {}", v.label()));
        let vis = frame
            .visibility
            .as_ref()
            .context("the renderer returned no visibility mask")?;
        let mask = Mask {
            width: vis.width,
            height: vis.height,
            lights: vis.lights,
            words_per_pixel: vis.words_per_pixel,
            words: vis.words.clone(),
        };
        let score = score::score(&r.vis, &r.band, &mask)?;
        let plan = renderer.plan();
        let footprints = match renderer.virtual_plan() {
            Some(vp) => {
                let sides: Vec<u32> = vp.faces.iter().map(|f| f.table[2]).collect();
                let lods: Vec<f32> = vp.faces.iter().map(|f| f.detail[0]).collect();
                aliasing::footprints(
                    &scene_v,
                    &PlannedViews {
                        views: &vp.views,
                        tile_sizes: &sides,
                        virtual_lods: Some(&lods),
                    },
                    &r.surfaces,
                    &r.vis.reach,
                )?
            }
            None => {
                let tile_sizes: Vec<u32> = plan.layout.tiles.iter().map(|t| t.size).collect();
                aliasing::footprints(
                    &scene_v,
                    &PlannedViews {
                        views: &plan.views,
                        tile_sizes: &tile_sizes,
                        virtual_lods: None,
                    },
                    &r.surfaces,
                    &r.vis.reach,
                )?
            }
        };
        let classes = score::error_classes(&r.vis, &r.band, &mask, None)?;
        let diff_path = args.out_dir.join(format!("diff-{}.png", v.label()));
        write_diff(&diff_path, &frame.rgba, &classes, frame.width, frame.height)?;
        if args.per_light_images {
            for l in 0..scene.lights.len() as u32 {
                let c = score::error_classes(&r.vis, &r.band, &mask, Some(l))?;
                let path = args.out_dir.join(format!(
                    "diff-{}-light{l:03}-{}.png",
                    v.label(),
                    scene.lights[l as usize].type_name()
                ));
                write_diff(&path, &frame.rgba, &c, frame.width, frame.height)?;
            }
        }
        let by_distance = point_errors_by_distance(&scene, r, &mask)?;
        results.push(VariantResult {
            by_distance,
            label: v.label(),
            technique: v.technique,
            resolution: v.resolution,
            atlas: plan.layout.size,
            shrink_steps: plan.layout.shrink_steps,
            shadow_bytes: match frame.virtual_maps {
                Some(v) => v.kept_bytes(),
                None => u64::from(plan.layout.size).pow(2) * 4,
            },
            gpu_ms: frame.timings.gpu_ms.clone(),
            score,
            footprints,
            diff_image: diff_path,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let r = reference.context("no technique could run on this adapter")?;
    let mut report = report(&ctx, &scene, args, &tracer, bvh_ms, &r, &results, started);
    for (i, v) in results.iter().enumerate() {
        if !v.by_distance.is_empty() {
            report["variants"][i]["point_light_errors_by_distance"] = json!(v
                .by_distance
                .iter()
                .map(|&(b, n, e)| json!({ "below_m": if b.is_finite() { json!(b) } else { json!(null) }, "pairs": n, "errors": e }))
                .collect::<Vec<_>>());
        }
    }
    report["skipped"] = json!(skipped
        .iter()
        .map(|(label, why)| json!({ "variant": label, "reason": why }))
        .collect::<Vec<_>>());
    print_table(&report, &results, &scene);
    if results.iter().any(|v| !v.by_distance.is_empty()) {
        println!("\npoint-light errors (outside the band) by distance from the light:");
        print!("{:<24}", "technique");
        let mut lo = 0.0;
        for &b in &DISTANCE_BINS {
            let head = if b.is_finite() {
                format!("{lo}-{b} m")
            } else {
                format!(">{lo} m")
            };
            print!(" {head:>14}");
            lo = b;
        }
        println!();
        for v in &results {
            print!("{:<24}", v.label);
            for &(_, n, e) in &v.by_distance {
                let cell = if n == 0 {
                    "-".to_string()
                } else {
                    format!("{:.3}%", 100.0 * e as f64 / n as f64)
                };
                print!(" {cell:>14}");
            }
            println!();
        }
    }
    for (label, why) in &skipped {
        println!("skipped    {label}: {why}");
    }
    if let Some(path) = &args.json {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(report)
}

/// The reference of the frame, computed once (the G-buffer is the same for every technique).
struct Reference {
    surfaces: Surfaces,
    vis: ReferenceVisibility,
    band: Mask,
    ms: f64,
    rays: u64,
}

struct VariantResult {
    label: String,
    technique: Technique,
    resolution: Option<u32>,
    atlas: u32,
    shrink_steps: u32,
    /// Shadow memory the variant keeps: the atlas, or the page pool plus the page table.
    shadow_bytes: u64,
    gpu_ms: manyshadows::GpuTimes,
    score: score::Score,
    footprints: Vec<Footprints>,
    diff_image: PathBuf,
    /// Point lights only: (upper bound of the distance bin in m, scored pairs, errors outside
    /// the edge band).
    by_distance: Vec<(f32, u64, u64)>,
}

/// Distance bins (upper bounds, metres) of the point-light error breakdown.
const DISTANCE_BINS: [f32; 5] = [2.0, 4.0, 8.0, 16.0, f32::INFINITY];

/// Errors of point-light shadows (outside the edge band) by the receiver's distance from the
/// light: where a map's texels grow (cube faces towards their corners, paraboloids towards
/// the rim) or its warp bends, errors concentrate at some distances.
fn point_errors_by_distance(
    scene: &Scene,
    r: &Reference,
    mask: &Mask,
) -> Result<Vec<(f32, u64, u64)>> {
    let mut bins: Vec<(f32, u64, u64)> = DISTANCE_BINS.iter().map(|&b| (b, 0, 0)).collect();
    let mut any = false;
    for (l, light) in scene.lights.iter().enumerate() {
        let manyshadows::scene::LightKind::Point { position, .. } = light.kind else {
            continue;
        };
        any = true;
        let c = score::error_classes(&r.vis, &r.band, mask, Some(l as u32))?;
        for (p, sp) in r.surfaces.points.iter().enumerate() {
            let Some(sp) = sp else { continue };
            if !(r.vis.reach.get(p, l as u32) && r.vis.facing.get(p, l as u32)) {
                continue;
            }
            let d = sp.position.distance(position);
            let k = DISTANCE_BINS
                .iter()
                .position(|&b| d < b)
                .unwrap_or(DISTANCE_BINS.len() - 1);
            bins[k].1 += 1;
            if c[p] & (class::FALSE_SHADOW | class::FALSE_LIGHT) != 0 {
                bins[k].2 += 1;
            }
        }
    }
    Ok(if any { bins } else { Vec::new() })
}

fn load(args: &CompareArgs) -> Result<Scene> {
    let lights = match args.lights {
        Some(n) => Some(n),
        None if args.scene == "atrium" => Some(ATRIUM_DEFAULT_LIGHTS),
        None => None,
    };
    let ra = RenderArgs {
        scene: args.scene.clone(),
        lights,
        seed: args.seed,
        light_types: args.light_types.clone(),
        mesh: args.mesh.clone(),
        subdivide: args.subdivide,
        ..RenderArgs::default()
    };
    crate::scenes::load_scene(&ra)
}

/// The scene with every light's shadow map at `resolution` (what `--shadow-resolution` does).
fn with_resolution(scene: &Scene, resolution: Option<u32>) -> Scene {
    let mut s = scene.clone();
    if let Some(r) = resolution {
        for l in &mut s.lights {
            l.shadow_resolution = r;
        }
    }
    s
}

fn settings(args: &CompareArgs, technique: Technique) -> RenderSettings {
    // The score reads the hard visibility mask, which PCF does not touch; the frame under
    // the difference images shows the hard edges that are being scored.
    RenderSettings::default()
        .with_width(args.width)
        .with_height(args.height)
        .with_technique(technique)
        .with_pcf(Pcf::Off)
        .with_bias(ShadowBias::new(
            args.bias_constant,
            args.bias_slope,
            args.bias_normal,
        ))
        .with_max_atlas_size(Some(args.atlas_max))
        .with_fit(if args.strict_atlas {
            FitPolicy::Strict
        } else {
            FitPolicy::Shrink
        })
        .with_visibility(true)
        .with_point_shadows(args.point_shadows)
        .with_shadow(manyshadows::ShadowOptions::default().with_casters(
            manyshadows::CasterOptions::default().with_ignore_masks(!args.shadow_alpha),
        ))
        .with_virtual_maps(
            manyshadows::VirtualOptions::default()
                .with_pool_bytes(u64::from(args.page_pool) << 20)
                .with_lod(args.virtual_lod)
                .with_directed_lod(args.virtual_directed_lod)
                .with_bias_scale(args.virtual_bias),
        )
}

fn trace_reference(
    multi: &MultiProgress,
    renderer: &Renderer,
    tracer: &Tracer,
    scene: &Scene,
    edge_band: u32,
) -> Result<Reference> {
    let g = renderer.read_gbuffer()?;
    let points = (0..g.position.len())
        .map(|i| {
            g.covered[i].then(|| SurfacePoint {
                position: g.position[i],
                normal: g.normal[i],
            })
        })
        .collect();
    let surfaces = Surfaces::new(g.width, g.height, points)?;
    let rows = multi.add(ProgressBar::new(g.height as u64));
    rows.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} rows of reference rays [{elapsed}]")
            .expect("valid template"),
    );
    let t = Instant::now();
    let vis = manyshadows_reference::reference_visibility(
        tracer,
        &scene.lights,
        &surfaces,
        &|| rows.inc(1),
        &AtomicBool::new(false),
    )
    .context("the reference was cancelled")?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    rows.finish_and_clear();
    let shadowed: Vec<bool> = scene.lights.iter().map(|l| l.casts_shadows).collect();
    let mut rays = 0u64;
    for (i, w) in vis.reach.words.iter().enumerate() {
        let first = (i % vis.reach.words_per_pixel as usize) * 32;
        let mut bits = *w;
        while bits != 0 {
            let b = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            rays += shadowed.get(first + b).copied().unwrap_or(false) as u64;
        }
    }
    let band = score::edge_band(&vis.lit, &surfaces.covered(), edge_band);
    Ok(Reference {
        surfaces,
        vis,
        band,
        ms,
        rays,
    })
}

/// The reference traced on the GPU: the technique that casts rays, for every light of every
/// pixel (no clusters), from the same G-buffer points with the same offsets and light
/// segments as the CPU's; reach and facing are the CPU's own (no rays), and the GPU's bits
/// count only where the CPU finds the light in reach.
fn gpu_reference(
    ctx: &GpuContext,
    renderer: &Renderer,
    scene: &Scene,
    args: &CompareArgs,
    edge_band: u32,
) -> Result<Reference> {
    let rays = crate::techniques::first_filling(manyshadows::Fills::Rays);
    if rays.info().fills != manyshadows::Fills::Rays {
        bail!("--reference gpu: no technique casts rays");
    }
    rays.info().check(ctx)?;
    let g = renderer.read_gbuffer()?;
    let points = (0..g.position.len())
        .map(|i| {
            g.covered[i].then(|| SurfacePoint {
                position: g.position[i],
                normal: g.normal[i],
            })
        })
        .collect();
    let surfaces = Surfaces::new(g.width, g.height, points)?;
    let t = Instant::now();
    let settings = settings(args, rays).with_light_loop(manyshadows::LightLoop::All);
    let frame = Renderer::new(ctx, scene, settings)?.render()?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let mask = frame
        .visibility
        .context("the ray-traced reference returned no mask")?;
    let mut vis = manyshadows_reference::reach_and_facing(&scene.lights, &surfaces);
    if (mask.width, mask.height, mask.words_per_pixel)
        != (vis.lit.width, vis.lit.height, vis.lit.words_per_pixel)
    {
        bail!("the GPU reference's mask does not match the frame's size");
    }
    let shadowed: Vec<bool> = scene.lights.iter().map(|l| l.casts_shadows).collect();
    let mut traced = 0u64;
    for (i, (lit, reach)) in vis.lit.words.iter_mut().zip(&vis.reach.words).enumerate() {
        *lit = mask.words[i] & reach;
        let first = (i % vis.reach.words_per_pixel as usize) * 32;
        let mut bits = *reach;
        while bits != 0 {
            let b = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            traced += shadowed.get(first + b).copied().unwrap_or(false) as u64;
        }
    }
    let band = score::edge_band(&vis.lit, &surfaces.covered(), edge_band);
    Ok(Reference {
        surfaces,
        vis,
        band,
        ms,
        rays: traced,
    })
}

fn image_out(path: &Path, w: u32, h: u32, rgba: &[u8]) -> Result<()> {
    image::save_buffer(path, rgba, w, h, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("writing {}", path.display()))
}

fn write_msvis(path: &Path, m: &Mask) -> Result<()> {
    let vis = manyshadows::VisibilityMask {
        width: m.width,
        height: m.height,
        lights: m.lights,
        words_per_pixel: m.words_per_pixel,
        words: m.words.clone(),
    };
    let file =
        std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
    vis.write_raw(std::io::BufWriter::new(file))
        .with_context(|| format!("writing {}", path.display()))
}

/// The frame dimmed to grey, with each pixel's error class on top.
fn write_diff(path: &Path, rgba: &[u8], classes: &[u8], w: u32, h: u32) -> Result<()> {
    let mut rgb = Vec::with_capacity(classes.len() * 3);
    for (px, &c) in rgba.chunks_exact(4).zip(classes) {
        let grey = (0.3 * px[0] as f32 + 0.59 * px[1] as f32 + 0.11 * px[2] as f32) * DIM;
        let g = grey as u8;
        let out = if c & (class::FALSE_SHADOW | class::FALSE_LIGHT) != 0 {
            [
                if c & class::FALSE_SHADOW != 0 { 255 } else { 0 },
                if c & class::FALSE_LIGHT != 0 { 255 } else { 0 },
                0,
            ]
        } else if c & (class::BAND_FALSE_SHADOW | class::BAND_FALSE_LIGHT) != 0 {
            [
                if c & class::BAND_FALSE_SHADOW != 0 {
                    130
                } else {
                    0
                },
                if c & class::BAND_FALSE_LIGHT != 0 {
                    130
                } else {
                    0
                },
                0,
            ]
        } else {
            [g, g, g]
        };
        rgb.extend_from_slice(&out);
    }
    image::save_buffer(path, &rgb, w, h, image::ExtendedColorType::Rgb8)
        .with_context(|| format!("writing {}", path.display()))
}

/// Light-type groups in table order, with the lights they hold.
fn groups(scene: &Scene) -> Vec<(&'static str, Vec<usize>)> {
    let mut out = Vec::new();
    for t in ["spot", "point", "directional"] {
        let ids: Vec<usize> = (0..scene.lights.len())
            .filter(|&i| scene.lights[i].type_name() == t)
            .collect();
        if !ids.is_empty() {
            out.push((t, ids));
        }
    }
    if out.len() > 1 {
        out.push(("all", (0..scene.lights.len()).collect()));
    }
    out
}

fn counts_json(c: &Counts) -> serde_json::Value {
    json!({
        "lights": c.lights,
        "in_reach_pixels": c.in_reach,
        "false_shadow": c.false_shadow,
        "false_light": c.false_light,
        "false_shadow_fraction": c.false_shadow_fraction(),
        "false_light_fraction": c.false_light_fraction(),
        "error_fraction": c.error_fraction(),
        "band_pixels": c.band,
        "band_fraction": c.band_fraction(),
        "band_false_shadow": c.band_false_shadow,
        "band_false_light": c.band_false_light,
        "band_error_fraction": c.band_error_fraction(),
        "back_facing_pixels": c.back_facing,
        "back_facing_disagree": c.back_facing_disagree,
    })
}

fn merged(f: &[Footprints], ids: &[usize]) -> Footprints {
    let mut h = Footprints::default();
    for &i in ids {
        h.merge(&f[i]);
    }
    h
}

#[allow(clippy::too_many_arguments)]
fn report(
    ctx: &GpuContext,
    scene: &Scene,
    args: &CompareArgs,
    tracer: &Tracer,
    bvh_ms: f64,
    r: &Reference,
    results: &[VariantResult],
    started: Instant,
) -> serde_json::Value {
    let groups = groups(scene);
    let variants: Vec<serde_json::Value> = results
        .iter()
        .map(|v| {
            let by_type: serde_json::Map<String, serde_json::Value> = groups
                .iter()
                .map(|(name, ids)| {
                    let c = v.score.total(|i| ids.contains(&i));
                    let mut j = counts_json(&c);
                    j["footprint_px"] = json!(merged(&v.footprints, ids).summary());
                    (name.to_string(), j)
                })
                .collect();
            let per_light: Vec<serde_json::Value> = v
                .score
                .per_light
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let mut j = counts_json(c);
                    j["type"] = json!(scene.lights[i].type_name());
                    j["footprint_px"] = json!(v.footprints[i].summary());
                    j
                })
                .collect();
            json!({
                "label": v.label,
                "technique": v.technique.name(),
                "shadow_resolution": v.resolution,
                "atlas": { "size": v.atlas, "shrink_steps": v.shrink_steps },
                "shadow_bytes": v.shadow_bytes,
                "gpu_ms": v.gpu_ms,
                "difference_image": v.diff_image,
                "by_type": by_type,
                "per_light": per_light,
            })
        })
        .collect();
    let count = |t: &str| scene.lights.iter().filter(|l| l.type_name() == t).count();
    let mut by_kind = BTreeMap::new();
    for t in ["spot", "point", "directional"] {
        by_kind.insert(t, count(t));
    }
    json!({
        "adapter": describe_adapter(&ctx.info),
        "backend": format!("{:?}", ctx.info.backend),
        "scene": scene.name,
        "resolution": [args.width, args.height],
        "lights": { "total": scene.lights.len(), "by_type": by_kind },
        "bias_texels": { "constant": args.bias_constant, "slope": args.bias_slope, "normal": args.bias_normal },
        "virtual_maps": { "lod": args.virtual_lod, "directed_lod": args.virtual_directed_lod, "bias_scale": args.virtual_bias, "page_pool_mib": args.page_pool },
        "edge_band_px": args.edge_band,
        "reference": {
            "triangles": tracer.triangle_count(),
            "bvh_build_ms": bvh_ms,
            "trace_ms": r.ms,
            "rays": r.rays,
            "rays_per_second": if r.ms > 0.0 { r.rays as f64 / (r.ms / 1e3) } else { 0.0 },
            "threads": rayon::current_num_threads(),
            "ray_offset_relative": manyshadows_reference::visibility::RAY_OFFSET_RELATIVE,
            "tracer": format!("{:?}", args.reference).to_lowercase(),
            "mask": args.out_dir.join("reference.msvis"),
        },
        "frame": args.out_dir.join("frame.png"),
        "variants": variants,
        "total_wall_ms": started.elapsed().as_secs_f64() * 1e3,
    })
}

fn pct(x: f64) -> String {
    format!("{:.3}%", x * 100.0)
}

fn print_table(report: &serde_json::Value, results: &[VariantResult], scene: &Scene) {
    let rf = &report["reference"];
    println!("adapter    {}", report["adapter"].as_str().unwrap_or("?"));
    println!(
        "scene      {} at {}x{}, {} lights; edge band {} px",
        scene.name,
        report["resolution"][0],
        report["resolution"][1],
        scene.lights.len(),
        report["edge_band_px"]
    );
    if rf["tracer"] == "gpu" {
        println!(
            "reference  traced on the GPU (ray queries): {} rays in {:.0} ms, acceleration \
             structures and pipelines included",
            rf["rays"],
            rf["trace_ms"].as_f64().unwrap_or(0.0),
        );
    } else {
        println!(
            "reference  {} triangles, BVH {:.0} ms; {} rays in {:.0} ms ({:.2} M rays/s on {} threads)",
            rf["triangles"],
            rf["bvh_build_ms"].as_f64().unwrap_or(0.0),
            rf["rays"],
            rf["trace_ms"].as_f64().unwrap_or(0.0),
            rf["rays_per_second"].as_f64().unwrap_or(0.0) / 1e6,
            rf["threads"]
        );
    }
    println!();
    println!(
        "{:<24} {:<13} {:>11} {:>12} {:>12} {:>9} {:>10} | {:>6} {:>6} {:>6} {:>7} {:>7}",
        "technique",
        "lights",
        "in reach",
        "false shad.",
        "false light",
        "band",
        "band err",
        "fp p50",
        "p90",
        "p99",
        "max",
        ">1 px"
    );
    let groups = groups(scene);
    for v in results {
        for (name, ids) in &groups {
            let c = v.score.total(|i| ids.contains(&i));
            let f = merged(&v.footprints, ids).summary();
            println!(
                "{:<24} {:<13} {:>11} {:>12} {:>12} {:>9} {:>10} | {:>6.2} {:>6.2} {:>6.2} {:>7.2} {:>7}",
                v.label,
                format!("{name} ({})", c.lights),
                c.in_reach,
                pct(c.false_shadow_fraction()),
                pct(c.false_light_fraction()),
                pct(c.band_fraction()),
                pct(c.band_error_fraction()),
                f.p50,
                f.p90,
                f.p99,
                f.max,
                format!("{:.1}%", f.above_1 * 100.0)
            );
        }
    }
    println!();
    println!(
        "false shadow / false light: outside the edge band, as a share of in-reach (pixel, light) pairs;"
    );
    println!("band: the edge band's share; band err: errors inside it; fp: shadow-texel footprint in screen pixels.");
    let memory: Vec<String> = results
        .iter()
        .map(|v| {
            format!(
                "{} {:.1}",
                v.label,
                v.shadow_bytes as f64 / (1024.0 * 1024.0)
            )
        })
        .collect();
    println!(
        "shadow memory kept (MiB; atlas, or page pool + page table (+ last frame's with caching)): {}",
        memory.join(", ")
    );
    let first = results.first().map(|v| v.diff_image.clone());
    if let Some(dir) = first.as_ref().and_then(|p| p.parent()) {
        println!(
            "wrote      {} (frame.png, diff-*.png: red false shadow, green false light, dark = in band; reference.msvis)",
            dir.display()
        );
    }
}
