//! The experiments of thesis Chapter 5, run as sweeps (parallel, resumable): Table 5.1 and
//! Figures 5.1–5.4 with the protocol of Sec 5.1.
//!
//! Protocol: v⁰ = −0.1, σ⁰ ∈ {0.1, 0.2, 0.5, 1.0}, γ = 0.99, N = 100, H = 20, 10,000
//! iterations, sampled gradients with confidence δ (default 0.2; the thesis gives none), both
//! LQG presets; Mountain Car (Fig 5.4): σ⁰ = 0.2, B⁰ = 1, SEPG-ZV against Adam. The tables and
//! figures made from the finished runs are in [`crate::report`].

use std::path::Path;

#[cfg(feature = "clap")]
use clap::ValueEnum;

use crate::error::{Error, Result};
use crate::spec::{AlgoName, EnvName, RunSpec};
use crate::sweep::{self, Seeds, Shard, SweepFile, SweepOptions, SweepSpec, SweepStats};

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

/// σ⁰ values of the LQG protocol (Sec 5.1).
pub const SIGMA0: [f64; 4] = [0.1, 0.2, 0.5, 1.0];

/// The reproducible experiments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
pub enum Experiment {
    /// Table 5.1: 95% upper confidence bound of |v − v*| after the run, all variants.
    #[cfg_attr(feature = "clap", value(name = "table-5.1"))]
    Table51,
    /// Figure 5.1: MI against LB-I (J, σ, v).
    #[cfg_attr(feature = "clap", value(name = "fig-5.1"))]
    Fig51,
    /// Figure 5.2: the type-II variants LB-II, LV, ZV (J_E, σ, v, guarantee, J_T, budget).
    #[cfg_attr(feature = "clap", value(name = "fig-5.2"))]
    Fig52,
    /// Figure 5.3: ZV against SIM-ν, ν ∈ {1/3, 1/2, 2/3}.
    #[cfg_attr(feature = "clap", value(name = "fig-5.3"))]
    Fig53,
    /// Figure 5.4: Mountain Car, SEPG-ZV against Adam (σ⁰ = 0.2, B⁰ = 1).
    #[cfg_attr(feature = "clap", value(name = "fig-5.4"))]
    Fig54,
}

impl Experiment {
    /// The experiment's name on the command line and in file names.
    pub fn name(self) -> &'static str {
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
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
pub enum LqgPreset {
    /// Thesis Sec 5.1 as written.
    Lqg,
    /// The 1-D LQG behind the thesis's numbers.
    Lqg1d,
}

/// The options of a reproduction: which experiment, and the protocol settings a user may
/// change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReproduceOptions {
    /// The experiment.
    pub what: Experiment,
    /// Only this LQG preset (`None`: both; must be `None` for Fig 5.4).
    pub preset: Option<LqgPreset>,
    /// Number of seeds K ≥ 1 (seeds 0..K).
    pub seeds: u64,
    /// Iterations per run (`None`: 10,000, or 1,000 for Fig 5.4).
    pub iterations: Option<u64>,
    /// Confidence δ of the sampled gradients.
    pub delta: f64,
    /// σ⁰ of the LQG figures (Figures 5.1 to 5.3).
    pub fig_sigma0: f64,
}

impl ReproduceOptions {
    /// The thesis's protocol for `what`: both presets, 10 seeds, δ = 0.2, σ⁰ = 1 in the
    /// LQG figures.
    pub fn new(what: Experiment) -> ReproduceOptions {
        ReproduceOptions {
            what,
            preset: None,
            seeds: 10,
            iterations: None,
            delta: 0.2,
            fig_sigma0: 1.0,
        }
    }
}

/// Whether a reproduction starts in a fresh folder or continues in its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Start; with `force`, replace a previous sweep in a non-empty folder.
    Start {
        /// Replace a previous sweep's files.
        force: bool,
    },
    /// Continue the interrupted reproduction with the same options.
    Resume,
}

fn variant(name: &str, algo: AlgoName) -> RunSpec {
    RunSpec {
        name: Some(name.to_owned()),
        algo: Some(algo),
        ..RunSpec::default()
    }
}

fn adam(lr: f64, name: &str) -> RunSpec {
    RunSpec {
        lr: Some(lr),
        ..variant(name, AlgoName::GpomdpAdam)
    }
}

