//! A fence between drawing and the compute passes after it, on OpenGL only.
//!
//! Mesa's llvmpipe runs a compute dispatch at once, on its own threads, while the draws
//! recorded before it may still wait to be binned and rasterized: a compute pass that reads
//! what a render pass wrote (the G-buffer, an atlas) can read it half drawn, and one that
//! writes a buffer a pending draw reads can change it under the draw. wgpu's OpenGL backend
//! emits `glMemoryBarrier` only after storage writes (WebGPU's rules need none between a
//! render attachment and a later read), and llvmpipe's `glMemoryBarrier` finishes every
//! pending draw. Without the fence a renderer's second frame could differ from its first:
//! the clusters' marking read a G-buffer whose last draws had not landed (docs/decisions.md,
//! "On OpenGL every compute pass of a frame starts with a fence").
//!
//! The fence is a compute pass of two dispatches that write one word of a storage buffer:
//! between the two, wgpu sees a storage write followed by another and emits the barrier in
//! place, after everything recorded before. Every compute pass of a frame begins through
//! [`RasterFence::begin_compute_pass`] (`GpuContext::raster_fence`, which passes keep a clone
//! of), which records the fence first; on other backends it records the pass alone (Vulkan's
//! barriers come from wgpu's usage tracking).

const SOURCE: &str = "
@group(0) @binding(0) var<storage, read_write> word: array<u32, 1>;
@compute @workgroup_size(1, 1, 1)
fn cs_fence() {
    word[0] = word[0] + 1u;
}
";

/// The fence (a cheap handle: clones share the pipeline); inert on every backend but OpenGL.
#[derive(Clone, Debug, Default)]
pub(crate) struct RasterFence(Option<std::sync::Arc<Fence>>);

/// The fence's pipeline and its one-word buffer.
#[derive(Debug)]
struct Fence {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl RasterFence {
    /// The fence `backend` needs: a pipeline on OpenGL, nothing elsewhere.
    pub(crate) fn new(device: &wgpu::Device, backend: wgpu::Backend) -> Self {
        Self((backend == wgpu::Backend::Gl).then(|| std::sync::Arc::new(Fence::new(device))))
    }

    /// Begins a compute pass of the frame after the fence: everything recorded before it in
    /// `encoder` is finished before the pass runs (only the pass where the fence is inert).
    /// Every compute pass of a frame begins here.
    pub(crate) fn begin_compute_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        desc: &wgpu::ComputePassDescriptor<'_>,
    ) -> wgpu::ComputePass<'e> {
        if let Some(f) = &self.0 {
            f.record(encoder);
        }
        encoder.begin_compute_pass(desc)
    }
}

impl Fence {
    fn new(device: &wgpu::Device) -> Self {
        let module = super::shaders::module(device, "raster_fence.shader", SOURCE);
        let layout = super::pipelines::bind_group_layout(
            device,
            "raster_fence.layout",
            &[super::pipelines::storage_rw_entry(
                0,
                wgpu::ShaderStages::COMPUTE,
            )],
        );
        let pipeline_layout =
            super::pipelines::pipeline_layout(device, "raster_fence.pipeline_layout", &[&layout]);
        let pipeline = super::pipelines::compute_pipeline(
            device,
            "raster_fence.pipeline",
            &pipeline_layout,
            &module,
            "cs_fence",
        );
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raster_fence.word"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let bind_group = super::pipelines::buffer_bind_group(
            device,
            "raster_fence.bind_group",
            &layout,
            &[&buffer],
        );
        Self {
            pipeline,
            bind_group,
        }
    }

    fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("raster_fence.pass"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        // The first dispatch's barrier (from the last frame's fence) wgpu may place at the
        // start of the submission; the second's lies here.
        pass.dispatch_workgroups(1, 1, 1);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
