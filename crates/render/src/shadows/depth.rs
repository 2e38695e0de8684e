//! The depth-only pipelines every shadow map is drawn with — atlas tiles by the atlas
//! techniques, virtual pages by the virtual maps — and the adapter features they need. Their
//! shared WGSL lies beside this module: per-view triangle culling (`cull.wgsl`), clip-space
//! positions mapped into a tile with clip distances (`tile.wgsl`) and the alpha-tested casters'
//! outputs and discarding fragment stage (`tile_mask.wgsl`).

use crate::gpu::pipelines::ATLAS_FORMAT;

/// A pipeline that writes depth 1 wherever `entry`'s triangles land (compare `Always`, no
/// fragment stage): clearing single tiles or pages of a depth texture that must otherwise
/// be kept.
pub(crate) fn clear_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::RenderPipeline {
    overwrite_pipeline(device, layout, module, entry, None)
}

/// A pipeline that replaces every atlas texel it covers (compare `Always`): the tile and
/// page clears (depth from the vertex stage, no fragment stage) and the copies of depth
/// rendered elsewhere into the atlas (`fragment` writes `frag_depth`: the compute rasterizer's
/// depth buffer, multiview's scratch layers).
pub(crate) fn overwrite_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    vertex: &str,
    fragment: Option<&str>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fragment.unwrap_or(vertex)),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: ATLAS_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: fragment.map(|entry| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A depth-only, two-sided pipeline writing the atlas with the given vertex entry point and
/// vertex buffers (none for vertex-pulling shaders): `Depth32Float`, compare `Less`, no
/// depth bias (bias is applied by the receiver), no fragment stage, no culling (what survives
/// per-view culling casts from both sides, as open meshes must).
pub(crate) fn depth_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
) -> wgpu::RenderPipeline {
    layered_depth_pipeline(device, layout, module, entry, buffers, None)
}

/// [`depth_pipeline`] rendering into the array layers `multiview_mask` selects (`None`: a
/// plain 2D target).
pub(crate) fn layered_depth_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    multiview_mask: Option<std::num::NonZeroU32>,
) -> wgpu::RenderPipeline {
    depth_pipeline_with(
        device,
        layout,
        module,
        (entry, None),
        buffers,
        multiview_mask,
        None,
    )
}

/// [`depth_pipeline`] that culls triangles whose front faces away from the light: the
/// rasterizer's back-face culling with fronts wound `front` in the view (`Ccw`: as world space
/// winds the cullable casters; `Cw`: a mirroring instance transform drawn from its mesh's own
/// indices), exactly the world-space test `faces_away` of cull.wgsl for a view whose centre
/// of projection is the light (spot, cube face, cascade).
pub(crate) fn culled_depth_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    front: wgpu::FrontFace,
) -> wgpu::RenderPipeline {
    depth_pipeline_with(
        device,
        layout,
        module,
        (entry, None),
        buffers,
        None,
        Some(front),
    )
}

/// [`depth_pipeline`] for alpha-tested casters: the vertex entry `entry` passes the texture
/// coordinate and material on, and the fragment entry `fs_alpha` (alpha_mask.wgsl) discards
/// uncovered texels. Only the masked range of the casters is drawn with it.
pub(crate) fn masked_depth_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    multiview_mask: Option<std::num::NonZeroU32>,
) -> wgpu::RenderPipeline {
    depth_pipeline_with(
        device,
        layout,
        module,
        (entry, Some("fs_alpha")),
        buffers,
        multiview_mask,
        None,
    )
}

/// A depth-only pipeline: vertex `entry`, a fragment stage where given, culling back faces
/// (fronts wound as `cull` says) where asked.
fn depth_pipeline_with(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (entry, fragment): (&str, Option<&str>),
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    multiview_mask: Option<std::num::NonZeroU32>,
    cull: Option<wgpu::FrontFace>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            front_face: cull.unwrap_or(wgpu::FrontFace::Ccw),
            cull_mode: cull.map(|_| wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: ATLAS_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: fragment.map(|entry| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask,
        cache: None,
    })
}

/// Alpha-tested casters drawn into tiles: outputs and the discarding fragment stage.
pub const TILE_MASK: &str = include_str!("tile_mask.wgsl");

/// Per-view triangle culling (frustum, back-face).
pub const CULL: &str = include_str!("cull.wgsl");

/// Mapping clip positions into atlas tiles with clip distances (`layered`, `gpu-driven`).
pub const TILE: &str = include_str!("tile.wgsl");
