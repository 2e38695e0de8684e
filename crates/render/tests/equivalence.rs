//! The proof that the fast shadow paths are right: for the same views, every technique must
//! fill the atlas with the depth `traditional` writes, texel for texel, up to a few texels on
//! triangle edges (different vertex arithmetic rounds edge coverage differently).
//!
//! Depths are compared exactly where both sides cover a texel with the same triangle; a texel
//! "differs" if its depth differs by more than [`DEPTH_TOL`]. Each scene's budget of differing
//! texels is stated beside it with its reason.

mod common;

use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::Scene;
use manyshadows::{
    CullMode, GpuContext, GpuScene, ShadowGenerator, ShadowOptions, ShadowPlan, Technique,
};

/// Depth difference that counts as a different texel: a few ULPs of depth near 1 (the model
/// transform runs in a compute pass instead of the vertex shader, so fused multiply-adds may
/// round differently).
const DEPTH_TOL: f32 = 2e-6;

struct Diff {
    differing: usize,
    covered: usize,
    max_depth_diff: f32,
}

fn atlas(ctx: &GpuContext, scene: &Scene, technique: Technique, options: ShadowOptions) -> Vec<f32> {
    let plan = ShadowPlan::new(scene, 16.0 / 9.0, 4096, FitPolicy::Shrink).expect("plan");
    let gpu = GpuScene::new(ctx, scene).expect("upload");
    let mut generator =
        ShadowGenerator::new(ctx, scene, &gpu, plan, technique, options).unwrap_or_else(|e| {
            panic!("{technique} cannot run on this adapter: {e}")
        });
    let timer = manyshadows::timing::GpuTimer::new(ctx);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let stats = generator.generate(ctx, &gpu, &mut encoder, &timer, None);
    ctx.queue.submit([encoder.finish()]);
    assert_eq!(stats.views_drawn as usize, generator.plan.views.len());
    generator.read_atlas(ctx).expect("read atlas")
}

fn diff(a: &[f32], b: &[f32]) -> Diff {
    assert_eq!(a.len(), b.len());
    let mut d = Diff {
        differing: 0,
        covered: 0,
        max_depth_diff: 0.0,
    };
    for (&x, &y) in a.iter().zip(b) {
        if x < 1.0 || y < 1.0 {
            d.covered += 1;
        }
        let e = (x - y).abs();
        if e > DEPTH_TOL {
            d.differing += 1;
        } else {
            d.max_depth_diff = d.max_depth_diff.max(e);
        }
    }
    d
}

fn scene(name: &str, lights: Option<usize>, mix: LightMix, res: u32) -> Scene {
    builtin::build(
        name,
        &BuiltinOptions {
            lights,
            seed: 7,
            mix,
            shadow_resolution: Some(res),
            ..Default::default()
        },
    )
    .expect("builtin scene")
}

/// Checks `technique` with every cull mode against `traditional` on `scene`, allowing
/// `budget` differing texels.
fn check(ctx: &GpuContext, label: &str, scene: &Scene, technique: Technique, budget: usize) {
    let reference = atlas(ctx, scene, Technique::Traditional, ShadowOptions::default());
    let covered = reference.iter().filter(|&&d| d < 1.0).count();
    assert!(covered > 1000, "{label}: the traditional atlas is nearly empty ({covered} texels)");
    for &cull in CullMode::ALL {
        let options = ShadowOptions {
            cull,
            ..Default::default()
        };
        let got = atlas(ctx, scene, technique, options);
        let d = diff(&reference, &got);
        eprintln!(
            "{label}: {technique} --cull {}: {} of {} covered texels differ (budget {budget}), \
             max depth difference elsewhere {:e}",
            cull.name(),
            d.differing,
            d.covered,
            d.max_depth_diff
        );
        assert!(
            d.differing <= budget,
            "{label}: {technique} --cull {} differs from traditional in {} texels (budget {budget})",
            cull.name(),
            d.differing
        );
    }
}

#[test]
fn layered_matches_traditional() {
    let ctx = common::context();
    // Spot, point (cube faces) and directional (cascades) lights over closed boxes and an
    // open floor: the budget is a handful of edge texels per view.
    let cubes = scene("cubes", Some(6), LightMix::All, 256);
    check(&ctx, "cubes", &cubes, Technique::Layered, 64);
    let point = scene("plane-point", None, LightMix::All, 256);
    check(&ctx, "plane-point", &point, Technique::Layered, 16);
    let sun = scene("plane-directional", None, LightMix::All, 512);
    check(&ctx, "plane-directional", &sun, Technique::Layered, 16);
    let dragon = scene("dragon", Some(4), LightMix::Spot, 256);
    check(&ctx, "dragon", &dragon, Technique::Layered, 64);
}
