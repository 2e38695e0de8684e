//! The order of a comparison: each `--scene` in turn (into its own sub-directory when there
//! are several, their reports gathered into one JSON), and for one scene the steps from the
//! flags' checks to the written report.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use indicatif::MultiProgress;
use serde_json::json;

use crate::compare::args::CompareArgs;
use crate::compare::report::{scene_report, write_json};
use crate::compare::scoring::score_variants;
use crate::compare::setup::{
    check_flags, check_ray_budget, has_sized_light, load, open, soft_plan, variants,
};
use crate::compare::table;

/// Runs the comparison of every `--scene`.
pub fn run(args: &CompareArgs) -> Result<()> {
    if args.scenes.is_empty() {
        bail!("--scene needs at least one scene");
    }
    if args.out_dir.exists() && !args.out_dir.is_dir() {
        bail!(
            "--out-dir {}: that is a file; give a folder (made if missing) for the images",
            args.out_dir.display()
        );
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
        write_json(path, &json!({ "scenes": reports }))?;
    }
    Ok(())
}

/// Scores the techniques on `args.scene`; returns the JSON report.
fn run_scene(args: &CompareArgs) -> Result<serde_json::Value> {
    if args.frames > 1 {
        return crate::compare::sequence::run_sequence(args);
    }
    let started = Instant::now();
    check_flags(args)?;
    crate::compare::sequence::check_sequence_flags(args)?;
    let multi = MultiProgress::new();
    let pb = multi.add(crate::progress::spinner("loading the scene"));
    let scene = load(args)?;
    check_ray_budget(args, &scene)?;
    let soft = soft_plan(args, &scene)?;
    let sized = has_sized_light(&scene);
    if !sized && args.soft.contains(&false) {
        pb.suspend(|| {
            eprintln!(
                "note: {} has no sized light that casts shadows: --soft off renders the same \
                 frame as on, so it is not run",
                scene.name
            )
        });
    }
    let variants = variants(args, sized);
    let setup = open(&pb, &scene, args, soft)?;
    pb.finish_and_clear();
    let scored = score_variants(&multi, &setup, &scene, &variants)?;
    let r = scored
        .reference
        .as_ref()
        .context("no technique could run on this adapter")?;
    let report = scene_report(&setup, &scene, r, &scored, started);
    table::print(&report, &scored, &scene);
    if let Some(path) = &setup.args.json {
        write_json(path, &report)?;
    }
    Ok(report)
}
