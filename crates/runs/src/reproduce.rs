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
use crate::spec::{
    AccountingName, AlgoName, ConfidenceName, ConstantsName, EnvName, FitName, Lb1Name, RunSpec,
    ScheduleName, ScoresName, WDirectionName, WStepName,
};
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

/// LQG presets accepted by `--preset` (the LQG presets of `sepg-mdp`).
pub use sepg_mdp::env::LqgPreset;

/// A named choice of the algorithm options for a whole reproduction. The options each
/// setting fixes are listed in docs/REPRODUCTION.md; flags override them one by one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(ValueEnum))]
pub enum Setting {
    /// sepg's defaults: the tight constants, the certified accounting, proven (sub-Gaussian)
    /// widths with δ spread over the run, the exploring w-update, the reference batch of
    /// J(θ⁰), cross-fitted ∇̂_w L, ν-split LB-I, leave-one-out baselines.
    #[default]
    Default,
    /// The thesis-era public code's choices that reproduce the published SEPG cells: no
    /// confidence widths (its δ = 1), no reference batch (J(θ⁰) from the first batch),
    /// ψ = 0.53 in d, policy scores at the clipped action, and the w-direction ∇̂_w L
    /// assembled from full-batch (plug-in) products, the quantity the thesis's text follows;
    /// ν-split LB-I, one v-block and one w-block per iteration, leave-one-out baselines. No
    /// guarantee holds under it.
    ThesisCode,
    /// The thesis-era public code taken literally (potion `algorithms/safe.py`, January
    /// 2019): no confidence widths, the metagradient w-direction, LB-I's full requirement per
    /// half-step, alternating v/w iterations for MI and LB-I, plug-in baselines, ψ = 0.53, no
    /// reference batch. No guarantee holds under it.
    PotionLiteral,
    /// The thesis's algorithm as described, with estimates used as exact: the defaults
    /// without confidence widths and without the reference batch. No guarantee holds under it.
    NoConfidence,
}

/// ψ of the thesis-era public code's d (Theorem 4.3), rounded up from Lemma A.1's
/// ψ = 0.52355702…
const POTION_PSI: f64 = 0.53;

impl Setting {
    /// The setting's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Setting::Default => "default",
            Setting::ThesisCode => "thesis-code",
            Setting::PotionLiteral => "potion-literal",
            Setting::NoConfidence => "no-confidence",
        }
    }

    /// The options the setting fixes, as a partial run specification.
    fn options(self) -> OptionFlags {
        match self {
            Setting::Default => OptionFlags::default(),
            Setting::ThesisCode => OptionFlags {
                accounting: Some(AccountingName::Estimated),
                schedule: Some(ScheduleName::Iteration),
                constants: Some(ConstantsName::Thesis),
                confidence: Some(ConfidenceName::None),
                w_direction: Some(WDirectionName::PlugIn),
                reference_batch: Some(0),
                psi: Some(POTION_PSI),
                scores: Some(ScoresName::Clipped),
                ..OptionFlags::default()
            },
            Setting::PotionLiteral => OptionFlags {
                accounting: Some(AccountingName::Estimated),
                schedule: Some(ScheduleName::Iteration),
                constants: Some(ConstantsName::Thesis),
                confidence: Some(ConfidenceName::None),
                w_direction: Some(WDirectionName::Metagradient),
                lb1_requirement: Some(Lb1Name::Full),
                alternating: Some(true),
                baseline_fit: Some(FitName::PlugIn),
                reference_batch: Some(0),
                psi: Some(POTION_PSI),
                scores: Some(ScoresName::Clipped),
                ..OptionFlags::default()
            },
            Setting::NoConfidence => OptionFlags {
                accounting: Some(AccountingName::Estimated),
                schedule: Some(ScheduleName::Iteration),
                constants: Some(ConstantsName::Thesis),
                confidence: Some(ConfidenceName::None),
                reference_batch: Some(0),
                ..OptionFlags::default()
            },
        }
    }
}

