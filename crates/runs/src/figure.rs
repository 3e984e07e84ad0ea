//! Figures as PNG and SVG (plotters) with confidence bands across seeds, rendered with an
//! embedded font so that no system font is needed, and statistics across seeds.
//!
//! Every band respects the domain of its quantity (see [`Scale`]): σ > 0 is banded on log σ
//! and transformed back, the budget by a percentile bootstrap that never leaves the range
//! its seeds reached, the other quantities by Student t-intervals. Labels may carry
//! subscripts written `J_{E}` (drawn as J with a lowered, smaller E).

use std::cmp::Ordering;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
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

/// Styles of the reference lines of a figure, in order of first appearance: colour, dash
/// length and gap (pixels at 100 dpi). Each differs from the others in both colour and dash
/// pattern, and none is a colour of the palette.
const REFERENCE_STYLES: [(RGBColor, u32, u32); 3] = [
    (RGBColor(0, 0, 0), 9, 4),
    (RGBColor(105, 105, 105), 2, 3),
    (RGBColor(128, 0, 64), 14, 3),
];

/// What the band around a mean curve shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[non_exhaustive]
pub enum BandKind {
    /// Two-sided 95% interval of the mean: m ± t(0.975, K − 1)·s/√K on the quantity's scale
    /// (wide for few seeds: t(0.975, 1) = 12.7), or the 95% percentile bootstrap interval
    /// (see [`Scale`]).
    #[default]
    Ci95,
    /// One standard error: m ± s/√K on the quantity's scale, or the central 68.27%
    /// percentile bootstrap interval.
    Se,
    /// No band.
    None,
}

impl BandKind {
    /// How the band is described in a figure's title.
    pub fn describe(self) -> &'static str {
        match self {
            BandKind::Ci95 => "mean and 95% interval across seeds",
            BandKind::Se => "mean ± one standard error across seeds",
            BandKind::None => "mean across seeds",
        }
    }
}

/// The scale on which a quantity's mean and band across seeds are computed, so that the band
/// stays in the quantity's domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Scale {
    /// Any real value (J, v): arithmetic mean and Student t-interval.
    #[default]
    Linear,
    /// Positive values (σ): mean and t-interval of log y, transformed back by exp, i.e. the
    /// geometric mean with a band that is positive and asymmetric. log σ = w is the
    /// parameter the algorithm moves, so this is the interval on the quantity it steps.
    Log,
    /// Values with a floor that a symmetric band would cross (the budget, which cannot fall
    /// below what the accounting allows): arithmetic mean and percentile bootstrap interval,
    /// resampling the seeds with replacement ([`BOOTSTRAP_RESAMPLES`] resamples, the seeded
    /// portable generator of [`bootstrap_indices`]). A mean of resampled seeds lies between
    /// the smallest and the largest value of the seeds, so the band never goes below the
    /// lowest value any seed reached, whatever the floor of the quantity.
    Bootstrap,
}

/// Fewest seeds for which a band is worth drawing without a warning: with two seeds the 95%
/// t-interval uses t(0.975, 1) = 12.7 and the standard error rests on one degree of freedom.
pub const MIN_BAND_SEEDS: usize = 3;

/// Resamples of every bootstrap (percentile bands and the tolerance of Table 5.1).
pub const BOOTSTRAP_RESAMPLES: usize = 2000;

/// Seed of the bootstrap's generator (Xoshiro256++), fixed so that figures and tables are
/// the same bit for bit on every machine.
pub const BOOTSTRAP_SEED: u64 = 0x5e96_b007;

/// Lower and upper ends of a confidence band, point by point.
pub type Band = (Vec<f64>, Vec<f64>);

/// One curve: a mean over seeds and, with two seeds or more, its 95% confidence band.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label (`_{…}` marks a subscript).
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
    /// Caption (`_{…}` marks a subscript).
    pub title: String,
    /// Abscissa label.
    pub x_label: String,
    /// Ordinate label.
    pub y_label: String,
    /// Curves.
    pub series: Vec<Series>,
    /// Dashed horizontal reference lines (label, value); each label gets its own colour and
    /// dash pattern.
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

/// Size of the text and resolution of a drawn figure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    /// Size of the tick labels in points (1/72 inch); every other text is scaled with it
    /// (titles 1.8 times, captions 1.3 times). Default 12, domain [4, 72].
    pub font_size: f64,
    /// Resolution in dots per inch: a PNG has dpi/100 times the pixels of the default
    /// figure in each direction, with every line and text scaled alike (an SVG is scaled
    /// the same way). Default 100, domain [50, 1200].
    pub dpi: u32,
}

