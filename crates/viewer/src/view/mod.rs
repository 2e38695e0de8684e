//! The viewer: the renderer in a window (winit + a wgpu surface), with a fly camera
//! and an on-screen panel (egui) to switch technique, point-shadow mode, PCF, light count and
//! caching at run time and to read the frame's GPU time per stage, lights, shadow views and
//! shadow memory.
//!
//! Each frame the renderer draws straight into the window's surface texture
//! (`Renderer::render_to`), then egui draws the panel over it. A camera script (`--script`)
//! replaces the fly camera, one camera per frame, and `--exit-after` ends the run, so a test
//! can drive the window and compare a screenshot of it with `render`'s frame.
//!
//! The parts: `args` (the flags, the controls' help, the camera script), `app` (the window
//! and its event loop), `state` (what the window holds between frames), `camera` (the fly
//! controls), `frame` (one frame, from the camera to the present), `panel` (the egui panel,
//! a function per section), `player` (a glTF file's animation: clip, time, speed, paused) and `overlays` (the atlas and visibility pictures it shows).

mod app;
mod args;
mod camera;
mod frame;
mod overlays;
mod panel;
mod player;
mod state;

pub(crate) use app::run;
pub(crate) use args::{ViewArgs, CONTROLS};
