//! The ray-traced scene: one bottom-level acceleration structure (BLAS) per mesh and opacity,
//! built once from the mesh's object-space triangles, and one top-level structure (TLAS) over
//! the shadow-casting instances, rebuilt on the GPU whenever an instance moved (wgpu has no
//! refit: a changed transform is a new TLAS build; the BLASes are reused as they are).
//!
//! Alpha-tested casters: a mesh drawn with a masked material gets a BLAS without the `OPAQUE`
//! flag, so the shadow ray's candidate hits on it reach the shader, which tests the mask
//! (`rays.wgsl`); every other BLAS is opaque and its hits are committed by the driver. The
//! ray geometry buffer holds what that test reads: per TLAS instance the first word of its
//! mesh's texture-coordinate triples and its material, per masked mesh three coordinates per
//! triangle, then the coverage masks in the mask-tail layout `alpha_mask.wgsl` reads.
//!
//! Single-sided casters that cast only where a light sees their front
//! (`SingleSidedShadows::Front`, the default) get a BLAS without the `OPAQUE` flag too: their
//! candidate hits reach the shader, which keeps those where the ray meets the triangle's back,
//! so the ray leaves the triangle's back side towards a light on its front side (the CPU
//! reference's rule). Their instance's material word carries [`FRONT_ONLY`].
//!
//! A skinned mesh that bends (a glTF file's skin, `Renderer::set_mesh_vertices`) has its BLASes
//! built again from the new vertices ([`RayAccel::deform`]), then the TLAS. The atlas
//! benchmark's skinning workload (`GpuScene::attach_skin`) never reaches a ray-traced frame.

use glam::Mat4;
use manyshadows_scene::masks::MaskSet;
use manyshadows_scene::{Scene, SingleSidedShadows};
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;
use crate::gpu_scene::instances::GpuScene;
use crate::sampled::options::RayOptions;

/// `RayParams` of rays.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct RayParams {
    /// Samples per pixel, seed, samples per side of a sized light's grid, unused.
    pub(crate) samples: [u32; 4],
}

/// Bit of an instance's material word (`FRONT_ONLY` in rays.wgsl): a single-sided caster whose
/// candidate hits count only where the ray meets its back.
pub(crate) const FRONT_ONLY: u32 = 1 << 31;

/// How the rays treat a BLAS's triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Every hit blocks (committed by the driver).
    Opaque,
    /// Alpha-tested: a hit blocks where its mask is solid.
    Masked,
    /// Single-sided: a hit blocks where the ray meets the triangle's back.
    FrontOnly,
}

/// One TLAS instance: the scene instance and its BLAS.
#[derive(Clone, Copy, Debug)]
struct Item {
    instance: usize,
    blas: usize,
}

/// The acceleration structures and the buffers the rays read.
pub struct RayAccel {
    blas: Vec<wgpu::Blas>,
    /// Per BLAS: its mesh, its size, its input vertex and index buffers, and whether its
    /// vertices changed since it was built (a bent skinned mesh: rebuilt by the next record).
    built: Vec<Built>,
    items: Vec<Item>,
    tlas: wgpu::Tlas,
    /// Per item: first word of its mesh's masked texture coordinates, material; then the
    /// coordinates and the mask tail.
    pub geometry: wgpu::Buffer,
    /// `RayParams`.
    pub params: wgpu::Buffer,
    /// The TLAS must be built before the next ray is cast.
    dirty: bool,
}

/// What a BLAS was built from, to build it again when its mesh bends.
struct Built {
    mesh: usize,
    size: wgpu::BlasTriangleGeometrySizeDescriptor,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    stale: bool,
    /// Bent on the GPU: where its vertices lie in the scene's positions, in bytes.
    copy_from: Option<u64>,
}

/// Row-major 3×4 affine part of `m`, as a TLAS instance's transform.
fn affine_rows(m: Mat4) -> [f32; 12] {
    let r = m.transpose();
    let (a, b, c) = (r.x_axis, r.y_axis, r.z_axis);
    [a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w, c.x, c.y, c.z, c.w]
}

