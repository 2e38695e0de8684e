//! What the camera sees, below the shadows: the G-buffer and its read-back, the light
//! clusters, and the visibility mask as data. Every shadow source reads these; the passes that
//! read the sources' output are in [`crate::shading`]. Each pass's WGSL lies beside it.

pub mod clusters;
pub mod eyes;
pub mod gbuffer;
pub mod gbuffer_pull;
pub mod gbuffer_readback;
mod gbuffer_record;
pub mod gbuffer_shaders;
pub mod visibility_mask;
