//! Embedding the renderer in a caller's own wgpu device: the caller makes the instance,
//! adapter, device and queue, wraps them with `GpuContext::from_parts`, keeps a `Renderer` in
//! its own struct (no borrowed lifetime), and renders into textures it owns with
//! `Renderer::render_to`. The frames must be the ones `Renderer::render` reads back.

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::{wgpu, GpuContext, RenderError, RenderSettings, Renderer};

/// The caller's own device, on the backend `WGPU_BACKEND` names (as the other GPU tests).
fn callers_device() -> GpuContext {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
    desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }))
    .expect(
        "an adapter (install mesa-vulkan-drivers for lavapipe, or libegl1 + libgl1-mesa-dri \
         for llvmpipe)",
    );
    // What a typical application asks for: WebGPU's default limits, no optional features.
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("the caller's device"),
        required_features: wgpu::Features::empty(),
        required_limits: wgpu::Limits::default(),
        ..Default::default()
    }))
    .expect("a device with WebGPU's default limits");
    GpuContext::from_parts(instance, adapter, device, queue).expect("the renderer accepts it")
}

/// A caller's struct that owns a renderer: no lifetime parameter needed.
struct App {
    renderer: Renderer,
    target: wgpu::Texture,
}

fn texture(ctx: &GpuContext, w: u32, h: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("the caller's texture"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

#[test]
fn render_to_a_callers_texture_gives_the_frame_render_reads_back() {
    let _own = common::own_device_lock();
    let ctx = callers_device();
    let scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    // Every frame drawn whole (with the default caching the second frame keeps every map and
    // draws no shadow pass).
    let settings = RenderSettings::default()
        .with_width(96)
        .with_height(64)
        .with_cache_shadows(false);
    let mut app = App {
        renderer: Renderer::new(&ctx, &scene, settings).unwrap(),
        target: texture(&ctx, 96, 64, wgpu::TextureFormat::Rgba8UnormSrgb),
    };
    let frame = app.renderer.render().unwrap();
    assert!(frame.rgba.iter().any(|&c| c > 40), "black reference frame");

    // Same size, sRGB: the very same bytes.
    let stats = app.renderer.render_to(&app.target).unwrap();
    assert!(stats.shadow_stats.passes > 0);
    let got = manyshadows::gpu::readback::read_texture(&ctx, &app.target, 4).unwrap();
    assert!(
        got == frame.rgba,
        "sRGB target differs from the read-back frame"
    );

    // A swapchain-like BGRA target that stores raw 8-bit values: the shader encodes to sRGB
    // itself; measured: every channel equal (Vulkan and OpenGL).
    let bgra = texture(&ctx, 96, 64, wgpu::TextureFormat::Bgra8Unorm);
    app.renderer.render_to(&bgra).unwrap();
    let got = manyshadows::gpu::readback::read_texture(&ctx, &bgra, 4).unwrap();
    let worst = got
        .chunks_exact(4)
        .zip(frame.rgba.chunks_exact(4))
        .flat_map(|(b, r)| [(b[2], r[0]), (b[1], r[1]), (b[0], r[2]), (b[3], r[3])])
        .map(|(a, b)| a.abs_diff(b))
        .max()
        .unwrap();
    assert_eq!(worst, 0, "BGRA target off by up to {worst} levels");

    // Twice the size: every 2×2 block is the frame's pixel (nearest texel).
    let big = texture(&ctx, 192, 128, wgpu::TextureFormat::Rgba8UnormSrgb);
    app.renderer.render_to(&big).unwrap();
    let got = manyshadows::gpu::readback::read_texture(&ctx, &big, 4).unwrap();
    let mut off = 0;
    for y in 0..128usize {
        for x in 0..192usize {
            let (g, r) = ((y * 192 + x) * 4, ((y / 2) * 96 + x / 2) * 4);
            off += usize::from(got[g..g + 4] != frame.rgba[r..r + 4]);
        }
    }
    assert_eq!(
        off, 0,
        "{off} pixels of the doubled target are not the frame's"
    );
}

#[test]
fn render_to_refuses_a_texture_it_cannot_draw_into() {
    let _own = common::own_device_lock();
    let ctx = callers_device();
    let scene = builtin::build("plane-spot", &BuiltinOptions::default()).unwrap();
    let mut r = Renderer::new(
        &ctx,
        &scene,
        RenderSettings::default().with_width(32).with_height(32),
    )
    .unwrap();
    let copy_only = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: 32,
            height: 32,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let err = r
        .render_to(&copy_only)
        .expect_err("no RENDER_ATTACHMENT usage");
    assert!(
        matches!(err, RenderError::UnsupportedTarget { .. })
            && err.to_string().contains("RENDER_ATTACHMENT"),
        "{err}"
    );
    let depth = texture(&ctx, 32, 32, wgpu::TextureFormat::Depth32Float);
    let err = r.render_to(&depth).expect_err("a depth target");
    assert!(
        matches!(
            err,
            RenderError::UnsupportedTarget {
                format: wgpu::TextureFormat::Depth32Float,
                ..
            }
        ),
        "{err}"
    );
    // The renderer still works afterwards.
    r.render_to(&texture(&ctx, 32, 32, wgpu::TextureFormat::Rgba8Unorm))
        .unwrap();
}

#[test]
fn a_callers_device_below_the_minimum_is_refused() {
    let _own = common::own_device_lock();
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
    desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).unwrap();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: wgpu::Limits::downlevel_defaults(),
        ..Default::default()
    }))
    .unwrap();
    let err = GpuContext::from_parts(instance, adapter, device, queue)
        .expect_err("downlevel limits (4 storage buffers per stage) are below the minimum");
    assert!(
        err.to_string()
            .contains("max_storage_buffers_per_shader_stage"),
        "{err}"
    );
}

