//! Light-space maths: every view-projection a shadow technique must fill.
//!
//! STUB: interface fixed, bodies to be written.

use glam::{Mat4, Vec3};

use crate::{Camera, LightKind, Scene};

/// Which part of a light a shadow view covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewKind {
    /// The single perspective view of a spot light.
    Spot,
    /// Cube face `0..6` of a point light, in the order +X, −X, +Y, −Y, +Z, −Z.
    CubeFace(u8),
    /// Cascade `0..count` of a directional light, nearest first.
    Cascade(u8),
}

/// One view-projection that a shadow technique renders into one atlas tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowView {
    /// Index of the light in [`Scene::lights`].
    pub light: usize,
    /// Which part of the light this view covers.
    pub kind: ViewKind,
    /// World → light view.
    pub view: Mat4,
    /// Light view → clip (wgpu conventions: depth 0..1, right-handed view looking down −Z).
    pub proj: Mat4,
    /// `proj * view`.
    pub view_proj: Mat4,
    /// Near plane distance of the projection (light view space).
    pub near: f32,
    /// Far plane distance of the projection (light view space).
    pub far: f32,
    /// True for orthographic projections (directional cascades).
    pub orthographic: bool,
    /// Texel resolution of the square tile this view wants.
    pub resolution: u32,
    /// For cascades: camera view-space distance at which this cascade ends (the lighting pass
    /// picks the first cascade whose `split_far` exceeds the pixel's depth). 0 otherwise.
    pub split_far: f32,
    /// World-space size of one texel: for orthographic views the texel width; for
    /// perspective views the texel width at distance 1 from the light (multiply by distance).
    pub texel_world: f32,
}

/// Perspective view of a spot light: field of view 2·cutoff (plus a small margin so PCF at the
/// cone's edge stays inside), near/far hugging the light's range.
pub fn spot_view(position: Vec3, direction: Vec3, cutoff_deg: f32, range: f32, resolution: u32) -> (Mat4, Mat4, f32, f32) {
    let _ = (position, direction, cutoff_deg, range, resolution);
    unimplemented!()
}

/// The six 90° cube-face views of a point light (+X, −X, +Y, −Y, +Z, −Z) with the cube-map up
/// vectors, and the shared projection; returns `(views, proj, near, far)`.
pub fn cube_face_views(position: Vec3, range: f32) -> ([Mat4; 6], Mat4, f32, f32) {
    let _ = (position, range);
    unimplemented!()
}

/// Cascade split distances `count + 1` values from `near` to `far`: the practical scheme,
/// λ·logarithmic + (1−λ)·uniform.
pub fn cascade_splits(near: f32, far: f32, count: u32, lambda: f32) -> Vec<f32> {
    let _ = (near, far, count, lambda);
    unimplemented!()
}

/// Every shadow view of every shadow-casting light in `scene`, in light order (a spot light
/// gives 1 view, a point light 6, a directional light one per cascade), each with the light's
/// requested resolution. `aspect` is the camera image's width / height.
pub fn shadow_views(scene: &Scene, aspect: f32) -> Vec<ShadowView> {
    let _ = (scene, aspect, Camera::default(), LightKind::Point { position: Vec3::ZERO, range: 1.0 });
    unimplemented!()
}
