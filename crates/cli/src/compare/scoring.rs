//! Each variant rendered and scored against the reference: its hard visibility mask's false
//! shadow and false light (edge band apart), the shadow-texel footprint at each pixel, the
//! point-light errors by distance, its difference images, and when soft shadows are scored
//! its soft visibility and frame against the soft reference's (`compare::soft`). The
//! reference is traced from the first variant that runs, and written beside the frame.

use std::path::PathBuf;

use anyhow::{Context, Result};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use manyshadows::scene::Scene;
use manyshadows::{Frame, Renderer, Technique};
use manyshadows_reference::aliasing::{self, Footprints, PlannedViews};
use manyshadows_reference::score::{self, class};
use manyshadows_reference::Mask;

use crate::compare::images::{image_out, write_diff, write_msvis};
use crate::compare::reference::{self, Reference};
use crate::compare::setup::{settings, variant_scene, Setup, SoftPlan, Variant};
use crate::compare::soft::{self, SoftResult};

/// Distance bins (upper bounds, metres) of the point-light error breakdown.
pub(super) const DISTANCE_BINS: [f32; 5] = [2.0, 4.0, 8.0, 16.0, f32::INFINITY];

/// One variant's numbers.
pub(super) struct VariantResult {
    pub(super) label: String,
    pub(super) technique: Technique,
    pub(super) resolution: Option<u32>,
    /// The lights rendered with their sizes (the soft filter on), or every one hard.
    pub(super) soft_filter: bool,
    pub(super) atlas: u32,
    pub(super) shrink_steps: u32,
    /// Shadow memory the variant keeps: the atlas, or the page pool plus the page table.
    pub(super) shadow_bytes: u64,
    pub(super) gpu_ms: manyshadows::GpuTimes,
    pub(super) score: score::Score,
    pub(super) footprints: Vec<Footprints>,
    pub(super) diff_image: PathBuf,
    /// Point lights only: (upper bound of the distance bin in m, scored pairs, errors outside
    /// the edge band).
    pub(super) by_distance: Vec<(f32, u64, u64)>,
    /// Its soft shadows against the soft reference, when they are scored.
    pub(super) soft: Option<SoftResult>,
}

/// What scoring one scene's variants found.
pub(super) struct Scored {
    /// Traced from the first variant that ran; `None` when none could.
    pub(super) reference: Option<Reference>,
    pub(super) results: Vec<VariantResult>,
    /// The variants this adapter cannot run: (label, why).
    pub(super) skipped: Vec<(String, String)>,
}

/// Renders and scores every variant in turn, with a progress bar on `multi`.
pub(super) fn score_variants(
    multi: &MultiProgress,
    setup: &Setup,
    scene: &Scene,
    variants: &[Variant],
) -> Result<Scored> {
    let bar = multi.add(ProgressBar::new(variants.len() as u64));
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed}]")
            .expect("valid template"),
    );
    let mut scored = Scored {
        reference: None,
        results: Vec::new(),
        skipped: Vec::new(),
    };
    for v in variants {
        bar.set_message(format!("rendering {}", v.label()));
        let scene_v = variant_scene(scene, v);
        let Some((mut renderer, estimate)) = renderer_for(setup, &scene_v, v, &mut scored.skipped)?
        else {
            bar.inc(1);
            continue;
        };
        let long = crate::render::long_frame(&estimate);
        if long {
            multi.suspend(|| {
                eprintln!(
                    "{}: estimate {}",
                    v.label(),
                    crate::summary::describe_estimate(&estimate)
                )
            });
        }
        let frame = if setup.args.stages || long {
            let (label, t0) = (v.label(), std::time::Instant::now());
            renderer.render_reporting(&mut |part| {
                multi.suspend(|| {
                    eprintln!(
                        "{label}: {} done after {:.1} s",
                        part.describe(),
                        t0.elapsed().as_secs_f64()
                    )
                })
            })?
        } else {
            renderer.render()?
        };
        if scored.reference.is_none() {
            bar.set_message("ray tracing the reference");
            scored.reference = Some(first_reference(multi, setup, &renderer, scene, &frame)?);
        }
        let r = scored.reference.as_ref().expect("computed above");
        bar.set_message(format!("scoring {}", v.label()));
        let result = score_variant(setup, scene, &scene_v, v, &renderer, &frame, r)?;
        scored.results.push(result);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(scored)
}

/// The renderer of variant `v` with its frame estimate, or `None` (with the reason pushed to
/// `skipped`) when every technique was asked for and this adapter cannot run this one.
fn renderer_for(
    setup: &Setup,
    scene_v: &Scene,
    v: &Variant,
    skipped: &mut Vec<(String, String)>,
) -> Result<Option<(Renderer, manyshadows::FrameEstimate)>> {
    let args = &setup.args;
    let soft_visibility = matches!(setup.soft, SoftPlan::Traced(_));
    match Renderer::new(
        &setup.ctx,
        scene_v,
        settings(args, v.technique, soft_visibility),
    ) {
        Ok(r) => {
            // A frame of minutes is estimated before it is drawn, as `render` does.
            let estimate = r.estimate_frame();
            if !args.insist {
                if let Err(e) = crate::render::check_shadow_work(&r, &estimate) {
                    if args.techniques.is_empty() {
                        skipped.push((v.label(), e.to_string()));
                        return Ok(None);
                    }
                    return Err(e);
                }
            }
            Ok(Some((r, estimate)))
        }
        // Asked for every technique: run those this adapter can, say which it cannot.
        Err(e) if e.is_unsupported() && args.techniques.is_empty() => {
            skipped.push((v.label(), e.to_string()));
            Ok(None)
        }
        // A setting out of range names the flag that set it, as `render` does.
        Err(e) => Err(crate::args::flag_error(e)),
    }
}