/// The algorithm options of a reproduction (each overrides the setting's choice). The SEPG
/// options reach the SEPG variants only (alternating: MI and LB-I; `lb1-requirement`: LB-I);
/// the baseline fit and the constant overrides reach every variant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct OptionFlags {
    /// Form of the SEPG w-update [default: exploring].
    #[cfg_attr(feature = "clap", arg(long = "w-step", value_enum))]
    pub w_step: Option<WStepName>,
    /// Direction of the SEPG w-update [default: cross-fitted].
    #[cfg_attr(feature = "clap", arg(long = "w-direction", value_enum))]
    pub w_direction: Option<WDirectionName>,
    /// Clipping threshold of the metagradient's last term [default: 100].
    #[cfg_attr(feature = "clap", arg(long = "metagradient-clip"))]
    pub metagradient_clip: Option<f64>,
    /// Confidence widths of sampled SEPG [default: sub-gaussian].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub confidence: Option<ConfidenceName>,
    /// Multiplier of the Student-t quantile [default: 1].
    #[cfg_attr(feature = "clap", arg(long = "quantile-factor"))]
    pub quantile_factor: Option<f64>,
    /// LB-I's requirement per half-step [default: split].
    #[cfg_attr(feature = "clap", arg(long = "lb1-requirement", value_enum))]
    pub lb1_requirement: Option<Lb1Name>,
    /// Alternate v- and w-iterations (MI, LB-I) [default: false].
    #[cfg_attr(feature = "clap", arg(long))]
    pub alternating: Option<bool>,
    /// Trajectories of the reference batch of J(θ⁰), 0 for none [default: 1000].
    #[cfg_attr(feature = "clap", arg(long = "reference-batch"))]
    pub reference_batch: Option<usize>,
    /// How the estimators' baselines are fitted [default: leave-one-out].
    #[cfg_attr(feature = "clap", arg(long = "baseline-fit", value_enum))]
    pub baseline_fit: Option<FitName>,
    /// Discount factor γ [default: 0.99].
    #[cfg_attr(feature = "clap", arg(long))]
    pub gamma: Option<f64>,
    /// R used by the bounds [default: the environment's].
    #[cfg_attr(feature = "clap", arg(long = "r-max"))]
    pub r_max: Option<f64>,
    /// M_φ used by the bounds [default: the environment's].
    #[cfg_attr(feature = "clap", arg(long = "m-phi"))]
    pub m_phi: Option<f64>,
    /// |A| used by the bounds [default: the environment's].
    #[cfg_attr(feature = "clap", arg(long = "action-volume"))]
    pub action_volume: Option<f64>,
    /// ψ used by the bound of Theorem 4.3 [default: Lemma A.1's ψ = 0.52355702…].
    #[cfg_attr(feature = "clap", arg(long))]
    pub psi: Option<f64>,
    /// Policy scores at the raw or at the clipped action [default: raw].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub scores: Option<ScoresName>,
    /// Certified safe steps of the SEPG variants [default: true].
    #[cfg_attr(feature = "clap", arg(long = "certified-steps"))]
    pub certified_steps: Option<bool>,
    /// What SEPG's requirements are built on [default: certified; the thesis settings:
    /// estimated].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub accounting: Option<AccountingName>,
    /// How δ is spread over the confidence widths [default: run; the thesis settings:
    /// iteration].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub schedule: Option<ScheduleName>,
    /// Family of the constants c and d of every variant's bounds [default: tight, with each
    /// preset's reward sign and the run's horizon; the thesis settings: thesis].
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub constants: Option<ConstantsName>,
}

