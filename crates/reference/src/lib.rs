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
//! - [`aliasing`]: perspective aliasing in numbers, the shadow-texel footprint in screen pixels;
//! - [`soft`]: soft shadows from sized lights, per pixel and light the fraction of the light
//!   the point sees: the light shapes (a spot's disc of radius `size` facing along its axis, a
//!   point light's sphere seen as its silhouette disc facing the receiver, a directional
//!   light's cone of angular diameter `size`, uniform in solid angle; size 0 is the hard
//!   reference bit for bit), sampled on an n×n jittered grid (N rounded up to a square, the
//!   concentric map onto discs, a hashed seed per pixel and light, so deterministic), one ray
//!   per sample with the hard reference's tracer, start and reach;
//! - [`soft_score`](mod@soft_score): a technique's fractions against the soft reference, the
//!   mean absolute error split by the reference's class (umbra = 0, lit = 1, penumbra
//!   between) over the pairs the hard score counts (in reach, facing the light);
//! - [`flip`](mod@flip): ꟻLIP, the perceptual difference of two shaded frames (mean error and
//!   the magma-coloured error map), through the `nv-flip` crate (native only: its C++ is not
//!   built for wasm32, where the web page traces and scores with the rest of this crate).
//!
//! Why the G-buffer's points and not the reference's own camera rays: the reference then
//! answers for exactly the surface points the frame shaded, so rasterization differences
//! (coverage, depth precision, silhouettes) can never count as shadow error.

pub mod aliasing;
pub mod error;
#[cfg(not(target_arch = "wasm32"))]
pub mod flip;
pub mod frame;
pub mod score;
pub mod soft;
pub mod soft_score;
mod tracer;
pub mod visibility;

pub use error::ReferenceError;
#[cfg(not(target_arch = "wasm32"))]
pub use flip::{flip_rgba8, FlipDifference};
pub use frame::{Fractions, Mask, SurfacePoint, Surfaces};
pub use soft::{reference_soft_visibility, SoftVisibility};
pub use soft_score::{soft_score, SoftScore};
pub use tracer::Tracer;
pub use visibility::{
    in_reach, ray_offset, reach_and_facing, reference_visibility, ReferenceVisibility,
};
