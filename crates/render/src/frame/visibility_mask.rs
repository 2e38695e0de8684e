//! The visibility mask on the CPU: one bit per light and pixel, as the visibility pass
//! ([`crate::shading::visibility`]) or irregular shadow maps leave it, and its file format.
//!
//! File format written by [`VisibilityMask::write_raw`] (`.msvis`, little-endian):
//! the 8 bytes `MSVIS001`, then `u32` width, height, light count, words per pixel, then
//! `width·height·words` `u32` words row-major from the top-left pixel; bit `b` of word `w` of a
//! pixel is light `32·w + b`; set = lit (within the light's reach and unoccluded).

use std::io::Write;

/// Why bytes are not a `.msvis` file.
#[non_exhaustive]
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MaskFileError {
    /// The first 24 bytes are not the header.
    #[error("not a .msvis file (bad header)")]
    BadHeader,
    /// The header's words per pixel do not match its light count.
    #[error("{lights} lights need {expected} words per pixel, the header says {found}")]
    WordsPerPixel {
        /// Lights in the header.
        lights: u32,
        /// Words per pixel those lights need.
        expected: u32,
        /// Words per pixel in the header.
        found: u32,
    },
    /// The header's sizes overflow 64 bits.
    #[error("{width}x{height} pixels of {words_per_pixel} words overflow")]
    Overflow {
        /// Width in the header.
        width: u32,
        /// Height in the header.
        height: u32,
        /// Words per pixel in the header.
        words_per_pixel: u32,
    },
    /// The words after the header are not as many as the header says.
    #[error("{width}x{height} pixels of {words_per_pixel} words need {needed} bytes of words, found {found}")]
    Length {
        /// Width in the header.
        width: u32,
        /// Height in the header.
        height: u32,
        /// Words per pixel in the header.
        words_per_pixel: u32,
        /// Bytes of words the header asks for.
        needed: u64,
        /// Bytes of words present.
        found: u64,
    },
}

/// Per-pixel light bits read back from the GPU.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VisibilityMask {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Number of lights.
    pub lights: u32,
    /// `ceil(lights / 32)` (at least 1).
    pub words_per_pixel: u32,
    /// `width · height · words_per_pixel` words.
    pub words: Vec<u32>,
}

impl VisibilityMask {
    /// Whether `light` reaches pixel `(x, y)` unoccluded.
    pub fn lit(&self, x: u32, y: u32, light: u32) -> bool {
        let pixel = y as usize * self.width as usize + x as usize;
        let i = pixel * self.words_per_pixel as usize + (light / 32) as usize;
        self.words[i] >> (light % 32) & 1 == 1
    }

    /// Writes the `.msvis` format described in the module docs.
    pub fn write_raw(&self, mut w: impl Write) -> std::io::Result<()> {
        w.write_all(b"MSVIS001")?;
        for v in [self.width, self.height, self.lights, self.words_per_pixel] {
            w.write_all(&v.to_le_bytes())?;
        }
        for v in &self.words {
            w.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    }

    /// Reads the `.msvis` format.
    pub fn read_raw(bytes: &[u8]) -> Result<Self, MaskFileError> {
        if bytes.len() < 24 || &bytes[..8] != b"MSVIS001" {
            return Err(MaskFileError::BadHeader);
        }
        let u = |i: usize| u32::from_le_bytes(bytes[8 + 4 * i..12 + 4 * i].try_into().unwrap());
        let (width, height, lights, words_per_pixel) = (u(0), u(1), u(2), u(3));
        let expected = lights.div_ceil(32).max(1);
        if words_per_pixel != expected {
            return Err(MaskFileError::WordsPerPixel {
                lights,
                expected,
                found: words_per_pixel,
            });
        }
        // The header's sizes are checked against the bytes present before anything is
        // allocated: a header claiming 2^32 × 2^32 pixels is an error, not an allocation.
        let n = (width as u64)
            .checked_mul(height as u64)
            .and_then(|p| p.checked_mul(words_per_pixel as u64))
            .and_then(|n| n.checked_mul(4))
            .ok_or(MaskFileError::Overflow {
                width,
                height,
                words_per_pixel,
            })?;
        if bytes.len() as u64 - 24 != n {
            return Err(MaskFileError::Length {
                width,
                height,
                words_per_pixel,
                needed: n,
                found: bytes.len() as u64 - 24,
            });
        }
        let words = bytes[24..]
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        Ok(Self {
            width,
            height,
            lights,
            words_per_pixel,
            words,
        })
    }

    /// A greyscale image of one light's bits (white = lit), 8 bits per pixel.
    pub fn light_image(&self, light: u32) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.width as usize * self.height as usize);
        for y in 0..self.height {
            for x in 0..self.width {
                out.push(if self.lit(x, y, light) { 255 } else { 0 });
            }
        }
        out
    }
}

