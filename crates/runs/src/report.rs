//! Reports made from finished runs: Table 5.1 (markdown and CSV, side by side with the
//! published values) and Figures 5.1–5.4 of a reproduction (PNG and SVG, 95% bands across
//! seeds), and the plots of any run or sweep folder.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use sepg_algo::core::options::Accounting;

use crate::figure::{
    self, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED, BandKind, Figure, MIN_BAND_SEEDS, Panel, Scale,
    Series, Style, bootstrap_indices, mean_band_on, mean_halfwidth,
};
use crate::folder::{CONFIG_FILE, Log, SUMMARY_FILE, Summary, load_resolved, read_summary};
use crate::logcheck::{LogCheck, validate_log};
use crate::reproduce::{Experiment, ReproduceOptions, Setting, TABLE_VARIANTS};
use crate::spec::EnvName;
use crate::sweep::{SWEEP_FILE, Seeds, SweepFile};

/// Table 5.1 of the thesis (Sec 5.1.2, "Upper bound confidence intervals at
/// 95% of |v − v*| after 10,000 iterations"), copied as published: for σ⁰ = 0.1, 0.2, 0.5,
/// 1.0, the columns in [`TABLE_VARIANTS`] order (Adam 1e-4, 1e-5, 1e-6; constant step 1e-4,
/// 1e-5, 1e-6; MI; LB-I; LB-II; LV; ZV). Values to compare against, not expectations.
pub const THESIS_TABLE_5_1: [(f64, [f64; 11]); 4] = [
    (
        0.1,
        [
            0.126, 0.432, 0.506, 0.132, 0.026, 0.228, 0.515, 0.510, 0.368, 0.429, 0.435,
        ],
    ),
    (
        0.2,
        [
            0.08, 0.429, 0.506, 0.124, 0.018, 0.201, 0.515, 0.494, 0.039, 0.028, 0.056,
        ],
    ),
    (
        0.5,
        [
            0.061, 0.428, 0.506, 0.122, 0.012, 0.125, 0.511, 0.29, 0.009, 0.01, 0.006,
        ],
    ),
    (
        1.0,
        [
            0.046, 0.422, 0.505, 0.122, 0.011, 0.069, 0.497, 0.01, 0.021, 0.021, 0.028,
        ],
    ),
];

/// The cells of [`THESIS_TABLE_5_1`] as the thesis prints them (same order), whose digits
/// set the rounding part of each cell's tolerance ("0.510" has three, "0.29" two).
pub const THESIS_TABLE_5_1_PRINTED: [[&str; 11]; 4] = [
    [
        "0.126", "0.432", "0.506", "0.132", "0.026", "0.228", "0.515", "0.510", "0.368", "0.429",
        "0.435",
    ],
    [
        "0.08", "0.429", "0.506", "0.124", "0.018", "0.201", "0.515", "0.494", "0.039", "0.028",
        "0.056",
    ],
    [
        "0.061", "0.428", "0.506", "0.122", "0.012", "0.125", "0.511", "0.29", "0.009", "0.01",
        "0.006",
    ],
    [
        "0.046", "0.422", "0.505", "0.122", "0.011", "0.069", "0.497", "0.01", "0.021", "0.021",
        "0.028",
    ],
];

/// A finished run of the sweep: its entry, summary and log.
struct Loaded {
    preset: EnvName,
    variant: String,
    sigma0: f64,
    summary: Summary,
    log: Log,
}

fn load(dir: &Path, file: &SweepFile) -> Result<Vec<Loaded>> {
    file.runs
        .iter()
        .map(|r| {
            let run_dir = dir.join(&r.dir);
            let text = std::fs::read_to_string(run_dir.join(SUMMARY_FILE))
                .map_err(|e| Error::failed_from(run_dir.display(), e))?;
            let summary: Summary = serde_json::from_str(&text)
                .map_err(|e| Error::failed_from(run_dir.display(), e))?;
            Ok(Loaded {
                preset: r.preset,
                variant: r.variant.clone(),
                sigma0: r.sigma0,
                summary,
                log: validated_log(&run_dir)?.0,
            })
        })
        .collect()
}

fn seed_count(seeds: &Seeds) -> u64 {
    match seeds {
        Seeds::Count(n) => *n,
        Seeds::List(v) => v.len() as u64,
    }
}

/// A CSV cell: shortest round-trip decimal, empty when undefined.
fn csv_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:?}")
    } else {
        String::new()
    }
}

fn fmt3(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "—".into()
    }
}

/// One cell of Table 5.1 compared with its published value, as docs/REPRODUCTION.md ("When a
/// measured cell reproduces a published one") defines it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellComparison {
    /// Seeds K of the cell.
    pub seeds: usize,
    /// Mean of |v − v*| over the seeds.
    pub mean: f64,
    /// Sample standard deviation over the seeds (`None` below two seeds).
    pub sd: Option<f64>,
    /// U = mean + t(0.975, K − 1)·s/√K, the 95% upper confidence bound (`None` below two
    /// seeds: one seed gives no spread, and U is not the mean).
    pub ucb: Option<f64>,
    /// Tolerance 0.5·10^(−digits of P) + 1.96·√2·SD_K, SD_K the bootstrap standard
    /// deviation of U over [`BOOTSTRAP_RESAMPLES`] resamples of the K seeds (`None` below
    /// two seeds).
    pub tolerance: Option<f64>,
    /// Whether |U − P| ≤ tolerance (`None` below two seeds).
    pub reproduces: Option<bool>,
}

