//! The shadow view: one view-projection that a shadow technique renders into one atlas tile,
//! and which part of its light it covers ([`ViewKind`]).

use glam::Mat4;

/// Which part of a light a shadow view covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewKind {
    /// The single perspective view of a spot light.
    Spot,
    /// Cube face `0..6` of a point light, in the order +X, −X, +Y, −Y, +Z, −Z.
    CubeFace(u8),
    /// Cascade `0..count` of a directional light, nearest first.
    Cascade(u8),
    /// Hemisphere `0` (towards +Y) or `1` (towards −Y) of a point light's dual-paraboloid map.
    /// Its `view` looks down −Z at the hemisphere's pole; `proj` is the identity because the
    /// paraboloid warp is not a matrix (see
    /// [`paraboloid_project`](super::point::paraboloid_project)).
    Paraboloid(u8),
}

/// One view-projection that a shadow technique renders into one atlas tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowView {
    /// Index of the light in [`Scene::lights`](crate::model::Scene::lights).
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