/// `from_parts` leaves the host's uncaptured-error handler in place (an error outside every
/// error scope reaches the host, not the renderer); `capture_uncaptured_errors` is how a host
/// hands them to the renderer instead, which then reports them.
#[test]
fn the_hosts_error_handler_stays_unless_it_asks() {
    let _own = common::own_device_lock();
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;
    let ctx = callers_device();
    let seen = Arc::new(AtomicUsize::new(0));
    let host = seen.clone();
    // Installed by the host before the renderer ever sees the device (callers_device wrapped
    // it with from_parts already; from_parts must not have replaced anything since).
    ctx.device.on_uncaptured_error(Arc::new(move |_| {
        host.fetch_add(1, Ordering::SeqCst);
    }));
    let bad = || {
        // A buffer mapped at creation whose size is not a multiple of 4: a validation error,
        // outside every error scope.
        let _ = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("invalid on purpose"),
            size: 3,
            usage: wgpu::BufferUsages::MAP_WRITE,
            mapped_at_creation: true,
        });
    };
    let scene = builtin::build("plane-spot", &BuiltinOptions::default()).unwrap();
    let mut r = Renderer::new(&ctx, &scene, RenderSettings::new(32, 32)).unwrap();
    bad();
    assert_eq!(
        seen.load(Ordering::SeqCst),
        1,
        "the host's handler saw the error"
    );
    assert!(
        ctx.take_uncaptured().is_none(),
        "the renderer recorded nothing"
    );
    r.render().expect("a frame: the error was the host's");

    ctx.capture_uncaptured_errors();
    bad();
    assert_eq!(
        seen.load(Ordering::SeqCst),
        1,
        "now the renderer's handler has it"
    );
    let err = r
        .render()
        .expect_err("the renderer reports the captured error");
    assert!(matches!(err, RenderError::Gpu { .. }), "{err:?}");
}

/// `poll_gpu_timings` hands back the GPU times of frames `render_to` submitted once the GPU
/// has finished them, without waiting: the same stages `read_gpu_timings` reads.
#[test]
fn gpu_timings_come_back_without_a_wait() {
    let _own = common::own_device_lock();
    let ctx = common::context();
    assert!(
        ctx.has(wgpu::Features::TIMESTAMP_QUERY),
        "the test adapter ({}) has no timestamp queries: use Mesa 25's lavapipe or llvmpipe \
         (`cargo xtask test` installs them), which have them",
        manyshadows::gpu::context::describe_adapter(&ctx.info)
    );
    let scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    let mut r = Renderer::new(&ctx, &scene, RenderSettings::new(64, 48)).unwrap();
    let target = texture(&ctx, 64, 48, wgpu::TextureFormat::Rgba8UnormSrgb);
    let mut got = None;
    for _ in 0..4 {
        r.render_to(&target).unwrap();
        if let Some(t) = r.poll_gpu_timings() {
            got = Some(t);
        }
    }
    // However far the GPU got, once it is idle the newest frame's times are there.
    ctx.wait_idle().unwrap();
    if let Some(t) = r.poll_gpu_timings() {
        got = Some(t);
    }
    let polled = got.expect("times after the GPU finished");
    assert!(
        r.poll_gpu_timings().is_none(),
        "each frame's times come back once"
    );
    let read = r.read_gpu_timings().unwrap();
    let stages = |t: &manyshadows::GpuTimes| t.iter().map(|(s, _)| s).collect::<Vec<_>>();
    assert_eq!(stages(&polled), stages(&read));
    assert!(polled.total().unwrap() > 0.0);
}

/// On a device without timestamp queries (a caller's device made with no optional feature)
/// nothing is timed, and both ways of reading the times say so without waiting for ever.
#[test]
fn gpu_timings_are_empty_without_timestamp_queries() {
    let _own = common::own_device_lock();
    let ctx = callers_device();
    assert!(!ctx.has(wgpu::Features::TIMESTAMP_QUERY));
    let scene = builtin::build("cubes", &BuiltinOptions::default()).unwrap();
    let mut r = Renderer::new(&ctx, &scene, RenderSettings::new(64, 48)).unwrap();
    let target = texture(&ctx, 64, 48, wgpu::TextureFormat::Rgba8UnormSrgb);
    r.render_to(&target).unwrap();
    ctx.wait_idle().unwrap();
    assert!(r.poll_gpu_timings().is_none_or(|t| t.is_empty()));
    assert!(r.read_gpu_timings().unwrap().is_empty());
    let frame = r.render().unwrap();
    assert!(frame.timings.gpu_ms.is_empty());
    assert!(
        frame.rgba.iter().any(|&b| b > 0),
        "the frame is drawn all the same"
    );
}
