//! The deferred Phong lighting pass (seed 004): reads the G-buffer, the pixel's light cluster
//! and the frame's shadows (through the source's lookup, or its mask), writes the final
//! colour.

use crate::frame::gbuffer::GBuffer;
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::shading::look::ShadingConsts;
use crate::shadows::lookup::{compose_reader, LookupWgsl};
use crate::shadows::source::ShadowOutput;

/// First binding of a shadow source's own declarations (the virtual maps' page table, the
/// ray-traced scene) in the lighting and visibility passes.
pub(crate) const SOURCE_FIRST_BINDING: u32 = 14;

/// Output colour format (sRGB-encoded on write).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// The lighting pass's WGSL, shadows found through `lookup` (its declarations from
/// `SOURCE_FIRST_BINDING`), shading as `consts` say.
pub(crate) fn shader(lookup: &LookupWgsl, consts: &ShadingConsts) -> String {
    let pass = format!(
        "{}{}{}",
        consts.wgsl(),
        include_str!("lighting.wgsl"),
        include_str!("sampled.wgsl")
    );
    compose_reader(lookup, SOURCE_FIRST_BINDING, &pass)
}

/// The lighting pass and its output image.
pub struct LightingPass {
    /// The shaded frame.
    pub color: wgpu::Texture,
    /// Render-target view of `color`, made once.
    color_view: wgpu::TextureView,
    pipeline: wgpu::RenderPipeline,
    /// `fs_composite` over `color`, after the denoiser (only when rays are denoised).
    composite: Option<wgpu::RenderPipeline>,
    /// `fs_spatial` over `color`, after the pass (only with spatial reuse).
    spatial: Option<wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    no_emission: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
}

/// Buffers the lighting and visibility passes read.
pub struct LightingInputs<'a> {
    /// `FrameUniforms`.
    pub frame: &'a wgpu::Buffer,
    /// `array<LightData>`.
    pub lights: &'a wgpu::Buffer,
    /// `array<MaterialData>`.
    pub materials: &'a wgpu::Buffer,
    /// G-buffer.
    pub gbuffer: &'a GBuffer,
    /// The clustered light lists.
    pub clusters: &'a crate::frame::clusters::LightClusters,
    /// What the frame's shadow source produced: an atlas, a page pool (both read with the
    /// shadow test, `fs_main`) or a visibility mask (shaded with directly, `fs_mask`).
    pub shadows: ShadowOutput<'a>,
    /// The denoiser's buffers, when sampled rays are denoised (`ShadingConsts::denoise`).
    pub denoise: Option<&'a crate::shading::denoise::DenoiseBuffers>,
    /// The reservoirs, when sampled lights are reused (`ShadingConsts::reuse`).
    pub reuse: Option<&'a crate::shading::reuse::ReuseBuffers>,
    /// The reflection probes' faces, when surfaces mirror them (`ShadingConsts::probes`).
    pub probes: Option<&'a crate::shading::probes::ProbeMaps>,
}

impl LightingInputs<'_> {
    /// The depth texture shadows are read from: the virtual maps' page pool or the atlas.
    pub fn shadow_texture(&self) -> &wgpu::TextureView {
        self.shadows.depth
    }

    /// The bind-group entries the lighting and the visibility pass both declare, at the same
    /// bindings: frame 0, lights 1, shadow views 2, G-buffer position 4 (`position`) and
    /// normal 5 (`normal`), the shadow texture 6, the visibility mask 8 (`mask`), the light
    /// clusters 9–11 and the shadow source's own declarations from `SOURCE_FIRST_BINDING`. Bindings 3
    /// and 7 are each pass's own.
    pub(crate) fn shared_entries<'s>(
        &'s self,
        position: &'s wgpu::TextureView,
        normal: &'s wgpu::TextureView,
        mask: &'s wgpu::Buffer,
    ) -> Vec<wgpu::BindGroupEntry<'s>> {
        let mut entries = vec![
            crate::gpu::pipelines::whole_entry(0, self.frame),
            crate::gpu::pipelines::whole_entry(1, self.lights),
            crate::gpu::pipelines::whole_entry(2, self.shadows.view_table),
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::TextureView(position),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: wgpu::BindingResource::TextureView(normal),
            },
            wgpu::BindGroupEntry {
                binding: 6,
                resource: wgpu::BindingResource::TextureView(self.shadow_texture()),
            },
            crate::gpu::pipelines::whole_entry(8, mask),
            crate::gpu::pipelines::whole_entry(9, &self.clusters.uniforms),
            crate::gpu::pipelines::whole_entry(10, &self.clusters.slots),
            crate::gpu::pipelines::whole_entry(11, &self.clusters.masks),
        ];
        entries.extend(self.shadows.extra_entries(SOURCE_FIRST_BINDING));
        entries
    }
}