impl Default for Style {
    fn default() -> Style {
        Style {
            font_size: 12.0,
            dpi: 100,
        }
    }
}

impl Style {
    /// Checks the domains of the font size and resolution.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the option out of its domain.
    pub fn validate(&self) -> Result<()> {
        if !(self.font_size.is_finite() && (4.0..=72.0).contains(&self.font_size)) {
            return Err(Error::invalid(format!(
                "--font-size {} must be between 4 and 72 points",
                self.font_size
            )));
        }
        if !(50..=1200).contains(&self.dpi) {
            return Err(Error::invalid(format!(
                "--dpi {} must be between 50 and 1200",
                self.dpi
            )));
        }
        Ok(())
    }

    /// Pixels per pixel of the default figure.
    fn px(&self) -> f64 {
        f64::from(self.dpi) / 100.0
    }

    /// A length of `base` pixels of the default figure, scaled to this resolution.
    fn len(&self, base: f64) -> u32 {
        (base * self.px()).round().max(1.0) as u32
    }

    /// The pixel size of a text of `base` points at the default font size, scaled to this
    /// font size and resolution.
    fn text(&self, base: f64) -> f64 {
        base * self.font_size / 12.0 * self.px()
    }
}

/// Mean and band of kind `kind` across seeds of equally long curves, point by point (the
/// curves are cut to the shortest), on the linear scale ([`Scale::Linear`]).
///
/// # Formula
/// ```text
/// m = mean(y),  s = sample sd(y),  K seeds (band only for K ≥ 2)
/// Ci95: m ± t(0.975, K − 1) · s / √K        Se: m ± s / √K        None: no band
/// ```
pub fn mean_band(curves: &[Vec<f64>], kind: BandKind) -> (Vec<f64>, Option<Band>) {
    mean_band_on(curves, kind, Scale::Linear)
}

/// Mean and band of kind `kind` across seeds of equally long curves, point by point (the
/// curves are cut to the shortest), on `scale`:
///
/// ```text
/// Linear:    m = mean(y),           band m ± h(y)            (h as in mean_band)
/// Log:       m = exp(mean(log y)),  band exp(mean(log y) ± h(log y))   (y > 0; else NaN)
/// Bootstrap: m = mean(y),           band the (q, 1 − q) percentiles of the means of
///            BOOTSTRAP_RESAMPLES resamples of the K seeds, q = 0.025 (Ci95) or
///            0.158655 (Se, one standard deviation of a normal)
/// ```
/// A point where a value is not finite (or not positive on the log scale) has a NaN mean and
/// band, which are not drawn.
pub fn mean_band_on(curves: &[Vec<f64>], kind: BandKind, scale: Scale) -> (Vec<f64>, Option<Band>) {
    let len = curves.iter().map(Vec::len).min().unwrap_or(0);
    let k = curves.len();
    let resamples = (scale == Scale::Bootstrap && k >= 2 && kind != BandKind::None)
        .then(|| bootstrap_indices(k, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED));
    let mut mean = Vec::with_capacity(len);
    let mut lo = Vec::with_capacity(len);
    let mut hi = Vec::with_capacity(len);
    let mut means = vec![0.0; BOOTSTRAP_RESAMPLES];
    for i in 0..len {
        let ys: Vec<f64> = curves.iter().map(|c| c[i]).collect();
        let (m, l, h) = match scale {
            Scale::Log => {
                let logs: Vec<f64> = ys
                    .iter()
                    .map(|&y| if y > 0.0 { y.ln() } else { f64::NAN })
                    .collect();
                let (m, h) = spread(&logs, kind);
                (m.exp(), (m - h).exp(), (m + h).exp())
            }
            Scale::Linear => {
                let (m, h) = spread(&ys, kind);
                (m, m - h, m + h)
            }
            Scale::Bootstrap => {
                let m = ys.iter().sum::<f64>() / k as f64;
                match &resamples {
                    Some(idx) => {
                        for (slot, draw) in means.iter_mut().zip(idx) {
                            *slot = draw.iter().map(|&j| ys[j]).sum::<f64>() / k as f64;
                        }
                        let q = if kind == BandKind::Se {
                            0.158_655_253_931_457
                        } else {
                            0.025
                        };
                        (
                            m,
                            percentile(&mut means, q),
                            percentile(&mut means, 1.0 - q),
                        )
                    }
                    None => (m, m, m),
                }
            }
        };
        mean.push(m);
        lo.push(l);
        hi.push(h);
    }
    let band = (k >= 2 && kind != BandKind::None).then_some((lo, hi));
    (mean, band)
}

