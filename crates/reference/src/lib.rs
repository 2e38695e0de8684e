//! # manyshadows-reference
//!
//! The exact answer that every shadow technique is scored against, on the CPU, with no GPU
//! code:
//!
//! - [`Tracer`]: every triangle of every shadow-casting instance in world space, in a BVH
//!   ([obvhs](https://docs.rs/obvhs)' compressed wide BVH), with a watertight two-sided
//!   ray/triangle test (casters are two-sided in the shadow passes too);
//! - [`visibility`]: per pixel and light, "within the light's reach and unoccluded" — the same
//!   bit the renderer's visibility mask holds — by casting one ray from the pixel's own
//!   G-buffer point towards the light (rayon-parallel over rows);
//! - [`score`]: a technique's mask against the reference: false shadow and false light among
//!   the pixels the light reaches, with a tolerance band at the reference's shadow edges
//!   counted separately, and per-pixel error classes for difference images;
//! - [`aliasing`]: perspective aliasing in numbers, the shadow-texel footprint in screen pixels.
//!
//! Why the G-buffer's points and not the reference's own camera rays: the reference then
//! answers for exactly the surface points the frame shaded, so rasterization differences
//! (coverage, depth precision, silhouettes) can never count as shadow error.

pub mod aliasing;
pub mod score;
mod tracer;
pub mod visibility;

pub use tracer::Tracer;
pub use visibility::{
    in_reach, ray_offset, reach_and_facing, reference_visibility, ReferenceVisibility,
};

use glam::Vec3;

/// Everything that can go wrong in the reference. Each message says what to do.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The scene is invalid (the same checks the renderer makes).
    #[error(transparent)]
    Scene(#[from] manyshadows_scene::SceneError),
    /// Two images or masks that must describe the same frame do not.
    #[error("{what}: expected {expected}, found {found}; score masks of the same frame and scene")]
    Mismatch {
        /// What differs.
        what: &'static str,
        /// The size or count expected.
        expected: String,
        /// The size or count found.
        found: String,
    },
}

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