/// Half a unit of the last printed digit of the published value `printed` (0.0005 for
/// "0.021" and "0.510", 0.005 for "0.01").
fn rounding(printed: &str) -> f64 {
    let digits = printed.split_once('.').map_or(0, |(_, f)| f.len());
    0.5 * 10f64.powi(-(digits as i32))
}

/// U = mean + t(0.975, K − 1)·s/√K of `ys` (K ≥ 2), or `None`.
fn upper_bound(ys: &[f64]) -> Option<f64> {
    let (mean, half) = mean_halfwidth(ys);
    half.map(|h| mean + h)
}

/// The comparison of the errors |v − v*| of one cell's seeds with the published value `p`,
/// printed as `printed` (its digits set the rounding; see [`CellComparison`]); the
/// bootstrap uses Xoshiro256++ seeded with [`BOOTSTRAP_SEED`], so the tolerance is the same
/// on every machine.
pub fn compare_cell(errors: &[f64], p: f64, printed: &str) -> CellComparison {
    let k = errors.len();
    let (mean, _) = mean_halfwidth(errors);
    let ucb = upper_bound(errors);
    let sd = (k >= 2).then(|| {
        let ss: f64 = errors.iter().map(|e| (e - mean) * (e - mean)).sum();
        (ss / (k - 1) as f64).sqrt()
    });
    let tolerance = ucb.map(|_| {
        let us: Vec<f64> = bootstrap_indices(k, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED)
            .iter()
            .map(|draw| {
                let ys: Vec<f64> = draw.iter().map(|&j| errors[j]).collect();
                upper_bound(&ys).unwrap_or(f64::NAN)
            })
            .collect();
        let n = us.len() as f64;
        let m = us.iter().sum::<f64>() / n;
        let sd_k = (us.iter().map(|u| (u - m) * (u - m)).sum::<f64>() / (n - 1.0)).sqrt();
        rounding(printed) + 1.96 * std::f64::consts::SQRT_2 * sd_k
    });
    let reproduces = ucb.zip(tolerance).map(|(u, tol)| (u - p).abs() <= tol);
    CellComparison {
        seeds: k,
        mean,
        sd,
        ucb,
        tolerance,
        reproduces,
    }
}

/// A tolerance to four decimals without trailing zeros.
fn fmt_tol(x: f64) -> String {
    let s = format!("{x:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_owned()
}

/// The warning for a table whose cells have fewer than two seeds, if any.
fn table_warning(fewest: usize) -> Option<String> {
    (fewest < 2).then(|| {
        format!(
            "a cell has only {fewest} seed(s): the 95% upper confidence bound U = mean + \
             t(0.975, K − 1)·s/√K cannot be computed from one seed, so the table shows it, \
             its tolerance and its verdict as n/a; use --seeds 2 or more (10 in the thesis)"
        )
    })
}

/// Table 5.1 as markdown and CSV, and the fewest seeds of a cell.
fn table(
    file: &SweepFile,
    runs: &[Loaded],
    delta: f64,
    setting: Setting,
) -> (String, String, usize) {
    let seeds = seed_count(&file.spec.seeds);
    let iterations = runs.first().map_or(0, |r| r.summary.iterations);
    let mut md = String::new();
    let mut csv = String::from(
        "preset,sigma0,variant,seeds,iterations,mean,sd,ucb95,thesis,tolerance,reproduces\n",
    );
    let _ = writeln!(
        md,
        "# Table 5.1: 95% upper confidence bound of |v − v*| after {iterations} iterations\n\n\
         Setting `{}`: {seeds} seeds, N = 100, H = 20, γ = 0.99, v⁰ = −0.1, δ = {}. Each cell: \
         U = mean + t(0.975, K − 1)·s/√K across the K seeds, ✓ when it reproduces the \
         published value P (|U − P| ≤ tolerance) and ✗ otherwise, ± the tolerance \
         0.5·10^(−digits of P) + 1.96·√2·SD_K (SD_K: bootstrap standard deviation of U over \
         {BOOTSTRAP_RESAMPLES} resamples of the seeds; docs/REPRODUCTION.md), then P in \
         brackets. n/a: fewer than two seeds.\n",
        setting.name(),
        delta
    );
    let mut fewest = usize::MAX;
    for &preset in &file.spec.presets {
        let _ = writeln!(md, "## Preset `{}`\n", preset.name());
        let _ = writeln!(md, "| σ⁰ | {} |", TABLE_VARIANTS.join(" | "));
        let _ = writeln!(md, "|---|{}", "---|".repeat(TABLE_VARIANTS.len()));
        for ((sigma0, thesis), printed) in
            THESIS_TABLE_5_1.into_iter().zip(THESIS_TABLE_5_1_PRINTED)
        {
            let mut cells = Vec::new();
            for (col, name) in TABLE_VARIANTS.iter().enumerate() {
                let errors: Vec<f64> = runs
                    .iter()
                    .filter(|r| r.preset == preset && r.variant == *name && r.sigma0 == sigma0)
                    .filter_map(|r| r.summary.abs_v_error)
                    .collect();
                let c = compare_cell(&errors, thesis[col], printed[col]);
                fewest = fewest.min(c.seeds);
                let cell = match (c.ucb, c.tolerance, c.reproduces) {
                    (Some(u), Some(tol), Some(ok)) => format!(
                        "{} {} ±{} [{}]",
                        fmt3(u),
                        if ok { "✓" } else { "✗" },
                        fmt_tol(tol),
                        printed[col]
                    ),
                    _ => format!("n/a [{}]", printed[col]),
                };
                cells.push(cell);
                let _ = writeln!(
                    csv,
                    "{},{sigma0:?},{name},{},{iterations},{},{},{},{},{},{}",
                    preset.name(),
                    c.seeds,
                    csv_num(c.mean),
                    c.sd.map_or_else(String::new, csv_num),
                    c.ucb.map_or_else(String::new, csv_num),
                    printed[col],
                    c.tolerance.map_or_else(String::new, csv_num),
                    c.reproduces.map_or("", |ok| if ok { "yes" } else { "no" }),
                );
            }
            let _ = writeln!(md, "| {sigma0:?} | {} |", cells.join(" | "));
        }
        md.push('\n');
    }
    (md, csv, if fewest == usize::MAX { 0 } else { fewest })
}

/// The abscissa of a figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[non_exhaustive]
pub enum XAxis {
    /// The iteration t.
    Iteration,
    /// Trajectories sampled so far (N per iteration, cumulated; the log's `trajectories`).
    Trajectories,
    /// Environment steps so far (trajectories × horizon, cumulated; the log's `steps`).
    Steps,
}

impl XAxis {
    /// The log column of the abscissa.
    pub fn column(self) -> &'static str {
        match self {
            XAxis::Iteration => "iteration",
            XAxis::Trajectories => "trajectories",
            XAxis::Steps => "steps",
        }
    }

    /// The axis label.
    fn label(self) -> &'static str {
        match self {
            XAxis::Iteration => "iteration",
            XAxis::Trajectories => "trajectories",
            XAxis::Steps => "environment steps",
        }
    }
}