/// Mean of `ys` and the half-width of a band of kind `kind` (0 when there is none).
fn spread(ys: &[f64], kind: BandKind) -> (f64, f64) {
    let (m, h) = match kind {
        BandKind::Se => mean_se(ys),
        _ => mean_halfwidth(ys),
    };
    (
        m,
        if kind == BandKind::None {
            0.0
        } else {
            h.unwrap_or(0.0)
        },
    )
}

/// The `q`-quantile of `xs` (0 ≤ q ≤ 1) by the nearest-rank rule: the ⌈q·n⌉-th smallest value
/// (the smallest for q = 0). `xs` is reordered; NaN when it holds a NaN or is empty.
pub fn percentile(xs: &mut [f64], q: f64) -> f64 {
    if xs.is_empty() || xs.iter().any(|x| x.is_nan()) || !(0.0..=1.0).contains(&q) {
        return f64::NAN;
    }
    let rank = ((q * xs.len() as f64).ceil() as usize).clamp(1, xs.len());
    let (_, x, _) = xs.select_nth_unstable_by(rank - 1, f64::total_cmp);
    *x
}

/// `resamples` bootstrap resamples of `k` seeds: each a list of `k` indices drawn uniformly
/// with replacement from 0..k, by Xoshiro256++ seeded with `seed` (the same on every machine
/// and for every thread count). Empty for k = 0.
pub fn bootstrap_indices(k: usize, resamples: usize, seed: u64) -> Vec<Vec<usize>> {
    if k == 0 {
        return Vec::new();
    }
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..resamples)
        .map(|_| (0..k).map(|_| rng.random_range(0..k)).collect())
        .collect()
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

/// The pieces of a label: plain runs and the subscripts written `_{…}`, in order, each with
/// whether it is a subscript. Text without `_{` is one plain piece (an underscore alone is
/// kept as it is, so names such as `my_run` are not mangled).
fn pieces(label: &str) -> Vec<(&str, bool)> {
    let mut out = Vec::new();
    let mut rest = label;
    while let Some(at) = rest.find("_{") {
        let Some(close) = rest[at + 2..].find('}') else {
            break;
        };
        if at > 0 {
            out.push((&rest[..at], false));
        }
        out.push((&rest[at + 2..at + 2 + close], true));
        rest = &rest[at + 3 + close..];
    }
    if !rest.is_empty() {
        out.push((rest, false));
    }
    out
}

/// The label as plain text, its subscripts written inline (for widths and file formats
/// without rich text).
pub fn plain_label(label: &str) -> String {
    pieces(label).into_iter().map(|(s, _)| s).collect()
}

/// Subscripts are drawn at this fraction of the text size, lowered by [`SUB_DROP`] of it.
const SUB_SIZE: f64 = 0.7;
const SUB_DROP: f64 = 0.35;

/// Draws `label` with its subscripts, text of `size` pixels, its top left corner at `at`;
/// returns the width drawn.
fn draw_rich<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    label: &str,
    at: (i32, i32),
    size: f64,
    colour: &RGBColor,
) -> Result<i32, String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut x = at.0;
    for (text, sub) in pieces(label) {
        let (s, dy) = if sub {
            (size * SUB_SIZE, (size * SUB_DROP).round() as i32)
        } else {
            (size, 0)
        };
        let font = (FAMILY, s).into_font().color(colour);
        area.draw(&Text::new(text.to_owned(), (x, at.1 + dy), font.clone()))
            .map_err(e)?;
        let (w, _) = area.estimate_text_size(text, &font).map_err(e)?;
        x += w as i32;
    }
    Ok(x - at.0)
}

/// Width in pixels of `label` drawn by [`draw_rich`] at `size`.
fn rich_width<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    label: &str,
    size: f64,
) -> Result<i32, String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut w = 0;
    for (text, sub) in pieces(label) {
        let s = if sub { size * SUB_SIZE } else { size };
        let (tw, _) = area
            .estimate_text_size(text, &TextStyle::from((FAMILY, s).into_font()))
            .map_err(e)?;
        w += tw as i32;
    }
    Ok(w)
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

