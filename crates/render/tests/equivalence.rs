//! The proof that the fast shadow paths are right: for the same views, every technique must
//! fill the atlas with the depth `traditional` writes, texel for texel, up to a few texels on
//! triangle edges (different vertex arithmetic rounds edge coverage differently).
//!
//! Depths are compared exactly where both sides cover a texel with the same triangle; a texel
//! "differs" if its depth differs by more than `common::ATLAS_DEPTH_TOL`. On a CPU rasterizer
//! (lavapipe, llvmpipe: CI) each scene's budget of differing texels is stated beside it with its
//! reason; a hardware rasterizer rounds depths and tips edges by its own rules and is held to
//! `AtlasDiff::within_hardware_rules` instead (every surface where `traditional` has it).

mod common;

use manyshadows::gpu_scene::instances::GpuScene;
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::Scene;
use manyshadows::shadows::atlas::generator::ShadowGenerator;
use manyshadows::shadows::plan::ShadowPlan;
use manyshadows::{CullMode, GpuContext, ShadowOptions, Technique};

fn atlas(
    ctx: &GpuContext,
    scene: &Scene,
    technique: Technique,
    options: ShadowOptions,
) -> Vec<f32> {
    let plan = ShadowPlan::new(scene, 16.0 / 9.0, 4096, FitPolicy::Shrink).expect("plan");
    let gpu = GpuScene::new(ctx, scene).expect("upload");
    let mut generator = ShadowGenerator::new(ctx, scene, &gpu, plan, technique.info(), options)
        .unwrap_or_else(|e| panic!("{technique} cannot run on this adapter: {e}"));
    let timer = manyshadows::gpu::timing::GpuTimer::new(ctx);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let stats = generator.generate(ctx, &gpu, &mut encoder, &timer, None);
    ctx.queue.submit([encoder.finish()]);
    assert_eq!(stats.views_drawn as usize, generator.plan.views.len());
    generator.read_atlas(ctx).expect("read atlas")
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
    let reference = atlas(ctx, scene, Technique::TRADITIONAL, ShadowOptions::default());
    let strict = common::cpu_rasterizer(ctx);
    let covered = reference.iter().filter(|&&d| d < 1.0).count();
    assert!(
        covered > 1000,
        "{label}: the traditional atlas is nearly empty ({covered} texels)"
    );
    for &cull in CullMode::ALL {
        let options = ShadowOptions::default().with_cull(cull);
        let got = atlas(ctx, scene, technique, options);
        let d = common::atlas_diff(&reference, &got);
        eprintln!(
            "{label}: {technique} --cull {}: {d} (budget {budget} on a CPU rasterizer)",
            cull.name()
        );
        let ok = if strict {
            d.differing <= budget
        } else {
            d.within_hardware_rules()
        };
        assert!(
            ok,
            "{label}: {technique} --cull {} differs from traditional: {d} ({})",
            cull.name(),
            if strict {
                format!("budget {budget}")
            } else {
                "hardware rules".into()
            }
        );
    }
}

#[test]
fn layered_matches_traditional() {
    let ctx = common::context();
    // Spot, point (cube faces) and directional (cascades) lights over closed boxes and an
    // open floor. Measured on lavapipe and llvmpipe GL (every cull mode): cubes 2 differing
    // texels, plane-point, plane-directional and dragon 0; the budgets are those plus 2.
    let cubes = scene("cubes", Some(6), LightMix::All, 256);
    check(&ctx, "cubes", &cubes, Technique::LAYERED, 4);
    let point = scene("plane-point", None, LightMix::All, 256);
    check(&ctx, "plane-point", &point, Technique::LAYERED, 2);
    let sun = scene("plane-directional", None, LightMix::All, 512);
    check(&ctx, "plane-directional", &sun, Technique::LAYERED, 2);
    let dragon = scene("dragon", Some(4), LightMix::Spot, 256);
    // Alpha-tested cards (lattice, banners, leaves, fence): the masked casters' texels too.
    // Measured 18 (lavapipe) and 13 (llvmpipe GL) of 995,261 covered texels, every cull mode: mask edges where the texture
    // coordinate interpolates a hair differently; the budget is that plus a margin.
    let courtyard = scene("courtyard", None, LightMix::All, 256);
    check(&ctx, "courtyard", &courtyard, Technique::LAYERED, 24);
    check(&ctx, "dragon", &dragon, Technique::LAYERED, 2);
}