/// How figures are drawn: the band across seeds, the text size and resolution, and the
/// abscissa (`None`: each figure's own, trajectories for Figure 5.3 as in the thesis and
/// iterations elsewhere).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FigureOptions {
    /// Band around each mean across seeds.
    pub band: BandKind,
    /// Font size and resolution.
    pub style: Style,
    /// Abscissa.
    pub x_axis: Option<XAxis>,
}

/// The scale on which the mean and band of log column `col` are taken so that the band stays
/// in the quantity's domain: σ > 0 on log σ, the budget by the percentile bootstrap (its
/// floor), the rest on the linear scale (see [`Scale`]).
fn scale_of(col: &str) -> Scale {
    match col {
        "sigma" => Scale::Log,
        "budget" => Scale::Bootstrap,
        _ => Scale::Linear,
    }
}

/// A quantity read from a log, and the scale of its mean and band across seeds.
type Quantity<'a> = (&'a dyn Fn(&Log) -> Option<Vec<f64>>, Scale);

/// Curves of `y` against column `x_col` for every run of (preset, variant) at σ⁰, as mean
/// and band of kind `band` on `scale` across seeds.
fn series(
    runs: &[Loaded],
    (preset, variant, sigma0): (EnvName, &str, f64),
    x_col: &str,
    (y, scale): Quantity<'_>,
    band: BandKind,
) -> Option<Series> {
    let group: Vec<&Loaded> = runs
        .iter()
        .filter(|r| r.preset == preset && r.variant == variant && r.sigma0 == sigma0)
        .collect();
    let curves: Vec<Vec<f64>> = group.iter().filter_map(|r| y(&r.log)).collect();
    let x = group.first()?.log.column(x_col)?;
    let (mean, band) = mean_band_on(&curves, band, scale);
    let x = x[..mean.len().min(x.len())].to_vec();
    Some(Series {
        label: display_name(variant),
        x,
        mean,
        band,
    })
}

fn col(name: &'static str) -> impl Fn(&Log) -> Option<Vec<f64>> {
    move |log: &Log| log.column(name)
}

/// Running mean over the logged iterations of (J_E + J_T)/2: the type-II guarantee of
/// Sec 5.1.2, (1/K) Σ_k (J(θᵏ) + J(θ_Tᵏ))/2 ≥ J_B.
fn guarantee(log: &Log) -> Option<Vec<f64>> {
    let je = log.column("j_explore")?;
    let jt = log.column("j_target")?;
    let mut sum = 0.0;
    Some(
        je.iter()
            .zip(&jt)
            .enumerate()
            .map(|(k, (a, b))| {
                sum += 0.5 * (a + b);
                sum / (k + 1) as f64
            })
            .collect(),
    )
}

/// What the panels of one preset's figure are drawn from.
struct PanelMaker<'a> {
    runs: &'a [Loaded],
    names: &'a [String],
    preset: EnvName,
    sigma0: f64,
    x_axis: XAxis,
    band: BandKind,
}

