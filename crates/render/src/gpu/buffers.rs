//! Buffers that grow with the scene or the frame.

use crate::error::RenderError;
use crate::gpu::context::GpuContext;

/// Makes `buffer` hold at least `needed` bytes: a buffer too small is replaced by one with room
/// for twice as much (so a growing scene reallocates rarely), capped at the device's limit for
/// its usage (`max_buffer_size`; storage buffers also `max_storage_buffer_binding_size`, since
/// they are bound whole). Returns true if the buffer was replaced; `needed` over the limit is a
/// [`RenderError::TooLarge`] naming `what`, never a GPU error.
pub(crate) fn grow_buffer(
    ctx: &GpuContext,
    buffer: &mut wgpu::Buffer,
    needed: u64,
    what: &str,
) -> Result<bool, RenderError> {
    if buffer.size() >= needed {
        return Ok(false);
    }
    let limits = ctx.limits();
    let usage = buffer.usage();
    let mut limit = limits.max_buffer_size;
    let mut limit_name = "max_buffer_size";
    if usage.contains(wgpu::BufferUsages::STORAGE) && limits.max_storage_buffer_binding_size < limit
    {
        limit = limits.max_storage_buffer_binding_size;
        limit_name = "max_storage_buffer_binding_size";
    }
    // Binding sizes must stay multiples of 4 (16 keeps arrays of vec4 whole).
    let limit = limit - limit % 16;
    if needed > limit {
        return Err(RenderError::TooLarge {
            what: format!("the {what} buffer"),
            needed,
            limit,
            unit: "bytes",
            limit_name,
        });
    }
    *buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(&format!("manyshadows.{}", what.replace(' ', "_"))),
        size: (2 * needed).next_multiple_of(16).min(limit).max(needed),
        usage,
        mapped_at_creation: false,
    });
    Ok(true)
}

/// A buffer of at least `size` bytes, rounded up to a multiple of 16 (at least 16: bindings of
/// arrays of `vec4` stay whole and no binding is empty).
pub(crate) fn buffer(
    ctx: &GpuContext,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(16),
        usage,
        mapped_at_creation: false,
    })
}
