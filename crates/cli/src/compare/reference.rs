//! The exact reference every variant is scored against, computed once per scene from the
//! first frame's G-buffer (the same for every technique): which (pixel, light) pairs the
//! light reaches and faces, which of them it lights, and the edge band around the reference's
//! shadow edges. Traced on the CPU (the default truth) or on the GPU with ray queries; when
//! soft shadows are scored, the soft reference too (on the CPU, `compare::soft`).

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use indicatif::MultiProgress;
use manyshadows::scene::{Light, Scene};
use manyshadows::{GpuContext, Renderer};
use manyshadows_reference::score;
use manyshadows_reference::{Mask, ReferenceVisibility, SurfacePoint, Surfaces, Tracer};

use crate::compare::args::{CompareArgs, ReferenceTracer};
use crate::compare::setup::{settings, Setup, SoftPlan};
use crate::compare::soft::{self, SoftReference};

/// The reference of the frame, computed once (the G-buffer is the same for every technique).
pub(super) struct Reference {
    pub(super) surfaces: Surfaces,
    pub(super) vis: ReferenceVisibility,
    pub(super) band: Mask,
    /// Time to trace it, ms.
    pub(super) ms: f64,
    /// The (pixel, light) pairs traced: every pair in reach of a light that casts shadows.
    pub(super) rays: u64,
    /// The soft reference, when soft shadows are scored.
    pub(super) soft: Option<SoftReference>,
}

/// The reference of `renderer`'s frame, traced by the tracer `--reference` names.
pub(super) fn trace(
    multi: &MultiProgress,
    setup: &Setup,
    renderer: &Renderer,
    scene: &Scene,
) -> Result<Reference> {
    let args = &setup.args;
    let mut r = match args.reference {
        ReferenceTracer::Cpu => {
            trace_reference(multi, renderer, &setup.tracer, scene, args.edge_band)?
        }
        ReferenceTracer::Gpu => gpu_reference(
            &setup.ctx,
            renderer,
            scene,
            args,
            args.edge_band,
            match setup.soft {
                SoftPlan::Traced(samples) => Some(samples),
                SoftPlan::Skipped(_) => None,
            },
        )?,
    };
    if let (SoftPlan::Traced(samples), None) = (&setup.soft, &r.soft) {
        let samples = *samples;
        r.soft = Some(soft::trace(
            multi,
            &setup.tracer,
            &scene.lights,
            &r.surfaces,
            samples,
        )?);
    }
    Ok(r)
}

/// The surface point of every covered pixel of `renderer`'s G-buffer.
fn surfaces(renderer: &Renderer) -> Result<Surfaces> {
    let g = renderer.read_gbuffer()?;
    let points = (0..g.position.len())
        .map(|i| {
            g.covered[i].then(|| SurfacePoint {
                position: g.position[i],
                normal: g.normal[i],
            })
        })
        .collect();
    Ok(Surfaces::new(g.width, g.height, points)?)
}

/// The pairs of `reach` whose light casts shadows: the rays the reference traces.
fn shadow_rays(reach: &Mask, lights: &[Light]) -> u64 {
    let shadowed: Vec<bool> = lights.iter().map(|l| l.casts_shadows).collect();
    let mut rays = 0u64;
    for (i, w) in reach.words.iter().enumerate() {
        let first = (i % reach.words_per_pixel as usize) * 32;
        let mut bits = *w;
        while bits != 0 {
            let b = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            rays += shadowed.get(first + b).copied().unwrap_or(false) as u64;
        }
    }
    rays
}

pub(super) fn trace_reference(
    multi: &MultiProgress,
    renderer: &Renderer,
    tracer: &Tracer,
    scene: &Scene,
    edge_band: u32,
) -> Result<Reference> {
    let surfaces = surfaces(renderer)?;
    // At most one ray per pixel and light (fewer: out of reach or facing away).
    let rows = crate::progress::RowProgress::new(
        multi,
        surfaces.height as u64,
        surfaces.width as f64 * scene.lights.len() as f64,
        "reference rays",
    );
    let t = Instant::now();
    let vis = manyshadows_reference::reference_visibility(
        tracer,
        &scene.lights,
        &surfaces,
        &|| rows.row(),
        &AtomicBool::new(false),
    )
    .context("the reference was cancelled")?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    rows.finish();
    let rays = shadow_rays(&vis.reach, &scene.lights);
    let band = score::edge_band(&vis.lit, &surfaces.covered(), edge_band);
    Ok(Reference {
        surfaces,
        vis,
        band,
        ms,
        rays,
        soft: None,
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
    soft_samples: Option<u32>,
) -> Result<Reference> {
    let rays = crate::techniques::first_filling(manyshadows::Fills::Rays);
    if rays.info().fills != manyshadows::Fills::Rays {
        bail!("--reference gpu: no technique casts rays");
    }
    rays.info().check(ctx)?;
    let surfaces = surfaces(renderer)?;
    let t = Instant::now();
    let mut settings = settings(args, rays, false).with_light_loop(manyshadows::LightLoop::All);
    if let Some(samples) = soft_samples {
        // The soft reference from the same rays: each sized light's shape sampled on an n x n
        // grid per pixel, as the CPU reference samples it.
        let side = manyshadows_reference::soft::grid_side(samples);
        let rays = settings.rays.with_area_samples(side);
        settings = settings.with_soft_visibility(true).with_rays(rays);
    }
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
    for (i, (lit, reach)) in vis.lit.words.iter_mut().zip(&vis.reach.words).enumerate() {
        *lit = mask.words[i] & reach;
    }
    let traced = shadow_rays(&vis.reach, &scene.lights);
    let band = score::edge_band(&vis.lit, &surfaces.covered(), edge_band);
    let soft = match (soft_samples, frame.soft_visibility) {
        (Some(samples), Some(bytes)) => {
            Some(soft::from_gpu(&vis, bytes, samples, &scene.lights, ms))
        }
        _ => None,
    };
    Ok(Reference {
        surfaces,
        vis,
        band,
        ms,
        rays: traced,
        soft,
    })
}
