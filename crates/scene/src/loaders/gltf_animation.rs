//! A glTF document's animations (glTF 2.0 §3.11): the node tree at rest and every clip's
//! translation, rotation and scale channels, as [`Animations`] (what they do with them is
//! said there).
//!
//! Accessors are checked before they are read: key times are `SCALAR` floats; translations and
//! scales `VEC3` floats; rotations `VEC4` floats or the normalized integer types §3.11.5
//! allows. A channel that cannot play (a type the specification does not allow, data outside
//! its buffer, key times not finite or not increasing, values not finite, a count that does
//! not match its interpolation, a zero rotation) is dropped, and the clip's note says which
//! and why; a clip left without channels is dropped with it. Morph-target weight channels
//! (`SCALAR`, as many weights per key as the node's mesh has targets) play too.
//!
//! Skins (§3.7.3): a skinned node's primitives are read in the mesh's own coordinates with
//! their `JOINTS_0` and `WEIGHTS_0` (`gltf_geometry`); here each gets its joints and inverse
//! bind matrices (`MAT4` floats, the identity where absent) as a [`Skin`]. A skin that cannot
//! bend its mesh (a vertex naming a joint the skin lacks, a joint outside the tree, matrices
//! not finite or too few) is refused by name: there is no sensible mesh to draw instead.

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::animation::{Interpolation as GltfInterpolation, Property as GltfProperty};
use glam::{Mat4, Quat, Vec3, Vec4};

use std::path::Path;

use super::common::parse_error;
use super::gltf_accessors::{check_layout, read_scalar, read_scalar_any, read_vec3, read_vec4};
use super::gltf_geometry::{MorphedPrimitive, SkinnedPrimitive};
use super::gltf_open::Opened;
use crate::animation::{
    Animations, Channel, Clip, Interpolation, Morph, Node, Property, Skin, WeightChannel,
};
use crate::error::SceneError;
use crate::model::Mesh;

