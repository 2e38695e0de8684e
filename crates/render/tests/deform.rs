//! Skinned and morphed meshes bent on the GPU (gpu_scene/deform.rs) against the same meshes
//! bent on the CPU (`Deform::Cpu`: every vertex bent and uploaded, the bounds the bent
//! vertices' own): the same frames up to rounding for every technique, shadows included (the
//! ray-traced shadows' structures built from the bent vertices where the adapter traces rays),
//! no fewer views redrawn, and histories that follow the bent surfaces alike.
//!
//! The scene: the built-in `walker` (one figure skinned to eight joints, walking), given a
//! morph target as well (the figure swells 6 cm along its normals, its normals tipped up,
//! weighted 0 → 1 → 0 over its clip), so that one mesh is both morphed and skinned.

mod common;

use glam::Vec3;
use manyshadows::scene::animation::{Interpolation, Morph, Playing, WeightChannel};
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::light_size::LightSizes;
use manyshadows::scene::Scene;
use manyshadows::{Deform, RayOptions, RenderSettings, Renderer, Technique};

/// The walker with its figure also morphed.
fn swelling_walker(lights: usize) -> Scene {
    let opts = BuiltinOptions {
        lights: Some(lights),
        light_sizes: LightSizes::HARD,
        ..BuiltinOptions::default()
    };
    let mut scene = builtin::build("walker", &opts).expect("walker");
    let anim = &mut scene.animations;
    let skin = anim.skins[0].clone();
    let node = anim.skins[0].joints[0];
    anim.morphs.push(Morph {
        mesh: skin.mesh,
        node,
        base_positions: skin.bind_positions.clone(),
        base_normals: skin.bind_normals.clone(),
        position_deltas: vec![skin.bind_normals.iter().map(|n| *n * 0.06).collect()],
        normal_deltas: vec![vec![Vec3::new(0.0, 0.6, 0.0); skin.bind_normals.len()]],
        default_weights: vec![0.0],
    });
    anim.clips[0].weights.push(WeightChannel {
        node,
        interpolation: Interpolation::Linear,
        times: vec![0.0, 1.0, 2.0],
        targets: 1,
        values: vec![0.0, 1.0, 0.0],
    });
    scene
}

/// RMSE of two frames' channels (of 255) and the share of visibility bits that differ.
fn apart(a: &manyshadows::Frame, b: &manyshadows::Frame) -> (f64, f64) {
    let (_, _, bits) = common::frame_differences(a, b);
    let total = a.visibility.as_ref().map_or(1, |v| v.words.len() * 32);
    (common::rmse(a, b), bits as f64 / total as f64)
}

/// Every technique draws the figure bent on the GPU as it draws it bent on the CPU, its
/// shadows included, at three times of the clip; both differ from the figure at rest.
#[test]
fn the_gpu_bends_skinned_and_morphed_meshes_as_the_cpu_does() {
    let ctx = common::context();
    let scene = swelling_walker(16);
    let mut techniques = vec![
        Technique::TRADITIONAL,
        Technique::GPU_DRIVEN,
        Technique::VIRTUAL,
    ];
    let unmet = Technique::RAYTRACED.info().unmet(&ctx);
    match unmet.first().map(|n| n.name()) {
        None => techniques.push(Technique::RAYTRACED),
        Some(need) => assert!(
            !manyshadows_testkit::must_offer(&need),
            "no {need}, which the test command says this backend must offer"
        ),
    }
    for t in techniques {
        let base = RenderSettings::new(192, 108)
            .with_technique(t)
            .with_visibility(true);
        let mut gpu = Renderer::new(&ctx, &scene, base.clone()).expect("renderer");
        let mut cpu =
            Renderer::new(&ctx, &scene, base.clone().with_deform(Deform::Cpu)).expect("renderer");
        let mut rest = Renderer::new(&ctx, &scene, base).expect("renderer");
        let still = rest.render().expect("frame");
        for time in [0.35, 0.9, 1.55] {
            gpu.set_time(Playing::One(0), time).expect("pose");
            cpu.set_time(Playing::One(0), time).expect("pose");
            let (g, c) = (gpu.render().expect("frame"), cpu.render().expect("frame"));
            let (rmse, bits) = apart(&g, &c);
            let (moved, moved_bits) = apart(&g, &still);
            eprintln!(
                "{t} at {time} s: GPU against CPU bending RMSE {rmse:.4}, visibility bits \
                 {:.4} %; against rest {moved:.2}, {:.2} %",
                100.0 * bits,
                100.0 * moved_bits
            );
            if rmse > 0.05 || bits > 2e-4 {
                common::differing_pixels(&g, &c, &format!("deform_{t}_{time}"), ["gpu", "cpu"]);
            }
            assert!(
                rmse <= 0.05 && bits <= 2e-4,
                "{t} at {time} s: bent on the GPU, RMSE {rmse} and {bits} of the visibility \
                 bits from the CPU's bending"
            );
            assert!(
                moved > 2.0 && moved_bits > 1e-3,
                "{t} at {time} s: the posed figure looks as at rest ({moved}, {moved_bits})"
            );
        }
    }
}

