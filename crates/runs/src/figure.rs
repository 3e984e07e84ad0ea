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

/// Mean and 95% confidence band across seeds of equally long curves, point by point.
///
/// # Formula
/// ```text
/// m = mean(y),  s = sample sd(y),  band = m ± t(0.975, K − 1) · s / √K     (K ≥ 2 seeds)
/// ```
pub fn mean_band(curves: &[Vec<f64>]) -> (Vec<f64>, Option<Band>) {
    let len = curves.iter().map(Vec::len).min().unwrap_or(0);
    let k = curves.len();
    let mut mean = Vec::with_capacity(len);
    let mut lo = Vec::with_capacity(len);
    let mut hi = Vec::with_capacity(len);
    for i in 0..len {
        let ys: Vec<f64> = curves.iter().map(|c| c[i]).collect();
        let (m, h) = mean_halfwidth(&ys);
        mean.push(m);
        lo.push(m - h.unwrap_or(0.0));
        hi.push(m + h.unwrap_or(0.0));
    }
    let band = (k >= 2).then_some((lo, hi));
    (mean, band)
}

/// Mean of `ys` and the half-width t(0.975, K − 1)·s/√K of its two-sided 95% confidence
/// interval (`None` for fewer than two values).
pub fn mean_halfwidth(ys: &[f64]) -> (f64, Option<f64>) {
    let k = ys.len();
    if k == 0 {
        return (f64::NAN, None);
    }
    let m = ys.iter().sum::<f64>() / k as f64;
    if k < 2 {
        return (m, None);
    }
    let var = ys.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (k - 1) as f64;
    let t = student_t_quantile(0.975, (k - 1) as f64).unwrap_or(f64::NAN);
    (m, Some(t * (var / k as f64).sqrt()))
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

fn tick(v: &f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else {
        format!("{v:.4}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_owned()
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let area = root.titled(&fig.title, (FAMILY, 22)).map_err(e)?;
    let cols = fig.columns.max(1);
    let rows = fig.panels.len().div_ceil(cols).max(1);
    for (cell, panel) in area.split_evenly((rows, cols)).iter().zip(&fig.panels) {
        draw_panel(cell, panel)?;
    }
    root.present().map_err(e)
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
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .light_line_style(WHITE)
        .draw()
        .map_err(e)?;
    for (i, s) in panel.series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        if let Some((lo, hi)) = &s.band {
            let mut poly: Vec<(f64, f64)> = finite_points(s.x.iter().zip(hi)).collect();
            poly.extend(finite_points(s.x.iter().zip(lo).rev()));
            chart
                .draw_series(std::iter::once(Polygon::new(
                    poly,
                    color.mix(0.18).filled(),
                )))
                .map_err(e)?;
        }
        let pts: Vec<(f64, f64)> = finite_points(s.x.iter().zip(&s.mean)).collect();
        chart
            .draw_series(LineSeries::new(pts, color.stroke_width(2)))
            .map_err(e)?
            .label(s.label.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
    }
    for (label, y) in &panel.hlines {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0, *y), (x1, *y)],
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(e)?
            .label(label.as_str())
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
    }
    if !panel.series.is_empty() || !panel.hlines.is_empty() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .label_font((FAMILY, 11))
            .draw()
            .map_err(e)?;
    }
    Ok(())
}

fn size(fig: &Figure) -> (u32, u32) {
    let cols = fig.columns.max(1) as u32;
    let rows = fig.panels.len().div_ceil(fig.columns.max(1)).max(1) as u32;
    (520 * cols, 60 + 400 * rows)
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
                draw(&root, fig).map_err(fail)?;
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
                draw(&root, fig).map_err(fail)?;
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
}
