//! `sepg reproduce`: the experiments of thesis Chapter 5 with the protocol of SPEC §6, run as
//! sweeps (parallel, resumable) and summarised as Table 5.1 (markdown and CSV, side by side
//! with the published values) and Figures 5.1–5.4 (PNG and SVG, 95% bands across seeds).
//!
//! Protocol (SPEC §6): v⁰ = −0.1, σ⁰ ∈ {0.1, 0.2, 0.5, 1.0}, γ = 0.99, N = 100, H = 20,
//! 10,000 iterations, sampled gradients with confidence δ (default 0.2; the thesis gives
//! none), both LQG presets; Mountain Car (Fig 5.4): σ⁰ = 0.2, B⁰ = 1, SEPG-ZV against Adam.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};

use crate::cli::CliError;
use crate::commands::figure::{self, Figure, Panel, Series, mean_band, mean_halfwidth};
use crate::commands::runfmt::{self, AlgoName, EnvName, Log, RunSpec, Summary};
use crate::commands::sweep::{self, Seeds, Shard, SweepFile, SweepSpec};
use crate::output::write_atomic;

/// Table 5.1 of the thesis (sepg-thesis.txt, Sec 5.1.2, "Upper bound confidence intervals at
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

/// Variant names of Table 5.1, in the thesis's column order.
pub const TABLE_VARIANTS: [&str; 11] = [
    "adam-1e-4",
    "adam-1e-5",
    "adam-1e-6",
    "const-1e-4",
    "const-1e-5",
    "const-1e-6",
    "mi",
    "lb1",
    "lb2",
    "lv",
    "zv",
];

/// σ⁰ values of the LQG protocol (SPEC §6).
pub const SIGMA0: [f64; 4] = [0.1, 0.2, 0.5, 1.0];

/// The reproducible experiments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Experiment {
    /// Table 5.1: 95% upper confidence bound of |v − v*| after the run, all variants.
    #[value(name = "table-5.1")]
    Table51,
    /// Figure 5.1: MI against LB-I (J, σ, v).
    #[value(name = "fig-5.1")]
    Fig51,
    /// Figure 5.2: the type-II variants LB-II, LV, ZV (J_E, σ, v, guarantee, J_T, budget).
    #[value(name = "fig-5.2")]
    Fig52,
    /// Figure 5.3: ZV against SIM-ν, ν ∈ {1/3, 1/2, 2/3}.
    #[value(name = "fig-5.3")]
    Fig53,
    /// Figure 5.4: Mountain Car, SEPG-ZV against Adam (σ⁰ = 0.2, B⁰ = 1).
    #[value(name = "fig-5.4")]
    Fig54,
}

impl Experiment {
    fn name(self) -> &'static str {
        match self {
            Experiment::Table51 => "table-5.1",
            Experiment::Fig51 => "fig-5.1",
            Experiment::Fig52 => "fig-5.2",
            Experiment::Fig53 => "fig-5.3",
            Experiment::Fig54 => "fig-5.4",
        }
    }
}

/// LQG presets accepted by `--preset`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LqgPreset {
    /// Thesis Sec 5.1 as written.
    Lqg,
    /// The 1-D LQG behind the thesis's numbers.
    Lqg1d,
}

/// Arguments of `sepg reproduce`.
#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// The experiment.
    #[arg(value_enum)]
    what: Experiment,
    /// Only this LQG preset (default: both).
    #[arg(long, value_enum)]
    preset: Option<LqgPreset>,
    /// Number of seeds (0..K).
    #[arg(long, default_value_t = 10)]
    seeds: u64,
    /// Iterations per run [default: 10000; 1000 for fig-5.4].
    #[arg(long)]
    iterations: Option<u64>,
    /// Confidence δ of the sampled gradients.
    #[arg(long, default_value_t = 0.2)]
    delta: f64,
    /// σ⁰ of the LQG figures (fig-5.1 to fig-5.3).
    #[arg(long = "fig-sigma0", default_value_t = 1.0)]
    fig_sigma0: f64,
    /// Output folder [default: sepg-<experiment>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Write into a non-empty folder, replacing a previous reproduction there.
    #[arg(long)]
    force: bool,
    /// Continue an interrupted reproduction in --out (same options).
    #[arg(long)]
    resume: bool,
    /// No progress bar; print only the table or the written files.
    #[arg(long)]
    quiet: bool,
}