impl PanelMaker<'_> {
    /// A panel of log column `c` with one curve per variant.
    fn panel(&self, title: &str, y_label: &str, c: &'static str) -> Panel {
        self.panel_of(title, y_label, (&col(c), scale_of(c)))
    }

    /// A panel with one curve of `y` (on its scale) per variant.
    fn panel_of(&self, title: &str, y_label: &str, y: Quantity<'_>) -> Panel {
        Panel {
            title: title.to_owned(),
            x_label: self.x_axis.label().to_owned(),
            y_label: y_label.to_owned(),
            series: self
                .names
                .iter()
                .filter_map(|n| {
                    let group = (self.preset, n.as_str(), self.sigma0);
                    series(self.runs, group, self.x_axis.column(), y, self.band)
                })
                .collect(),
            hlines: Vec::new(),
        }
    }

    /// `title` with the kind of the preset's budgets (certified or estimated).
    fn budget_title(&self, title: &str) -> String {
        let kinds: Vec<&str> = self
            .runs
            .iter()
            .filter(|r| r.preset == self.preset)
            .map(|r| accounting_words(r.summary.options.accounting))
            .collect();
        budget_title(title, &kinds)
    }

    /// The panel of v, with v* as a reference line when known.
    fn v_panel(&self, title: &str) -> Panel {
        let mut p = self.panel(title, "v", "v");
        let v_star = self
            .runs
            .iter()
            .find(|r| r.preset == self.preset)
            .and_then(|r| r.summary.v_star.as_ref())
            .map(|v| v[0]);
        if let Some(v) = v_star {
            p.hlines.push(("v*".into(), v));
        }
        p
    }

    /// The guarantee panel of Fig 5.2, with J_B = J(θ⁰) averaged over the seeds.
    fn guarantee_panel(&self) -> Panel {
        let mut g = self.panel_of(
            "(d) guarantee: running mean of (J_{E} + J_{T})/2",
            "J",
            (&guarantee, Scale::Linear),
        );
        let first: Vec<f64> = self
            .runs
            .iter()
            .filter(|r| r.preset == self.preset)
            .filter_map(|r| r.log.column("j_explore").and_then(|c| c.first().copied()))
            .collect();
        g.hlines
            .push(("J_{B} = J(θ⁰)".into(), mean_halfwidth(&first).0));
        g
    }

    /// The panels of experiment `what`, in the thesis's order.
    fn panels(&self, what: Experiment) -> Vec<Panel> {
        const SIGMA: &str = "standard deviation σᵗ (geometric mean)";
        match what {
            Experiment::Fig51 => vec![
                self.panel("(a) performance J(θᵗ)", "J", "j_explore"),
                self.panel(&format!("(b) {SIGMA}"), "σ", "sigma"),
                self.v_panel("(c) mean parameter vᵗ"),
            ],
            Experiment::Fig52 => vec![
                self.panel("(a) exploratory J(θ_{E})", "J", "j_explore"),
                self.panel(&format!("(b) {SIGMA}"), "σ", "sigma"),
                self.v_panel("(c) mean parameter vᵗ"),
                self.guarantee_panel(),
                self.panel("(e) target J(θ_{T})", "J", "j_target"),
                with_zero_line(self.panel(&self.budget_title("(f) budget Bᵗ"), "B", "budget")),
            ],
            Experiment::Fig53 => vec![
                self.panel("(a) exploratory J(θ_{E})", "J", "j_explore"),
                self.panel("(b) target J(θ_{T})", "J", "j_target"),
                self.v_panel("(c) mean parameter vᵗ"),
                self.panel(&format!("(d) {SIGMA}"), "σ", "sigma"),
            ],
            Experiment::Fig54 | Experiment::Table51 => vec![
                self.panel("(a) performance J(θᵗ)", "J", "j_explore"),
                self.panel(&format!("(b) {SIGMA}"), "σ", "sigma"),
            ],
        }
    }
}

/// Panels per row for `n` panels: all in one row up to three, 2 × 2 for four, rows of
/// three beyond, so that no grid cell is left empty for the counts the figures use.
fn grid_columns(n: usize) -> usize {
    match n {
        0..=3 => n.max(1),
        4 => 2,
        _ => 3,
    }
}

/// The budget panel `p` with its B = 0 line: the safety requirement of the budget-based
/// variants is Bᵗ ≥ 0 (Definition 4.3, Sec 4.2.2).
fn with_zero_line(mut p: Panel) -> Panel {
    p.hlines.push(("B = 0".into(), 0.0));
    p
}

/// The name under which the thesis shows a variant or algorithm (SEPG-MI, SEPG-LB-I, …,
/// G(PO)MDP-Adam); names it does not know are kept as they are.
pub fn display_name(variant: &str) -> String {
    let short = variant.strip_prefix("sepg-").unwrap_or(variant);
    let known = sepg_algo::AlgoName::from_short_name(short).map(sepg_algo::AlgoName::thesis_name);
    if let Some(k) = known {
        return k.to_owned();
    }
    if let Some(lr) = short.strip_prefix("adam-") {
        return format!("G(PO)MDP-Adam, α = {lr}");
    }
    if let Some(a) = short.strip_prefix("const-") {
        return format!("G(PO)MDP, α = {a}");
    }
    if let Some(nu) = short.strip_prefix("sim-")
        && let Some((p, q)) = nu.split_once("of")
    {
        return format!("SEPG-SIM, ν = {p}/{q}");
    }
    variant.to_owned()
}