fn constant(alpha: f64, name: &str) -> RunSpec {
    RunSpec {
        alpha: Some(alpha),
        ..variant(name, AlgoName::GpomdpConst)
    }
}

fn sim(nu: f64, name: &str) -> RunSpec {
    RunSpec {
        nu: Some(nu),
        ..variant(name, AlgoName::SepgSim)
    }
}

/// The environments of the experiment.
fn presets(opts: &ReproduceOptions) -> Result<Vec<EnvName>> {
    Ok(match (opts.what, opts.preset) {
        (Experiment::Fig54, Some(_)) => {
            return Err(Error::invalid(
                "--preset does not apply to fig-5.4 (Mountain Car)",
            ));
        }
        (Experiment::Fig54, None) => vec![EnvName::MountainCar],
        (_, Some(LqgPreset::Lqg)) => vec![EnvName::Lqg],
        (_, Some(LqgPreset::Lqg1d)) => vec![EnvName::Lqg1d],
        (_, None) => vec![EnvName::Lqg, EnvName::Lqg1d],
    })
}

/// The variants and σ⁰ values of the experiment.
fn variants(opts: &ReproduceOptions) -> (Vec<RunSpec>, Vec<f64>) {
    let sepg = variant;
    match opts.what {
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
            vec![opts.fig_sigma0],
        ),
        Experiment::Fig52 => (
            vec![
                sepg("lb2", AlgoName::SepgLb2),
                sepg("lv", AlgoName::SepgLv),
                sepg("zv", AlgoName::SepgZv),
            ],
            vec![opts.fig_sigma0],
        ),
        Experiment::Fig53 => (
            vec![
                sepg("zv", AlgoName::SepgZv),
                sim(1.0 / 3.0, "sim-1of3"),
                sim(0.5, "sim-1of2"),
                sim(2.0 / 3.0, "sim-2of3"),
            ],
            vec![opts.fig_sigma0],
        ),
        Experiment::Fig54 => (
            vec![sepg("zv", AlgoName::SepgZv), adam(1e-3, "adam-1e-3")],
            vec![0.2],
        ),
    }
}

/// The sweep of an experiment.
///
/// # Errors
/// [`Error::Invalid`] for a preset with Fig 5.4 or zero seeds.
pub fn sweep_spec(opts: &ReproduceOptions) -> Result<SweepSpec> {
    let presets = presets(opts)?;
    if opts.seeds == 0 {
        return Err(Error::invalid("--seeds must be at least 1"));
    }
    let iterations = opts
        .iterations
        .unwrap_or(if opts.what == Experiment::Fig54 {
            1000
        } else {
            10_000
        });
    let base = RunSpec {
        iterations: Some(iterations),
        delta: Some(opts.delta),
        // About 500 logged rows per run: enough for curves, small on disk.
        log_every: Some((iterations / 500).max(1)),
        ..RunSpec::default()
    };
    let (variant, sigma0) = variants(opts);
    Ok(SweepSpec {
        presets,
        seeds: Seeds::Count(opts.seeds),
        sigma0,
        base,
        variant,
    })
}

/// Runs the sweep of the experiment in `dir` (started or resumed by `mode`) and returns its
/// `sweep.json` and throughput; [`crate::report`] turns the finished runs into the table or
/// figures.
///
/// # Errors
/// [`Error::Invalid`] for bad options, a non-empty folder (starting without `force`) or a
/// folder holding another reproduction (resuming); otherwise as [`sweep::execute`].
pub fn run(
    opts: &ReproduceOptions,
    dir: &Path,
    mode: Mode,
    sweep_opts: SweepOptions<'_>,
) -> Result<(SweepFile, SweepStats)> {
    let spec = sweep_spec(opts)?;
    let (file, resolved) = sweep::expand(&spec, Shard { index: 0, count: 1 })?;
    let stats = match mode {
        Mode::Resume => {
            let existing = SweepFile::read(dir)?;
            if existing.sweep_id != file.sweep_id {
                return Err(Error::invalid(format!(
                    "{} holds a different reproduction (other options or sepg version)",
                    dir.display()
                )));
            }
            sweep::execute(dir, &file, &resolved, sweep_opts)?
        }
        Mode::Start { force } => sweep::start(dir, &file, &resolved, force, sweep_opts)?,
    };
    Ok((file, stats))
}