fn variant(name: &str, algo: AlgoName) -> RunSpec {
    RunSpec {
        name: Some(name.to_owned()),
        algo: Some(algo),
        ..RunSpec::default()
    }
}

/// The sweep of an experiment.
fn sweep_spec(args: &ReproduceArgs) -> Result<SweepSpec, CliError> {
    let presets = match (args.what, args.preset) {
        (Experiment::Fig54, Some(_)) => {
            return Err(CliError::usage(
                "--preset does not apply to fig-5.4 (Mountain Car)",
            ));
        }
        (Experiment::Fig54, None) => vec![EnvName::MountainCar],
        (_, Some(LqgPreset::Lqg)) => vec![EnvName::Lqg],
        (_, Some(LqgPreset::Lqg1d)) => vec![EnvName::Lqg1d],
        (_, None) => vec![EnvName::Lqg, EnvName::Lqg1d],
    };
    if args.seeds == 0 {
        return Err(CliError::usage("--seeds must be at least 1"));
    }
    let iterations = args
        .iterations
        .unwrap_or(if args.what == Experiment::Fig54 {
            1000
        } else {
            10_000
        });
    let base = RunSpec {
        iterations: Some(iterations),
        delta: Some(args.delta),
        // About 500 logged rows per run: enough for curves, small on disk.
        log_every: Some((iterations / 500).max(1)),
        ..RunSpec::default()
    };
    let sepg = |name: &str, algo| variant(name, algo);
    let adam = |lr: f64, name: &str| RunSpec {
        lr: Some(lr),
        ..variant(name, AlgoName::GpomdpAdam)
    };
    let constant = |a: f64, name: &str| RunSpec {
        alpha: Some(a),
        ..variant(name, AlgoName::GpomdpConst)
    };
    let sim = |nu: f64, name: &str| RunSpec {
        nu: Some(nu),
        ..variant(name, AlgoName::SepgSim)
    };
    let (variants, sigma0) = match args.what {
        Experiment::Table51 => (
            vec![
                adam(1e-4, TABLE_VARIANTS[0]),
                adam(1e-5, TABLE_VARIANTS[1]),
                adam(1e-6, TABLE_VARIANTS[2]),
                constant(1e-4, TABLE_VARIANTS[3]),
                constant(1e-5, TABLE_VARIANTS[4]),
                constant(1e-6, TABLE_VARIANTS[5]),
                sepg("mi", AlgoName::SepgMi),
                sepg("lb1", AlgoName::SepgLb1),
                sepg("lb2", AlgoName::SepgLb2),
                sepg("lv", AlgoName::SepgLv),
                sepg("zv", AlgoName::SepgZv),
            ],
            SIGMA0.to_vec(),
        ),
        Experiment::Fig51 => (
            vec![sepg("mi", AlgoName::SepgMi), sepg("lb1", AlgoName::SepgLb1)],
            vec![args.fig_sigma0],
        ),
        Experiment::Fig52 => (
            vec![
                sepg("lb2", AlgoName::SepgLb2),
                sepg("lv", AlgoName::SepgLv),
                sepg("zv", AlgoName::SepgZv),
            ],
            vec![args.fig_sigma0],
        ),
        Experiment::Fig53 => (
            vec![
                sepg("zv", AlgoName::SepgZv),
                sim(1.0 / 3.0, "sim-1of3"),
                sim(0.5, "sim-1of2"),
                sim(2.0 / 3.0, "sim-2of3"),
            ],
            vec![args.fig_sigma0],
        ),
        Experiment::Fig54 => (
            vec![sepg("zv", AlgoName::SepgZv), adam(1e-3, "adam-1e-3")],
            vec![0.2],
        ),
    };
    Ok(SweepSpec {
        presets,
        seeds: Seeds::Count(args.seeds),
        sigma0,
        base,
        variant: variants,
    })
}

