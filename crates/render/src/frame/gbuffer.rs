//! The G-buffer pass: for each pixel the world position, normal and material of the nearest
//! surface. Positions are stored directly (not reconstructed from depth) so the quality
//! reference can ray-trace from exactly the points the frame shades.

use crate::frame::eyes::EyePasses;
pub use crate::frame::gbuffer_shaders::{
    face_clusters_shader, face_layers_shader, faces_shader, layered_shader, multiview_shader,
    shader,
};
use crate::gpu::context::GpuContext;
use crate::gpu_scene::instances::{
    CameraCull, GpuScene, LAST_POSITION_LAYOUT, NORMAL_LAYOUT, POSITION_LAYOUT, UV_LAYOUT,
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
/// The scene instance seen, plus one (0: no geometry), only for a camera whose frames keep
/// histories that follow moving instances ([`GBufferViews::MonoMoving`],
/// sampled/motion.rs), on devices whose colour attachments hold it beside the others.
pub const INSTANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The instance target where meshes bend (`GpuScene::last_positions`): the instance seen + 1,
/// then the f32 bits of the offset, in this frame's world, from the point to where its bent
/// mesh held it last frame (before its instance's motion; gbuffer.wgsl `MovingVsOut`).
pub const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// G-buffer targets and the pipeline that fills them.
pub struct GBuffer {
    /// World positions.
    pub position: wgpu::Texture,
    /// Normals and material indices.
    pub normal: wgpu::Texture,
    /// Emissive texels (see [`EMISSION_FORMAT`]); `None` where no material has an emissive
    /// texture or the device cannot hold a third target (the factor alone is used then).
    pub emission: Option<wgpu::Texture>,
    /// The instance seen per pixel (see [`INSTANCE_FORMAT`]); `None` unless the views are
    /// [`GBufferViews::MonoMoving`] and the device can hold it.
    pub instance: Option<wgpu::Texture>,
    /// Render-target views of position, normal, depth, then emission and instance where
    /// they exist, made once.
    pub(super) views: Vec<wgpu::TextureView>,
    /// By (alpha-tested, face culling): the opaque and alpha-testing pipelines, and culling
    /// variants where a material asks for them. With stereo drawn layered, these are the
    /// layered pipelines (both eyes per draw).
    pub(super) pipelines: std::collections::HashMap<(bool, CameraCull), wgpu::RenderPipeline>,
    pub(super) bind_group: wgpu::BindGroup,
    /// With stereo: how the eyes are drawn.
    pub(super) stereo: Option<EyePasses>,
    /// With square views in tiles: how many (drawn layered, or from culled clusters).
    pub(super) faces: Option<u32>,
    /// With stereo drawn multiview: two-layer targets (position, normal, depth, emission),
    /// one layer per eye, copied into the halves after the pass.
    pub(super) multiview: Option<MultiviewTargets>,
    /// Width and height of the whole image.
    pub(super) size: (u32, u32),
}

/// Which views a G-buffer holds and how they are drawn.
#[derive(Clone, Copy)]
pub enum GBufferViews<'a> {
    /// One camera (`FrameUniforms::eye_view_proj[0]`).
    Mono,
    /// One camera, and per pixel the instance seen (`GBuffer::instance`): for frames whose
    /// denoiser or reservoirs follow surfaces of moving instances (sampled/motion.rs).
    MonoMoving,
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
pub(super) struct MultiviewTargets {
    pub(super) textures: Vec<wgpu::Texture>,
    pub(super) views: Vec<wgpu::TextureView>,
    /// Layers (views per pass).
    pub(super) layers: u32,
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
        let attachment_bytes = ctx.limits().max_color_attachment_bytes_per_sample;
        let emission = if !scene.textures.has_emissive() {
            None
        } else if attachment_bytes >= bytes_needed {
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
                attachment_bytes
            );
            None
        };
        let instance_format = if scene.last_positions.is_some() {
            MOTION_FORMAT
        } else {
            INSTANCE_FORMAT
        };
        let instance_bytes = bytes_needed
            - if emission.is_some() {
                0
            } else {
                EMISSION_FORMAT.target_pixel_byte_cost().unwrap_or(4)
            }
            + instance_format.target_pixel_byte_cost().unwrap_or(16);
        let instance = if !matches!(views_drawn, GBufferViews::MonoMoving) {
            None
        } else if attachment_bytes >= instance_bytes {
            Some(target(
                ctx,
                "gbuffer.instance",
                w,
                h,
                instance_format,
                color_usage,
            ))
        } else {
            log::warn!(
                "surfaces of moving instances restart their denoised and reused histories on \
                 this device (its colour attachments hold {attachment_bytes} bytes per pixel, \
                 the G-buffer with the instance seen would need {instance_bytes})"
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
        let color_targets: Vec<Option<wgpu::ColorTargetState>> = [
            Some(POSITION_FORMAT),
            Some(NORMAL_FORMAT),
            emission.as_ref().map(|_| EMISSION_FORMAT),
            instance.as_ref().map(|_| instance_format),
        ]
        .into_iter()
        .flatten()
        .map(|f| Some(f.into()))
        .collect();
        // `vs_moving` reads the last frame's positions too (gbuffer_record.rs binds them).
        let moving_vertices = instance.is_some()
            && pull.is_none()
            && faces.is_none()
            && !face_layers
            && !layered
            && !multiview;
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
                    } else if instance.is_some() {
                        "vs_moving"
                    } else {
                        "vs_main"
                    }),
                    compilation_options: Default::default(),
                    // Clusters' vertices are read from storage.
                    buffers: if pull.is_some() {
                        &[]
                    } else if moving_vertices {
                        &[
                            Some(POSITION_LAYOUT),
                            Some(NORMAL_LAYOUT),
                            Some(UV_LAYOUT),
                            Some(LAST_POSITION_LAYOUT),
                        ]
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
                let fragment = match (masked, emission.is_some(), instance.is_some()) {
                    (false, false, false) => "fs_main",
                    (true, false, false) => "fs_masked",
                    (false, true, false) => "fs_main_emission",
                    (true, true, false) => "fs_masked_emission",
                    (false, false, true) => "fs_main_moving",
                    (true, false, true) => "fs_masked_moving",
                    (false, true, true) => "fs_main_emission_moving",
                    (true, true, true) => "fs_masked_emission_moving",
                };
                pipelines.insert((masked, cull), pipeline(fragment, cull));
            }
        }
        let views = [
            Some(&position),
            Some(&normal),
            Some(&depth),
            emission.as_ref(),
            instance.as_ref(),
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
            instance,
            views,
            pipelines,
            bind_group,
            stereo,
            faces,
            multiview,
            size: (w, h),
        }
    }
}
