//! Before anything is scored: the flags checked (edge band, resolutions, biases, how many
//! reference rays the frame and its lights need), the scene loaded, the variants listed
//! (each technique at each shadow resolution), the render settings every variant and the GPU
//! reference share, and the GPU and the casters' BVH opened.

use std::time::Instant;

use anyhow::{bail, Context, Result};
use indicatif::ProgressBar;
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::Scene;
use manyshadows::{GpuContext, Pcf, RenderSettings, ShadowBias, Technique};
use manyshadows_reference::Tracer;

use crate::args::RenderArgs;
use crate::compare::args::{CompareArgs, ReferenceTracer};

/// Most (pixel, light) pairs one comparison may trace: about a minute of rays on two cores.
const MAX_RAYS: u64 = 200_000_000;
/// Most (pixel, light) pairs the GPU reference traces: 1920×1080 × 2,048 lights.
const MAX_GPU_RAYS: u64 = 1920 * 1080 * 2048;
/// Largest edge band accepted, pixels.
const MAX_EDGE_BAND: u32 = 64;
/// Atrium lights when `--lights` is not given: a run of well under a minute on two cores.
const ATRIUM_DEFAULT_LIGHTS: usize = 8;
/// Most soft-reference rays one comparison may trace (pixels × sized lights × samples, an
/// upper bound: only pairs in reach are traced): about ten minutes on two cores.
const MAX_SOFT_RAYS: u64 = 3_000_000_000;

/// Whether soft shadows are scored on a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum SoftPlan {
    /// Traced on the CPU with this many samples per (pixel, sized light): `--soft-samples`
    /// rounded up to a square.
    Traced(u32),
    /// Not scored, and why.
    Skipped(&'static str),
}

/// Samples of the soft reference per (pixel, sized light) when `--soft-samples` is not given:
/// a 16x16 grid, unless that passes [`MAX_SOFT_RAYS`] (then the largest square under it).
pub(super) const DEFAULT_SOFT_SAMPLES: u32 = 256;
/// The fewest samples the default comes down to (a 4x4 grid): below it the reference's
/// fractions are too coarse to score a penumbra by, and the flags must say what to give up.
const MIN_CHOSEN_SOFT_SAMPLES: u32 = 16;

/// Whether soft shadows are scored on `scene` under the flags: when it has a sized light that
/// casts shadows, `--soft-samples` is not 0 and the reference is the CPU's. Without
/// `--soft-samples`, the samples are [`DEFAULT_SOFT_SAMPLES`] or the most whose rays fit
/// [`MAX_SOFT_RAYS`] (said in a note), at least [`MIN_CHOSEN_SOFT_SAMPLES`]. Fails when the
/// soft reference would trace more than [`MAX_SOFT_RAYS`] with the samples given, or with the
/// fewest the default comes down to.
pub(super) fn soft_plan(args: &CompareArgs, scene: &Scene) -> Result<SoftPlan> {
    if !has_sized_light(scene) {
        return Ok(SoftPlan::Skipped(
            "no light with a size casts shadows (--light-size, --sun-size size them)",
        ));
    }
    let asked = args.soft_samples.unwrap_or(DEFAULT_SOFT_SAMPLES);
    if asked == 0 {
        return Ok(SoftPlan::Skipped("--soft-samples 0"));
    }
    let mut n = manyshadows_reference::soft::grid_side(asked);
    if asked > manyshadows_reference::soft::MAX_SAMPLES {
        eprintln!(
            "note: --soft-samples {asked} is clamped to {} (a {n}x{n} grid per pixel and sized \
             light)",
            n * n
        );
    }
    if args.reference == ReferenceTracer::Gpu && n > 16 {
        bail!(
            "--soft-samples {asked}: the GPU reference traces at most 256 rays per (pixel, sized \
             light) (a 16x16 grid); use --reference cpu for more"
        );
    }
    let sized = scene
        .lights
        .iter()
        .filter(|l| l.size > 0.0 && l.casts_shadows)
        .count() as u64;
    let pixels = args.width as u64 * args.height as u64;
    let rays = |side: u32| pixels * sized * u64::from(side * side);
    if args.soft_samples.is_none() && rays(n) > MAX_SOFT_RAYS {
        let fits = (1..n).rev().find(|&side| rays(side) <= MAX_SOFT_RAYS);
        if let Some(side) = fits.filter(|&side| side * side >= MIN_CHOSEN_SOFT_SAMPLES) {
            eprintln!(
                "note: the soft reference traces {} samples per (pixel, sized light) (a \
                 {side}x{side} grid), not the default {}: {}x{} pixels x {sized} sized lights x \
                 {} samples would pass the {MAX_SOFT_RAYS} rays one comparison traces; \
                 --soft-samples N sets it",
                side * side,
                n * n,
                args.width,
                args.height,
                n * n
            );
            n = side;
        }
    }
    if rays(n) > MAX_SOFT_RAYS {
        bail!(
            "{}x{} pixels x {sized} sized lights x {} samples is more than {MAX_SOFT_RAYS} soft \
             reference rays; use fewer --soft-samples (0 scores hard shadows only), fewer lights \
             or a smaller frame",
            args.width,
            args.height,
            n * n
        );
    }
    Ok(SoftPlan::Traced(n * n))
}