/// The figures of experiment `what` (one per preset), drawn as `opts` asks, and their file
/// stems.
fn figures(
    what: Experiment,
    file: &SweepFile,
    runs: &[Loaded],
    delta: f64,
    opts: &FigureOptions,
) -> Vec<(String, Figure)> {
    let sigma0 = file.spec.sigma0[0];
    let names: Vec<String> = file
        .spec
        .variant
        .iter()
        .filter_map(|v| v.name.clone())
        .collect();
    let x_axis = opts.x_axis.unwrap_or(if what == Experiment::Fig53 {
        XAxis::Trajectories
    } else {
        XAxis::Iteration
    });
    let mut out = Vec::new();
    for &preset in &file.spec.presets {
        let maker = PanelMaker {
            runs,
            names: &names,
            preset,
            sigma0,
            x_axis,
            band: opts.band,
        };
        let panels = maker.panels(what);
        let seeds = seed_count(&file.spec.seeds);
        let title = format!(
            "{} — {}, σ⁰ = {sigma0}, {seeds} seeds, δ = {delta} ({})",
            what.name(),
            preset.name(),
            opts.band.describe(),
        );
        let columns = grid_columns(panels.len());
        let stem = if what == Experiment::Fig54 {
            what.name().to_owned()
        } else {
            format!("{}-{}", what.name(), preset.name())
        };
        out.push((
            stem,
            Figure {
                title,
                panels,
                columns,
            },
        ));
    }
    out
}

/// What a reproduction wrote next to its runs.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Outputs {
    /// Table 5.1, written as `table-5.1.md` and `table-5.1.csv`.
    Table {
        /// The markdown table.
        markdown: String,
        /// Warnings for the reader (cells with fewer than two seeds).
        warnings: Vec<String>,
    },
    /// The figures, each as PNG and SVG.
    Figures {
        /// The files written, in order.
        paths: Vec<PathBuf>,
        /// Warnings for the reader (bands over fewer than [`MIN_BAND_SEEDS`] seeds).
        warnings: Vec<String>,
    },
}

/// The warning for bands of kind `band` drawn over as few as `fewest` seeds, if any: below
/// [`MIN_BAND_SEEDS`] seeds a band rests on too few degrees of freedom to say much.
fn band_warning(band: BandKind, fewest: usize) -> Option<String> {
    (band != BandKind::None && fewest < MIN_BAND_SEEDS).then(|| {
        format!(
            "a group has only {fewest} seed(s): its band rests on {} degree(s) of freedom \
             and says little; use {MIN_BAND_SEEDS} seeds or more, or --band none",
            fewest.saturating_sub(1)
        )
    })
}

/// Writes the table or figures of the finished reproduction in `dir` (whose `sweep.json` is
/// `file`, run with `opts`); the figures are drawn as `fig` asks.
///
/// # Errors
/// [`Error::Invalid`] for a run whose log is malformed or a style out of its domain;
/// [`Error::Failed`] when a run cannot be read or a file cannot be written or drawn.
pub fn write_outputs(
    opts: &ReproduceOptions,
    dir: &Path,
    file: &SweepFile,
    fig: &FigureOptions,
) -> Result<Outputs> {
    fig.style.validate()?;
    let runs = load(dir, file)?;
    if opts.what == Experiment::Table51 {
        let (markdown, csv, fewest) = table(file, &runs, opts.delta, opts.setting);
        crate::folder::write_atomic(&dir.join("table-5.1.md"), markdown.as_bytes())?;
        crate::folder::write_atomic(&dir.join("table-5.1.csv"), csv.as_bytes())?;
        let warnings = table_warning(fewest).into_iter().collect();
        return Ok(Outputs::Table { markdown, warnings });
    }
    let mut paths = Vec::new();
    for (stem, figure) in figures(opts.what, file, &runs, opts.delta, fig) {
        paths.extend(figure::save_both(&figure, dir, &stem, &fig.style)?);
    }
    let fewest = usize::try_from(seed_count(&file.spec.seeds)).unwrap_or(usize::MAX);
    let warnings = band_warning(fig.band, fewest).into_iter().collect();
    Ok(Outputs::Figures { paths, warnings })
}

/// The (column, panel title, axis label) of the four panels of `sepg plot`.
const PANELS: [(&str, &str, &str); 4] = [
    (
        "j_explore",
        "performance J(θᵗ) of the exploratory policy",
        "J",
    ),
    ("sigma", "standard deviation σᵗ", "σ"),
    ("v", "mean parameter vᵗ (first component)", "v"),
    ("budget", "budget Bᵗ", "B"),
];

/// The panel of `col` with its reference line (B = 0).
fn finish_panel(col: &str, panel: Panel) -> Panel {
    match col {
        "budget" => with_zero_line(panel),
        _ => panel,
    }
}

/// The log of the run folder `dir`, validated as the audit reads it ([`validate_log`]: every
/// row present, of the header's width, every cell a finite number or empty where allowed),
/// and how far it goes. Errors name the log file and its first bad line.
fn validated_log(dir: &Path) -> Result<(Log, LogCheck)> {
    let check = validate_log(dir)?;
    check.require_valid()?;
    Ok((Log::read_run(dir)?, check))
}

/// The mark of a run that has not finished: "incomplete: k of n iterations".
fn incomplete_mark(done: u64, total: u64) -> String {
    format!("incomplete: {done} of {total} iterations")
}

/// What the budget of run folder `dir` is: certified (sums of certified improvements) or
/// estimated (the thesis's bookkeeping of estimated J, Sec 4.4.4), from its summary or, for
/// an unfinished run, its configuration.
fn budget_kind(dir: &Path) -> Result<&'static str> {
    let accounting = match read_summary(dir) {
        Ok(s) => s.options.accounting,
        Err(_) => load_resolved(dir)?.checked.config().options.accounting,
    };
    Ok(accounting_words(accounting))
}

