//! Skinning (seed 000 §19.4.1's skeletal-animation workload): up to four bones per vertex,
//! a skin uploaded once and its bone matrices rewritten per frame. The caster transform and
//! `traditional`'s skinned pipeline read it.

use glam::Mat4;
use manyshadows_scene::Scene;
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;

/// Bone matrices of a skinned scene (seed 000 Listing 19.7).
pub const MAX_BONES: usize = 64;

/// Bytes per skinned vertex: position, 4 joint bytes, 4 weights.
pub const SKIN_VERTEX_STRIDE: u64 = 32;

/// Skinning of every vertex of a scene (in the order of
/// [`GpuScene`](crate::gpu_scene::instances::GpuScene)'s vertex buffer: meshes concatenated), up to
/// four bones per vertex out of [`MAX_BONES`].
#[derive(Clone, Debug)]
pub struct Skin {
    /// Bone indices per vertex.
    pub joints: Vec<[u8; 4]>,
    /// Bone weights per vertex (summing to 1).
    pub weights: Vec<[f32; 4]>,
}

/// A skin on the GPU.
pub struct GpuSkin {
    /// Interleaved 32-byte vertices (vertex buffer and storage).
    pub vertices: wgpu::Buffer,
    /// `array<mat4x4<f32>, 64>` (uniform).
    pub bones: wgpu::Buffer,
}

/// Vertex layout of skinned vertices (locations 0, 1, 2).
pub const SKIN_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: SKIN_VERTEX_STRIDE,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32, 2 => Float32x4],
};

impl GpuSkin {
    /// Uploads a skin for `scene`; every bone starts as the identity.
    pub fn new(ctx: &GpuContext, scene: &Scene, skin: &Skin) -> Result<Self, RenderError> {
        let n: usize = scene.meshes.iter().map(|m| m.positions.len()).sum();
        if skin.joints.len() != n || skin.weights.len() != n {
            return Err(RenderError::SkinMismatch {
                joints: skin.joints.len(),
                weights: skin.weights.len(),
                vertices: n,
            });
        }
        if let Some(j) = skin
            .joints
            .iter()
            .flatten()
            .find(|&&j| j as usize >= MAX_BONES)
        {
            return Err(RenderError::SkinJointOutOfRange {
                joint: u32::from(*j),
                bones: MAX_BONES as u32,
            });
        }
        let mut bytes = Vec::with_capacity(n * SKIN_VERTEX_STRIDE as usize);
        let positions = scene.meshes.iter().flat_map(|m| m.positions.iter());
        for ((p, j), w) in positions.zip(&skin.joints).zip(&skin.weights) {
            bytes.extend_from_slice(bytemuck::cast_slice(&p.to_array()));
            bytes.extend_from_slice(j);
            bytes.extend_from_slice(bytemuck::cast_slice(w));
        }
        if bytes.is_empty() {
            bytes.resize(SKIN_VERTEX_STRIDE as usize, 0);
        }
        let vertices = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("skin.vertices"),
                contents: &bytes,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
            });
        let bones = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("skin.bones"),
                contents: bytemuck::cast_slice(&[Mat4::IDENTITY.to_cols_array(); MAX_BONES]),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
        Ok(Self { vertices, bones })
    }

    /// Replaces the bone matrices (at most [`MAX_BONES`]; missing ones keep their value).
    pub fn set_bones(&self, queue: &wgpu::Queue, bones: &[Mat4]) {
        let m: Vec<[f32; 16]> = bones
            .iter()
            .take(MAX_BONES)
            .map(|b| b.to_cols_array())
            .collect();
        queue.write_buffer(&self.bones, 0, bytemuck::cast_slice(&m));
    }
}
