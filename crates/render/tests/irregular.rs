//! `--technique irregular` (irregular shadow maps, [`manyshadows::irregular`]): exact shadow
//! outlines of the analytic scenes (the check of `analytic.rs`), equality with the CPU
//! reference on a many-light scene (more than 32 lights, so more than one mask word), a
//! reported node-pool overflow, and the cases it refuses.

mod common;

use manyshadows::gpu_scene::instances::GpuScene;
use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::shadows::atlas::generator::ShadowGenerator;
use manyshadows::shadows::plan::ShadowPlan;
use manyshadows::IrregularOptions;
use manyshadows::{Pcf, RenderError, RenderSettings, Renderer, ShadowOptions, Technique};

const SIZE: u32 = 256;
const EDGE_BAND_PX: i32 = 2;

fn settings(w: u32, h: u32) -> RenderSettings {
    RenderSettings::default()
        .with_width(w)
        .with_height(h)
        .with_pcf(Pcf::Off)
        .with_visibility(true)
        .with_technique(Technique::IRREGULAR)
}

/// Pixels more than [`EDGE_BAND_PX`] from an edge whose visibility disagrees with the exact
/// analytic shadow, and all disagreeing pixels (a difference image goes to
/// target/test-artifacts).
fn wrong_pixels(name: &str, grid: Option<u32>) -> (usize, usize) {
    wrong_pixels_hashed(name, grid, None)
}

fn wrong_pixels_hashed(name: &str, grid: Option<u32>, hash: Option<u32>) -> (usize, usize) {
    let ctx = common::context();
    let scene = builtin::build(name, &BuiltinOptions::default()).expect("builtin scene");
    let mut s = settings(SIZE, SIZE);
    s.irregular.grid = grid;
    s.irregular.hash = hash;
    let mut r = Renderer::new(&ctx, &scene, s).expect("renderer");
    let frame = r.render().expect("frame");
    let vis = frame.visibility.expect("visibility mask");
    let truth = common::analytic_truth(&scene, SIZE);
    let path = common::artifacts_dir().join(format!("irregular-{name}.png"));
    let common::TruthAgreement {
        wrong,
        wrong_anywhere,
        ..
    } = common::agree_with_truth(&vis, &truth, SIZE, EDGE_BAND_PX, &path);
    eprintln!(
        "{name} irregular (grid {grid:?}): {wrong} pixels away from edges and \
         {wrong_anywhere} in all disagree with the exact shadow ({})",
        path.display()
    );
    (wrong, wrong_anywhere)
}

/// The multimap hash (texels sharing list heads) changes which samples a triangle visits, not
/// the answer: still exact away from edges.
#[test]
fn multimap_hash_keeps_the_shadow_exact() {
    for name in ["plane-spot", "plane-point"] {
        let (wrong, _) = wrong_pixels_hashed(name, None, Some(8));
        assert_eq!(
            wrong, 0,
            "{name} with a hashed multimap: {wrong} pixels disagree"
        );
    }
}

fn check(name: &str) {
    // The default grid, and a coarse one (long lists): the grid changes the cost only.
    for grid in [None, Some(16)] {
        let (wrong, _) = wrong_pixels(name, grid);
        assert_eq!(
            wrong, 0,
            "{name} (grid {grid:?}): {wrong} pixels away from edges disagree with the exact shadow"
        );
    }
}

#[test]
fn spot_light_shadow_matches_exact_outline() {
    check("plane-spot");
}

#[test]
fn point_light_shadow_matches_exact_outline() {
    check("plane-point");
}

#[test]
fn directional_light_shadow_matches_exact_outline() {
    check("plane-directional");
}

/// 40 lights of every type over the atrium: the mask has two words per pixel, and every bit
/// must equal the exact CPU reference traced from the same G-buffer points, except within
/// two pixels of a reference edge (where single-precision differences between the GPU and
/// CPU segment tests may flip a bit).
#[test]
fn many_lights_match_the_reference() {
    let ctx = common::context();
    let opts = BuiltinOptions {
        lights: Some(40),
        ..Default::default()
    };
    let scene = builtin::build("atrium", &opts).expect("atrium");
    let (w, h) = (160, 90);
    let mut r = Renderer::new(&ctx, &scene, settings(w, h)).expect("renderer");
    let frame = r.render().expect("frame");
    let vis = frame.visibility.expect("mask");
    assert_eq!(vis.words_per_pixel, 2);
    let stats = r.irregular_stats().expect("irregular stats");
    assert_eq!(stats.unmapped, 0, "{stats:?}");
    let common::ReferenceErrors {
        pairs,
        lit,
        wrong,
        wrong_in_band,
        ..
    } = common::reference_errors(&r, &scene, &vis, 2);
    eprintln!(
        "atrium, 40 lights, {w}x{h}: {wrong} of {pairs} (pixel, light) bits differ from the \
         reference outside the edge band, {wrong_in_band} inside it ({lit} lit; {stats:?})"
    );
    assert!(lit > pairs / 20, "degenerate: {lit} lit bits of {pairs}");
    assert_eq!(
        wrong, 0,
        "bits differ from the reference outside the edge band"
    );
    assert!(
        wrong_in_band * 10_000 <= pairs,
        "{wrong_in_band} bits differ inside the edge band"
    );
}

