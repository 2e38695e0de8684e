//! Page marking by 4×4-pixel tiles (step 1 of [`crate::shadows::vsm`] with
//! [`VirtualOptions::tile_marking`](super::plan::VirtualOptions::tile_marking),
//! `vsm_tiles.wgsl` after `vsm_mark.wgsl`): a thread per tile bounds its samples and marks
//! once per light the page every sample provably needs; what it cannot settle it hands on as
//! jobs (or whole tiles) to per-pixel marking with the same functions as [`super::mark`], so
//! the pages are the same. Three passes: the tiles (`cs_mark_tiles`), the hand-off's
//! dispatch arguments and the tiles' statistics (`cs_mark_args`), the jobs (`cs_mark_pixels`).
//! The hand-off list lives here, sized by the screen and the device's binding limit.

use crate::gpu::buffers::buffer;
use crate::gpu::context::GpuContext;
use crate::gpu::pipelines::{
    bind_group_layout, compute_pipeline, pipeline_layout, storage_rw_entry, uniform_entry,
    whole_entry,
};
use crate::gpu::shaders::{compose, module, COMMON};
use crate::shadows::lookup::{PARABOLOID, SHADOW_LOOKUP};
use crate::shadows::vsm::mark::{sample_group, sample_layout, Samples, MARK};
use crate::shadows::vsm::plan::VSM_COMMON;
use crate::shadows::vsm::table::{TableBuffers, PAGE_TABLE};
use crate::shadows::vsm::types::VSM_TYPES;

/// Pixels per side of a tile of the tile marking (`MARK_TILE` in `vsm_tiles.wgsl`).
const MARK_TILE: u32 = 4;
/// Room for the tile marking's jobs, in words per tile of the screen (a job is 2 words and 3
/// per light handed on; a tile whose job does not fit does it in its own thread: the same
/// pages, slower).
const JOB_WORDS_PER_TILE: u64 = 12;

/// Bytes of the tile marking's hand-off list for a `width` x `height` screen (`mark_list` in
/// `vsm_tiles.wgsl`): counts, a word per tile for tiles handed on whole and one for jobs'
/// offsets, then room for the jobs, as much of it as `limit` (the device's binding limit)
/// leaves. The fixed part, 8 bytes per 4x4-pixel tile, fits every device the renderer accepts
/// (2 MiB at its 2048² texture limit against 4 MiB bindings).
fn mark_list_bytes(width: u32, height: u32, limit: u64) -> u64 {
    let tiles = width.div_ceil(MARK_TILE) as u64 * height.div_ceil(MARK_TILE) as u64;
    let fixed = 4 * (8 + 2 * tiles);
    // (16 bytes spare: the buffer is rounded up to a multiple of 16.)
    let room = (4 * tiles * JOB_WORDS_PER_TILE).min(limit.saturating_sub(fixed + 16) / 16 * 16);
    fixed + room
}

/// The tile marking: `cs_mark_tiles`, `cs_mark_args`, `cs_mark_pixels` (and, composed with
/// them, `vsm_mark.wgsl`'s `cs_mark`, which [`super::mark`] runs).
pub(crate) fn shader() -> String {
    compose(&[
        COMMON,
        VSM_TYPES,
        PARABOLOID,
        SHADOW_LOOKUP,
        VSM_COMMON,
        PAGE_TABLE,
        MARK,
        include_str!("vsm_tiles.wgsl"),
    ])
}

/// The tile marking's passes, their layouts and bind groups, and the hand-off list.
pub(crate) struct TilePass {
    /// [`VirtualOptions::tile_marking`](super::plan::VirtualOptions::tile_marking), unless
    /// the device cannot hold the hand-off list.
    enabled: bool,
    /// The (tile, light) pairs the tiles hand on to per-pixel marking, and their dispatch
    /// arguments (`mark_list`, `mark_args` in `vsm_tiles.wgsl`).
    list: wgpu::Buffer,
    args: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    tiles: wgpu::ComputePipeline,
    pixels: wgpu::ComputePipeline,
    args_pipeline: wgpu::ComputePipeline,
    groups: Option<[wgpu::BindGroup; 2]>,
}