/// Ticks of an axis over the data range [`x0`, `x1`] (x0 < x1): multiples of a round step
/// (1, 2 or 5 times a power of ten) giving at most 7 ticks, from the last multiple at or
/// below x0 to the first at or above x1, so that the last tick covers the data (data to
/// 1,999 or 2,000 end on a 2,000 tick, not 1,500). Returns the axis range and the ticks.
fn ticks(x0: f64, x1: f64) -> ((f64, f64), Vec<f64>) {
    let span = x1 - x0;
    if !(span.is_finite() && span > 0.0) {
        return ((x0, x1), vec![x0]);
    }
    let mut step = 10f64.powf((span / 6.0).log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0, 20.0] {
        let s = step * m;
        if ((x1 / s).ceil() - (x0 / s).floor()) <= 6.0 {
            step = s;
            break;
        }
    }
    let a = (x0 / step).floor();
    let b = (x1 / step).ceil();
    let n = (b - a).round() as i64;
    let ticks = (0..=n).map(|i| (a + i as f64) * step).collect();
    (((a * step), (b * step)), ticks)
}

/// A linear axis whose ticks are given (see [`ticks`]).
struct TickedAxis {
    inner: RangedCoordf64,
    ticks: Vec<f64>,
}

impl Ranged for TickedAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }
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
    /// Width and height of one panel.
    panel_w: u32,
    panel_h: u32,
    /// Left edge of the legend column, right of every panel.
    legend_x: u32,
}

/// Panel size, title band and legend row height at 100 dpi and 12 pt.
const PANEL_W: u32 = 520;
const PANEL_H: u32 = 400;
const TITLE_H: u32 = 60;
const LEGEND_ROW: u32 = 20;

/// One entry of the legend: a label, its colour and, for a reference line, its dash length
/// and gap (at 100 dpi).
#[derive(Debug, Clone, PartialEq)]
struct Entry {
    label: String,
    colour: RGBColor,
    dash: Option<(u32, u32)>,
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
/// every reference line once, each with its own colour and dash pattern. A label keeps its
/// colour in every panel.
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
            dash: None,
        })
        .collect();
    let mut references = 0;
    for (l, _) in fig.panels.iter().flat_map(|p| &p.hlines) {
        if !out.iter().any(|e| e.dash.is_some() && e.label == *l) {
            let (colour, dash, gap) = REFERENCE_STYLES[references % REFERENCE_STYLES.len()];
            // Past the listed styles, lengthen the dash so that no two entries coincide.
            let longer = 4 * (references / REFERENCE_STYLES.len()) as u32;
            references += 1;
            out.push(Entry {
                label: l.clone(),
                colour,
                dash: Some((dash + longer, gap)),
            });
        }
    }
    out
}

fn layout(fig: &Figure, style: &Style) -> Layout {
    let n = shown(fig).len().max(1) as u32;
    let columns = (fig.columns.max(1) as u32).min(n);
    let rows = n.div_ceil(columns);
    let entries = legend(fig);
    let chars = entries
        .iter()
        .map(|e| plain_label(&e.label).chars().count())
        .max()
        .unwrap_or(0) as f64;
    let fs = style.font_size / 12.0;
    let panel_w = style.len(f64::from(PANEL_W) * fs.max(1.0));
    let panel_h = style.len(f64::from(PANEL_H) * fs.max(1.0));
    let legend_w = style.len(50.0 + 7.0 * fs * chars.max(8.0));
    let title_h = style.len(f64::from(TITLE_H) * fs);
    let legend_h =
        title_h + style.len(20.0) + style.len(f64::from(LEGEND_ROW) * fs) * entries.len() as u32;
    Layout {
        width: panel_w * columns + legend_w,
        height: (title_h + panel_h * rows).max(legend_h),
        rows,
        columns,
        panel_w,
        panel_h,
        legend_x: panel_w * columns,
    }
}

/// How curves are stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pen {
    /// One polyline of width 2 (SVG: the viewer joins the segments).
    Stroke,
    /// Polylines of width 1, offset by a pixel right and up (bitmaps: plotters fills a
    /// wider polyline as one polygon whose joins at sharp turns spike far beyond the data).
    Pixels,
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    pen: Pen,
    style: &Style,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let lay = layout(fig, style);
    root.fill(&WHITE).map_err(e)?;
    let area = root
        .titled(
            &plain_label(&fig.title),
            (FAMILY, style.text(22.0)).into_font(),
        )
        .map_err(e)?;
    let (panels_area, legend_area) = area.split_horizontally(lay.legend_x);
    let panels_area = panels_area.shrink((0, 0), (lay.legend_x, lay.panel_h * lay.rows));
    let entries = legend(fig);
    let cells = panels_area.split_evenly((lay.rows as usize, lay.columns as usize));
    for (cell, panel) in cells.iter().zip(shown(fig)) {
        draw_panel(cell, panel, &entries, pen, style)?;
    }
    draw_legend(&legend_area, &entries, style)?;
    root.present().map_err(e)
}