/// How the budget panel names an accounting.
fn accounting_words(accounting: Accounting) -> &'static str {
    match accounting {
        Accounting::Certified => "certified: sums of certified improvements",
        Accounting::Estimated => "estimated: differences of estimated J, no guarantee",
    }
}

/// The budget panel's title for runs whose budgets are of the kinds `kinds` (one entry per
/// run): the kind when they agree, both when they differ.
fn budget_title(title: &str, kinds: &[&str]) -> String {
    match kinds.first() {
        Some(first) if kinds.iter().all(|k| k == first) => format!("{title} ({first})"),
        Some(_) => format!("{title} (certified and estimated runs)"),
        None => title.to_owned(),
    }
}

/// The title of the run in `dir`: environment, algorithm, σ⁰, N and seed.
fn run_title(dir: &Path) -> Result<String> {
    let spec = load_resolved(dir)?.spec;
    let env = spec.env.map_or("?", |e| e.name());
    let name = display_name(spec.name.as_deref().unwrap_or_default());
    let sigma0 = match &spec.sigma0 {
        Some(crate::spec::Values::One(x)) => format!("{x}"),
        Some(crate::spec::Values::Many(v)) => v
            .iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(", "),
        None => "?".to_owned(),
    };
    let batch = spec.batch.map_or_else(|| "?".to_owned(), |n| n.to_string());
    let seed = spec.seed.map_or_else(|| "?".to_owned(), |s| s.to_string());
    Ok(format!(
        "{env}, {name}, σ⁰ = {sigma0}, N = {batch}, seed {seed}"
    ))
}

fn one_run(dir: &Path, x_axis: XAxis) -> Result<Figure> {
    let (log, check) = validated_log(dir)?;
    let x = log.column(x_axis.column()).ok_or_else(|| {
        Error::invalid(format!(
            "{}: log has no {} column",
            dir.display(),
            x_axis.column()
        ))
    })?;
    let name = display_name(&load_resolved(dir)?.spec.name.unwrap_or_default());
    let budget = budget_kind(dir)?;
    let panels = PANELS
        .iter()
        .map(|&(col, title, y)| {
            let mut series: Vec<Series> = log
                .column(col)
                .map(|mean| Series {
                    label: name.clone(),
                    x: x.clone(),
                    mean,
                    band: None,
                })
                .into_iter()
                .collect();
            if col == "j_explore"
                && let Some(mean) = log.column("j_target")
            {
                series.push(Series {
                    label: format!("{name} target"),
                    x: x.clone(),
                    mean,
                    band: None,
                });
            }
            let title = if col == "budget" {
                format!("{title} ({budget})")
            } else {
                title.to_owned()
            };
            let panel = Panel {
                title,
                x_label: x_axis.label().into(),
                y_label: y.into(),
                series,
                hlines: Vec::new(),
            };
            finish_panel(col, panel)
        })
        .collect();
    let mut title = run_title(dir)?;
    if !check.complete {
        title.push_str(&format!(
            " ({})",
            incomplete_mark(check.iterations_done, check.iterations_expected)
        ));
    }
    Ok(Figure {
        title,
        panels,
        columns: 2,
    })
}

/// The figure of a sweep folder, and the fewest seeds of any of its groups.
fn sweep_figure(dir: &Path, file: &SweepFile, opts: &FigureOptions) -> Result<(Figure, usize)> {
    let x_axis = opts.x_axis.unwrap_or(XAxis::Iteration);
    let logs = SweepLogs::read(dir, file)?;
    let groups = &logs.groups;
    if groups.is_empty() {
        return Err(Error::invalid(format!(
            "{} has no started run yet",
            dir.display()
        )));
    }
    let fewest = groups.iter().map(|(_, l)| l.len()).min().unwrap_or(0);
    let panels = PANELS
        .iter()
        .map(|&(col, title, y)| {
            let title = match col {
                "sigma" => format!("{title} (geometric mean)"),
                "budget" => budget_title(title, &logs.kinds),
                _ => title.to_owned(),
            };
            let panel = Panel {
                title,
                x_label: x_axis.label().into(),
                y_label: y.into(),
                series: logs.series(col, x_axis, opts.band),
                hlines: Vec::new(),
            };
            finish_panel(col, panel)
        })
        .collect();
    let runs = groups.iter().map(|(_, l)| l.len()).sum::<usize>();
    let mut title = format!(
        "sweep of {runs} runs in {} groups ({})",
        groups.len(),
        opts.band.describe()
    );
    if logs.done < logs.total {
        title.push_str(&format!(" ({})", incomplete_mark(logs.done, logs.total)));
    }
    let fig = Figure {
        title,
        panels,
        columns: 2,
    };
    Ok((fig, fewest))
}

/// The logs of the started runs of a sweep, grouped by (preset, variant, σ⁰).
struct SweepLogs {
    /// Each group's label and logs, in order of its first run.
    groups: Vec<(String, Vec<Log>)>,
    /// Iterations done by the started runs.
    done: u64,
    /// Iterations the started runs are to do.
    total: u64,
    /// The budget kind of each started run ([`budget_kind`]).
    kinds: Vec<&'static str>,
}

