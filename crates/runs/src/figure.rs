//! Figures as PNG and SVG (plotters) with confidence bands across seeds, rendered with an
//! embedded font so that no system font is needed, and statistics across seeds.

use std::cmp::Ordering;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use sepg_estimators::student_t_quantile;

use crate::error::{Error, Result};
use crate::folder::write_atomic;

/// DejaVu Sans restricted to Latin, Greek and mathematical symbols (see
/// `figure/LICENSE-DejaVu.txt`).
static FONT: &[u8] = include_bytes!("figure/DejaVuSans-subset.ttf");
const FAMILY: &str = "sans-serif";

/// Colours of the series, in order (the Tableau 10 palette).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Colour of series `i` out of `n`: the Tableau 10 palette up to ten series; beyond, `n` hues
/// spread evenly around the colour wheel, neighbours in hue also differing in lightness, so
/// that no two series of a figure share a colour however many there are.
pub fn colour(i: usize, n: usize) -> RGBColor {
    if n <= PALETTE.len() {
        return PALETTE[i % PALETTE.len()];
    }
    let hue = i as f64 / n as f64;
    let lightness = [0.42, 0.62, 0.30][i % 3];
    hsl_to_rgb(hue, 0.80, lightness)
}

/// sRGB colour of hue `h` ∈ [0, 1) (fraction of a turn), saturation `s` and lightness `l`
/// ∈ [0, 1] (the HSL model).
fn hsl_to_rgb(h: f64, s: f64, l: f64) -> RGBColor {
    let c = (1.0 - (2.0 * l - 1.0).abs()) * s;
    let hp = 6.0 * h.rem_euclid(1.0);
    let x = c * (1.0 - (hp % 2.0 - 1.0).abs());
    let (r, g, b) = match hp as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    let byte = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    RGBColor(byte(r), byte(g), byte(b))
}

/// What the band around a mean curve shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[non_exhaustive]
pub enum BandKind {
    /// Two-sided 95% t-interval of the mean: m ± t(0.975, K − 1)·s/√K (wide for few seeds:
    /// t(0.975, 1) = 12.7).
    #[default]
    Ci95,
    /// One standard error: m ± s/√K.
    Se,
    /// No band.
    None,
}

impl BandKind {
    /// How the band is described in a figure's title.
    pub fn describe(self) -> &'static str {
        match self {
            BandKind::Ci95 => "mean and 95% t-interval across seeds",
            BandKind::Se => "mean ± one standard error across seeds",
            BandKind::None => "mean across seeds",
        }
    }
}

/// Fewest seeds for which a band is worth drawing without a warning: with two seeds the 95%
/// t-interval uses t(0.975, 1) = 12.7 and the standard error rests on one degree of freedom.
pub const MIN_BAND_SEEDS: usize = 3;

/// Lower and upper ends of a confidence band, point by point.
pub type Band = (Vec<f64>, Vec<f64>);

/// One curve: a mean over seeds and, with two seeds or more, its 95% confidence band.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Mean over seeds.
    pub mean: Vec<f64>,
    /// Lower and upper ends of the band.
    pub band: Option<Band>,
}

/// One panel of a figure.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Panel {
    /// Caption.
    pub title: String,
    /// Abscissa label.
    pub x_label: String,
    /// Ordinate label.
    pub y_label: String,
    /// Curves.
    pub series: Vec<Series>,
    /// Dashed horizontal reference lines (label, value).
    pub hlines: Vec<(String, f64)>,
}

impl Panel {
    /// The panel with every band raised to at least `floor`, for quantities that cannot go
    /// below it (σ ≥ 0): a symmetric band around a mean close to the floor would otherwise
    /// show impossible values.
    #[must_use]
    pub fn clipped_at(mut self, floor: f64) -> Panel {
        for s in &mut self.series {
            if let Some((lo, hi)) = &mut s.band {
                for y in lo.iter_mut().chain(hi.iter_mut()) {
                    *y = y.max(floor);
                }
            }
        }
        self
    }
}

/// A figure: a title and a grid of panels.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Title above the panels.
    pub title: String,
    /// Panels, row by row.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
}

