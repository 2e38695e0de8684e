//! What the shadow-reading passes (lighting, visibility) read of the frame: its uniforms, its
//! lights, the G-buffer, the light clusters and the shadow source's output. Each pass declares
//! its bindings once ([`crate::gpu::bindings`]): its own list, then the source's lookup's, then
//! (lighting only) the parts plugged into it; this module gives the declarations and the
//! resources both passes share.

use crate::frame::clusters::LightClusters;
use crate::frame::gbuffer::GBuffer;
use crate::gpu::bindings::{Binding, BindingList, Part};
use crate::shadows::source::ShadowOutput;

/// What the lighting and visibility passes read of a frame.
pub struct FrameInputs<'a> {
    /// `FrameUniforms`.
    pub frame: &'a wgpu::Buffer,
    /// `array<LightData>`.
    pub lights: &'a wgpu::Buffer,
    /// `array<MaterialData>`.
    pub materials: &'a wgpu::Buffer,
    /// The G-buffer.
    pub gbuffer: &'a GBuffer,
    /// The clustered light lists.
    pub clusters: &'a LightClusters,
    /// What the frame's shadow source produced: an atlas or a page pool (read with the
    /// shadow test), or a visibility mask (shaded with directly).
    pub shadows: ShadowOutput<'a>,
}

/// The frame's uniforms, lights and shadow views (the first three bindings of both passes).
pub const FRAME: &[Binding] = &[
    Binding::uniform("frame", "FrameUniforms"),
    Binding::storage("lights", "array<LightData>"),
    Binding::storage("shadow_views", "array<ShadowViewData>"),
];

/// The G-buffer's world positions and normals (with the material index).
pub const GBUFFER: &[Binding] = &[
    Binding::texture_u32("gbuf_position"),
    Binding::texture_u32("gbuf_normal"),
];

/// The clustered light lists (frame/clusters.rs): per cluster a slot value, and the slot pool.
pub const CLUSTERS: &[Binding] = &[
    Binding::uniform("clusters", "ClusterUniforms"),
    Binding::storage("cluster_slots", "array<u32>"),
    Binding::storage("cluster_masks", "array<u32>"),
];

/// Views of the G-buffer's targets a pass binds, made per bind group.
pub struct GBufferViews {
    /// World positions.
    pub position: wgpu::TextureView,
    /// Normals and materials.
    pub normal: wgpu::TextureView,
    /// Emissive texels, where the G-buffer keeps them.
    pub emission: Option<wgpu::TextureView>,
}

impl FrameInputs<'_> {
    /// Views of the G-buffer's targets.
    pub fn gbuffer_views(&self) -> GBufferViews {
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        GBufferViews {
            position: view(&self.gbuffer.position),
            normal: view(&self.gbuffer.normal),
            emission: self.gbuffer.emission.as_ref().map(view),
        }
    }

    /// The resources of [`FRAME`].
    pub fn frame_resources(&self) -> Vec<wgpu::BindingResource<'_>> {
        vec![
            self.frame.as_entire_binding(),
            self.lights.as_entire_binding(),
            self.shadows.view_table.as_entire_binding(),
        ]
    }

    /// The resources of [`CLUSTERS`].
    pub fn cluster_resources(&self) -> Vec<wgpu::BindingResource<'_>> {
        vec![
            self.clusters.uniforms.as_entire_binding(),
            self.clusters.slots.as_entire_binding(),
            self.clusters.masks.as_entire_binding(),
        ]
    }
}

/// A pass's bindings: its own, the lookup's, then every part's, in order.
pub fn pass_bindings(
    own: &[&[Binding]],
    shadows_lookup: &[Binding],
    parts: &[Part<'_>],
) -> BindingList {
    let mut list = BindingList::default();
    for b in own {
        list.extend(b);
    }
    list.extend(shadows_lookup);
    for p in parts {
        list.extend(p.bindings);
    }
    list
}
