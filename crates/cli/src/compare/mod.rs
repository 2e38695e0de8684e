//! `manyshadows compare`: every shadow technique scored against the exact CPU reference.
//!
//! One frame's G-buffer is read back; `manyshadows-reference` casts a ray from each pixel's
//! surface point to each light through a BVH of every shadow-casting triangle. Each technique
//! (at each requested shadow resolution) then renders the same frame, and its hard visibility
//! mask is scored against the reference: false shadow and false light among the pixels a light
//! reaches, with errors in the edge band reported apart, plus the shadow-texel footprint in
//! screen pixels (perspective aliasing). Results: a table, optional JSON, difference images.
//!
//! The parts, in the order a run uses them: `args` (the flags and the long help), `run` (the
//! steps, per scene), `setup` (checks, scene, variants, settings, GPU and BVH), `scoring`
//! (each variant rendered and scored), `reference` (traced once, on the CPU or the GPU),
//! `images` (the frame, the reference mask and the difference images), `report` (the JSON)
//! and `table` (what is printed).

mod args;
mod images;
mod reference;
mod report;
mod run;
mod scoring;
mod setup;
mod table;

pub use args::{CompareArgs, LONG_ABOUT};
pub use run::run;
