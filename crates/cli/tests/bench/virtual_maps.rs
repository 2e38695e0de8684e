//! `bench virtual`, with and without `--cache`.

use crate::helpers::{assert_ratio, bench_ok, records, rejects};

/// `bench virtual` on a tiny frame: both paths run in the same run, every light count gets a
/// record, the virtual side's pages add up (resident + denied = what the admission rule
/// admits or denies, resident within the pool, quarter pages four to a pool page), and a 1 MiB pool (16 pages) at 200 lights must
/// deny pages and say so.
#[test]
fn bench_virtual_reports_pages_memory_and_both_paths() {
    let (dir, json) = bench_ok(
        "virtual",
        "--scene cubes --lights 4,200 --width 160 --height 90 --page-pool 1 --repeats 1 --warmup 0",
    );
    let records = records(&json);
    assert_eq!(records.len(), 2, "{json}");
    for r in records {
        let s = &r["stats"];
        let needed: u64 = s["needed"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .sum();
        let (resident, denied) = (
            s["resident"].as_u64().unwrap(),
            s["denied"].as_u64().unwrap(),
        );
        // The admission rule (VirtualStats::asked): the finest level A whose marked pages fit
        // the pool with the asked pages of every coarser level is admitted whole, asked pages
        // coarser than A are resident, asked pages finer than A denied; ancestors no sample
        // asked for are drawn only at A. When not even level 0 fits, level 0 is placed (in
        // quarter pages, the rest denied) and every finer asked page is denied.
        let per_level = |key: &str| -> Vec<u64> {
            s[key]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap())
                .collect()
        };
        let (marked, asked) = (per_level("needed"), per_level("asked"));
        let pool = s["pool_pages"].as_u64().unwrap();
        let accounted = if marked[0] > pool {
            marked[0] + asked[1..].iter().sum::<u64>()
        } else {
            let mut coarser = 0;
            let mut a = 0;
            for (level, &m) in marked.iter().enumerate() {
                if coarser + m > pool {
                    break;
                }
                a = level;
                coarser += asked[level];
            }
            asked[..a].iter().sum::<u64>() + marked[a] + asked[a + 1..].iter().sum::<u64>()
        };
        assert_eq!(resident + denied, accounted, "{r}");
        assert!(accounted <= needed, "{r}");
        // Pool pages used: whole pages plus quarter pages four to one.
        let quarters = s["quarter_faces"].as_u64().unwrap();
        assert!(
            resident - quarters + quarters.div_ceil(4) <= s["pool_pages"].as_u64().unwrap(),
            "{r}"
        );
        assert_eq!(
            s["pool_pages"].as_u64().unwrap(),
            16,
            "1 MiB = 512² texels = 16 pages"
        );
        assert!(resident > 0, "{r}");
        // Memory kept: the page pool (1 MiB) plus the table (per entry its page, its farthest
        // receiver's key and the cells its samples reach: 12 bytes) against the atlas; every
        // map drawn anew, so no copy of last frame's table is kept.
        let table = s["fit"]["table_entries"].as_u64().unwrap();
        assert_eq!(s["table_bytes"].as_u64().unwrap(), 12 * table, "{r}");
        assert_eq!(s["prev_table_bytes"].as_u64().unwrap(), 0, "{r}");
        let v_mib = r["virtual_maps"]["shadow_mib"].as_f64().unwrap();
        let want = (s["pool_bytes"].as_u64().unwrap() + 12 * table) as f64 / (1u64 << 20) as f64;
        assert!(
            (v_mib - want).abs() < 1e-6 && (1.0..3.0).contains(&v_mib),
            "{r}"
        );
        assert!(r["atlas"]["shadow_mib"].as_f64().unwrap() > 0.0, "{r}");
        // The frame ratio comes from the two paths' medians in the same run.
        assert_ratio(
            &r["frame_ratio_virtual_vs_atlas"],
            &r["virtual_maps"]["frame_ms"],
            &r["atlas"]["frame_ms"],
            r,
        );
    }
    // 200 lights use hundreds of faces: not even a quarter page each fits, so the pool fills
    // with level-0 quarter pages (four faces to a pool page) and the faces beyond them are
    // counted unshadowed.
    let s = &records[1]["stats"];
    assert!(
        s["denied"].as_u64().unwrap() > 0,
        "200 lights cannot fit 16 pages: {s}"
    );
    assert_eq!(s["resident"].as_u64().unwrap(), 4 * 16, "{s}");
    assert_eq!(s["quarter_faces"].as_u64().unwrap(), 4 * 16, "{s}");
    assert!(s["unshadowed_faces"].as_u64().unwrap() > 0, "{s}");
    assert!(dir.join("virtual-cubes-160x90.png").is_file());
}

/// `bench virtual --cache`: both paths keep what did not change while the smallest caster
/// moves, so the measured (post-warm-up) frame of the virtual maps draws only some of its
/// resident pages and keeps the rest; the memory kept then counts last frame's page table
/// too (as large as the table). Without `--page-pool` the pool is as large as the atlas
/// (equal memory); `--page-pool 0` is refused naming the flag.
#[test]
fn bench_virtual_with_cache_measures_frames_that_keep_pages() {
    let (_, json) = bench_ok(
        "virtual",
        "--scene cubes --lights 8 --width 160 --height 90 --repeats 2 --warmup 1 --cache",
    );
    assert_eq!(json["cache"], true, "{json}");
    let records = records(&json);
    let s = &records[0]["stats"];
    let (drawn, kept, resident) = (
        s["drawn"].as_u64().unwrap(),
        s["kept"].as_u64().unwrap(),
        s["resident"].as_u64().unwrap(),
    );
    // A pool below one page is refused naming the flag, before any frame is measured.
    rejects(
        "virtual --scene cubes --lights 4 --width 32 --height 18 --page-pool 0",
        "--page-pool",
    );
    assert!(kept > 0 && drawn < resident, "{s}");
    assert_eq!(drawn + kept, resident, "{s}");
    let table = s["table_bytes"].as_u64().unwrap();
    assert_eq!(s["prev_table_bytes"].as_u64().unwrap(), table, "{s}");
    let atlas_mib = records[0]["atlas"]["shadow_mib"].as_f64().unwrap();
    let pool_mib = s["pool_bytes"].as_u64().unwrap() as f64 / (1u64 << 20) as f64;
    assert!(
        (pool_mib - atlas_mib).abs() < 1e-6,
        "pool {pool_mib} MiB, atlas {atlas_mib} MiB"
    );
    let mib = records[0]["virtual_maps"]["shadow_mib"].as_f64().unwrap();
    let want = (s["pool_bytes"].as_u64().unwrap() + 2 * table) as f64 / (1u64 << 20) as f64;
    assert!((mib - want).abs() < 1e-6, "{mib} MiB kept, want {want}");
}
