//! Textures: decoded RGBA8 images that materials refer to, how their coordinates wrap, and how
//! a material uses alpha.
//!
//! Images are decoded by the `image` crate (PNG and JPEG) into 8-bit RGBA, rows from the top.
//! Colour channels are sRGB-encoded (as glTF's base-colour textures are), alpha is linear. The
//! renderer uploads them with mipmaps for the camera's view; shadow passes and the CPU
//! reference read only the coverage bits derived from alpha ([`crate::masks`]), at full
//! resolution and without filtering, so every technique and the reference test the same texels.

use std::path::Path;
use std::sync::Arc;

use crate::error::SceneError;

/// Largest texture side accepted (texels).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Largest decoded image accepted, in bytes of RGBA8 (1 GiB: 16384² texels).
pub const MAX_TEXTURE_BYTES: u64 = 1 << 30;

/// An RGBA8 image, rows from the top (texture coordinate v = 0 is the first row).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// A name for messages (file name, or the generator's name).
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width · height · 4` bytes: sRGB-encoded red, green, blue and linear alpha per texel.
    /// Shared, so cloning a scene does not copy its images.
    pub rgba: Arc<[u8]>,
}

impl Texture {
    /// A texture from raw RGBA8 rows; fails if the length does not match or a side is 0 or
    /// over [`MAX_TEXTURE_SIDE`].
    pub fn new(
        name: impl Into<String>,
        width: u32,
        height: u32,
        rgba: Vec<u8>,
    ) -> Result<Self, String> {
        let t = Self {
            name: name.into(),
            width,
            height,
            rgba: rgba.into(),
        };
        t.validate()?;
        Ok(t)
    }

    /// A texture whose texel `(x, y)` is `f(x, y)` (procedural textures of built-in scenes).
    pub fn from_fn(
        name: impl Into<String>,
        width: u32,
        height: u32,
        f: impl Fn(u32, u32) -> [u8; 4],
    ) -> Self {
        let mut rgba = Vec::with_capacity(width as usize * height as usize * 4);
        for y in 0..height {
            for x in 0..width {
                rgba.extend_from_slice(&f(x, y));
            }
        }
        Self {
            name: name.into(),
            width,
            height,
            rgba: rgba.into(),
        }
    }

    /// Decodes a PNG or JPEG file (the format is read from the content, not the name).
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        Self::decode(&name, &bytes).map_err(|reason| SceneError::Parse {
            path: path.to_path_buf(),
            reason,
        })
    }

    /// Decodes PNG or JPEG bytes; `name` is used in messages. Images over
    /// [`MAX_TEXTURE_SIDE`] or [`MAX_TEXTURE_BYTES`] are refused before decoding.
    pub fn decode(name: &str, bytes: &[u8]) -> Result<Self, String> {
        let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("image {name}: {e}"))?;
        if reader.format().is_none() {
            return Err(format!(
                "image {name}: not a PNG or JPEG file (unrecognised content)"
            ));
        }
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_TEXTURE_SIDE);
        limits.max_image_height = Some(MAX_TEXTURE_SIDE);
        limits.max_alloc = Some(MAX_TEXTURE_BYTES);
        reader.limits(limits);
        let image = reader
            .decode()
            .map_err(|e| format!("image {name}: {e}"))?
            .into_rgba8();
        let (width, height) = image.dimensions();
        Self::new(name, width, height, image.into_raw())
    }

    /// Checks the size and the data length.
    pub fn validate(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 {
            return Err(format!(
                "'{}' has no texels ({}x{})",
                self.name, self.width, self.height
            ));
        }
        if self.width > MAX_TEXTURE_SIDE || self.height > MAX_TEXTURE_SIDE {
            return Err(format!(
                "'{}' is {}x{} texels; the limit is {MAX_TEXTURE_SIDE} per side",
                self.name, self.width, self.height
            ));
        }
        let want = self.width as usize * self.height as usize * 4;
        if self.rgba.len() != want {
            return Err(format!(
                "'{}' has {} bytes of data for {}x{} RGBA8 texels ({want} bytes)",
                self.name,
                self.rgba.len(),
                self.width,
                self.height
            ));
        }
        Ok(())
    }

    /// The texel at `(x, y)` (clamped to the image).
    pub fn texel(&self, x: u32, y: u32) -> [u8; 4] {
        let x = x.min(self.width - 1) as usize;
        let y = y.min(self.height - 1) as usize;
        let i = 4 * (y * self.width as usize + x);
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// This image resampled to `width`×`height` (a triangle filter; colour in linear light,
    /// alpha as it is).
    pub fn resized(&self, width: u32, height: u32) -> Texture {
        if width == self.width && height == self.height {
            return self.clone();
        }
        // Work in linear light so that averaging does not darken (sRGB is not linear).
        let linear: Vec<f32> = self
            .rgba
            .chunks_exact(4)
            .flat_map(|t| {
                [
                    srgb_to_linear(t[0]),
                    srgb_to_linear(t[1]),
                    srgb_to_linear(t[2]),
                    t[3] as f32 / 255.0,
                ]
            })
            .collect();
        let src = image::Rgba32FImage::from_raw(self.width, self.height, linear)
            .expect("the buffer holds width·height texels");
        let out =
            image::imageops::resize(&src, width, height, image::imageops::FilterType::Triangle);
        let rgba: Vec<u8> = out
            .into_raw()
            .chunks_exact(4)
            .flat_map(|t| {
                [
                    linear_to_srgb(t[0]),
                    linear_to_srgb(t[1]),
                    linear_to_srgb(t[2]),
                    (t[3].clamp(0.0, 1.0) * 255.0).round() as u8,
                ]
            })
            .collect();
        Texture {
            name: self.name.clone(),
            width,
            height,
            rgba: rgba.into(),
        }
    }

    /// Whether any texel's alpha is below 255.
    pub fn has_alpha(&self) -> bool {
        self.rgba.chunks_exact(4).any(|t| t[3] < 255)
    }
}

/// sRGB-encoded byte → linear value in 0..1 (the exact sRGB curve).
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value in 0..1 → sRGB-encoded byte (rounded).
pub fn linear_to_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// How a texture coordinate outside 0..1 maps into the image (glTF sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles (the fractional part of the coordinate).
    #[default]
    Repeat,
    /// The image tiles, every other copy mirrored.
    MirroredRepeat,
    /// Coordinates clamp to the edge texels.
    ClampToEdge,
}

impl Wrap {
    /// The code shaders use (`alpha_mask.wgsl`): 0 repeat, 1 mirrored repeat, 2 clamp.
    pub fn code(self) -> u32 {
        match self {
            Wrap::Repeat => 0,
            Wrap::MirroredRepeat => 1,
            Wrap::ClampToEdge => 2,
        }
    }

    /// `t` mapped into 0..=1 by this mode.
    pub fn apply(self, t: f32) -> f32 {
        match self {
            Wrap::Repeat => t - t.floor(),
            Wrap::MirroredRepeat => {
                let m = t - 2.0 * (t * 0.5).floor();
                if m > 1.0 {
                    2.0 - m
                } else {
                    m
                }
            }
            Wrap::ClampToEdge => t.clamp(0.0, 1.0),
        }
    }

    /// The texel column (or row) of `t` in an image `n` texels across: nearest-texel lookup,
    /// the rule every shadow pass and the CPU reference share.
    pub fn texel(self, t: f32, n: u32) -> u32 {
        // `as u32` saturates (NaN → 0), as WGSL's conversion does for in-range values.
        ((self.apply(t) * n as f32) as u32).min(n.saturating_sub(1))
    }
}

/// A material's use of a texture: which one and how its coordinates wrap.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureRef {
    /// Index into [`crate::Scene::textures`].
    pub texture: usize,
    /// Wrap mode along u (glTF `wrapS`).
    pub wrap_s: Wrap,
    /// Wrap mode along v (glTF `wrapT`).
    pub wrap_t: Wrap,
}

impl TextureRef {
    /// Texture `texture`, repeating in both directions.
    pub fn repeat(texture: usize) -> Self {
        Self {
            texture,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
        }
    }
}

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum AlphaMode {
    /// Alpha is ignored: the surface is solid.
    #[default]
    Opaque,
    /// Texels whose alpha is below the cutoff are holes (foliage, chains, lattices).
    Mask,
    /// glTF's blended transparency, which a deferred renderer with one surface per pixel and
    /// shadow maps with one depth per texel cannot show: treated as `Mask` with cutoff 0.5.
    Blend,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes() {
        assert_eq!(Wrap::Repeat.texel(1.25, 4), 1);
        assert_eq!(Wrap::Repeat.texel(-0.25, 4), 3);
        assert_eq!(Wrap::ClampToEdge.texel(1.25, 4), 3);
        assert_eq!(Wrap::ClampToEdge.texel(-3.0, 4), 0);
        assert_eq!(Wrap::MirroredRepeat.texel(1.1, 10), 9);
        assert_eq!(Wrap::MirroredRepeat.texel(1.95, 10), 0);
        assert_eq!(Wrap::MirroredRepeat.texel(0.05, 10), 0);
        assert_eq!(Wrap::Repeat.texel(f32::NAN, 4), 0);
    }

    #[test]
    fn srgb_round_trip() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(c)), c);
        }
    }

    #[test]
    fn decode_png_and_refuse_garbage() {
        let t = Texture::from_fn("c", 3, 2, |x, y| [x as u8 * 80, y as u8 * 100, 7, 128]);
        let mut png = Vec::new();
        image::RgbaImage::from_raw(3, 2, t.rgba.to_vec())
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let back = Texture::decode("c.png", &png).unwrap();
        assert_eq!(back.rgba, t.rgba);
        assert_eq!((back.width, back.height), (3, 2));
        assert!(Texture::decode("x", b"not an image").is_err());
        assert!(Texture::new("bad", 2, 2, vec![0; 15]).is_err());
    }

    #[test]
    fn resizing_a_flat_image_keeps_its_colour() {
        let t = Texture::from_fn("flat", 8, 8, |_, _| [200, 100, 50, 77]);
        let r = t.resized(2, 2);
        assert!(r.rgba.chunks_exact(4).all(|p| p == [200, 100, 50, 77]));
    }
}
