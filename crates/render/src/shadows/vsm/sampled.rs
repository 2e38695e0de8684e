//! Virtual maps' page marking under sampled lights (`vsm_sampled.wgsl`): only the pages of the
//! (pixel, light) pairs the sampled lights' choose pass noted (`sampled::pages`), instead of
//! every light of a pixel's cluster ([`super::mark`]), and the pages such pairs asked for within
//! the last frames ([`VirtualOptions::sampled_keep_frames`](super::plan::VirtualOptions)), so that samples that change from frame to frame reuse pages
//! instead of drawing them again. It marks in place of the per-pixel or tile marking, every
//! frame (the pairs change, so last frame's marks never carry over whole).

use crate::gpu::pipelines::{
    bind_group_layout, compute_pipeline, pipeline_layout, storage_entry, storage_rw_entry,
    whole_entry,
};
use crate::gpu::shaders::module;
use crate::shadows::vsm::mark::{sample_group, sample_layout, Samples};
use crate::shadows::vsm::table::{entry_groups, TableBuffers, TABLE_WORDS};

/// The marking of sampled pairs: its layout, pipelines, bind group and the entries' ages (this
/// frame's and last frame's).
pub(crate) struct SampledMarking {
    layout: wgpu::BindGroupLayout,
    mark: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
    keep: wgpu::ComputePipeline,
    group: Option<wgpu::BindGroup>,
    ages: wgpu::Buffer,
    prev_ages: wgpu::Buffer,
}

impl SampledMarking {
    /// The marking that keeps pages `keep_frames` frames after a sample last asked for them.
    pub(crate) fn new(device: &wgpu::Device, keep_frames: u32) -> Self {
        let cs = wgpu::ShaderStages::COMPUTE;
        let mut entries = sample_layout();
        entries.extend([
            storage_rw_entry(10, cs),
            storage_entry(14, cs),
            storage_entry(15, cs),
            storage_rw_entry(16, cs),
            storage_entry(17, cs),
        ]);
        let layout = bind_group_layout(device, "vsm.sampled_layout", &entries);
        let code = module(
            device,
            "vsm.sampled_shader",
            &format!(
                "{}const KEEP_FRAMES: u32 = {keep_frames}u;\n{}{}",
                super::mark::shader(),
                crate::sampled::pages::wants_wgsl(),
                include_str!("vsm_sampled.wgsl")
            ),
        );
        let pl = pipeline_layout(device, "vsm.sampled_pipeline_layout", &[&layout]);
        Self {
            mark: compute_pipeline(device, "vsm.mark_wanted", &pl, &code, "cs_mark_wanted"),
            count: compute_pipeline(device, "vsm.count_asked", &pl, &code, "cs_count_asked"),
            keep: compute_pipeline(device, "vsm.keep_recent", &pl, &code, "cs_keep_recent"),
            layout,
            group: None,
            ages: ages_buffer(device, "vsm.ages", 4),
            prev_ages: ages_buffer(device, "vsm.prev_ages", 4),
        }
    }

    /// Builds the bind group (whenever a buffer it holds was replaced), with the choose pass's
    /// notes `wants`: ages for as many entries as the table holds (those of a table that grew
    /// start anew).
    pub(crate) fn bind(
        &mut self,
        device: &wgpu::Device,
        samples: &Samples<'_>,
        table: &TableBuffers<'_>,
        wants: &wgpu::Buffer,
    ) {
        let bytes = (table.table.size() / (TABLE_WORDS * 4)).max(1) * 4;
        if self.ages.size() < bytes {
            self.ages = ages_buffer(device, "vsm.ages", bytes);
            self.prev_ages = ages_buffer(device, "vsm.prev_ages", bytes);
        }
        self.group = Some(sample_group(
            device,
            "vsm.sampled_group",
            &self.layout,
            samples,
            table,
            &[
                whole_entry(10, table.counters),
                whole_entry(14, table.prev_table),
                whole_entry(15, wants),
                whole_entry(16, &self.ages),
                whole_entry(17, &self.prev_ages),
            ],
        ));
    }

    /// Before the frame's passes: last frame's ages (of `prev_entries` entries) become the
    /// ones read, this frame's start at 0.
    pub(crate) fn begin(&self, encoder: &mut wgpu::CommandEncoder, prev_entries: u32) {
        let bytes = (u64::from(prev_entries) * 4).min(self.ages.size());
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(&self.ages, 0, &self.prev_ages, 0, bytes);
        }
        encoder.clear_buffer(&self.ages, 0, None);
    }

    /// Marks the pages of the sampled pairs of the pixels of `rect` (x0, y0, x1, y1; its
    /// first pixel is `VsmUniforms::lod.yz`), then counts them and asks again, in a table of
    /// `entries` entries, for those resident last frame that samples asked for within the
    /// frames kept, while the pool has room (`vsm_sampled.wgsl`'s `KEEP_SHARE`).
    pub(crate) fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        [x0, y0, x1, y1]: [u32; 4],
        entries: u32,
    ) {
        let Some(group) = &self.group else {
            return;
        };
        pass.set_bind_group(0, group, &[]);
        pass.set_pipeline(&self.mark);
        pass.dispatch_workgroups((x1 - x0).div_ceil(8), (y1 - y0).div_ceil(8), 1);
        let (x, y) = entry_groups(u64::from(entries));
        pass.set_pipeline(&self.count);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&self.keep);
        pass.dispatch_workgroups(x, y, 1);
    }
}

fn ages_buffer(device: &wgpu::Device, label: &str, bytes: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}
