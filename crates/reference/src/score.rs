//! A technique's visibility mask scored against the reference.
//!
//! Among the pixels a light reaches (by the reference's [`in_reach`](crate::in_reach)), a
//! **false shadow** is a pixel the reference sees lit and the technique shadowed (acne,
//! over-wide shadows), a **false light** one the reference sees shadowed and the technique lit
//! (light leaks, peter-panning, missing casters). A technique bit set outside the light's reach
//! also counts as false light.
//!
//! Only pixels whose normal faces the light (`n · l > 0`, the G-buffer normal) are scored.
//! Where it does not, the lighting pass adds nothing from that light whatever the bit says, so
//! a wrong bit is invisible; yet such pixels are where a shadow map's receiver bias routinely
//! disagrees with exact occlusion (the slope term pushes a back-facing point up to 11 texels
//! towards the light, out of its own mesh). They are counted apart (`back_facing`,
//! `back_facing_disagree`) so nothing is hidden.
//!
//! **The edge band.** A shadow map cannot place an edge more finely than its texel, and the
//! receiver bias moves edges by a few texels by design, so errors next to a true shadow edge
//! are expected and are reported apart from errors elsewhere. The band of a light is every
//! pixel within `radius` pixels (Chebyshev distance, in the image) of a covered pixel whose
//! reference bit for that light differs: both sides of every reference shadow outline, of
//! every reach boundary (spot cone, range), and of contact lines. The radius is a screen
//! distance on purpose: it is the same for every technique, resolution and light type, so
//! their band errors stay comparable; how coarse a technique's texels are on screen is
//! measured on its own by [`crate::aliasing`].

use serde::Serialize;

use crate::error::ReferenceError;
use crate::frame::Mask;
use crate::visibility::ReferenceVisibility;

/// Per pixel, the lights whose reference bit differs within `radius` pixels (see the module
/// docs). `covered[pixel]` is false where the pixel saw no geometry; those pixels neither are
/// in the band nor put their neighbours in it.
pub fn edge_band(reference: &Mask, covered: &[bool], radius: u32) -> Mask {
    let (w, h) = (reference.width as i64, reference.height as i64);
    let n = reference.words_per_pixel as usize;
    let r = radius as i64;
    let mut band = Mask::zeros(reference.width, reference.height, reference.lights);
    for y in 0..h {
        for x in 0..w {
            let p = (y * w + x) as usize;
            if !covered[p] {
                continue;
            }
            let here = reference.pixel_words(p);
            for ny in (y - r).max(0)..=(y + r).min(h - 1) {
                for nx in (x - r).max(0)..=(x + r).min(w - 1) {
                    let q = (ny * w + nx) as usize;
                    if !covered[q] {
                        continue;
                    }
                    let there = reference.pixel_words(q);
                    for i in 0..n {
                        band.words[p * n + i] |= here[i] ^ there[i];
                    }
                }
            }
        }
    }
    band
}

/// Error counts of one light or a group of lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Lights counted.
    pub lights: u32,
    /// (pixel, light) pairs within reach, by the reference, facing the light: the pixels
    /// scored and the denominator of every fraction.
    pub in_reach: u64,
    /// Of those, in the edge band.
    pub band: u64,
    /// False shadow outside the edge band.
    pub false_shadow: u64,
    /// False light outside the edge band.
    pub false_light: u64,
    /// False shadow inside the edge band.
    pub band_false_shadow: u64,
    /// False light inside the edge band.
    pub band_false_light: u64,
    /// (pixel, light) pairs within reach whose normal faces away from the light (not scored).
    pub back_facing: u64,
    /// Of the pixels facing away, those where the technique and the reference disagree.
    pub back_facing_disagree: u64,
}

impl Counts {
    fn add(&mut self, o: &Counts) {
        self.lights += o.lights;
        self.in_reach += o.in_reach;
        self.band += o.band;
        self.false_shadow += o.false_shadow;
        self.false_light += o.false_light;
        self.band_false_shadow += o.band_false_shadow;
        self.band_false_light += o.band_false_light;
        self.back_facing += o.back_facing;
        self.back_facing_disagree += o.back_facing_disagree;
    }

    fn frac(&self, n: u64) -> f64 {
        if self.in_reach == 0 {
            0.0
        } else {
            n as f64 / self.in_reach as f64
        }
    }

    /// False shadow outside the band, as a fraction of in-reach pixels.
    pub fn false_shadow_fraction(&self) -> f64 {
        self.frac(self.false_shadow)
    }

    /// False light outside the band, as a fraction of in-reach pixels.
    pub fn false_light_fraction(&self) -> f64 {
        self.frac(self.false_light)
    }

