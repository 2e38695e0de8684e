//! Back-face culling is exact only for closed meshes. These tests show (1) that culling
//! really removes triangles — forcing it on an open quad whose back faces the light removes
//! the quad's shadow from the atlas — and (2) that the default closure check keeps such
//! open meshes, so the atlas stays identical to `traditional`'s.

mod common;

use glam::{Mat4, Vec3};
use manyshadows::gpu_scene::instances::GpuScene;
use manyshadows::scene::atlas::FitPolicy;
use manyshadows::scene::{
    primitives, Attenuation, Camera, Instance, Light, LightKind, Material, Scene,
};
use manyshadows::shadows::atlas::generator::ShadowGenerator;
use manyshadows::shadows::plan::ShadowPlan;
use manyshadows::CasterOptions;
use manyshadows::{CullMode, GpuContext, ShadowOptions, Technique};

/// A floor, an open quad 1 m above it turned upside down (its front faces the floor), and a
/// spot light above both looking down at the quad's back.
fn scene() -> Scene {
    let floor = primitives::plane(8.0, 8.0, 1);
    let quad = primitives::plane(1.0, 1.0, 1);
    let light = Light {
        kind: LightKind::Spot {
            position: Vec3::new(0.0, 3.0, 0.0),
            direction: Vec3::NEG_Y,
            cutoff_deg: 45.0,
            range: 10.0,
        },
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
        attenuation: Attenuation::for_range(10.0),
        casts_shadows: true,
        shadow_resolution: 256,
        size: 0.0,
    };
    Scene {
        textures: Vec::new(),
        name: "upside-down quad".into(),
        meshes: vec![floor, quad],
        materials: vec![Material::default()],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance {
                mesh: 1,
                material: 0,
                transform: Mat4::from_translation(Vec3::Y)
                    * Mat4::from_rotation_x(std::f32::consts::PI),
                casts_shadows: true,
            },
        ],
        lights: vec![light],
        camera: Camera::look_at(Vec3::new(0.0, 4.0, 6.0), Vec3::ZERO),
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}

fn atlas(
    ctx: &GpuContext,
    scene: &Scene,
    technique: Technique,
    options: ShadowOptions,
) -> Vec<f32> {
    let plan = ShadowPlan::new(scene, 1.0, 4096, FitPolicy::Strict).expect("plan");
    let gpu = GpuScene::new(ctx, scene).expect("upload");
    let mut g = ShadowGenerator::new(ctx, scene, &gpu, plan, technique.info(), options)
        .unwrap_or_else(|e| panic!("{technique}: {e}"));
    let timer = manyshadows::gpu::timing::GpuTimer::new(ctx);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    g.generate(ctx, &gpu, &mut encoder, &timer, None);
    ctx.queue.submit([encoder.finish()]);
    g.read_atlas(ctx).expect("read atlas")
}

fn differing(a: &[f32], b: &[f32]) -> usize {
    a.iter()
        .zip(b)
        .filter(|(x, y)| (**x - **y).abs() > 2e-6)
        .count()
}

#[test]
fn backface_culling_removes_back_faces_only_where_that_is_exact() {
    let ctx = common::context();
    let scene = scene();
    let reference = atlas(
        &ctx,
        &scene,
        Technique::TRADITIONAL,
        ShadowOptions::default(),
    );
    // The quad covers a square of roughly (1 m / (2·2 m·tan 45°))² of the 256² map: ~4000
    // texels nearer than the floor.
    let safe = ShadowOptions::default().with_cull(CullMode::All);
    let forced = ShadowOptions::default()
        .with_cull(CullMode::Backface)
        .with_casters(CasterOptions::default().with_assume_closed(true));
    let kept = differing(&reference, &atlas(&ctx, &scene, Technique::LAYERED, safe));
    let culled = differing(&reference, &atlas(&ctx, &scene, Technique::LAYERED, forced));
    eprintln!("open quad kept: {kept} texels differ; culling forced: {culled} texels differ");
    assert!(
        kept <= 4,
        "the default check must keep open meshes ({kept} texels differ)"
    );
    assert!(
        culled > 2000,
        "forced back-face culling must drop the upside-down quad ({culled} texels differ)"
    );
}

/// A double-sided material is never back-face culled, not even when seed 000's "every mesh
/// is closed" is forced: the same upside-down quad, its material marked double-sided, keeps
/// its shadow in every single-pass technique (the test above shows the same forcing drops it
/// when the material is single-sided).
#[test]
fn double_sided_casters_keep_their_shadow_under_forced_culling() {
    let ctx = common::context();
    let mut scene = scene();
    scene.materials.push(Material {
        double_sided: true,
        ..Material::default()
    });
    scene.instances[1].material = 1;
    let reference = atlas(
        &ctx,
        &scene,
        Technique::TRADITIONAL,
        ShadowOptions::default(),
    );
    let forced = ShadowOptions::default()
        .with_cull(CullMode::All)
        .with_casters(CasterOptions::default().with_assume_closed(true));
    for technique in [
        Technique::LAYERED,
        Technique::GPU_DRIVEN,
        Technique::COMPUTE,
    ] {
        let d = differing(&reference, &atlas(&ctx, &scene, technique, forced));
        eprintln!("double-sided quad, culling forced, {technique}: {d} texels differ");
        assert!(
            d <= 4,
            "{technique} culled a double-sided caster ({d} texels differ)"
        );
    }
}
