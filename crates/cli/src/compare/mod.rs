//! `manyshadows compare`: every shadow technique scored against the exact CPU reference.
//!
//! One frame's G-buffer is read back; `manyshadows-reference` casts a ray from each pixel's
//! surface point to each light through a BVH of every shadow-casting triangle. Each technique
//! (at each requested shadow resolution) then renders the same frame, and its hard visibility
//! mask is scored against the reference: false shadow and false light among the pixels a light
//! reaches, with errors in the edge band reported apart, plus the shadow-texel footprint in
//! screen pixels (perspective aliasing). When lights have sizes, the CPU also traces the soft
//! reference (the fraction of each light each pixel sees) and each technique's soft visibility
//! and shaded frame are scored against it. Results: a table, optional JSON, difference images
//! and ꟻLIP error maps.
//!
//! The parts, in the order a run uses them: `args` (the flags and the long help), `run` (the
//! steps, per scene), `setup` (checks, scene, variants, settings, GPU and BVH), `scoring`
//! (each variant rendered and scored), `reference` (traced once, on the CPU or the GPU),
//! `soft` (the soft reference and the soft scores), `images` (the frame, the reference mask,
//! the difference images and ꟻLIP maps), `report` (the JSON) and `table` (what is printed);
//! `sequence` scores `--frames N` frames instead, each against the exact image of that frame.

mod args;
mod images;
mod reference;
mod report;
mod run;
mod scoring;
mod sequence;
mod setup;
mod soft;
mod table;

pub use args::{CompareArgs, LONG_ABOUT};
pub use run::run;