/// How much of each light reaches each pixel, 0..=255 for 0..=1, where a technique filters
/// sized lights' shadows (soft shadows) or the hard test decides (0 or 255): what the
/// visibility pass writes beside the mask when `RenderSettings::soft_visibility` asks for
/// it. 0 for pixels without geometry and lights that do not reach the pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SoftVisibility {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Lights per pixel.
    pub lights: u32,
    /// `width·height·lights` values, row-major from the top-left pixel, lights in order.
    pub values: Vec<u8>,
}

impl SoftVisibility {
    /// The fraction of light `light` reaching pixel (x, y), 0..=1.
    pub fn get(&self, x: u32, y: u32, light: u32) -> f32 {
        let i = (y as usize * self.width as usize + x as usize) * self.lights as usize;
        f32::from(self.values[i + light as usize]) / 255.0
    }

    /// The hard mask as soft visibility (each bit 0 or 255): what a technique that only
    /// answers lit or not reports.
    pub fn from_mask(mask: &VisibilityMask) -> Self {
        let mut values =
            Vec::with_capacity(mask.width as usize * mask.height as usize * mask.lights as usize);
        for y in 0..mask.height {
            for x in 0..mask.width {
                for l in 0..mask.lights {
                    values.push(if mask.lit(x, y, l) { 255 } else { 0 });
                }
            }
        }
        Self {
            width: mask.width,
            height: mask.height,
            lights: mask.lights,
            values,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::VisibilityMask;

    fn header(w: u32, h: u32, lights: u32, words: u32) -> Vec<u8> {
        let mut b = b"MSVIS001".to_vec();
        for v in [w, h, lights, words] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b
    }

    #[test]
    fn round_trip() {
        let m = VisibilityMask {
            width: 3,
            height: 2,
            lights: 40,
            words_per_pixel: 2,
            words: (0..12).map(|i| i * 0x0101_0101).collect(),
        };
        let mut bytes = Vec::new();
        m.write_raw(&mut bytes).unwrap();
        assert_eq!(VisibilityMask::read_raw(&bytes).unwrap(), m);
    }

    #[test]
    fn lying_headers_are_errors_not_allocations() {
        // Sizes whose product overflows u64, and ones that merely exceed the bytes present.
        for (w, h, lights, words) in [
            (u32::MAX, u32::MAX, u32::MAX, u32::MAX.div_ceil(32)),
            (1 << 20, 1 << 20, 64, 2),
            (2, 2, 1, 1),
        ] {
            let err = VisibilityMask::read_raw(&header(w, h, lights, words))
                .unwrap_err()
                .to_string();
            assert!(err.contains("overflow") || err.contains("need"), "{err}");
        }
        // Words per pixel that do not match the light count (lit() would read out of range).
        let mut b = header(1, 1, 64, 1);
        b.extend_from_slice(&[0; 4]);
        let err = VisibilityMask::read_raw(&b).unwrap_err();
        assert_eq!(
            err,
            super::MaskFileError::WordsPerPixel {
                lights: 64,
                expected: 2,
                found: 1
            }
        );
        assert!(err.to_string().contains("64 lights need 2 words"), "{err}");
        assert!(VisibilityMask::read_raw(b"MSVIS00").is_err());
        assert!(VisibilityMask::read_raw(b"NOTMSVIS0000000000000000").is_err());
    }
}
