//! A technique's soft-shadow visibility (a fraction per pixel and light) scored against the
//! soft reference ([`crate::soft`]).
//!
//! The pairs scored are the hard score's ([`crate::score`]): (pixel, light) pairs within the
//! light's reach by the reference, whose normal faces the light's centre (`n · l > 0`; where
//! it does not, the lighting pass adds nothing from that light, so an error is invisible).
//! Over those pairs the score is the **mean absolute error** `|technique − reference|`,
//! split by the reference's class:
//!
//! - **umbra**: reference 0 (no sample of the light is seen);
//! - **lit**: reference 1 (every sample is seen);
//! - **penumbra**: strictly between.
//!
//! The split says where a technique errs: a penumbra that is too wide shows as error in the
//! umbra and lit classes near their edges, a noisy or blocky one as error in the penumbra
//! class, light leaks as error in the umbra class. Counted apart and not in any mean, as the
//! hard score does: in-reach pairs facing away from the light (`back_facing`, with their
//! error), and pairs out of the light's reach where the technique still sees some light
//! (`outside_reach_lit`; the reference is 0 there by definition).
//!
//! Technique values are taken as they are (not clamped): a value above 1 or below 0 is error
//! like any other. They must be finite.

use serde::Serialize;

use crate::error::ReferenceError;
use crate::frame::{Fractions, Mask};
use crate::soft::SoftVisibility;

/// The absolute error summed over the pairs of one class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ClassError {
    /// (pixel, light) pairs in the class.
    pub pairs: u64,
    /// Sum of `|technique − reference|` over them.
    pub abs_error: f64,
}

impl ClassError {
    fn add_pair(&mut self, error: f64) {
        self.pairs += 1;
        self.abs_error += error;
    }

    fn add(&mut self, o: &ClassError) {
        self.pairs += o.pairs;
        self.abs_error += o.abs_error;
    }

    /// The mean absolute error; 0 for an empty class.
    pub fn mean(&self) -> f64 {
        if self.pairs == 0 {
            0.0
        } else {
            self.abs_error / self.pairs as f64
        }
    }
}

/// The soft score of one light or a group of lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SoftCounts {
    /// Lights counted.
    pub lights: u32,
    /// Scored pairs whose reference is 0.
    pub umbra: ClassError,
    /// Scored pairs whose reference is strictly between 0 and 1.
    pub penumbra: ClassError,
    /// Scored pairs whose reference is 1.
    pub lit: ClassError,
    /// In-reach pairs whose normal faces away from the light (not scored), with their error.
    pub back_facing: ClassError,
    /// Pairs out of the light's reach, facing it, where the technique's value is not 0.
    pub outside_reach_lit: u64,
}

impl SoftCounts {
    fn add(&mut self, o: &SoftCounts) {
        self.lights += o.lights;
        self.umbra.add(&o.umbra);
        self.penumbra.add(&o.penumbra);
        self.lit.add(&o.lit);
        self.back_facing.add(&o.back_facing);
        self.outside_reach_lit += o.outside_reach_lit;
    }

    /// Every scored pair: umbra, penumbra and lit together.
    pub fn scored(&self) -> ClassError {
        let mut all = self.umbra;
        all.add(&self.penumbra);
        all.add(&self.lit);
        all
    }
}

/// The soft score of one technique.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SoftScore {
    /// One entry per light, in scene order.
    pub per_light: Vec<SoftCounts>,
}

impl SoftScore {
    /// Counts summed over the lights for which `keep(light index)` holds.
    pub fn total(&self, keep: impl Fn(usize) -> bool) -> SoftCounts {
        let mut c = SoftCounts::default();
        for (i, l) in self.per_light.iter().enumerate() {
            if keep(i) {
                c.add(l);
            }
        }
        c
    }
}