/// One technique at one shadow resolution, with its soft-shadow filter on or off.
pub(super) struct Variant {
    pub(super) technique: Technique,
    pub(super) resolution: Option<u32>,
    /// The lights rendered with their sizes (the soft filter on), or every one hard.
    pub(super) soft: bool,
}

impl Variant {
    /// `<technique>[-<resolution>][-hard]`: the name of its row and of its images.
    pub(super) fn label(&self) -> String {
        let mut label = self.technique.name().to_string();
        if let Some(r) = self.resolution {
            label += &format!("-{r}");
        }
        if !self.soft {
            label += "-hard";
        }
        label
    }
}

/// Fails on the flags no scene can be scored with: an edge band over [`MAX_EDGE_BAND`], a
/// shadow resolution out of range, a bias that is not a finite number, a light size no light
/// can have.
pub(super) fn check_flags(args: &CompareArgs) -> Result<()> {
    args.light_sizes.sizes()?;
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
    Ok(())
}

/// `args.scene` with its lights (the atrium gets [`ATRIUM_DEFAULT_LIGHTS`] unless `--lights`
/// says otherwise).
pub(super) fn load(args: &CompareArgs) -> Result<Scene> {
    let lights = match args.lights {
        Some(n) => Some(n),
        None if args.scene == "atrium" && args.add_lights.is_none() => Some(ATRIUM_DEFAULT_LIGHTS),
        None => None,
    };
    let ra = RenderArgs {
        scene: args.scene.clone(),
        lights,
        add_lights: args.add_lights,
        camera: args.camera,
        seed: args.seed,
        light_types: args.light_types.clone(),
        light_sizes: args.light_sizes,
        model: args.model,
        mesh: args.mesh.clone(),
        subdivide: args.subdivide,
        probes: args.probes,
        animation: args.animation.clone(),
        frames: args.frames,
        ..RenderArgs::default()
    };
    crate::scenes::load_scene(&ra)
}

/// Fails when the frame's pixels times the scene's lights are more reference rays than the
/// chosen tracer takes in reasonable time.
pub(super) fn check_ray_budget(args: &CompareArgs, scene: &Scene) -> Result<()> {
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
    Ok(())
}

/// Every asked technique (each once, in the order asked; every technique when none is) at
/// every asked shadow resolution (the scene's own when none is), with each asked `--soft`
/// (only `on` when `sized` is false: without a sized light the two are the same frame).
pub(super) fn variants(args: &CompareArgs, sized: bool) -> Vec<Variant> {
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
    let mut softs: Vec<bool> = Vec::new();
    for &on in &args.soft {
        if !softs.contains(&on) && (on || sized) {
            softs.push(on);
        }
    }
    if softs.is_empty() {
        softs.push(true);
    }
    let mut out = Vec::new();
    for &technique in &techniques {
        for &resolution in &resolutions {
            for &soft in &softs {
                out.push(Variant {
                    technique,
                    resolution,
                    soft,
                });
            }
        }
    }
    out
}

/// Whether `scene` has a light that casts soft shadows: one with a size that casts shadows.
pub(super) fn has_sized_light(scene: &Scene) -> bool {
    scene.lights.iter().any(|l| l.size > 0.0 && l.casts_shadows)
}

/// The scene variant `v` renders: every light's shadow map at its resolution (what
/// `--shadow-resolution` does) and, with its soft filter off, every light hard (size 0; the
/// references keep the sizes).
pub(super) fn variant_scene(scene: &Scene, v: &Variant) -> Scene {
    let mut s = scene.clone();
    for l in &mut s.lights {
        if let Some(r) = v.resolution {
            l.shadow_resolution = r;
        }
        if !v.soft {
            l.size = 0.0;
        }
    }
    s
}

