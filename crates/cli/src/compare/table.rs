//! The printed result of one scene: the adapter, the scene and the reference's cost, one
//! table row per variant and light type (errors outside and inside the edge band, texel
//! footprints), the shadow memory each variant keeps, the point-light errors by distance, the
//! soft-shadow table when soft shadows are scored, and the skipped variants.

use manyshadows::scene::Scene;

use crate::compare::report::{area_rays, groups, merged};
use crate::compare::scoring::{Scored, VariantResult, DISTANCE_BINS};

/// Prints everything `report` holds for a reader, in the order a run shows it.
pub(super) fn print(report: &serde_json::Value, scored: &Scored, scene: &Scene) {
    print_table(report, &scored.results, scene);
    print_distances(&scored.results);
    print_soft(report, &scored.results, scene);
    for (label, why) in &scored.skipped {
        println!("skipped    {label}: {why}");
    }
}

/// The point-light errors (outside the band) by distance, one row per variant; nothing when
/// the scene has no point light.
fn print_distances(results: &[VariantResult]) {
    if !results.iter().any(|v| !v.by_distance.is_empty()) {
        return;
    }
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
    for v in results {
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

fn pct(x: f64) -> String {
    format!("{:.3}%", x * 100.0)
}

/// The adapter, scene and reference lines, the table, its legend and the shadow memory.
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

/// The soft-shadow table: per variant and light type the mean absolute error of the visible
/// fraction by the reference's class, and per variant its frame against the frame shaded with
/// the reference's fractions (8-bit RMSE, mean ꟻLIP); or why soft shadows were not scored.
fn print_soft(report: &serde_json::Value, results: &[VariantResult], scene: &Scene) {
    let s = &report["soft"];
    if s["scored"] != true {
        if let Some(why) = s["why_not"].as_str() {
            println!("\nsoft shadows not scored: {why}");
        }
        return;
    }
    println!(
        "\nsoft reference  {} samples per (pixel, sized light): {} rays in {:.1} s ({:.2} M rays/s)",
        s["samples"],
        s["rays"],
        s["trace_ms"].as_f64().unwrap_or(0.0) / 1e3,
        s["rays_per_second"].as_f64().unwrap_or(0.0) / 1e6,
    );
    let default = crate::compare::setup::DEFAULT_SOFT_SAMPLES;
    if s["samples_asked"].is_null() && s["samples"].as_u64().is_some_and(|n| n < default.into()) {
        println!(
            "                fewer than the default {default}, to fit the rays one comparison \
             traces (--soft-samples N sets it)"
        );
    }
    println!(
        "{:<24} {:<13} {:>10} {:>10} {:>10} {:>10} {:>10} | {:>10} {:>7}",
        "technique", "lights", "penumbrae", "umbra", "penumbra", "lit", "all", "image RMSE", "FLIP"
    );
    let groups = groups(scene);
    for v in results {
        let Some(soft) = &v.soft else { continue };
        for (k, (name, ids)) in groups.iter().enumerate() {
            let c = soft.score.total(|i| ids.contains(&i));
            // The whole frame's numbers on the variant's last row (every light).
            let whole = if k + 1 == groups.len() {
                format!("{:>10.2} {:>7.4}", soft.image_rmse, soft.flip)
            } else {
                String::new()
            };
            println!(
                "{:<24} {:<13} {:>10} {:>10.4} {:>10.4} {:>10.4} {:>10.4} | {whole}",
                v.label,
                format!("{name} ({})", c.lights),
                c.penumbra.pairs,
                c.umbra.mean(),
                c.penumbra.mean(),
                c.lit.mean(),
                c.scored().mean(),
            );
        }
    }
    println!();
    println!(
        "umbra / penumbra / lit: mean |technique - reference| of the fraction of the light seen, over the in-reach"
    );
    println!(
        "pairs facing the light where the reference sees none, some or all of it (penumbrae: how many pairs);"
    );
    println!(
        "image RMSE (8-bit RGB levels) and FLIP (mean): the frame against the same frame shaded with the reference."
    );
    let hard: Vec<&str> = results
        .iter()
        .filter(|v| v.soft.is_some() && !v.technique.info().soft_shadows)
        .map(|v| v.label.as_str())
        .collect();
    if !hard.is_empty() {
        println!(
            "render sized lights hard (no soft filter): {}",
            hard.join(", ")
        );
    }
    for v in results.iter().filter(|v| v.soft_filter) {
        if let Some(n) = area_rays(v) {
            println!("{}: {n} shadow rays per (pixel, sized light)", v.label);
        }
    }
    if results.iter().any(|v| !v.soft_filter) {
        println!(
            "-hard: every light rendered with size 0 (--soft off); the references keep the sizes."
        );
    }
    if let Some(dir) = report["soft"]["reference_image"]
        .as_str()
        .and_then(|p| std::path::Path::new(p).parent())
    {
        println!(
            "wrote      {} (soft-reference.png: the frame shaded with the reference; flip-*.png: FLIP error maps)",
            dir.display()
        );
    }
}
