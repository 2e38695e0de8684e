//! Light-space maths: every view-projection a shadow technique must fill.
//!
//! Seed 004 gives the three light types their projections, and this module follows it:
//!
//! - a **spot light** is one perspective view along its axis, its near and far planes pulled in
//!   as tight as the light allows ("the far plane can be decreased to match the light's area of
//!   influence"): far = the light's range;
//! - a **point light** is six cube-face views. Read the seed's 45° as the half-angle: each
//!   face's full field of view is **90°**, the only angle at which six frusta tile the sphere
//!   with no gaps and no overlaps;
//! - a **directional light** is orthographic, and, after the seed's terrain-renderer post,
//!   **cascaded**: the camera frustum is cut into slices (the practical split scheme,
//!   λ·logarithmic + (1−λ)·uniform) and each slice gets its own map, so texels near the camera
//!   are small and texels far away are large. One cascade is the plain single-map fallback.
//!
//! The trade-offs chosen here, and why:
//!
//! - **Near planes** are `max(range·0.002, 0.01)` ([`LIGHT_NEAR_FRACTION`], [`LIGHT_NEAR_MIN`]):
//!   a far/near ratio of 500 keeps depth precision usable across the whole range while clipping
//!   only occluders closer than 0.2 % of the range to the light.
//! - **Maps are a little wider than what they must cover**: [`PCF_MARGIN_TEXELS`] texels on
//!   every side of a spot cone and of a cascade's sphere (plus half a texel for snapping), so
//!   a 3×3 PCF kernel centred on the edge still reads inside the map.
//! - **Cascades are fitted with a bounding sphere, not a tight box.** A sphere's size does not
//!   change when the camera turns, so the texel size stays constant and the map's origin can be
//!   **snapped to whole texels**: shadows stay still instead of shimmering as the camera moves.
//!   The price is resolution (the sphere wastes the corners of the map). The sphere is the
//!   smallest one around the slice (centre on the view axis), its radius rounded up to 1/16 of
//!   its octave so float noise cannot change the texel size from frame to frame.
//! - **Cascades cover only the depth range the scene occupies**: the camera's near/far are
//!   clamped to the view depths of the scene's world bounds ([`view_depth_range`]), so no
//!   cascade is spent on empty space past the last object (or before the first).
//! - **Cascade depth ranges reach every shadow caster** in the scene's bounds, so an occluder
//!   outside a slice (a tall tower behind the camera) still casts into it.
//!
//! Conventions everywhere: right-handed views looking down −Z, wgpu clip depth 0..1, standard
//! depth (near → 0, far → 1, depth test `Less`).
//!
//! The parts, by job: `common` holds what the views of every light type share (near planes,
//! the PCF margin, up vectors), `spot`, `point` and `cascades` make the views of one light
//! type, `view` is the value a technique renders, `scene_views` makes every view of a scene,
//! and `culling` tests spheres against frusta and views. Their public items are re-exported
//! here, the paths users name.

mod cascades;
mod common;
mod culling;
mod point;
mod scene_views;
mod spot;
mod view;

#[cfg(test)]
mod testing;

pub use cascades::{
    cascade_splits, directional_fit, frustum_slice_corners, slice_bounding_sphere,
    view_depth_range, DirectionalFit,
};
pub use common::{
    light_depth_range, stable_up, LIGHT_NEAR_FRACTION, LIGHT_NEAR_MIN, PCF_MARGIN_TEXELS,
};
pub use culling::{frustum_planes, sphere_in_planes};
pub use point::{
    cube_face_for, cube_face_views, paraboloid_project, paraboloid_views, PointShadows, CUBE_FACES,
};
pub use scene_views::{shadow_views, shadow_views_with};
pub use spot::{spot_half_fov, spot_view};
pub use view::{ShadowView, ViewKind};
