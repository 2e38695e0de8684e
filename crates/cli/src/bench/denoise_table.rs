//! `bench denoise`'s results.txt: per light count the errors and times, against every light
//! through the same maps where the technique samples over them, the trails, and the growth
//! across light counts.

use serde::Serialize;

use crate::bench::harness::{median, ms};

/// One frame's numbers.
#[derive(Serialize, Clone, Copy)]
pub(super) struct FrameRow {
    pub(super) frame: u32,
    /// RMSE against the exact frame (None without the reference).
    pub(super) plain_rmse: Option<f64>,
    pub(super) denoised_rmse: Option<f64>,
    pub(super) plain_ms: Option<f64>,
    pub(super) denoised_ms: Option<f64>,
    /// The denoised frame's lighting stage and its denoiser's passes with the composite.
    pub(super) denoised_lighting_ms: Option<f64>,
    pub(super) denoise_ms: Option<f64>,
    pub(super) exact_ms: Option<f64>,
    /// Shadow maps: RMSE against the same technique with every light.
    pub(super) plain_every_rmse: Option<f64>,
    pub(super) denoised_every_rmse: Option<f64>,
    /// Shadow maps: the every-light frame's GPU ms, and its RMSE against the exact frame (the
    /// maps' own error, which no sampling removes).
    pub(super) every_ms: Option<f64>,
    pub(super) every_exact_rmse: Option<f64>,
    /// Virtual maps: pages drawn this frame by the denoised renderer and by every light.
    pub(super) denoised_pages: Option<u32>,
    pub(super) every_pages: Option<u32>,
    /// With a still camera and a moving caster: how many frames behind the denoised shadow
    /// is (`denoise.rs`, `trail`).
    pub(super) trail_frames: Option<u32>,
}

/// One light count's sequence.
#[derive(Serialize)]
pub(super) struct Record {
    pub(super) lights: usize,
    /// With --animation: "moving" (the animation plays) or "frozen" (held at 0 s).
    pub(super) animation: Option<&'static str>,
    pub(super) frames: Vec<FrameRow>,
    pub(super) plain_mean_rmse: Option<f64>,
    pub(super) denoised_mean_rmse: Option<f64>,
    pub(super) plain_median_ms: Option<f64>,
    pub(super) denoised_median_ms: Option<f64>,
    /// Denoised frame over plain frame, medians of the same sequence.
    pub(super) cost_ratio: Option<f64>,
    /// The median of each frame's denoised over plain (the two alternate, so each pair saw
    /// the machine alike).
    pub(super) cost_ratio_paired: Option<f64>,
    /// Median of the denoiser's own passes and composite.
    pub(super) denoise_median_ms: Option<f64>,
    /// Mean of the frames' trails (still camera, moving caster).
    pub(super) mean_trail_frames: Option<f64>,
    /// Shadow maps: mean RMSE against every light through the same maps.
    pub(super) plain_every_mean_rmse: Option<f64>,
    pub(super) denoised_every_mean_rmse: Option<f64>,
    /// Shadow maps: median GPU ms of the every-light frame, and the denoised frame over it
    /// (median of each frame's ratio).
    pub(super) every_median_ms: Option<f64>,
    pub(super) denoised_over_every_paired: Option<f64>,
    /// Shadow maps: mean RMSE of the every-light frame against the exact frame.
    pub(super) every_exact_mean_rmse: Option<f64>,
    /// Virtual maps: mean pages drawn per frame, denoised and every light.
    pub(super) denoised_mean_pages: Option<f64>,
    pub(super) every_mean_pages: Option<f64>,
}

impl Record {
    /// Its light count, and with --animation whether it moves.
    fn label(&self) -> String {
        match self.animation {
            Some(a) => format!("{} {a}", self.lights),
            None => self.lights.to_string(),
        }
    }
}

