//! The deferred lighting pass (seed 004): reads the G-buffer, the pixel's light cluster and
//! the frame's shadows (through the source's lookup, or its mask), writes the final colour.
//!
//! Its bindings are declared once, here ([`LIGHTING`]) and by what plugs into it: the frame's
//! inputs (`inputs.rs`), the shadow source's lookup, then each part the renderer hands it
//! (sampled lights and their histories, reflection probes: `gpu::bindings::Part`, made in their
//! own folders). `gpu::bindings` numbers them in that order and writes their WGSL
//! declarations; `lighting.wgsl` and the parts' WGSL only use the names.

use std::collections::HashMap;

use crate::error::RenderError;
use crate::gpu::bindings::{Binding, BindingList, Part};
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::shading::inputs::{pass_bindings, FrameInputs, CLUSTERS, FRAME, GBUFFER};
use crate::shading::look::ShadingConsts;
use crate::shadows::lookup::{compose_reader, LookupWgsl};

/// Output colour format (sRGB-encoded on write).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// Output format of linear radiance (`ShadingConsts::linear_out`: a probe's faces).
pub const LINEAR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The lighting pass's own bindings beside the frame's inputs (`FRAME` first, then these in
/// order, then `CLUSTERS`, then [`LIGHTING_AFTER_CLUSTERS`]).
pub const LIGHTING: &[Binding] = &[Binding::storage("materials", "array<MaterialData>")];

/// The shadow texture for comparison sampling; the one comparison sampler of every PCF mode
/// (OpenGL cannot pair one texture with two samplers; at a texel centre bilinear weights are
/// (1, 0, 0, 0), so a lookup there compares exactly one texel, as a nearest-filtered one
/// would); and the visibility computed elsewhere (`fs_mask`: `counts.w` words per pixel, bit
/// set = lit; `fs_fraction`: a byte per pixel and light, 255 = all of the light), or, where the
/// source computes none, the (pixel, light) pairs the choose pass notes
/// ([`LightingInputs::wants`]; a dummy without).
pub const LIGHTING_SHADOWS: &[Binding] = &[
    Binding::texture_depth("atlas"),
    Binding::sampler_comparison("cmp_linear"),
    Binding::storage_rw("vis_mask", "array<u32>"),
];

/// The shadow texture's raw depths for the soft shadows' blocker search (the same texture
/// read as floats: OpenGL cannot pair one texture with two samplers), and the emissive texel
/// of each pixel's material (a white texel where the G-buffer keeps none; `EMISSION_TEXTURE`
/// is false then).
pub const LIGHTING_AFTER_CLUSTERS: &[Binding] = &[
    Binding::texture_f32("atlas_depth"),
    Binding::texture_f32("gbuf_emission"),
];

/// The lighting pass's bindings with `lookup` and `parts`.
fn bindings(lookup: &LookupWgsl, parts: &[Part<'_>]) -> BindingList {
    pass_bindings(
        &[
            FRAME,
            LIGHTING,
            GBUFFER,
            LIGHTING_SHADOWS,
            CLUSTERS,
            LIGHTING_AFTER_CLUSTERS,
        ],
        lookup.bindings,
        parts,
    )
}

/// Refuses, naming the limit and the buffers, a lighting pass whose storage buffers (the frame's
/// and the shadow source's, and those of the parts plugged in: the denoiser's, the reservoirs)
/// are more than the device binds in one stage: measured in Chromium's WebGPU on SwiftShader,
/// which allows 10, virtual maps with reuse and the denoiser need 12 (the layout's creation
/// failed with a validation error).
pub fn check_limits(ctx: &GpuContext, inputs: &LightingInputs<'_>) -> Result<(), RenderError> {
    let buffers = bindings(&inputs.frame.shadows.lookup, &inputs.parts).storage_buffers();
    let max = ctx.limits().max_storage_buffers_per_shader_stage;
    if buffers.len() as u32 <= max {
        return Ok(());
    }
    Err(RenderError::LimitsTooSmall {
        adapter: ctx.describe(),
        needs: "the lighting pass".into(),
        shortfalls: vec![format!(
            "max_storage_buffers_per_shader_stage: the device allows {max}, the lighting pass \
             needs {} ({}); fewer parts plugged in need fewer (drop reuse or the denoiser)",
            buffers.len(),
            buffers.join(", ")
        )],
    })
}

/// The lighting pass's WGSL, shadows found through `lookup`, with `parts`, shading as `consts`
/// say.
pub fn shader(lookup: &LookupWgsl, consts: &ShadingConsts, parts: &[Part<'_>]) -> String {
    let mut pass = format!("{}{}", consts.wgsl(), include_str!("lighting.wgsl"));
    for p in parts {
        pass.push_str(&p.wgsl);
    }
    compose_reader(lookup, &bindings(lookup, parts), &pass)
}

/// What the lighting pass reads: the frame's inputs and the parts plugged into it.
pub struct LightingInputs<'a> {
    /// The frame's uniforms, lights, G-buffer, clusters and shadows.
    pub frame: FrameInputs<'a>,
    /// What plugs into the pass besides the shadow source (the renderer's list).
    pub parts: Vec<Part<'a>>,
    /// Where the sampled lights' choose pass (`fs_choose`, a part's own entry point) notes
    /// the (pixel, light) pairs whose visibility the frame will ask for, for the shadow source
    /// to make only their shadows (`sampled::pages`); bound as the mask where the source
    /// leaves none.
    pub wants: Option<&'a wgpu::Buffer>,
}

/// The lighting pass and its output image.
pub struct LightingPass {
    /// The shaded frame.
    pub color: wgpu::Texture,
    /// Render-target view of `color`, made once.
    color_view: wgpu::TextureView,
    pipeline: wgpu::RenderPipeline,
    /// The parts' entry points drawn right after the pass's own, in order.
    follow: Vec<wgpu::RenderPipeline>,
    /// The parts' entry points their owners draw, by name.
    own: HashMap<&'static str, wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    /// The declarations the layout was made from (a rebind must bring the same).
    bindings: BindingList,
    sampler: wgpu::Sampler,
    no_emission: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
}

impl LightingPass {
    /// Creates the output texture and pipeline.
    pub fn new(
        ctx: &GpuContext,
        inputs: &LightingInputs<'_>,
        (w, h): (u32, u32),
        consts: &ShadingConsts,
    ) -> Self {
        let entry = if inputs.frame.shadows.mask.is_some() {
            "fs_mask"
        } else {
            "fs_main"
        };
        Self::with_entry(ctx, inputs, (w, h), entry, consts)
    }

    /// The pass shading with given fractions per pixel and light (`inputs.frame.shadows.mask`
    /// holds them, a byte each) instead of the shadow source's answer.
    pub fn with_fractions(
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
            LINEAR_FORMAT
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
        let lookup = &inputs.frame.shadows.lookup;
        let bindings = bindings(lookup, &inputs.parts);
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "lighting.layout",
            &bindings.layout(wgpu::ShaderStages::FRAGMENT),
        );
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
        let bind_group = bind(ctx, &layout, &bindings, &linear, &no_emission, inputs);
        let module = crate::gpu::shaders::module(
            device,
            "lighting.shader",
            &shader(lookup, consts, &inputs.parts),
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
        let follow = inputs
            .parts
            .iter()
            .flat_map(|p| p.follow)
            .map(|e| fullscreen(e))
            .collect();
        let own = inputs
            .parts
            .iter()
            .flat_map(|p| p.own)
            .map(|&e| (e, fullscreen(e)))
            .collect();
        Self {
            color_view: color.create_view(&Default::default()),
            color,
            pipeline,
            follow,
            own,
            layout,
            bindings,
            sampler: linear,
            no_emission,
            bind_group,
        }
    }

    /// Binds new inputs (after a frame's update replaced a buffer or the atlas); they declare
    /// the bindings the pass was made with.
    pub fn rebind(&mut self, ctx: &GpuContext, inputs: &LightingInputs<'_>) {
        let declared = bindings(&inputs.frame.shadows.lookup, &inputs.parts);
        assert_eq!(
            declared, self.bindings,
            "the lighting pass rebound with other bindings than it was made with"
        );
        self.bind_group = bind(
            ctx,
            &self.layout,
            &self.bindings,
            &self.sampler,
            &self.no_emission,
            inputs,
        );
    }

    /// Records the pass, then the parts' entry points that follow it (spatial reuse), as one
    /// timing span.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: &GpuTimer, span: Option<Span>) {
        let passes: Vec<&wgpu::RenderPipeline> = std::iter::once(&self.pipeline)
            .chain(&self.follow)
            .collect();
        for (i, pipeline) in passes.iter().enumerate() {
            let writes = timer.render_writes(span, i == 0, i + 1 == passes.len());
            self.pass_into(encoder, &self.color_view, pipeline, writes);
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

    /// Records a part's own entry point `entry` over the frame (the denoiser's composite,
    /// after its passes), ending `span` (begun by the part's own passes); nothing where no
    /// part brought it.
    pub fn record_own(
        &self,
        entry: &str,
        encoder: &mut wgpu::CommandEncoder,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        self.record_own_as(entry, encoder, (timer, span), (false, true));
    }

    /// [`Self::record_own`], writing the span's first (`begin`) and last (`end`) timestamps
    /// as asked (the choose pass: a span of its own).
    pub fn record_own_as(
        &self,
        entry: &str,
        encoder: &mut wgpu::CommandEncoder,
        (timer, span): (&GpuTimer, Option<Span>),
        (begin, end): (bool, bool),
    ) {
        if let Some(pipeline) = self.own.get(entry) {
            let writes = timer.render_writes(span, begin, end);
            self.pass_into(encoder, &self.color_view, pipeline, writes);
        }
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
    bindings: &BindingList,
    sampler: &wgpu::Sampler,
    no_emission: &wgpu::TextureView,
    inputs: &LightingInputs<'_>,
) -> wgpu::BindGroup {
    let device = &ctx.device;
    let f = &inputs.frame;
    // `fs_main` never reads the mask, but one layout serves every entry point.
    let dummy_mask;
    let mask = match f.shadows.mask.or(inputs.wants) {
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
    let g = f.gbuffer_views();
    let depth = wgpu::BindingResource::TextureView(f.shadows.depth);
    let mut resources = f.frame_resources();
    resources.extend([
        // LIGHTING
        f.materials.as_entire_binding(),
        // GBUFFER
        wgpu::BindingResource::TextureView(&g.position),
        wgpu::BindingResource::TextureView(&g.normal),
        // LIGHTING_SHADOWS
        depth.clone(),
        wgpu::BindingResource::Sampler(sampler),
        mask.as_entire_binding(),
    ]);
    resources.extend(f.cluster_resources());
    resources.extend([
        // LIGHTING_AFTER_CLUSTERS: the emissive texels, or the white texel.
        depth,
        wgpu::BindingResource::TextureView(g.emission.as_ref().unwrap_or(no_emission)),
    ]);
    resources.extend(f.shadows.resources.iter().cloned());
    for p in &inputs.parts {
        resources.extend(p.resources.iter().cloned());
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("lighting.bind_group"),
        layout,
        entries: &bindings.entries(resources),
    })
}