/// The reference traced from `renderer`'s G-buffer, with the lit frame (`frame.png`), the
/// reference's lit bits (`reference.msvis`) and, when soft shadows are scored, the frame shaded
/// with the soft reference (`soft-reference.png`) written to `--out-dir`.
fn first_reference(
    multi: &MultiProgress,
    setup: &Setup,
    renderer: &Renderer,
    scene: &Scene,
    frame: &Frame,
) -> Result<Reference> {
    let out_dir = &setup.args.out_dir;
    let r = reference::trace(multi, setup, renderer, scene)?;
    image_out(
        &out_dir.join("frame.png"),
        frame.width,
        frame.height,
        &frame.rgba,
    )?;
    write_msvis(&out_dir.join("reference.msvis"), &r.vis.lit)?;
    if let Some(s) = &r.soft {
        let image = soft::reference_image(renderer, s)?;
        image_out(
            &out_dir.join("soft-reference.png"),
            frame.width,
            frame.height,
            &image,
        )?;
    }
    Ok(r)
}

/// A frame's hard visibility mask as the reference crate scores it.
pub(super) fn mask_of(vis: &manyshadows::VisibilityMask) -> Mask {
    Mask {
        width: vis.width,
        height: vis.height,
        lights: vis.lights,
        words_per_pixel: vis.words_per_pixel,
        words: vis.words.clone(),
    }
}

/// Variant `v`'s frame scored against `r`, its difference images written.
fn score_variant(
    setup: &Setup,
    scene: &Scene,
    scene_v: &Scene,
    v: &Variant,
    renderer: &Renderer,
    frame: &Frame,
    r: &Reference,
) -> Result<VariantResult> {
    let vis = frame
        .visibility
        .as_ref()
        .context("the renderer returned no visibility mask")?;
    let mask = mask_of(vis);
    let score = score::score(&r.vis, &r.band, &mask)?;
    let plan = renderer.plan();
    let footprints = footprints(renderer, scene_v, r)?;
    let diff_image = write_diffs(setup, scene, v, frame, r, &mask)?;
    let by_distance = point_errors_by_distance(scene, r, &mask)?;
    let soft = match &r.soft {
        Some(s) => Some(soft::score(
            &setup.args.out_dir,
            &v.label(),
            renderer,
            frame,
            s,
        )?),
        None => None,
    };
    Ok(VariantResult {
        by_distance,
        label: v.label(),
        technique: v.technique,
        resolution: v.resolution,
        soft_filter: v.soft,
        soft,
        atlas: plan.layout.size,
        shrink_steps: plan.layout.shrink_steps,
        shadow_bytes: match &frame.virtual_maps {
            Some(v) => v.kept_bytes(),
            None => u64::from(plan.layout.size).pow(2) * 4,
        },
        gpu_ms: frame.timings.gpu_ms.clone(),
        score,
        footprints,
        diff_image,
    })
}

/// Screen pixels one shadow texel spans at each (pixel, light) pair in reach, per light:
/// from the virtual maps' faces (their table sides and levels of detail) or the atlas tiles.
fn footprints(renderer: &Renderer, scene_v: &Scene, r: &Reference) -> Result<Vec<Footprints>> {
    let plan = renderer.plan();
    Ok(match renderer.virtual_plan() {
        Some(vp) => {
            let sides: Vec<u32> = vp.faces.iter().map(|f| f.table[2]).collect();
            let lods: Vec<[f32; 2]> = vp
                .faces
                .iter()
                .map(|f| [f.detail[0], f.detail[1]])
                .collect();
            aliasing::footprints(
                scene_v,
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
                scene_v,
                &PlannedViews {
                    views: &plan.views,
                    tile_sizes: &tile_sizes,
                    virtual_lods: None,
                },
                &r.surfaces,
                &r.vis.reach,
            )?
        }
    })
}

/// Variant `v`'s difference image (`diff-<label>.png`, every light), and with
/// `--per-light-images` one per light; returns the first one's path.
fn write_diffs(
    setup: &Setup,
    scene: &Scene,
    v: &Variant,
    frame: &Frame,
    r: &Reference,
    mask: &Mask,
) -> Result<PathBuf> {
    let args = &setup.args;
    let classes = score::error_classes(&r.vis, &r.band, mask, None)?;
    let diff_path = args.out_dir.join(format!("diff-{}.png", v.label()));
    write_diff(&diff_path, &frame.rgba, &classes, frame.width, frame.height)?;
    if args.per_light_images {
        for l in 0..scene.lights.len() as u32 {
            let c = score::error_classes(&r.vis, &r.band, mask, Some(l))?;
            let path = args.out_dir.join(format!(
                "diff-{}-light{l:03}-{}.png",
                v.label(),
                scene.lights[l as usize].type_name()
            ));
            write_diff(&path, &frame.rgba, &c, frame.width, frame.height)?;
        }
    }
    Ok(diff_path)
}

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
