//! Irregular (alias-free) shadow maps, `--technique irregular`: the compute passes that test
//! every caster triangle against the camera samples under it ([`maps`], `irregular.wgsl`
//! beside it) and the frame's shadow source made of them ([`source`]).

pub mod maps;
pub mod source;