/// Bounds drawn from the joints are conservative: the crowd bent on the GPU, its kept atlas
/// views redrawn only where its joints' bounds reach, shows the shadows of a renderer made
/// afresh from the crowd bent on the CPU (every view drawn), while redrawing fewer views than
/// there are; the same for virtual maps' pages.
#[test]
fn the_crowd_bent_on_the_gpu_redraws_what_its_joints_reach() {
    let ctx = common::context();
    let scene = builtin::build(
        "crowd",
        &BuiltinOptions {
            lights: Some(256),
            mix: LightMix::All,
            light_sizes: LightSizes::HARD,
            ..BuiltinOptions::default()
        },
    )
    .expect("crowd");
    for t in [Technique::TRADITIONAL, Technique::VIRTUAL] {
        let settings = RenderSettings::new(160, 90)
            .with_technique(t)
            .with_visibility(true);
        let mut gpu = Renderer::new(&ctx, &scene, settings.clone()).expect("renderer");
        gpu.render().expect("frame");
        let still = gpu.render().expect("frame");
        assert_eq!(still.shadow_stats.views_drawn, 0, "{t}: nothing moved");
        for time in [0.25, 0.5] {
            gpu.set_time(Playing::One(0), time).expect("pose");
            let g = gpu.render().expect("frame");
            let mut posed = scene.clone();
            posed.set_time(Playing::One(0), time);
            let fresh = Renderer::new(&ctx, &posed, settings.clone())
                .expect("renderer")
                .render()
                .expect("frame");
            let (rmse, bits) = apart(&g, &fresh);
            let (drawn, of) = match (&g.virtual_maps, &fresh.virtual_maps) {
                (Some(v), Some(f)) => (v.drawn, f.drawn),
                _ => (g.shadow_stats.views_drawn, gpu.plan().views.len() as u32),
            };
            eprintln!(
                "{t}, crowd at {time} s: against a fresh renderer RMSE {rmse:.4}, {:.4} % of the \
                 visibility bits; drawn {drawn} (a fresh frame draws {of})",
                100.0 * bits
            );
            assert!(
                rmse <= 0.05 && bits <= 2e-4,
                "{t} at {time} s: what the cached frame kept is stale: RMSE {rmse}, {bits}"
            );
            assert!(drawn > 0 && drawn < of, "{t}: {drawn} drawn of {of}");
        }
    }
}

/// The denoised and reused frames follow the figure bent on the GPU as they follow it bent
/// on the CPU: the last frame's positions are copied before each bend (with the moved-caster
/// cut off, whose spheres differ: the joints' against runs of vertices).
#[test]
fn histories_follow_meshes_bent_on_the_gpu() {
    let ctx = common::context();
    let scene = swelling_walker(64);
    let rays = RayOptions::default()
        .with_light_samples(1)
        .with_reuse(true)
        .with_denoise(true)
        .with_moved_shadows(false);
    let base = RenderSettings::new(160, 90).with_rays(rays);
    let mut gpu = common::sampler(&ctx, &scene, base.clone());
    let mut cpu = common::sampler(&ctx, &scene, base.with_deform(Deform::Cpu));
    let mut worst = 0.0f64;
    for f in 1..=6 {
        let time = f as f32 / 15.0;
        gpu.set_time(Playing::One(0), time).expect("pose");
        cpu.set_time(Playing::One(0), time).expect("pose");
        let (g, c) = (gpu.render().expect("frame"), cpu.render().expect("frame"));
        worst = worst.max(common::rmse(&g, &c));
    }
    eprintln!("denoised and reused, GPU against CPU bending: worst RMSE {worst:.4}");
    assert!(worst <= 0.1, "the histories differ: RMSE {worst}");
}