impl SweepLogs {
    /// Reads the validated log of every started run of the shard `file` of `dir`.
    fn read(dir: &Path, file: &SweepFile) -> Result<Self> {
        let mut logs = SweepLogs {
            groups: Vec::new(),
            done: 0,
            total: 0,
            kinds: Vec::new(),
        };
        for r in file.shard_runs() {
            let run_dir = dir.join(&r.dir);
            if !run_dir.join(CONFIG_FILE).is_file() {
                continue;
            }
            let label = format!(
                "{}, {}, σ⁰ = {}",
                r.preset.name(),
                display_name(&r.variant),
                r.sigma0
            );
            let (log, check) = validated_log(&run_dir)?;
            logs.kinds.push(budget_kind(&run_dir)?);
            logs.done += check.iterations_done;
            logs.total += check.iterations_expected;
            match logs.groups.iter_mut().find(|(l, _)| *l == label) {
                Some((_, group)) => group.push(log),
                None => logs.groups.push((label, vec![log])),
            }
        }
        Ok(logs)
    }

    /// One series per group of log column `col` against `x_axis`: the mean over the group's
    /// runs and its band, up to the shortest abscissa (none for a group without the column).
    fn series(&self, col: &str, x_axis: XAxis, band: BandKind) -> Vec<Series> {
        self.groups
            .iter()
            .filter_map(|(label, logs)| {
                let curves: Vec<Vec<f64>> = logs.iter().filter_map(|l| l.column(col)).collect();
                let x = logs
                    .iter()
                    .filter_map(|l| l.column(x_axis.column()))
                    .min_by_key(Vec::len)?;
                let (mean, band) = mean_band_on(&curves, band, scale_of(col));
                Some(Series {
                    label: label.clone(),
                    x: x[..mean.len().min(x.len())].to_vec(),
                    mean,
                    band,
                })
            })
            .collect()
    }
}

/// What `sepg plot` wrote, and what the reader of the figure should be warned about.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Plotted {
    /// The files written.
    pub paths: Vec<PathBuf>,
    /// Warnings for the user (a band over fewer than [`MIN_BAND_SEEDS`] seeds, an unfinished
    /// run).
    pub warnings: Vec<String>,
}

