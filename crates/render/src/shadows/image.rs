//! Reading the depth atlas back and turning it into a picture: linearized depth per tile (seed
//! 004's shadow-map visualization, done properly with each view's near and far) and the tile
//! outlines.

use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;
use crate::shadows::plan::ShadowPlan;
use crate::shadows::storage::ShadowAtlas;

/// A picture of a renderer's shadow maps (`Renderer::shadow_picture`).
#[non_exhaustive]
#[derive(Clone, Debug)]
pub struct ShadowPicture {
    /// Side of the square picture in pixels.
    pub side: u32,
    /// RGB8 pixels, row-major from the top-left.
    pub rgb: Vec<u8>,
    /// What it shows ("4096² atlas, 97 views").
    pub description: String,
}

impl ShadowPicture {
    /// The atlas with each of `plan`'s view tiles outlined, read back from the GPU.
    pub fn of_atlas(
        ctx: &GpuContext,
        atlas: &ShadowAtlas,
        plan: &ShadowPlan,
    ) -> Result<Self, RenderError> {
        let depth = read_depth(ctx, atlas)?;
        let (side, rgb) = atlas_picture(&depth, atlas.size, plan);
        Ok(ShadowPicture {
            side,
            rgb,
            description: format!("{}² atlas, {} views", atlas.size, plan.views.len()),
        })
    }

