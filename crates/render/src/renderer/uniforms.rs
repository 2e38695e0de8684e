//! The frame's uniform block and the lights buffer's records.

use crate::frame::eyes::Eyes;
use crate::gpu::types::{FrameUniforms, LightData};
use crate::settings::RenderSettings;
use glam::Vec3;
use manyshadows_scene::Scene;

/// The lights buffer's records, one placeholder when there are no lights (a binding is never
/// empty).
pub(super) fn lights_or_placeholder(mut data: Vec<LightData>) -> Vec<LightData> {
    if data.is_empty() {
        data.push(bytemuck::Zeroable::zeroed());
    }
    data
}

/// The frame's uniforms; `atlas_size` is the side of the texture shadows are read from (the
/// atlas, or the virtual maps' page pool) and `max_penumbra` the widest penumbra its lookup
/// filters at one level (`ShadowOutput::max_penumbra`).
pub(super) fn frame_uniforms(
    scene: &Scene,
    s: &RenderSettings,
    (atlas_size, max_penumbra): (u32, f32),
) -> FrameUniforms {
    let cam = &scene.camera;
    let aspect = s.width as f32 / s.height as f32;
    let view = cam.view();
    let proj = cam.projection(aspect);
    let (mut look, modes) = s.look.resolve(scene).uniforms();
    // Sampled lights over shadow maps (`lookup::NO_RAYS` reads them): the seed in `look.y`;
    // the count in `soft.w` below. Shadow rays carry their own.
    let maps_sample = s.technique.info().fills != crate::error::Fills::Rays;
    look[1] = f32::from_bits(if maps_sample { s.rays.seed } else { 0 });
    let eyes = Eyes::new(cam, s.stereo, (s.width, s.height));
    let eye = |i: usize| i.min(eyes.cameras.len() - 1);
    FrameUniforms {
        view_proj: (proj * view).to_cols_array_2d(),
        view: view.to_cols_array_2d(),
        camera_pos: cam.position.extend(1.0).to_array(),
        viewport: [
            s.width as f32,
            s.height as f32,
            1.0 / s.width as f32,
            1.0 / s.height as f32,
        ],
        counts: [
            scene.lights.len() as u32,
            s.pcf.code(),
            atlas_size,
            (scene.lights.len() as u32).div_ceil(32).max(1),
        ],
        // w: world size of a pixel at view depth 1 (virtual maps pick levels by it).
        bias: [
            s.bias.constant,
            s.bias.slope,
            s.bias.normal_offset,
            2.0 / (proj.y_axis.y * s.height as f32),
        ],
        sky: SKY.extend(1.0).to_array(),
        soft: [
            s.soft.blocker_taps as f32,
            s.soft.filter_taps as f32,
            s.soft.max_penumbra.min(max_penumbra),
            if maps_sample {
                s.rays.light_samples as f32
            } else {
                0.0
            },
        ],
        look,
        modes,
        eye_view_proj: [0, 1].map(|i| eyes.view_proj(eye(i)).to_cols_array_2d()),
        eye_pos: [0, 1].map(|i| eyes.cameras[eye(i)].position.extend(1.0).to_array()),
        eyes: [eyes.eye_width as f32, eyes.cameras.len() as f32, 0.0, 0.0],
    }
}

/// Colour of pixels with no geometry (linear).
pub(super) const SKY: Vec3 = Vec3::new(0.015, 0.018, 0.03);