/// Mean and band of kind `kind` across seeds of equally long curves, point by point (the
/// curves are cut to the shortest).
///
/// # Formula
/// ```text
/// m = mean(y),  s = sample sd(y),  K seeds (band only for K ≥ 2)
/// Ci95: m ± t(0.975, K − 1) · s / √K        Se: m ± s / √K        None: no band
/// ```
pub fn mean_band(curves: &[Vec<f64>], kind: BandKind) -> (Vec<f64>, Option<Band>) {
    let len = curves.iter().map(Vec::len).min().unwrap_or(0);
    let k = curves.len();
    let mut mean = Vec::with_capacity(len);
    let mut lo = Vec::with_capacity(len);
    let mut hi = Vec::with_capacity(len);
    for i in 0..len {
        let ys: Vec<f64> = curves.iter().map(|c| c[i]).collect();
        let (m, h) = match kind {
            BandKind::Se => mean_se(&ys),
            _ => mean_halfwidth(&ys),
        };
        mean.push(m);
        lo.push(m - h.unwrap_or(0.0));
        hi.push(m + h.unwrap_or(0.0));
    }
    let band = (k >= 2 && kind != BandKind::None).then_some((lo, hi));
    (mean, band)
}

/// Mean of `ys` and its standard error s/√K (`None` for fewer than two values).
fn mean_se(ys: &[f64]) -> (f64, Option<f64>) {
    let k = ys.len();
    if k == 0 {
        return (f64::NAN, None);
    }
    let m = ys.iter().sum::<f64>() / k as f64;
    if k < 2 {
        return (m, None);
    }
    let var = ys.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (k - 1) as f64;
    (m, Some((var / k as f64).sqrt()))
}

/// Mean of `ys` and the half-width t(0.975, K − 1)·s/√K of its two-sided 95% confidence
/// interval (`None` for fewer than two values).
pub fn mean_halfwidth(ys: &[f64]) -> (f64, Option<f64>) {
    let k = ys.len();
    if k == 0 {
        return (f64::NAN, None);
    }
    let (m, se) = mean_se(ys);
    let t = student_t_quantile(0.975, (k - 1) as f64).unwrap_or(f64::NAN);
    (m, se.map(|se| t * se))
}

fn register_font() -> Result<()> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(Error::failed("the embedded font cannot be loaded"))
    }
}

