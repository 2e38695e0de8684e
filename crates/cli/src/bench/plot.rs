//! Plots in the manner of seed 000's Figures 19.3–19.9: time against the number of shadow
//! maps, one line per method; total on the left, per map on the right; GPU on top, CPU below.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

/// One record's medians, as [`plots`] draws them.
pub struct PlotPoint {
    /// Experiment (one picture per variant and resolution).
    pub variant: String,
    /// Resolution (0: none in the file name and title).
    pub resolution: u32,
    /// The count on the x axis (maps, lights).
    pub maps: usize,
    /// Method label (one line each).
    pub method: String,
    /// Median GPU ms.
    pub gpu_ms: Option<f64>,
    /// Median CPU ms, or what the plots' `second` names (`bench irregular`: the shadow stage's
    /// GPU ms).
    pub cpu_ms: f64,
}

/// What [`PlotPoint::cpu_ms`] holds in the benchmarks of shadow generation.
pub const CPU_TIME: &str = "CPU ms (record + submit)";

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

fn ensure_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The bundled DejaVu Sans, so plots need no system fonts.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

const COLOURS: &[RGBColor] = &[
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// A named line: `(name, [(x, y)])`.
pub type Series = (String, Vec<(f64, f64)>);

/// One panel of [`panels`]: caption, y unit and its series.
pub type Panel = (String, String, Vec<Series>);

/// A series of [`panels`]: `y` of every row that has one, against its count `x`.
pub fn series<R>(
    name: &str,
    rows: &[&R],
    x: impl Fn(&R) -> usize,
    y: impl Fn(&R) -> Option<f64>,
) -> Series {
    (
        name.to_string(),
        rows.iter()
            .filter_map(|r| y(r).map(|v| (x(r) as f64, v)))
            .collect(),
    )
}

/// Plots of any benchmark whose x axis is a count (`x_name`), files `<prefix>-<variant>-<res>.png`.
pub fn plots(
    points: &[PlotPoint],
    adapter: &str,
    dir: &Path,
    prefix: &str,
    x_name: &str,
    second: &str,
) -> Result<Vec<PathBuf>> {
    ensure_font();
    let mut keys: Vec<(String, u32)> = Vec::new();
    for p in points {
        let k = (p.variant.clone(), p.resolution);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let mut written = Vec::new();
    for (variant, res) in keys {
        let rows: Vec<&PlotPoint> = points
            .iter()
            .filter(|p| p.variant == variant && p.resolution == res)
            .collect();
        let mut methods: Vec<String> = Vec::new();
        for r in &rows {
            if !methods.contains(&r.method) {
                methods.push(r.method.clone());
            }
        }
        let series = |f: &dyn Fn(&PlotPoint) -> Option<f64>, per_map: bool| -> Vec<Series> {
            methods
                .iter()
                .map(|m| {
                    let pts = rows
                        .iter()
                        .filter(|r| &r.method == m)
                        .filter_map(|r| {
                            f(r).filter(|v| v.is_finite()).map(|v| {
                                let y = if per_map { v / r.maps as f64 } else { v };
                                (r.maps as f64, y)
                            })
                        })
                        .collect();
                    (m.clone(), pts)
                })
                .collect()
        };
        let path = if res > 0 {
            dir.join(format!("{prefix}-{variant}-{res}.png"))
        } else {
            dir.join(format!("{prefix}-{variant}.png"))
        };
        let (w, h) = (1400u32, 1000u32);
        let mut pixels = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
            let (title, body) = root.split_vertically(50);
            title
                .titled(
                    &if res > 0 {
                        format!("bench {prefix}: {variant}, {res}² maps — {adapter}")
                    } else {
                        format!("bench {prefix}: {variant} — {adapter}")
                    },
                    ("sans-serif", 20),
                )
                .map_err(|e| anyhow!("plot: {e}"))?;
            let panels = body.split_evenly((2, 2));
            let unit = x_name.trim_end_matches('s');
            let per_label_gpu = format!("GPU ms per {unit}");
            let per_label_cpu = format!("{second} per {unit}");
            let total_cpu = format!("{second}, total");
            let specs: [(&str, Vec<Series>); 4] = [
                ("GPU ms, total", series(&|p| p.gpu_ms, false)),
                (per_label_gpu.as_str(), series(&|p| p.gpu_ms, true)),
                (total_cpu.as_str(), series(&|p| Some(p.cpu_ms), false)),
                (per_label_cpu.as_str(), series(&|p| Some(p.cpu_ms), true)),
            ];
            for (area, (caption, data)) in panels.iter().zip(specs) {
                panel(area, caption, x_name, &data)?;
            }
            root.present().map_err(|e| anyhow!("plot: {e}"))?;
        }
        save_png(&path, &pixels, w, h)?;
        written.push(path);
    }
    Ok(written)
}

/// PNG with the strongest compression: flat-coloured plots shrink several-fold.
fn save_png(path: &Path, rgb: &[u8], w: u32, h: u32) -> Result<()> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;
    let file =
        std::fs::File::create(path).map_err(|e| anyhow!("writing {}: {e}", path.display()))?;
    PngEncoder::new_with_quality(
        std::io::BufWriter::new(file),
        CompressionType::Best,
        FilterType::Adaptive,
    )
    .write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
    .map_err(|e| anyhow!("writing {}: {e}", path.display()))
}

