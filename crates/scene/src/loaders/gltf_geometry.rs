//! The geometry of a glTF document: every triangle primitive reached from the default scene,
//! depth-first, as its own [`Mesh`] with the node's world transform baked in, or, for a node
//! with `EXT_mesh_gpu_instancing`, in the mesh's own coordinates with one placement per
//! instance. Accessors are checked (type, stride, sparse section) before they are read, in
//! every component type `KHR_mesh_quantization` allows (`gltf_accessors`); Draco-compressed primitives are decoded (`gltf_compressed`); strips and fans
//! become lists as the specification numbers their triangles; mirroring transforms flip the
//! winding back to counter-clockwise; positions and normals are checked finite, by vertex.

use std::path::Path;

use ::gltf::accessor::Dimensions;
use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

use super::common::{
    check_finite, check_triangles, mesh_name, parse_error, set_normals, too_large, RawTriangles,
};
use super::gltf_accessors::{
    check_accessor, read_joints, read_vec2, read_vec3, read_vec4, INDEX_TYPES, NORMAL_TYPES,
    POSITION_TYPES, TEXCOORD_TYPES,
};
use super::gltf_draco::decode_draco;
use super::gltf_instancing::instance_transforms;
use super::gltf_open::Opened;
use crate::error::SceneError;
use crate::model::Mesh;

/// A skinned primitive's skin and its vertices' joints and weights (`JOINTS_0`, `WEIGHTS_0`).
pub(super) struct SkinnedPrimitive {
    /// The document's skin.
    pub(super) skin: usize,
    /// Per vertex, four indices into the skin's joints.
    pub(super) joints: Vec<[u16; 4]>,
    /// Per vertex, the four joints' weights, summing to 1 (normalized as three.js does) with
    /// `extra_weights`.
    pub(super) weights: Vec<[f32; 4]>,
    /// `JOINTS_1` where the primitive has it (empty otherwise).
    pub(super) extra_joints: Vec<[u16; 4]>,
    /// `WEIGHTS_1` where the primitive has it (empty otherwise).
    pub(super) extra_weights: Vec<[f32; 4]>,
}

/// A primitive's morph targets, in the mesh's coordinates as loaded (the node's rest transform
/// baked into the displacements as into the vertices).
pub(super) struct MorphedPrimitive {
    /// The node whose weights shape it.
    pub(super) node: usize,
    /// Per target, a displacement per vertex.
    pub(super) positions: Vec<Vec<Vec3>>,
    /// Per target, a normal displacement per vertex (zeros where the target has none).
    pub(super) normals: Vec<Vec<Vec3>>,
    /// The node's default weights, else the mesh's, else zeros.
    pub(super) weights: Vec<f32>,
}

/// Most morph targets a primitive may have.
const MAX_MORPH_TARGETS: usize = 256;

/// The triangle meshes of a document, in depth-first node order.
pub(super) struct Geometry<'a> {
    pub(super) meshes: Vec<Mesh>,
    /// The glTF material of each mesh (`None`: the primitive names none).
    pub(super) materials: Vec<Option<usize>>,
    /// The placements of each mesh: the identity (the node's transform is baked in), or one
    /// per instance of an `EXT_mesh_gpu_instancing` node.
    pub(super) transforms: Vec<Vec<Mat4>>,
    /// The node each mesh is drawn at (`None`: a document without scenes, or a skinned mesh,
    /// which its joints place).
    pub(super) mesh_nodes: Vec<Option<usize>>,
    /// Each mesh's skin, for a skinned node's primitives (in the mesh's own coordinates).
    pub(super) skinned: Vec<Option<SkinnedPrimitive>>,
    /// Each mesh's morph targets, for a primitive that has them.
    pub(super) morphed: Vec<Option<MorphedPrimitive>>,
    /// Remarks on instances left out.
    pub(super) notes: Vec<String>,
    /// Every node reached from the default scene with its world transform, depth-first.
    pub(super) nodes: Vec<(::gltf::Node<'a>, Mat4)>,
    /// Point and line primitives skipped.
    pub(super) skipped: usize,
}

