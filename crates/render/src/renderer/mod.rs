//! The frame, assembled from its passes in the order of the algorithm:
//!
//! 1. G-buffer (world position, normal, material per pixel),
//! 2. shadows: the frame's [`ShadowSource`] (made from the technique by
//!    `registry::create`) fills an atlas, a virtual page pool or a visibility mask,
//! 3. deferred Phong lighting with the shadow test (or the mask),
//! 4. optionally, the hard visibility mask (computed from the atlas or pool; a source whose
//!    output is the mask reads it back).
//!
//! Nothing here depends on the technique: the source's [`crate::shadows::source::ShadowOutput`]
//! says what the lighting and visibility passes read.
//!
//! `state` holds the renderer (creation, the setters, deriving the GPU state from changes);
//! `frame_loop` records, submits and reads back its frames (`render`, `render_to`, GPU
//! times); `inspect` what callers read of it (plans, estimates, read-backs,
//! frames shaded with given visibility); `uniforms` the frame's uniform block; `capabilities`
//! what a device needs for stereo and probe faces in one pass.

mod capabilities;
#[cfg(not(target_arch = "wasm32"))]
mod estimate;
mod frame_loop;
mod inspect;
mod parts;
mod state;
mod uniforms;

pub use frame_loop::FramePart;
pub use state::Renderer;