/// The animations and skins of `opened`, and notes on what was dropped. `meshes` are the
/// document's meshes (`skinned`: each one's skin, its vertices still in the mesh's own
/// coordinates, as the skin's bind data); a skin that cannot bend its mesh is refused by name.
pub(super) fn read_animations(
    path: &Path,
    opened: &Opened,
    meshes: &[Mesh],
    skinned: Vec<Option<SkinnedPrimitive>>,
    morphed: Vec<Option<MorphedPrimitive>>,
    notes: &mut Vec<String>,
) -> Result<Animations, SceneError> {
    let document = &opened.document;
    let buffers = &opened.buffers;
    let get = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(|d| d.0.as_slice());
    if document.animations().len() == 0
        && skinned.iter().all(Option::is_none)
        && morphed.iter().all(Option::is_none)
    {
        return Ok(Animations::default());
    }
    let mut nodes: Vec<Node> = document
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            Node {
                parent: None,
                rest: Mat4::from_cols_array_2d(&n.transform().matrix()),
                translation: Vec3::from_array(t),
                rotation: Quat::from_array(r).normalize(),
                scale: Vec3::from_array(s),
            }
        })
        .collect();
    for n in document.nodes() {
        for c in n.children() {
            if let Some(child) = nodes.get_mut(c.index()) {
                child.parent = Some(n.index());
            }
        }
    }
    let mut clips = Vec::new();
    for (k, anim) in document.animations().enumerate() {
        let name = anim
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("animation {k}"));
        let mut channels = Vec::new();
        let mut weights = Vec::new();
        let mut dropped = Vec::new();
        for (c, channel) in anim.channels().enumerate() {
            let target = channel.target();
            let property = match target.property() {
                GltfProperty::Translation => Property::Translation,
                GltfProperty::Rotation => Property::Rotation,
                GltfProperty::Scale => Property::Scale,
                GltfProperty::MorphTargetWeights => {
                    let node = target.node().index();
                    let sampler = channel.sampler();
                    match read_weights(&sampler, &get, nodes.len(), node) {
                        Ok(w) => weights.push(w),
                        Err(why) => {
                            dropped.push(format!("channel {c} (node {node} weights): {why}"))
                        }
                    }
                    continue;
                }
            };
            let sampler = channel.sampler();
            let interpolation = match sampler.interpolation() {
                GltfInterpolation::Step => Interpolation::Step,
                GltfInterpolation::Linear => Interpolation::Linear,
                GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let node = target.node().index();
            let read = read_channel(&sampler, property, &get).and_then(|(times, values)| {
                let ch = Channel {
                    node,
                    property,
                    interpolation,
                    times,
                    values,
                };
                match ch.problem(nodes.len()) {
                    Some(why) => Err(why),
                    None => Ok(ch),
                }
            });
            match read {
                Ok(ch) => channels.push(ch),
                Err(why) => dropped.push(format!(
                    "channel {c} (node {node} {}): {why}",
                    property.name()
                )),
            }
        }
        if !dropped.is_empty() {
            notes.push(format!(
                "animation '{name}': {} dropped, the rest plays",
                dropped.join("; ")
            ));
        }
        if channels.is_empty() && weights.is_empty() {
            if !dropped.is_empty() {
                notes.push(format!(
                    "animation '{name}' has nothing left to play: dropped"
                ));
            }
            continue;
        }
        clips.push(Clip {
            name,
            channels,
            weights,
        });
    }
    let mut skins = Vec::new();
    for (mesh, primitive) in skinned.into_iter().enumerate() {
        let Some(primitive) = primitive else {
            continue;
        };
        let refuse = |why: String| {
            parse_error(
                path,
                format!(
                    "glTF skin {} of mesh {}: {why}",
                    primitive.skin,
                    meshes.get(mesh).map_or("?", |m| m.name.as_str())
                ),
            )
        };
        let skin = document
            .skins()
            .nth(primitive.skin)
            .ok_or_else(|| refuse("no such skin".into()))?;
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind = match skin.inverse_bind_matrices() {
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(a) => {
                if a.data_type() != DataType::F32 || a.dimensions() != Dimensions::Mat4 {
                    return Err(refuse(format!(
                        "inverse bind matrices are {:?} {:?}, not MAT4 floats",
                        a.dimensions(),
                        a.data_type()
                    )));
                }
                check_layout(&a, &bad("inverse bind matrices")).map_err(|e| refuse(reason(e)))?;
                ::gltf::accessor::Iter::<[[f32; 4]; 4]>::new(a.clone(), get)
                    .map(|it| it.map(|m| Mat4::from_cols_array_2d(&m)).collect::<Vec<_>>())
                    .filter(|m| m.len() == a.count())
                    .ok_or_else(|| refuse("inverse bind matrices outside their buffer".into()))?
            }
        };
        let m = &meshes[mesh];
        let s = Skin {
            mesh,
            joints,
            inverse_bind,
            vertex_joints: primitive.joints,
            vertex_weights: primitive.weights,
            extra_joints: primitive.extra_joints,
            extra_weights: primitive.extra_weights,
            bind_positions: m.positions.clone(),
            bind_normals: m.normals.clone(),
        };
        if let Some(why) = s.problem(nodes.len()) {
            return Err(refuse(why));
        }
        skins.push(s);
    }
    let morphs = morphed
        .into_iter()
        .enumerate()
        .filter_map(|(mesh, m)| {
            let m = m?;
            let base = &meshes[mesh];
            Some(Morph {
                mesh,
                node: m.node,
                base_positions: base.positions.clone(),
                base_normals: base.normals.clone(),
                position_deltas: m.positions,
                normal_deltas: m.normals,
                default_weights: m.weights,
            })
        })
        .collect();
    Ok(Animations {
        nodes: std::mem::take(&mut nodes),
        clips,
        moving: Vec::new(),
        skins,
        morphs,
        bent_bounds: Default::default(),
    })
}