/// Checks that a mask describes the frame and lights of `f`.
fn check_mask(f: &Fractions, m: &Mask, what: &'static str) -> Result<(), ReferenceError> {
    let ok = m.width == f.width
        && m.height == f.height
        && m.lights == f.lights
        && m.words.len() == m.width as usize * m.height as usize * m.words_per_pixel as usize;
    if ok {
        Ok(())
    } else {
        Err(ReferenceError::Mismatch {
            what,
            expected: format!("{}x{} pixels, {} lights", f.width, f.height, f.lights),
            found: format!(
                "{}x{} pixels, {} lights ({} words)",
                m.width,
                m.height,
                m.lights,
                m.words.len()
            ),
        })
    }
}

/// Scores `technique` (the fractions of the same frame and lights) against `reference`.
pub fn soft_score(
    reference: &SoftVisibility,
    technique: &Fractions,
) -> Result<SoftScore, ReferenceError> {
    let r = &reference.visible;
    // The reference against itself: its own value count matches its size.
    r.check_same_shape(r, "soft reference")?;
    r.check_same_shape(technique, "technique visibility fractions")?;
    check_mask(r, &reference.reach, "soft reference reach mask")?;
    check_mask(r, &reference.facing, "soft reference facing mask")?;
    if let Some(i) = technique.values.iter().position(|v| !v.is_finite()) {
        let lights = technique.lights.max(1) as usize;
        return Err(ReferenceError::Mismatch {
            what: "technique visibility fractions",
            expected: "finite values".into(),
            found: format!(
                "{} at pixel {}, light {}",
                technique.values[i],
                i / lights,
                i % lights
            ),
        });
    }
    let lights = r.lights as usize;
    let pixels = r.width as usize * r.height as usize;
    let mut per_light = vec![
        SoftCounts {
            lights: 1,
            ..Default::default()
        };
        lights
    ];
    for p in 0..pixels {
        for (l, c) in per_light.iter_mut().enumerate() {
            let i = p * lights + l;
            let (rv, tv) = (r.values[i], technique.values[i]);
            let facing = reference.facing.get(p, l as u32);
            if !reference.reach.get(p, l as u32) {
                c.outside_reach_lit += (facing && tv != 0.0) as u64;
                continue;
            }
            let error = (tv as f64 - rv as f64).abs();
            let class = if !facing {
                &mut c.back_facing
            } else if rv <= 0.0 {
                &mut c.umbra
            } else if rv >= 1.0 {
                &mut c.lit
            } else {
                &mut c.penumbra
            };
            class.add_pair(error);
        }
    }
    Ok(SoftScore { per_light })
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

    fn fractions(w: u32, h: u32, lights: u32, values: &[f32]) -> Fractions {
        Fractions {
            width: w,
            height: h,
            lights,
            values: values.to_vec(),
        }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn errors_split_by_the_reference_class() {
        // 8x1 image, one light. Pixels 0-1 umbra, 2-4 penumbra, 5-6 lit, 7 out of reach.
        let reference = SoftVisibility {
            visible: fractions(8, 1, 1, &[0.0, 0.0, 0.25, 0.5, 0.75, 1.0, 1.0, 0.0]),
            reach: mask(8, 1, &[true, true, true, true, true, true, true, false]),
            facing: mask(8, 1, &[true; 8]),
            samples: 4,
        };
        let t = fractions(8, 1, 1, &[0.0, 0.5, 0.5, 0.5, 0.25, 1.0, 0.0, 0.75]);
        let c = score_one(&reference, &t);
        // Umbra: |0 − 0| + |0.5 − 0| = 0.5 over 2 pairs.
        assert_eq!(c.umbra.pairs, 2);
        assert!(close(c.umbra.abs_error, 0.5) && close(c.umbra.mean(), 0.25));
        // Penumbra: 0.25 + 0 + 0.5 = 0.75 over 3 pairs.
        assert_eq!(c.penumbra.pairs, 3);
        assert!(close(c.penumbra.abs_error, 0.75) && close(c.penumbra.mean(), 0.25));
        // Lit: 0 + 1 = 1 over 2 pairs.
        assert_eq!(c.lit.pairs, 2);
        assert!(close(c.lit.mean(), 0.5));
        // All scored: 2.25 over 7. Pixel 7 is out of reach yet lit by the technique.
        assert_eq!(c.scored().pairs, 7);
        assert!(close(c.scored().mean(), 2.25 / 7.0));
        assert_eq!(c.outside_reach_lit, 1);
        assert_eq!(c.back_facing, ClassError::default());
    }

    fn score_one(reference: &SoftVisibility, t: &Fractions) -> SoftCounts {
        let s = soft_score(reference, t).unwrap();
        assert_eq!(s.per_light.len(), 1);
        s.per_light[0]
    }

    #[test]
    fn back_facing_pairs_are_counted_apart_and_lights_summed() {
        // 2x1 image, two lights (values pixel-major: p0 l0, p0 l1, p1 l0, p1 l1).
        let mut reach = Mask::zeros(2, 1, 2);
        reach.words = vec![0b11, 0b11];
        let mut facing = Mask::zeros(2, 1, 2);
        facing.words = vec![0b11, 0b01]; // pixel 1 faces away from light 1
        let reference = SoftVisibility {
            visible: fractions(2, 1, 2, &[1.0, 0.5, 0.0, 0.5]),
            reach,
            facing,
            samples: 16,
        };
        let t = fractions(2, 1, 2, &[0.5, 0.5, 0.0, 0.0]);
        let s = soft_score(&reference, &t).unwrap();
        let (l0, l1) = (s.per_light[0], s.per_light[1]);
        // Light 0: pixel 0 lit off by 0.5, pixel 1 umbra exact.
        assert_eq!((l0.lit.pairs, l0.umbra.pairs, l0.penumbra.pairs), (1, 1, 0));
        assert!(close(l0.lit.abs_error, 0.5) && close(l0.umbra.abs_error, 0.0));
        // Light 1: pixel 0 penumbra exact; pixel 1 faces away (error 0.5, not scored).
        assert_eq!((l1.penumbra.pairs, l1.scored().pairs), (1, 1));
        assert!(close(l1.penumbra.abs_error, 0.0));
        assert_eq!(l1.back_facing.pairs, 1);
        assert!(close(l1.back_facing.abs_error, 0.5));
        // Both lights: 3 scored pairs, error 0.5 in all.
        let all = s.total(|_| true);
        assert_eq!((all.lights, all.scored().pairs), (2, 3));
        assert!(close(all.scored().mean(), 0.5 / 3.0));
        assert_eq!(s.total(|i| i == 1).lights, 1);
    }

    #[test]
    fn mismatched_or_bad_input_is_an_error() {
        let reference = SoftVisibility {
            visible: fractions(2, 1, 1, &[1.0, 0.0]),
            reach: mask(2, 1, &[true, true]),
            facing: mask(2, 1, &[true, true]),
            samples: 1,
        };
        let e = soft_score(&reference, &fractions(1, 2, 1, &[1.0, 0.0])).unwrap_err();
        assert!(
            e.to_string().contains("technique visibility fractions"),
            "{e}"
        );
        assert!(e.to_string().contains("expected 2x1 pixels"), "{e}");
        let e = soft_score(&reference, &fractions(2, 1, 1, &[1.0])).unwrap_err();
        assert!(e.to_string().contains("1 values"), "{e}");
        let e = soft_score(&reference, &fractions(2, 1, 1, &[1.0, f32::NAN])).unwrap_err();
        assert!(e.to_string().contains("NaN at pixel 1"), "{e}");
        let mut bad = reference.clone();
        bad.facing = Mask::zeros(2, 1, 2);
        let e = soft_score(&bad, &fractions(2, 1, 1, &[1.0, 0.0])).unwrap_err();
        assert!(e.to_string().contains("facing mask"), "{e}");
    }
}