#[test]
fn multiview_matches_traditional_or_says_unsupported() {
    let ctx = common::context();
    if !Technique::MULTIVIEW.info().unmet(&ctx).is_empty() {
        // OpenGL (llvmpipe) has no multiview: the technique must refuse clearly, not fall back.
        let err = Technique::MULTIVIEW
            .create(&ctx)
            .err()
            .expect("multiview must refuse to start without the MULTIVIEW feature");
        let msg = err.to_string();
        eprintln!("multiview on an adapter without MULTIVIEW: {msg}");
        assert!(
            matches!(
                &err,
                manyshadows::RenderError::MissingFeature { needs, .. } if needs == "technique multiview"
            ),
            "{err:?}"
        );
        assert!(
            msg.contains("MULTIVIEW") && msg.contains("layered"),
            "unclear message: {msg}"
        );
        manyshadows_testkit::refused("MULTIVIEW", &msg);
        return;
    }
    let per_pass = manyshadows::shadows::atlas::multiview::Multiview::new(&ctx)
        .expect("multiview")
        .views_per_pass();
    // Rendering a group at the tile size from the scratch origin hits the same texels as
    // traditional's viewport at the tile's offset, and the copy is exact: the budgets are
    // layered's (a handful of edge texels per view). Lavapipe before Mesa 25 put every
    // clipped primitive of a multiview pass into view 0's layer (whole cube faces came out as
    // the union of six views, hundreds of thousands of texels), so there the technique runs
    // one view per pass (`clips_into_layer_zero`); elsewhere groups of views share a pass
    // and this test fails where a group loses its view index. Measured on lavapipe (Mesa
    // 25.0.7, six views per pass): cubes 1, the rest 0; layered's budgets.
    if !manyshadows::shadows::atlas::multiview::clips_into_layer_zero(&ctx.info) {
        assert!(
            per_pass > 1 || ctx.limits().max_multiview_view_count <= 1,
            "one view per pass on a driver without the clipper bug"
        );
    }
    eprintln!("multiview: up to {per_pass} views per pass on this adapter");
    let cubes = scene("cubes", Some(6), LightMix::All, 256);
    check(&ctx, "cubes", &cubes, Technique::MULTIVIEW, 4);
    let point = scene("plane-point", None, LightMix::All, 256);
    check(&ctx, "plane-point", &point, Technique::MULTIVIEW, 2);
    let sun = scene("plane-directional", None, LightMix::All, 512);
    check(&ctx, "plane-directional", &sun, Technique::MULTIVIEW, 2);
    let dragon = scene("dragon", Some(4), LightMix::Spot, 256);
    // Alpha-tested cards (lattice, banners, leaves, fence): the masked casters' texels too.
    // Measured 9 (lavapipe) of 995,261 covered texels, every cull mode: mask edges where the texture
    // coordinate interpolates a hair differently; the budget is that plus a margin.
    let courtyard = scene("courtyard", None, LightMix::All, 256);
    check(&ctx, "courtyard", &courtyard, Technique::MULTIVIEW, 15);
    check(&ctx, "dragon", &dragon, Technique::MULTIVIEW, 2);
}

