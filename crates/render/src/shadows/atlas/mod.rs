//! Shadow maps in one depth atlas: one module per technique with its WGSL beside it
//! ([`traditional`], [`layered`], [`multiview`], [`gpu_driven`], [`compute`]), what they share
//! without importing each other (`shared`), the [`generator`] that drives one frame after
//! frame (caching), and the frame's [`source`] made of it. The atlas and the interface every
//! technique implements are a floor below ([`crate::shadows::storage`],
//! [`crate::shadows::technique`]). Each technique module declares itself (`INFO`); the
//! registry (`crate::registry`) lists them.

pub mod compute;
pub mod generator;
pub mod gpu_driven;
pub mod layered;
pub mod multiview;
pub(crate) mod shared;
pub mod source;
pub mod traditional;