/// A weights channel's keys, checked: `SCALAR` floats (or the normalized integer types
/// §3.11.5 allows), as many per key as the node's mesh has targets.
fn read_weights<'a, 's, F>(
    sampler: &::gltf::animation::Sampler<'a>,
    get: &F,
    nodes: usize,
    node: usize,
) -> Result<WeightChannel, String>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let input = sampler.input();
    if input.data_type() != DataType::F32 || input.dimensions() != Dimensions::Scalar {
        return Err("key times are not SCALAR floats".into());
    }
    check_layout(&input, &bad("key times")).map_err(reason)?;
    let output = sampler.output();
    let allowed = [
        (DataType::F32, false),
        (DataType::I8, true),
        (DataType::U8, true),
        (DataType::I16, true),
        (DataType::U16, true),
    ];
    if output.dimensions() != Dimensions::Scalar
        || !allowed.contains(&(output.data_type(), output.normalized()))
    {
        return Err(format!(
            "weights are {:?} {:?}, not SCALAR floats or normalized integers",
            output.dimensions(),
            output.data_type()
        ));
    }
    check_layout(&output, &bad("weights")).map_err(reason)?;
    let times = read_scalar(&input, get.clone())
        .filter(|t| t.len() == input.count())
        .ok_or("key times are missing or outside their buffer")?;
    let values = read_scalar_any(&output, get.clone())
        .filter(|v| v.len() == output.count())
        .ok_or("weights are missing or outside their buffer")?;
    let interpolation = match sampler.interpolation() {
        GltfInterpolation::Step => Interpolation::Step,
        GltfInterpolation::Linear => Interpolation::Linear,
        GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let per_key = if interpolation == Interpolation::CubicSpline {
        3
    } else {
        1
    };
    let targets = values.len() / (per_key * times.len()).max(1);
    let ch = WeightChannel {
        node,
        interpolation,
        times,
        targets,
        values,
    };
    match ch.problem(nodes) {
        Some(why) => Err(why),
        None => Ok(ch),
    }
}

/// A sampler's key times and values, checked; the error says why it cannot be read.
fn read_channel<'a, 's, F>(
    sampler: &::gltf::animation::Sampler<'a>,
    property: Property,
    get: &F,
) -> Result<(Vec<f32>, Vec<Vec4>), String>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let input = sampler.input();
    if input.data_type() != DataType::F32
        || input.normalized()
        || input.dimensions() != Dimensions::Scalar
    {
        return Err(format!(
            "key times are {:?} {:?}, not SCALAR floats",
            input.dimensions(),
            input.data_type()
        ));
    }
    check_layout(&input, &bad("key times")).map_err(reason)?;
    let output = sampler.output();
    let (dims, allowed): (Dimensions, &[(DataType, bool)]) = match property {
        Property::Rotation => (
            Dimensions::Vec4,
            &[
                (DataType::F32, false),
                (DataType::I8, true),
                (DataType::U8, true),
                (DataType::I16, true),
                (DataType::U16, true),
            ],
        ),
        _ => (Dimensions::Vec3, &[(DataType::F32, false)]),
    };
    if output.dimensions() != dims || !allowed.contains(&(output.data_type(), output.normalized()))
    {
        return Err(format!(
            "values are {:?} {:?}{}, which a {} channel cannot hold",
            output.dimensions(),
            output.data_type(),
            if output.normalized() {
                " (normalized)"
            } else {
                ""
            },
            property.name()
        ));
    }
    check_layout(&output, &bad("values")).map_err(reason)?;
    let times = read_scalar(&input, get.clone())
        .filter(|t| t.len() == input.count())
        .ok_or("key times are missing or outside their buffer")?;
    let values = match dims {
        Dimensions::Vec4 => read_vec4(&output, get.clone()),
        _ => {
            read_vec3(&output, get.clone()).map(|v| v.into_iter().map(|v| v.extend(0.0)).collect())
        }
    }
    .filter(|v: &Vec<Vec4>| v.len() == output.count())
    .ok_or("values are missing or outside their buffer")?;
    Ok((times, values))
}

/// A parse error of `what` (its path empty: [`reason`] takes the words out).
fn bad(what: &'static str) -> impl Fn(String) -> SceneError {
    move |reason: String| SceneError::Parse {
        path: std::path::PathBuf::new(),
        reason: format!("{what} {reason}"),
    }
}

/// The reason inside a parse error.
fn reason(e: SceneError) -> String {
    match e {
        SceneError::Parse { reason, .. } => reason,
        other => other.to_string(),
    }
}