#[test]
fn gpu_driven_matches_traditional() {
    let ctx = common::context();
    // Cluster culling drops only clusters that cannot touch a view (sphere outside the
    // frustum) or whose every triangle faces away (normal cone), and the vertex shader maps
    // into tiles as layered does. Measured on lavapipe and llvmpipe GL, every round size:
    // cubes 2, the rest 0; layered's budgets.
    let cubes = scene("cubes", Some(6), LightMix::All, 256);
    check(&ctx, "cubes", &cubes, Technique::GPU_DRIVEN, 4);
    let point = scene("plane-point", None, LightMix::All, 256);
    check(&ctx, "plane-point", &point, Technique::GPU_DRIVEN, 2);
    let sun = scene("plane-directional", None, LightMix::All, 512);
    check(&ctx, "plane-directional", &sun, Technique::GPU_DRIVEN, 2);
    let dragon = scene("dragon", Some(4), LightMix::Spot, 256);
    // Alpha-tested cards (lattice, banners, leaves, fence): the masked casters' texels too.
    // Measured 18 (lavapipe) and 13 (llvmpipe GL) of 995,261 covered texels, every cull mode: mask edges where the texture
    // coordinate interpolates a hair differently; the budget is that plus a margin.
    let courtyard = scene("courtyard", None, LightMix::All, 256);
    check(&ctx, "courtyard", &courtyard, Technique::GPU_DRIVEN, 24);
    check(&ctx, "dragon", &dragon, Technique::GPU_DRIVEN, 2);
}

#[test]
fn compute_matches_traditional() {
    let ctx = common::context();
    // The compute rasterizer reproduces the fixed-function rules (viewport transform, 8-bit
    // sub-pixel snapping, top-left fill rule, screen-space depth plane, near clipping) in
    // compute, with depth from the triangle's clip-space plane. Measured on lavapipe and
    // llvmpipe GL (every cull mode): cubes 5 and 8 differing texels, plane-point 0 and 0,
    // plane-directional 4 and 4, dragon 0 and 0 (edge texels and depths a few ULPs beyond
    // the tolerance where the hardware interpolates from corners it clipped). The budgets are
    // the larger measurement plus 2–4.
    let cubes = scene("cubes", Some(6), LightMix::All, 256);
    check(&ctx, "cubes", &cubes, Technique::COMPUTE, 12);
    let point = scene("plane-point", None, LightMix::All, 256);
    check(&ctx, "plane-point", &point, Technique::COMPUTE, 2);
    let sun = scene("plane-directional", None, LightMix::All, 512);
    check(&ctx, "plane-directional", &sun, Technique::COMPUTE, 6);
    let dragon = scene("dragon", Some(4), LightMix::Spot, 256);
    // Alpha-tested cards (lattice, banners, leaves, fence): the masked casters' texels too.
    // Measured 18 (lavapipe) and 22 (llvmpipe GL) of 995,261 covered texels, every cull mode: mask edges where the texture
    // coordinate interpolates a hair differently; the budget is that plus a margin.
    let courtyard = scene("courtyard", None, LightMix::All, 256);
    check(&ctx, "courtyard", &courtyard, Technique::COMPUTE, 30);
    check(&ctx, "dragon", &dragon, Technique::COMPUTE, 2);
}

/// Runs `technique` directly on `scene`'s views with the given draw list into `atlas`.
fn generate_into(
    ctx: &GpuContext,
    technique: &mut dyn manyshadows::shadows::technique::ShadowTechnique,
    parts: &Parts,
    options: &ShadowOptions,
    draw_list: &[u32],
) -> manyshadows::ShadowStats {
    ctx.queue
        .write_buffer(&parts.atlas.draw_list, 0, bytemuck::cast_slice(draw_list));
    let input = manyshadows::shadows::technique::ShadowInput {
        ctx,
        scene: &parts.gpu,
        views: &parts.plan.views,
        atlas: &parts.atlas,
        casters: &parts.casters,
        options,
        draw_list,
    };
    let timer = manyshadows::gpu::timing::GpuTimer::new(ctx);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let stats = technique.generate(&input, &mut encoder, &timer, None);
    ctx.queue.submit([encoder.finish()]);
    stats
}