    /// All misclassified pixels outside the band, as a fraction of in-reach pixels.
    pub fn error_fraction(&self) -> f64 {
        self.frac(self.false_shadow + self.false_light)
    }

    /// Misclassified pixels inside the band, as a fraction of in-reach pixels.
    pub fn band_error_fraction(&self) -> f64 {
        self.frac(self.band_false_shadow + self.band_false_light)
    }

    /// The band's share of in-reach pixels.
    pub fn band_fraction(&self) -> f64 {
        self.frac(self.band)
    }
}

/// The score of one technique's mask.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Score {
    /// One entry per light, in scene order.
    pub per_light: Vec<Counts>,
}

impl Score {
    /// Counts summed over the lights for which `keep(light index)` holds.
    pub fn total(&self, keep: impl Fn(usize) -> bool) -> Counts {
        let mut c = Counts::default();
        for (i, l) in self.per_light.iter().enumerate() {
            if keep(i) {
                c.add(l);
            }
        }
        c
    }
}

/// Scores `technique` (the renderer's visibility mask of the same frame) against `reference`,
/// with `band` from [`edge_band`].
pub fn score(
    reference: &ReferenceVisibility,
    band: &Mask,
    technique: &Mask,
) -> Result<Score, ReferenceError> {
    reference
        .lit
        .check_same_shape(technique, "technique visibility mask")?;
    reference.lit.check_same_shape(band, "edge band")?;
    reference
        .lit
        .check_same_shape(&reference.facing, "facing mask")?;
    reference
        .lit
        .check_same_shape(&reference.reach, "reach mask")?;
    let n = reference.lit.words_per_pixel as usize;
    let pixels = reference.lit.width as usize * reference.lit.height as usize;
    let mut per_light = vec![
        Counts {
            lights: 1,
            ..Default::default()
        };
        reference.lit.lights as usize
    ];
    for p in 0..pixels {
        for wi in 0..n {
            let i = p * n + wi;
            let (r, t) = (reference.lit.words[i], technique.words[i]);
            let (reach, b) = (reference.reach.words[i], band.words[i]);
            let facing = reference.facing.words[i];
            if reach | t == 0 {
                continue;
            }
            let false_shadow = r & !t;
            let false_light = t & !r;
            let mut bits = reach | t;
            while bits != 0 {
                let bit = bits.trailing_zeros();
                bits &= bits - 1;
                let c = &mut per_light[wi * 32 + bit as usize];
                let m = 1u32 << bit;
                if facing & m == 0 {
                    c.back_facing += (reach & m != 0) as u64;
                    c.back_facing_disagree += ((r ^ t) & m != 0) as u64;
                    continue;
                }
                let in_band = b & m != 0;
                if reach & m != 0 {
                    c.in_reach += 1;
                    c.band += in_band as u64;
                }
                if false_shadow & m != 0 {
                    if in_band {
                        c.band_false_shadow += 1;
                    } else {
                        c.false_shadow += 1;
                    }
                } else if false_light & m != 0 {
                    if in_band {
                        c.band_false_light += 1;
                    } else {
                        c.false_light += 1;
                    }
                }
            }
        }
    }
    Ok(Score { per_light })
}

/// Error classes of one pixel, for difference images.
pub mod class {
    /// Some light: false shadow outside the band.
    pub const FALSE_SHADOW: u8 = 1;
    /// Some light: false light outside the band.
    pub const FALSE_LIGHT: u8 = 2;
    /// Some light: false shadow inside the band.
    pub const BAND_FALSE_SHADOW: u8 = 4;
    /// Some light: false light inside the band.
    pub const BAND_FALSE_LIGHT: u8 = 8;
}

/// The colour of a pixel's [`class`] bits in the difference pictures (`compare`'s images, the
/// web page's overlay): red false shadow, green false light (yellow both) outside the edge
/// band, the same at 130 inside it; `None` for a pixel with no error.
pub fn class_colour(c: u8) -> Option<[u8; 3]> {
    let pick = |shadow: u8, light: u8, level: u8| {
        [
            if c & shadow != 0 { level } else { 0 },
            if c & light != 0 { level } else { 0 },
            0,
        ]
    };
    if c & (class::FALSE_SHADOW | class::FALSE_LIGHT) != 0 {
        Some(pick(class::FALSE_SHADOW, class::FALSE_LIGHT, 255))
    } else if c & (class::BAND_FALSE_SHADOW | class::BAND_FALSE_LIGHT) != 0 {
        Some(pick(class::BAND_FALSE_SHADOW, class::BAND_FALSE_LIGHT, 130))
    } else {
        None
    }
}