/// The points of a dashed segment from `x0` to `x1` at height `y`: dashes of `dash` pixels
/// separated by `gap`.
fn dashes(x0: i32, x1: i32, y: i32, (dash, gap): (i32, i32)) -> Vec<[(i32, i32); 2]> {
    let mut out = Vec::new();
    let mut x = x0;
    while x < x1 {
        out.push([(x, y), ((x + dash).min(x1), y)]);
        x += dash + gap;
    }
    out
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    style: &Style,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let size = style.text(13.0);
    let row = style.len(f64::from(LEGEND_ROW) * style.font_size / 12.0) as i32;
    let len = |x: f64| style.len(x) as i32;
    for (i, entry) in entries.iter().enumerate() {
        let y = len(30.0) + row * i as i32;
        match entry.dash {
            Some((dash, gap)) => {
                let pattern = (len(f64::from(dash)), len(f64::from(gap)));
                for seg in dashes(len(8.0), len(40.0), y, pattern) {
                    area.draw(&PathElement::new(
                        seg.to_vec(),
                        entry.colour.stroke_width(style.len(1.5)),
                    ))
                    .map_err(e)?;
                }
            }
            None => {
                area.draw(&PathElement::new(
                    vec![(len(10.0), y), (len(38.0), y)],
                    entry.colour.stroke_width(style.len(3.0)),
                ))
                .map_err(e)?;
            }
        }
        draw_rich(
            area,
            &entry.label,
            (len(46.0), y - (size / 2.0).round() as i32),
            size,
            &BLACK,
        )?;
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

/// The chart of one panel: the ticked abscissa against a linear ordinate.
type PanelChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<TickedAxis, RangedCoordf64>>;

fn draw_panel<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    panel: &Panel,
    entries: &[Entry],
    pen: Pen,
    style: &Style,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let (x0, x1, y0, y1) = range(panel);
    let ((x0, x1), x_ticks) = ticks(x0, x1);
    let chart_area = draw_caption(cell, &panel.title, style)?;
    let mut chart = ChartBuilder::on(&chart_area)
        .margin(style.len(10.0))
        .x_label_area_size(style.len(40.0 * style.font_size / 12.0))
        .y_label_area_size(style.len(70.0 * style.font_size / 12.0))
        .build_cartesian_2d(
            TickedAxis {
                inner: (x0..x1).into(),
                ticks: x_ticks,
            },
            y0..y1,
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .label_style((FAMILY, style.text(12.0)))
        .axis_desc_style((FAMILY, style.text(13.0)))
        .y_labels(6)
        .x_label_formatter(&|v| tick(*v, x1 - x0))
        .y_label_formatter(&|v| tick(*v, y1 - y0))
        .light_line_style(WHITE)
        .draw()
        .map_err(e)?;
    for s in &panel.series {
        let colour = entries
            .iter()
            .find(|en| en.dash.is_none() && en.label == s.label)
            .map_or(BLACK, |en| en.colour);
        draw_curve(&mut chart, s, colour, pen, style, (x1 - x0, y1 - y0))?;
    }
    for (label, y) in &panel.hlines {
        let Some(entry) = entries
            .iter()
            .find(|en| en.dash.is_some() && en.label == *label)
        else {
            continue;
        };
        let (dash, gap) = entry.dash.unwrap_or((6, 4));
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0, *y), (x1, *y)],
                style.len(f64::from(dash)),
                style.len(f64::from(gap)),
                entry.colour.stroke_width(style.len(1.5)),
            ))
            .map_err(e)?;
    }
    Ok(())
}

/// Draws the caption `title` (with its subscripts) centred at the top of `cell`, and returns
/// the area below it for the chart.
fn draw_caption<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    title: &str,
    style: &Style,
) -> Result<DrawingArea<DB, Shift>, String> {
    let caption = style.text(16.0);
    let caption_h = (caption * 1.6).round() as u32;
    let (top, chart_area) = cell.split_vertically(caption_h);
    let width = rich_width(&top, title, caption)?;
    let (w, _) = top.dim_in_pixel();
    let left = ((w as i32 - width) / 2).max(0);
    draw_rich(
        &top,
        title,
        (left, (caption * 0.4).round() as i32),
        caption,
        &BLACK,
    )?;
    Ok(chart_area)
}

