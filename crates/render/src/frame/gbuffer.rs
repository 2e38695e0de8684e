//! The G-buffer pass: for each pixel the world position, normal and material of the nearest
//! surface. Positions are stored directly (not reconstructed from depth) so the quality
//! reference can ray-trace from exactly the points the frame shades.

use crate::frame::eyes::EyePasses;
pub use crate::frame::gbuffer_shaders::{
    face_clusters_shader, face_layers_shader, faces_shader, layered_shader, multiview_shader,
    shader,
};
use crate::gpu::context::GpuContext;
use crate::gpu::timing::{GpuTimer, Span};
use crate::gpu_scene::instances::{
    CameraCull, GpuScene, NORMAL_LAYOUT, POSITION_LAYOUT, UV_LAYOUT,
};

/// xyz world position (`f32` bits in a `u32` target, because OpenGL ES and WebGL cannot render
/// to `Rgba32Float` but can to `Rgba32Uint`, and positions must be exact); w = the surface's
/// albedo as four sRGB-encoded bytes, alpha byte 255 (0 where no geometry was drawn; all ones
/// for untextured surfaces). Packing the albedo into the spare channel keeps the G-buffer
/// within WebGPU's 32 bytes of colour attachments per sample.
pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
/// xyz normal (`f32` bits), w = material index.
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
/// Camera depth buffer.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The emissive texture's texel (linear rgb, stored sRGB), only for scenes whose materials
/// have emissive textures, on devices whose colour attachments may hold more than the 32
/// bytes per pixel of position and normal (every native adapter; not a browser's WebGPU).
pub const EMISSION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// G-buffer targets and the pipeline that fills them.
pub struct GBuffer {
    /// World positions.
    pub position: wgpu::Texture,
    /// Normals and material indices.
    pub normal: wgpu::Texture,
    /// Emissive texels (see [`EMISSION_FORMAT`]); `None` where no material has an emissive
    /// texture or the device cannot hold a third target (the factor alone is used then).
    pub emission: Option<wgpu::Texture>,
    /// Render-target views of position, normal, depth and emission, made once.
    views: Vec<wgpu::TextureView>,
    /// By (alpha-tested, face culling): the opaque and alpha-testing pipelines, and culling
    /// variants where a material asks for them. With stereo drawn layered, these are the
    /// layered pipelines (both eyes per draw).
    pipelines: std::collections::HashMap<(bool, CameraCull), wgpu::RenderPipeline>,
    bind_group: wgpu::BindGroup,
    /// With stereo: how the eyes are drawn.
    stereo: Option<EyePasses>,
    /// With square views in tiles: how many (drawn layered, or from culled clusters).
    faces: Option<u32>,
    /// With stereo drawn multiview: two-layer targets (position, normal, depth, emission),
    /// one layer per eye, copied into the halves after the pass.
    multiview: Option<MultiviewTargets>,
    /// Width and height of the whole image.
    size: (u32, u32),
}

/// Which views a G-buffer holds and how they are drawn.
#[derive(Clone, Copy)]
pub enum GBufferViews<'a> {
    /// One camera (`FrameUniforms::eye_view_proj[0]`).
    Mono,
    /// Two eyes side by side, drawn that way (its feature is checked by `Renderer::new`).
    Stereo(EyePasses),
    /// Square views in tiles, all drawn in one layered pass (needs `CLIP_DISTANCES`):
    /// `views` holds `FaceView`s (`gbuffer_faces.wgsl`), one per view.
    Faces {
        /// The views, `array<FaceView>`.
        views: &'a wgpu::Buffer,
        /// How many.
        count: u32,
    },
    /// Square views in tiles as for `Faces`, drawn from triangle clusters that a compute pass
    /// culled per view, by indirect multi-draws (`record_face_clusters`); `pull` is the layout
    /// of the draws' second bind group (`gbuffer_pull.rs`).
    FaceClusters {
        /// The views, `array<FaceView>`.
        views: &'a wgpu::Buffer,
        /// How many.
        count: u32,
        /// `gbuffer_pull::layout`.
        pull: &'a wgpu::BindGroupLayout,
    },
    /// Six square views (a probe's faces) per multiview pass, each into its layer of six-layer
    /// targets at the origin (needs six views per multiview pass): `views` as for `Faces`.
    FaceLayers {
        /// The views, `array<FaceView>`.
        views: &'a wgpu::Buffer,
    },
}

