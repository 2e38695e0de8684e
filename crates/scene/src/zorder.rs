//! Z-order (Morton) keys of points in the unit cube: sorting by them lists points near each
//! other in space near each other in the list. The renderer orders each mesh's triangles by
//! them (compact clusters for culling); the seeded light layouts order their lights by them
//! (`builtin`: the denoiser's samples stratify over space).

use glam::Vec3;

/// The 30-bit Morton key of `unit` (each coordinate clamped to [0, 1], quantized to 10 bits):
/// bit `b` of x, y and z at bits `3b`, `3b + 1` and `3b + 2`. NaN quantizes to 0.
pub fn key3(unit: Vec3) -> u32 {
    let q = (unit.clamp(Vec3::ZERO, Vec3::ONE) * 1023.0).to_array();
    let spread = |v: f32| -> u32 {
        // 10 bits → every third bit of 30.
        let mut x = (v as u32) & 0x3ff;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    spread(q[0]) | (spread(q[1]) << 1) | (spread(q[2]) << 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_interleave_x_then_y_then_z() {
        let unit = |x: u32, y: u32, z: u32| Vec3::new(x as f32, y as f32, z as f32) / 1023.0;
        assert_eq!(key3(unit(1, 0, 0)), 0b001);
        assert_eq!(key3(unit(0, 1, 0)), 0b010);
        assert_eq!(key3(unit(0, 0, 1)), 0b100);
        assert_eq!(key3(unit(2, 0, 0)), 0b001_000);
        assert_eq!(key3(Vec3::ONE), (1 << 30) - 1);
        assert_eq!(key3(Vec3::splat(f32::NAN)), 0);
        assert_eq!(key3(Vec3::splat(-5.0)), 0);
    }
}
