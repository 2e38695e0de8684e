//! The frame's passes, in two floors around the shadows: below [`crate::shadows`] what the
//! sources read (the G-buffer and its read-back, the light clusters, the visibility mask as
//! data), above it what reads the sources' output (lighting, the visibility pass, the copy
//! into a caller's texture). Each pass's WGSL lies beside it.

pub(crate) mod blit;
pub mod clusters;
pub mod gbuffer;
pub mod gbuffer_readback;
pub mod lighting;
pub mod visibility;
pub mod visibility_mask;
