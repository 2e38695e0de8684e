//! The `manyshadows` binary end to end: it renders, writes what it promises, and turns bad
//! input into a one-line error with exit code 1 (2 for argument errors), never a panic.

#[path = "../common/animated.rs"]
mod animated;
mod helpers;

mod animation;
mod bad_input;
mod estimates;
mod frames;
mod render;
mod render_flags;
mod summary;
