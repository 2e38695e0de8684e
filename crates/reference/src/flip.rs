//! ꟻLIP, NVIDIA's perceptual difference of two images (Andersson et al., "FLIP: A Difference
//! Evaluator for Alternating Images", HPG 2020), through the `nv-flip` crate (the binding
//! wgpu's own image tests use, over NVIDIA's C++ implementation).
//!
//! Mask scores count wrong pixels; ꟻLIP says how visible the difference between two shaded
//! frames is to a viewer (a per-pixel error in `[0, 1]` weighing colour and edges at the
//! viewing distance), so soft shadows whose penumbrae are noisy, blocky or too wide can be
//! compared as seen. Images are read as sRGB; alpha is ignored (ꟻLIP compares colour). The
//! viewing condition is ꟻLIP's default, [`PIXELS_PER_DEGREE`]: 67 pixels per degree, a 0.7 m wide
//! 3840-pixel monitor seen from 0.7 m.

use crate::error::ReferenceError;

/// Pixels per degree of visual angle the comparison assumes: ꟻLIP's default.
pub const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// The ꟻLIP comparison of two images.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipDifference {
    /// The mean of the per-pixel error (the single number ꟻLIP's authors recommend); 0 for
    /// identical images.
    pub mean: f64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The per-pixel error in `[0, 1]`, row-major from the top-left pixel.
    pub errors: Vec<f32>,
    /// The error map coloured with ꟻLIP's magma ramp (black = no difference, yellow-white =
    /// the largest), RGB8, row-major from the top-left pixel.
    pub error_map: Vec<u8>,
}

/// Compares `test` with `reference`, both RGBA8 images of `width` × `height` pixels,
/// row-major from the top-left pixel (alpha ignored).
pub fn flip_rgba8(
    reference: &[u8],
    test: &[u8],
    width: u32,
    height: u32,
) -> Result<FlipDifference, ReferenceError> {
    let expected = width as usize * height as usize * 4;
    for (what, image) in [
        ("ꟻLIP reference image (RGBA8)", reference),
        ("ꟻLIP test image (RGBA8)", test),
    ] {
        if image.len() != expected {
            return Err(ReferenceError::Mismatch {
                what,
                expected: format!("{expected} bytes ({width}x{height} RGBA8)"),
                found: format!("{} bytes", image.len()),
            });
        }
    }
    if expected == 0 {
        // An empty image differs from nothing; the C++ library is not asked.
        return Ok(FlipDifference {
            mean: 0.0,
            width,
            height,
            errors: Vec::new(),
            error_map: Vec::new(),
        });
    }
    let rgb = |image: &[u8]| {
        let data: Vec<u8> = image
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        nv_flip::FlipImageRgb8::with_data(width, height, &data)
    };
    let map = nv_flip::flip(rgb(reference), rgb(test), PIXELS_PER_DEGREE);
    let errors = map.to_vec();
    let mean = errors.iter().map(|&e| e as f64).sum::<f64>() / errors.len() as f64;
    let error_map = map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    Ok(FlipDifference {
        mean,
        width,
        height,
        errors,
        error_map,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 32x32 RGBA8 image: a horizontal ramp with a dark square in the middle.
    fn image() -> Vec<u8> {
        (0..32 * 32)
            .flat_map(|i| {
                let (x, y) = (i % 32, i / 32);
                let v = if (12..20).contains(&x) && (12..20).contains(&y) {
                    20
                } else {
                    (x * 8) as u8
                };
                [v, v, v, 255]
            })
            .collect()
    }

    #[test]
    fn identical_images_differ_by_nothing() {
        let a = image();
        let d = flip_rgba8(&a, &a, 32, 32).unwrap();
        assert_eq!(d.mean, 0.0);
        assert!(d.errors.iter().all(|&e| e == 0.0));
        assert_eq!(d.error_map.len(), 32 * 32 * 3);
        // Zero error is magma's first colour, the same everywhere.
        assert!(d.error_map.chunks_exact(3).all(|c| c == &d.error_map[..3]));
        // Alpha is not compared.
        let mut b = a.clone();
        b.iter_mut().skip(3).step_by(4).for_each(|alpha| *alpha = 0);
        assert_eq!(flip_rgba8(&a, &b, 32, 32).unwrap().mean, 0.0);
    }

    #[test]
    fn a_changed_image_differs() {
        let a = image();
        let mut b = a.clone();
        // Lighten the dark square: a shadow that leaks.
        for y in 12..20 {
            for x in 12..20 {
                let i = (y * 32 + x) * 4;
                b[i..i + 3].copy_from_slice(&[200, 200, 200]);
            }
        }
        let d = flip_rgba8(&a, &b, 32, 32).unwrap();
        assert!(d.mean > 0.0, "{}", d.mean);
        let centre = d.errors[16 * 32 + 16];
        let corner = d.errors[0];
        assert!(centre > 0.1 && centre > corner, "{centre} vs {corner}");
        assert!(d.errors.iter().all(|e| (0.0..=1.0).contains(e)));
    }

    #[test]
    fn wrong_sizes_are_an_error() {
        let a = image();
        let e = flip_rgba8(&a, &a[4..], 32, 32).unwrap_err();
        assert!(e.to_string().contains("test image"), "{e}");
        let e = flip_rgba8(&a, &a, 16, 16).unwrap_err();
        assert!(e.to_string().contains("reference image"), "{e}");
        let empty = flip_rgba8(&[], &[], 0, 7).unwrap();
        assert_eq!((empty.mean, empty.errors.len()), (0.0, 0));
    }
}