pub(super) fn read_geometry<'a>(
    path: &Path,
    opened: &'a Opened,
) -> Result<Geometry<'a>, SceneError> {
    let document = &opened.document;
    let buffers = &opened.buffers;
    let get = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(|d| d.0.as_slice());
    let mut out = Geometry {
        meshes: Vec::new(),
        materials: Vec::new(),
        transforms: Vec::new(),
        mesh_nodes: Vec::new(),
        skinned: Vec::new(),
        morphed: Vec::new(),
        notes: Vec::new(),
        nodes: Vec::new(),
        skipped: 0,
    };
    let mut total_triangles = 0usize;
    // `world` is baked into the vertices; `placed` are the mesh's placements.
    let mut emit = |out: &mut Geometry<'a>,
                    node: Option<usize>,
                    mesh: ::gltf::Mesh<'a>,
                    world: Mat4,
                    placed: &[Mat4],
                    skin: Option<usize>| {
        for prim in mesh.primitives() {
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                log::debug!(
                    "{}: skipping a {:?} primitive of mesh {} (only triangles are loaded)",
                    path.display(),
                    mode,
                    mesh.index()
                );
                out.skipped += 1;
                continue;
            }
            let label = match mesh.name() {
                Some(n) => format!("{n}#{}", prim.index()),
                None => format!("mesh{}#{}", mesh.index(), prim.index()),
            };
            let draco = opened.json.pointer(&format!(
                "/meshes/{}/primitives/{}/extensions/KHR_draco_mesh_compression",
                mesh.index(),
                prim.index()
            ));
            let read = match draco {
                Some(_) if skin.is_some() => {
                    return Err(parse_error(
                        path,
                        format!(
                            "glTF primitive {label} is skinned and Draco-compressed, which this \
                             loader does not read (decompress it, e.g. with gltf-transform)"
                        ),
                    ))
                }
                Some(ext) => decode_draco(path, &label, opened, ext)?,
                None => read_primitive(path, &label, &prim, &get)?,
            };
            let vertices = read.positions.len();
            let targets = prim.morph_targets().len();
            let morphed = match node {
                Some(n) if targets > 0 => {
                    if draco.is_some() {
                        return Err(parse_error(
                            path,
                            format!(
                                "glTF primitive {label} has morph targets and is \
                                 Draco-compressed, which this loader does not read (decompress \
                                 it, e.g. with gltf-transform)"
                            ),
                        ));
                    }
                    let defaults = opened
                        .document
                        .nodes()
                        .nth(n)
                        .and_then(|n| n.weights())
                        .or(mesh.weights())
                        .unwrap_or(&[]);
                    Some(read_morph_targets(
                        path, &label, &prim, &get, vertices, world, n, defaults,
                    )?)
                }
                _ => None,
            };
            let skinned = match skin {
                Some(skin) => {
                    let (joints, weights, extra_joints, extra_weights) =
                        read_skin_attributes(path, &label, &prim, &get, vertices)?;
                    Some(SkinnedPrimitive {
                        skin,
                        joints,
                        weights,
                        extra_joints,
                        extra_weights,
                    })
                }
                None => None,
            };
            let m = finish(
                path,
                &label,
                read,
                world,
                skinned.is_some() || morphed.is_some(),
            )?;
            if m.indices.is_empty() {
                continue;
            }
            total_triangles += m.triangle_count();
            check_triangles(path, total_triangles)?;
            out.meshes.push(m);
            out.materials.push(prim.material().index());
            out.transforms.push(placed.to_vec());
            out.mesh_nodes
                .push(if skinned.is_some() { None } else { node });
            out.skinned.push(skinned);
            out.morphed.push(morphed);
        }
        Ok::<(), SceneError>(())
    };

    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => {
            // Depth-first walk with an explicit stack; a node reached twice means the "tree" has
            // a cycle or shared child, which the specification forbids.
            let mut seen = vec![false; document.nodes().len()];
            let mut stack: Vec<(::gltf::Node<'a>, Mat4)> =
                scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
            stack.reverse();
            while let Some((node, parent)) = stack.pop() {
                if std::mem::replace(&mut seen[node.index()], true) {
                    return Err(parse_error(
                        path,
                        format!(
                            "glTF: node {} is reached twice (the node graph is not a tree)",
                            node.index()
                        ),
                    ));
                }
                let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
                if let (Some(mesh), Some(skin)) = (node.mesh(), node.skin()) {
                    // A skinned mesh is placed by its joints alone (the node's own transform
                    // is ignored, glTF 2.0 §3.7.3.3): its vertices stay in its own coordinates.
                    emit(
                        &mut out,
                        Some(node.index()),
                        mesh,
                        Mat4::IDENTITY,
                        &[Mat4::IDENTITY],
                        Some(skin.index()),
                    )?;
                } else if let Some(mesh) = node.mesh() {
                    match instance_transforms(path, opened, node.index())? {
                        // The node's mesh is drawn once per instance, at world × instance
                        // (EXT_mesh_gpu_instancing), and not at the node itself.
                        Some(instances) => {
                            let (placed, singular): (Vec<Mat4>, Vec<Mat4>) = instances
                                .into_iter()
                                .map(|t| world * t)
                                .partition(|t| t.is_finite() && t.determinant().abs() >= 1e-12);
                            if !singular.is_empty() {
                                out.notes.push(format!(
                                    "node {}: {} of its {} instances are scaled to nothing or \
                                     not finite: left out",
                                    node.index(),
                                    singular.len(),
                                    singular.len() + placed.len()
                                ));
                            }
                            if !placed.is_empty() {
                                emit(
                                    &mut out,
                                    Some(node.index()),
                                    mesh,
                                    Mat4::IDENTITY,
                                    &placed,
                                    None,
                                )?;
                            }
                        }
                        None => emit(
                            &mut out,
                            Some(node.index()),
                            mesh,
                            world,
                            &[Mat4::IDENTITY],
                            None,
                        )?,
                    }
                }
                let children: Vec<_> = node.children().collect();
                stack.extend(children.into_iter().rev().map(|c| (c, world)));
                out.nodes.push((node, world));
            }
        }
        None => {
            for mesh in document.meshes() {
                emit(
                    &mut out,
                    None,
                    mesh,
                    Mat4::IDENTITY,
                    &[Mat4::IDENTITY],
                    None,
                )?;
            }
        }
    }
    Ok(out)
}

