//! `bench layered`.

use crate::helpers::{assert_ratios, bench_ok, records, rejects};

#[test]
fn bench_layered_writes_table_json_and_plots() {
    let (dir, json) = bench_ok(
        "layered",
        "--maps 1,3 --resolutions 128 --variants skinned,backface \
         --methods traditional,layered --repeats 2 --warmup 0",
    );
    assert_eq!(
        (json["repeats"].as_u64(), json["warmup"].as_u64()),
        (Some(2), Some(0))
    );
    let records = records(&json);
    // skinned: traditional + layered:none; backface: traditional + layered:none +
    // layered:backface; two map counts each.
    assert_eq!(records.len(), (2 + 3) * 2, "{json}");
    for r in records {
        let maps = r["maps"].as_u64().unwrap();
        assert_eq!(r["cpu_ms_runs"].as_array().unwrap().len(), 2, "repeats");
        assert!(r["cpu_ms"].as_f64().unwrap() > 0.0);
        // Every method generated every map: one view drawn per map.
        assert_eq!(r["stats"]["views_drawn"].as_u64().unwrap(), maps, "{r}");
        if r["method"] == "traditional" {
            assert_eq!(
                r["stats"]["passes"].as_u64().unwrap(),
                maps,
                "one pass per map"
            );
        } else {
            assert_eq!(
                r["stats"]["draws"].as_u64().unwrap(),
                1,
                "one draw for all maps"
            );
        }
    }
    // Ratios: every method's GPU time over traditional's for the same variant, resolution and
    // map count.
    let ratios = assert_ratios(
        records,
        "gpu_ms",
        "gpu_ratio_vs_traditional",
        "traditional",
        &["variant", "maps", "resolution"],
    );
    assert_eq!(ratios, 3 * 2, "one ratio per layered record");
    for variant in ["skinned", "backface"] {
        let png = dir.join(format!("layered-{variant}-128.png"));
        let img = image::open(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert_eq!((img.width(), img.height()), (1400, 1000));
    }
    assert!(std::fs::read_to_string(dir.join("results.txt"))
        .unwrap()
        .contains("traditional"));
}

#[test]
fn bench_layered_rejects_bad_arguments() {
    for (args, needle) in [
        ("--maps 0", "--maps 0"),
        ("--maps 5000", "--maps 5000"),
        ("--resolutions 3", "--resolutions 3"),
        ("--variants nope", "unknown variant"),
        ("--methods nope", "unknown technique"),
        ("--methods layered:sideways", "unknown cull mode"),
        ("--repeats 0", "--repeats"),
    ] {
        rejects(&format!("layered {args}"), needle);
    }
}