    /// A page pool of `pool_side`² texels in pages of `page_size`² (its `depth` read back).
    pub fn of_pool(depth: &[f32], pool_side: u32, page_size: u32) -> Self {
        let (side, rgb) = pool_picture(depth, pool_side);
        let pages = (pool_side / page_size).pow(2);
        ShadowPicture {
            side,
            rgb,
            description: format!("{pool_side}² page pool ({pages} pages)"),
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CopyParams {
    first_row: u32,
    rows: u32,
    width: u32,
    _pad: u32,
}

/// Reads the atlas depth (`size`² floats, row-major from the top-left texel). Works on GL too:
/// the depth texture is loaded as an unfilterable float texture by a compute shader, in bands
/// of rows that fit the storage-binding limit.
pub fn read_depth(ctx: &GpuContext, atlas: &ShadowAtlas) -> Result<Vec<f32>, RenderError> {
    read_depth_view(ctx, &atlas.view, atlas.size)
}

/// Reads any `size`² `Depth32Float` texture through its depth view (the atlas, the virtual
/// maps' page pool), as [`read_depth`] does.
pub fn read_depth_view(
    ctx: &GpuContext,
    view: &wgpu::TextureView,
    size: u32,
) -> Result<Vec<f32>, RenderError> {
    let device = &ctx.device;
    let limit = ctx.limits().max_storage_buffer_binding_size.min(64 << 20);
    let rows_per_band = ((limit / (size as u64 * 4)) as u32).clamp(1, size);
    let layout = crate::gpu::pipelines::bind_group_layout(
        device,
        "atlas_copy.layout",
        &[
            crate::gpu::pipelines::texture_entry(
                0,
                wgpu::TextureSampleType::Float { filterable: false },
                wgpu::ShaderStages::COMPUTE,
            ),
            crate::gpu::pipelines::storage_rw_entry(1, wgpu::ShaderStages::COMPUTE),
            crate::gpu::pipelines::uniform_entry(2, wgpu::ShaderStages::COMPUTE),
        ],
    );
    let module = crate::gpu::shaders::module(device, "atlas_copy.shader", &atlas_copy_shader());
    let pipeline_layout =
        crate::gpu::pipelines::pipeline_layout(device, "atlas_copy.pipeline_layout", &[&layout]);
    let pipeline = crate::gpu::pipelines::compute_pipeline(
        device,
        "atlas_copy.pipeline",
        &pipeline_layout,
        &module,
        "cs_main",
    );
    let mut out = Vec::with_capacity(size as usize * size as usize);
    let mut first_row = 0;
    while first_row < size {
        let rows = rows_per_band.min(size - first_row);
        let bytes = rows as u64 * size as u64 * 4;
        let storage = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("atlas_copy.band"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("atlas_copy.readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("atlas_copy.params"),
            contents: bytemuck::bytes_of(&CopyParams {
                first_row,
                rows,
                width: size,
                _pad: 0,
            }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("atlas_copy.bind_group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: storage.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: params.as_entire_binding(),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("atlas_copy.encoder"),
        });
        // The copy reads the atlas the frame drew.
        {
            let mut pass = ctx.raster_fence().begin_compute_pass(
                &mut encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some("atlas_copy.pass"),
                    timestamp_writes: None,
                },
            );
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(size.div_ceil(16), rows.div_ceil(16), 1);
        }
        encoder.copy_buffer_to_buffer(&storage, 0, &readback, 0, bytes);
        ctx.queue.submit([encoder.finish()]);
        let data = crate::gpu::readback::map_read(ctx, &readback, 0..bytes)?;
        out.extend_from_slice(bytemuck::cast_slice::<u8, f32>(&data));
        first_row += rows;
    }
    Ok(out)
}

/// Largest side of the atlas picture; bigger atlases are shown scaled down (nearest texel).
pub const MAX_ATLAS_IMAGE: u32 = 4096;

/// An RGB picture of the atlas: each tile's depth linearized between its view's near and far
/// plane (near = white, far or empty = black), tiles outlined (spot yellow, point cyan,
/// cascade magenta), unused atlas area dark blue. Returns `(side, rgb bytes)`.
pub fn atlas_picture(depth: &[f32], atlas_size: u32, plan: &ShadowPlan) -> (u32, Vec<u8>) {
    use manyshadows_scene::light_space::ViewKind;
    let scale = atlas_size.div_ceil(MAX_ATLAS_IMAGE).max(1);
    let side = atlas_size / scale;
    let mut rgb = vec![0u8; side as usize * side as usize * 3];
    for px in rgb.chunks_exact_mut(3) {
        px.copy_from_slice(&[10, 12, 40]);
    }
    for (view, tile) in plan.views.iter().zip(&plan.layout.tiles) {
        let (x0, y0) = (tile.x / scale, tile.y / scale);
        let n = (tile.size / scale).max(1);
        let outline: [u8; 3] = match view.kind {
            ViewKind::Spot => [255, 220, 0],
            ViewKind::CubeFace(_) => [0, 220, 255],
            ViewKind::Cascade(_) => [255, 0, 220],
            ViewKind::Paraboloid(_) => [80, 255, 120],
        };
        for ty in 0..n {
            for tx in 0..n {
                let (ax, ay) = (x0 + tx, y0 + ty);
                if ax >= side || ay >= side {
                    continue;
                }
                let d = depth[((ay * scale) * atlas_size + ax * scale) as usize];
                let lin = if view.orthographic {
                    d
                } else {
                    // Perspective depth d = far(z - near) / (z (far - near)) → view distance z.
                    let (nr, fr) = (view.near, view.far);
                    let z = nr * fr / (fr - d * (fr - nr));
                    ((z - nr) / (fr - nr)).clamp(0.0, 1.0)
                };
                let g = if d >= 1.0 {
                    0
                } else {
                    (255.0 * (1.0 - lin).powf(1.5)) as u8
                };
                let border = tx == 0 || ty == 0 || tx + 1 == n || ty + 1 == n;
                let i = (ay as usize * side as usize + ax as usize) * 3;
                rgb[i..i + 3].copy_from_slice(&if border { outline } else { [g, g, g] });
            }
        }
    }
    (side, rgb)
}

/// An RGB picture of the virtual maps' page pool (`side`² texels): drawn depth as grey (near
/// = white), pages cleared but empty black, pool texels never used since the pool was made
/// dark blue (pages fill the pool from the top-left, in page-table order). Returns `(side, rgb
/// bytes)`, scaled down like [`atlas_picture`].
pub fn pool_picture(depth: &[f32], pool_side: u32) -> (u32, Vec<u8>) {
    let scale = pool_side.div_ceil(MAX_ATLAS_IMAGE).max(1);
    let side = pool_side / scale;
    let mut rgb = vec![0u8; side as usize * side as usize * 3];
    for y in 0..side {
        for x in 0..side {
            let d = depth[((y * scale) * pool_side + x * scale) as usize];
            let px = if d == 0.0 {
                // A new texture reads 0; a page in use was cleared to 1 before drawing.
                [10, 12, 40]
            } else if d >= 1.0 {
                [0, 0, 0]
            } else {
                let g = (255.0 * (1.0 - d).clamp(0.0, 1.0).powf(0.25)) as u8;
                [g, g, g]
            };
            let i = (y as usize * side as usize + x as usize) * 3;
            rgb[i..i + 3].copy_from_slice(&px);
        }
    }
    (side, rgb)
}

#[cfg(test)]
mod tests {
    use super::CopyParams;
    use crate::gpu::types::layout::same_layout;

    #[test]
    fn params_match_the_wgsl() {
        same_layout!(in super::atlas_copy_shader(), CopyParams, first_row, rows, width, _pad);
    }
}

/// The depth read-back copy's WGSL.
fn atlas_copy_shader() -> String {
    include_str!("atlas_copy.wgsl").to_string()
}

#[cfg(test)]
mod shader_tests {
    /// What this module composes is WGSL a WebGPU device accepts.
    #[test]
    fn shader_validates_for_webgpu() {
        crate::gpu::shaders::validate_for_webgpu(
            "atlas_copy",
            &super::atlas_copy_shader(),
            wgpu::Features::empty(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}
