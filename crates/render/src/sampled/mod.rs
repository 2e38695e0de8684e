//! Sampled lights and their histories: the lighting pass's draws of K lights per pixel by
//! importance (`lights.wgsl`: stratified over frames where they are denoised), the reservoirs
//! that reuse the draws across frames and neighbouring pixels ([`reuse`]), the denoiser of
//! their shadow ratio ([`denoise`]), and the motion of instances between frames that both
//! histories follow ([`motion`]). What the lighting pass composes of them is
//! [`lighting_parts`]: the renderer hands those parts to it (the lighting pass, a floor below,
//! names none of them).

pub mod denoise;
pub mod motion;
pub mod options;
pub mod pages;
pub mod reuse;

use crate::gpu::bindings::Part;
use crate::sampled::options::MAX_LIGHT_SAMPLES;

/// The lighting pass's parts of sampled lights: the draws (always: the light loop visits
/// every light through them, and without samples they add each light whole; with `choose`,
/// their choose pass too, which with `choose == Some(true)` hands its draws to the lighting
/// pass: [`pages`]), reuse's and the denoiser's (each doing nothing where its buffers are
/// `None`).
pub fn lighting_parts<'a>(
    denoise: Option<&'a denoise::DenoiseBuffers>,
    reuse: Option<&'a reuse::Reuse>,
    choose: Option<bool>,
) -> Vec<Part<'a>> {
    let mut draws = draws(choose == Some(true));
    if choose.is_some() {
        draws.own = &[pages::CHOOSE];
    }
    vec![
        draws,
        reuse::lighting_part(reuse),
        denoise::lighting_part(denoise),
    ]
}

/// [`lighting_parts`]' WGSL and bindings alone (no resources): with the denoiser or not, with
/// reuse (and its spatial mode) or not: what a shader is composed of.
#[cfg(test)]
pub fn lighting_parts_declared(
    denoise: bool,
    reuse: Option<options::SpatialReuse>,
) -> Vec<Part<'static>> {
    vec![
        draws(false),
        reuse::lighting_part_declared(reuse),
        denoise::lighting_part_declared(denoise),
    ]
}

/// The draws of sampled lights (`lights.wgsl`); with `carry`, the choose pass hands them to
/// the lighting pass ([`pages::PageWants::carry`]).
fn draws(carry: bool) -> Part<'static> {
    Part::wgsl(format!(
        "const MAX_SAMPLES: u32 = {MAX_LIGHT_SAMPLES}u;\nconst CARRY: bool = {carry};\n{}{}",
        pages::wants_wgsl(),
        include_str!("lights.wgsl")
    ))
}