/// The two-layer targets of a multiview stereo pass, and their render views.
struct MultiviewTargets {
    textures: Vec<wgpu::Texture>,
    views: Vec<wgpu::TextureView>,
    /// Layers (views per pass).
    layers: u32,
}

fn target(
    ctx: &GpuContext,
    label: &str,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A fragment-stage binding of a filterable 2D texture array.
fn array_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}

impl GBuffer {
    /// Creates `w`×`h` targets holding `views`; `frame` is the frame-uniform buffer.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        frame: &wgpu::Buffer,
        (w, h): (u32, u32),
        views_drawn: GBufferViews<'_>,
    ) -> Self {
        use wgpu::TextureUsages as U;
        let stereo = match views_drawn {
            GBufferViews::Stereo(p) => Some(p),
            _ => None,
        };
        let (faces, face_buffer) = match views_drawn {
            GBufferViews::Faces { views, count } => (Some(count), Some(views)),
            GBufferViews::FaceClusters { views, count, .. } => (Some(count), Some(views)),
            GBufferViews::FaceLayers { views } => (None, Some(views)),
            _ => (None, None),
        };
        let face_layers = matches!(views_drawn, GBufferViews::FaceLayers { .. });
        let pull = match views_drawn {
            GBufferViews::FaceClusters { pull, .. } => Some(pull),
            _ => None,
        };
        // Views per multiview pass, and each view's target size.
        let (layers, layer_width) = if face_layers {
            (6, w)
        } else {
            (2, (w / 2).max(1))
        };
        let multiview = stereo == Some(EyePasses::Multiview) || face_layers;
        // Copy targets too: a multiview pass's layers, a probe face's tile, are copied in.
        let color_usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST;
        let position = target(ctx, "gbuffer.position", w, h, POSITION_FORMAT, color_usage);
        let normal = target(ctx, "gbuffer.normal", w, h, NORMAL_FORMAT, color_usage);
        let bytes_needed = [POSITION_FORMAT, NORMAL_FORMAT, EMISSION_FORMAT]
            .iter()
            .map(|f| f.target_pixel_byte_cost().unwrap_or(16))
            .sum::<u32>();
        let emission = if !scene.textures.has_emissive() {
            None
        } else if ctx.limits().max_color_attachment_bytes_per_sample >= bytes_needed {
            Some(target(
                ctx,
                "gbuffer.emission",
                w,
                h,
                EMISSION_FORMAT,
                color_usage,
            ))
        } else {
            log::warn!(
                "emissive textures are not shown on this device (its colour attachments hold \
                 {} bytes per pixel, the G-buffer would need {bytes_needed}): their materials \
                 emit their factor",
                ctx.limits().max_color_attachment_bytes_per_sample
            );
            None
        };
        let depth = target(
            ctx,
            "gbuffer.depth",
            w,
            h,
            DEPTH_FORMAT,
            U::RENDER_ATTACHMENT,
        );
        let device = &ctx.device;
        let layered = stereo == Some(EyePasses::Layered);
        let module = if pull.is_some() {
            crate::gpu::shaders::module(
                device,
                "gbuffer.face_clusters.shader",
                &face_clusters_shader(),
            )
        } else if faces.is_some() {
            crate::gpu::shaders::module(device, "gbuffer.faces.shader", &faces_shader())
        } else if face_layers {
            crate::gpu::shaders::module(device, "gbuffer.face_layers.shader", &face_layers_shader())
        } else if layered {
            crate::gpu::shaders::module(device, "gbuffer.layered.shader", &layered_shader())
        } else if multiview {
            crate::gpu::shaders::module(device, "gbuffer.multiview.shader", &multiview_shader())
        } else {
            crate::gpu::shaders::module(device, "gbuffer.shader", &shader())
        };
        let layout = crate::gpu::pipelines::bind_group_layout(
            device,
            "gbuffer.layout",
            &[
                crate::gpu::pipelines::uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                crate::gpu::pipelines::storage_entry(1, wgpu::ShaderStages::VERTEX),
                crate::gpu::pipelines::storage_entry(2, wgpu::ShaderStages::FRAGMENT),
                array_texture_entry(3),
                array_texture_entry(4),
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ]
            .into_iter()
            .chain(face_buffer.map(|_| {
                crate::gpu::pipelines::storage_entry(6, wgpu::ShaderStages::VERTEX_FRAGMENT)
            }))
            .collect::<Vec<_>>(),
        );
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer.bind_group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: scene.instances.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: scene.materials.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&scene.textures.colour),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&scene.textures.normal),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::Sampler(&scene.textures.sampler),
                },
            ]
            .into_iter()
            .chain(face_buffer.map(|b| wgpu::BindGroupEntry {
                binding: 6,
                resource: b.as_entire_binding(),
            }))
            .collect::<Vec<_>>(),
        });
        let groups: Vec<&wgpu::BindGroupLayout> = std::iter::once(&layout).chain(pull).collect();
        let pipeline_layout =
            crate::gpu::pipelines::pipeline_layout(device, "gbuffer.pipeline_layout", &groups);
        let color_targets: Vec<Option<wgpu::ColorTargetState>> =
            [POSITION_FORMAT, NORMAL_FORMAT, EMISSION_FORMAT]
                .into_iter()
                .take(if emission.is_some() { 3 } else { 2 })
                .map(|f| Some(f.into()))
                .collect();
        let pipeline = |fragment: &str, cull: CameraCull| {
            let (front_face, cull_mode) = match cull {
                CameraCull::None => (wgpu::FrontFace::Ccw, None),
                CameraCull::BackCcw => (wgpu::FrontFace::Ccw, Some(wgpu::Face::Back)),
                CameraCull::BackCw => (wgpu::FrontFace::Cw, Some(wgpu::Face::Back)),
            };
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fragment),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(if pull.is_some() {
                        "vs_face_clusters"
                    } else if faces.is_some() {
                        "vs_faces"
                    } else if face_layers {
                        "vs_face_layers"
                    } else if layered {
                        "vs_layered"
                    } else if multiview {
                        "vs_multiview"
                    } else {
                        "vs_main"
                    }),
                    compilation_options: Default::default(),
                    // Clusters' vertices are read from storage.
                    buffers: if pull.is_some() {
                        &[]
                    } else {
                        &[Some(POSITION_LAYOUT), Some(NORMAL_LAYOUT), Some(UV_LAYOUT)]
                    },
                },
                primitive: wgpu::PrimitiveState {
                    front_face,
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &color_targets,
                }),
                multiview_mask: if multiview {
                    std::num::NonZeroU32::new((1 << layers) - 1)
                } else {
                    None
                },
                cache: None,
            })
        };
        // Per alpha test and face culling; the culling ones only where a material asks (an
        // instance's transform may turn mirrored later, so then both windings).
        let culls: &[CameraCull] = if scene
            .draws
            .iter()
            .any(|d| d.camera_cull != CameraCull::None)
        {
            &[CameraCull::None, CameraCull::BackCcw, CameraCull::BackCw]
        } else {
            &[CameraCull::None]
        };
        let mut pipelines = std::collections::HashMap::new();
        for masked in [false, true] {
            for &cull in culls {
                let fragment = match (masked, emission.is_some()) {
                    (false, false) => "fs_main",
                    (true, false) => "fs_masked",
                    (false, true) => "fs_main_emission",
                    (true, true) => "fs_masked_emission",
                };
                pipelines.insert((masked, cull), pipeline(fragment, cull));
            }
        }
        let views = [
            Some(&position),
            Some(&normal),
            Some(&depth),
            emission.as_ref(),
        ]
        .into_iter()
        .flatten()
        .map(|t| t.create_view(&Default::default()))
        .collect();
        let multiview = multiview.then(|| {
            let formats = [
                Some(POSITION_FORMAT),
                Some(NORMAL_FORMAT),
                Some(DEPTH_FORMAT),
                emission.as_ref().map(|_| EMISSION_FORMAT),
            ];
            let textures: Vec<wgpu::Texture> = formats
                .into_iter()
                .flatten()
                .map(|format| {
                    ctx.device.create_texture(&wgpu::TextureDescriptor {
                        label: Some("gbuffer.multiview"),
                        size: wgpu::Extent3d {
                            width: layer_width,
                            height: h,
                            depth_or_array_layers: layers,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage: U::RENDER_ATTACHMENT | U::COPY_SRC,
                        view_formats: &[],
                    })
                })
                .collect();
            let views = textures
                .iter()
                .map(|t| {
                    t.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2Array),
                        array_layer_count: Some(layers),
                        ..Default::default()
                    })
                })
                .collect();
            MultiviewTargets {
                textures,
                views,
                layers,
            }
        });
        Self {
            position,
            normal,
            emission,
            views,
            pipelines,
            bind_group,
            stereo,
            faces,
            multiview,
            size: (w, h),
        }
    }

    /// Records the pass: every instance, no culling (the camera sees a handful of instances
    /// fewer at most; the shadow passes are where culling pays). Stereo: one pass per eye, or
    /// one pass drawing both (`EyePasses`).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        if let Some(n) = self.faces {
            self.record_pass(encoder, scene, (timer, span, true, true), None, (n, 0..n));
            return;
        }
        self.record_views(encoder, scene, timer, span);
    }

    /// A probe's six faces (`GBufferViews::FaceLayers`): probe `probe`'s multiview pass into
    /// the six-layer targets (draw instances `probe · instances + i`), beginning the span when
    /// `begin`; [`Self::copy_layer`] then hands each face on.
    pub(crate) fn record_face_layers(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span, begin): (&GpuTimer, Option<Span>, bool),
        probe: u32,
    ) {
        let Some(mv) = &self.multiview else {
            debug_assert!(false, "face layers are drawn into multiview targets");
            return;
        };
        let base = probe * scene.draws.len() as u32;
        let writes = (timer, span, begin, false);
        self.record_into(
            encoder,
            scene,
            &mv.views,
            writes,
            (true, None, None),
            (1, base..base + 1),
        );
    }

    /// Copies layer `layer` of the face-layer targets (position, normal, emission) into `into`.
    pub(crate) fn copy_layer(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        layer: u32,
        into: &GBuffer,
    ) {
        let Some(mv) = &self.multiview else {
            return;
        };
        // The layers' textures are position, normal, depth, emission (see `new`).
        let pairs = [(0, &into.position), (1, &into.normal)]
            .into_iter()
            .chain(into.emission.as_ref().map(|e| (3, e)));
        for (i, target) in pairs {
            let Some(layers) = mv.textures.get(i) else {
                continue;
            };
            encoder.copy_texture_to_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: layers,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                target.as_image_copy(),
                wgpu::Extent3d {
                    width: target.width(),
                    height: target.height(),
                    depth_or_array_layers: 1,
                },
            );
        }
    }

    /// Square views in tiles (`GBufferViews::Faces`) in their one pass, which begins the span
    /// (passes recorded after it end it); `visible[draw · views + view]` false leaves that
    /// instance out of that view (consecutive views still drawn, one draw per run).
    pub(crate) fn record_faces_begin(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span): (&GpuTimer, Option<Span>),
        visible: Option<&[bool]>,
    ) {
        let n = self.faces.unwrap_or(1);
        let writes = (timer, span, true, false);
        self.record_into(
            encoder,
            scene,
            &self.views,
            writes,
            (true, None, visible),
            (n, 0..n),
        );
    }

    fn record_views(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        match self.stereo {
            None => {
                self.record_pass(encoder, scene, (timer, span, true, true), None, (1, 0..1));
            }
            Some(EyePasses::PerEye) => {
                let eye_width = self.size.0 / 2;
                for eye in 0..2u32 {
                    let rect = [eye * eye_width, 0, eye_width, self.size.1];
                    let writes = (timer, span, eye == 0, eye == 1);
                    self.record_pass(encoder, scene, writes, Some(rect), (2, eye..eye + 1));
                }
            }
            Some(EyePasses::Layered) => {
                self.record_pass(encoder, scene, (timer, span, true, true), None, (2, 0..2));
            }
            Some(EyePasses::Multiview) => self.record_multiview(encoder, scene, timer, span),
        }
    }

    /// Both eyes in one multiview pass into the two-layer targets, then each layer copied
    /// into its eye's half (the depth is not needed after the pass).
    fn record_multiview(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &GpuTimer,
        span: Option<Span>,
    ) {
        let Some(mv) = &self.multiview else {
            debug_assert!(false, "multiview targets are made with the pipelines");
            return;
        };
        let writes = (timer, span, true, true);
        self.record_into(
            encoder,
            scene,
            &mv.views,
            writes,
            (true, None, None),
            (1, 0..1),
        );
        let eye_width = self.size.0 / 2;
        // The layers' textures are position, normal, depth, emission (see `new`).
        let pairs = [(0, &self.position), (1, &self.normal)]
            .into_iter()
            .chain(self.emission.as_ref().map(|e| (3, e)));
        for (i, target) in pairs {
            let layers = &mv.textures[i];
            for eye in 0..2u32 {
                encoder.copy_texture_to_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: layers,
                        mip_level: 0,
                        origin: wgpu::Origin3d { x: 0, y: 0, z: eye },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::TexelCopyTextureInfo {
                        texture: target,
                        mip_level: 0,
                        origin: wgpu::Origin3d {
                            x: eye * eye_width,
                            y: 0,
                            z: 0,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::Extent3d {
                        width: eye_width,
                        height: self.size.1,
                        depth_or_array_layers: 1,
                    },
                );
            }
        }
    }

    /// One render pass: the first (`writes.2`) clears; `rect` limits it to one eye's half;
    /// each scene instance `i` is drawn as draw instances `eyes·i + copies`.
    fn record_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        rect: Option<[u32; 4]>,
        (eyes, copies): (u32, std::ops::Range<u32>),
    ) {
        let writes = (timer, span, first, last);
        self.record_into(
            encoder,
            scene,
            &self.views,
            writes,
            (first, rect, None),
            (eyes, copies),
        );
    }

    /// A mono pass that clears and writes the span's first (`begin`) and last (`end`)
    /// timestamps as asked: several frames' G-buffers drawn into the same targets one after
    /// another (a reflection probe's faces), timed as one span; `visible` (by draw) leaves out
    /// the draws it marks false (culled by the caller against the view's frustum).
    pub(crate) fn record_timed(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        (timer, span): (&GpuTimer, Option<Span>),
        (begin, end): (bool, bool),
        visible: Option<&[bool]>,
    ) {
        let writes = (timer, span, begin, end);
        self.record_into(
            encoder,
            scene,
            &self.views,
            writes,
            (true, None, visible),
            (1, 0..1),
        );
    }

    /// [`Self::record_pass`] into `views` (position, normal, depth, emission): the frame's
    /// targets, or the multiview pass's two-layer ones.
    fn record_into(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        views: &[wgpu::TextureView],
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        (clear, rect, visible): (bool, Option<[u32; 4]>, Option<&[bool]>),
        (eyes, copies): (u32, std::ops::Range<u32>),
    ) {
        let mut pass = self.begin_pass(encoder, views, (timer, span, first, last), clear);
        if let Some([x, y, w, h]) = rect {
            pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, w, h);
        }
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.positions.slice(..));
        pass.set_vertex_buffer(1, scene.normals.slice(..));
        pass.set_vertex_buffer(2, scene.uvs.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        // Opaque surfaces first (early depth testing), then the alpha-tested ones.
        for masked in [false, true] {
            let mut set = None;
            for (k, d) in scene.draws.iter().enumerate() {
                if d.masked != masked {
                    continue;
                }
                // The draw's copies (views) to draw: all, or the runs `visible` marks (index
                // `draw · eyes + copy`).
                let shown = |c: u32| {
                    visible.is_none_or(|v| {
                        v.get(k * eyes as usize + c as usize)
                            .copied()
                            .unwrap_or(true)
                    })
                };
                let mut c = copies.start;
                while c < copies.end {
                    if !shown(c) {
                        c += 1;
                        continue;
                    }
                    let run = c;
                    while c < copies.end && shown(c) {
                        c += 1;
                    }
                    let key = (masked, d.camera_cull);
                    if set != Some(key) {
                        pass.set_pipeline(&self.pipelines[&key]);
                        set = Some(key);
                    }
                    let m = d.mesh;
                    pass.draw_indexed(
                        m.first_index..m.first_index + m.index_count,
                        m.base_vertex,
                        eyes * d.instance + run..eyes * d.instance + c,
                    );
                }
            }
        }
    }

    /// One round of GPU-culled clusters (`GBufferViews::FaceClusters`): a pass into the
    /// atlas (cleared when `clear`; the span's timestamps as `first` and `last` say) with the
    /// pipeline of `key` (alpha test, face culling) and `pull` bound at `offset`, in which
    /// `draw` records the round's indirect multi-draw.
    pub(crate) fn record_face_clusters(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        clear: bool,
        (pull, offset): (&wgpu::BindGroup, u32),
        key: (bool, CameraCull),
        draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        let mut pass = self.begin_pass(encoder, &self.views, (timer, span, first, last), clear);
        let Some(pipeline) = self.pipelines.get(&key) else {
            debug_assert!(false, "no G-buffer pipeline for {key:?}");
            return;
        };
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_bind_group(1, pull, &[offset]);
        draw(&mut pass);
    }

    /// A pass into `views` (position, normal, depth, emission), cleared when `clear`, its
    /// timestamps as `first` and `last` say.
    fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        views: &[wgpu::TextureView],
        (timer, span, first, last): (&GpuTimer, Option<Span>, bool, bool),
        clear: bool,
    ) -> wgpu::RenderPass<'e> {
        let (pv, nv, dv) = (&views[0], &views[1], &views[2]);
        let load = if clear {
            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
        } else {
            wgpu::LoadOp::Load
        };
        let target = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer.pass"),
            color_attachments: &if let Some(ev) = views.get(3) {
                vec![target(pv), target(nv), target(ev)]
            } else {
                vec![target(pv), target(nv)]
            },
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: dv,
                depth_ops: Some(wgpu::Operations {
                    // The first pass clears the whole image, the second eye's loads it.
                    load: if clear {
                        wgpu::LoadOp::Clear(1.0)
                    } else {
                        wgpu::LoadOp::Load
                    },
                    store: if last {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_writes(span, first, last),
            occlusion_query_set: None,
            multiview_mask: self
                .multiview
                .as_ref()
                .and_then(|mv| std::num::NonZeroU32::new((1 << mv.layers) - 1)),
        })
    }
}
