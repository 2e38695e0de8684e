//! `manyshadows bench layered` end to end on a tiny configuration: it measures every method it
//! was asked for, writes consistent JSON, a table and plots, and rejects bad arguments cleanly.

#[path = "../shared_gpu/mod.rs"]
mod shared_gpu;

mod helpers;

mod layered;
mod runs;
mod shadows;
mod techniques;
mod virtual_maps;
