//! Page allocation of the virtual shadow maps (step 2 of [`crate::shadows::vsm`],
//! `vsm_alloc.wgsl`), after the marking: the marked entries counted per level, the admitted
//! level chosen, pages admitted, denied or kept from last frame (`cs_retain`, with
//! [`super::carry`]'s faces), the free pool pages listed and the new pages placed in
//! page-table order, each with its view in the draw list; last, the page draw's indirect
//! arguments (`cs_args`). The frame's counters (`VirtualStats`) are counted on the way.

use crate::gpu::pipelines::{
    bind_group_layout, compute_pipeline, pipeline_layout, storage_entry, storage_rw_entry,
    uniform_entry, whole_entry,
};
use crate::gpu::shaders::{compose, module, COMMON};
use crate::shadows::vsm::draw::group_decl;
use crate::shadows::vsm::table::{entry_groups, TableBuffers, PAGE_TABLE};
use crate::shadows::vsm::types::VSM_TYPES;

/// Page-table entries per allocation thread (`BLOCK` in `vsm_alloc.wgsl`).
pub(crate) const ALLOC_BLOCK: u64 = 32;

/// The allocation and the indirect arguments: `cs_count` to `cs_args`.
pub(crate) fn shader() -> String {
    compose(&[
        COMMON,
        VSM_TYPES,
        PAGE_TABLE,
        &group_decl(),
        include_str!("vsm_alloc.wgsl"),
    ])
}

/// The buffers the allocation writes besides the table (owned by [`super::pages`]).
pub(crate) struct AllocBuffers<'a> {
    /// The view of every page drawn this frame, in rank order.
    pub page_views: &'a wgpu::Buffer,
    /// `array<VsmRound>` of the page draw.
    pub rounds: &'a wgpu::Buffer,
    /// The page draw's indirect arguments.
    pub args: &'a wgpu::Buffer,
    /// Kept and free pool pages, new pages per block (`scratch` in `vsm_alloc.wgsl`).
    pub scratch: &'a wgpu::Buffer,
}

/// The allocation passes: their layout, pipelines and bind group.
pub(crate) struct AllocPass {
    layout: wgpu::BindGroupLayout,
    count: wgpu::ComputePipeline,
    count_keepable: wgpu::ComputePipeline,
    retain: wgpu::ComputePipeline,
    free: wgpu::ComputePipeline,
    count_new: wgpu::ComputePipeline,
    scan_new: wgpu::ComputePipeline,
    alloc_new: wgpu::ComputePipeline,
    args: wgpu::ComputePipeline,
    group: Option<wgpu::BindGroup>,
}

impl AllocPass {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let cs = wgpu::ShaderStages::COMPUTE;
        // Eight storage buffers, WebGPU's default per-stage limit.
        let layout = bind_group_layout(
            device,
            "vsm.alloc_layout",
            &[
                uniform_entry(7, cs),
                storage_entry(8, cs),
                storage_rw_entry(9, cs),
                storage_rw_entry(10, cs),
                storage_rw_entry(11, cs),
                storage_entry(12, cs),
                storage_rw_entry(13, cs),
                storage_entry(14, cs),
                storage_rw_entry(15, cs),
            ],
        );
        let code = module(device, "vsm.alloc_shader", &shader());
        let pl = pipeline_layout(device, "vsm.alloc_pipeline_layout", &[&layout]);
        let compute = |label: &str, entry| compute_pipeline(device, label, &pl, &code, entry);
        Self {
            count: compute("vsm.count", "cs_count"),
            count_keepable: compute("vsm.count_keepable", "cs_count_keepable"),
            retain: compute("vsm.retain", "cs_retain"),
            free: compute("vsm.free", "cs_free"),
            count_new: compute("vsm.count_new", "cs_count_new"),
            scan_new: compute("vsm.scan_new", "cs_scan_new"),
            alloc_new: compute("vsm.alloc_new", "cs_alloc_new"),
            args: compute("vsm.args", "cs_args"),
            layout,
            group: None,
        }
    }

    /// Builds the bind group (whenever a buffer it holds was replaced).
    pub(crate) fn bind(
        &mut self,
        device: &wgpu::Device,
        table: &TableBuffers<'_>,
        buffers: &AllocBuffers<'_>,
    ) {
        self.group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vsm.alloc_group"),
            layout: &self.layout,
            entries: &[
                whole_entry(7, table.uniforms),
                whole_entry(8, table.faces),
                whole_entry(9, table.table),
                whole_entry(10, table.counters),
                whole_entry(11, buffers.page_views),
                whole_entry(12, buffers.rounds),
                whole_entry(13, buffers.args),
                whole_entry(14, table.prev_table),
                whole_entry(15, buffers.scratch),
            ],
        }));
    }

    /// Allocates the pages marked in a table of `entries` entries (after the marking).
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>, entries: u32) {
        let Some(group) = &self.group else {
            return;
        };
        let entries = entries as u64;
        // One thread per block of page-table entries, or per entry.
        let blocks = entry_groups(entries.div_ceil(ALLOC_BLOCK));
        let each = entry_groups(entries);
        pass.set_bind_group(0, group, &[]);
        for (pipeline, (x, y)) in [
            (&self.count, blocks),
            (&self.count_keepable, each),
            (&self.retain, each),
            (&self.free, (1, 1)),
            (&self.count_new, blocks),
            (&self.scan_new, (1, 1)),
            (&self.alloc_new, blocks),
        ] {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(x, y, 1);
        }
    }

    /// Writes the page draw's indirect arguments from the pages placed (every frame, with or
    /// without faces).
    pub(crate) fn record_args(&self, pass: &mut wgpu::ComputePass<'_>) {
        let Some(group) = &self.group else {
            return;
        };
        pass.set_bind_group(0, group, &[]);
        pass.set_pipeline(&self.args);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
