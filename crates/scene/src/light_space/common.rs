//! What the views of every light type share: the near plane of a spot or point light, the
//! margin a map keeps for PCF around what it must cover, the up vector of a light view, and
//! the corners of a box (for depth ranges that must reach every caster).

use glam::Vec3;

/// Near plane of a spot or point light's projection, as a fraction of the light's range.
pub const LIGHT_NEAR_FRACTION: f32 = 0.002;

/// Smallest near plane of a spot or point light's projection, in world units.
pub const LIGHT_NEAR_MIN: f32 = 0.01;

/// Texels kept free around a spot cone and around a cascade's sphere so that a 3×3 PCF kernel
/// centred on the edge of what the map must cover still reads inside the map.
pub const PCF_MARGIN_TEXELS: f32 = 1.5;

/// Near and far planes of a spot or point light of reach `range`: `near = max(range·0.002,
/// 0.01)` (but at most half the range, for absurdly short lights), `far = range`.
pub fn light_depth_range(range: f32) -> (f32, f32) {
    let near = (range * LIGHT_NEAR_FRACTION)
        .max(LIGHT_NEAR_MIN)
        .min(range * 0.5);
    (near, range)
}

/// A world axis that is not (nearly) parallel to `dir`: +Y, or +Z when `dir` is within about
/// 8° of vertical. Used as the up vector of light views.
pub fn stable_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// The 8 corners of the box `lo..hi`.
pub(super) fn box_corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}
