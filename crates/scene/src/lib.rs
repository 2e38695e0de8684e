//! # manyshadows-scene
//!
//! Pure scene data for manyshadows: no GPU code. It holds
//!
//! - the data model ([`Scene`], its [`animation`]s, [`Mesh`], [`Instance`], [`Material`], [`Light`], [`Camera`]),
//! - light-space maths ([`light_space`]): every view-projection a shadow technique must fill,
//! - the shadow-atlas tile allocator ([`atlas`]),
//! - file loaders ([`loaders`]: OBJ, glTF 2.0, PLY and `.ply.gz`) and the TOML scene format
//!   ([`scene_file`]),
//! - built-in scenes ([`builtin`]) and seeded light layouts, with the default sizes of their
//!   lights and overrides of every light's size ([`light_size`]).
//!
//! Everything here can be unit-tested without a graphics adapter.

pub mod animation;
pub mod atlas;
pub mod builtin;
pub mod error;
mod light;
pub mod light_size;
pub mod light_space;
pub mod loaders;
pub mod look;
pub mod masks;
mod model;
mod normals;
pub mod primitives;
pub mod scene_file;
pub mod texture;
pub mod zorder;

pub use error::SceneError;
pub use look::{Lighting, Pbr};
pub use model::*;
pub use texture::{AlphaMode, Texture, TextureRef, Wrap};
