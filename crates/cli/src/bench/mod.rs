//! `manyshadows bench …`: one module per benchmark, and what they share: the measuring loop
//! (warm-up, round-robin runs, medians, progress, results: [`harness`]) and the plots
//! ([`plot`]).

pub(crate) mod animation;
pub(crate) mod denoise;
mod denoise_table;
pub(crate) mod estimate;
pub(crate) mod harness;
pub(crate) mod irregular;
pub(crate) mod layered;
pub(crate) mod lights;
pub(crate) mod omni;
pub(crate) mod plot;
pub(crate) mod probes;
pub(crate) mod shadows;
pub(crate) mod soak;
pub(crate) mod soft;
pub(crate) mod stereo;
pub(crate) mod suite;
pub(crate) mod virtual_maps;