/// Per pixel, the [`class`] bits of the lights selected by `light` (`None` = every light),
/// over the pixels that face each light (as scored).
pub fn error_classes(
    reference: &ReferenceVisibility,
    band: &Mask,
    technique: &Mask,
    light: Option<u32>,
) -> Result<Vec<u8>, ReferenceError> {
    reference
        .lit
        .check_same_shape(technique, "technique visibility mask")?;
    let n = reference.lit.words_per_pixel as usize;
    let pixels = reference.lit.width as usize * reference.lit.height as usize;
    let mut out = vec![0u8; pixels];
    for (p, o) in out.iter_mut().enumerate() {
        for wi in 0..n {
            let i = p * n + wi;
            let select = match light {
                None => u32::MAX,
                Some(l) if l as usize / 32 == wi => 1 << (l % 32),
                Some(_) => 0,
            };
            let (r, t, b) = (reference.lit.words[i], technique.words[i], band.words[i]);
            let select = select & reference.facing.words[i];
            let fs = r & !t & select;
            let fl = t & !r & select;
            if fs & !b != 0 {
                *o |= class::FALSE_SHADOW;
            }
            if fl & !b != 0 {
                *o |= class::FALSE_LIGHT;
            }
            if fs & b != 0 {
                *o |= class::BAND_FALSE_SHADOW;
            }
            if fl & b != 0 {
                *o |= class::BAND_FALSE_LIGHT;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(w: u32, h: u32, bits: &[bool]) -> Mask {
        let mut m = Mask::zeros(w, h, 1);
        for (i, &b) in bits.iter().enumerate() {
            m.words[i] = b as u32;
        }
        m
    }

    #[test]
    fn band_surrounds_edges_and_errors_split_by_kind() {
        // 6x1 image, one light: reference lit on the left half.
        let r = mask(6, 1, &[true, true, true, false, false, false]);
        let reach = mask(6, 1, &[true; 6]);
        let covered = [true; 6];
        let band = edge_band(&r, &covered, 1);
        assert_eq!(band.words, vec![0, 0, 1, 1, 0, 0]);
        // Technique: pixel 0 false shadow (outside band), pixel 3 false light (inside band),
        // pixel 5 false light (outside band).
        let t = mask(6, 1, &[false, true, true, true, false, true]);
        let facing = mask(6, 1, &[true; 6]);
        let reference = ReferenceVisibility {
            lit: r,
            reach,
            facing,
        };
        let s = score(&reference, &band, &t).unwrap();
        let c = s.per_light[0];
        assert_eq!(
            (c.in_reach, c.band, c.false_shadow, c.false_light),
            (6, 2, 1, 1)
        );
        assert_eq!((c.band_false_shadow, c.band_false_light), (0, 1));
        let classes = error_classes(&reference, &band, &t, None).unwrap();
        assert_eq!(
            classes,
            vec![
                class::FALSE_SHADOW,
                0,
                0,
                class::BAND_FALSE_LIGHT,
                0,
                class::FALSE_LIGHT
            ]
        );
    }

    #[test]
    fn back_facing_pixels_are_counted_apart() {
        // Two pixels in reach, both wrong; the second faces away from the light.
        let r = mask(2, 1, &[true, true]);
        let reference = ReferenceVisibility {
            lit: r.clone(),
            reach: r.clone(),
            facing: mask(2, 1, &[true, false]),
        };
        let band = Mask::zeros(2, 1, 1);
        let t = Mask::zeros(2, 1, 1);
        let c = score(&reference, &band, &t).unwrap().per_light[0];
        assert_eq!((c.in_reach, c.false_shadow), (1, 1));
        assert_eq!((c.back_facing, c.back_facing_disagree), (1, 1));
        let classes = error_classes(&reference, &band, &t, Some(0)).unwrap();
        assert_eq!(classes, vec![class::FALSE_SHADOW, 0]);
    }

    #[test]
    fn uncovered_pixels_do_not_make_a_band() {
        let r = mask(3, 1, &[true, false, true]);
        let band = edge_band(&r, &[true, false, true], 1);
        assert_eq!(band.words, vec![0, 0, 0]);
    }

    #[test]
    fn mismatched_masks_are_an_error() {
        let r = mask(2, 1, &[true, true]);
        let reference = ReferenceVisibility {
            lit: r.clone(),
            reach: r.clone(),
            facing: r.clone(),
        };
        let other = Mask::zeros(1, 2, 1);
        let e = score(&reference, &r, &other).unwrap_err();
        assert!(e.to_string().contains("technique visibility mask"), "{e}");
    }
}