impl TilePass {
    /// The passes for a `width` x `height` screen; marking by tiles if `wanted` and the
    /// device's storage bindings hold the hand-off list.
    pub(crate) fn new(ctx: &GpuContext, (width, height): (u32, u32), wanted: bool) -> Self {
        let device = &ctx.device;
        let limits = ctx.limits();
        let binding_limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            / 16
            * 16;
        let list_bytes = mark_list_bytes(width, height, binding_limit);
        let enabled = wanted && list_bytes <= binding_limit;
        use wgpu::BufferUsages as U;
        let list = buffer(
            ctx,
            "vsm.mark_list",
            if enabled { list_bytes } else { 16 },
            U::STORAGE | U::COPY_DST,
        );
        let args = buffer(ctx, "vsm.mark_args", 12, U::STORAGE | U::INDIRECT);
        let cs = wgpu::ShaderStages::COMPUTE;
        let mut entries = sample_layout();
        entries.push(storage_rw_entry(16, cs));
        let layout = bind_group_layout(device, "vsm.mark_tiles_layout", &entries);
        let args_layout = bind_group_layout(
            device,
            "vsm.mark_args_layout",
            &[
                uniform_entry(0, cs),
                storage_rw_entry(10, cs),
                storage_rw_entry(16, cs),
                storage_rw_entry(17, cs),
            ],
        );
        let code = module(device, "vsm.mark_tiles_shader", &shader());
        let pl = pipeline_layout(device, "vsm.mark_tiles_pipeline_layout", &[&layout]);
        let args_pl = pipeline_layout(device, "vsm.mark_args_pipeline_layout", &[&args_layout]);
        Self {
            enabled,
            list,
            args,
            tiles: compute_pipeline(device, "vsm.mark_tiles", &pl, &code, "cs_mark_tiles"),
            pixels: compute_pipeline(device, "vsm.mark_pixels", &pl, &code, "cs_mark_pixels"),
            args_pipeline: compute_pipeline(
                device,
                "vsm.mark_args",
                &args_pl,
                &code,
                "cs_mark_args",
            ),
            layout,
            args_layout,
            groups: None,
        }
    }

    /// Whether the frame marks by tiles (else per pixel, [`super::mark`]).
    pub(crate) fn enabled(&self) -> bool {
        self.enabled
    }

    /// Builds the bind groups (whenever a buffer they hold was replaced).
    pub(crate) fn bind(
        &mut self,
        device: &wgpu::Device,
        samples: &Samples<'_>,
        table: &TableBuffers<'_>,
    ) {
        let tiles = sample_group(
            device,
            "vsm.mark_tiles_group",
            &self.layout,
            samples,
            table,
            &[whole_entry(16, &self.list)],
        );
        let args = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.mark_args_group"),
            layout: &self.args_layout,
            entries: &[
                whole_entry(0, samples.frame),
                whole_entry(10, table.counters),
                whole_entry(16, &self.list),
                whole_entry(17, &self.args),
            ],
        });
        self.groups = Some([tiles, args]);
    }

    /// Clears the hand-off count before the frame's marking (the entries are written before
    /// they are read).
    pub(crate) fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        if self.enabled {
            encoder.clear_buffer(&self.list, 0, Some(32));
        }
    }

    /// Marks the pages the pixels of `rect` (x0, y0, x1, y1; its first pixel is
    /// `VsmUniforms::lod.yz`) need.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>, [x0, y0, x1, y1]: [u32; 4]) {
        let Some([tiles, args]) = &self.groups else {
            return;
        };
        // One thread per tile of MARK_TILE² pixels (workgroups of 8 x 8 tiles: past the
        // rectangle's end by up to 31 pixels, like the per-pixel pass's 7), then the jobs the
        // tiles handed on, four per workgroup.
        let groups = |n: u32| n.div_ceil(MARK_TILE).div_ceil(8);
        pass.set_bind_group(0, tiles, &[]);
        pass.set_pipeline(&self.tiles);
        pass.dispatch_workgroups(groups(x1 - x0), groups(y1 - y0), 1);
        pass.set_bind_group(0, args, &[]);
        pass.set_pipeline(&self.args_pipeline);
        pass.dispatch_workgroups(1, 1, 1);
        pass.set_bind_group(0, tiles, &[]);
        pass.set_pipeline(&self.pixels);
        pass.dispatch_workgroups_indirect(&self.args, 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hand-off list: its fixed part (counts, a word per tile for whole tiles and one for
    /// job offsets) always, the jobs' room up to what the binding limit leaves; on the
    /// smallest device the renderer accepts (2048² textures, 4 MiB bindings) a full-size
    /// screen still fits.
    #[test]
    fn the_mark_list_fits_the_binding_limit() {
        let big = 1u64 << 40;
        // 1280x720: 320 x 180 tiles.
        let tiles = 320 * 180;
        assert_eq!(
            mark_list_bytes(1280, 720, big),
            4 * (8 + 2 * tiles + JOB_WORDS_PER_TILE * tiles)
        );
        let small = 4u64 << 20;
        let bytes = mark_list_bytes(2048, 2048, small);
        let fixed = 4 * (8 + 2 * 512 * 512);
        assert!(
            bytes.next_multiple_of(16) <= small && bytes > fixed,
            "{bytes}"
        );
        assert_eq!((bytes - fixed) % 16, 0);
        // A screen whose fixed part alone passes the limit: the renderer turns tiles off.
        assert!(mark_list_bytes(16384, 16384, small) > small);
    }
}
