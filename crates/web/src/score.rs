//! The page's score button: the current view's hard shadows against the exact CPU reference
//! (`manyshadows-reference`, compiled to wasm32), scored as `manyshadows compare` scores them.
//!
//! The view is rendered once more as `compare` renders a variant (PCF off, the hard
//! visibility mask on), its G-buffer and mask read back ([`manyshadows::read_deferred`]), and
//! one ray traced per covered pixel and light in reach, a few rows at a time
//! ([`ScoreRun::step`]): the page returns to its event loop between steps, so it shows
//! progress and can stop the run. The result is `compare`'s numbers for the view (false
//! shadow and false light outside the edge band, as fractions of the in-reach pairs) and the
//! misclassified pixels in `compare`'s colours, to lay over the frame. With soft samples asked
//! for and a sized light that casts shadows, the soft reference follows (the same samples per
//! pair, seeds and rays as `compare --soft-samples N`), and the technique's soft visibility is
//! scored against it: the mean absolute error of the lit fractions, by the reference's class.

use std::sync::atomic::AtomicBool;

use manyshadows::scene::{Light, Scene};
use manyshadows::{Pcf, RenderSettings, Renderer};
use manyshadows_reference::score;
use manyshadows_reference::soft::{grid_side, point_soft_visibility, seed};
use manyshadows_reference::{
    in_reach, reference_visibility, soft_score, Fractions, Mask, ReferenceVisibility, SoftScore,
    SoftVisibility, SurfacePoint, Surfaces, Tracer,
};

/// `compare`'s default edge band: errors within 2 pixels of a true shadow edge are counted
/// apart.
const EDGE_BAND: u32 = 2;

fn now_ms() -> f64 {
    js_sys::Date::now()
}

/// Rows from `first` to trace in about `left_ms` at `speed` rays per millisecond, and their
/// rays: at least one row; every row at once is never guessed before a speed is known.
fn rows_to_trace(rays_per_row: &[u64], first: u32, speed: f64, left_ms: f64) -> (u32, u64) {
    let h = rays_per_row.len() as u32;
    let mut rows = 1u32;
    let mut rays = rays_per_row[first as usize];
    while first + rows < h && speed > 0.0 {
        let next = rays_per_row[(first + rows) as usize];
        if (rays + next) as f64 > speed * left_ms {
            break;
        }
        rays += next;
        rows += 1;
    }
    (rows, rays)
}

/// A score in progress: the reference traced row by row into `vis`.
pub(crate) struct ScoreRun {
    tracer: Tracer,
    lights: Vec<Light>,
    surfaces: Surfaces,
    /// The technique's hard visibility mask of the same frame.
    technique: Mask,
    vis: ReferenceVisibility,
    next_row: u32,
    /// Rays (pairs in reach of a shadow-casting light) per row, and in all.
    rays_per_row: Vec<u64>,
    rays: u64,
    rays_done: u64,
    trace_ms: f64,
    /// What preparing took: the extra frame and its read-backs, the BVH.
    pub(crate) render_ms: f64,
    pub(crate) bvh_ms: f64,
    /// The technique scored.
    technique_name: String,
    /// Set once the last row is traced: the score, and the misclassification class per pixel.
    result: Option<score::Score>,
    classes: Option<Vec<u8>>,
    /// The soft part, where asked for and a sized light casts shadows.
    soft: Option<SoftRun>,
}

/// The soft reference traced row by row after the hard one, and the technique's fractions.
struct SoftRun {
    /// Samples per (pixel, sized light) side: n² rays per pair.
    n: u32,
    technique: Fractions,
    visible: Fractions,
    next_row: u32,
    rays_per_row: Vec<u64>,
    result: Option<SoftScore>,
}

