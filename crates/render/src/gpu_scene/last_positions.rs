//! The vertex positions the last frame drew, for the histories that follow deformed surfaces
//! (a skinned or morphed mesh bent between frames: `GpuScene::set_mesh_vertices`). The
//! G-buffer reads them beside this frame's positions, and keeps per pixel how far the surface
//! point moved since the last frame (frame/gbuffer.rs, `MOTION_FORMAT`); the denoiser and the
//! reservoirs take the point back by it (sampled/motion.rs).
//!
//! The buffer mirrors the scene's position buffer vertex for vertex, so the same draws (the
//! same base vertex) read both. Only the meshes bent since the scene was uploaded are kept on
//! the CPU, as the last frame drew them.

use std::collections::HashMap;

use wgpu::util::DeviceExt;

/// Last frame's positions on the GPU, and what it takes to keep them so.
pub struct LastPositions {
    /// `vec3<f32>` per vertex, 12-byte stride, like `GpuScene::positions`.
    pub buffer: wgpu::Buffer,
    /// Per mesh bent at least once: its positions as the last frame drew them.
    drawn: HashMap<usize, Vec<[f32; 3]>>,
    /// Per mesh bent since the last frame: its positions now (the next frame draws them).
    next: HashMap<usize, Vec<[f32; 3]>>,
    /// Meshes bent between the last two frames (their last positions differ from their
    /// positions until they are set equal, the first frame they stay still).
    moving: Vec<usize>,
    /// Where each mesh's first vertex lies in the buffer, in bytes.
    at: HashMap<usize, u64>,
    /// Ranges `(first byte, bytes)` of meshes bent on the GPU before the next frame
    /// ([`LastPositions::note_gpu`]), and before the last.
    gpu_next: Vec<(u64, u64)>,
    gpu_last: Vec<(u64, u64)>,
}

impl LastPositions {
    /// A copy of the positions uploaded (`positions`: every vertex of the scene).
    pub fn new(device: &wgpu::Device, positions: &[[f32; 3]]) -> Self {
        let bytes: &[u8] = bytemuck::cast_slice(positions);
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene.last_positions"),
            contents: if bytes.is_empty() { &[0; 12] } else { bytes },
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        Self {
            buffer,
            drawn: HashMap::new(),
            next: HashMap::new(),
            moving: Vec::new(),
            at: HashMap::new(),
            gpu_next: Vec::new(),
            gpu_last: Vec::new(),
        }
    }

    /// Mesh `mesh` (first vertex `at` bytes into the buffer) gets `positions` for the next
    /// frame: its last positions become what the last frame drew (only the first bend since
    /// that frame counts).
    pub fn note(&mut self, queue: &wgpu::Queue, mesh: usize, at: u64, positions: &[[f32; 3]]) {
        self.at.insert(mesh, at);
        if !self.next.contains_key(&mesh) {
            // Never bent before: the buffer already holds what was drawn (the rest pose).
            if let Some(drawn) = self.drawn.get(&mesh) {
                queue.write_buffer(&self.buffer, at, bytemuck::cast_slice(drawn));
            }
        }
        self.next.insert(mesh, positions.to_vec());
    }

    /// The mesh at `bytes` (first byte, length) of the buffer is bent on the GPU before the
    /// next frame draws (gpu_scene/deform.rs): [`LastPositions::record_gpu`] copies what the
    /// last frame drew before the bend.
    pub fn note_gpu(&mut self, bytes: (u64, u64)) {
        if !self.gpu_next.contains(&bytes) {
            self.gpu_next.push(bytes);
        }
    }

    /// Before the GPU bends meshes for a frame: every mesh bent on the GPU for this frame or
    /// the last gets its last positions copied from `positions` (what the last frame drew;
    /// for a mesh not bent again, its positions now, so that it stands still).
    pub fn record_gpu(&mut self, encoder: &mut wgpu::CommandEncoder, positions: &wgpu::Buffer) {
        let last = std::mem::take(&mut self.gpu_last);
        for &(at, len) in self
            .gpu_next
            .iter()
            .chain(last.iter().filter(|r| !self.gpu_next.contains(r)))
        {
            encoder.copy_buffer_to_buffer(positions, at, &self.buffer, at, len);
        }
        self.gpu_last = std::mem::take(&mut self.gpu_next);
    }

    /// Before a frame's passes: meshes bent between the last two frames but not since get
    /// their last positions set to their positions (they stand still now); what is bent
    /// becomes what this frame draws.
    pub fn begin_frame(&mut self, queue: &wgpu::Queue) {
        for mesh in std::mem::take(&mut self.moving) {
            if self.next.contains_key(&mesh) {
                continue;
            }
            if let (Some(drawn), Some(&at)) = (self.drawn.get(&mesh), self.at.get(&mesh)) {
                queue.write_buffer(&self.buffer, at, bytemuck::cast_slice(drawn));
            }
        }
        for (mesh, now) in self.next.drain() {
            self.moving.push(mesh);
            self.drawn.insert(mesh, now);
        }
    }
}
