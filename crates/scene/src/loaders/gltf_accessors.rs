//! Reading a glTF primitive's accessors safely and in every component type the format allows.
//!
//! The `gltf` crate's readers assume a well-formed accessor (a stride too small for an element
//! or an empty sparse section misbehaves), and its position and normal readers read floats
//! whatever the accessor holds. So the layout is checked first, and vertex attributes are read
//! by their component type: floats, and the integer types `KHR_mesh_quantization` allows
//! (positions as signed or unsigned bytes or shorts, normalized or not; normals as normalized
//! signed bytes or shorts; texture coordinates as bytes or shorts, normalized or not; what
//! gltfpack and meshopt-compressed files use), turned into floats as the specification says
//! (`c / 127`, `c / 255`, `c / 32767`, `c / 65535` for normalized types, signed ones clamped
//! at −1; the value itself otherwise, the node transform dequantizing it).

use std::path::Path;

use ::gltf::accessor::{DataType, Dimensions, Iter};
use ::gltf::Accessor;
use glam::{Vec2, Vec3};

use super::common::parse_error;
use crate::error::SceneError;

/// A component type, and whether it is normalized.
pub(super) type Component = (DataType, bool);

/// What `POSITION` may hold.
pub(super) const POSITION_TYPES: &[Component] = &[
    (DataType::F32, false),
    (DataType::I8, false),
    (DataType::I8, true),
    (DataType::U8, false),
    (DataType::U8, true),
    (DataType::I16, false),
    (DataType::I16, true),
    (DataType::U16, false),
    (DataType::U16, true),
];

/// What `NORMAL` may hold.
pub(super) const NORMAL_TYPES: &[Component] = &[
    (DataType::F32, false),
    (DataType::I8, true),
    (DataType::I16, true),
];

/// What `TEXCOORD_n` may hold.
pub(super) const TEXCOORD_TYPES: &[Component] = &[
    (DataType::F32, false),
    (DataType::U8, true),
    (DataType::U16, true),
    (DataType::I8, false),
    (DataType::I8, true),
    (DataType::U8, false),
    (DataType::I16, false),
    (DataType::I16, true),
    (DataType::U16, false),
];

/// What indices may hold.
pub(super) const INDEX_TYPES: &[Component] = &[
    (DataType::U8, false),
    (DataType::U16, false),
    (DataType::U32, false),
];

/// Checks an accessor's buffer views are safe to hand to the crate's readers.
pub(super) fn check_layout(
    a: &Accessor<'_>,
    bad: &dyn Fn(String) -> SceneError,
) -> Result<(), SceneError> {
    let size = a.size();
    let views = a
        .view()
        .into_iter()
        .chain(a.sparse().map(|s| s.values().view()));
    for v in views {
        if let Some(stride) = v.stride() {
            if stride < size {
                return Err(bad(format!(
                    "buffer view stride {stride} is smaller than an element ({size} bytes)"
                )));
            }
        }
    }
    if let Some(s) = a.sparse() {
        if s.count() == 0 {
            return Err(bad("accessor has an empty sparse section".into()));
        }
    }
    Ok(())
}

/// Checks an accessor holds `dims` of one of `types`, with a safe layout; the error names the
/// primitive (`label`) and the attribute (`what`).
pub(super) fn check_accessor(
    path: &Path,
    label: &str,
    what: &str,
    a: &Accessor<'_>,
    types: &[Component],
    dims: Dimensions,
) -> Result<(), SceneError> {
    let bad =
        |reason: String| parse_error(path, format!("glTF primitive {label}: {what} {reason}"));
    if !types.contains(&(a.data_type(), a.normalized())) || a.dimensions() != dims {
        let allowed: Vec<String> = types
            .iter()
            .map(|(t, n)| format!("{t:?}{}", if *n { " (normalized)" } else { "" }))
            .collect();
        return Err(bad(format!(
            "accessor has type {:?} {:?}{}; expected {dims:?} of {}",
            a.dimensions(),
            a.data_type(),
            if a.normalized() { " (normalized)" } else { "" },
            allowed.join(", ")
        )));
    }
    check_layout(a, &bad)
}

