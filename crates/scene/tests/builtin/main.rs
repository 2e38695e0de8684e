//! Tests of the built-in scenes, their seeded light layouts and the procedural primitives.
//!
//! The scenes are test and benchmark fixtures for the whole project, so what other code relies
//! on is pinned here: triangle and instance counts, light counts and types, determinism per
//! seed, the exact parameters of the analytic scenes, and the winding/normal conventions of
//! every generated mesh.
//!
//! By subject: what holds for every scene and the light options (`every_scene`), one module per
//! scene (`atrium`, `terrain`, `dragon`, `analytic`, `cubes_and_layout` with the generic light
//! layout), the lights' sizes (`light_sizes`) and the procedural primitives (`primitives`);
//! the helpers they share are in `common`.

mod analytic;
mod atrium;
mod common;
mod cubes_and_layout;
mod dragon;
mod every_scene;
mod light_sizes;
mod primitives;
mod terrain;
