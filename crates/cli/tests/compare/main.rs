//! `manyshadows compare` end to end on the GPU that `WGPU_BACKEND` selects (no adapter: the
//! binary exits 1 and these tests fail, never skip).
//!
//! Error bounds, and why they are what they are (measured on llvmpipe, Vulkan and OpenGL,
//! Mesa 22.3.6, 256×256 frames, 2048² maps, default bias of 1 texel in each term):
//!
//! - analytic scenes (`plane-*`): **0** misclassified pixels outside the 2-pixel edge band for
//!   every technique and light type. A flat floor under a flat occluder has no grazing
//!   surfaces and no contact lines, so nothing but the outline can be wrong, and the band
//!   holds the outline. This is the bound the renderer's own analytic test enforces, now
//!   measured against the ray-traced reference instead of a hand-written box test.
//!   Inside the band: 0 (spot, point) and 9 of 65,536 pixels (directional, 0.014 %) measured;
//!   the bound is 0.1 % of in-reach pixels, a sub-texel placement error of the outline.
//! - `cubes` (boxes and a sphere resting on a floor): 2 of 86,102 scored pixels outside the
//!   band measured, both false shadow of the spot light on the floor right at the foot of the
//!   tall box (a contact line, where the biased floor point meets the box's depth). Bound
//!   0.02 % (about 17 pixels): a handful of contact pixels, never a region.
//! - a deliberately wrong bias (−1 texel in every term: the receiver is pushed *into* its
//!   surface, so it shadows itself) gives 78 % false shadow on `plane-spot`; the test requires
//!   more than 50 %, against 0 with the default bias, so the score cannot miss acne.

#[path = "../shared_gpu/mod.rs"]
mod shared_gpu;

#[path = "../common/animated.rs"]
mod animated;
mod helpers;

mod animation;
mod bounds;
mod gpu_reference;
mod messages;
mod sequences;
mod soft;
