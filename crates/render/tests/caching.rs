//! Caching across frames: after one object moves, a cached generation redraws only the views
//! that see the object's old or new place, and the atlas it leaves is the atlas a full
//! generation of the moved scene writes.

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::Scene;
use manyshadows::{
    GpuContext, GpuScene, RenderError, ShadowGenerator, ShadowOptions, ShadowPlan, Technique,
};

fn generate(ctx: &GpuContext, g: &mut ShadowGenerator, gpu: &GpuScene) -> u32 {
    let timer = manyshadows::timing::GpuTimer::new(ctx);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let stats = g.generate(ctx, gpu, &mut encoder, &timer, None);
    ctx.queue.submit([encoder.finish()]);
    stats.views_drawn
}

fn generator(
    ctx: &GpuContext,
    scene: &Scene,
    gpu: &GpuScene,
    t: Technique,
) -> Result<ShadowGenerator, RenderError> {
    let plan = ShadowPlan::new(scene, 16.0 / 9.0, 4096, FitPolicy::Shrink).expect("plan");
    ShadowGenerator::new(ctx, scene, gpu, plan, t, ShadowOptions::default())
}

#[test]
fn cached_generation_equals_a_full_one_after_a_move() {
    let ctx = common::context();
    let scene = builtin::build(
        "cubes",
        &BuiltinOptions {
            lights: Some(8),
            seed: 3,
            mix: LightMix::All,
            shadow_resolution: Some(256),
            ..Default::default()
        },
    )
    .expect("scene");
    // The smallest shadow caster moves 0.4 m sideways.
    let (k, _) = scene
        .instances
        .iter()
        .enumerate()
        .filter(|(_, i)| i.casts_shadows)
        .map(|(k, i)| {
            let (lo, hi) = scene.meshes[i.mesh].bounds().expect("bounds");
            (k, (hi - lo).length())
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("a caster");
    let moved = Mat4::from_translation(Vec3::new(0.4, 0.0, 0.0)) * scene.instances[k].transform;
    let mut moved_scene = scene.clone();
    moved_scene.instances[k].transform = moved;

    let mut ran = Vec::new();
    for &t in Technique::ALL {
        let mut gpu = GpuScene::new(&ctx, &scene).expect("upload");
        let mut cached = match generator(&ctx, &scene, &gpu, t) {
            Ok(g) => g,
            Err(RenderError::Unsupported(why)) => {
                eprintln!("{t}: not on this adapter ({why})");
                continue;
            }
            Err(e) => panic!("{t}: {e}"),
        };
        cached.set_caching(true);
        let views = cached.plan.views.len() as u32;
        assert_eq!(
            generate(&ctx, &mut cached, &gpu),
            views,
            "{t}: first frame draws all"
        );
        assert_eq!(
            generate(&ctx, &mut cached, &gpu),
            0,
            "{t}: nothing moved, nothing drawn"
        );
        let old = gpu.draws[k].sphere;
        gpu.set_instance_transform(&ctx.queue, k, moved);
        cached.note_moved(old, gpu.draws[k].sphere);
        let redrawn = generate(&ctx, &mut cached, &gpu);
        let got = cached.read_atlas(&ctx).expect("read");

        let fresh_gpu = GpuScene::new(&ctx, &moved_scene).expect("upload");
        let mut fresh = generator(&ctx, &moved_scene, &fresh_gpu, t).expect("fresh");
        generate(&ctx, &mut fresh, &fresh_gpu);
        let want = fresh.read_atlas(&ctx).expect("read");
        let differing = got
            .iter()
            .zip(&want)
            .filter(|(a, b)| (**a - **b).abs() > 2e-6)
            .count();
        eprintln!(
            "{t}: {redrawn} of {views} views redrawn after the move, {differing} texels differ"
        );
        assert!(
            redrawn > 0 && redrawn < views,
            "{t}: {redrawn} of {views} views redrawn"
        );
        assert_eq!(
            differing, 0,
            "{t}: the cached atlas differs from a full generation"
        );
        ran.push(t);
    }
    assert!(ran.contains(&Technique::Traditional) && ran.contains(&Technique::Layered));
}
