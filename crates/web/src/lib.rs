//! The renderer in a web page: WebGPU through wgpu, the atrium rendered into a texture and
//! read back (an offscreen frame: headless browsers do not present canvases).
#![cfg(target_arch = "wasm32")]

use manyshadows::scene::builtin;
use manyshadows::{wgpu, GpuContext, RenderSettings, Renderer};
use wasm_bindgen::prelude::*;

fn err(e: impl std::fmt::Display) -> JsValue {
    JsValue::from_str(&e.to_string())
}

/// Renders `scene` (a built-in name) at `width`×`height` and returns the RGBA8 pixels.
#[wasm_bindgen]
pub async fn render_builtin(scene: String, width: u32, height: u32) -> Result<Vec<u8>, JsValue> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::BROWSER_WEBGPU;
    let instance = wgpu::Instance::new(desc);
    let adapter = instance
        .request_adapter(&wgpu::RequestAdapterOptions::default())
        .await
        .map_err(err)?;
    let features =
        adapter.features() & (wgpu::Features::CLIP_DISTANCES | wgpu::Features::TIMESTAMP_QUERY);
    let (device, queue) = adapter
        .request_device(&wgpu::DeviceDescriptor {
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        })
        .await
        .map_err(err)?;
    let ctx = GpuContext::from_parts(instance, adapter, device, queue).map_err(err)?;
    let scene = builtin::build(&scene, &Default::default()).map_err(err)?;
    let settings = RenderSettings {
        width,
        height,
        ..Default::default()
    };
    let mut renderer = Renderer::new(&ctx, &scene, settings).map_err(err)?;
    let target = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("web.frame"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    renderer.render_to(&target).map_err(err)?;
    // Read back: rows padded to 256 bytes, mapped asynchronously.
    let row = (width * 4).next_multiple_of(256);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("web.readback"),
        size: row as u64 * height as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        target.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let (tx, rx) = futures_channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| tx(r.is_ok()));
    if !rx.await {
        return Err(err("mapping the frame for reading failed"));
    }
    let data = buffer.get_mapped_range(..).map_err(err)?;
    let mut out = Vec::with_capacity((width * height * 4) as usize);
    for y in 0..height as usize {
        out.extend_from_slice(&data[y * row as usize..y * row as usize + width as usize * 4]);
    }
    Ok(out)
}

/// A one-shot channel as a JS promise (no extra crate): resolved by the map callback.
fn futures_channel() -> (
    impl FnOnce(bool) + 'static,
    impl std::future::Future<Output = bool>,
) {
    let mut resolve_fn = None;
    let promise = js_sys::Promise::new(&mut |resolve, _| resolve_fn = Some(resolve));
    let resolve = resolve_fn.expect("Promise::new runs its executor at once");
    let send = move |ok: bool| {
        let _ = resolve.call1(&JsValue::NULL, &JsValue::from_bool(ok));
    };
    let fut = async move {
        wasm_bindgen_futures::JsFuture::from(promise)
            .await
            .ok()
            .and_then(|v| v.as_bool())
            .unwrap_or(false)
    };
    (send, fut)
}