/// Draws the band and the mean of the series `s` in `colour` with `pen`; `spans` are the
/// widths of the abscissa and ordinate ranges (the offsets of [`Pen::Pixels`] are pixels).
fn draw_curve<DB: DrawingBackend>(
    chart: &mut PanelChart<'_, DB>,
    s: &Series,
    colour: RGBColor,
    pen: Pen,
    style: &Style,
    (x_span, y_span): (f64, f64),
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
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
                .draw_series(LineSeries::new(points, colour.stroke_width(style.len(2.0))))
                .map_err(e)?;
        }
        Pen::Pixels => {
            let (w, h) = chart.plotting_area().dim_in_pixel();
            let dx = x_span / f64::from(w.max(1));
            let dy = y_span / f64::from(h.max(1));
            let thick = style.len(2.0) as i32 - 1;
            let offsets = (0..=thick).flat_map(|i| {
                let i = f64::from(i);
                [(i * dx, 0.0), (0.0, i * dy)]
            });
            let mut seen = Vec::new();
            for (ox, oy) in offsets {
                if seen.contains(&(ox, oy)) {
                    continue;
                }
                seen.push((ox, oy));
                let shifted = points.iter().map(|&(x, y)| (x + ox, y + oy));
                chart
                    .draw_series(LineSeries::new(shifted, colour.stroke_width(1)))
                    .map_err(e)?;
            }
        }
    }
    Ok(())
}

fn size(fig: &Figure, style: &Style) -> (u32, u32) {
    let lay = layout(fig, style);
    (lay.width, lay.height)
}

/// Writes `fig` to `path` in `style`, as PNG or SVG by the extension, atomically (rendered
/// to a temporary file in the same folder, then renamed).
///
/// # Errors
/// [`Error::Invalid`] for another extension or a style out of its domain; [`Error::Failed`]
/// when rendering or writing fails.
pub fn save(fig: &Figure, path: &Path, style: &Style) -> Result<()> {
    style.validate()?;
    register_font()?;
    let fail = |e: String| Error::failed(format!("cannot draw {}: {e}", path.display()));
    match path.extension().and_then(|e| e.to_str()) {
        Some("svg") => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size(fig, style)).into_drawing_area();
                draw(&root, fig, Pen::Stroke, style).map_err(fail)?;
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
                .map_err(|e| {
                    Error::failed_from(format_args!("cannot write in {}", dir.display()), e)
                })?;
            {
                let root = BitMapBackend::new(tmp.path(), size(fig, style)).into_drawing_area();
                draw(&root, fig, Pen::Pixels, style).map_err(fail)?;
            }
            tmp.persist(path).map_err(|e| {
                Error::failed_from(format_args!("cannot write {}", path.display()), e.error)
            })?;
            Ok(())
        }
        _ => Err(Error::invalid(format!(
            "{}: figures are written as .png or .svg",
            path.display()
        ))),
    }
}