/// The render settings of `technique` under the flags: the frame, the biases, the atlas, the
/// point shadows, the casters' alpha and the virtual maps, with the hard visibility mask on
/// (and the soft visibility too when `soft_visibility`).
pub(super) fn settings(
    args: &CompareArgs,
    technique: Technique,
    soft_visibility: bool,
) -> RenderSettings {
    // The score reads the hard visibility mask, which PCF does not touch; the frame under
    // the difference images shows the hard edges that are being scored.
    let settings = RenderSettings::default()
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
        .with_soft_visibility(soft_visibility)
        .with_soft(args.soft_maps.soft())
        .with_point_shadows(args.point_shadows)
        .with_shadow(
            manyshadows::ShadowOptions::default().with_casters(
                manyshadows::CasterOptions::default()
                    .with_ignore_masks(!args.shadow_alpha)
                    .with_single_sided(args.single_sided_shadows),
            ),
        );
    args.per_technique.apply(settings)
}

/// What one scene's scoring runs on: the GPU, the flags as that GPU takes them, and the BVH
/// of the shadow casters that the CPU reference traces.
pub(super) struct Setup {
    pub(super) ctx: GpuContext,
    /// The flags, `--atlas-max` clamped to the adapter's limit.
    pub(super) args: CompareArgs,
    pub(super) tracer: Tracer,
    /// Time to build `tracer`, ms.
    pub(super) bvh_ms: f64,
    /// Whether soft shadows are scored.
    pub(super) soft: SoftPlan,
}

/// Opens the GPU, builds the casters' BVH and creates `--out-dir`, saying each step on `pb`;
/// `soft` is [`soft_plan`]'s answer.
pub(super) fn open(
    pb: &ProgressBar,
    scene: &Scene,
    args: &CompareArgs,
    soft: SoftPlan,
) -> Result<Setup> {
    pb.set_message("opening the GPU");
    let ctx = GpuContext::new(&args.gpu.request())?;
    let args = CompareArgs {
        atlas_max: pb.suspend(|| crate::args::effective_atlas_max(&ctx, args.atlas_max)),
        ..args.clone()
    };
    pb.set_message("building the BVH of the shadow casters");
    let t = Instant::now();
    let tracer = Tracer::with_rule(scene, args.single_sided_shadows)?;
    let bvh_ms = t.elapsed().as_secs_f64() * 1e3;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    Ok(Setup {
        ctx,
        args,
        tracer,
        bvh_ms,
        soft,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    fn args(flags: &[&str]) -> CompareArgs {
        #[derive(Parser)]
        struct Only {
            #[command(flatten)]
            compare: CompareArgs,
        }
        let mut argv = vec!["compare"];
        argv.extend_from_slice(flags);
        let mut a = Only::parse_from(argv).compare;
        a.scene = "atrium".into();
        a
    }

    fn sized_lights(scene: &Scene) -> u64 {
        scene
            .lights
            .iter()
            .filter(|l| l.size > 0.0 && l.casts_shadows)
            .count() as u64
    }

    /// `compare --lights 64` at its defaults (960x540, the atrium's sized lights): 256 samples
    /// would pass the soft-ray budget, so the default comes down to the largest square under
    /// it (and says so), where a number the user gives is refused instead.
    #[test]
    fn the_default_soft_samples_come_down_to_the_ray_budget_and_a_given_number_does_not() {
        let a = args(&["--lights", "64"]);
        let scene = load(&a).expect("the atrium");
        let sized = sized_lights(&scene);
        let pixels = u64::from(a.width) * u64::from(a.height);
        assert!(
            pixels * sized * 256 > MAX_SOFT_RAYS,
            "the case must pass the budget at 256 samples: {pixels} pixels x {sized} lights"
        );
        let Ok(SoftPlan::Traced(samples)) = soft_plan(&a, &scene) else {
            panic!("not traced: {:?}", soft_plan(&a, &scene));
        };
        let side = samples.isqrt();
        assert_eq!(side * side, samples, "a square grid");
        assert!(pixels * sized * u64::from(samples) <= MAX_SOFT_RAYS);
        assert!(
            pixels * sized * u64::from((side + 1) * (side + 1)) > MAX_SOFT_RAYS,
            "{samples} is not the largest square under the budget"
        );
        assert!(samples >= MIN_CHOSEN_SOFT_SAMPLES);

        let given = args(&["--lights", "64", "--soft-samples", "256"]);
        let refused = soft_plan(&given, &scene).expect_err("256 given past the budget");
        assert!(refused.to_string().contains("--soft-samples"), "{refused}");

        // Under the budget the default stays 256.
        let small = args(&["--lights", "64", "--width", "320", "--height", "180"]);
        assert_eq!(soft_plan(&small, &scene).unwrap(), SoftPlan::Traced(256));

        // Where even the fewest it comes down to would pass, it is refused, naming the flag.
        let huge = args(&["--lights", "64", "--width", "8192", "--height", "8192"]);
        let refused = soft_plan(&huge, &scene).expect_err("past the budget at 16 samples");
        assert!(refused.to_string().contains("--soft-samples"), "{refused}");
    }
}
