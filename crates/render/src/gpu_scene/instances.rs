//! The scene on the GPU: one vertex buffer of positions (what depth-only passes read), one of
//! normals, one index buffer, and storage buffers of instances and materials. Each instance is
//! drawn with its index as `instance_index`, so shaders fetch its transform from storage.

use glam::{Mat4, Vec3, Vec4};
use manyshadows_scene::masks::MaskSet;
use manyshadows_scene::{Mesh, Scene};
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu::context::GpuContext;
use crate::gpu::types::{InstanceData, MaterialData};

/// Where one mesh lives in the shared buffers.
#[derive(Clone, Copy, Debug)]
pub struct MeshRange {
    /// First index in the index buffer.
    pub first_index: u32,
    /// Number of indices.
    pub index_count: u32,
    /// Added to every index.
    pub base_vertex: i32,
}

/// An instance ready to draw: its mesh range and world-space bounding sphere.
#[derive(Clone, Copy, Debug)]
pub struct DrawItem {
    /// Instance index (`instance_index` in shaders).
    pub instance: u32,
    /// Mesh range.
    pub mesh: MeshRange,
    /// World-space bounding sphere: centre, radius.
    pub sphere: (Vec3, f32),
    /// Drawn into shadow maps.
    pub casts_shadows: bool,
    /// Object-space bounding sphere of the mesh.
    pub object_sphere: (Vec3, f32),
    /// Material index.
    pub material: u32,
    /// Its material is alpha-tested (drawn with the alpha-testing pipelines).
    pub masked: bool,
    /// Which faces the camera sees (`Material::cull_back_faces`).
    pub camera_cull: CameraCull,
}

/// An instance whose world bounding sphere changed: (instance, before, after), each sphere
/// (centre, radius).
pub type MovedSphere = (usize, (Vec3, f32), (Vec3, f32));

/// Which faces of a draw the camera pass keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CameraCull {
    /// Both (the default: surfaces shaded from either side).
    None,
    /// The front faces, counter-clockwise on screen (glTF's single-sided materials).
    BackCcw,
    /// The front faces of a mirrored instance (negative determinant), clockwise on screen.
    BackCw,
}

/// Scene buffers on the GPU.
pub struct GpuScene {
    /// Vertex positions (`vec3<f32>`, 12-byte stride).
    pub positions: wgpu::Buffer,
    /// Vertex normals (`vec3<f32>`, 12-byte stride).
    pub normals: wgpu::Buffer,
    /// Vertex texture coordinates (`vec2<f32>`, 8-byte stride; zeros for meshes without).
    pub uvs: wgpu::Buffer,
    /// `u32` triangle indices.
    pub indices: wgpu::Buffer,
    /// `array<InstanceData>`.
    pub instances: wgpu::Buffer,
    /// `array<MaterialData>`.
    pub materials: wgpu::Buffer,
    /// One per instance, in instance order.
    pub draws: Vec<DrawItem>,
    /// Where each mesh lives in the shared buffers, in the scene's mesh order.
    pub meshes: Vec<MeshRange>,
    /// Triangles over all instances.
    pub triangles: u64,
    /// Skinning, if attached with [`GpuScene::attach_skin`] (benchmarks).
    pub skin: Option<crate::gpu_scene::skinning::GpuSkin>,
    /// The positions the last frame drew, kept with [`GpuScene::keep_last_positions`] for
    /// histories that follow bent meshes.
    pub last_positions: Option<crate::gpu_scene::last_positions::LastPositions>,
    /// The coverage bits of alpha-tested materials (read by shadow passes through the caster
    /// geometry, [`crate::gpu_scene::casters`]).
    pub masks: MaskSet,
    /// The materials' images for the camera's view.
    pub textures: crate::gpu_scene::textures::SceneTextures,
}

/// Bytes per vertex position.
pub const POSITION_STRIDE: u64 = 12;

/// Most materials a scene may have: the G-buffer keeps a pixel's material index in 16 bits
/// (the other 16 hold its metallic-roughness texel).
pub const MAX_MATERIALS: usize = 1 << 16;

/// Vertex layout of the position buffer (location 0).
pub const POSITION_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: POSITION_STRIDE,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3],
};

/// Vertex layout of the last frame's positions (location 3: gpu_scene/last_positions.rs).
pub const LAST_POSITION_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: POSITION_STRIDE,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![3 => Float32x3],
};

/// Vertex layout of the normal buffer (location 1).
pub const NORMAL_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 12,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![1 => Float32x3],
};