/// Triangle `i` of a strip is `(v_i, v_{i+1+i%2}, v_{i+2-i%2})` (glTF 2.0, §3.7.2.1), which
/// keeps every triangle's winding that of the first.
pub(crate) fn strip_to_list(v: &[u32]) -> Vec<u32> {
    let n = v.len().saturating_sub(2);
    let mut out = Vec::with_capacity(3 * n);
    for i in 0..n {
        out.extend_from_slice(&[v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]]);
    }
    out
}

/// Triangle `i` of a fan is `(v_{i+1}, v_{i+2}, v_0)` (glTF 2.0, §3.7.2.1).
pub(crate) fn fan_to_list(v: &[u32]) -> Vec<u32> {
    let n = v.len().saturating_sub(2);
    let mut out = Vec::with_capacity(3 * n);
    for i in 0..n {
        out.extend_from_slice(&[v[i + 1], v[i + 2], v[0]]);
    }
    out
}

/// Reads a primitive through its accessors.
fn read_primitive<'p, 's, F>(
    path: &Path,
    label: &str,
    prim: &'p ::gltf::Primitive<'p>,
    get: &F,
) -> Result<RawTriangles, SceneError>
where
    F: Clone + Fn(::gltf::Buffer<'p>) -> Option<&'s [u8]>,
{
    let mode = prim.mode();
    let pos_acc = prim.get(&Semantic::Positions).ok_or_else(|| {
        parse_error(
            path,
            format!("glTF primitive {label} has no POSITION attribute"),
        )
    })?;
    check_accessor(
        path,
        label,
        "POSITION",
        &pos_acc,
        POSITION_TYPES,
        Dimensions::Vec3,
    )?;
    let vertex_count = pos_acc.count();
    if vertex_count == 0 {
        return Ok(RawTriangles {
            positions: Vec::new(),
            normals: None,
            uvs: Vec::new(),
            indices: Vec::new(),
        });
    }
    if vertex_count > u32::MAX as usize {
        return Err(too_large(
            path,
            format!("glTF primitive {label} has {vertex_count} vertices"),
        ));
    }
    let normal_acc = prim
        .get(&Semantic::Normals)
        .filter(|a| a.count() == vertex_count);
    if let Some(a) = &normal_acc {
        check_accessor(path, label, "NORMAL", a, NORMAL_TYPES, Dimensions::Vec3)?;
    }
    let uv_acc = prim
        .get(&Semantic::TexCoords(0))
        .filter(|a| a.count() == vertex_count);
    if let Some(a) = &uv_acc {
        check_accessor(
            path,
            label,
            "TEXCOORD_0",
            a,
            TEXCOORD_TYPES,
            Dimensions::Vec2,
        )?;
    }
    let index_acc = prim.indices();
    let listed = match &index_acc {
        Some(a) => {
            check_accessor(path, label, "indices", a, INDEX_TYPES, Dimensions::Scalar)?;
            a.count()
        }
        None => vertex_count,
    };
    check_triangles(
        path,
        match mode {
            Mode::Triangles => listed / 3,
            _ => listed.saturating_sub(2),
        },
    )?;

    let reader = prim.reader(get.clone());
    let missing = |what: &str| {
        parse_error(
            path,
            format!("glTF primitive {label}: {what} data is missing or outside its buffer"),
        )
    };
    let positions = read_vec3(&pos_acc, get.clone()).ok_or_else(|| missing("POSITION"))?;
    if positions.len() != vertex_count {
        return Err(missing("POSITION"));
    }
    let normals: Option<Vec<Vec3>> = match &normal_acc {
        Some(a) => Some(read_vec3(a, get.clone()).ok_or_else(|| missing("NORMAL"))?),
        None => None,
    };
    let uvs: Vec<Vec2> = match &uv_acc {
        Some(a) => {
            let uvs = read_vec2(a, get.clone()).ok_or_else(|| missing("TEXCOORD_0"))?;
            if uvs.len() != vertex_count {
                return Err(missing("TEXCOORD_0"));
            }
            uvs
        }
        None => Vec::new(),
    };
    let listed: Vec<u32> = match &index_acc {
        Some(a) => {
            let idx: Vec<u32> = reader
                .read_indices()
                .ok_or_else(|| missing("indices"))?
                .into_u32()
                .collect();
            if idx.len() != a.count() {
                return Err(missing("indices"));
            }
            idx
        }
        None => (0..vertex_count as u32).collect(),
    };
    let indices = match mode {
        Mode::TriangleStrip => strip_to_list(&listed),
        Mode::TriangleFan => fan_to_list(&listed),
        _ => {
            if !listed.len().is_multiple_of(3) {
                return Err(parse_error(
                    path,
                    format!(
                        "glTF primitive {label}: {} indices is not a multiple of 3",
                        listed.len()
                    ),
                ));
            }
            listed
        }
    };
    Ok(RawTriangles {
        positions,
        normals,
        uvs,
        indices,
    })
}

/// Checks a primitive's vertices and bakes the node's world transform into them.
/// `smooth`: normals the file lacks are computed without splitting vertices at creases (a
/// skinned primitive's vertices must stay those its joints and weights are given for).
fn finish(
    path: &Path,
    label: &str,
    read: RawTriangles,
    world: Mat4,
    smooth: bool,
) -> Result<Mesh, SceneError> {
    let name = mesh_name(path, Some(label));
    let RawTriangles {
        positions,
        normals,
        uvs,
        mut indices,
    } = read;
    check_finite(&name, &positions, normals.as_deref())?;
    // Bake the node's world transform.
    let positions: Vec<Vec3> = positions
        .into_iter()
        .map(|p| world.transform_point3(p))
        .collect();
    let linear = Mat3::from_mat4(world);
    let det = linear.determinant();
    if det < 0.0 {
        // A mirroring transform turns counter-clockwise triangles clockwise; swap two corners.
        for t in indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    let normals = if det.is_finite() && det.abs() > 1e-30 {
        let normal_matrix = linear.inverse().transpose();
        normals.map(|ns| ns.into_iter().map(|n| normal_matrix * n).collect())
    } else {
        None // a singular transform flattens the mesh: derive normals from what is left
    };
    let mut mesh = Mesh {
        name,
        positions,
        normals: Vec::new(),
        uvs,
        indices,
    };
    super::common::check_indices(&mesh)?;
    if smooth && normals.is_none() {
        mesh.compute_normals();
    } else {
        set_normals(&mut mesh, normals);
    }
    Ok(mesh)
}

/// A primitive's morph targets (`POSITION` and `NORMAL` displacements, of the types those
/// attributes allow), one per vertex, taken through the linear part of `world` (normals
/// through its inverse transpose) as the vertices are baked.
#[allow(clippy::too_many_arguments)]
fn read_morph_targets<'p, 's, F>(
    path: &Path,
    label: &str,
    prim: &'p ::gltf::Primitive<'p>,
    get: &F,
    vertices: usize,
    world: Mat4,
    node: usize,
    defaults: &[f32],
) -> Result<MorphedPrimitive, SceneError>
where
    F: Clone + Fn(::gltf::Buffer<'p>) -> Option<&'s [u8]>,
{
    let targets = prim.morph_targets().len();
    if targets > MAX_MORPH_TARGETS {
        return Err(too_large(
            path,
            format!(
                "glTF primitive {label} has {targets} morph targets (at most {MAX_MORPH_TARGETS})"
            ),
        ));
    }
    let linear = Mat3::from_mat4(world);
    let normal_matrix = if linear.determinant().abs() > 1e-30 {
        linear.inverse().transpose()
    } else {
        Mat3::IDENTITY
    };
    let mut out = MorphedPrimitive {
        node,
        positions: Vec::with_capacity(targets),
        normals: Vec::with_capacity(targets),
        weights: (0..targets)
            .map(|k| defaults.get(k).copied().unwrap_or(0.0))
            .collect(),
    };
    for (k, target) in prim.morph_targets().enumerate() {
        let what = |a: &str| format!("morph target {k} {a}");
        let read = |a: Option<::gltf::Accessor<'p>>, name: &str, types, m: Mat3| {
            let Some(a) = a else {
                return Ok(vec![Vec3::ZERO; vertices]);
            };
            check_accessor(path, label, &what(name), &a, types, Dimensions::Vec3)?;
            let d = read_vec3(&a, get.clone())
                .filter(|d| d.len() == vertices)
                .ok_or_else(|| {
                    parse_error(
                        path,
                        format!(
                            "glTF primitive {label}: {} is missing, outside its buffer or not \
                             one per vertex",
                            what(name)
                        ),
                    )
                })?;
            if d.iter().any(|v| !v.is_finite()) {
                return Err(parse_error(
                    path,
                    format!("glTF primitive {label}: {} is not finite", what(name)),
                ));
            }
            Ok::<_, SceneError>(d.into_iter().map(|v| m * v).collect::<Vec<Vec3>>())
        };
        out.positions.push(read(
            target.positions(),
            "POSITION",
            POSITION_TYPES,
            linear,
        )?);
        out.normals.push(read(
            target.normals(),
            "NORMAL",
            NORMAL_TYPES,
            normal_matrix,
        )?);
    }
    if out.weights.iter().any(|w| !w.is_finite()) {
        return Err(parse_error(
            path,
            format!("glTF primitive {label}: a default morph weight is not finite"),
        ));
    }
    Ok(out)
}

/// Per vertex, four joints and their weights (`JOINTS_0`, `WEIGHTS_0`), and four more where
/// the primitive has `JOINTS_1` and `WEIGHTS_1` (empty otherwise).
type JointsAndWeights = (Vec<[u16; 4]>, Vec<[f32; 4]>, Vec<[u16; 4]>, Vec<[f32; 4]>);

/// One set of four joints and weights a vertex, as read.
type OneSet = (Vec<[u16; 4]>, Vec<Vec4>);

/// A skinned primitive's `JOINTS_0` (unsigned bytes or shorts) and `WEIGHTS_0` (floats, or
/// normalized unsigned bytes or shorts), one per vertex, and `JOINTS_1`/`WEIGHTS_1` where both
/// are given (up to eight joints a vertex); each vertex's weights normalized to sum 1 over all
/// its joints (a vertex whose weights are all 0 follows its first joint), as three.js's loader
/// does.
fn read_skin_attributes<'p, 's, F>(
    path: &Path,
    label: &str,
    prim: &'p ::gltf::Primitive<'p>,
    get: &F,
    vertices: usize,
) -> Result<JointsAndWeights, SceneError>
where
    F: Clone + Fn(::gltf::Buffer<'p>) -> Option<&'s [u8]>,
{
    use ::gltf::accessor::DataType;
    let bad =
        |what: String| parse_error(path, format!("glTF primitive {label} is skinned: {what}"));
    let read_set = |set: u32| -> Result<Option<OneSet>, SceneError> {
        let (jn, wn) = (format!("JOINTS_{set}"), format!("WEIGHTS_{set}"));
        let (Some(joints), Some(weights)) = (
            prim.get(&Semantic::Joints(set)),
            prim.get(&Semantic::Weights(set)),
        ) else {
            return Ok(None);
        };
        check_accessor(
            path,
            label,
            &jn,
            &joints,
            &[(DataType::U8, false), (DataType::U16, false)],
            Dimensions::Vec4,
        )?;
        check_accessor(
            path,
            label,
            &wn,
            &weights,
            &[
                (DataType::F32, false),
                (DataType::U8, true),
                (DataType::U16, true),
            ],
            Dimensions::Vec4,
        )?;
        let j = read_joints(&joints, get.clone())
            .filter(|j| j.len() == vertices)
            .ok_or_else(|| {
                bad(format!(
                    "{jn} is missing, outside its buffer or not one per vertex"
                ))
            })?;
        let w = read_vec4(&weights, get.clone())
            .filter(|w| w.len() == vertices)
            .ok_or_else(|| {
                bad(format!(
                    "{wn} is missing, outside its buffer or not one per vertex"
                ))
            })?;
        if let Some((v, w)) = w
            .iter()
            .enumerate()
            .find(|(_, w)| !w.is_finite() || w.min_element() < 0.0)
        {
            return Err(bad(format!("vertex {v} has {wn} {w} (finite, 0 or more)")));
        }
        Ok(Some((j, w)))
    };
    let (j0, w0) = read_set(0)?.ok_or_else(|| bad("it has no JOINTS_0 and WEIGHTS_0".into()))?;
    let (j1, w1) = read_set(1)?.unwrap_or_default();
    let mut n0 = Vec::with_capacity(vertices);
    let mut n1 = Vec::with_capacity(w1.len());
    for (v, w) in w0.iter().enumerate() {
        let extra = w1.get(v).copied();
        let sum = w.element_sum() + extra.map_or(0.0, Vec4::element_sum);
        if sum > 0.0 {
            n0.push((*w / sum).to_array());
            if let Some(e) = extra {
                n1.push((e / sum).to_array());
            }
        } else {
            n0.push([1.0, 0.0, 0.0, 0.0]);
            if extra.is_some() {
                n1.push([0.0; 4]);
            }
        }
    }
    Ok((j0, n0, j1, n1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_follow_the_specification() {
        assert_eq!(
            strip_to_list(&[0, 1, 2, 3, 4]),
            vec![0, 1, 2, 1, 3, 2, 2, 3, 4]
        );
        assert_eq!(fan_to_list(&[0, 1, 2, 3]), vec![1, 2, 0, 2, 3, 0]);
        assert!(strip_to_list(&[0, 1]).is_empty());
        assert!(fan_to_list(&[]).is_empty());
    }
}