impl ScoreRun {
    /// Renders `scene` as `compare` renders a variant with `settings` (PCF off, visibility
    /// mask on), reads the frame's G-buffer and mask back and builds the reference's BVH.
    pub(crate) async fn start(
        ctx: &manyshadows::GpuContext,
        scene: &Scene,
        settings: RenderSettings,
        soft_samples: u32,
    ) -> Result<Self, String> {
        let t0 = now_ms();
        let sized = scene.lights.iter().any(|l| l.size > 0.0 && l.casts_shadows);
        let soft_wanted = soft_samples > 0 && sized;
        let settings = settings
            .with_pcf(Pcf::Off)
            .with_visibility(true)
            .with_soft_visibility(soft_wanted);
        let single_sided = settings.shadow.casters.single_sided;
        let technique_name = settings.technique.name().to_string();
        let (w, h) = (settings.width, settings.height);
        let mut renderer = Renderer::new(ctx, scene, settings).map_err(|e| e.to_string())?;
        let target = ctx
            .device
            .create_texture(&manyshadows::wgpu::TextureDescriptor {
                label: Some("web.score.frame"),
                size: manyshadows::wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: manyshadows::wgpu::TextureDimension::D2,
                format: manyshadows::wgpu::TextureFormat::Rgba8UnormSrgb,
                usage: manyshadows::wgpu::TextureUsages::RENDER_ATTACHMENT
                    | manyshadows::wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
        renderer.render_to(&target).map_err(|e| e.to_string())?;
        let g = manyshadows::read_deferred(|| renderer.read_gbuffer())
            .await
            .map_err(|e| e.to_string())?;
        let (mask, soft_bytes) = manyshadows::read_deferred(|| renderer.read_visibility())
            .await
            .map_err(|e| e.to_string())?;
        let mask = mask.ok_or_else(|| {
            format!("technique {technique_name} gave no visibility mask to score")
        })?;
        let render_ms = now_ms() - t0;
        let points: Vec<Option<SurfacePoint>> = (0..g.position.len())
            .map(|i| {
                g.covered[i].then(|| SurfacePoint {
                    position: g.position[i],
                    normal: g.normal[i],
                })
            })
            .collect();
        let surfaces = Surfaces::new(g.width, g.height, points).map_err(|e| e.to_string())?;
        let technique = Mask {
            width: mask.width,
            height: mask.height,
            lights: mask.lights,
            words_per_pixel: mask.words_per_pixel,
            words: mask.words,
        };
        let t1 = now_ms();
        let scene = renderer.scene();
        let tracer = Tracer::with_rule(scene, single_sided).map_err(|e| e.to_string())?;
        let bvh_ms = now_ms() - t1;
        let lights = scene.lights.clone();
        // The rays: every covered pixel's pairs in reach of a light that casts shadows.
        let rays_per_row: Vec<u64> = (0..g.height as usize)
            .map(|y| {
                let row = &surfaces.points[y * g.width as usize..(y + 1) * g.width as usize];
                row.iter()
                    .flatten()
                    .map(|p| {
                        lights
                            .iter()
                            .filter(|l| l.casts_shadows && in_reach(l, p.position))
                            .count() as u64
                    })
                    .sum()
            })
            .collect();
        let soft = match (soft_wanted, soft_bytes) {
            (false, _) => None,
            (true, None) => {
                return Err(format!(
                    "technique {technique_name} gave no soft visibility to score"
                ))
            }
            (true, Some(b)) => {
                let n = grid_side(soft_samples);
                // n² rays per in-reach pair of a sized light that casts shadows, one per pair
                // of a hard one (the hard reference's ray again).
                let rays_per_row = (0..g.height as usize)
                    .map(|y| {
                        let row =
                            &surfaces.points[y * g.width as usize..(y + 1) * g.width as usize];
                        row.iter()
                            .flatten()
                            .map(|p| {
                                lights
                                    .iter()
                                    .filter(|l| in_reach(l, p.position))
                                    .map(|l| match (l.size > 0.0, l.casts_shadows) {
                                        (true, true) => u64::from(n * n),
                                        (false, true) => 1,
                                        _ => 0,
                                    })
                                    .sum::<u64>()
                            })
                            .sum()
                    })
                    .collect();
                Some(SoftRun {
                    n,
                    technique: Fractions {
                        width: b.width,
                        height: b.height,
                        lights: b.lights,
                        values: b.values.iter().map(|&v| f32::from(v) / 255.0).collect(),
                    },
                    visible: Fractions::zeros(g.width, g.height, lights.len() as u32),
                    next_row: 0,
                    rays_per_row,
                    result: None,
                })
            }
        };
        let rays = rays_per_row.iter().sum::<u64>()
            + soft
                .as_ref()
                .map_or(0, |s| s.rays_per_row.iter().sum::<u64>());
        let n = lights.len() as u32;
        Ok(Self {
            tracer,
            vis: ReferenceVisibility {
                lit: Mask::zeros(g.width, g.height, n),
                reach: Mask::zeros(g.width, g.height, n),
                facing: Mask::zeros(g.width, g.height, n),
            },
            lights,
            surfaces,
            technique,
            next_row: 0,
            rays_per_row,
            rays,
            rays_done: 0,
            trace_ms: 0.0,
            render_ms,
            bvh_ms,
            technique_name,
            result: None,
            classes: None,
            soft,
        })
    }

    /// What the run will trace, as JSON: the frame's size, the lights, the rays.
    pub(crate) fn plan_json(&self) -> String {
        format!(
            "{{\"technique\":\"{}\",\"width\":{},\"height\":{},\"lights\":{},\"rays\":{},\
             \"triangles\":{},\"render_ms\":{:.1},\"bvh_ms\":{:.1},\"soft_samples\":{}}}",
            self.technique_name,
            self.surfaces.width,
            self.surfaces.height,
            self.lights.len(),
            self.rays,
            self.tracer.triangle_count(),
            self.render_ms,
            self.bvh_ms,
            self.soft.as_ref().map_or(0, |s| s.n * s.n)
        )
    }

    /// Traces rows for about `budget_ms` (at least one row); returns the fraction of the rays
    /// traced so far. Once every row is traced the frame is scored.
    pub(crate) fn step(&mut self, budget_ms: f64) -> Result<f64, String> {
        let start = now_ms();
        let (w, h) = (self.surfaces.width, self.surfaces.height);
        let row_words = w as usize * self.vis.lit.words_per_pixel as usize;
        while self.next_row < h {
            // Rows at a time, as many as should fit the budget at the speed so far.
            let left = (budget_ms - (now_ms() - start)).max(1.0);
            let (rows, rays) = rows_to_trace(&self.rays_per_row, self.next_row, self.speed(), left);
            let (a, b) = (self.next_row as usize, (self.next_row + rows) as usize);
            let part = Surfaces::new(
                w,
                rows,
                self.surfaces.points[a * w as usize..b * w as usize].to_vec(),
            )
            .map_err(|e| e.to_string())?;
            let t = now_ms();
            let v = reference_visibility(
                &self.tracer,
                &self.lights,
                &part,
                &|| {},
                &AtomicBool::new(false),
            )
            .ok_or("the reference was cancelled")?;
            self.trace_ms += now_ms() - t;
            self.rays_done += rays;
            for (dst, src) in [
                (&mut self.vis.lit, &v.lit),
                (&mut self.vis.reach, &v.reach),
                (&mut self.vis.facing, &v.facing),
            ] {
                dst.words[a * row_words..b * row_words].copy_from_slice(&src.words);
            }
            self.next_row += rows;
            if now_ms() - start >= budget_ms {
                break;
            }
        }
        if self.next_row >= h && self.classes.is_none() {
            let band = score::edge_band(&self.vis.lit, &self.surfaces.covered(), EDGE_BAND);
            let s = score::score(&self.vis, &band, &self.technique).map_err(|e| e.to_string())?;
            self.classes = Some(
                score::error_classes(&self.vis, &band, &self.technique, None)
                    .map_err(|e| e.to_string())?,
            );
            self.result = Some(s);
        }
        if self.next_row >= h {
            self.step_soft(start, budget_ms)?;
        }
        Ok(if self.finished() {
            1.0
        } else if self.rays == 0 {
            0.0
        } else {
            (self.rays_done as f64 / self.rays as f64).min(0.999)
        })
    }

    /// The soft reference's next rows, while the budget that began at `start` lasts (at least
    /// one row); scores the soft visibility after the last.
    fn step_soft(&mut self, start: f64, budget_ms: f64) -> Result<(), String> {
        let mut speed = self.speed();
        let Some(soft) = self.soft.as_mut() else {
            return Ok(());
        };
        let (w, h) = (self.surfaces.width as usize, self.surfaces.height);
        let lights = self.lights.len();
        while soft.next_row < h {
            let left = (budget_ms - (now_ms() - start)).max(1.0);
            let (rows, rays) = rows_to_trace(&soft.rays_per_row, soft.next_row, speed, left);
            let t = now_ms();
            // As `reference_soft_visibility` traces a row: the same samples and seeds.
            for y in soft.next_row..soft.next_row + rows {
                for x in 0..w {
                    let pixel = y as usize * w + x;
                    let Some(sp) = self.surfaces.points[pixel] else {
                        continue;
                    };
                    for (li, light) in self.lights.iter().enumerate() {
                        if !self.vis.reach.get(pixel, li as u32) {
                            continue;
                        }
                        soft.visible.values[pixel * lights + li] = point_soft_visibility(
                            &self.tracer,
                            light,
                            sp.position,
                            sp.normal,
                            soft.n,
                            seed(x as u32, y, li as u32),
                        );
                    }
                }
            }
            self.trace_ms += now_ms() - t;
            self.rays_done += rays;
            speed = self.rays_done as f64 / self.trace_ms.max(1e-3);
            soft.next_row += rows;
            if now_ms() - start >= budget_ms {
                break;
            }
        }
        if soft.next_row >= h && soft.result.is_none() {
            let reference = SoftVisibility {
                visible: soft.visible.clone(),
                reach: self.vis.reach.clone(),
                facing: self.vis.facing.clone(),
                samples: soft.n * soft.n,
            };
            soft.result = Some(soft_score(&reference, &soft.technique).map_err(|e| e.to_string())?);
        }
        Ok(())
    }

    /// Rays traced per millisecond so far (0 before the first row).
    fn speed(&self) -> f64 {
        if self.trace_ms > 0.0 {
            self.rays_done as f64 / self.trace_ms
        } else {
            0.0
        }
    }

    /// Whether every row of every part is traced and scored.
    fn finished(&self) -> bool {
        self.result.is_some() && self.soft.as_ref().is_none_or(|s| s.result.is_some())
    }

    /// The score once every row is traced, as JSON (`compare --json`'s names, over every
    /// light: fractions of the in-reach pairs), `None` before.
    pub(crate) fn result_json(&self) -> Option<String> {
        if !self.finished() {
            return None;
        }
        let s = self.result.as_ref()?;
        let c = s.total(|_| true);
        // The soft part: mean absolute error of the lit fractions over the scored pairs, and
        // by the reference's class (`compare`'s soft table).
        let soft = match self
            .soft
            .as_ref()
            .and_then(|s| s.result.as_ref().map(|r| (s, r)))
        {
            Some((run, r)) => {
                let t = r.total(|_| true);
                let class = |c: &manyshadows_reference::soft_score::ClassError| {
                    format!("{{\"pairs\":{},\"mean_abs_error\":{}}}", c.pairs, c.mean())
                };
                format!(
                    "{{\"samples\":{},\"all\":{},\"umbra\":{},\"penumbra\":{},\"lit\":{}}}",
                    run.n * run.n,
                    class(&t.scored()),
                    class(&t.umbra),
                    class(&t.penumbra),
                    class(&t.lit)
                )
            }
            None => "null".into(),
        };
        Some(format!(
            "{{\"technique\":\"{}\",\"width\":{},\"height\":{},\"lights\":{},\
             \"in_reach_pixels\":{},\"false_shadow\":{},\"false_light\":{},\
             \"false_shadow_fraction\":{},\"false_light_fraction\":{},\"error_fraction\":{},\
             \"band_fraction\":{},\"band_error_fraction\":{},\"rays\":{},\"trace_ms\":{:.1},\
             \"render_ms\":{:.1},\"bvh_ms\":{:.1},\"edge_band\":{},\"soft\":{}}}",
            self.technique_name,
            self.surfaces.width,
            self.surfaces.height,
            c.lights,
            c.in_reach,
            c.false_shadow,
            c.false_light,
            c.false_shadow_fraction(),
            c.false_light_fraction(),
            c.error_fraction(),
            c.band_fraction(),
            c.band_error_fraction(),
            self.rays,
            self.trace_ms,
            self.render_ms,
            self.bvh_ms,
            EDGE_BAND,
            soft
        ))
    }

    /// The misclassified pixels to lay over the frame, RGBA: `compare`'s colours (red =
    /// false shadow, green = false light, darker inside the edge band, yellow = both),
    /// transparent elsewhere. Empty before the score.
    pub(crate) fn overlay(&self) -> Vec<u8> {
        let Some(classes) = &self.classes else {
            return Vec::new();
        };
        let mut out = Vec::with_capacity(classes.len() * 4);
        for &c in classes {
            let px = match score::class_colour(c) {
                Some([r, g, b]) => [r, g, b, 255],
                None => [0; 4],
            };
            out.extend_from_slice(&px);
        }
        out
    }
}