/// One picture of panels sharing a count axis (log scale), two side by side per row, as
/// many rows as they need: `(caption, y unit, series)` each, where a series is
/// `(name, [(x, y)])`. A panel whose values span more than a factor [`LOG_SPAN`] has a
/// logarithmic y axis too.
pub fn panels(path: &Path, title: &str, x_name: &str, specs: &[Panel]) -> Result<()> {
    ensure_font();
    let rows = specs.len().div_ceil(2).max(1);
    let (w, h) = (1400u32, 50 + 475 * rows as u32);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
        let (top, body) = root.split_vertically(50);
        top.titled(title, ("sans-serif", 20))
            .map_err(|e| anyhow!("plot: {e}"))?;
        for (area, (caption, unit, data)) in body.split_evenly((rows, 2)).iter().zip(specs) {
            panel_with_unit(area, caption, x_name, unit, data, true)?;
        }
        root.present().map_err(|e| anyhow!("plot: {e}"))?;
    }
    save_png(path, &pixels, w, h)
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    x_name: &str,
    data: &[Series],
) -> Result<()> {
    // Linear, as the seed's figures.
    panel_with_unit(area, caption, x_name, "ms", data, false)
}

fn panel_with_unit<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    x_name: &str,
    unit: &str,
    data: &[Series],
    log_y: bool,
) -> Result<()> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("plot: {e}");
    let all: Vec<(f64, f64)> = data.iter().flat_map(|s| s.1.iter().copied()).collect();
    if all.is_empty() {
        area.titled(&format!("{caption}: no data"), ("sans-serif", 16))
            .map_err(err)?;
        return Ok(());
    }
    let xmax = all.iter().map(|p| p.0).fold(1.0, f64::max).max(2.0);
    let ymax = all.iter().map(|p| p.1).fold(0.0, f64::max).max(1e-3) * 1.1;
    let ymin = all.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let builder = |area| {
        let mut b = ChartBuilder::on(area);
        b.caption(caption, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60);
        b
    };
    // With `log_y`, values spanning more than a factor LOG_SPAN (a denoised error beside a
    // plain one) on a log scale, so the small ones are not flattened against the axis.
    if log_y && ymin > 0.0 && ymax > LOG_SPAN * ymin {
        let mut chart = builder(area)
            // Powers of two: a decade has one labelled line, too few under 10.
            .build_cartesian_2d(
                (1.0..xmax).log_scale(),
                (0.9 * ymin..ymax).log_scale().base(2.0),
            )
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_name)
            .y_desc(format!("{unit} (log scale)"))
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| match *y {
                y if y >= 10.0 => format!("{y:.0}"),
                y if y >= 1.0 => format!("{y:.1}"),
                y => format!("{y:.3}"),
            })
            .light_line_style(TRANSPARENT)
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(err)?;
        draw_lines(&mut chart, data).map_err(err)
    } else {
        let mut chart = builder(area)
            .build_cartesian_2d((1.0..xmax).log_scale(), 0.0..ymax)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_name)
            .y_desc(unit)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .light_line_style(TRANSPARENT)
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(err)?;
        draw_lines(&mut chart, data).map_err(err)
    }
}

/// How many times its smallest value a panel's largest may be before its y axis turns
/// logarithmic.
const LOG_SPAN: f64 = 8.0;

/// The series as lines with dots, and their legend.
fn draw_lines<'a, DB: DrawingBackend + 'a, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    data: &[Series],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for (i, (name, pts)) in data.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
}
