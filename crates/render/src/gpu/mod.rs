//! The lowest floor: what every pass builds on, knowing nothing of the scene or of shadows.
//! The adapter and device ([`context`]), the wgpu objects every pass builds the same way
//! (`pipelines`), buffers that grow (`buffers`), read-back ([`readback`]), timer and
//! statistics queries ([`timing`]), the `#[repr(C)]` mirrors of WGSL structs ([`types`], with
//! their WGSL declarations in `common.wgsl` beside it) and the composition of every shader from
//! the WGSL files beside the modules that own them ([`shaders`]), and the fence that orders
//! draws before compute passes on OpenGL (`raster_fence`).

pub mod bindings;
pub(crate) mod buffers;
pub mod context;
pub(crate) mod pipelines;
pub(crate) mod raster_fence;
pub mod readback;
pub mod shaders;
pub mod timing;
pub mod types;