impl OptionFlags {
    /// These flags, each falling back to `base`'s.
    fn over(self, base: OptionFlags) -> OptionFlags {
        macro_rules! pick {
            ($($f:ident),*) => { OptionFlags { $($f: self.$f.or(base.$f),)* } };
        }
        pick!(
            w_step,
            w_direction,
            metagradient_clip,
            confidence,
            quantile_factor,
            lb1_requirement,
            alternating,
            reference_batch,
            baseline_fit,
            gamma,
            r_max,
            m_phi,
            action_volume,
            psi,
            scores,
            certified_steps,
            accounting,
            schedule,
            constants
        )
    }

    /// The options for a variant running `algo`.
    fn for_variant(self, algo: AlgoName) -> RunSpec {
        let sepg = !matches!(
            algo,
            AlgoName::GpomdpConst | AlgoName::GpomdpAdam | AlgoName::Adastep
        );
        RunSpec {
            w_step: self.w_step.filter(|_| sepg),
            w_direction: self.w_direction.filter(|_| sepg),
            metagradient_clip: self.metagradient_clip.filter(|_| sepg),
            confidence: self.confidence.filter(|_| sepg),
            quantile_factor: self.quantile_factor.filter(|_| sepg),
            lb1_requirement: self.lb1_requirement.filter(|_| algo == AlgoName::SepgLb1),
            alternating: self
                .alternating
                .filter(|_| matches!(algo, AlgoName::SepgMi | AlgoName::SepgLb1)),
            reference_batch: self.reference_batch.filter(|_| sepg),
            baseline_fit: self.baseline_fit,
            gamma: self.gamma,
            r_max: self.r_max,
            m_phi: self.m_phi,
            action_volume: self.action_volume,
            psi: self.psi,
            scores: self.scores,
            certified_steps: self.certified_steps.filter(|_| sepg),
            accounting: self.accounting.filter(|_| sepg),
            schedule: self.schedule.filter(|_| sepg),
            constants: self.constants,
            ..RunSpec::default()
        }
    }
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
    /// The named choice of algorithm options.
    pub setting: Setting,
    /// Options overriding the setting's.
    pub flags: OptionFlags,
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
            delta: sepg_algo::DEFAULT_DELTA,
            fig_sigma0: 1.0,
            setting: Setting::Default,
            flags: OptionFlags::default(),
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
        (_, Some(preset)) => vec![preset.preset()],
        (_, None) => LqgPreset::ALL.map(LqgPreset::preset).to_vec(),
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
    let flags = opts.flags.over(opts.setting.options());
    let variant = variant
        .into_iter()
        .map(|v| match v.algo {
            Some(algo) => flags.for_variant(algo).overlay(&v),
            None => v,
        })
        .collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The potion-literal setting reaches the SEPG variants (alternating and LB-I's full
    /// requirement only where they apply), the baseline fit and ψ reach every variant, and a
    /// flag overrides the setting.
    #[test]
    fn settings_reach_the_variants_they_apply_to() {
        let opts = ReproduceOptions {
            setting: Setting::PotionLiteral,
            flags: OptionFlags {
                confidence: Some(ConfidenceName::StudentT),
                ..OptionFlags::default()
            },
            ..ReproduceOptions::new(Experiment::Table51)
        };
        let spec = sweep_spec(&opts).expect("valid");
        let by_name = |n: &str| {
            spec.variant
                .iter()
                .find(|v| v.name.as_deref() == Some(n))
                .expect("variant")
        };
        let (lb1, zv, adam) = (by_name("lb1"), by_name("zv"), by_name("adam-1e-4"));
        assert_eq!(lb1.alternating, Some(true));
        assert_eq!(lb1.lb1_requirement, Some(Lb1Name::Full));
        assert_eq!(zv.alternating, None);
        assert_eq!(zv.w_direction, Some(WDirectionName::Metagradient));
        assert_eq!(zv.confidence, Some(ConfidenceName::StudentT));
        assert_eq!(adam.w_direction, None);
        assert_eq!(adam.baseline_fit, Some(FitName::PlugIn));
        assert_eq!((lb1.psi, adam.psi), (Some(0.53), Some(0.53)));
        assert_eq!(adam.scores, Some(ScoresName::Clipped));
        let (_, resolved) = crate::sweep::expand(&spec, crate::sweep::Shard { index: 0, count: 1 })
            .expect("every run resolves");
        assert_eq!(resolved.len(), 880);
        let default = sweep_spec(&ReproduceOptions::new(Experiment::Table51)).expect("valid");
        assert!(default.variant.iter().all(|v| v.w_direction.is_none()));
        assert!(default.variant.iter().all(|v| v.psi.is_none()));
    }

    /// The thesis-code setting fixes no confidence, no reference batch, ψ = 0.53, clipped
    /// scores and the plug-in w-direction for every SEPG variant, and nothing that applies to
    /// MI/LB-I only.
    #[test]
    fn thesis_code_setting_fixes_its_options() {
        let opts = ReproduceOptions {
            setting: Setting::ThesisCode,
            ..ReproduceOptions::new(Experiment::Table51)
        };
        let spec = sweep_spec(&opts).expect("valid");
        for v in spec.variant.iter().filter(|v| {
            matches!(
                v.algo,
                Some(AlgoName::SepgMi | AlgoName::SepgLb1 | AlgoName::SepgZv)
            )
        }) {
            assert_eq!(v.confidence, Some(ConfidenceName::None));
            assert_eq!(v.w_direction, Some(WDirectionName::PlugIn));
            assert_eq!((v.reference_batch, v.psi), (Some(0), Some(0.53)));
            assert_eq!(v.scores, Some(ScoresName::Clipped));
            assert_eq!((v.alternating, v.lb1_requirement), (None, None));
        }
    }

    /// The thesis's settings keep the thesis's constants for every variant; the default
    /// setting leaves the key to the runs' default (tight), and `--constants` overrides both.
    #[test]
    fn thesis_settings_keep_the_thesis_constants_and_the_default_takes_tight() {
        let one = crate::sweep::Shard { index: 0, count: 1 };
        for setting in [
            Setting::ThesisCode,
            Setting::PotionLiteral,
            Setting::NoConfidence,
        ] {
            let opts = ReproduceOptions {
                setting,
                preset: Some(LqgPreset::Lqg1d),
                seeds: 1,
                ..ReproduceOptions::new(Experiment::Table51)
            };
            let spec = sweep_spec(&opts).expect("valid");
            assert!(
                spec.variant
                    .iter()
                    .all(|v| v.constants == Some(ConstantsName::Thesis))
            );
            let (_, resolved) = crate::sweep::expand(&spec, one).expect("resolves");
            assert!(
                resolved
                    .iter()
                    .all(|r| r.checked.constants().family()
                        == sepg_bounds::penalties::Family::Thesis)
            );
        }
        let default = ReproduceOptions {
            preset: Some(LqgPreset::Lqg1d),
            seeds: 1,
            ..ReproduceOptions::new(Experiment::Table51)
        };
        let spec = sweep_spec(&default).expect("valid");
        assert!(spec.variant.iter().all(|v| v.constants.is_none()));
        let (_, resolved) = crate::sweep::expand(&spec, one).expect("resolves");
        let tight = sepg_bounds::penalties::Family::Tight(sepg_bounds::penalties::Tight::new(
            sepg_bounds::penalties::Horizon::Finite(20),
            sepg_bounds::penalties::Rewards::NonPositive,
        ));
        assert!(
            resolved
                .iter()
                .all(|r| r.checked.constants().family() == tight)
        );
        let thesis = ReproduceOptions {
            flags: OptionFlags {
                constants: Some(ConstantsName::Thesis),
                ..OptionFlags::default()
            },
            ..default
        };
        let spec = sweep_spec(&thesis).expect("valid");
        assert!(
            spec.variant
                .iter()
                .all(|v| v.constants == Some(ConstantsName::Thesis))
        );
    }
}
