//! The JSON report of one scene (what `--json` writes and the table prints): the adapter,
//! the scene, the flags that shape the score, the reference's cost, and each variant's counts
//! and footprints by light type and per light, its point-light errors by distance, its soft
//! scores when soft shadows are scored, and the variants this adapter could not run.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use manyshadows::gpu::context::describe_adapter;
use manyshadows::scene::Scene;
use manyshadows_reference::aliasing::Footprints;
use manyshadows_reference::score::Counts;
use manyshadows_reference::soft_score::{ClassError, SoftCounts};
use serde_json::json;

use crate::compare::args::CompareArgs;
use crate::compare::reference::Reference;
use crate::compare::scoring::{Scored, VariantResult};
use crate::compare::setup::{Setup, SoftPlan};
use crate::compare::soft::SoftResult;

/// The report of one scored scene: [`report`]'s numbers, each variant's point-light errors
/// by distance (when the scene has point lights), and the skipped variants.
pub(super) fn scene_report(
    setup: &Setup,
    scene: &Scene,
    r: &Reference,
    scored: &Scored,
    started: Instant,
) -> serde_json::Value {
    let results = &scored.results;
    let mut report = report(setup, scene, r, results, started);
    for (i, v) in results.iter().enumerate() {
        if !v.by_distance.is_empty() {
            report["variants"][i]["point_light_errors_by_distance"] = json!(v
                .by_distance
                .iter()
                .map(|&(b, n, e)| json!({ "below_m": if b.is_finite() { json!(b) } else { json!(null) }, "pairs": n, "errors": e }))
                .collect::<Vec<_>>());
        }
    }
    report["skipped"] = json!(scored
        .skipped
        .iter()
        .map(|(label, why)| json!({ "variant": label, "reason": why }))
        .collect::<Vec<_>>());
    report
}

/// Writes `value` as pretty JSON to `path`, creating its directory.
pub(super) fn write_json(path: &Path, value: &serde_json::Value) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(path, serde_json::to_string_pretty(value)?)
        .with_context(|| format!("writing {}", path.display()))
}

/// Light-type groups in table order, with the lights they hold.
pub(super) fn groups(scene: &Scene) -> Vec<(&'static str, Vec<usize>)> {
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

/// One group's (or one light's) counts and their fractions.
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

/// One class's pairs and mean absolute error.
fn class_json(c: &ClassError) -> serde_json::Value {
    json!({ "pairs": c.pairs, "mean_abs_error": c.mean() })
}

/// One group's (or one light's) soft score.
fn soft_counts_json(c: &SoftCounts) -> serde_json::Value {
    json!({
        "lights": c.lights,
        "umbra": class_json(&c.umbra),
        "penumbra": class_json(&c.penumbra),
        "lit": class_json(&c.lit),
        "all": class_json(&c.scored()),
        "back_facing": class_json(&c.back_facing),
        "outside_reach_lit": c.outside_reach_lit,
    })
}

/// One variant's soft scores: by light type, per light, and its frame against the frame
/// shaded with the reference's fractions.
fn soft_json(s: &SoftResult, groups: &[(&str, Vec<usize>)], scene: &Scene) -> serde_json::Value {
    let by_type: serde_json::Map<String, serde_json::Value> = groups
        .iter()
        .map(|(name, ids)| {
            let c = s.score.total(|i| ids.contains(&i));
            (name.to_string(), soft_counts_json(&c))
        })
        .collect();
    let per_light: Vec<serde_json::Value> = s
        .score
        .per_light
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut j = soft_counts_json(c);
            j["type"] = json!(scene.lights[i].type_name());
            j["size"] = json!(scene.lights[i].size);
            j
        })
        .collect();
    json!({
        "by_type": by_type,
        "per_light": per_light,
        "image_rmse_8bit": s.image_rmse,
        "flip_mean": s.flip,
        "flip_image": s.flip_image,
    })
}

/// Shadow rays per (pixel, sized light) of a technique that casts rays, at the settings
/// `compare` renders with; `None` for the others.
pub(super) fn area_rays(v: &VariantResult) -> Option<u32> {
    (v.technique.info().fills == manyshadows::Fills::Rays).then(|| {
        let side = manyshadows::RayOptions::default().area_samples.max(1);
        side * side
    })
}

/// The footprints of the lights `ids`, merged.
pub(super) fn merged(f: &[Footprints], ids: &[usize]) -> Footprints {
    let mut h = Footprints::default();
    for &i in ids {
        h.merge(&f[i]);
    }
    h
}

/// The numbers of the scene, the reference and each variant (by light type and per light).
fn report(
    setup: &Setup,
    scene: &Scene,
    r: &Reference,
    results: &[VariantResult],
    started: Instant,
) -> serde_json::Value {
    let Setup {
        ctx,
        args,
        tracer,
        bvh_ms,
        soft,
    } = setup;
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
                "soft_filter": v.soft_filter,
                "soft_shadows": v.technique.info().soft_shadows,
                "area_rays": area_rays(v),
                "soft": v.soft.as_ref().map(|s| soft_json(s, &groups, scene)),
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
        "probes": scene.probes.len(),
        "bias_texels": { "constant": args.bias_constant, "slope": args.bias_slope, "normal": args.bias_normal },
        "virtual_maps": { "lod": args.per_technique.virtual_lod, "directed_lod": args.per_technique.virtual_directed_lod, "bias_scale": args.per_technique.virtual_bias, "page_pool_mib": args.per_technique.page_pool, "atlas_floor": args.per_technique.virtual_atlas_floor },
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
        "soft": soft_reference_json(args, *soft, r),
        "frame": args.out_dir.join("frame.png"),
        "variants": variants,
        "total_wall_ms": started.elapsed().as_secs_f64() * 1e3,
    })
}

/// Whether soft shadows were scored (and why not), and the soft reference's cost.
fn soft_reference_json(args: &CompareArgs, plan: SoftPlan, r: &Reference) -> serde_json::Value {
    let filters: Vec<&str> = args
        .soft
        .iter()
        .map(|&on| if on { "on" } else { "off" })
        .collect();
    match (plan, &r.soft) {
        (SoftPlan::Traced(samples), Some(s)) => json!({
            "scored": true,
            "samples": samples,
            // `--soft-samples` as given (null: the default, or fewer chosen to fit the budget).
            "samples_asked": args.soft_samples,
            "filters": filters,
            "trace_ms": s.ms,
            "rays": s.rays,
            "rays_per_second": if s.ms > 0.0 { s.rays as f64 / (s.ms / 1e3) } else { 0.0 },
            "reference_image": args.out_dir.join("soft-reference.png"),
        }),
        (SoftPlan::Skipped(why), _) => {
            json!({ "scored": false, "why_not": why, "filters": filters })
        }
        (SoftPlan::Traced(_), None) => {
            json!({ "scored": false, "why_not": "not traced", "filters": filters })
        }
    }
}