impl RayAccel {
    /// Builds a BLAS per (mesh, opacity) the casting instances use, submits their build, and
    /// prepares the TLAS (built by the first [`RayAccel::record`]).
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        masks: &MaskSet,
        options: RayOptions,
        single_sided: SingleSidedShadows,
    ) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let limits = ctx.limits();
        // (mesh, kind) → BLAS index.
        let mut keys: Vec<(usize, Kind)> = Vec::new();
        let mut items = Vec::new();
        for (i, inst) in scene.instances.iter().enumerate() {
            if !inst.casts_shadows || scene.meshes[inst.mesh].indices.is_empty() {
                continue;
            }
            let kind = if masks.is_masked(inst.material) {
                Kind::Masked
            } else if scene
                .materials
                .get(inst.material)
                .is_some_and(|m| m.casts_front_only(single_sided))
            {
                Kind::FrontOnly
            } else {
                Kind::Opaque
            };
            let key = (inst.mesh, kind);
            let blas = match keys.iter().position(|k| *k == key) {
                Some(b) => b,
                None => {
                    keys.push(key);
                    keys.len() - 1
                }
            };
            items.push(Item { instance: i, blas });
        }
        let mut short = Vec::new();
        let largest = keys
            .iter()
            .map(|&(m, _)| scene.meshes[m].indices.len() as u64 / 3)
            .max()
            .unwrap_or(0);
        for (name, have, need) in [
            (
                "max_tlas_instance_count",
                u64::from(limits.max_tlas_instance_count),
                items.len().max(1) as u64,
            ),
            (
                "max_blas_primitive_count",
                u64::from(limits.max_blas_primitive_count),
                largest,
            ),
            (
                "max_blas_geometry_count",
                u64::from(limits.max_blas_geometry_count),
                1,
            ),
            (
                "max_acceleration_structures_per_shader_stage",
                u64::from(limits.max_acceleration_structures_per_shader_stage),
                1,
            ),
        ] {
            if have < need {
                short.push(format!(
                    "{name}: the device allows {have}, the scene needs {need}"
                ));
            }
        }
        if !short.is_empty() {
            return Err(RenderError::LimitsTooSmall {
                adapter: ctx.describe(),
                needs: "technique raytraced".into(),
                shortfalls: short,
            });
        }

        // The BLASes, built from copies of the meshes' triangles (BLAS input buffers).
        let sizes: Vec<wgpu::BlasTriangleGeometrySizeDescriptor> = keys
            .iter()
            .map(|&(m, kind)| {
                let mesh = &scene.meshes[m];
                wgpu::BlasTriangleGeometrySizeDescriptor {
                    vertex_format: wgpu::VertexFormat::Float32x3,
                    vertex_count: mesh.positions.len() as u32,
                    index_format: Some(wgpu::IndexFormat::Uint32),
                    index_count: Some(mesh.indices.len() as u32),
                    flags: if kind == Kind::Opaque {
                        wgpu::AccelerationStructureGeometryFlags::OPAQUE
                    } else {
                        wgpu::AccelerationStructureGeometryFlags::empty()
                    },
                }
            })
            .collect();
        let blas: Vec<wgpu::Blas> = sizes
            .iter()
            .map(|size| {
                device.create_blas(
                    &wgpu::CreateBlasDescriptor {
                        label: Some("raytraced.blas"),
                        flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                        update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                    },
                    wgpu::BlasGeometrySizeDescriptors::Triangles {
                        descriptors: vec![size.clone()],
                    },
                )
            })
            .collect();
        let inputs: Vec<(wgpu::Buffer, wgpu::Buffer)> = keys
            .iter()
            .map(|&(m, _)| {
                let mesh = &scene.meshes[m];
                let positions: Vec<[f32; 3]> =
                    mesh.positions.iter().map(|p| p.to_array()).collect();
                let usage = wgpu::BufferUsages::BLAS_INPUT | wgpu::BufferUsages::COPY_DST;
                (
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("raytraced.blas_vertices"),
                        contents: bytemuck::cast_slice(&positions),
                        usage,
                    }),
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("raytraced.blas_indices"),
                        contents: bytemuck::cast_slice(&mesh.indices),
                        usage,
                    }),
                )
            })
            .collect();
        if !blas.is_empty() {
            let entries: Vec<wgpu::BlasBuildEntry<'_>> = blas
                .iter()
                .zip(&sizes)
                .zip(&inputs)
                .map(|((b, size), (v, i))| wgpu::BlasBuildEntry {
                    blas: b,
                    geometry: wgpu::BlasGeometries::TriangleGeometries(vec![
                        wgpu::BlasTriangleGeometry {
                            size,
                            vertex_buffer: v,
                            first_vertex: 0,
                            vertex_stride: 12,
                            index_buffer: Some(i),
                            first_index: Some(0),
                            transform_buffer: None,
                            transform_buffer_offset: None,
                        },
                    ]),
                })
                .collect();
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("raytraced.blas_build"),
            });
            encoder.build_acceleration_structures(entries.iter(), std::iter::empty());
            ctx.queue.submit([encoder.finish()]);
        }

        // The ray geometry: per item (first uv word, material), the masked meshes' uv
        // triples, then the mask tail (records with absolute first words, bits, header).
        let mut words: Vec<u32> = vec![0; 2 * items.len().max(1)];
        let mut uv_start: Vec<Option<u32>> = vec![None; scene.meshes.len()];
        for (k, item) in items.iter().enumerate() {
            let inst = &scene.instances[item.instance];
            let kind = keys[item.blas].1;
            words[2 * k + 1] = inst.material as u32
                | if kind == Kind::FrontOnly {
                    FRONT_ONLY
                } else {
                    0
                };
            if kind != Kind::Masked {
                continue;
            }
            let start = *uv_start[inst.mesh].get_or_insert_with(|| {
                let start = words.len() as u32;
                let mesh = &scene.meshes[inst.mesh];
                for &v in &mesh.indices {
                    let uv = mesh.uvs.get(v as usize).copied().unwrap_or_default();
                    words.extend([uv.x.to_bits(), uv.y.to_bits()]);
                }
                start
            });
            words[2 * k] = start;
        }
        let records = words.len() as u32;
        let bits = records + 4 * masks.records.len().max(1) as u32;
        for r in &masks.records {
            words.extend([r.first_word + bits, r.width, r.height, r.flags]);
        }
        if masks.records.is_empty() {
            words.extend([0; 4]);
        }
        words.extend_from_slice(&masks.bits);
        words.extend([0, 0, 0, records]);
        let binding_limit = limits.max_storage_buffer_binding_size;
        if words.len() as u64 * 4 > binding_limit {
            return Err(RenderError::TooLarge {
                what: "the ray geometry (texture coordinates of masked casters and their masks)"
                    .into(),
                needed: words.len() as u64 * 4,
                limit: binding_limit,
                unit: "bytes",
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let geometry = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("raytraced.geometry"),
            contents: bytemuck::cast_slice(&words),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("raytraced.params"),
            contents: bytemuck::bytes_of(&RayParams {
                samples: [options.light_samples, options.seed, options.area_samples, 0],
            }),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("raytraced.tlas"),
            max_instances: items.len().max(1) as u32,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        for (k, item) in items.iter().enumerate() {
            tlas[k] = Some(wgpu::TlasInstance::new(
                &blas[item.blas],
                affine_rows(scene.instances[item.instance].transform),
                k as u32,
                0xff,
            ));
        }
        let _ = gpu;
        let built = keys
            .iter()
            .zip(sizes)
            .zip(inputs)
            .map(|((&(mesh, _), size), (vertices, indices))| Built {
                mesh,
                size,
                vertices,
                indices,
                stale: false,
                copy_from: None,
            })
            .collect();
        Ok(Self {
            blas,
            built,
            items,
            tlas,
            geometry,
            params,
            dirty: true,
        })
    }

    /// Takes the instances' transforms of `scene`; the next [`RayAccel::record`] rebuilds the
    /// TLAS if one changed.
    pub fn update(&mut self, scene: &Scene) {
        for (k, item) in self.items.iter().enumerate() {
            let t = affine_rows(scene.instances[item.instance].transform);
            let same = self.tlas[k].as_ref().is_some_and(|i| i.transform == t);
            if !same {
                self.tlas[k] = Some(wgpu::TlasInstance::new(
                    &self.blas[item.blas],
                    t,
                    k as u32,
                    0xff,
                ));
                self.dirty = true;
            }
        }
    }

    /// Mesh `mesh` bent to `positions` (as many as it had): its BLASes are built again, from
    /// these, by the next [`RayAccel::record`] (wgpu has no refit; a rebuild, measured in
    /// docs/real-content.md).
    pub fn deform(&mut self, queue: &wgpu::Queue, mesh: usize, positions: &[glam::Vec3]) {
        let flat: Vec<[f32; 3]> = positions.iter().map(|p| p.to_array()).collect();
        for b in self.built.iter_mut().filter(|b| b.mesh == mesh) {
            if b.size.vertex_count as usize == flat.len() {
                queue.write_buffer(&b.vertices, 0, bytemuck::cast_slice(&flat));
                b.stale = true;
                self.dirty = true;
            }
        }
    }

    /// Mesh `mesh` is bent on the GPU, `bytes` (first byte, length) into the scene's
    /// positions: the next [`RayAccel::record`] copies its vertices from there and builds its
    /// BLASes again.
    pub fn deform_on_gpu(&mut self, mesh: usize, bytes: (u64, u64)) {
        for b in self.built.iter_mut().filter(|b| b.mesh == mesh) {
            if u64::from(b.size.vertex_count) * 12 == bytes.1 {
                b.copy_from = Some(bytes.0);
                b.stale = true;
                self.dirty = true;
            }
        }
    }

    /// Records the builds of the BLASes of bent meshes (those bent on the GPU first copy
    /// their vertices from `positions`, the scene's), and the TLAS's if an instance moved or
    /// a BLAS was built since the last one; true if it did.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, positions: &wgpu::Buffer) -> bool {
        if !self.dirty {
            return false;
        }
        for b in &mut self.built {
            if let Some(at) = b.copy_from.take() {
                let len = u64::from(b.size.vertex_count) * 12;
                encoder.copy_buffer_to_buffer(positions, at, &b.vertices, 0, len);
            }
        }
        let entries: Vec<wgpu::BlasBuildEntry<'_>> = self
            .blas
            .iter()
            .zip(&self.built)
            .filter(|(_, b)| b.stale)
            .map(|(blas, b)| wgpu::BlasBuildEntry {
                blas,
                geometry: wgpu::BlasGeometries::TriangleGeometries(vec![
                    wgpu::BlasTriangleGeometry {
                        size: &b.size,
                        vertex_buffer: &b.vertices,
                        first_vertex: 0,
                        vertex_stride: 12,
                        index_buffer: Some(&b.indices),
                        first_index: Some(0),
                        transform_buffer: None,
                        transform_buffer_offset: None,
                    },
                ]),
            })
            .collect();
        encoder.build_acceleration_structures(entries.iter(), std::iter::once(&self.tlas));
        drop(entries);
        for b in &mut self.built {
            b.stale = false;
        }
        self.dirty = false;
        true
    }

    /// The TLAS.
    pub fn tlas(&self) -> &wgpu::Tlas {
        &self.tlas
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn affine_rows_are_the_matrix_rows() {
        let m = Mat4::from_cols_array_2d(&[
            [1.0, 2.0, 3.0, 0.0],
            [4.0, 5.0, 6.0, 0.0],
            [7.0, 8.0, 9.0, 0.0],
            [10.0, 11.0, 12.0, 1.0],
        ]);
        // Row 0 = (x_axis.x, y_axis.x, z_axis.x, w_axis.x).
        assert_eq!(
            affine_rows(m),
            [1.0, 4.0, 7.0, 10.0, 2.0, 5.0, 8.0, 11.0, 3.0, 6.0, 9.0, 12.0]
        );
    }
}
