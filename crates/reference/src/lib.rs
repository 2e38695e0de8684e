//! # manyshadows-reference
//!
//! The exact answer that every shadow technique is scored against, on the CPU, with no GPU
//! code:
//!
//! - [`Tracer`]: every triangle of every shadow-casting instance in world space, in a BVH
//!   ([obvhs](https://docs.rs/obvhs)' compressed wide BVH), with a watertight two-sided
//!   ray/triangle test (casters are two-sided in the shadow passes too);
//! - [`visibility`]: per pixel and light, "within the light's reach and unoccluded" — the same
//!   bit the renderer's visibility mask holds — by casting one ray from the pixel's own
//!   G-buffer point towards the light (rayon-parallel over rows);
//! - [`score`]: a technique's mask against the reference: false shadow and false light among
//!   the pixels the light reaches, with a tolerance band at the reference's shadow edges
//!   counted separately, and per-pixel error classes for difference images;
//! - [`aliasing`]: perspective aliasing in numbers, the shadow-texel footprint in screen pixels.
//!
//! Why the G-buffer's points and not the reference's own camera rays: the reference then
//! answers for exactly the surface points the frame shaded, so rasterization differences
//! (coverage, depth precision, silhouettes) can never count as shadow error.

pub mod aliasing;
pub mod error;
pub mod frame;
pub mod score;
mod tracer;
pub mod visibility;

pub use error::ReferenceError;
pub use frame::{Mask, SurfacePoint, Surfaces};
pub use tracer::Tracer;
pub use visibility::{
    in_reach, ray_offset, reach_and_facing, reference_visibility, ReferenceVisibility,
};
