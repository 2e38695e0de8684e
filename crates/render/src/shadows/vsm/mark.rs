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

/// The marking of sampled pairs (`cs_mark_wanted`, after [`MARK`]): per pixel, the pages of
/// the lights the sampled lights' choose pass noted (`sampled::pages`) instead of every light
/// of its cluster.
const MARK_WANTED: &str = "
@group(0) @binding(15) var<storage, read> page_wants: array<u32>;

// `sampled/lights.wgsl`'s notes per pixel: 2 per sample and 2 more; none past the first
// 0xffffffff.
fn wants_per_pixel() -> u32 {
    return 2u * u32(frame.soft.w) + 2u;
}

@compute @workgroup_size(8, 8, 1)
fn cs_mark_wanted(@builtin(global_invocation_id) id: vec3<u32>) {
    let px = id.xy + vec2<u32>(vsm.lod.yz);
    let s = pixel_sample(px);
    if (!s.valid) {
        return;
    }
    let stride = wants_per_pixel();
    let base = (px.y * u32(frame.viewport.x) + px.x) * stride;
    for (var n = 0u; n < stride; n = n + 1u) {
        let i = page_wants[base + n];
        if (i >= frame.counts.x) {
            return;
        }
        mark_light(i, s.p, s.n, s.view_depth);
    }
}
";

/// The per-pixel marking of sampled pairs: its layout, pipeline and bind group (with the
/// notes bound).
struct WantedPass {
    layout: wgpu::BindGroupLayout,
    mark: wgpu::ComputePipeline,
    group: Option<wgpu::BindGroup>,
}

/// The per-pixel marking pass: its layout, pipeline and bind group; and, made when first
/// bound with the sampled lights' notes, the marking of their pairs alone.
pub(crate) struct MarkPass {
    layout: wgpu::BindGroupLayout,
    mark: wgpu::ComputePipeline,
    group: Option<wgpu::BindGroup>,
    wanted: Option<WantedPass>,
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
            wanted: None,
        }
    }

    /// Builds the bind group (whenever a buffer it holds was replaced); with `wants`, the
    /// sampled pairs' marking too, which then marks instead.
    pub(crate) fn bind(
        &mut self,
        device: &wgpu::Device,
        samples: &Samples<'_>,
        table: &TableBuffers<'_>,
        wants: Option<&wgpu::Buffer>,
    ) {
        self.group = Some(sample_group(
            device,
            "vsm.mark_group",
            &self.layout,
            samples,
            table,
            &[],
        ));
        let Some(wants) = wants else {
            self.wanted = None;
            return;
        };
        let wanted = self.wanted.get_or_insert_with(|| {
            let mut entries = sample_layout();
            entries.push(storage_entry(15, wgpu::ShaderStages::COMPUTE));
            let layout = bind_group_layout(device, "vsm.mark_wanted_layout", &entries);
            let code = module(
                device,
                "vsm.mark_wanted_shader",
                &format!("{}{MARK_WANTED}", shader()),
            );
            let pl = pipeline_layout(device, "vsm.mark_wanted_pipeline_layout", &[&layout]);
            let mark = compute_pipeline(device, "vsm.mark_wanted", &pl, &code, "cs_mark_wanted");
            WantedPass {
                layout,
                mark,
                group: None,
            }
        });
        wanted.group = Some(sample_group(
            device,
            "vsm.mark_wanted_group",
            &wanted.layout,
            samples,
            table,
            &[whole_entry(15, wants)],
        ));
    }

    /// Whether the pass marks the sampled pairs alone ([`Self::record_wanted`]).
    pub(crate) fn wanted(&self) -> bool {
        self.wanted.is_some()
    }

    /// Marks the pages of the sampled pairs of the pixels of `rect` (as [`Self::record`]).
    pub(crate) fn record_wanted(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        [x0, y0, x1, y1]: [u32; 4],
    ) {
        let Some(WantedPass {
            mark,
            group: Some(group),
            ..
        }) = &self.wanted
        else {
            return;
        };
        pass.set_bind_group(0, group, &[]);
        pass.set_pipeline(mark);
        pass.dispatch_workgroups((x1 - x0).div_ceil(8), (y1 - y0).div_ceil(8), 1);
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
