//! Ray-traced shadows, `--technique raytraced`: the acceleration structures ([`accel`]) and
//! the frame's shadow source made of them ([`source`]); the rays are cast by the lighting and
//! visibility passes (`rays.wgsl` beside these).

pub mod accel;
pub mod source;
