//! `manyshadows compare` end to end on the GPU that `WGPU_BACKEND` selects (no adapter: the
//! binary exits 1 and these tests fail, never skip).
//!
//! Error bounds, and why they are what they are (measured on llvmpipe, Vulkan and OpenGL,
//! Mesa 22.3.6, 256×256 frames, 2048² maps, default bias of 1 texel in each term):
//!
//! - analytic scenes (`plane-*`): **0** misclassified pixels outside the 2-pixel edge band for
//!   every technique and light type. A flat floor under a flat occluder has no grazing
//!   surfaces and no contact lines, so nothing but the outline can be wrong, and the band
//!   holds the outline. This is the bound the renderer's own analytic test enforces, now
//!   measured against the ray-traced reference instead of a hand-written box test.
//!   Inside the band: 0 (spot, point) and 9 of 65,536 pixels (directional, 0.014 %) measured;
//!   the bound is 0.1 % of in-reach pixels, a sub-texel placement error of the outline.
//! - `cubes` (boxes and a sphere resting on a floor): 2 of 86,102 scored pixels outside the
//!   band measured, both false shadow of the spot light on the floor right at the foot of the
//!   tall box (a contact line, where the biased floor point meets the box's depth). Bound
//!   0.02 % (about 17 pixels): a handful of contact pixels, never a region.
//! - a deliberately wrong bias (−1 texel in every term: the receiver is pushed *into* its
//!   surface, so it shadows itself) gives 78 % false shadow on `plane-spot`; the test requires
//!   more than 50 %, against 0 with the default bias, so the score cannot miss acne.

mod shared_gpu;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn tmp(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("manyshadows-compare-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manyshadows"))
        .args(args)
        .output()
        .expect("run manyshadows")
}

