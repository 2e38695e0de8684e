//! `EXT_mesh_gpu_instancing`: a node that draws its mesh many times, each instance placed by
//! its own translation, rotation and scale (accessors named `TRANSLATION`, `ROTATION`,
//! `SCALE` in the node's extension). Read from the raw JSON (the `gltf` crate drops unknown
//! node extensions) through the crate's accessor readers, after checking each accessor's
//! type. Other instance attributes (`_ID`, custom ones) are ignored.

use std::path::Path;

use ::gltf::accessor::{DataType, Dimensions};
use glam::{Mat4, Quat, Vec3};

use super::common::{parse_error, too_large, MAX_TRIANGLES};
use super::gltf_open::Opened;
use crate::error::SceneError;

/// The instance transforms (`T · R · S`, in the node's space) of node `node`, if it has the
/// extension; missing attributes are the identity (zero translation, no rotation, unit
/// scale). All attributes must have the same count.
pub(super) fn instance_transforms(
    path: &Path,
    opened: &Opened,
    node: usize,
) -> Result<Option<Vec<Mat4>>, SceneError> {
    let pointer = format!("/nodes/{node}/extensions/EXT_mesh_gpu_instancing/attributes");
    let Some(attributes) = opened.json.pointer(&pointer) else {
        return Ok(None);
    };
    let bad = |reason: String| {
        parse_error(
            path,
            format!("glTF node {node}: EXT_mesh_gpu_instancing {reason}"),
        )
    };
    let accessor = |name: &str| -> Result<Option<::gltf::Accessor<'_>>, SceneError> {
        let Some(v) = attributes.get(name) else {
            return Ok(None);
        };
        let index = v
            .as_u64()
            .ok_or_else(|| bad(format!("{name} is {v}, not an accessor index")))?;
        opened
            .document
            .accessors()
            .nth(index as usize)
            .map(Some)
            .ok_or_else(|| {
                bad(format!(
                    "{name} names accessor {index}, which does not exist"
                ))
            })
    };
    let translation = accessor("TRANSLATION")?;
    let rotation = accessor("ROTATION")?;
    let scale = accessor("SCALE")?;
    let counts: Vec<usize> = [&translation, &rotation, &scale]
        .into_iter()
        .flatten()
        .map(|a| a.count())
        .collect();
    let Some(&count) = counts.first() else {
        return Ok(Some(vec![Mat4::IDENTITY])); // no attributes: one instance at the node
    };
    if counts.iter().any(|&c| c != count) {
        return Err(bad(format!(
            "attributes have different counts ({counts:?}); they must be equal"
        )));
    }
    if count > MAX_TRIANGLES {
        return Err(too_large(
            path,
            format!("glTF node {node} has {count} instances; the limit is {MAX_TRIANGLES}"),
        ));
    }
    let get = |b: ::gltf::Buffer<'_>| opened.buffers.get(b.index()).map(|d| d.0.as_slice());
    let missing = |name: &str| bad(format!("{name} data is missing or outside its buffer"));

    let vec3s = |name: &str, a: &Option<::gltf::Accessor<'_>>, default: Vec3| {
        let Some(a) = a else {
            return Ok(vec![default; count]);
        };
        if a.dimensions() != Dimensions::Vec3 || a.data_type() != DataType::F32 || a.normalized() {
            return Err(bad(format!(
                "{name} accessor has type {:?} {:?}; expected Vec3 of F32",
                a.dimensions(),
                a.data_type()
            )));
        }
        check_view(a, 12).map_err(|r| bad(format!("{name} {r}")))?;
        let v: Vec<Vec3> = ::gltf::accessor::Iter::<[f32; 3]>::new(a.clone(), get)
            .ok_or_else(|| missing(name))?
            .map(Vec3::from_array)
            .collect();
        if v.len() == count {
            Ok(v)
        } else {
            Err(missing(name))
        }
    };
    let translations = vec3s("TRANSLATION", &translation, Vec3::ZERO)?;
    let scales = vec3s("SCALE", &scale, Vec3::ONE)?;
    let rotations: Vec<Quat> = match &rotation {
        None => vec![Quat::IDENTITY; count],
        Some(a) => {
            let ok = a.dimensions() == Dimensions::Vec4
                && match a.data_type() {
                    DataType::F32 => !a.normalized(),
                    DataType::I8 | DataType::I16 => a.normalized(),
                    _ => false,
                };
            if !ok {
                return Err(bad(format!(
                    "ROTATION accessor has type {:?} {:?}; expected Vec4 of F32, or of \
                     normalized I8 or I16",
                    a.dimensions(),
                    a.data_type()
                )));
            }
            check_view(a, a.size()).map_err(|r| bad(format!("ROTATION {r}")))?;
            let raw: Option<Vec<[f32; 4]>> = match a.data_type() {
                DataType::I8 => ::gltf::accessor::Iter::<[i8; 4]>::new(a.clone(), get).map(|it| {
                    it.map(|q| q.map(|c| (c as f32 / 127.0).max(-1.0)))
                        .collect()
                }),
                DataType::I16 => {
                    ::gltf::accessor::Iter::<[i16; 4]>::new(a.clone(), get).map(|it| {
                        it.map(|q| q.map(|c| (c as f32 / 32767.0).max(-1.0)))
                            .collect()
                    })
                }
                _ => ::gltf::accessor::Iter::<[f32; 4]>::new(a.clone(), get).map(|it| it.collect()),
            };
            let raw = raw.ok_or_else(|| missing("ROTATION"))?;
            if raw.len() != count {
                return Err(missing("ROTATION"));
            }
            raw.into_iter()
                .map(|q| {
                    let q = glam::Vec4::from_array(q);
                    q.try_normalize().map_or(Quat::IDENTITY, Quat::from_vec4)
                })
                .collect()
        }
    };
    Ok(Some(
        (0..count)
            .map(|i| {
                Mat4::from_scale_rotation_translation(scales[i], rotations[i], translations[i])
            })
            .collect(),
    ))
}

/// The stride of an accessor's buffer view must hold an element (the crate's reader would
/// misbehave otherwise); sparse instance attributes are not supported.
fn check_view(a: &::gltf::Accessor<'_>, size: usize) -> Result<(), String> {
    if a.sparse().is_some() {
        return Err("accessor is sparse, which instance attributes do not support here".into());
    }
    if let Some(stride) = a.view().and_then(|v| v.stride()) {
        if stride < size {
            return Err(format!(
                "buffer view stride {stride} is smaller than an element ({size} bytes)"
            ));
        }
    }
    Ok(())
}
