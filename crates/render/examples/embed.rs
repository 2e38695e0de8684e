//! Embedding manyshadows in an application's own wgpu device: the application creates the
//! device, hands it to the renderer, keeps the renderer in its own struct and renders into a
//! texture it owns (a window's surface texture works the same way), beside its own passes.
//!
//! `cargo run --release -p manyshadows --example embed` writes `embedded.png`.

use manyshadows::scene::builtin;
use manyshadows::{wgpu, GpuContext, RenderSettings, Renderer};

struct App {
    renderer: Renderer, // no lifetime: the renderer holds its own handle to the device
    target: wgpu::Texture,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The application's device (WGPU_BACKEND picks the backend, as everywhere).
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
    desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&Default::default()))?;
    let ctx = GpuContext::from_parts(instance, adapter, device, queue)?;

    let scene = builtin::build("atrium", &Default::default())?;
    let (w, h) = (640, 360);
    let settings = RenderSettings::default().with_width(w).with_height(h);
    let app = App {
        renderer: Renderer::new(&ctx, &scene, settings)?,
        target: ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("app.frame"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        }),
    };
    let mut app = app;
    let submitted = app.renderer.render_to(&app.target)?;
    println!(
        "recorded in {:.2} ms, {} shadow passes",
        submitted.cpu_record_ms, submitted.shadow_stats.passes
    );
    // The application would present or sample `app.target` now; here it is saved.
    let rgba = manyshadows::gpu::readback::read_texture(&ctx, &app.target, 4)?;
    image::save_buffer("embedded.png", &rgba, w, h, image::ColorType::Rgba8)?;
    println!("wrote embedded.png");
    Ok(())
}