/// `heading`: the run's settings (see `denoise::heading`); `reuse`: whether the denoised frame
/// also reuses lights; `area_samples`: rays per side over each sized light in the exact frame.
pub(super) fn table(heading: &str, reuse: bool, area_samples: u32, records: &[Record]) -> String {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    let mut t = heading.to_string();
    t += "lights | RMSE plain: mean first last | denoised: mean first last | GPU ms plain denoised (its passes) | ratio paired\n";
    for r in records {
        let first = r.frames.first();
        let last = r.frames.last();
        t += &format!(
            "{:>6} | {:>16} {:>5} {:>5} | {:>14} {:>5} {:>5} | {:>14} {:>8} ({:>6}) | {:>5} {:>6}\n",
            r.label(),
            opt(r.plain_mean_rmse),
            opt(first.and_then(|x| x.plain_rmse)),
            opt(last.and_then(|x| x.plain_rmse)),
            opt(r.denoised_mean_rmse),
            opt(first.and_then(|x| x.denoised_rmse)),
            opt(last.and_then(|x| x.denoised_rmse)),
            ms(r.plain_median_ms),
            ms(r.denoised_median_ms),
            ms(r.denoise_median_ms),
            opt(r.cost_ratio),
            opt(r.cost_ratio_paired),
        );
    }
    for r in records {
        if r.every_median_ms.is_none() && r.denoised_every_mean_rmse.is_none() {
            continue;
        }
        // `mean M (first F, last L)` of a per-frame series.
        let series = |mean: Option<f64>, pick: fn(&FrameRow) -> Option<f64>| {
            format!(
                "mean {} (first {}, last {})",
                opt(mean),
                opt(r.frames.first().and_then(pick)),
                opt(r.frames.last().and_then(pick))
            )
        };
        t += &format!(
            "{} lights, against every light through the same maps: RMSE plain {}, denoised {}; \
             every-light frame {} ms, denoised over it {}x (median of each frame's ratio){}{}\n",
            r.lights,
            series(r.plain_every_mean_rmse, |x| x.plain_every_rmse),
            series(r.denoised_every_mean_rmse, |x| x.denoised_every_rmse),
            ms(r.every_median_ms),
            opt(r.denoised_over_every_paired),
            r.every_exact_mean_rmse.map_or(String::new(), |e| format!(
                "; the every-light frame itself {e:.2} from the exact one (the maps' own error)"
            )),
            match (r.denoised_mean_pages, r.every_mean_pages) {
                (Some(d), Some(e)) => format!(
                    "; pages drawn per frame {d:.0} denoised, {e:.0} every light ({})",
                    opt(crate::bench::harness::ratio(Some(d), Some(e))).to_string() + "x"
                ),
                _ => String::new(),
            }
        );
    }
    // With --animation: each moving sequence against its frozen twin (same light count).
    for m in records.iter().filter(|r| r.animation == Some("moving")) {
        let Some(f) = records
            .iter()
            .find(|r| r.animation == Some("frozen") && r.lights == m.lights)
        else {
            continue;
        };
        let ratio = |a: Option<f64>, b: Option<f64>| {
            crate::bench::harness::ratio(a, b).map_or("-".to_string(), |x| format!("{x:.2}x"))
        };
        t += &format!(
            "{} lights, moving against frozen: mean RMSE denoised {} vs {} ({}), plain {} vs {} \
             ({}); denoised frame {} vs {} ms\n",
            m.lights,
            opt(m.denoised_mean_rmse),
            opt(f.denoised_mean_rmse),
            ratio(m.denoised_mean_rmse, f.denoised_mean_rmse),
            opt(m.plain_mean_rmse),
            opt(f.plain_mean_rmse),
            ratio(m.plain_mean_rmse, f.plain_mean_rmse),
            ms(m.denoised_median_ms),
            ms(f.denoised_median_ms),
        );
    }
    for r in records {
        if let Some(trail) = r.mean_trail_frames {
            t += &format!(
                "{} lights: the denoised frame's changed pixels match the exact frame {:.2} frames \
                 back on average (0: no trail; over {} frames with enough change)\n",
                r.lights,
                trail,
                r.frames.iter().filter(|x| x.trail_frames.is_some()).count()
            );
        }
    }
    // Growth across light counts: the moving (or only) sequence of each.
    let counts: Vec<&Record> = records
        .iter()
        .filter(|r| r.animation != Some("frozen"))
        .collect();
    if let (Some(&a), Some(&b)) = (counts.first(), counts.last()) {
        if counts.len() > 1 {
            // The frames of the counts alternate, so frame k of each saw the machine alike:
            // the median of the frame-by-frame ratios is the steadier figure.
            type Pick = fn(&FrameRow) -> Option<f64>;
            let paired = |pick: Pick| {
                let v: Vec<f64> = a
                    .frames
                    .iter()
                    .zip(&b.frames)
                    .filter_map(|(x, y)| crate::bench::harness::ratio(pick(y), pick(x)))
                    .collect();
                (!v.is_empty()).then(|| median(&v))
            };
            t +=
                &format!(
                "growth from {} to {} lights: plain {}x, denoised {}x (median frames); frame by \
                 frame plain {}x, denoised {}x (median of each frame's ratio)\n",
                a.lights,
                b.lights,
                opt(crate::bench::harness::ratio(b.plain_median_ms, a.plain_median_ms)),
                opt(crate::bench::harness::ratio(
                    b.denoised_median_ms,
                    a.denoised_median_ms
                )),
                opt(paired(|x| x.plain_ms)),
                opt(paired(|x| x.denoised_ms)),
            );
            // What the denoiser (and reuse, with --reuse) adds to the plain frame: the same
            // frame's difference, whose growth is the denoiser's own.
            let added = |r: &Record| {
                let v: Vec<f64> = r
                    .frames
                    .iter()
                    .filter_map(|x| Some(x.denoised_ms? - x.plain_ms?))
                    .collect();
                (!v.is_empty()).then(|| median(&v))
            };
            t += &format!(
                "what the denoiser{} adds to the plain frame (median of each frame's \
                 difference): {} ms at {} lights, {} ms at {} ({}x)\n",
                if reuse { " and reuse" } else { "" },
                ms(added(a)),
                a.lights,
                ms(added(b)),
                b.lights,
                opt(crate::bench::harness::ratio(added(b), added(a))),
            );
        }
    }
    t += &format!(
        "   RMSE: sRGB channels 0-255 against every cluster light traced in the same frame \
         ({0}x{0} rays over each sized light); GPU ms: median over the frames of each \
         renderer's frame (the denoised one includes its passes); ratio: denoised over plain, of \
         the medians and (paired) the median of each frame's.\n",
        area_samples
    );
    t
}