/// Writes `fig` as `<stem>.png` and `<stem>.svg` in `dir` in `style`; returns the two paths.
///
/// # Errors
/// As [`save`].
pub fn save_both(fig: &Figure, dir: &Path, stem: &str, style: &Style) -> Result<[PathBuf; 2]> {
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    save(fig, &png, style)?;
    save(fig, &svg, style)?;
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
    fn sigma_bands_are_intervals_on_log_sigma() {
        // Two seeds with σ = 0.001 and 0.021: the 95% t-interval on σ, 0.011 ± 12.7 · 0.01,
        // reaches −0.116. On log σ: logs −6.9078 and −3.8632, mean −5.3855 (geometric mean
        // √(0.001 · 0.021) = 0.0045826), s = 2.1528, half-width 12.706 · 2.1528/√2 = 19.342:
        // the band is exp(−5.3855 ± 19.342), positive on both ends.
        let curves = vec![vec![0.001, 0.5], vec![0.021, 0.5]];
        let (lo_lin, _) = mean_band(&curves, BandKind::Ci95).1.expect("two seeds");
        assert!(lo_lin[0] < -0.1, "{lo_lin:?}");
        let (mean, band) = mean_band_on(&curves, BandKind::Ci95, Scale::Log);
        let (lo, hi) = band.expect("two seeds");
        let g = (0.001f64 * 0.021).sqrt();
        assert!((mean[0] - g).abs() < 1e-15, "{mean:?}");
        let t1 = 12.706_204_736_174_7;
        let s = (0.021f64.ln() - 0.001f64.ln()).abs() / 2f64.sqrt();
        let h = t1 * s / 2f64.sqrt();
        assert!((lo[0] / (g.ln() - h).exp() - 1.0).abs() < 1e-9, "{lo:?}");
        assert!((hi[0] / (g.ln() + h).exp() - 1.0).abs() < 1e-9, "{hi:?}");
        assert!(lo.iter().all(|&y| y > 0.0));
        // Equal values: no spread, the band collapses on the value.
        assert!((mean[1] - 0.5).abs() < 1e-15 && (lo[1] - 0.5).abs() < 1e-15);
    }

    #[test]
    fn bootstrap_bands_stay_within_the_seeds() {
        // Budgets of five seeds, four at 0 and one far below: the t-interval's lower end
        // (mean −20, s = 44.72, t(0.975, 4) = 2.7764: −20 − 55.5 = −75.5) is below every
        // seed's value; a percentile bootstrap interval of the mean lies between the smallest
        // and the largest mean of a resample, here in [−100, 0].
        let curves: Vec<Vec<f64>> = [0.0, 0.0, 0.0, 0.0, -100.0]
            .iter()
            .map(|&b| vec![b])
            .collect();
        let (lo_t, _) = mean_band(&curves, BandKind::Ci95).1.expect("band");
        assert!(lo_t[0] < -75.0, "{lo_t:?}");
        let (mean, band) = mean_band_on(&curves, BandKind::Ci95, Scale::Bootstrap);
        let (lo, hi) = band.expect("band");
        assert_eq!(mean, vec![-20.0]);
        assert!(lo[0] >= -100.0 && hi[0] <= 0.0, "{lo:?} {hi:?}");
        // The number of resampled −100s is Binomial(5, 1/5): the mean is −20·j with
        // P(j = 0) = 0.32768 > 2.5%, so the upper 97.5% percentile is 0; P(j ≥ 3) =
        // 0.05792 > 2.5% and P(j ≥ 4) = 0.00672, so the lower 2.5% percentile is −60 (with
        // 2,000 resamples the estimated tails are within 4.4 standard errors, 0.026 and
        // 0.0081, of these).
        assert_eq!(hi[0], 0.0);
        assert_eq!(lo[0], -60.0);
        // Same seed, same band.
        assert_eq!(
            mean_band_on(&curves, BandKind::Ci95, Scale::Bootstrap).1,
            Some((lo, hi))
        );
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
        save(&fig, &path, &Style::default()).expect("drawn");
        let svg = std::fs::read_to_string(&path).expect("read");
        assert!(svg.len() < 1_000_000, "{} bytes", svg.len());
        let lay = layout(&fig, &Style::default());
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
        let style = Style::default();
        let (w, h) = size(&fig, &style);
        let mut buf = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            draw(&root, &fig, Pen::Pixels, &style).expect("drawn");
        }
        // Left of the legend (whose sample line has the series' colour).
        let curve = rows_with(
            &buf,
            w as usize,
            layout(&fig, &style).legend_x as usize,
            PALETTE[0],
        );
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
        let lay = layout(&fig, &Style::default());
        assert_eq!((lay.rows, lay.columns), (1, 3));
    }

    /// A figure with the three reference lines of Figure 5.2 (v*, J_B, B = 0) in three panels
    /// and math labels in its captions and legend.
    fn reference_figure() -> Figure {
        let series = |label: &str| Series {
            label: label.into(),
            x: (0..2000).map(f64::from).collect(),
            mean: (0..2000).map(|i| f64::from(i).sqrt()).collect(),
            band: None,
        };
        let panel = |title: &str, hline: &str| Panel {
            title: title.into(),
            x_label: "iteration".into(),
            y_label: "J".into(),
            series: vec![series("SEPG-MI"), series("J(θ_{T})")],
            hlines: vec![(hline.into(), 1.0)],
        };
        Figure {
            title: "references".into(),
            panels: vec![
                panel("(c) mean parameter v", "v*"),
                panel("(d) mean of (J_{E} + J_{T})/2", "J_{B} = J(θ⁰)"),
                panel("(f) budget", "B = 0"),
            ],
            columns: 3,
        }
    }

    #[test]
    fn reference_lines_have_distinct_legend_entries() {
        let entries = legend(&reference_figure());
        let refs: Vec<&Entry> = entries.iter().filter(|e| e.dash.is_some()).collect();
        assert_eq!(refs.len(), 3);
        for (i, a) in refs.iter().enumerate() {
            assert!(!PALETTE.contains(&a.colour), "{a:?}");
            for b in &refs[..i] {
                assert_ne!(a.colour, b.colour, "{a:?} {b:?}");
                assert_ne!(a.dash, b.dash, "{a:?} {b:?}");
            }
        }
        // Many reference lines: still pairwise distinct.
        let mut fig = reference_figure();
        fig.panels[0].hlines = (0..7).map(|i| (format!("r{i}"), 0.0)).collect();
        let entries = legend(&fig);
        for (i, a) in entries.iter().enumerate() {
            for b in &entries[..i] {
                assert!((a.colour, a.dash) != (b.colour, b.dash), "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn subscripts_are_parsed_and_drawn_without_markup() {
        assert_eq!(pieces("J_{E}"), vec![("J", false), ("E", true)]);
        assert_eq!(
            pieces("(J_{E} + J_{T})/2"),
            vec![
                ("(J", false),
                ("E", true),
                (" + J", false),
                ("T", true),
                (")/2", false)
            ]
        );
        assert_eq!(pieces("my_run"), vec![("my_run", false)]);
        assert_eq!(plain_label("θ_{E}"), "θE");
        // In the SVG, no text element shows the markup or a raw underscore, and the
        // subscript is a text element of its own, smaller than the text it follows.
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("f.svg");
        save(&reference_figure(), &path, &Style::default()).expect("drawn");
        let svg = std::fs::read_to_string(&path).expect("read");
        assert!(!svg.contains("_{") && !svg.contains("J_"), "markup drawn");
        assert!(svg.contains(">\n(d) mean of (J\n</text>"), "caption split");
        assert!(svg.contains(">\nE\n</text>"), "subscript drawn");
    }

    #[test]
    fn the_last_x_tick_covers_the_data() {
        // Iterations 0..1999: the ticks end at 2,000, not 1,500.
        let ((a, b), t) = ticks(0.0, 1999.0);
        assert_eq!((a, b), (0.0, 2000.0));
        assert_eq!(t, vec![0.0, 500.0, 1000.0, 1500.0, 2000.0]);
        for (x0, x1) in [
            (0.0, 9999.0),
            (3.0, 17.0),
            (-0.7, 0.1),
            (0.0, 2.4e7),
            (5.0, 5.5),
        ] {
            let ((a, b), t) = ticks(x0, x1);
            assert!(a <= x0 && b >= x1, "{x0} {x1}: {a} {b}");
            assert_eq!((t[0], *t.last().expect("ticks")), (a, b));
            assert!(t.len() >= 2 && t.len() <= 7, "{x0} {x1}: {t:?}");
        }
        // Drawn: the 2,000 tick label is in the SVG.
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("f.svg");
        save(&reference_figure(), &path, &Style::default()).expect("drawn");
        let svg = std::fs::read_to_string(&path).expect("read");
        assert!(svg.contains(">\n2000\n</text>"), "no 2000 tick");
    }

    #[test]
    fn dpi_scales_the_image_and_font_size_the_text() {
        let fig = reference_figure();
        let base = size(&fig, &Style::default());
        let double = size(
            &fig,
            &Style {
                dpi: 200,
                ..Style::default()
            },
        );
        assert_eq!(double, (2 * base.0, 2 * base.1));
        let big = Style {
            font_size: 24.0,
            ..Style::default()
        };
        assert_eq!(big.text(12.0), 24.0);
        assert!(size(&fig, &big).0 > base.0);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("f.png");
        save(
            &fig,
            &path,
            &Style {
                dpi: 150,
                ..Style::default()
            },
        )
        .expect("drawn");
        let png = std::fs::read(&path).expect("read");
        // The PNG header's IHDR chunk: width and height, big-endian, at bytes 16..24.
        let w = u32::from_be_bytes([png[16], png[17], png[18], png[19]]);
        let h = u32::from_be_bytes([png[20], png[21], png[22], png[23]]);
        let expect = size(
            &fig,
            &Style {
                dpi: 150,
                ..Style::default()
            },
        );
        assert_eq!((w, h), expect);
        assert!((w as f64 / base.0 as f64 - 1.5).abs() < 0.01);
        for bad in [
            Style {
                dpi: 10,
                ..Style::default()
            },
            Style {
                font_size: f64::NAN,
                ..Style::default()
            },
        ] {
            assert!(save(&fig, &path, &bad).is_err());
        }
    }
}
