//! Shadow maps in one depth atlas: the atlas and its per-view buffers ([`storage`]), the
//! interface every technique implements ([`technique`]), one module per technique with its
//! WGSL beside it ([`traditional`], [`layered`], [`multiview`], [`gpu_driven`], [`compute`]),
//! what they share without importing each other (`shared`), the [`generator`] that drives
//! one frame after frame (caching), and the frame's [`source`] made of it. Each technique
//! module declares itself (`INFO`); [`crate::shadows::registry`] lists them.

pub mod compute;
pub mod generator;
pub mod gpu_driven;
pub mod layered;
pub mod multiview;
pub(crate) mod shared;
pub mod source;
pub mod storage;
pub mod technique;
pub mod traditional;