/// Runs `sepg reproduce`.
///
/// # Errors
/// Usage error (exit 2) for bad options or a non-empty output folder; failure (exit 1) for
/// failed runs or I/O errors.
pub fn run(args: &ReproduceArgs) -> Result<(), CliError> {
    let spec = sweep_spec(args)?;
    let (file, resolved) = sweep::expand(&spec, Shard { index: 0, count: 1 })?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("sepg-{}", args.what.name())));
    let stats = if args.resume {
        let existing = SweepFile::read(&dir)?;
        if existing.sweep_id != file.sweep_id {
            return Err(CliError::usage(format!(
                "{} holds a different reproduction (other options or sepg version)",
                dir.display()
            )));
        }
        sweep::execute(&dir, &file, &resolved, 2000, !args.quiet)?
    } else {
        sweep::start(&dir, &file, &resolved, args.force, 2000, !args.quiet)?
    };
    if !args.quiet {
        eprintln!("{}", sweep::stats_line(&dir, &file, &stats));
    }
    let runs = load(&dir, &file)?;
    match args.what {
        Experiment::Table51 => {
            let (md, csv) = table(&file, &runs, args)?;
            write_atomic(&dir.join("table-5.1.md"), md.as_bytes())?;
            write_atomic(&dir.join("table-5.1.csv"), csv.as_bytes())?;
            print!("{md}");
        }
        what => {
            for fig in figures(what, &file, &runs, args) {
                let stem = fig.0;
                let paths = figure::save_both(&fig.1, &dir, &stem)?;
                if !args.quiet {
                    for p in paths {
                        println!("{}", p.display());
                    }
                }
            }
        }
    }
    Ok(())
}

/// A finished run of the sweep: its entry, summary and log.
struct Loaded {
    preset: EnvName,
    variant: String,
    sigma0: f64,
    summary: Summary,
    log: Log,
}