/// A node pool too small for the frame's samples is an error, never a silently wrong mask.
#[test]
fn node_pool_overflow_is_reported() {
    let ctx = common::context();
    let scene = builtin::build("plane-spot", &BuiltinOptions::default()).expect("scene");
    let mut s = settings(64, 64);
    s.irregular = IrregularOptions::default().with_node_capacity(Some(100));
    let mut r = Renderer::new(&ctx, &scene, s).expect("renderer");
    match r.render() {
        Err(RenderError::NodePoolOverflow {
            dropped, capacity, ..
        }) => {
            assert_eq!(capacity, 100);
            assert!(dropped > 0);
        }
        Err(e) => panic!("expected a node-pool overflow, got {e}"),
        Ok(_) => panic!("a 100-node pool cannot hold a 64x64 frame's samples"),
    }
    // The same frame with the planned pool renders.
    let mut r = Renderer::new(&ctx, &scene, settings(64, 64)).expect("renderer");
    let frame = r.render().expect("frame");
    let stats = r.irregular_stats().expect("stats");
    assert!(stats.peak_nodes > 0 && stats.peak_nodes <= stats.node_capacity);
    assert!(frame.visibility.is_some());
}

/// What irregular refuses, with a clear error: atlas generation on its own (benchmarks,
/// caching), the atlas read-back, and dual-paraboloid point shadows (curved edges).
#[test]
fn refuses_atlas_paths_and_paraboloids() {
    let ctx = common::context();
    let scene = builtin::build("plane-point", &BuiltinOptions::default()).expect("scene");
    let gpu = GpuScene::new(&ctx, &scene).expect("upload");
    let plan = ShadowPlan::new(&scene, 1.0, 4096, Default::default()).expect("plan");
    let err = ShadowGenerator::new(
        &ctx,
        &scene,
        &gpu,
        plan,
        Technique::IRREGULAR.info(),
        ShadowOptions::default(),
    )
    .err()
    .expect("no atlas generator for irregular");
    assert!(
        matches!(
            err,
            RenderError::NoAtlas {
                technique: Technique::IRREGULAR,
                ..
            }
        ),
        "{err}"
    );
    let r = Renderer::new(&ctx, &scene, settings(32, 32)).expect("renderer");
    assert!(matches!(
        r.read_page_pool(),
        Err(RenderError::NoPagePool {
            technique: Technique::IRREGULAR,
            ..
        })
    ));
    assert!(matches!(
        r.read_page_table(),
        Err(RenderError::NoPagePool {
            technique: Technique::IRREGULAR,
            ..
        })
    ));
    assert!(matches!(
        r.read_atlas(),
        Err(RenderError::NoAtlas {
            technique: Technique::IRREGULAR,
            ..
        })
    ));
    let mut s = settings(32, 32);
    s.point_shadows = PointShadows::DualParaboloid;
    let err = Renderer::new(&ctx, &scene, s)
        .err()
        .expect("paraboloids refused");
    assert!(err.to_string().contains("it renders cube"), "{err}");
}

/// One grid texel for a whole frame: every sample in one list. On llvmpipe (which ends an
/// invocation's loops after 65535 iterations) the walk is cut short and the frame must be an
/// error; on adapters without that limit the frame must be exact. Never a wrong mask.
#[test]
fn long_lists_are_exact_or_an_error() {
    let ctx = common::context();
    let scene = builtin::build("plane-directional", &BuiltinOptions::default()).expect("scene");
    let mut s = settings(384, 384);
    s.irregular.grid = Some(1);
    let mut r = Renderer::new(&ctx, &scene, s).expect("renderer");
    match r.render() {
        Err(e @ RenderError::LoopLimit { .. }) => {
            eprintln!("refused as expected on this adapter: {e}");
            assert!(e.to_string().contains("loop limit"), "{e}");
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok(frame) => {
            let mut fine = Renderer::new(&ctx, &scene, settings(384, 384)).expect("renderer");
            let want = fine.render().expect("frame").visibility.expect("mask");
            assert_eq!(
                frame.visibility.expect("mask"),
                want,
                "grid 1 changed the mask"
            );
        }
    }
}