fn range(panel: &Panel) -> (f64, f64, f64, f64) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for s in &panel.series {
        let bands = s.band.iter().flat_map(|(lo, hi)| lo.iter().chain(hi));
        for (&x, &y) in s.x.iter().zip(&s.mean) {
            if x.is_finite() && y.is_finite() {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
        for &y in bands.filter(|y| y.is_finite()) {
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    for &(_, y) in &panel.hlines {
        if y.is_finite() {
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    if x0.partial_cmp(&x1) != Some(Ordering::Less) {
        (x0, x1) = if x0.is_finite() {
            (x0 - 1.0, x0 + 1.0)
        } else {
            (0.0, 1.0)
        };
    }
    if y0.partial_cmp(&y1) != Some(Ordering::Less) {
        (y0, y1) = if y0.is_finite() {
            (y0 - 0.5 * y0.abs().max(1e-9), y0 + 0.5 * y0.abs().max(1e-9))
        } else {
            (0.0, 1.0)
        };
    }
    let pad = 0.05 * (y1 - y0);
    (x0, x1, y0 - pad, y1 + pad)
}

/// The label of tick value `v` on an axis spanning `span`: a value within 10⁻⁹·span of 0 is
/// round-off of the tick arithmetic and reads `0`; others get the digits that tell ticks a
/// tenth of the span apart, as a plain decimal for 10⁻³ ≤ |v| < 10⁵ and in scientific
/// notation otherwise, without trailing zeros.
fn tick(v: f64, span: f64) -> String {
    let a = v.abs();
    let span = if span.is_finite() && span > 0.0 {
        span
    } else {
        a.max(1.0)
    };
    if !v.is_finite() {
        return v.to_string();
    }
    if a <= 1e-9 * span {
        return "0".to_owned();
    }
    let resolution = (span / 10.0).log10().floor();
    if (1e-3..1e5).contains(&a) {
        let decimals = (-resolution).clamp(0.0, 12.0) as usize;
        trim_zeros(&format!("{v:.decimals$}")).to_owned()
    } else {
        let digits = (a.log10().floor() - resolution).clamp(1.0, 12.0) as usize;
        let s = format!("{v:.digits$e}");
        match s.split_once('e') {
            Some((mantissa, exponent)) => format!("{}e{exponent}", trim_zeros(mantissa)),
            None => s,
        }
    }
}

/// `s` without the trailing zeros of its fractional part (and without a bare point).
fn trim_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

/// Most points drawn per curve: longer curves are reduced to this many buckets, each keeping
/// its lowest and highest point, so that spikes survive and a sweep's SVG stays small.
const MAX_BUCKETS: usize = 300;

/// The finite points of `(x, y)` reduced to at most [`MAX_BUCKETS`] buckets of consecutive
/// points, each kept as its lowest and highest point in order (`Pick::Both`), or only the
/// lowest (`Pick::Min`, lower band edges) or highest (`Pick::Max`, upper band edges), so the
/// drawn envelope never shrinks.
fn decimate(x: &[f64], y: &[f64], pick: Pick) -> Vec<(f64, f64)> {
    let pts: Vec<(f64, f64)> = finite_points(x.iter().zip(y)).collect();
    if pts.len() <= 2 * MAX_BUCKETS {
        return pts;
    }
    let stride = pts.len().div_ceil(MAX_BUCKETS);
    let mut out = Vec::with_capacity(2 * MAX_BUCKETS + 1);
    for chunk in pts.chunks(stride) {
        let by_y = |a: &&(f64, f64), b: &&(f64, f64)| a.1.total_cmp(&b.1);
        let lo = chunk.iter().min_by(by_y).copied();
        let hi = chunk.iter().max_by(by_y).copied();
        match (pick, lo, hi) {
            (Pick::Min, Some(lo), _) => out.push(lo),
            (Pick::Max, _, Some(hi)) => out.push(hi),
            (Pick::Both, Some(lo), Some(hi)) => {
                if lo.0 <= hi.0 {
                    out.extend([lo, hi]);
                } else {
                    out.extend([hi, lo]);
                }
            }
            _ => {}
        }
    }
    out.dedup();
    out
}

/// Which points of a bucket [`decimate`] keeps.
#[derive(Clone, Copy)]
enum Pick {
    Min,
    Max,
    Both,
}

/// Pixel geometry of a drawn figure.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Layout {
    /// Width and height of the whole image.
    width: u32,
    height: u32,
    /// Panel grid (rows, columns).
    rows: u32,
    columns: u32,
    /// Left edge of the legend column, right of every panel.
    legend_x: u32,
}

const PANEL_W: u32 = 520;
const PANEL_H: u32 = 400;
const TITLE_H: u32 = 60;
const LEGEND_ROW: u32 = 20;

/// One entry of the legend: a label, its colour and whether it is a dashed reference line.
struct Entry {
    label: String,
    colour: RGBColor,
    dashed: bool,
}

/// The panels that have something to show.
fn shown(fig: &Figure) -> Vec<&Panel> {
    fig.panels
        .iter()
        .filter(|p| {
            p.series
                .iter()
                .any(|s| s.mean.iter().any(|y| y.is_finite()))
        })
        .collect()
}

/// The legend entries of `fig`: every series label once, in order of first appearance, then
/// every reference line once. A label keeps its colour in every panel.
fn legend(fig: &Figure) -> Vec<Entry> {
    let mut labels: Vec<&str> = Vec::new();
    for s in fig.panels.iter().flat_map(|p| &p.series) {
        if !labels.contains(&s.label.as_str()) {
            labels.push(&s.label);
        }
    }
    let n = labels.len();
    let mut out: Vec<Entry> = labels
        .iter()
        .enumerate()
        .map(|(i, l)| Entry {
            label: (*l).to_owned(),
            colour: colour(i, n),
            dashed: false,
        })
        .collect();
    for (l, _) in fig.panels.iter().flat_map(|p| &p.hlines) {
        if !out.iter().any(|e| e.dashed && e.label == *l) {
            out.push(Entry {
                label: l.clone(),
                colour: BLACK,
                dashed: true,
            });
        }
    }
    out
}

fn layout(fig: &Figure) -> Layout {
    let n = shown(fig).len().max(1) as u32;
    let columns = (fig.columns.max(1) as u32).min(n);
    let rows = n.div_ceil(columns);
    let entries = legend(fig);
    let chars = entries
        .iter()
        .map(|e| e.label.chars().count())
        .max()
        .unwrap_or(0) as u32;
    let legend_w = 50 + 7 * chars.max(8);
    let legend_h = TITLE_H + 20 + LEGEND_ROW * entries.len() as u32;
    Layout {
        width: PANEL_W * columns + legend_w,
        height: (TITLE_H + PANEL_H * rows).max(legend_h),
        rows,
        columns,
        legend_x: PANEL_W * columns,
    }
}

/// How curves are stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pen {
    /// One polyline of width 2 (SVG: the viewer joins the segments).
    Stroke,
    /// Three polylines of width 1, offset by a pixel right and up (bitmaps: plotters fills a
    /// wider polyline as one polygon whose joins at sharp turns spike far beyond the data).
    Pixels,
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    pen: Pen,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let lay = layout(fig);
    root.fill(&WHITE).map_err(e)?;
    let area = root.titled(&fig.title, (FAMILY, 22)).map_err(e)?;
    let (panels_area, legend_area) = area.split_horizontally(lay.legend_x);
    let panels_area = panels_area.shrink((0, 0), (lay.legend_x, PANEL_H * lay.rows));
    let entries = legend(fig);
    let cells = panels_area.split_evenly((lay.rows as usize, lay.columns as usize));
    for (cell, panel) in cells.iter().zip(shown(fig)) {
        draw_panel(cell, panel, &entries, pen)?;
    }
    draw_legend(&legend_area, &entries)?;
    root.present().map_err(e)
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let font = (FAMILY, 13).into_font().color(&BLACK);
    for (i, entry) in entries.iter().enumerate() {
        let y = 30 + LEGEND_ROW as i32 * i as i32;
        let line = vec![(10, y), (38, y)];
        if entry.dashed {
            area.draw(&PathElement::new(
                vec![(10, y), (20, y)],
                BLACK.stroke_width(1),
            ))
            .map_err(e)?;
            area.draw(&PathElement::new(
                vec![(28, y), (38, y)],
                BLACK.stroke_width(1),
            ))
            .map_err(e)?;
        } else {
            area.draw(&PathElement::new(line, entry.colour.stroke_width(3)))
                .map_err(e)?;
        }
        area.draw(&Text::new(entry.label.as_str(), (46, y - 7), font.clone()))
            .map_err(e)?;
    }
    Ok(())
}

/// The (x, y) points of a curve where both are finite.
fn finite_points<'a>(
    points: impl Iterator<Item = (&'a f64, &'a f64)>,
) -> impl Iterator<Item = (f64, f64)> {
    points
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(&x, &y)| (x, y))
}

fn draw_panel<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    panel: &Panel,
    entries: &[Entry],
    pen: Pen,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let (x0, x1, y0, y1) = range(panel);
    let mut chart = ChartBuilder::on(cell)
        .caption(&panel.title, (FAMILY, 16))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .x_labels(6)
        .y_labels(6)
        .x_label_formatter(&|v| tick(*v, x1 - x0))
        .y_label_formatter(&|v| tick(*v, y1 - y0))
        .light_line_style(WHITE)
        .draw()
        .map_err(e)?;
    for s in &panel.series {
        let colour = entries
            .iter()
            .find(|en| !en.dashed && en.label == s.label)
            .map_or(BLACK, |en| en.colour);
        if let Some((lo, hi)) = &s.band {
            let mut poly = decimate(&s.x, hi, Pick::Max);
            poly.extend(decimate(&s.x, lo, Pick::Min).into_iter().rev());
            chart
                .draw_series(std::iter::once(Polygon::new(
                    poly,
                    colour.mix(0.18).filled(),
                )))
                .map_err(e)?;
        }
        let points = decimate(&s.x, &s.mean, Pick::Both);
        match pen {
            Pen::Stroke => {
                chart
                    .draw_series(LineSeries::new(points, colour.stroke_width(2)))
                    .map_err(e)?;
            }
            Pen::Pixels => {
                let (w, h) = chart.plotting_area().dim_in_pixel();
                let dx = (x1 - x0) / f64::from(w.max(1));
                let dy = (y1 - y0) / f64::from(h.max(1));
                for (ox, oy) in [(0.0, 0.0), (dx, 0.0), (0.0, dy)] {
                    let shifted = points.iter().map(|&(x, y)| (x + ox, y + oy));
                    chart
                        .draw_series(LineSeries::new(shifted, colour.stroke_width(1)))
                        .map_err(e)?;
                }
            }
        }
    }
    for (_, y) in &panel.hlines {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0, *y), (x1, *y)],
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(e)?;
    }
    Ok(())
}