/// Vertex layout of the texture-coordinate buffer (location 2).
pub const UV_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 8,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![2 => Float32x2],
};

/// [`UV_LAYOUT`] at location 1 (depth-only passes with positions at 0).
pub const UV_LAYOUT_1: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 8,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![1 => Float32x2],
};

impl GpuScene {
    /// Uploads a validated scene. Fails if a buffer would exceed the device's limits.
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Result<Self, RenderError> {
        let limits = ctx.limits();
        let mut positions: Vec<[f32; 3]> = Vec::new();
        let mut normals: Vec<[f32; 3]> = Vec::new();
        let mut uvs: Vec<[f32; 2]> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut ranges = Vec::with_capacity(scene.meshes.len());
        let mut spheres = Vec::with_capacity(scene.meshes.len());
        for mesh in &scene.meshes {
            ranges.push(MeshRange {
                first_index: indices.len() as u32,
                index_count: mesh.indices.len() as u32,
                base_vertex: positions.len() as i32,
            });
            positions.extend(mesh.positions.iter().map(|p| p.to_array()));
            normals.extend(mesh.normals.iter().map(|n| n.to_array()));
            if mesh.uvs.len() == mesh.positions.len() {
                uvs.extend(mesh.uvs.iter().map(|t| t.to_array()));
            } else {
                uvs.resize(positions.len(), [0.0; 2]);
            }
            // Morton-ordered triangles: better vertex reuse in every pass (same image).
            indices.extend(morton_order(mesh));
            spheres.push(bounding_sphere(&mesh.positions));
        }
        let bytes = [
            ("positions", positions.len() as u64 * 12),
            ("indices", indices.len() as u64 * 4),
            (
                "instances",
                scene.instances.len() as u64 * std::mem::size_of::<InstanceData>() as u64,
            ),
        ];
        for (what, size) in bytes {
            let (limit, limit_name) = if what == "instances" {
                (
                    limits
                        .max_buffer_size
                        .min(limits.max_storage_buffer_binding_size),
                    "max_storage_buffer_binding_size",
                )
            } else {
                (limits.max_buffer_size, "max_buffer_size")
            };
            if size > limit {
                return Err(RenderError::TooLarge {
                    what: format!("the {what} buffer"),
                    needed: size,
                    limit,
                    unit: "bytes",
                    limit_name,
                });
            }
        }
        // Zero-sized buffers are invalid; keep one dummy element so an empty scene still renders.
        if positions.is_empty() {
            positions.push([0.0; 3]);
            normals.push([0.0, 1.0, 0.0]);
            uvs.push([0.0; 2]);
        }
        if indices.is_empty() {
            indices.extend([0, 0, 0]);
        }
        let instance_data: Vec<InstanceData> = if scene.instances.is_empty() {
            vec![InstanceData::new(Mat4::IDENTITY, 0)]
        } else {
            scene
                .instances
                .iter()
                .map(|i| InstanceData::new(i.transform, i.material as u32))
                .collect()
        };
        if scene.materials.len() > MAX_MATERIALS {
            return Err(RenderError::TooLarge {
                what: format!("the scene's {} materials", scene.materials.len()),
                needed: scene.materials.len() as u64,
                limit: MAX_MATERIALS as u64,
                unit: "materials",
                limit_name: "G-buffer material index (16 bits)",
            });
        }
        let masks = MaskSet::new(scene);
        let textures = crate::gpu_scene::textures::SceneTextures::new(ctx, scene)?;
        let layer = |layers: &[Option<u32>], t: Option<manyshadows_scene::TextureRef>| {
            t.and_then(|t| layers.get(t.texture).copied().flatten())
        };
        let mut material_data: Vec<MaterialData> = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| {
                MaterialData::new(
                    m,
                    layer(&textures.colour_layers, m.base_color_texture),
                    layer(&textures.normal_layers, m.normal_texture),
                    layer(&textures.mr_layers, m.metallic_roughness_texture),
                    layer(&textures.emissive_layers, m.emissive_texture),
                    masks.is_masked(i),
                )
            })
            .collect();
        if material_data.is_empty() {
            material_data.push(MaterialData::from(&manyshadows_scene::Material::default()));
        }
        let draws = scene
            .instances
            .iter()
            .enumerate()
            .map(|(i, inst)| {
                let (c, r) = spheres[inst.mesh];
                let m = inst.transform;
                let scale = max_axis_scale(m);
                DrawItem {
                    object_sphere: (c, r),
                    material: inst.material as u32,
                    instance: i as u32,
                    mesh: ranges[inst.mesh],
                    sphere: (m.transform_point3(c), r * scale),
                    casts_shadows: inst.casts_shadows,
                    masked: masks.is_masked(inst.material),
                    camera_cull: match scene.materials.get(inst.material) {
                        Some(mat) if mat.cull_back_faces => {
                            if m.determinant() < 0.0 {
                                CameraCull::BackCw
                            } else {
                                CameraCull::BackCcw
                            }
                        }
                        _ => CameraCull::None,
                    },
                }
            })
            .collect();
        let device = &ctx.device;
        let buf = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        Ok(Self {
            positions: buf(
                "scene.positions",
                bytemuck::cast_slice(&positions),
                wgpu::BufferUsages::VERTEX
                    | wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
            ),
            normals: buf(
                "scene.normals",
                bytemuck::cast_slice(&normals),
                wgpu::BufferUsages::VERTEX
                    | wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST,
            ),
            uvs: buf(
                "scene.uvs",
                bytemuck::cast_slice(&uvs),
                wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
            ),
            indices: buf(
                "scene.indices",
                bytemuck::cast_slice(&indices),
                wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE,
            ),
            instances: buf(
                "scene.instances",
                bytemuck::cast_slice(&instance_data),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            ),
            materials: buf(
                "scene.materials",
                bytemuck::cast_slice(&material_data),
                wgpu::BufferUsages::STORAGE,
            ),
            draws,
            meshes: ranges,
            triangles: scene.triangle_count() as u64,
            skin: None,
            last_positions: None,
            masks,
            textures,
        })
    }

    /// Skins every vertex (seed 000 §19.4.1's skeletal-animation workload). Shadow techniques
    /// then transform vertices by the bones and then by the instance's model matrix.
    pub fn attach_skin(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        skin: &crate::gpu_scene::skinning::Skin,
    ) -> Result<(), RenderError> {
        self.skin = Some(crate::gpu_scene::skinning::GpuSkin::new(ctx, scene, skin)?);
        Ok(())
    }

    /// Keeps the positions the last frame drew from now on (histories that follow the
    /// surfaces of bent meshes: the G-buffer reads them), starting as `scene`'s, which this
    /// was uploaded from.
    pub fn keep_last_positions(&mut self, ctx: &GpuContext, scene: &Scene) {
        let positions: Vec<[f32; 3]> = scene
            .meshes
            .iter()
            .flat_map(|m| m.positions.iter().map(|p| p.to_array()))
            .collect();
        self.last_positions = Some(crate::gpu_scene::last_positions::LastPositions::new(
            &ctx.device,
            &positions,
        ));
    }

    /// Rewrites mesh `mesh`'s vertices and normals (as many as it has: a skinned mesh bent)
    /// and the bounding spheres of the instances that draw it (`transform`: an instance's
    /// transform by its index); returns each such instance with its world sphere before and after.
    pub fn set_mesh_vertices(
        &mut self,
        queue: &wgpu::Queue,
        mesh: usize,
        positions: &[Vec3],
        normals: &[Vec3],
        transform: impl Fn(usize) -> Mat4,
    ) -> Vec<MovedSphere> {
        let Some(range) = self.meshes.get(mesh).copied() else {
            return Vec::new();
        };
        let at = range.base_vertex as u64 * POSITION_STRIDE;
        let flat = |v: &[Vec3]| v.iter().map(|p| p.to_array()).collect::<Vec<[f32; 3]>>();
        let now = flat(positions);
        if let Some(last) = &mut self.last_positions {
            last.note(queue, mesh, at, &now);
        }
        queue.write_buffer(&self.positions, at, bytemuck::cast_slice(&now));
        queue.write_buffer(&self.normals, at, bytemuck::cast_slice(&flat(normals)));
        self.set_mesh_sphere(mesh, bounding_sphere(positions), transform)
    }

    /// Gives every instance drawing mesh `mesh` the bounding sphere `object` (in the mesh's
    /// coordinates; `transform`: an instance's transform by its index); returns each such
    /// instance with its world sphere before and after.
    pub fn set_mesh_sphere(
        &mut self,
        mesh: usize,
        object: (Vec3, f32),
        transform: impl Fn(usize) -> Mat4,
    ) -> Vec<MovedSphere> {
        let Some(range) = self.meshes.get(mesh).copied() else {
            return Vec::new();
        };
        let mut moved = Vec::new();
        for (k, d) in self.draws.iter_mut().enumerate() {
            if d.mesh.base_vertex != range.base_vertex || d.mesh.first_index != range.first_index {
                continue;
            }
            let m = transform(k);
            let old = d.sphere;
            d.object_sphere = object;
            d.sphere = (m.transform_point3(object.0), object.1 * max_axis_scale(m));
            moved.push((k, old, d.sphere));
        }
        moved
    }

    /// Replaces one instance's model matrix (e.g. a moving object between frames) and its
    /// world bounding sphere. Out-of-range instances are ignored.
    pub fn set_instance_transform(&mut self, queue: &wgpu::Queue, instance: usize, m: Mat4) {
        let Some(d) = self.draws.get_mut(instance) else {
            return;
        };
        let (c, r) = d.object_sphere;
        d.sphere = (m.transform_point3(c), r * max_axis_scale(m));
        // A mirroring transform turns the winding the camera sees as front.
        if d.camera_cull != CameraCull::None {
            d.camera_cull = if m.determinant() < 0.0 {
                CameraCull::BackCw
            } else {
                CameraCull::BackCcw
            };
        }
        let data = InstanceData::new(m, d.material);
        queue.write_buffer(
            &self.instances,
            (instance * std::mem::size_of::<InstanceData>()) as u64,
            bytemuck::bytes_of(&data),
        );
    }
}