/// Runs `compare` with `extra` arguments into a fresh directory; returns the JSON and the dir.
fn compare(name: &str, extra: &[&str]) -> (Value, PathBuf) {
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
fn every_technique_scored_or_honestly_skipped(v: &Value, scene: &str) {
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

fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

fn read_msvis(path: &Path) -> manyshadows::VisibilityMask {
    manyshadows::VisibilityMask::read_raw(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn analytic_scenes_score_every_technique_within_bounds() {
    for scene in ["plane-spot", "plane-point", "plane-directional"] {
        let (v, dir) = compare(
            scene,
            &[
                "--scene",
                scene,
                "--width",
                "256",
                "--height",
                "256",
                "--shadow-resolutions",
                "2048",
            ],
        );
        let variants = v["variants"].as_array().unwrap();
        every_technique_scored_or_honestly_skipped(&v, scene);
        // The virtual maps' settings are recorded with the scores (the library's defaults).
        let defaults = manyshadows::VirtualOptions::default();
        assert_eq!(
            v["virtual_maps"]["bias_scale"].as_f64(),
            Some(f64::from(defaults.bias_scale)),
            "{scene}: {}",
            v["virtual_maps"]
        );
        assert_eq!(
            v["virtual_maps"]["lod"].as_f64(),
            Some(f64::from(defaults.lod))
        );
        for var in variants {
            let label = var["label"].as_str().unwrap();
            let by_type = var["by_type"].as_object().unwrap();
            assert_eq!(by_type.len(), 1, "{scene}: one light type");
            let c = by_type.values().next().unwrap();
            let reach = u(&c["in_reach_pixels"]);
            assert!(
                reach > 20_000,
                "{scene} {label}: only {reach} pixels in reach"
            );
            assert_eq!(
                (u(&c["false_shadow"]), u(&c["false_light"])),
                (0, 0),
                "{scene} {label}: errors away from the outline ({})",
                var["difference_image"]
            );
            let band_err = u(&c["band_false_shadow"]) + u(&c["band_false_light"]);
            // The atlas variants here have 2048² maps, far finer than the 256² frame
            // (measured: at most 0.014 % of reach in the band). Virtual maps aim for one texel
            // per pixel whatever the requested resolution, so their outline may sit half a
            // texel off inside the band: measured 0.81 % (spot), 0.22 % (point), 0.06 %
            // (directional).
            let budget = if var["technique"] == "virtual" {
                0.01
            } else {
                0.001
            };
            assert!(
                (band_err as f64) <= budget * reach as f64,
                "{scene} {label}: {band_err} errors in the edge band"
            );
            assert!(
                u(&c["band_pixels"]) > 200,
                "{scene} {label}: the outline must make a band"
            );
            // Shadow maps have texels a footprint measures; rays have none.
            let fp = &c["footprint_px"];
            let rays = var["technique"]
                .as_str()
                .unwrap()
                .parse::<manyshadows::Technique>()
                .unwrap()
                .info()
                .fills
                == manyshadows::Fills::Rays;
            assert!(rays || (u(&fp["samples"]) > 0 && fp["max"].as_f64().unwrap() > 0.0));
            assert!(Path::new(var["difference_image"].as_str().unwrap()).is_file());
        }
        // The reference mask: the frame's size, one light, some pixels lit and some not.
        let r = read_msvis(&dir.join("reference.msvis"));
        assert_eq!((r.width, r.height, r.lights), (256, 256, 1));
        let lit = r.light_image(0).iter().filter(|&&p| p > 0).count();
        assert!(lit > 10_000 && lit < 65_000, "{scene}: {lit} lit pixels");
        assert!(dir.join("frame.png").is_file());
    }
}

#[test]
fn cubes_traditional_error_is_a_few_contact_pixels() {
    let (v, _) = compare(
        "cubes",
        &[
            "--scene",
            "cubes",
            "--width",
            "256",
            "--height",
            "256",
            "--shadow-resolutions",
            "2048",
            "--techniques",
            "traditional",
        ],
    );
    let var = &v["variants"][0];
    let all = &var["by_type"]["all"];
    let errors = u(&all["false_shadow"]) + u(&all["false_light"]);
    let reach = u(&all["in_reach_pixels"]);
    assert!(reach > 50_000, "{reach}");
    assert!(
        (errors as f64) <= 0.0002 * reach as f64,
        "{errors} of {reach} pixels wrong outside the band ({})",
        var["difference_image"]
    );
    for t in ["spot", "point", "directional"] {
        assert_eq!(u(&var["by_type"][t]["lights"]), 1, "{t}");
    }
}

#[test]
fn a_wrong_bias_sign_is_caught() {
    let base = [
        "--scene",
        "plane-spot",
        "--width",
        "160",
        "--height",
        "120",
        "--shadow-resolutions",
        "2048",
        "--techniques",
        "traditional",
    ];
    let (good, _) = compare("bias-good", &base);
    let mut wrong_args = base.to_vec();
    wrong_args.extend_from_slice(&[
        "--bias-constant",
        "-1",
        "--bias-slope",
        "-1",
        "--bias-normal",
        "-1",
    ]);
    let (wrong, dir) = compare("bias-wrong", &wrong_args);
    let g = &good["variants"][0]["by_type"]["spot"];
    let w = &wrong["variants"][0]["by_type"]["spot"];
    assert_eq!(g["error_fraction"].as_f64().unwrap(), 0.0);
    let e = w["false_shadow_fraction"].as_f64().unwrap();
    assert!(e > 0.5, "self-shadowing scored only {e}");
    assert_eq!(
        u(&w["false_light"]),
        0,
        "acne is false shadow, not false light"
    );
    // The difference image shows it: red (false shadow) pixels.
    let img = image::open(dir.join("diff-traditional-2048.png"))
        .unwrap()
        .to_rgb8();
    let red = img.pixels().filter(|p| p.0 == [255, 0, 0]).count();
    assert!(red > 3000, "{red} red pixels");
}

#[test]
fn bad_input_is_a_clear_error() {
    let cases: &[(&[&str], i32, &str)] = &[
        (&["--edge-band", "1000"], 1, "edge-band"),
        (&["--shadow-resolutions", "0"], 1, "between 1 and 16384"),
        (&["--bias-constant", "NaN"], 1, "finite"),
        (&["--scene", "nope"], 1, "unknown built-in scene"),
        (&["--techniques", "nope"], 2, "unknown technique"),
        (&["--atlas-max", "8"], 1, "--atlas-max 8"),
        (
            &["--techniques", "virtual", "--virtual-bias", "NaN"],
            1,
            "--virtual-bias",
        ),
        (
            &["--techniques", "virtual", "--virtual-lod", "0"],
            1,
            "--virtual-lod",
        ),
        (
            &["--lights", "4096", "--width", "8192", "--height", "8192"],
            1,
            "reference rays",
        ),
        (&["--soft", "maybe"], 2, "neither on nor off"),
        // Out of range for every technique, not only where rays read it.
        (
            &[
                "--techniques",
                "traditional",
                "--frames",
                "2",
                "--light-samples",
                "99",
            ],
            1,
            "--light-samples",
        ),
        (&["--probes", "65"], 1, "--probes 65"),
        (
            &[
                "--soft-samples",
                "65536",
                "--width",
                "2000",
                "--height",
                "2000",
            ],
            1,
            "soft reference rays",
        ),
    ];
    for (extra, code, needle) in cases {
        let dir = tmp("bad");
        let mut args = vec!["compare", "--out-dir", dir.to_str().unwrap()];
        args.extend_from_slice(extra);
        let out = run(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(*code), "{extra:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{extra:?}: {stderr}");
        assert!(
            stderr.to_lowercase().contains(&needle.to_lowercase()),
            "{extra:?}: expected '{needle}' in {stderr}"
        );
    }
}

/// `--atlas-max` that is not a power of two is announced, not changed silently.
#[test]
fn a_rounded_atlas_max_is_announced() {
    let dir = tmp("atlas-note");
    let out = run(&[
        "compare",
        "--out-dir",
        dir.to_str().unwrap(),
        "--scene",
        "plane-spot",
        "--width",
        "32",
        "--height",
        "32",
        "--techniques",
        "traditional",
        "--atlas-max",
        "3000",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--atlas-max 3000 is used as 2048"),
        "no note: {stderr}"
    );
}

/// The share of misclassified (pixel, light) pairs outside the edge band, over every light.
fn outside_band_error(variant: &Value) -> f64 {
    let all = &variant["by_type"]["all"];
    (u(&all["false_shadow"]) + u(&all["false_light"])) as f64
        / u(&all["in_reach_pixels"]).max(1) as f64
}

/// Alpha-masked casters (the `courtyard`: a lattice roof, banners, leaf cards, a wire fence)
/// scored by the alpha-aware reference. Every technique must do at least as well outside the
/// edge band as on the same scene with every material opaque (`courtyard-opaque`: the same
/// geometry, cameras and lights; what the masks add is holes, and so edges), and shadowing
/// the masks as solid cards (`--shadow-alpha off`, the mutation a renderer that ignores alpha
/// commits) must fail that bound.
///
/// Measured on llvmpipe (Mesa 22.3.6), 320×180, default maps, masks on / opaque scene /
/// masks ignored (outside the band, all lights): see the eprintln lines of the run; the
/// figures in README.md ("Real content") are from the same command at 640×360.
#[test]
fn alpha_masked_casters_score_like_opaque_ones_and_solid_cards_fail() {
    // Hard scores only: the courtyard's lights are sized, and the soft reference would add
    // seconds to each of the three runs without touching what this test reads.
    let base = ["--width", "320", "--height", "180", "--soft-samples", "0"];
    let with = |scene: &str, extra: &[&str]| {
        let mut args = base.to_vec();
        args.extend_from_slice(&["--scene", scene]);
        args.extend_from_slice(extra);
        let (v, _) = compare(&format!("{scene}{}", extra.join("")), &args);
        v["variants"]
            .as_array()
            .unwrap()
            .iter()
            .map(|var| {
                (
                    var["technique"].as_str().unwrap().to_string(),
                    outside_band_error(var),
                )
            })
            .collect::<Vec<_>>()
    };
    let masked = with("courtyard", &[]);
    let opaque = with("courtyard-opaque", &[]);
    let solid = with("courtyard", &["--shadow-alpha", "off"]);
    assert!(masked.len() >= 6, "{masked:?}");
    for (technique, m) in &masked {
        let o = opaque.iter().find(|(t, _)| t == technique).unwrap().1;
        let s = solid.iter().find(|(t, _)| t == technique).unwrap().1;
        eprintln!(
            "{technique}: masked {:.4} %, opaque scene {:.4} %, masks shadowed as solid {:.4} % \
             misclassified outside the edge band",
            100.0 * m,
            100.0 * o,
            100.0 * s
        );
        assert!(
            *m <= o,
            "{technique}: masked casters score {m} outside the band, worse than the opaque scene's {o}"
        );
        assert!(
            s > o,
            "{technique}: shadowing the masks as solid ({s}) passed the opaque bound ({o})"
        );
    }
}

/// Set bits that differ between two masks of the same size.
fn differing_bits(a: &manyshadows::VisibilityMask, b: &manyshadows::VisibilityMask) -> u64 {
    assert_eq!((a.width, a.height, a.lights), (b.width, b.height, b.lights));
    a.words
        .iter()
        .zip(&b.words)
        .map(|(x, y)| u64::from((x ^ y).count_ones()))
        .sum()
}

/// `compare --reference gpu` traces the same rays as the CPU reference, from the same points:
/// the two masks agree but for the few rays that graze a shared edge or vertex, where the two
/// triangle tests (the CPU's watertight one, the driver's) may decide differently. Measured on
/// lavapipe (Mesa 25): atrium 480x270, 8 lights: 0 of 86,692 lit bits; the plane scenes at
/// 256x256: 0 of 25,992 / 61,300 / 64,635; by hand at 960x540, 2 of 346,432. Bound: 1 in
/// 10,000 lit bits. Without ray queries the GPU reference is refused by name.
#[test]
fn the_gpu_reference_agrees_with_the_cpu_reference() {
    let ctx = shared_gpu::context();
    let rays_here = shared_gpu::rays_here(&ctx);
    for (scene, size) in [
        ("atrium", ["480", "270"]),
        ("plane-spot", ["256", "256"]),
        ("plane-point", ["256", "256"]),
        ("plane-directional", ["256", "256"]),
    ] {
        // Hard references only (the GPU's is hard; the CPU's soft one is not compared here).
        let common = [
            "--scene",
            scene,
            "--width",
            size[0],
            "--height",
            size[1],
            "--soft-samples",
            "0",
        ];
        let mut gpu_args = vec!["--reference", "gpu", "--techniques", "layered"];
        gpu_args.extend(common);
        if !rays_here {
            let dir = tmp(&format!("gpu-ref-{scene}"));
            let out = run(&[
                &["compare", "--out-dir", dir.to_str().unwrap()],
                &gpu_args[..],
            ]
            .concat());
            assert_clean_failure_compare(&out, "EXPERIMENTAL_RAY_QUERY");
            continue;
        }
        let (_, cpu_dir) = compare(
            &format!("cpu-ref-{scene}"),
            &[&["--techniques", "layered"], &common[..]].concat(),
        );
        let (gpu, gpu_dir) = compare(&format!("gpu-ref-{scene}"), &gpu_args);
        assert_eq!(gpu["reference"]["tracer"], "gpu");
        let cpu = read_msvis(&cpu_dir.join("reference.msvis"));
        let gpu = read_msvis(&gpu_dir.join("reference.msvis"));
        let lit: u64 = cpu.words.iter().map(|w| u64::from(w.count_ones())).sum();
        let d = differing_bits(&cpu, &gpu);
        eprintln!("{scene}: {d} of {lit} lit bits differ between the CPU and GPU references");
        assert!(lit > 1000, "{scene}: too few lit bits");
        assert!(d * 10_000 <= lit, "{scene}: {d} of {lit} bits differ");
    }
}

fn assert_clean_failure_compare(out: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains(needle), "expected '{needle}' in: {stderr}");
}

/// One variant's soft score of one class over every light: (pairs, mean absolute error).
fn soft_class(variant: &Value, class: &str) -> (u64, f64) {
    let c = &variant["soft"]["by_type"]["all"][class];
    (u(&c["pairs"]), c["mean_abs_error"].as_f64().unwrap())
}

/// Soft shadows scored against the CPU's soft reference (256 samples per pair): on the
/// courtyard, whose built-in lights are sized (2 % of their range, the sun 0.53°), every
/// technique that softens sized lights must err less in the penumbra than the same technique
/// rendering the same lights hard (`--soft off`: sizes 0 for rendering, the reference keeps
/// them), and its frame must be closer to the frame shaded with the reference.
///
/// Measured on lavapipe (Vulkan) and llvmpipe (OpenGL), Mesa 25.0.7, 160×90, 8 lights, 4,848
/// penumbra pairs (4,844 on OpenGL): mean penumbra error 0.105 for every atlas technique
/// against 0.309 hard, virtual 0.089 against 0.296, raytraced (4 area rays, Vulkan only)
/// 0.136 against 0.278; image RMSE (8-bit) 4.60 against 6.28 (atlas), 4.37 against 5.91
/// (virtual), 1.73 against 3.76 (raytraced). (Before PCSS's comparisons were capped at the
/// receiver's depth, pcss.wgsl's `soft_reference`: atlas 0.132, virtual 0.156.) Bounds: at
/// most 0.2, and at most 0.7 times the hard error (measured ratios 0.30 to 0.49); image RMSE
/// below 0.9 times the hard frame's (measured 0.46 to 0.74). The mutation "PCSS filter off" (the filter radius set to 0 in
/// `pcss.wgsl`, the blocker search kept) fails it, as seen by hand: traditional 0.251
/// against 0.309, a ratio of 0.81. irregular renders every light hard, so both ways give
/// the same numbers (0.278, as rays at size 0 do); the hard scores never depend on the sizes,
/// so they are identical both ways for every technique.
#[test]
fn soft_shadows_beat_hard_ones_in_the_penumbra() {
    let (v, dir) = compare(
        "soft",
        &[
            "--scene",
            "courtyard",
            "--width",
            "160",
            "--height",
            "90",
            "--soft",
            "on,off",
        ],
    );
    every_technique_scored_or_honestly_skipped(&v, "courtyard");
    assert_eq!(v["soft"]["scored"], true, "{}", v["soft"]);
    assert_eq!(u(&v["soft"]["samples"]), 256);
    assert!(Path::new(v["soft"]["reference_image"].as_str().unwrap()).is_file());
    assert!(dir.join("soft-reference.png").is_file());
    let variants = v["variants"].as_array().unwrap();
    let mut compared = 0;
    for on in variants.iter().filter(|x| x["soft_filter"] == true) {
        let label = on["label"].as_str().unwrap();
        let hard = variants
            .iter()
            .find(|x| x["label"].as_str() == Some(&format!("{label}-hard")))
            .unwrap_or_else(|| panic!("{label}: no -hard twin"));
        assert_eq!(hard["soft_filter"], false);
        // The hard score reads the test at each light's centre: the sizes do not change it.
        // Virtual maps' sized lights ask for the pages their filter reaches, so more pages
        // are resident and a hard test may read a finer page than without: only inside the
        // edge band (measured: 606 / 568 band errors against 607 / 571; outside it the same).
        let outside_band = |scores: &serde_json::Value| -> serde_json::Value {
            let mut s = scores.clone();
            for kind in s.as_object_mut().unwrap().values_mut() {
                let o = kind.as_object_mut().unwrap();
                o.retain(|k, _| !k.starts_with("band_"));
            }
            s
        };
        if label.starts_with("virtual") {
            assert_eq!(
                outside_band(&on["by_type"]),
                outside_band(&hard["by_type"]),
                "{label}: hard scores outside the edge band differ"
            );
        } else {
            assert_eq!(
                on["by_type"], hard["by_type"],
                "{label}: hard scores differ"
            );
        }
        let (pairs, soft_error) = soft_class(on, "penumbra");
        let (hard_pairs, hard_error) = soft_class(hard, "penumbra");
        assert_eq!(
            pairs, hard_pairs,
            "{label}: the classes are the reference's"
        );
        assert!(pairs > 2000, "{label}: only {pairs} penumbra pairs");
        let (rmse, hard_rmse) = (
            on["soft"]["image_rmse_8bit"].as_f64().unwrap(),
            hard["soft"]["image_rmse_8bit"].as_f64().unwrap(),
        );
        let flip = on["soft"]["flip_mean"].as_f64().unwrap();
        eprintln!(
            "{label}: penumbra error {soft_error:.4} (hard {hard_error:.4}) over {pairs} pairs; \
             image RMSE {rmse:.2} (hard {hard_rmse:.2}); FLIP {flip:.4}"
        );
        assert!(flip > 0.0 && flip < 0.2, "{label}: FLIP {flip}");
        assert!(Path::new(on["soft"]["flip_image"].as_str().unwrap()).is_file());
        if on["soft_shadows"] == false {
            assert_eq!(
                (soft_error, rmse),
                (hard_error, hard_rmse),
                "{label} renders sized lights hard: the same both ways"
            );
            continue;
        }
        assert!(
            soft_error <= 0.2 && soft_error <= 0.7 * hard_error,
            "{label}: penumbra error {soft_error} with the soft filter, {hard_error} without"
        );
        assert!(
            rmse < 0.9 * hard_rmse,
            "{label}: image RMSE {rmse} with the soft filter, {hard_rmse} without"
        );
        compared += 1;
    }
    // Every atlas technique this adapter runs, and virtual maps.
    assert!(compared >= 5, "only {compared} soft techniques compared");
}

/// The soft reference traced on the GPU (`--reference gpu`: the ray-traced technique's soft
/// visibility, 256 rays per pixel and sized light on the same kind of stratified grid) agrees
/// with the CPU's: the same penumbra within sampling noise. Measured on lavapipe (Mesa 25),
/// courtyard 320x180, 8 lights, traditional scored against each: 16,812 penumbra pairs (CPU)
/// against 16,705 (GPU), mean penumbra error 0.1413 against 0.1420. Bounds: pairs within 3 %,
/// the error within 0.01. Without ray queries the GPU reference is refused by name.
#[test]
fn the_gpu_soft_reference_agrees_with_the_cpu_one() {
    let ctx = shared_gpu::context();
    let rays_here = shared_gpu::rays_here(&ctx);
    let common = [
        "--scene",
        "courtyard",
        "--width",
        "320",
        "--height",
        "180",
        "--techniques",
        "traditional",
    ];
    if !rays_here {
        let dir = tmp("soft-gpu-ref-refused");
        let out = run(&[
            &[
                "compare",
                "--out-dir",
                dir.to_str().unwrap(),
                "--reference",
                "gpu",
            ],
            &common[..],
        ]
        .concat());
        assert_clean_failure_compare(&out, "EXPERIMENTAL_RAY_QUERY");
        return;
    }
    let (cpu, _) = compare("soft-cpu-ref", &common);
    let (gpu, _) = compare(
        "soft-gpu-ref",
        &[&common[..], &["--reference", "gpu"]].concat(),
    );
    assert_eq!(gpu["reference"]["tracer"], "gpu");
    let penumbra = |v: &Value| soft_class(&v["variants"][0], "penumbra");
    let ((cpu_pairs, cpu_error), (gpu_pairs, gpu_error)) = (penumbra(&cpu), penumbra(&gpu));
    eprintln!("penumbra pairs {cpu_pairs} / {gpu_pairs}, error {cpu_error:.4} / {gpu_error:.4}");
    assert!(cpu_pairs > 5000);
    assert!(cpu_pairs.abs_diff(gpu_pairs) * 100 <= 3 * cpu_pairs);
    assert!((cpu_error - gpu_error).abs() <= 0.01);
}

/// A technique whose frame would take minutes is estimated before it is drawn, as `render`
/// does: named, it is refused with its estimate (irregular at 16,384 lights: every caster
/// triangle against each of 43,693 light views).
#[test]
fn a_technique_of_minutes_is_refused_with_its_estimate() {
    let dir = tmp("minutes");
    let out = run(&[
        "compare",
        "--lights",
        "16384",
        "--techniques",
        "irregular",
        "--soft-samples",
        "0",
        "--width",
        "64",
        "--height",
        "36",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert_clean_failure_compare(&out, "technique irregular would take");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--insist"), "{stderr}");
}

/// The CPU reference shows its progress: in a log (stderr no terminal) a line at every tenth
/// of its rows with the rays so far, rays per second and the time left (issue 42).
#[test]
fn the_reference_shows_its_progress_in_a_log() {
    let dir = tmp("progress");
    let out = run(&[
        "compare",
        "--scene",
        "plane-spot",
        "--techniques",
        "traditional",
        "--width",
        "80",
        "--height",
        "60",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("reference rays: "))
        .collect();
    // Rows finish on several threads: the lines may come in any order, each tenth once.
    let mut rows: Vec<u32> = lines
        .iter()
        .map(|l| {
            l["reference rays: ".len()..]
                .split('/')
                .next()
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("{l}"))
        })
        .collect();
    rows.sort_unstable();
    assert_eq!(
        rows,
        (1..=10).map(|k| k * 6).collect::<Vec<u32>>(),
        "a line per tenth of 60 rows: {stderr}"
    );
    for l in &lines {
        assert!(l.contains("/s") && l.ends_with("s left"), "{l}");
    }
}

/// `compare --stages` says each part of every technique's frame as the GPU finishes it, in
/// order (as `render --stages`, whose frames are checked byte for byte in cli.rs).
#[test]
fn compare_tells_each_frame_in_stages() {
    let dir = tmp("stages");
    let out = run(&[
        "compare",
        "--scene",
        "cubes",
        "--techniques",
        "traditional,virtual",
        "--width",
        "96",
        "--height",
        "72",
        "--soft-samples",
        "0",
        "--stages",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{err}");
    for t in ["traditional", "virtual"] {
        let lines: Vec<&str> = err
            .lines()
            .filter(|l| l.starts_with(&format!("{t}: ")) && l.contains(" done after "))
            .collect();
        assert_eq!(lines.len(), 3, "{t}: {err}");
        for (l, part) in lines
            .iter()
            .zip(["G-buffer and light clusters", "shadows", "lighting"])
        {
            assert!(l.contains(part), "{t}: {l}");
        }
    }
}

/// `compare --frames N` scores every frame of a sequence against the exact image of that same
/// frame: the ray-traced technique with every light is that exact image (RMSE 0 in every frame
/// of a turning camera and a moving caster, which fails if any renderer misses a step of the
/// sequence), shadow maps differ from it a little, and sampled rays denoised over still frames
/// come closer to it frame by frame. Without ray queries it is refused by name.
#[test]
fn compare_over_a_sequence_scores_each_frame_against_its_exact_image() {
    let ctx = shared_gpu::context();
    let rays_here = shared_gpu::rays_here(&ctx);
    let frame = ["--scene", "cubes", "--width", "160", "--height", "90"];
    if !rays_here {
        let dir = tmp("sequence-refused");
        let out = run(&[
            &[
                "compare",
                "--out-dir",
                dir.to_str().unwrap(),
                "--frames",
                "3",
            ],
            &frame[..],
        ]
        .concat());
        assert_clean_failure_compare(&out, "EXPERIMENTAL_RAY_QUERY");
        return;
    }
    let dir = tmp("sequence-moving");
    let json = dir.join("score.json");
    let out = run(&[
        &[
            "compare",
            "--out-dir",
            dir.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ],
        &frame[..],
        &[
            "--frames",
            "4",
            "--orbit",
            "3",
            "--techniques",
            "raytraced,traditional",
            "--probes",
            "2",
        ],
    ]
    .concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // Progress in a log (stderr is no terminal here): a line per tenth of the frames.
    assert!(stderr.contains("frame 4/4 scored after"), "{stderr}");
    let moving: Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(moving["frames"], 4);
    // Two seeded probes, lit (and reflected) alike by the exact renderer and the technique.
    assert_eq!(moving["probes"], 2);
    assert!(moving["moving_instance"].is_u64(), "{moving}");
    let rows = moving["techniques"].as_array().expect("techniques");
    let rmse = |name: &str| -> Vec<f64> {
        let row = rows
            .iter()
            .find(|r| r["technique"] == name)
            .unwrap_or_else(|| panic!("no {name} row: {moving}"));
        row["rmse"]
            .as_array()
            .expect("rmse per frame")
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    assert_eq!(
        rmse("raytraced"),
        vec![0.0; 4],
        "every light traced is the exact frame"
    );
    let maps = rmse("traditional");
    assert_eq!(maps.len(), 4);
    assert!(
        maps.iter().all(|&e| e > 0.0 && e < 10.0),
        "shadow maps a little off the exact frames: {maps:?}"
    );
    for f in ["sequence.png", "exact-last.png", "traditional-last.png"] {
        assert!(dir.join(f).exists(), "{f} not written");
    }
    let (still, _) = compare(
        "sequence-denoised",
        &[
            &frame[..],
            &[
                "--lights",
                "64",
                "--frames",
                "6",
                "--still",
                "--techniques",
                "raytraced",
                "--light-samples",
                "1",
                "--denoise",
            ],
        ]
        .concat(),
    );
    let row = &still["techniques"][0];
    assert_eq!(row["technique"], "raytraced-k1-denoise");
    let e: Vec<f64> = row["rmse"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    eprintln!("K = 1 denoised over still frames: RMSE {e:?}");
    assert!(
        e.iter().all(|&x| x > 0.0),
        "sampled frames are not exact: {e:?}"
    );
    assert!(
        e[5] < 0.85 * e[0],
        "the denoiser's history brings the still frames closer: {e:?}"
    );
    // Sequence flags without a sequence, and a sequence of no frames.
    for (bad, needle) in [
        (vec!["--light-samples", "1"], "--light-samples"),
        (vec!["--orbit", "2"], "--orbit"),
        (vec!["--frames", "0"], "--frames"),
    ] {
        let dir = tmp("sequence-bad");
        let out = run(&[
            &["compare", "--out-dir", dir.to_str().unwrap()],
            &frame[..],
            &bad[..],
        ]
        .concat());
        assert_clean_failure_compare(&out, needle);
    }
}

/// Issue 42's quality table, its two cells that were worse (one false-shadow pair each):
/// with hard lights at 320 × 180 on the atrium and the courtyard, virtual maps misclassify no
/// more (pixel, light) pairs outside the edge band than the atlas, for every light type. Their
/// spot faces sample the atlas floor there, whose texels are the atlas tile's; with half the
/// atlas's receiver bias (before) each scene's spot lights had one false-shadow pair the atlas
/// has not (0.003 % and 0.004 % against 0.000 %). The whole table is in
/// docs/bench/virtual-vs-atlas-quality-lavapipe.txt.
#[test]
fn virtual_maps_misclassify_no_more_than_the_atlas_in_small_frames() {
    for scene in ["atrium", "courtyard"] {
        let (v, _) = compare(
            &format!("virtual-vs-atlas-{scene}"),
            &[
                "--scene",
                scene,
                "--techniques",
                "traditional,virtual",
                "--light-size",
                "0",
                "--sun-size",
                "0",
                "--width",
                "320",
                "--height",
                "180",
            ],
        );
        let variant = |t: &str| {
            v["variants"]
                .as_array()
                .unwrap()
                .iter()
                .find(|x| x["technique"] == t)
                .unwrap_or_else(|| panic!("{t} not scored: {v}"))
                .clone()
        };
        let (atlas, virt) = (variant("traditional"), variant("virtual"));
        for kind in ["spot", "point", "directional"] {
            let wrong = |x: &Value| {
                let t = &x["by_type"][kind];
                u(&t["false_shadow"]) + u(&t["false_light"])
            };
            eprintln!(
                "{scene} {kind}: atlas {} pairs, virtual {} pairs misclassified outside the band",
                wrong(&atlas),
                wrong(&virt)
            );
            assert!(
                wrong(&virt) <= wrong(&atlas),
                "{scene}, {kind} lights: virtual {} against the atlas's {}",
                wrong(&virt),
                wrong(&atlas)
            );
        }
    }
}
