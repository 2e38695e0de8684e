//! Reflection probes (seed 000's reflection cube maps), whole: what the lighting pass reads of
//! them ([`maps`]: every probe's faces, their records, the WGSL of a reflection and its part of
//! the lighting pass), how the faces are drawn through the frame's own G-buffer, shadow and
//! lighting passes and kept until what they see changes ([`faces`]), and the GPU-driven way
//! of drawing them ([`clusters`]: triangle clusters culled per face). A floor above the
//! shading passes (a face is lit by the lighting pass) and the shadows (the clusters' cull is
//! the shadow maps').

pub mod clusters;
pub mod faces;
pub mod maps;