/// A sphere around `positions`: the centre of their box, the farthest one's distance.
fn bounding_sphere(positions: &[Vec3]) -> (Vec3, f32) {
    let (lo, hi) = positions
        .iter()
        .fold(None, |b: Option<(Vec3, Vec3)>, &p| {
            Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
        })
        .unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let c = (lo + hi) * 0.5;
    let r = positions
        .iter()
        .map(|p| p.distance(c))
        .fold(0.0f32, f32::max);
    (c, r)
}

/// Largest length of the matrix's three axes: how much it can grow a sphere.
fn max_axis_scale(m: Mat4) -> f32 {
    [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .map(|a| Vec4::truncate(*a).length())
        .fold(0.0f32, f32::max)
}

/// The mesh's triangles (as index triples) sorted along a Morton curve through their
/// centroids, so consecutive runs — the clusters — are spatially compact: tight bounding
/// spheres for frustum culling, narrow normal cones for back-face culling. Depth-only
/// rendering with a `Less` test does not depend on triangle order.
pub(crate) fn morton_order(mesh: &Mesh) -> Vec<u32> {
    let Some((lo, hi)) = mesh.bounds() else {
        return mesh.indices.clone();
    };
    let extent = (hi - lo).max(Vec3::splat(1e-12));
    let mut keyed: Vec<(u32, usize)> = mesh
        .indices
        .chunks_exact(3)
        .enumerate()
        .map(|(t, tri)| {
            let c = tri
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .sum::<Vec3>()
                / 3.0;
            (manyshadows_scene::zorder::key3((c - lo) / extent), t)
        })
        .collect();
    keyed.sort_by_key(|&(k, t)| (k, t));
    keyed
        .iter()
        .flat_map(|&(_, t)| mesh.indices[3 * t..3 * t + 3].iter().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use manyshadows_scene::light_space::{frustum_planes, sphere_in_planes as sphere_visible};

    #[test]
    fn frustum_culling_of_spheres() {
        let vp = Mat4::perspective_rh(90f32.to_radians(), 1.0, 0.1, 10.0)
            * Mat4::look_at_rh(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
        let planes = frustum_planes(vp);
        assert!(sphere_visible(&planes, Vec3::new(0.0, 0.0, -5.0), 0.1));
        assert!(
            !sphere_visible(&planes, Vec3::new(0.0, 0.0, 5.0), 1.0),
            "behind the eye"
        );
        assert!(
            !sphere_visible(&planes, Vec3::new(0.0, 0.0, -12.0), 1.0),
            "beyond far"
        );
        assert!(
            sphere_visible(&planes, Vec3::new(0.0, 0.0, -10.5), 1.0),
            "straddles far"
        );
        assert!(
            !sphere_visible(&planes, Vec3::new(8.0, 0.0, -5.0), 1.0),
            "right of the 90° cone"
        );
        assert!(
            sphere_visible(&planes, Vec3::new(5.5, 0.0, -5.0), 1.0),
            "straddles the right plane"
        );
    }
}
