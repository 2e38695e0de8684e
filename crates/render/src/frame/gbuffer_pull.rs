//! The G-buffer's second bind group when probe faces are drawn from GPU-culled triangle
//! clusters (`GBufferViews::FaceClusters`, `gbuffer_face_clusters.wgsl`): each round's
//! parameters (a dynamic offset into one uniform buffer) and the scene's vertex attributes as
//! storage, which the vertex shader reads by index (the indirect commands' base vertex carries
//! the face and the instance, so vertex buffers would be read at the wrong place).

use crate::gpu::pipelines::{dynamic_uniform_entry, storage_entry, whole_entry};
use crate::gpu_scene::instances::GpuScene;

/// `FaceDrawParams` of `gbuffer_face_clusters.wgsl`: one round of the cull and its draw.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FaceDrawParams {
    /// First face of the round, faces in it, first cluster, clusters in it.
    pub round: [u32; 4],
    /// Slot stride S (scene vertices × instances), scene vertices V, 1 = compact commands,
    /// unused.
    pub stride: [u32; 4],
}

/// `FaceDrawParams` in WGSL, for the cull and the draw.
pub const PARAMS_WGSL: &str = include_str!("gbuffer_pull.wgsl");

/// Bytes between rounds' parameters in their buffer (every device's dynamic-offset alignment
/// divides 256).
pub const FACE_DRAW_PARAMS_STRIDE: u64 = 256;

/// The bind group's layout (group 1 of the G-buffer pipelines that draw face clusters).
pub fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let vs = wgpu::ShaderStages::VERTEX;
    crate::gpu::pipelines::bind_group_layout(
        device,
        "gbuffer.pull_layout",
        &[
            dynamic_uniform_entry(
                0,
                vs | wgpu::ShaderStages::COMPUTE,
                std::mem::size_of::<FaceDrawParams>() as u64,
            ),
            storage_entry(1, vs),
            storage_entry(2, vs),
            storage_entry(3, vs),
        ],
    )
}

/// The bind group: `params` (rounds [`FACE_DRAW_PARAMS_STRIDE`] apart) and `scene`'s
/// positions, normals and texture coordinates.
pub fn bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    scene: &GpuScene,
    params: &wgpu::Buffer,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("gbuffer.pull_group"),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: params,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<FaceDrawParams>() as u64),
                }),
            },
            whole_entry(1, &scene.positions),
            whole_entry(2, &scene.normals),
            whole_entry(3, &scene.uvs),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::types::layout::same_layout;

    #[test]
    fn params_match_the_wgsl() {
        same_layout!(in PARAMS_WGSL, FaceDrawParams, round, stride);
    }
}
