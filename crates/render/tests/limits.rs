//! The renderer on a small device: every technique runs on exactly the limits
//! `context::required_limits()` promises (WebGPU's defaults with 2048² textures and 4 MiB
//! buffers), gives the same image there as on the full adapter, and a scene or frame past a
//! limit is a clear error (never a GPU validation error), on whichever backend `WGPU_BACKEND`
//! picks (CI: Vulkan and OpenGL).

mod common;

use glam::{Mat4, Vec3};
use manyshadows::gpu::context::{required_limits, webgpu_default_limits};
use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::scene::{Instance, Material, Mesh, Scene};
use manyshadows::wgpu;
use manyshadows::VirtualOptions;
use manyshadows::{AdapterRequest, GpuContext, RenderError, RenderSettings, Renderer, Technique};

fn context_with(limits: wgpu::Limits) -> Result<GpuContext, RenderError> {
    GpuContext::new(&AdapterRequest::default().with_limits(Some(limits)))
}

fn small_device() -> GpuContext {
    context_with(required_limits()).expect("the adapter offers the renderer's minimum limits")
}

fn settings(technique: Technique) -> RenderSettings {
    // The same atlas and pool on both devices, so the plans are the same.
    RenderSettings::default()
        .with_width(96)
        .with_height(64)
        .with_technique(technique)
        .with_visibility(true)
        .with_max_atlas_size(Some(2048))
        .with_virtual_maps(VirtualOptions::default().with_pool_bytes(2048 * 2048 * 4))
}

/// Every technique renders on the minimum device, and its image and visibility equal the full
/// adapter's texel for texel (the limits change capacities, never results). Multiview, which
/// needs more than WebGPU offers, is refused with an error that says so.
#[test]
fn every_technique_renders_on_the_minimum_limits_as_on_the_full_adapter() {
    let _own = common::own_device_lock();
    let full = common::context();
    let small = small_device();
    assert_eq!(small.limits().max_storage_buffers_per_shader_stage, 8);
    let scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    for t in Technique::all() {
        let on_small = Renderer::new(&small, &scene, settings(t)).and_then(|mut r| r.render());
        // A technique that needs more than core WebGPU (multiview: views per pass; raytraced:
        // ray queries and acceleration-structure limits, all 0 in WebGPU's defaults) is
        // refused by name there, never half run.
        if !t.info().needs.is_empty() {
            if let Err(err) = &on_small {
                assert!(
                    matches!(
                        err,
                        RenderError::MissingFeature { .. } | RenderError::LimitsTooSmall { .. }
                    ),
                    "{t}: {err}"
                );
                eprintln!("{t} on the minimum limits: refused by name: {err}");
                continue;
            }
        }
        if let Some(need) = t.info().unmet(&full).first() {
            manyshadows_testkit::refused(&need.name(), &format!("{t} on the full adapter"));
            continue;
        }
        let on_small = on_small.unwrap_or_else(|e| panic!("{t:?} on the minimum limits: {e}"));
        let on_full = Renderer::new(&full, &scene, settings(t))
            .and_then(|mut r| r.render())
            .unwrap_or_else(|e| panic!("{t:?} on the full adapter: {e}"));
        assert!(
            on_small.rgba.iter().any(|&c| c > 40),
            "{t:?}: black frame on the minimum limits"
        );
        let (vs, vf) = (on_small.visibility.unwrap(), on_full.visibility.unwrap());
        let w = vs.words_per_pixel as usize;
        let differing = vs
            .words
            .chunks(w)
            .zip(vf.words.chunks(w))
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differing, 0,
            "{t:?}: visibility differs in {differing} pixels"
        );
        assert!(on_small.rgba == on_full.rgba, "{t:?}: lit images differ");
    }
}

#[test]
fn a_device_below_the_minimum_is_refused_naming_the_limit() {
    let _own = common::own_device_lock();
    let err = context_with(wgpu::Limits {
        max_storage_buffers_per_shader_stage: 4,
        ..required_limits()
    })
    .expect_err("4 storage buffers per stage is below the minimum");
    assert!(
        matches!(&err, RenderError::LimitsTooSmall { shortfalls, .. } if shortfalls.len() == 1),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("max_storage_buffers_per_shader_stage") && msg.contains("needs 8"),
        "{msg}"
    );
}

