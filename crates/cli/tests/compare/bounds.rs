//! Hard shadows' error bounds against the CPU reference (see the crate's documentation).

use std::path::Path;

use serde_json::Value;

use crate::helpers::{compare, every_technique_scored_or_honestly_skipped, read_msvis, u};

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