/// What a generation needs, built without [`ShadowGenerator`] (to reach technique knobs).
struct Parts {
    plan: ShadowPlan,
    gpu: GpuScene,
    atlas: manyshadows::shadows::storage::ShadowAtlas,
    casters: manyshadows::gpu_scene::casters::CasterGeometry,
}

fn parts(ctx: &GpuContext, scene: &Scene) -> Parts {
    let plan = ShadowPlan::new(scene, 16.0 / 9.0, 4096, FitPolicy::Shrink).expect("plan");
    let gpu = GpuScene::new(ctx, scene).expect("upload");
    let atlas = manyshadows::shadows::storage::ShadowAtlas::new(ctx, &plan).expect("atlas");
    let casters =
        manyshadows::gpu_scene::casters::CasterGeometry::new(ctx, scene, &gpu, Default::default())
            .expect("casters");
    Parts {
        plan,
        gpu,
        atlas,
        casters,
    }
}

#[test]
fn gpu_driven_splits_views_and_clusters_into_rounds() {
    use manyshadows::shadows::atlas::gpu_driven::GpuDriven;
    use manyshadows::shadows::cluster_draw::plan_rounds;
    let ctx = common::context();
    // 6 lights of every kind: spot, point (6 faces) and directional (cascades) views.
    let scene = scene("cubes", Some(6), LightMix::All, 256);
    let reference = atlas(
        &ctx,
        &scene,
        Technique::TRADITIONAL,
        ShadowOptions::default(),
    );
    let p = parts(&ctx, &scene);
    let views = p.plan.views.len() as u32;
    let clusters = p.casters.clusters.len() as u64;
    let list: Vec<u32> = (0..views).collect();
    // Two views per round, then rounds that also split the clusters.
    for max in [2 * clusters, clusters / 3 + 1] {
        let rounds = plan_rounds(
            views,
            clusters as u32,
            (0, p.casters.first_masked_cluster),
            p.casters.vertices,
            max,
        );
        assert!(
            rounds.len() > 1,
            "{views} views, {clusters} clusters: one round only"
        );
        for &cull in CullMode::ALL {
            let mut technique = GpuDriven::new(&ctx)
                .expect("gpu-driven")
                .with_max_round_commands(max);
            let options = ShadowOptions::default().with_cull(cull);
            let stats = generate_into(&ctx, &mut technique, &p, &options, &list);
            assert_eq!(stats.passes as usize, 2 * rounds.len());
            assert_eq!(stats.draws, views as u64 * clusters);
            let got = manyshadows::shadows::image::read_depth(&ctx, &p.atlas).expect("read");
            assert_eq!(ctx.take_uncaptured(), None, "GPU errors");
            let d = common::atlas_diff(&reference, &got);
            eprintln!(
                "cubes: gpu-driven in {} rounds of <= {max} commands, --cull {}: {d}",
                rounds.len(),
                cull.name()
            );
            // Measured: 2 (as the single-round run), every round size and cull mode.
            let ok = if common::cpu_rasterizer(&ctx) {
                d.differing <= 4
            } else {
                d.within_hardware_rules()
            };
            assert!(ok, "{d}");
        }
    }
}

