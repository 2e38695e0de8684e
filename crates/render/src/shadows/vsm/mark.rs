//! Per-pixel page marking of the virtual shadow maps (step 1 of [`crate::shadows::vsm`],
//! `vsm_mark.wgsl`): one thread per pixel of a rectangle of the screen visits the lights of
//! its cluster and marks the page each needs *asked* (with the receiver bounds of its sample)
//! and that page's ancestors *above*. It is the marking when
//! [`VirtualOptions::tile_marking`](super::plan::VirtualOptions::tile_marking) is off; the
//! tile marking ([`super::tiles`]) composes the same WGSL and hands it what its tiles cannot
//! settle, so both ask for the same pages.

use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::GBuffer;
use crate::gpu::pipelines::{
    bind_group_layout, compute_pipeline, pipeline_layout, storage_entry, storage_rw_entry,
    texture_entry, uniform_entry, whole_entry,
};
use crate::gpu::shaders::{compose, module, COMMON};
use crate::shadows::lookup::{PARABOLOID, SHADOW_LOOKUP};
use crate::shadows::vsm::plan::VSM_COMMON;
use crate::shadows::vsm::table::{TableBuffers, PAGE_TABLE};
use crate::shadows::vsm::types::VSM_TYPES;

/// The marking's WGSL (after `vsm_table.wgsl`): its bindings of the frame, the marking of a
/// sample's pages and `cs_mark`.
pub(crate) const MARK: &str = include_str!("vsm_mark.wgsl");

/// The per-pixel marking: `cs_mark`.
pub(crate) fn shader() -> String {
    compose(&[
        COMMON,
        VSM_TYPES,
        PARABOLOID,
        SHADOW_LOOKUP,
        VSM_COMMON,
        PAGE_TABLE,
        MARK,
    ])
}

/// What the marking reads of the frame.
pub(crate) struct Samples<'a> {
    /// `FrameUniforms`.
    pub frame: &'a wgpu::Buffer,
    /// `array<LightData>`.
    pub lights: &'a wgpu::Buffer,
    /// The G-buffer: the samples' positions and normals.
    pub gbuffer: &'a GBuffer,
    /// The light clusters: which lights each sample visits.
    pub clusters: &'a LightClusters,
}

/// Layout entries of the marking's bindings 0 to 9: the frame's samples (`vsm_mark.wgsl`) and
/// the page table (`vsm_table.wgsl`'s uniforms, faces and entries).
pub(crate) fn sample_layout() -> Vec<wgpu::BindGroupLayoutEntry> {
    let cs = wgpu::ShaderStages::COMPUTE;
    let tex = |binding| texture_entry(binding, wgpu::TextureSampleType::Uint, cs);
    vec![
        uniform_entry(0, cs),
        storage_entry(1, cs),
        tex(2),
        tex(3),
        uniform_entry(4, cs),
        storage_entry(5, cs),
        storage_entry(6, cs),
        uniform_entry(7, cs),
        storage_entry(8, cs),
        storage_rw_entry(9, cs),
    ]
}

/// A bind group of [`sample_layout`]'s bindings and `more`.
pub(crate) fn sample_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    samples: &Samples<'_>,
    table: &TableBuffers<'_>,
    more: &[wgpu::BindGroupEntry<'_>],
) -> wgpu::BindGroup {
    let pv = samples.gbuffer.position.create_view(&Default::default());
    let nv = samples.gbuffer.normal.create_view(&Default::default());
    let mut entries = vec![
        whole_entry(0, samples.frame),
        whole_entry(1, samples.lights),
        wgpu::BindGroupEntry {
            binding: 2,
            resource: wgpu::BindingResource::TextureView(&pv),
        },
        wgpu::BindGroupEntry {
            binding: 3,
            resource: wgpu::BindingResource::TextureView(&nv),
        },
        whole_entry(4, &samples.clusters.uniforms),
        whole_entry(5, &samples.clusters.slots),
        whole_entry(6, &samples.clusters.masks),
        whole_entry(7, table.uniforms),
        whole_entry(8, table.faces),
        whole_entry(9, table.table),
    ];
    entries.extend_from_slice(more);
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// The per-pixel marking pass: its layout, pipeline and bind group.
pub(crate) struct MarkPass {
    layout: wgpu::BindGroupLayout,
    mark: wgpu::ComputePipeline,
    group: Option<wgpu::BindGroup>,
}

impl MarkPass {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let layout = bind_group_layout(device, "vsm.mark_layout", &sample_layout());
        let code = module(device, "vsm.mark_shader", &shader());
        let pl = pipeline_layout(device, "vsm.mark_pipeline_layout", &[&layout]);
        let mark = compute_pipeline(device, "vsm.mark", &pl, &code, "cs_mark");
        Self {
            layout,
            mark,
            group: None,
        }
    }

    /// Builds the bind group (whenever a buffer it holds was replaced).
    pub(crate) fn bind(
        &mut self,
        device: &wgpu::Device,
        samples: &Samples<'_>,
        table: &TableBuffers<'_>,
    ) {
        self.group = Some(sample_group(
            device,
            "vsm.mark_group",
            &self.layout,
            samples,
            table,
            &[],
        ));
    }

    /// Marks the pages the pixels of `rect` (x0, y0, x1, y1; its first pixel is
    /// `VsmUniforms::lod.yz`) need.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>, [x0, y0, x1, y1]: [u32; 4]) {
        let Some(group) = &self.group else {
            return;
        };
        pass.set_bind_group(0, group, &[]);
        pass.set_pipeline(&self.mark);
        pass.dispatch_workgroups((x1 - x0).div_ceil(8), (y1 - y0).div_ceil(8), 1);
    }
}
