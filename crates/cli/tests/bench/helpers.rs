//! Helpers the test modules share.

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

pub(crate) fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("manyshadows-bench-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `manyshadows bench ARGS…` (`args` split at white space), then `extra`.
pub(crate) fn bench(args: &str, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .arg("bench")
        .args(args.split_whitespace())
        .args(extra)
        .output()
        .expect("run manyshadows")
}

/// `manyshadows bench COMMAND ARGS… --out-dir <a fresh directory>`, which must succeed without
/// a validation error and print and write a table naming the adapter; the directory and its
/// results.json.
pub(crate) fn bench_ok(command: &str, args: &str) -> (PathBuf, Value) {
    // A directory per command and arguments: tests of one command run side by side.
    let mut h = std::collections::hash_map::DefaultHasher::new();
    std::hash::Hash::hash(args, &mut h);
    let dir = tmp(&format!("{command}-{:x}", std::hash::Hasher::finish(&h)));
    let out = bench(
        &format!("{command} {args}"),
        &["--out-dir", dir.to_str().unwrap()],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "bench {args:?} failed: {stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
    assert!(
        stdout.contains("adapter:"),
        "every table names the adapter: {stdout}"
    );
    assert!(std::fs::read_to_string(dir.join("results.txt"))
        .unwrap()
        .contains("adapter:"));
    let json: Value =
        serde_json::from_slice(&std::fs::read(dir.join("results.json")).unwrap()).unwrap();
    assert!(json["adapter"].is_string(), "{json}");
    // Every table reports the run's peak resident memory, measured (more than the 1 MiB no
    // process running a GPU device stays under).
    assert!(
        stdout.contains("memory: peak resident"),
        "no memory line: {stdout}"
    );
    assert!(
        json["peak_resident_bytes"]
            .as_u64()
            .is_some_and(|b| b > 1 << 20),
        "{}",
        json["peak_resident_bytes"]
    );
    (dir, json)
}

/// results.json's records.
pub(crate) fn records(json: &Value) -> &Vec<Value> {
    json["records"].as_array().unwrap()
}

/// `manyshadows bench ARGS…` must fail cleanly (exit code 1, no panic), saying `needle`.
pub(crate) fn rejects(args: &str, needle: &str) {
    let out = bench(args, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected '{needle}' in {stderr}"
    );
}

/// `ratio` must be `time / base_time`, both GPU medians of `record`'s run (lavapipe and
/// llvmpipe GL both have timestamp queries, so the times must be there).
pub(crate) fn assert_ratio(ratio: &Value, time: &Value, base_time: &Value, record: &Value) {
    let time = time
        .as_f64()
        .unwrap_or_else(|| panic!("no GPU time on an adapter with timestamps: {record}"));
    let base = base_time
        .as_f64()
        .unwrap_or_else(|| panic!("no baseline GPU time beside {record}"));
    let want = time / base;
    let got = ratio
        .as_f64()
        .unwrap_or_else(|| panic!("no ratio in {record}"));
    assert!(
        (got - want).abs() <= 1e-9 * want.abs().max(1.0),
        "ratio {got} is not {time} / {base} ({want}): {record}"
    );
}

/// Every record's `ratio_key` must be its `time_key` over that of the `base_method` record
/// with the same `same` fields, recomputed here from the records' own medians. Returns how
/// many records other than the baseline's have one.
pub(crate) fn assert_ratios(
    records: &[Value],
    time_key: &str,
    ratio_key: &str,
    base_method: &str,
    same: &[&str],
) -> usize {
    let mut ratios = 0;
    for r in records {
        let base = records
            .iter()
            .find(|b| b["method"] == base_method && same.iter().all(|k| b[k] == r[k]))
            .unwrap_or_else(|| panic!("no {base_method} record beside {r}"));
        assert_ratio(&r[ratio_key], &r[time_key], &base[time_key], r);
        ratios += usize::from(r["method"] != base_method);
    }
    ratios
}