/// With a partial draw list, listed tiles are cleared and redrawn and every other tile keeps
/// its depth: draw everything, then redraw the odd views with rasterization discarded, which
/// must leave exactly the odd tiles cleared.
#[test]
fn partial_draw_lists_clear_only_listed_tiles() {
    let ctx = common::context();
    let scene = scene("cubes", Some(6), LightMix::All, 256);
    let p = parts(&ctx, &scene);
    let views = p.plan.views.len() as u32;
    let all: Vec<u32> = (0..views).collect();
    let odd: Vec<u32> = (1..views).step_by(2).collect();
    let mut techniques = vec![Technique::GPU_DRIVEN];
    match Technique::MULTIVIEW.create(&ctx) {
        Ok(_) => techniques.push(Technique::MULTIVIEW),
        Err(e) => common::check_refusal(&ctx, Technique::MULTIVIEW, &e),
    }
    for technique in techniques {
        let mut t = technique.create(&ctx).expect("technique");
        generate_into(&ctx, t.as_mut(), &p, &ShadowOptions::default(), &all);
        let full = manyshadows::shadows::image::read_depth(&ctx, &p.atlas).expect("read");
        let discard = ShadowOptions::default().with_discard_raster(true);
        generate_into(&ctx, t.as_mut(), &p, &discard, &odd);
        let partial = manyshadows::shadows::image::read_depth(&ctx, &p.atlas).expect("read");
        let size = p.atlas.size as usize;
        let mut odd_covered = 0;
        for (v, tile) in p.atlas.tiles.iter().enumerate() {
            for y in tile.y as usize..(tile.y + tile.size) as usize {
                for x in tile.x as usize..(tile.x + tile.size) as usize {
                    let i = y * size + x;
                    if v % 2 == 1 {
                        assert_eq!(partial[i], 1.0, "{technique}: view {v} not cleared");
                    } else {
                        assert_eq!(partial[i], full[i], "{technique}: view {v} changed");
                    }
                    odd_covered += usize::from(v % 2 == 1 && full[i] < 1.0);
                }
            }
        }
        assert!(
            odd_covered > 1000,
            "the odd tiles were nearly empty: the test proves nothing"
        );
        eprintln!(
            "{technique}: {} of {views} tiles cleared and redrawn, others kept",
            odd.len()
        );
    }
}

/// The looser rules a hardware rasterizer is held to still see what a broken technique does:
/// one tile left empty, or every tile's contents shifted by a texel (a viewport transform off by
/// one), fails them.
#[test]
fn hardware_rules_see_a_lost_or_shifted_tile() {
    let ctx = common::context();
    let cubes = scene("cubes", Some(6), LightMix::All, 256);
    let reference = atlas(
        &ctx,
        &cubes,
        Technique::TRADITIONAL,
        ShadowOptions::default(),
    );
    let plan = ShadowPlan::new(&cubes, 16.0 / 9.0, 4096, FitPolicy::Shrink).expect("plan");
    let side = plan.layout.size as usize;
    assert_eq!(side * side, reference.len());
    let same = common::atlas_diff(&reference, &reference);
    assert!(
        same.within_hardware_rules() && same.differing == 0,
        "{same}"
    );
    // A tile's contents moved `dx` texels left (what enters from outside is empty).
    let shift = |atlas: &mut Vec<f32>, t: &manyshadows::scene::atlas::Tile, dx: usize| {
        let (x0, y0, n) = (t.x as usize, t.y as usize, t.size as usize);
        for y in y0..y0 + n {
            for x in x0..x0 + n {
                atlas[y * side + x] = if x + dx < x0 + n {
                    reference[y * side + x + dx]
                } else {
                    1.0
                };
            }
        }
    };
    let first = plan.layout.tiles[0];
    let mut lost = reference.clone();
    shift(&mut lost, &first, first.size as usize);
    let d = common::atlas_diff(&reference, &lost);
    eprintln!("the first tile lost: {d}");
    assert!(!d.within_hardware_rules(), "a lost tile passes: {d}");
    for dx in [1, 2, 4] {
        let mut shifted = reference.clone();
        for t in &plan.layout.tiles {
            shift(&mut shifted, t, dx);
        }
        let d = common::atlas_diff(&reference, &shifted);
        eprintln!("every tile shifted by {dx}: {d}");
        assert!(
            !d.within_hardware_rules(),
            "tiles shifted by {dx} texel pass: {d}"
        );
    }
}