#[test]
fn limits_beyond_the_adapter_are_refused_naming_the_limit() {
    let _own = common::own_device_lock();
    let have = common::context().adapter.limits();
    let err = context_with(wgpu::Limits {
        max_texture_dimension_2d: have.max_texture_dimension_2d + 1,
        ..have
    })
    .expect_err("a texture limit above the adapter's");
    assert!(
        matches!(err, RenderError::LimitsUnavailable { .. }),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("max_texture_dimension_2d"),
        "{err}"
    );
    // WebGPU's defaults are within every adapter CI uses.
    context_with(webgpu_default_limits()).expect("WebGPU default limits");
}

/// A flat grid of `n`×`n` quads: (n+1)² vertices, 2n² triangles.
fn grid_scene(n: u32) -> Scene {
    let mut mesh = Mesh {
        name: "grid".into(),
        ..Default::default()
    };
    for z in 0..=n {
        for x in 0..=n {
            mesh.positions.push(Vec3::new(
                x as f32 / n as f32 * 4.0 - 2.0,
                0.0,
                z as f32 / n as f32 * 4.0 - 2.0,
            ));
        }
    }
    for z in 0..n {
        for x in 0..n {
            let i = z * (n + 1) + x;
            mesh.indices
                .extend([i, i + n + 1, i + 1, i + 1, i + n + 1, i + n + 2]);
        }
    }
    mesh.compute_normals();
    let mut scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    scene.meshes.push(mesh);
    scene.materials.push(Material::default());
    scene.instances.push(Instance::caster(
        scene.meshes.len() - 1,
        scene.materials.len() - 1,
        Mat4::from_translation(Vec3::new(0.0, 2.0, 0.0)),
    ));
    scene
}

/// Casters beyond one storage binding (16 bytes per caster vertex: 300,000 vertices need
/// 4.8 MB of a 4 MiB binding, on a device whose buffers may be bigger than one binding) are
/// refused before anything is uploaded, naming the buffer and the limit, for every technique;
/// on the minimum device (4 MiB buffers) the 7.2 MB index buffer is refused first; a smaller
/// grid renders.
#[test]
fn casters_beyond_one_storage_binding_are_a_clear_error() {
    let _own = common::own_device_lock();
    let big_buffers = context_with(wgpu::Limits {
        max_buffer_size: 64 << 20,
        ..required_limits()
    })
    .expect("64 MiB buffers");
    let small = small_device();
    let scene = grid_scene(547); // 548² = 300,304 vertices, 598,418 triangles
    for t in Technique::all() {
        // Techniques beyond core WebGPU are refused on these devices before any buffer is
        // sized (the test above checks that refusal).
        if !t.info().needs.is_empty() && !t.info().unmet(&big_buffers).is_empty() {
            continue;
        }
        if t == Technique::MULTIVIEW {
            continue;
        }
        for (ctx, needle) in [
            (&big_buffers, "caster world-position buffer"),
            (&small, "indices buffer"),
        ] {
            let err = Renderer::new(ctx, &scene, settings(t))
                .and_then(|mut r| r.render())
                .err()
                .unwrap_or_else(|| panic!("{t:?}: 300k caster vertices on a 4 MiB binding"));
            assert!(
                matches!(err, RenderError::TooLarge { .. }),
                "{t:?}: {err:?}"
            );
            let msg = err.to_string();
            assert!(
                msg.contains(needle) && msg.contains("over its max_"),
                "{t:?}: {msg}"
            );
            if t == Technique::TRADITIONAL {
                eprintln!("{msg}");
            }
        }
    }
    // A grid under the limits renders on the same devices.
    for ctx in [&big_buffers, &small] {
        Renderer::new(ctx, &grid_scene(300), settings(Technique::TRADITIONAL))
            .and_then(|mut r| r.render())
            .expect("90,601 vertices fit a 4 MiB binding");
    }
}

/// Frames and maps at the texture limit: a frame wider than 2048 is refused; one exactly
/// 2048 wide renders; an atlas asked bigger than the device allows is capped to it.
#[test]
fn frames_and_atlases_at_the_texture_limit() {
    let _own = common::own_device_lock();
    let small = small_device();
    let scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    let wide = |width: u32, height: u32| {
        RenderSettings::default()
            .with_width(width)
            .with_height(height)
            .with_max_atlas_size(Some(8192))
    };
    let Err(err) = Renderer::new(&small, &scene, wide(2049, 8)) else {
        panic!("2049 pixels wide on a 2048 device");
    };
    assert!(
        matches!(err, RenderError::ResolutionTooLarge { .. }),
        "{err:?}"
    );
    let mut r = Renderer::new(&small, &scene, wide(2048, 8)).expect("2048 wide");
    assert!(
        r.plan().layout.size <= 2048,
        "atlas {}",
        r.plan().layout.size
    );
    r.render().expect("a 2048×8 frame");
}

