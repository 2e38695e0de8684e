//! Copying the lit frame into a texture the caller owns ([`crate::Renderer::render_to`]): a
//! full-target triangle that loads the nearest texel of the frame, so the target may have any
//! size and any renderable colour format. One pipeline per target format, built on first use.

use std::collections::HashMap;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;

/// The blit pipelines and their shared layout.
pub(crate) struct Blit {
    module: wgpu::ShaderModule,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    params: wgpu::Buffer,
    /// Bind group of the frame texture it was made for.
    group: Option<(wgpu::Texture, wgpu::BindGroup)>,
}

impl Blit {
    pub(crate) fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let module = crate::gpu::shaders::module(device, "blit.shader", include_str!("blit.wgsl"));
        let fs = wgpu::ShaderStages::FRAGMENT;
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "blit.layout",
            &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: fs,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                crate::gpu::pipelines::uniform_entry(1, fs),
            ],
        );
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "blit.pipeline_layout", &[&layout]);
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blit.params"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            module,
            layout,
            pipeline_layout,
            pipelines: HashMap::new(),
            params,
            group: None,
        }
    }

    /// Records the copy of `frame` into `target` (which must allow `RENDER_ATTACHMENT`).
    pub(crate) fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &wgpu::Texture,
        target: &wgpu::Texture,
    ) -> Result<(), RenderError> {
        if !target
            .usage()
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        {
            return Err(RenderError::UnsupportedTarget {
                format: target.format(),
                needs: "RENDER_ATTACHMENT usage",
            });
        }
        if target.dimension() != wgpu::TextureDimension::D2 || target.sample_count() != 1 {
            return Err(RenderError::UnsupportedTarget {
                format: target.format(),
                needs: "to be a single-sampled 2D texture",
            });
        }
        let format = target.format();
        if format.is_depth_stencil_format()
            || !matches!(
                format.sample_type(None, None),
                Some(wgpu::TextureSampleType::Float { .. })
            )
        {
            return Err(RenderError::UnsupportedTarget {
                format,
                needs: "a floating-point or normalized colour format",
            });
        }
        let device = &ctx.device;
        let pipeline = self.pipelines.entry(format).or_insert_with(|| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("blit.pipeline"),
                layout: Some(&self.pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some("vs_blit"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some("fs_blit"),
                    compilation_options: Default::default(),
                    targets: &[Some(format.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        });
        if self.group.as_ref().is_none_or(|(t, _)| t != frame) {
            let view = frame.create_view(&wgpu::TextureViewDescriptor::default());
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("blit.bind_group"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: self.params.as_entire_binding(),
                    },
                ],
            });
            self.group = Some((frame.clone(), group));
        }
        // 8-bit targets that store raw values get sRGB-encoded values (what the frame holds);
        // sRGB targets and float targets get linear light, encoded by the hardware if at all.
        let encode = !format.is_srgb()
            && matches!(
                format,
                wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Bgra8Unorm
            );
        let params = [
            target.width() as f32,
            target.height() as f32,
            if encode { 1.0 } else { 0.0 },
            0.0,
        ];
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::cast_slice(&params));
        let view = target.create_view(&wgpu::TextureViewDescriptor::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("blit"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.group.as_ref().expect("bind group").1, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }
}

#[cfg(test)]
mod shader_tests {
    /// What this module composes is WGSL a WebGPU device accepts.
    #[test]
    fn shader_validates_for_webgpu() {
        crate::gpu::shaders::validate_for_webgpu(
            "blit",
            include_str!("blit.wgsl"),
            wgpu::Features::empty(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}