/// Reads `N`-component elements of whatever component type the accessor has, as floats.
macro_rules! read_floats {
    ($a:expr, $get:expr, $n:literal) => {{
        let a: &Accessor<'_> = $a;
        let norm = a.normalized();
        let out: Option<Vec<[f32; $n]>> = match a.data_type() {
            DataType::F32 => Iter::<[f32; $n]>::new(a.clone(), $get).map(|it| it.collect()),
            DataType::I8 => Iter::<[i8; $n]>::new(a.clone(), $get).map(|it| {
                it.map(|v| {
                    v.map(|c| {
                        if norm {
                            (c as f32 / 127.0).max(-1.0)
                        } else {
                            c as f32
                        }
                    })
                })
                .collect()
            }),
            DataType::U8 => Iter::<[u8; $n]>::new(a.clone(), $get).map(|it| {
                it.map(|v| v.map(|c| if norm { c as f32 / 255.0 } else { c as f32 }))
                    .collect()
            }),
            DataType::I16 => Iter::<[i16; $n]>::new(a.clone(), $get).map(|it| {
                it.map(|v| {
                    v.map(|c| {
                        if norm {
                            (c as f32 / 32767.0).max(-1.0)
                        } else {
                            c as f32
                        }
                    })
                })
                .collect()
            }),
            DataType::U16 => Iter::<[u16; $n]>::new(a.clone(), $get).map(|it| {
                it.map(|v| v.map(|c| if norm { c as f32 / 65535.0 } else { c as f32 }))
                    .collect()
            }),
            DataType::U32 => None,
        };
        out
    }};
}

/// A checked `VEC3` accessor as floats; `None` if its data is missing or outside its buffer.
pub(super) fn read_vec3<'a, 's, F>(a: &Accessor<'a>, get: F) -> Option<Vec<Vec3>>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    read_floats!(a, get, 3).map(|v| v.into_iter().map(Vec3::from_array).collect())
}

/// A checked `VEC2` accessor as floats; `None` if its data is missing or outside its buffer.
pub(super) fn read_vec2<'a, 's, F>(a: &Accessor<'a>, get: F) -> Option<Vec<Vec2>>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    read_floats!(a, get, 2).map(|v| v.into_iter().map(Vec2::from_array).collect())
}

/// A checked `SCALAR` accessor of floats (what animation key times are); `None` if its data
/// is missing or outside its buffer, or not floats.
pub(super) fn read_scalar<'a, 's, F>(a: &Accessor<'a>, get: F) -> Option<Vec<f32>>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    match a.data_type() {
        DataType::F32 => Iter::<f32>::new(a.clone(), get).map(|it| it.collect()),
        _ => None,
    }
}

/// A checked `VEC4` accessor as floats; `None` if its data is missing or outside its buffer.
pub(super) fn read_vec4<'a, 's, F>(a: &Accessor<'a>, get: F) -> Option<Vec<glam::Vec4>>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    read_floats!(a, get, 4).map(|v| v.into_iter().map(glam::Vec4::from_array).collect())
}

/// A checked `VEC4` accessor of unsigned bytes or shorts (skin joints); `None` if its data is
/// missing or outside its buffer, or of another type.
pub(super) fn read_joints<'a, 's, F>(a: &Accessor<'a>, get: F) -> Option<Vec<[u16; 4]>>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    match a.data_type() {
        DataType::U8 => {
            Iter::<[u8; 4]>::new(a.clone(), get).map(|it| it.map(|v| v.map(u16::from)).collect())
        }
        DataType::U16 => Iter::<[u16; 4]>::new(a.clone(), get).map(|it| it.collect()),
        _ => None,
    }
}

/// A checked `SCALAR` accessor of floats or normalized integers, as floats; `None` if its
/// data is missing or outside its buffer, or of another type.
pub(super) fn read_scalar_any<'a, 's, F>(a: &Accessor<'a>, get: F) -> Option<Vec<f32>>
where
    F: Clone + Fn(::gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let norm = a.normalized();
    match (a.data_type(), norm) {
        (DataType::F32, _) => Iter::<f32>::new(a.clone(), get).map(|it| it.collect()),
        (DataType::I8, true) => Iter::<i8>::new(a.clone(), get)
            .map(|it| it.map(|c| (c as f32 / 127.0).max(-1.0)).collect()),
        (DataType::U8, true) => {
            Iter::<u8>::new(a.clone(), get).map(|it| it.map(|c| c as f32 / 255.0).collect())
        }
        (DataType::I16, true) => Iter::<i16>::new(a.clone(), get)
            .map(|it| it.map(|c| (c as f32 / 32767.0).max(-1.0)).collect()),
        (DataType::U16, true) => {
            Iter::<u16>::new(a.clone(), get).map(|it| it.map(|c| c as f32 / 65535.0).collect())
        }
        _ => None,
    }
}
