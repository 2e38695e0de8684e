//! Reading GPU results back to the CPU: textures through a row-padded buffer, buffers by
//! mapping. Every wait is bounded by the device poll and every failure is an error, not a panic.
//!
//! In a browser nothing can wait for the GPU: a mapping completes only after control returns
//! to the page's event loop. There every read-back goes through [`read_deferred`], which runs
//! the reading function again after each mapping it asked for has come back (see its
//! documentation); natively it just calls the function.

use crate::error::RenderError;
use crate::gpu::context::GpuContext;

/// Maps `range` of a `MAP_READ` buffer after the work that fills it has been submitted, and
/// copies the bytes out.
pub fn map_read(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    range: std::ops::Range<u64>,
) -> Result<Vec<u8>, RenderError> {
    #[cfg(target_arch = "wasm32")]
    {
        let _ = ctx;
        deferred::map_read(buffer, range)
    }
    #[cfg(not(target_arch = "wasm32"))]
    map_read_waiting(ctx, buffer, range)
}

#[cfg(not(target_arch = "wasm32"))]
fn map_read_waiting(
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

/// Runs `read` (any of the library's read-backs: [`Renderer::read_gbuffer`],
/// [`Renderer::read_visibility`], [`Renderer::shadow_picture`], …) where waiting for the GPU
/// is impossible, in a browser: each time `read` maps a buffer that has not come back yet,
/// the mapping is awaited (returning to the event loop) and `read` runs again from the
/// start, its earlier mappings answered with the bytes that came back. A read-back that
/// maps `k` buffers runs `k + 1` times; its copies are submitted again each time, of the same
/// GPU state, as long as nothing is rendered meanwhile (the caller's `&self` borrow sees to
/// that for a `Renderer`). Natively it is `read()`.
///
/// [`Renderer::read_gbuffer`]: crate::Renderer::read_gbuffer
/// [`Renderer::read_visibility`]: crate::Renderer::read_visibility
/// [`Renderer::shadow_picture`]: crate::Renderer::shadow_picture
pub async fn read_deferred<T>(
    mut read: impl FnMut() -> Result<T, RenderError>,
) -> Result<T, RenderError> {
    #[cfg(target_arch = "wasm32")]
    {
        deferred::run(&mut read).await
    }
    #[cfg(not(target_arch = "wasm32"))]
    read()
}

#[cfg(target_arch = "wasm32")]
mod deferred {
    use std::cell::RefCell;
    use std::collections::VecDeque;
    use std::future::Future;
    use std::pin::Pin;
    use std::rc::Rc;
    use std::task::{Context, Poll, Waker};

    use crate::error::RenderError;

    type MapResult = Result<(), wgpu::BufferAsyncError>;

    /// A mapping asked for: the buffer, its range, and where its callback answers.
    struct Asked {
        buffer: wgpu::Buffer,
        range: std::ops::Range<u64>,
        slot: Rc<RefCell<(Option<MapResult>, Option<Waker>)>>,
    }

    /// The run of a reading function in progress: the bytes of its earlier mappings, in the
    /// order it asked for them, and the one mapping it is waiting for.
    struct Replay {
        answers: VecDeque<Vec<u8>>,
        asked: Option<Asked>,
    }

    thread_local! {
        static REPLAY: RefCell<Option<Replay>> = const { RefCell::new(None) };
    }

    pub(super) fn map_read(
        buffer: &wgpu::Buffer,
        range: std::ops::Range<u64>,
    ) -> Result<Vec<u8>, RenderError> {
        REPLAY.with(|r| {
            let mut r = r.borrow_mut();
            let Some(replay) = r.as_mut() else {
                return Err(RenderError::Readback {
                    what: "a buffer",
                    reason: "in a browser nothing can wait for the GPU: read through \
                             readback::read_deferred"
                        .into(),
                });
            };
            if let Some(bytes) = replay.answers.pop_front() {
                return Ok(bytes);
            }
            if replay.asked.is_none() {
                let slot: Rc<RefCell<(Option<MapResult>, Option<Waker>)>> =
                    Rc::new(RefCell::new((None, None)));
                let answer = slot.clone();
                buffer.map_async(wgpu::MapMode::Read, range.clone(), move |res| {
                    let mut a = answer.borrow_mut();
                    a.0 = Some(res);
                    if let Some(w) = a.1.take() {
                        w.wake();
                    }
                });
                replay.asked = Some(Asked {
                    buffer: buffer.clone(),
                    range,
                    slot,
                });
            }
            Err(RenderError::Readback {
                what: "a buffer",
                reason: "its mapping has not come back yet (read_deferred runs the read again)"
                    .into(),
            })
        })
    }

    struct Mapped(Rc<RefCell<(Option<MapResult>, Option<Waker>)>>);

    impl Future for Mapped {
        type Output = MapResult;
        fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<MapResult> {
            let mut s = self.0.borrow_mut();
            match s.0.take() {
                Some(r) => Poll::Ready(r),
                None => {
                    s.1 = Some(cx.waker().clone());
                    Poll::Pending
                }
            }
        }
    }

    pub(super) async fn run<T>(
        read: &mut impl FnMut() -> Result<T, RenderError>,
    ) -> Result<T, RenderError> {
        let mut answers: Vec<Vec<u8>> = Vec::new();
        loop {
            REPLAY.with(|r| {
                *r.borrow_mut() = Some(Replay {
                    answers: answers.iter().cloned().collect(),
                    asked: None,
                })
            });
            let out = read();
            let replay = REPLAY.with(|r| r.borrow_mut().take());
            // Whatever error the mapping's placeholder became on its way out, a mapping asked
            // for means: wait for it and run again.
            let Some(asked) = replay.and_then(|r| r.asked) else {
                return out;
            };
            Mapped(asked.slot.clone())
                .await
                .map_err(|e| RenderError::Readback {
                    what: "a buffer",
                    reason: format!("mapping it: {e}"),
                })?;
            let bytes = asked
                .buffer
                .get_mapped_range(asked.range)
                .map_err(|e| RenderError::Readback {
                    what: "a buffer",
                    reason: e.to_string(),
                })?
                .to_vec();
            asked.buffer.unmap();
            answers.push(bytes);
        }
    }
}
