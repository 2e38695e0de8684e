//! What a frame hands the reference and gets back: its surface points (one per pixel, from
//! the G-buffer), a bit mask per pixel and light (hard shadows), and a fraction per pixel and
//! light (soft shadows).

use glam::Vec3;

use crate::error::ReferenceError;

/// The surface seen by one pixel: a point of the frame's G-buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// World position.
    pub position: Vec3,
    /// Unit normal facing the camera (the G-buffer flips back faces).
    pub normal: Vec3,
}

/// The surface points of a whole frame, row-major from the top-left pixel; `None` where the
/// pixel saw no geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct Surfaces {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// `width · height` entries.
    pub points: Vec<Option<SurfacePoint>>,
}

impl Surfaces {
    /// Checks that `points` has `width · height` entries, all finite.
    pub fn new(
        width: u32,
        height: u32,
        points: Vec<Option<SurfacePoint>>,
    ) -> Result<Self, ReferenceError> {
        let expected = width as usize * height as usize;
        if points.len() != expected {
            return Err(ReferenceError::Mismatch {
                what: "surface points",
                expected: format!("{expected} ({width}x{height})"),
                found: points.len().to_string(),
            });
        }
        if let Some(i) = points
            .iter()
            .position(|p| p.is_some_and(|p| !(p.position.is_finite() && p.normal.is_finite())))
        {
            return Err(ReferenceError::Mismatch {
                what: "surface points",
                expected: "finite positions and normals".into(),
                found: format!("a non-finite value at pixel {i}"),
            });
        }
        Ok(Self {
            width,
            height,
            points,
        })
    }

    /// Whether each pixel saw geometry.
    pub fn covered(&self) -> Vec<bool> {
        self.points.iter().map(Option::is_some).collect()
    }
}

/// One bit per light and pixel, laid out exactly like the renderer's visibility mask (and its
/// `.msvis` file): `words_per_pixel` `u32` words per pixel, row-major from the top-left pixel;
/// bit `b` of word `w` is light `32·w + b`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Number of lights.
    pub lights: u32,
    /// `ceil(lights / 32)`, at least 1.
    pub words_per_pixel: u32,
    /// `width · height · words_per_pixel` words.
    pub words: Vec<u32>,
}

impl Mask {
    /// An all-zero mask.
    pub fn zeros(width: u32, height: u32, lights: u32) -> Self {
        let words_per_pixel = lights.div_ceil(32).max(1);
        Self {
            width,
            height,
            lights,
            words_per_pixel,
            words: vec![0; width as usize * height as usize * words_per_pixel as usize],
        }
    }

    /// Bit of `light` at pixel index `pixel` (`y · width + x`).
    pub fn get(&self, pixel: usize, light: u32) -> bool {
        let i = pixel * self.words_per_pixel as usize + (light / 32) as usize;
        self.words[i] >> (light % 32) & 1 == 1
    }

    /// The words of one pixel.
    pub fn pixel_words(&self, pixel: usize) -> &[u32] {
        let n = self.words_per_pixel as usize;
        &self.words[pixel * n..(pixel + 1) * n]
    }

    /// Checks that `other` describes the same frame and lights.
    pub fn check_same_shape(&self, other: &Mask, what: &'static str) -> Result<(), ReferenceError> {
        let shape = |m: &Mask| {
            format!(
                "{}x{} pixels, {} lights, {} words per pixel",
                m.width, m.height, m.lights, m.words_per_pixel
            )
        };
        let ok = self.width == other.width
            && self.height == other.height
            && self.lights == other.lights
            && self.words_per_pixel == other.words_per_pixel
            && other.words.len()
                == other.width as usize * other.height as usize * other.words_per_pixel as usize;
        if ok {
            Ok(())
        } else {
            Err(ReferenceError::Mismatch {
                what,
                expected: shape(self),
                found: format!("{} ({} words)", shape(other), other.words.len()),
            })
        }
    }
}

/// A visibility fraction in `[0, 1]` per pixel and light (soft shadows: the share of a sized
/// light the point sees), `lights` values per pixel, row-major from the top-left pixel: the
/// value of light `l` at pixel index `p` (`y · width + x`) is `values[p · lights + l]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Fractions {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Number of lights.
    pub lights: u32,
    /// `width · height · lights` values.
    pub values: Vec<f32>,
}

impl Fractions {
    /// All zero (nothing visible).
    pub fn zeros(width: u32, height: u32, lights: u32) -> Self {
        Self {
            width,
            height,
            lights,
            values: vec![0.0; width as usize * height as usize * lights as usize],
        }
    }

    /// Value of `light` at pixel index `pixel` (`y · width + x`).
    pub fn get(&self, pixel: usize, light: u32) -> f32 {
        self.values[pixel * self.lights as usize + light as usize]
    }

    /// Checks that `other` describes the same frame and lights as `self` (and holds as many
    /// values as it says).
    pub fn check_same_shape(
        &self,
        other: &Fractions,
        what: &'static str,
    ) -> Result<(), ReferenceError> {
        let shape = |f: &Fractions| format!("{}x{} pixels, {} lights", f.width, f.height, f.lights);
        let ok = self.width == other.width
            && self.height == other.height
            && self.lights == other.lights
            && other.values.len()
                == other.width as usize * other.height as usize * other.lights as usize;
        if ok {
            Ok(())
        } else {
            Err(ReferenceError::Mismatch {
                what,
                expected: shape(self),
                found: format!("{} ({} values)", shape(other), other.values.len()),
            })
        }
    }
}