impl LightingPass {
    /// Creates the output texture and pipeline.
    pub(crate) fn new(
        ctx: &GpuContext,
        inputs: &LightingInputs<'_>,
        (w, h): (u32, u32),
        consts: &ShadingConsts,
    ) -> Self {
        let entry = if inputs.shadows.mask.is_some() {
            "fs_mask"
        } else {
            "fs_main"
        };
        Self::with_entry(ctx, inputs, (w, h), entry, consts)
    }

    /// The pass shading with given fractions per pixel and light (`inputs.shadows.mask` holds
    /// them, a byte each) instead of the shadow source's answer.
    pub(crate) fn with_fractions(
        ctx: &GpuContext,
        inputs: &LightingInputs<'_>,
        (w, h): (u32, u32),
        consts: &ShadingConsts,
    ) -> Self {
        Self::with_entry(ctx, inputs, (w, h), "fs_fraction", consts)
    }

    fn with_entry(
        ctx: &GpuContext,
        inputs: &LightingInputs<'_>,
        (w, h): (u32, u32),
        entry: &'static str,
        consts: &ShadingConsts,
    ) -> Self {
        let device = &ctx.device;
        // A probe's faces keep linear radiance; the frame its tone-mapped colour.
        let format = if consts.linear_out {
            crate::shading::probes::FACE_FORMAT
        } else {
            COLOR_FORMAT
        };
        let color = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("lighting.color"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let frag = wgpu::ShaderStages::FRAGMENT;
        let cmp = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: frag,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
            count: None,
        };
        let mut entries = vec![
            crate::gpu::pipelines::uniform_entry(0, frag),
            crate::gpu::pipelines::storage_entry(1, frag),
            crate::gpu::pipelines::storage_entry(2, frag),
            crate::gpu::pipelines::storage_entry(3, frag),
            crate::gpu::pipelines::texture_entry(4, wgpu::TextureSampleType::Uint, frag),
            crate::gpu::pipelines::texture_entry(5, wgpu::TextureSampleType::Uint, frag),
            crate::gpu::pipelines::texture_entry(6, wgpu::TextureSampleType::Depth, frag),
            cmp(7),
            crate::gpu::pipelines::storage_entry(8, frag),
            crate::gpu::pipelines::uniform_entry(9, frag),
            crate::gpu::pipelines::storage_entry(10, frag),
            crate::gpu::pipelines::storage_entry(11, frag),
            crate::gpu::pipelines::texture_entry(
                12,
                wgpu::TextureSampleType::Float { filterable: false },
                frag,
            ),
            crate::gpu::pipelines::texture_entry(
                13,
                wgpu::TextureSampleType::Float { filterable: false },
                frag,
            ),
        ];
        entries.extend(inputs.shadows.extra_layout(SOURCE_FIRST_BINDING, frag));
        if consts.denoise {
            entries.push(crate::gpu::pipelines::storage_rw_entry(40, frag));
            entries.push(crate::gpu::pipelines::storage_rw_entry(41, frag));
        }
        if consts.reuse {
            entries.push(crate::gpu::pipelines::uniform_entry(42, frag));
            entries.push(crate::gpu::pipelines::storage_rw_entry(43, frag));
            entries.push(crate::gpu::pipelines::texture_entry(
                47,
                wgpu::TextureSampleType::Uint,
                frag,
            ));
            entries.push(crate::gpu::pipelines::storage_entry(48, frag));
        }
        if consts.probes {
            entries.push(wgpu::BindGroupLayoutEntry {
                binding: 44,
                visibility: frag,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            });
            entries.push(wgpu::BindGroupLayoutEntry {
                binding: 45,
                visibility: frag,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            });
            entries.push(crate::gpu::pipelines::uniform_entry(46, frag));
        }
        let layout = crate::gpu::pipelines::bind_group_layout(device, "lighting.layout", &entries);
        let linear = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("lighting.cmp_linear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        // Bound where the G-buffer keeps no emissive texels (never read then:
        // `EMISSION_TEXTURE` is false); made once per pass, not per bind.
        let no_emission = crate::gpu::pipelines::one_texel_view(
            &ctx.device,
            "lighting.no_emission",
            crate::frame::gbuffer::EMISSION_FORMAT,
        );
        let bind_group = bind(ctx, &layout, &linear, &no_emission, inputs);
        let module = crate::gpu::shaders::module(
            device,
            "lighting.shader",
            &shader(&inputs.shadows.lookup, consts),
        );
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "lighting.pipeline_layout", &[&layout]);
        let fullscreen = |entry: &str| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_fullscreen"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    targets: &[Some(format.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let pipeline = fullscreen(entry);
        let composite = consts.denoise.then(|| fullscreen("fs_composite"));
        let spatial = (consts.reuse && consts.spatial != 0).then(|| fullscreen("fs_spatial"));
        Self {
            color_view: color.create_view(&Default::default()),
            color,
            pipeline,
            composite,
            spatial,
            layout,
            sampler: linear,
            no_emission,
            bind_group,
        }
    }

