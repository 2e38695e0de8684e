//! What reads the shadows, above every shadow source: the deferred lighting pass, the
//! visibility pass (the hard mask per pixel and light) and the copy of a frame into a caller's
//! texture. They read a source's [`crate::shadows::source::ShadowOutput`] and compose its
//! lookup WGSL into their own. Each pass's WGSL lies beside it.

pub(crate) mod blit;
pub mod denoise;
pub mod lighting;
pub mod look;
pub mod probes;
pub mod reuse;
pub mod visibility;