/// Plots performance, σ, v and budget of the run or sweep folder `dir` into `out` (.png or
/// .svg), or into `dir/plot.png` and `dir/plot.svg`, drawn as `opts` asks. A sweep's groups
/// are drawn as means across seeds with bands of kind `opts.band` (σ on log σ, the budget by
/// a percentile bootstrap), warned about when a group has fewer than [`MIN_BAND_SEEDS`]
/// seeds.
///
/// Every run's log is validated as `sepg audit` reads it: a truncated log, a NaN or
/// non-numeric cell or a missing row is refused, naming the file and its first bad line. A
/// run that has not finished (its checkpointed rows) is plotted with "incomplete: k of n
/// iterations" in the figure's title, and a warning.
///
/// # Errors
/// [`Error::Invalid`] for a folder that is neither a run nor a sweep, a malformed log, an
/// output file that is not .png or .svg, or a style out of its domain; [`Error::Failed`]
/// when drawing or writing fails.
pub fn plot(dir: &Path, out: Option<&Path>, opts: &FigureOptions) -> Result<Plotted> {
    if let Some(out) = out
        && !matches!(
            out.extension().and_then(|e| e.to_str()),
            Some("png" | "svg")
        )
    {
        return Err(Error::invalid(format!(
            "{}: figures are written as .png or .svg",
            out.display()
        )));
    }
    opts.style.validate()?;
    let mut warnings = Vec::new();
    let fig = if dir.join(SWEEP_FILE).is_file() {
        let (fig, fewest) = sweep_figure(dir, &SweepFile::read(dir)?, opts)?;
        warnings.extend(band_warning(opts.band, fewest));
        fig
    } else if dir.join(CONFIG_FILE).is_file() {
        one_run(dir, opts.x_axis.unwrap_or(XAxis::Iteration))?
    } else {
        return Err(Error::invalid(format!(
            "{} is neither a run folder nor a sweep folder",
            dir.display()
        )));
    };
    if let Some(at) = fig.title.find("(incomplete: ") {
        warnings.push(format!(
            "{}: {}; the figure is marked so",
            dir.display(),
            fig.title[at + 1..].trim_end_matches(')')
        ));
    }
    let paths = match out {
        Some(out) => {
            figure::save(&fig, out, &opts.style)?;
            vec![out.to_path_buf()]
        }
        None => figure::save_both(&fig, dir, "plot", &opts.style)?.to_vec(),
    };
    Ok(Plotted { paths, warnings })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_names_and_grids() {
        for (v, shown) in [
            ("mi", "SEPG-MI"),
            ("sepg-lb1", "SEPG-LB-I"),
            ("lb2", "SEPG-LB-II"),
            ("gpomdp-adam", "G(PO)MDP-Adam"),
            ("adam-1e-4", "G(PO)MDP-Adam, α = 1e-4"),
            ("sim-1of3", "SEPG-SIM, ν = 1/3"),
            ("my-variant", "my-variant"),
        ] {
            assert_eq!(display_name(v), shown);
        }
        // Figures 5.1–5.4 have 3, 6, 4 and 2 panels: no grid cell is left empty.
        for n in [2, 3, 4, 6] {
            assert_eq!(n % grid_columns(n), 0, "{n} panels");
        }
        let b = with_zero_line(Panel::default());
        assert_eq!(b.hlines, vec![("B = 0".to_owned(), 0.0)]);
    }

    #[test]
    fn published_cells_keep_their_printed_digits() {
        for ((_, values), printed) in THESIS_TABLE_5_1.iter().zip(THESIS_TABLE_5_1_PRINTED) {
            for (v, p) in values.iter().zip(printed) {
                assert_eq!(p.parse::<f64>().ok(), Some(*v), "{p}");
            }
        }
        // "0.510" is printed to three decimals although 0.510 as a number reads 0.51.
        assert_eq!(rounding(THESIS_TABLE_5_1_PRINTED[0][7]), 0.0005);
        assert_eq!(rounding("0.29"), 0.005);
        // Seeds that all agree: no sampling part, the rounding alone.
        let same = compare_cell(&[0.5104; 10], 0.510, "0.510");
        // (Up to the round-off of the mean of equal values, 1e-16.)
        let tol = same.tolerance.expect("ten seeds");
        assert!((tol - 0.0005).abs() < 1e-12, "{tol}");
        assert_eq!(same.reproduces, Some(true));
        assert_eq!(
            compare_cell(&[0.5106; 10], 0.510, "0.510").reproduces,
            Some(false)
        );
        let one = compare_cell(&[0.2], 0.29, "0.29");
        assert_eq!((one.ucb, one.tolerance, one.reproduces), (None, None, None));
    }

    /// Mean and sample standard deviation of `ys`, computed here from the definitions.
    fn mean_sd(ys: &[f64]) -> (f64, f64) {
        let k = ys.len() as f64;
        let m = ys.iter().sum::<f64>() / k;
        let ss = ys.iter().map(|y| (y - m).powi(2)).sum::<f64>();
        (m, (ss / (k - 1.0)).sqrt())
    }

    /// Figures 5.1 of a three-seed reproduction drawn with each kind of band: every point of
    /// every band is m ± t(0.975, 2)·s/√3 (ci95) or m ± s/√3 (se) of the three runs' logged
    /// values, on log σ for σ (transformed back by exp); `none` draws no band. t(0.975, 2) = 0.95/√(2·0.975·
    /// 0.025) in closed form. Cost: 2 variants × 3 seeds × 8 iterations on `lqg1d`.
    #[test]
    fn reproduced_figures_draw_the_band_asked_for() {
        use crate::reproduce::{LqgPreset, Mode};
        use crate::run::Silent;
        use crate::sweep::SweepOptions;
        use std::sync::atomic::AtomicBool;

        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = tmp.path().join("fig");
        let opts = ReproduceOptions {
            preset: Some(LqgPreset::Lqg1d),
            seeds: 3,
            iterations: Some(8),
            ..ReproduceOptions::new(Experiment::Fig51)
        };
        let stop = AtomicBool::new(false);
        let sweep_opts = SweepOptions {
            checkpoint_every: 100,
            stop: &stop,
            observer: &Silent,
        };
        let (file, _) =
            crate::reproduce::run(&opts, &dir, Mode::Start { force: false }, sweep_opts)
                .expect("reproduction runs");
        let runs = load(&dir, &file).expect("runs load");
        let t2 = 0.95 / (2.0 * 0.975 * 0.025f64).sqrt();
        for (band, factor) in [
            (BandKind::Ci95, Some(t2)),
            (BandKind::Se, Some(1.0)),
            (BandKind::None, None),
        ] {
            let fig_opts = FigureOptions {
                band,
                ..FigureOptions::default()
            };
            let figs = figures(Experiment::Fig51, &file, &runs, opts.delta, &fig_opts);
            assert_eq!(figs.len(), 1);
            let fig = &figs[0].1;
            assert!(fig.title.contains(band.describe()), "{}", fig.title);
            // σ is banded on log σ: mean and band are exp of the mean and band of log σ.
            for (panel, column, log) in [
                (&fig.panels[0], "j_explore", false),
                (&fig.panels[1], "sigma", true),
                (&fig.panels[2], "v", false),
            ] {
                assert_eq!(panel.series.len(), 2, "{}", panel.title);
                for s in &panel.series {
                    let logs: Vec<Vec<f64>> = runs
                        .iter()
                        .filter(|r| display_name(&r.variant) == s.label)
                        .map(|r| r.log.column(column).expect("column"))
                        .collect();
                    assert_eq!(logs.len(), 3, "{}", s.label);
                    let Some(factor) = factor else {
                        assert_eq!(s.band, None);
                        continue;
                    };
                    let (lo, hi) = s.band.as_ref().expect("band");
                    assert_eq!(s.mean.len(), 8);
                    for i in 0..8 {
                        let y = |k: usize| if log { logs[k][i].ln() } else { logs[k][i] };
                        let (m, sd) = mean_sd(&[y(0), y(1), y(2)]);
                        let h = factor * sd / 3f64.sqrt();
                        let back = |x: f64| if log { x.exp() } else { x };
                        let (m, l, u) = (back(m), back(m - h), back(m + h));
                        let tol = 1e-12 * (m.abs() + u.abs()).max(1e-300);
                        assert!((s.mean[i] - m).abs() <= tol, "{column} {i}");
                        assert!((hi[i] - u).abs() <= tol, "{column} {i}");
                        assert!((lo[i] - l).abs() <= tol, "{column} {i}");
                        if log {
                            assert!(lo[i] > 0.0, "{column} {i}");
                        }
                    }
                }
            }
        }
        assert!(band_warning(BandKind::Ci95, 3).is_none());
        assert!(band_warning(BandKind::Se, 2).is_some_and(|w| w.contains("2 seed(s)")));
        assert!(band_warning(BandKind::None, 1).is_none());
    }
}
