//! What reads the shadows, above every shadow source: the deferred lighting pass, the
//! visibility pass (the hard mask per pixel and light), the frame's look (shading model,
//! exposure, tone map) and the copy of a frame into a caller's texture. The two passes read a
//! source's [`crate::shadows::source::ShadowOutput`] and compose its lookup WGSL into their own;
//! what else plugs into the lighting pass (sampled lights and their histories, reflection
//! probes) is handed in as parts ([`crate::gpu::bindings::Part`]) by the renderer, each made in
//! its own folder. Each pass's WGSL lies beside it.

pub(crate) mod blit;
pub mod inputs;
pub mod lighting;
pub mod look;
pub mod visibility;