/// Thousands of lights on the minimum device: they render (maps shrink or go, counted) or the
/// frame is refused with a clear error; never a GPU error.
#[test]
fn thousands_of_lights_on_the_minimum_limits() {
    let _own = common::own_device_lock();
    let small = small_device();
    let scene = builtin::build(
        "atrium",
        &BuiltinOptions {
            lights: Some(4096),
            ..Default::default()
        },
    )
    .unwrap();
    for t in [Technique::TRADITIONAL, Technique::VIRTUAL] {
        match Renderer::new(&small, &scene, settings(t)).and_then(|mut r| r.render()) {
            Ok(frame) => {
                eprintln!("{t:?}: 4096 lights rendered");
                assert_eq!(frame.visibility.unwrap().lights, 4096)
            }
            Err(e) => {
                eprintln!("{t:?}: 4096 lights refused: {e}");
                assert!(
                    !matches!(e, RenderError::Gpu { .. }),
                    "{t:?}: 4096 lights gave a GPU error: {e}"
                )
            }
        }
    }
}

/// What the test command says this backend must offer (`MANYSHADOWS_EXPECT`, set by `cargo
/// xtask test`: on Vulkan with Mesa 25's lavapipe ray queries, multiview of at least two views
/// per pass, clip distances and indirect execution), the adapter offers: a driver too old for
/// ray queries, or a regression of feature detection, fails here by name instead of turning
/// the ray-query tests into checks of a refusal. Without the test command nothing is expected.
/// Seen failing with `MANYSHADOWS_WITHOUT_FEATURES=EXPERIMENTAL_RAY_QUERY` on Vulkan.
#[test]
fn the_adapter_offers_what_the_test_command_expects() {
    let ctx = common::context();
    let expected = manyshadows_testkit::expected();
    let mut missing = Vec::new();
    for need in &expected {
        let met = match need.as_str() {
            "INDIRECT_EXECUTION" => ctx
                .adapter
                .get_downlevel_capabilities()
                .flags
                .contains(manyshadows::wgpu::DownlevelFlags::INDIRECT_EXECUTION),
            "MULTIVIEW" => ctx.multiview_views_per_pass() >= 2,
            name => {
                let feature = manyshadows::wgpu::Features::from_name(name)
                    .unwrap_or_else(|| panic!("{name} is no wgpu feature"));
                ctx.has(feature)
            }
        };
        if !met {
            missing.push(need.clone());
        }
    }
    eprintln!("{}: expected {expected:?}", ctx.describe());
    assert!(
        missing.is_empty(),
        "{} lacks {missing:?}, which the test command says this backend must offer; on \
         Debian 12 install Mesa 25 from bookworm-backports (`cargo xtask test` does)",
        ctx.describe()
    );
}

/// The lighting pass's storage buffers against the device's per-stage limit: on a device that
/// binds 10 (Chromium's WebGPU on SwiftShader), sampled lights over virtual maps with the
/// denoiser (10 buffers) render, and with reuse as well (12: the reservoirs and their motion)
/// are refused naming the limit and the buffers, where creating the pass was a validation
/// error in the browser.
#[test]
fn a_lighting_pass_past_the_storage_buffer_limit_is_refused_by_name() {
    let _own = common::own_device_lock();
    let ctx = context_with(wgpu::Limits {
        max_storage_buffers_per_shader_stage: 10,
        ..required_limits()
    })
    .expect("the adapter offers 10 storage buffers per stage");
    let scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    let sampled = manyshadows::RayOptions::default()
        .with_light_samples(1)
        .with_denoise(true);
    let denoised = settings(Technique::VIRTUAL).with_rays(sampled);
    Renderer::new(&ctx, &scene, denoised.clone())
        .and_then(|mut r| r.render())
        .expect("virtual maps, K = 1 denoised, on 10 storage buffers a stage");
    match Renderer::new(&ctx, &scene, denoised.with_rays(sampled.with_reuse(true))) {
        Err(e @ RenderError::LimitsTooSmall { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("max_storage_buffers_per_shader_stage")
                    && text.contains("allows 10")
                    && text.contains("needs 12")
                    && text.contains("reservoirs"),
                "{text}"
            );
        }
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(_) => panic!("12 storage buffers accepted on a device that binds 10"),
    }
}
