//! A glTF document's animations (glTF 2.0 §3.11): the node tree at rest and every clip's
//! translation, rotation and scale channels, as [`Animations`] (what they do with them is
//! said there).
//!
//! Accessors are checked before they are read: key times are `SCALAR` floats; translations and
//! scales `VEC3` floats; rotations `VEC4` floats or the normalized integer types §3.11.5
//! allows. A channel that cannot play (a type the specification does not allow, data outside
//! its buffer, key times not finite or not increasing, values not finite, a count that does
//! not match its interpolation, a zero rotation) is dropped, and the clip's note says which
//! and why; a clip left without channels is dropped with it. Morph-target weight channels are
//! not played yet (the file's default weights are drawn), said in one note; so are skins.

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::animation::{Interpolation as GltfInterpolation, Property as GltfProperty};
use glam::{Mat4, Quat, Vec3, Vec4};

use super::gltf_accessors::{check_layout, read_scalar, read_vec3, read_vec4};
use super::gltf_open::Opened;
use crate::animation::{Animations, Channel, Clip, Interpolation, Node, Property};

/// The animations of `opened`, and notes on what was dropped.
pub(super) fn read_animations(opened: &Opened, notes: &mut Vec<String>) -> Animations {
    let document = &opened.document;
    let buffers = &opened.buffers;
    let get = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(|d| d.0.as_slice());
    if document.animations().len() == 0 {
        return Animations::default();
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
    let mut weights = 0usize;
    for (k, anim) in document.animations().enumerate() {
        let name = anim
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("animation {k}"));
        let mut channels = Vec::new();
        let mut dropped = Vec::new();
        for (c, channel) in anim.channels().enumerate() {
            let target = channel.target();
            let property = match target.property() {
                GltfProperty::Translation => Property::Translation,
                GltfProperty::Rotation => Property::Rotation,
                GltfProperty::Scale => Property::Scale,
                GltfProperty::MorphTargetWeights => {
                    weights += 1;
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
        if channels.is_empty() {
            if !dropped.is_empty() {
                notes.push(format!(
                    "animation '{name}' has nothing left to play: dropped"
                ));
            }
            continue;
        }
        clips.push(Clip { name, channels });
    }
    if weights > 0 {
        notes.push(format!(
            "{weights} morph-target weight channel(s) not played (morph targets are drawn at \
             the file's default weights)"
        ));
    }
    if document.skins().len() > 0 {
        notes.push(
            "skins are not applied: skinned meshes are drawn in their bind pose, at their \
             node"
                .into(),
        );
    }
    Animations {
        nodes: std::mem::take(&mut nodes),
        clips,
        moving: Vec::new(),
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
    let bad = |what: &'static str| {
        move |reason: String| crate::error::SceneError::Parse {
            path: std::path::PathBuf::new(),
            reason: format!("{what} {reason}"),
        }
    };
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

/// The reason inside a parse error.
fn reason(e: crate::error::SceneError) -> String {
    match e {
        crate::error::SceneError::Parse { reason, .. } => reason,
        other => other.to_string(),
    }
}
