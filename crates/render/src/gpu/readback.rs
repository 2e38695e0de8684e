//! Reading GPU results back to the CPU: textures through a row-padded buffer, buffers by
//! mapping. Every wait is bounded by the device poll and every failure is an error, not a panic.

use crate::error::RenderError;
use crate::gpu::context::GpuContext;

/// Maps `range` of a `MAP_READ` buffer after the work that fills it has been submitted, and
/// copies the bytes out.
pub fn map_read(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    range: std::ops::Range<u64>,
) -> Result<Vec<u8>, RenderError> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, range.clone(), move |r| {
        let _ = tx.send(r);
    });
    ctx.wait_idle()?;
    rx.recv()
        .map_err(|_| RenderError::Readback {
            what: "a buffer",
            reason: "the map callback never ran".into(),
        })?
        .map_err(|e| RenderError::Readback {
            what: "a buffer",
            reason: format!("mapping it: {e}"),
        })?;
    let bytes = buffer
        .get_mapped_range(range)
        .map_err(|e| RenderError::Readback {
            what: "a buffer",
            reason: e.to_string(),
        })?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// Copies a whole `COPY_SRC` buffer into a staging buffer and reads it back (for inspection
/// and tests, not per frame).
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, RenderError> {
    let size = buffer.size();
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("manyshadows.readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("manyshadows.readback.copy"),
        });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    map_read(ctx, &staging, 0..size)
}

/// Copies a whole 2D texture (colour formats) to tightly packed bytes.
pub fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    bytes_per_pixel: u32,
) -> Result<Vec<u8>, RenderError> {
    read_texture_layer(ctx, texture, bytes_per_pixel, 0)
}

/// Copies layer `layer` of a 2D texture or array (colour formats) to tightly packed bytes.
pub fn read_texture_layer(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    bytes_per_pixel: u32,
    layer: u32,
) -> Result<Vec<u8>, RenderError> {
    let (w, h) = (texture.width(), texture.height());
    let row = w * bytes_per_pixel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback.texture"),
        size: padded as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback.encoder"),
        });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            ..texture.as_image_copy()
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    ctx.queue.submit([encoder.finish()]);
    let data = map_read(ctx, &buffer, 0..padded as u64 * h as u64)?;
    let mut out = Vec::with_capacity((row * h) as usize);
    for y in 0..h as usize {
        let start = y * padded as usize;
        out.extend_from_slice(&data[start..start + row as usize]);
    }
    Ok(out)
}
