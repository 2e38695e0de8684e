//! Shadow-generation techniques, one module each with its WGSL beside it. Adding a technique
//! means a module here and one line in [`crate::shadow::Technique`].

pub mod traditional;
