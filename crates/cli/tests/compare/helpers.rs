//! Helpers the test modules share.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

use crate::shared_gpu;

pub(crate) fn tmp(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("manyshadows-compare-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub(crate) fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(args)
        .output()
        .expect("run manyshadows")
}

/// Runs `compare` with `extra` arguments into a fresh directory; returns the JSON and the dir.
pub(crate) fn compare(name: &str, extra: &[&str]) -> (Value, PathBuf) {
    let dir = tmp(name);
    let json = dir.join("score.json");
    let mut args = vec![
        "compare",
        "--out-dir",
        dir.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = run(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "compare {extra:?} failed: {stderr}\n(GPU tests need an adapter: install mesa-vulkan-drivers or libegl1 + libgl1-mesa-dri)"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    // One frame's table, or a sequence's (--frames).
    assert!(
        stdout.contains("false shad.") || stdout.contains("mean RMSE"),
        "no table printed: {stdout}"
    );
    let v: Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    (v, dir)
}

/// Every technique of the registry was scored, or skipped because this adapter lacks
/// something the technique declares it needs (and the skip says which). A skip of a technique
/// the adapter can run, or a technique neither scored nor skipped, fails.
pub(crate) fn every_technique_scored_or_honestly_skipped(v: &Value, scene: &str) {
    let ctx = shared_gpu::context();
    let scored: Vec<&str> = v["variants"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["technique"].as_str().unwrap())
        .collect();
    let skipped: Vec<(&str, &str)> = v["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            (
                s["variant"].as_str().unwrap(),
                s["reason"].as_str().unwrap(),
            )
        })
        .collect();
    for t in manyshadows::Technique::all() {
        let unmet = t.info().unmet(&ctx);
        if scored.contains(&t.name()) {
            assert!(
                unmet.is_empty(),
                "{scene}: {t} scored on a device without {unmet:?}"
            );
            continue;
        }
        let (_, why) = skipped
            .iter()
            .find(|(label, _)| *label == t.name() || label.starts_with(&format!("{t}-")))
            .unwrap_or_else(|| panic!("{scene}: technique {t} was neither scored nor skipped"));
        assert!(
            !unmet.is_empty(),
            "{scene}: {t} was skipped ({why}) though {} has everything it needs",
            ctx.describe()
        );
        assert!(
            why.contains(&unmet[0].name()),
            "{scene}: the skip of {t} should name {}: {why}",
            unmet[0].name()
        );
        manyshadows_testkit::refused(
            &unmet[0].name(),
            &format!("compare on {scene} skipped {t}: {why}"),
        );
    }
}

pub(crate) fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

pub(crate) fn read_msvis(path: &Path) -> manyshadows::VisibilityMask {
    manyshadows::VisibilityMask::read_raw(&std::fs::read(path).unwrap()).unwrap()
}

pub(crate) fn assert_clean_failure_compare(out: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains(needle), "expected '{needle}' in: {stderr}");
}

/// One variant's soft score of one class over every light: (pairs, mean absolute error).
pub(crate) fn soft_class(variant: &Value, class: &str) -> (u64, f64) {
    let c = &variant["soft"]["by_type"]["all"][class];
    (u(&c["pairs"]), c["mean_abs_error"].as_f64().unwrap())
}