fn size(fig: &Figure) -> (u32, u32) {
    let lay = layout(fig);
    (lay.width, lay.height)
}

/// Writes `fig` to `path`, as PNG or SVG by the extension, atomically (rendered to a
/// temporary file in the same folder, then renamed).
///
/// # Errors
/// [`Error::Invalid`] for another extension; [`Error::Failed`] when rendering or writing fails.
pub fn save(fig: &Figure, path: &Path) -> Result<()> {
    register_font()?;
    let fail = |e: String| Error::failed(format!("cannot draw {}: {e}", path.display()));
    match path.extension().and_then(|e| e.to_str()) {
        Some("svg") => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size(fig)).into_drawing_area();
                draw(&root, fig, Pen::Stroke).map_err(fail)?;
            }
            write_atomic(path, svg.as_bytes())
        }
        Some("png") => {
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            };
            let tmp = crate::folder::output_builder(0o644)
                .prefix(".sepg-figure-")
                .suffix(".png")
                .tempfile_in(&dir)
                .map_err(|e| Error::failed(format!("cannot write in {}: {e}", dir.display())))?;
            {
                let root = BitMapBackend::new(tmp.path(), size(fig)).into_drawing_area();
                draw(&root, fig, Pen::Pixels).map_err(fail)?;
            }
            tmp.persist(path).map_err(|e| {
                Error::failed(format!("cannot write {}: {}", path.display(), e.error))
            })?;
            Ok(())
        }
        _ => Err(Error::invalid(format!(
            "{}: figures are written as .png or .svg",
            path.display()
        ))),
    }
}

