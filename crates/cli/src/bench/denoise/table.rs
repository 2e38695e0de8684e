//! `bench denoise`'s results.txt: per light count the errors and times, against every light
//! through the same maps where the technique samples over them, the trails, and the growth
//! across light counts.

use super::{DenoiseArgs, FrameRow, Record};
use crate::bench::harness::{median, ms};

pub(super) fn table(args: &DenoiseArgs, adapter: &str, records: &[Record]) -> String {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    let camera = match &args.camera_path {
        Some(p) => format!("camera along {}", p.display()),
        None => format!("camera {} deg/frame", args.orbit),
    };
    let mut t = format!(
        "== bench denoise: {} at {}x{}, {} frames, {camera}, {}; K = {}, visibility from {}{}\n   adapter: {adapter}\n",
        args.scene,
        args.width,
        args.height,
        args.frames,
        if args.still {
            "no caster moving"
        } else {
            "a caster circling"
        },
        args.light_samples,
        match args.technique.info().fills {
            manyshadows::Fills::Rays => "shadow rays".to_string(),
            _ => format!("{}'s shadow maps", args.technique),
        },
        match (args.reuse, args.spatial) {
            (false, _) => String::new(),
            (true, manyshadows::SpatialReuse::Off) =>
                ", lights reused across frames (plain: reuse alone)".to_string(),
            (true, m) => format!(
                ", lights reused across frames and between neighbours ({}; plain: without the denoiser)",
                m.name()
            ),
        }
    );
    t += "lights | RMSE plain: mean first last | denoised: mean first last | GPU ms plain denoised (its passes) | ratio paired\n";
    for r in records {
        let first = r.frames.first();
        let last = r.frames.last();
        t += &format!(
            "{:>6} | {:>16} {:>5} {:>5} | {:>14} {:>5} {:>5} | {:>14} {:>8} ({:>6}) | {:>5} {:>6}\n",
            r.lights,
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
    if let (Some(a), Some(b)) = (records.first(), records.last()) {
        if records.len() > 1 {
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
                if args.reuse { " and reuse" } else { "" },
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
        args.reference_area_samples
    );
    t
}