fn load(dir: &Path, file: &SweepFile) -> Result<Vec<Loaded>, CliError> {
    file.runs
        .iter()
        .map(|r| {
            let run_dir = dir.join(&r.dir);
            let text = std::fs::read_to_string(run_dir.join(runfmt::SUMMARY_FILE))
                .map_err(|e| CliError::failure(format!("{}: {e}", run_dir.display())))?;
            let summary: Summary = serde_json::from_str(&text)
                .map_err(|e| CliError::failure(format!("{}: {e}", run_dir.display())))?;
            Ok(Loaded {
                preset: r.preset,
                variant: r.variant.clone(),
                sigma0: r.sigma0,
                summary,
                log: Log::read_run(&run_dir)?,
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

/// Table 5.1 as markdown and CSV.
fn table(
    file: &SweepFile,
    runs: &[Loaded],
    args: &ReproduceArgs,
) -> Result<(String, String), CliError> {
    let seeds = seed_count(&file.spec.seeds);
    let iterations = runs.first().map_or(0, |r| r.summary.iterations);
    let mut md = String::new();
    let mut csv = String::from("preset,sigma0,variant,seeds,iterations,mean,sd,ucb95,thesis\n");
    let _ = writeln!(
        md,
        "# Table 5.1: 95% upper confidence bound of |v − v*| after {iterations} iterations\n\n\
         {seeds} seeds, N = 100, H = 20, γ = 0.99, v⁰ = −0.1, δ = {}. Each cell: ours (thesis). \
         Bound: mean + t(0.975, K − 1)·s/√K across the K seeds.\n",
        args.delta
    );
    for &preset in &file.spec.presets {
        let _ = writeln!(md, "## Preset `{}`\n", preset.name());
        let _ = writeln!(md, "| σ⁰ | {} |", TABLE_VARIANTS.join(" | "));
        let _ = writeln!(md, "|---|{}", "---|".repeat(TABLE_VARIANTS.len()));
        for (sigma0, thesis) in THESIS_TABLE_5_1 {
            let mut cells = Vec::new();
            for (col, name) in TABLE_VARIANTS.iter().enumerate() {
                let errors: Vec<f64> = runs
                    .iter()
                    .filter(|r| r.preset == preset && r.variant == *name && r.sigma0 == sigma0)
                    .filter_map(|r| r.summary.abs_v_error)
                    .collect();
                let (mean, half) = mean_halfwidth(&errors);
                let ucb = mean + half.unwrap_or(0.0);
                let k = errors.len() as f64;
                let sd = if k >= 2.0 {
                    (errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / (k - 1.0)).sqrt()
                } else {
                    f64::NAN
                };
                cells.push(format!("{} ({})", fmt3(ucb), thesis[col]));
                let _ = writeln!(
                    csv,
                    "{},{sigma0:?},{name},{},{iterations},{},{},{},{}",
                    preset.name(),
                    errors.len(),
                    csv_num(mean),
                    csv_num(sd),
                    csv_num(ucb),
                    thesis[col]
                );
            }
            let _ = writeln!(md, "| {sigma0:?} | {} |", cells.join(" | "));
        }
        md.push('\n');
    }
    Ok((md, csv))
}

/// Curves of `column` (x = iteration or trajectories) for every run of (preset, variant)
/// at σ⁰, as mean and band across seeds.
fn series(
    runs: &[Loaded],
    preset: EnvName,
    variant: &str,
    sigma0: f64,
    x_col: &str,
    y: &dyn Fn(&Log) -> Option<Vec<f64>>,
) -> Option<Series> {
    let group: Vec<&Loaded> = runs
        .iter()
        .filter(|r| r.preset == preset && r.variant == variant && r.sigma0 == sigma0)
        .collect();
    let curves: Vec<Vec<f64>> = group.iter().filter_map(|r| y(&r.log)).collect();
    let x = group.first()?.log.column(x_col)?;
    let (mean, band) = mean_band(&curves);
    let x = x[..mean.len().min(x.len())].to_vec();
    Some(Series {
        label: variant.to_owned(),
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

fn figures(
    what: Experiment,
    file: &SweepFile,
    runs: &[Loaded],
    args: &ReproduceArgs,
) -> Vec<(String, Figure)> {
    let sigma0 = file.spec.sigma0[0];
    let names: Vec<String> = file
        .spec
        .variant
        .iter()
        .filter_map(|v| v.name.clone())
        .collect();
    let mut out = Vec::new();
    for &preset in &file.spec.presets {
        let x_col = if what == Experiment::Fig53 {
            "trajectories"
        } else {
            "iteration"
        };
        let panel = |title: &str, y_label: &str, y: &dyn Fn(&Log) -> Option<Vec<f64>>| Panel {
            title: title.to_owned(),
            x_label: x_col.to_owned(),
            y_label: y_label.to_owned(),
            series: names
                .iter()
                .filter_map(|n| series(runs, preset, n, sigma0, x_col, y))
                .collect(),
            hlines: Vec::new(),
        };
        let v_star = runs
            .iter()
            .find(|r| r.preset == preset)
            .and_then(|r| r.summary.v_star.as_ref())
            .map(|v| v[0]);
        let with_vstar = |mut p: Panel| {
            if let Some(v) = v_star {
                p.hlines.push(("v*".into(), v));
            }
            p
        };
        let j0 = {
            let first: Vec<f64> = runs
                .iter()
                .filter(|r| r.preset == preset)
                .filter_map(|r| r.log.column("j_explore").and_then(|c| c.first().copied()))
                .collect();
            mean_halfwidth(&first).0
        };
        let panels = match what {
            Experiment::Fig51 => vec![
                panel("(a) performance J(θᵗ)", "J", &col("j_explore")),
                panel("(b) standard deviation σᵗ", "σ", &col("sigma")),
                with_vstar(panel("(c) mean parameter vᵗ", "v", &col("v"))),
            ],
            Experiment::Fig52 => {
                let mut g = panel("(d) guarantee mean of (J_E + J_T)/2", "J", &guarantee);
                g.hlines.push(("J_B = J(θ⁰)".into(), j0));
                vec![
                    panel("(a) exploratory J(θ_E)", "J", &col("j_explore")),
                    panel("(b) standard deviation σᵗ", "σ", &col("sigma")),
                    with_vstar(panel("(c) mean parameter vᵗ", "v", &col("v"))),
                    g,
                    panel("(e) target J(θ_T)", "J", &col("j_target")),
                    panel("(f) budget Bᵗ", "B", &col("budget")),
                ]
            }
            Experiment::Fig53 => vec![
                panel("(a) exploratory J(θ_E)", "J", &col("j_explore")),
                panel("(b) target J(θ_T)", "J", &col("j_target")),
                with_vstar(panel("(c) mean parameter vᵗ", "v", &col("v"))),
                panel("(d) standard deviation σᵗ", "σ", &col("sigma")),
            ],
            Experiment::Fig54 | Experiment::Table51 => vec![
                panel("(a) performance J(θᵗ)", "J", &col("j_explore")),
                panel("(b) standard deviation σᵗ", "σ", &col("sigma")),
            ],
        };
        let seeds = seed_count(&file.spec.seeds);
        let title = format!(
            "{} — {}, σ⁰ = {sigma0}, {seeds} seeds, δ = {} (mean, 95% band)",
            what.name(),
            preset.name(),
            args.delta
        );
        let columns = if panels.len() > 4 {
            3
        } else {
            panels.len().min(2)
        };
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