/// Writes `fig` as `<stem>.png` and `<stem>.svg` in `dir`; returns the two paths.
///
/// # Errors
/// As [`save`].
pub fn save_both(fig: &Figure, dir: &Path, stem: &str) -> Result<[PathBuf; 2]> {
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    save(fig, &png)?;
    save(fig, &svg)?;
    Ok([png, svg])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_is_the_t_interval() {
        // Values 1, 2, 3: mean 2, s = 1. For 2 degrees of freedom the t quantile has the
        // closed form t(p, 2) = (2p − 1)/√(2p(1 − p)).
        let (m, h) = mean_halfwidth(&[1.0, 2.0, 3.0]);
        assert_eq!(m, 2.0);
        let h = h.expect("two or more values");
        let t = 0.95 / (2.0 * 0.975 * 0.025f64).sqrt();
        assert!((h - t / 3f64.sqrt()).abs() < 1e-12, "{h}");
        assert_eq!(mean_halfwidth(&[5.0]), (5.0, None));
    }

    #[test]
    fn standard_error_band_and_no_band() {
        // Values 1, 2, 3 at every point: s = 1, K = 3, so the standard error is 1/√3.
        let curves = vec![vec![1.0; 4], vec![2.0; 4], vec![3.0; 4]];
        let (m, band) = mean_band(&curves, BandKind::Se);
        assert_eq!(m, vec![2.0; 4]);
        let (lo, hi) = band.expect("three seeds");
        let se = 1.0 / 3f64.sqrt();
        assert!(lo.iter().all(|y| (y - (2.0 - se)).abs() < 1e-12), "{lo:?}");
        assert!(hi.iter().all(|y| (y - (2.0 + se)).abs() < 1e-12), "{hi:?}");
        assert_eq!(mean_band(&curves, BandKind::None).1, None);
    }

    #[test]
    fn sigma_bands_are_clipped_at_zero() {
        // Two seeds with σ = 0.001 and 0.021: the 95% t-interval, 0.011 ± 12.7 · 0.01, reaches
        // −0.116; clipped at 0 its lower end is 0 and its upper end is unchanged.
        let curves = vec![vec![0.001, 0.5], vec![0.021, 0.5]];
        let (mean, band) = mean_band(&curves, BandKind::Ci95);
        let (lo, hi) = band.clone().expect("two seeds");
        assert!(lo[0] < -0.1, "{lo:?}");
        let panel = Panel {
            series: vec![Series {
                label: "σ".into(),
                x: vec![0.0, 1.0],
                mean,
                band,
            }],
            ..Panel::default()
        }
        .clipped_at(0.0);
        let (clo, chi) = panel.series[0].band.clone().expect("band kept");
        assert_eq!(clo, vec![0.0, 0.5]);
        assert_eq!(chi, hi);
    }

    /// CIE L*a*b* of an sRGB colour (D65 white), for perceptual distances.
    fn lab(c: RGBColor) -> [f64; 3] {
        let lin = |u: u8| {
            let v = f64::from(u) / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        let (r, g, b) = (lin(c.0), lin(c.1), lin(c.2));
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
        let f = |t: f64| {
            if t > 216.0 / 24389.0 {
                t.cbrt()
            } else {
                (24389.0 / 27.0 * t + 16.0) / 116.0
            }
        };
        let (fx, fy, fz) = (f(x), f(y), f(z));
        [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
    }

    #[test]
    fn colours_stay_distinct_for_many_series() {
        // Every pair of the n colours differs by a CIE76 ΔE of at least 10 for up to 24 series
        // (about four just-noticeable differences), and no two colours coincide up to 100.
        for n in 1..=100usize {
            let cs: Vec<[f64; 3]> = (0..n).map(|i| lab(colour(i, n))).collect();
            let mut min = f64::INFINITY;
            for i in 0..n {
                for j in 0..i {
                    let d = (0..3).map(|k| (cs[i][k] - cs[j][k]).powi(2)).sum::<f64>();
                    min = min.min(d.sqrt());
                }
            }
            let need = if n <= 24 { 10.0 } else { 1.0 };
            assert!(min >= need, "{n} series: closest pair ΔE = {min}");
        }
    }

    #[test]
    fn decimation_keeps_spikes_and_bounds_the_points() {
        let x: Vec<f64> = (0..10_001).map(f64::from).collect();
        let mut y = vec![0.0; x.len()];
        y[4321] = 7.0;
        let pts = decimate(&x, &y, Pick::Both);
        assert!(pts.len() <= 2 * MAX_BUCKETS, "{}", pts.len());
        assert!(pts.contains(&(4321.0, 7.0)));
        assert!(decimate(&x, &y, Pick::Max).contains(&(4321.0, 7.0)));
        assert!(!decimate(&x, &y, Pick::Min).contains(&(4321.0, 7.0)));
    }

    /// A sweep-sized figure: `groups` series of `len` points with bands in four panels.
    fn big_figure(groups: usize, len: usize) -> Figure {
        let x: Vec<f64> = (0..len).map(|i| i as f64).collect();
        let series: Vec<Series> = (0..groups)
            .map(|g| {
                let mean: Vec<f64> = x.iter().map(|t| (t * 0.01 + g as f64).sin()).collect();
                let lo = mean.iter().map(|m| m - 0.1).collect();
                let hi = mean.iter().map(|m| m + 0.1).collect();
                Series {
                    label: format!("group {g}"),
                    x: x.clone(),
                    mean,
                    band: Some((lo, hi)),
                }
            })
            .collect();
        let panel = Panel {
            title: "p".into(),
            series,
            ..Panel::default()
        };
        Figure {
            title: "sweep".into(),
            panels: vec![panel; 4],
            columns: 2,
        }
    }

    #[test]
    fn sweep_svg_is_small_and_its_legend_is_right_of_the_panels() {
        // 16 groups × 4 panels × 10,001 iterations with bands: drawn in full this is
        // over 15 MB of SVG.
        let fig = big_figure(16, 10_001);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("f.svg");
        save(&fig, &path).expect("drawn");
        let svg = std::fs::read_to_string(&path).expect("read");
        assert!(svg.len() < 1_000_000, "{} bytes", svg.len());
        let lay = layout(&fig);
        assert_eq!((lay.rows, lay.columns, lay.legend_x), (2, 2, 2 * PANEL_W));
        // Every legend label is a text element whose x lies right of the last panel column.
        for g in 0..16 {
            let label = format!(">\ngroup {g}\n</text>");
            let at = svg
                .find(&label)
                .unwrap_or_else(|| panic!("group {g} not in legend"));
            let open = svg[..at].rfind("<text x=\"").expect("text element") + 9;
            let x: u32 = svg[open..]
                .split('"')
                .next()
                .and_then(|v| v.parse().ok())
                .expect("x attribute");
            assert!(x >= lay.legend_x, "group {g} at x = {x}");
        }
    }

    #[test]
    fn tick_labels_snap_round_off_to_zero_and_keep_ticks_apart() {
        // The v-panel of a reproduction spanning [-0.7, 0.1] put its 0 tick at -1.1e-16.
        assert_eq!(tick(-1.1e-16, 0.8), "0");
        assert_eq!(tick(2.2e-17, 5e3), "0");
        assert_eq!(tick(0.0, 0.8), "0");
        assert_eq!(tick(-0.6, 0.8), "-0.6");
        assert_eq!(tick(-0.25, 0.8), "-0.25");
        assert_eq!(tick(1500.0, 4000.0), "1500");
        // A tiny value on a tiny axis is a real tick, shown in scientific notation.
        assert_eq!(tick(2.5e-5, 1e-4), "2.5e-5");
        assert_eq!(tick(3e-4, 1e-3), "3e-4");
        assert_eq!(tick(-1.5e5, 1e5), "-1.5e5");
        // Ticks a tenth of the span apart never share a label, on axes of any size.
        for span in [1e-7, 3e-4, 0.02, 0.8, 7.0, 3e3, 2e6] {
            let start = -span * 0.37;
            let step = span / 10.0;
            let labels: Vec<String> = (0..=10)
                .map(|k| tick(start + step * f64::from(k), span))
                .collect();
            for (i, a) in labels.iter().enumerate() {
                assert!(!labels[..i].contains(a), "{span}: {labels:?}");
            }
        }
    }

    /// Rows of the RGB image `buf` of width `w` holding a pixel of colour `c` left of
    /// column `right`.
    fn rows_with(buf: &[u8], w: usize, right: usize, c: RGBColor) -> Vec<usize> {
        let mut rows: Vec<usize> = buf
            .chunks(3)
            .enumerate()
            .filter(|(i, px)| i % w < right && px == &[c.0, c.1, c.2])
            .map(|(i, _)| i / w)
            .collect();
        rows.dedup();
        rows
    }

    #[test]
    fn dense_noisy_curves_stay_inside_their_panel_in_png() {
        // A noisy curve of 10,000 points in [0, 1], like the J of a sampled run: decimated to
        // sharp zigzags. Drawn with a thick polygonised stroke, the zigzags' joins spiked far
        // beyond the data, across the axis, its labels and the figure's title. The panel's
        // plotting area is its 400 px less the caption (about 20 px), the margins (2 × 10 px)
        // and the x-axis labels (40 px); the curve, with the range padded by 5% on each side,
        // must fit in it, below the figure's title (22 px text).
        let n = 10_000;
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mean: Vec<f64> = (0..n)
            .map(|_| {
                // xorshift64*, a fixed stream.
                state ^= state >> 12;
                state ^= state << 25;
                state ^= state >> 27;
                (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect();
        let fig = Figure {
            title: "noise".into(),
            panels: vec![Panel {
                title: "p".into(),
                series: vec![Series {
                    label: "noise".into(),
                    x: (0..n).map(f64::from).collect(),
                    mean,
                    band: None,
                }],
                ..Panel::default()
            }],
            columns: 1,
        };
        register_font().expect("font");
        let (w, h) = size(&fig);
        let mut buf = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            draw(&root, &fig, Pen::Pixels).expect("drawn");
        }
        // Left of the legend (whose sample line has the series' colour).
        let curve = rows_with(&buf, w as usize, layout(&fig).legend_x as usize, PALETTE[0]);
        let (top, bottom) = (
            *curve.first().expect("drawn"),
            *curve.last().expect("drawn"),
        );
        assert!(top > 40, "curve reaches row {top}");
        assert!(
            bottom - top < (PANEL_H - 80) as usize,
            "curve spans rows {top}..={bottom} of {h}"
        );
    }

    #[test]
    fn empty_panels_are_not_drawn() {
        let mut fig = big_figure(1, 10);
        fig.panels[1].series.clear();
        fig.columns = 3;
        assert_eq!(shown(&fig).len(), 3);
        let lay = layout(&fig);
        assert_eq!((lay.rows, lay.columns), (1, 3));
    }
}