    /// Binds new inputs (after a frame's update replaced a buffer or the atlas).
    pub fn rebind(&mut self, ctx: &GpuContext, inputs: &LightingInputs<'_>) {
        self.bind_group = bind(ctx, &self.layout, &self.sampler, &self.no_emission, inputs);
    }

    /// Records the pass (with a denoiser, the first of the span: [`LightingPass::record_composite`]
    /// ends it).
    /// With spatial reuse its pass follows, in the same span.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: &GpuTimer, span: Option<Span>) {
        let last = self.spatial.is_none();
        self.fullscreen_pass(
            encoder,
            &self.pipeline,
            timer.render_writes(span, true, last),
        );
        if let Some(spatial) = &self.spatial {
            self.fullscreen_pass(encoder, spatial, timer.render_writes(span, false, true));
        }
    }

    /// Records the pass into `target` (a view of the pass's format and size: a probe's face
    /// layer), writing the span's first (`begin`) and last (`end`) timestamps as asked (a
    /// probe's faces lit one after another, timed as one span).
    pub(crate) fn record_into(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        (timer, span): (&GpuTimer, Option<Span>),
        (begin, end): (bool, bool),
    ) {
        let writes = timer.render_writes(span, begin, end);
        self.pass_into(encoder, target, &self.pipeline, writes);
    }

    /// With a denoiser: shades the filtered ratio into the frame (after the denoiser's passes),
    /// ending the denoiser's span (`Stage::Denoise`, begun by its passes).
    pub fn record_composite(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        if let Some(composite) = &self.composite {
            self.fullscreen_pass(encoder, composite, timer.render_writes(span, false, true));
        }
    }

    fn fullscreen_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        self.pass_into(encoder, &self.color_view, pipeline, timestamp_writes);
    }

    fn pass_into(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        pipeline: &wgpu::RenderPipeline,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lighting.pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

fn bind(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    sampler: &wgpu::Sampler,
    no_emission: &wgpu::TextureView,
    inputs: &LightingInputs<'_>,
) -> wgpu::BindGroup {
    let device = &ctx.device;
    // `fs_main` never reads the mask, but one layout serves both entry points.
    let dummy_mask;
    let mask = match inputs.shadows.mask {
        Some(m) => m,
        None => {
            dummy_mask = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lighting.no_mask"),
                size: 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            &dummy_mask
        }
    };
    let pv = inputs.gbuffer.position.create_view(&Default::default());
    let nv = inputs.gbuffer.normal.create_view(&Default::default());
    // The G-buffer's emissive texels, or the white texel where it keeps none.
    let ev = inputs
        .gbuffer
        .emission
        .as_ref()
        .map(|t| t.create_view(&Default::default()));
    let ev = ev.as_ref().unwrap_or(no_emission);
    let mut entries = inputs.shared_entries(&pv, &nv, mask);
    entries.extend([
        wgpu::BindGroupEntry {
            binding: 3,
            resource: inputs.materials.as_entire_binding(),
        },
        wgpu::BindGroupEntry {
            binding: 7,
            resource: wgpu::BindingResource::Sampler(sampler),
        },
        wgpu::BindGroupEntry {
            binding: 12,
            resource: wgpu::BindingResource::TextureView(inputs.shadow_texture()),
        },
        wgpu::BindGroupEntry {
            binding: 13,
            resource: wgpu::BindingResource::TextureView(ev),
        },
    ]);
    if let Some(d) = inputs.denoise {
        entries.push(crate::gpu::pipelines::whole_entry(40, &d.pixels));
        entries.push(crate::gpu::pipelines::whole_entry(41, &d.ratio));
    }
    if let Some(r) = inputs.reuse {
        entries.push(crate::gpu::pipelines::whole_entry(42, &r.params));
        entries.push(crate::gpu::pipelines::whole_entry(43, &r.reservoirs));
        entries.push(wgpu::BindGroupEntry {
            binding: 47,
            resource: wgpu::BindingResource::TextureView(&r.instance),
        });
        entries.push(crate::gpu::pipelines::whole_entry(48, &r.motion_back));
    }
    if let Some(p) = inputs.probes {
        entries.push(wgpu::BindGroupEntry {
            binding: 44,
            resource: wgpu::BindingResource::TextureView(&p.view),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 45,
            resource: wgpu::BindingResource::Sampler(&p.sampler),
        });
        entries.push(crate::gpu::pipelines::whole_entry(46, &p.data));
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("lighting.bind_group"),
        layout,
        entries: &entries,
    })
}

#[cfg(test)]
mod shader_tests {
    /// With the atlas lookup the pass is WGSL a WebGPU device accepts (every technique's own
    /// lookup is checked by the registry's tests).
    #[test]
    fn shader_validates_for_webgpu() {
        let src = super::shader(
            &crate::shadows::lookup::ATLAS_LOOKUP,
            &crate::shading::look::ShadingConsts::default(),
        );
        crate::gpu::shaders::validate_for_webgpu("lighting", &src, wgpu::Features::empty())
            .unwrap_or_else(|e| panic!("{e}"));
    }

    /// With reflection probes, and as a probe's faces are lit (linear output), too.
    #[test]
    fn shader_with_probes_validates_for_webgpu() {
        for (probes, linear_out) in [(true, false), (false, true)] {
            let src = super::shader(
                &crate::shadows::lookup::ATLAS_LOOKUP,
                &crate::shading::look::ShadingConsts {
                    probes,
                    linear_out,
                    ..Default::default()
                },
            );
            crate::gpu::shaders::validate_for_webgpu("lighting", &src, wgpu::Features::empty())
                .unwrap_or_else(|e| panic!("probes {probes}, linear {linear_out}: {e}"));
        }
    }
}
