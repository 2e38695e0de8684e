//! Shadows, between the frame's passes that feed them (G-buffer, clusters) and those that read
//! them (lighting, visibility). From the bottom up:
//!
//! - [`plan`]: every shadow view of a frame and its atlas tile, and the priority fit;
//! - [`depth`] and [`cluster_draw`]: the depth-only pipelines every shadow map is drawn with,
//!   and the cluster culling + indirect multi-draw rounds `gpu-driven` and the virtual maps
//!   share (with their WGSL); [`image`]: depth read-back and pictures;
//! - [`source`]: the [`ShadowSource`](source::ShadowSource) trait the renderer drives, its
//!   output, and the view table of the sources that fill no atlas;
//! - [`descriptor`]: how a technique declares itself (`TechniqueInfo`), with its price list for
//!   the frame estimate ([`cost`]) and how the lighting pass reads it ([`lookup`]);
//! - one folder per kind of source: [`atlas`] (the atlas, its techniques, the caching
//!   generator), [`irregular`] (a visibility mask), [`vsm`] (virtual shadow maps: a page pool),
//!   [`raytraced`] (acceleration structures and shadow rays); the registry (`crate::registry`)
//!   is the one place a technique becomes a source.
//!
//! `shadow_lookup.wgsl` (view selection, bias, atlas addressing) and `paraboloid.wgsl` (the
//! dual-paraboloid warp) lie here too: every pass that reads shadows composes them
//! ([`crate::gpu::shaders`]).

pub mod atlas;
pub mod cluster_draw;
pub mod cost;
pub mod depth;
pub mod descriptor;
pub mod image;
pub mod irregular;
pub mod lookup;
pub mod options;
pub mod plan;
pub mod raytraced;
pub mod report;
pub mod source;
pub mod storage;
pub mod technique;
pub mod vsm;
