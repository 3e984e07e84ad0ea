//! Robustness properties of the library crates: every public function of `sepg-bounds`, of
//! `sepg-estimators` (through small [`Batch`]es of arbitrary shape and content) and the
//! constructors, exact oracles and policy of `sepg-mdp`, fed arbitrary `f64` (NaN, ±∞,
//! subnormals, ±0, huge, negative), returns a typed error or finite values, and never panics.
//!
//! Inputs are decoded from raw bytes by [`Source`]: each number is, by its selector byte, a
//! value from [`SPECIAL`] (the IEEE-754 edge cases and the domain boundaries of the thesis's
//! parameters), a moderate value (a 16-bit integer / 256), or any of the 2⁶⁴ bit patterns.
//! The same case functions ([`bounds_case`], [`estimators_case`], [`mdp_case`]) are run by
//! `proptest!` here and by the libFuzzer targets of `fuzz/` (see docs/RELIABILITY.md), which
//! include this file.

use std::fmt::Debug;

use sepg_bounds::budget::{Budget, split_requirement};
use sepg_bounds::constants::{self, TaskConstants};
use sepg_bounds::high_probability::{self, CorrectedNorm, HighProbabilityBound, HpForm};
use sepg_bounds::outcome::{SafeInterval, StepOutcome};
use sepg_bounds::papini::GreedyStep;
use sepg_bounds::pirotta::AdaptiveStep;
use sepg_bounds::{batch_size, greedy, papini, pirotta, rigorous, surrogate, v_update, w_update};
use sepg_estimators::{
    Baseline, BaselineFit, Confidence, Estimate, Estimator, GradientSpec, Kind, Param,
    SurrogateEstimate, Width, normal_quantile, student_t_quantile, width,
};
use sepg_mdp::Batch;
use sepg_mdp::env::{Environment, LqgEnv};
use sepg_mdp::features::{FeatureMap, RbfGrid};
use sepg_mdp::lqg_model::{BoxBounds, LqgModel};
use sepg_mdp::monte_carlo::{McEstimate, summarize};
use sepg_mdp::mountain_car::MountainCar;
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, DpConfig, ExactEval, ExactOracle, Exploration, Horizon,
};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::{SeedKey, rng_from_seed};
use sepg_mdp::rollout::{rollout, rollout_returns};

/// Edge cases every number may take: IEEE-754 specials and the boundaries of the domains of
/// γ, σ, δ, ν, probabilities and degrees of freedom.
pub const SPECIAL: [f64; 32] = [
    0.0,
    -0.0,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::MIN_POSITIVE,
    -f64::MIN_POSITIVE,
    5e-324,
    -5e-324,
    2.2e-308,
    f64::MAX,
    f64::MIN,
    f64::EPSILON,
    1.0,
    -1.0,
    0.5,
    0.999_999_999_999_999_9,
    1.000_000_000_000_000_2,
    0.99,
    2.0,
    -2.0,
    1e-300,
    -1e-300,
    1e300,
    -1e300,
    1e154,
    -1e154,
    1e-154,
    354.0,
    -354.0,
    709.8,
    1e16,
];

/// A reader of fuzz bytes; past the end every read returns zero-like values.
#[derive(Debug)]
pub struct Source<'a> {
    bytes: &'a [u8],
}

impl<'a> Source<'a> {
    /// Reads from `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Source { bytes }
    }

    fn byte(&mut self) -> u8 {
        match self.bytes.split_first() {
            Some((b, rest)) => {
                self.bytes = rest;
                *b
            }
            None => 0,
        }
    }

    /// An `f64`: a special value, a moderate value, or any bit pattern.
    pub fn f64(&mut self) -> f64 {
        let sel = self.byte();
        match sel % 4 {
            0 => SPECIAL[usize::from(sel / 4) % SPECIAL.len()],
            1 => f64::from(i16::from_le_bytes([self.byte(), self.byte()])) / 256.0,
            _ => {
                let mut b = [0u8; 8];
                for x in &mut b {
                    *x = self.byte();
                }
                f64::from_bits(u64::from_le_bytes(b))
            }
        }
    }

    /// An integer in `0..=max`.
    pub fn small(&mut self, max: usize) -> usize {
        usize::from(self.byte()) % (max + 1)
    }

    /// A boolean.
    pub fn flag(&mut self) -> bool {
        self.byte() & 1 == 1
    }

    /// A vector of `0..=max_len` numbers.
    pub fn vec(&mut self, max_len: usize) -> Vec<f64> {
        let n = self.small(max_len);
        (0..n).map(|_| self.f64()).collect()
    }

    /// A `u64` from eight bytes.
    pub fn u64(&mut self) -> u64 {
        let mut b = [0u8; 8];
        for x in &mut b {
            *x = self.byte();
        }
        u64::from_le_bytes(b)
    }
}

/// Values whose every number must be finite when a function returns them.
pub trait AllFinite {
    /// Whether every number in the value is finite.
    fn all_finite(&self) -> bool;
}

impl AllFinite for f64 {
    fn all_finite(&self) -> bool {
        self.is_finite()
    }
}

impl AllFinite for u64 {
    fn all_finite(&self) -> bool {
        true
    }
}

impl AllFinite for usize {
    fn all_finite(&self) -> bool {
        true
    }
}

impl AllFinite for () {
    fn all_finite(&self) -> bool {
        true
    }
}

impl<T: AllFinite> AllFinite for [T] {
    fn all_finite(&self) -> bool {
        self.iter().all(AllFinite::all_finite)
    }
}

impl<T: AllFinite> AllFinite for Vec<T> {
    fn all_finite(&self) -> bool {
        self.as_slice().all_finite()
    }
}

impl<T: AllFinite> AllFinite for Option<T> {
    fn all_finite(&self) -> bool {
        self.as_ref().is_none_or(AllFinite::all_finite)
    }
}

impl<A: AllFinite, B: AllFinite> AllFinite for (A, B) {
    fn all_finite(&self) -> bool {
        self.0.all_finite() && self.1.all_finite()
    }
}

impl AllFinite for SafeInterval {
    fn all_finite(&self) -> bool {
        [self.c_max, self.vertex, self.lo, self.hi].all_finite()
            && self.lambda.all_finite()
            && self.lo <= self.hi
            && self.contains(self.lo)
            && self.largest().is_finite()
    }
}

impl AllFinite for StepOutcome {
    fn all_finite(&self) -> bool {
        let fields = match self {
            StepOutcome::Feasible(s) => s.all_finite(),
            StepOutcome::Infeasible { c_max, vertex } => [*c_max, *vertex].all_finite(),
            StepOutcome::ZeroGradient { .. } | StepOutcome::BelowNoise => true,
        };
        let _ = self.is_feasible();
        fields && self.chosen_step().all_finite() && self.c_max().all_finite()
    }
}

impl AllFinite for AdaptiveStep {
    fn all_finite(&self) -> bool {
        match self {
            AdaptiveStep::Step { alpha, guarantee } => [*alpha, *guarantee].all_finite(),
            AdaptiveStep::ZeroGradient | AdaptiveStep::BelowNoise => true,
        }
    }
}

impl AllFinite for GreedyStep {
    fn all_finite(&self) -> bool {
        [self.alpha, self.guarantee].all_finite() && self.steps.all_finite()
    }
}

impl AllFinite for greedy::CoordinateStep {
    fn all_finite(&self) -> bool {
        self.outcome.all_finite()
    }
}

impl AllFinite for CorrectedNorm {
    fn all_finite(&self) -> bool {
        [self.lower, self.upper].all_finite()
    }
}

impl AllFinite for HighProbabilityBound {
    fn all_finite(&self) -> bool {
        [
            self.direction,
            self.linear_lower,
            self.linear_upper,
            self.quadratic,
            self.vertex(),
            self.c_max(),
        ]
        .all_finite()
    }
}

impl AllFinite for Estimate {
    fn all_finite(&self) -> bool {
        self.mean().all_finite()
            && self.samples().all_finite()
            && self.variance().all_finite()
            && self.norm_inf().is_finite()
            && self.samples().len() == self.n() * self.dim()
            && (0..self.n()).all(|i| self.sample(i).is_some_and(AllFinite::all_finite))
    }
}

impl AllFinite for Confidence {
    fn all_finite(&self) -> bool {
        let _ = self.above_noise();
        [self.norm_inf, self.eps, self.lower(), self.upper()].all_finite()
    }
}

impl AllFinite for SurrogateEstimate {
    fn all_finite(&self) -> bool {
        self.grad_w_l().all_finite()
            && self.grad_v().all_finite()
            && self.mixed().all_finite()
            && self.surrogate().is_finite()
    }
}

impl AllFinite for McEstimate {
    fn all_finite(&self) -> bool {
        [
            self.mean,
            self.std_error,
            self.ci_low,
            self.ci_high,
            self.level,
            self.half_width(),
        ]
        .all_finite()
    }
}

impl AllFinite for ExactEval {
    fn all_finite(&self) -> bool {
        self.j.is_finite()
            && self.grad_v.all_finite()
            && self.grad_w.all_finite()
            && self.mixed_wv.all_finite()
            && self.sigma.all_finite()
            && self
                .hessian
                .as_ref()
                .is_none_or(|h| h.iter().all(|x| x.is_finite()))
            && self.grad_sigma().all_finite()
            && self.mixed_sigma_v().all_finite()
    }
}

impl AllFinite for Batch {
    fn all_finite(&self) -> bool {
        self.disc_rewards.all_finite()
            && self.cum_score_v.all_finite()
            && self.cum_score_w.all_finite()
            && self.sigma.all_finite()
    }
}

/// Passes an `Ok` value through after asserting that it is finite (the invariant of every
/// public function: a typed error, or a value without NaN or ±∞). `case` is shown on failure.
#[track_caller]
pub fn ok<T: AllFinite + Debug, E>(
    case: &dyn Debug,
    name: &str,
    result: Result<T, E>,
) -> Option<T> {
    let value = result.ok()?;
    assert!(
        value.all_finite(),
        "{name} returned a non-finite value {value:?} for {case:?}"
    );
    Some(value)
}

/// The inputs of one `sepg-bounds` case.
#[derive(Debug, Clone)]
pub struct BoundsCase {
    /// (γ, R, M_φ, |A|) of [`TaskConstants::new`].
    pub task: [f64; 4],
    /// σ.
    pub sigma: f64,
    /// Scalar arguments (steps, requirements, widths, gradients, ν, δ, ...).
    pub s: [f64; 8],
    /// Gradient-like vectors of arbitrary (possibly different, possibly zero) lengths.
    pub x: Vec<f64>,
    /// Second vector (widths, steps, h, ∇_w J).
    pub y: Vec<f64>,
    /// Third vector (∇_w L).
    pub z: Vec<f64>,
    /// Horizon H of the batch-size bounds.
    pub horizon: u32,
}

impl BoundsCase {
    /// Decodes a case.
    pub fn decode(src: &mut Source<'_>) -> Self {
        let task = [src.f64(), src.f64(), src.f64(), src.f64()];
        let sigma = src.f64();
        let mut s = [0.0; 8];
        for x in &mut s {
            *x = src.f64();
        }
        let x = src.vec(6);
        let y = if src.flag() {
            x.iter().map(|_| src.f64()).collect()
        } else {
            src.vec(6)
        };
        let z = if src.flag() {
            y.iter().map(|_| src.f64()).collect()
        } else {
            src.vec(6)
        };
        // The batch-size bounds take O(H) time: H is kept below 2^16 (u32::MAX costs seconds).
        let horizon = match src.small(7) {
            0 => 0,
            1 => u32::from(u16::MAX),
            _ => u32::from(src.byte()),
        };
        BoundsCase {
            task,
            sigma,
            s,
            x,
            y,
            z,
            horizon,
        }
    }
}

/// Calls every public function of `sepg-bounds` on `c`.
pub fn bounds_case(c: &BoundsCase) {
    let [g, r, m, a] = c.task;
    let fallback = TaskConstants::new(0.9, 1.0, 1.0, 2.0).expect("valid constants");
    let k = TaskConstants::new(g, r, m, a).unwrap_or(fallback);
    for x in [k.gamma(), k.r_max(), k.m_phi(), k.action_volume()] {
        assert!(
            x.is_finite(),
            "TaskConstants holds a non-finite value for {c:?}"
        );
    }
    let (sg, s, x, y, z) = (
        c.sigma,
        &c.s,
        c.x.as_slice(),
        c.y.as_slice(),
        c.z.as_slice(),
    );
    assert!(constants::psi().is_finite());
    ok(c, "c", constants::c(&k, sg));
    ok(c, "dc_dsigma", constants::dc_dsigma(&k, sg));
    ok(c, "d", constants::d(&k, sg));

    ok(c, "pirotta::bound", pirotta::bound(&k, sg, x, s[0]));
    ok(c, "pirotta::optimal_step", pirotta::optimal_step(&k, sg, x));
    ok(
        c,
        "pirotta::hp_bound",
        pirotta::hp_bound(&k, sg, x, y, s[0]),
    );
    ok(
        c,
        "pirotta::hp_optimal_step",
        pirotta::hp_optimal_step(&k, sg, x, y),
    );
    ok(c, "papini::bound", papini::bound(&k, sg, x, y));
    ok(c, "papini::greedy_step", papini::greedy_step(&k, sg, x));
    let horizon = c.horizon;
    ok(
        c,
        "batch_size::reinforce",
        batch_size::reinforce(&k, sg, s[0], s[1], horizon),
    );
    ok(
        c,
        "batch_size::gpomdp",
        batch_size::gpomdp(&k, sg, s[0], s[1], horizon),
    );

    ok(c, "v_update::alpha_star", v_update::alpha_star(&k, sg));
    ok(c, "v_update::c_max", v_update::c_max(&k, sg, x));
    ok(c, "v_update::bound", v_update::bound(&k, sg, x, s[0]));
    ok(
        c,
        "v_update::safe_step",
        v_update::safe_step(&k, sg, x, s[1]),
    );

    ok(c, "w_update::beta_star", w_update::beta_star(&k, sg));
    ok(c, "w_update::c_max", w_update::c_max(&k, sg, s[0]));
    ok(
        c,
        "w_update::bound_along_j",
        w_update::bound_along_j(&k, sg, s[0], s[1]),
    );
    ok(
        c,
        "w_update::safe_step_along_j",
        w_update::safe_step_along_j(&k, sg, s[0], s[1]),
    );
    ok(
        c,
        "w_update::bound_along_l",
        w_update::bound_along_l(&k, sg, s[0], s[1], s[2]),
    );
    ok(
        c,
        "w_update::beta_tilde",
        w_update::beta_tilde(&k, sg, s[0], s[1]),
    );
    ok(
        c,
        "w_update::safe_step_along_l",
        w_update::safe_step_along_l(&k, sg, s[0], s[1], s[2]),
    );

    ok(c, "surrogate::surrogate", surrogate::surrogate(&k, sg, x));
    ok(
        c,
        "surrogate::mixed_from_h",
        surrogate::mixed_from_h(x, y, sg),
    );
    ok(
        c,
        "surrogate::grad_sigma",
        surrogate::grad_sigma(&k, sg, x, y),
    );
    ok(c, "surrogate::grad_w", surrogate::grad_w(&k, sg, x, y));

    ok(
        c,
        "corrected_norm",
        high_probability::corrected_norm(x, s[0]),
    );
    let bounds = [
        HighProbabilityBound::v_update(&k, sg, x, s[0]),
        HighProbabilityBound::w_along_j(&k, sg, s[0], s[1]),
        HighProbabilityBound::w_along_l(&k, sg, s[0], s[1], s[2], s[3]),
    ];
    for b in bounds {
        if let Some(Some(b)) = ok(c, "HighProbabilityBound", b) {
            ok(c, "HighProbabilityBound::value", b.value(s[4]));
            ok(
                c,
                "HighProbabilityBound::sign_aware_value",
                b.sign_aware_value(s[4]),
            );
            for form in [HpForm::Thesis, HpForm::SignAware] {
                ok(
                    c,
                    "HighProbabilityBound::safe_step",
                    b.safe_step(s[5], form),
                );
            }
        }
    }
    for form in [HpForm::Thesis, HpForm::SignAware] {
        ok(
            c,
            "v_safe_step",
            high_probability::v_safe_step(&k, sg, x, s[0], s[1], form),
        );
        ok(
            c,
            "w_safe_step_along_j",
            high_probability::w_safe_step_along_j(&k, sg, s[0], s[1], s[2], form),
        );
        ok(
            c,
            "w_safe_step_along_l",
            high_probability::w_safe_step_along_l(&k, sg, s[0], s[1], s[2], s[3], s[4], form),
        );
    }

    ok(c, "greedy::argmax_abs", greedy::argmax_abs(x));
    ok(
        c,
        "greedy::coordinate_update",
        greedy::coordinate_update(x, y, s[0]),
    );
    ok(c, "greedy::v_step", greedy::v_step(&k, sg, x, s[0]));
    ok(c, "greedy::w_step", greedy::w_step(&k, x, y, z, s[0]));

    ok(c, "rigorous::kl2", rigorous::kl2(s[0]));
    ok(c, "rigorous::bound", rigorous::bound(&k, sg, s[0], s[1]));
    ok(
        c,
        "rigorous::thesis_bound",
        rigorous::thesis_bound(&k, sg, s[0], s[1]),
    );
    ok(c, "rigorous::gap", rigorous::gap(&k, sg, s[0]));
    ok(
        c,
        "rigorous::safe_delta_w",
        rigorous::safe_delta_w(&k, sg, s[0], s[1]),
    );
    ok(
        c,
        "rigorous::safe_step_along_j",
        rigorous::safe_step_along_j(&k, sg, s[0], s[1]),
    );
    ok(
        c,
        "rigorous::safe_step_along_l",
        rigorous::safe_step_along_l(&k, sg, s[0], s[1], s[2]),
    );

    ok(c, "split_requirement", split_requirement(s[0], s[1]));
    let target = (s[2] > 0.0).then_some(s[3]);
    if let Ok(mut b) = Budget::new(s[0], s[1], target) {
        let _ = b.add_exploratory_difference(s[4]);
        let _ = b.add_target_difference(s[5]);
        ok(c, "Budget::record_exploratory", b.record_exploratory(s[6]));
        ok(c, "Budget::record_target", b.record_target(s[7]));
        let values = [
            b.value(),
            b.initial(),
            b.required_improvement(),
            b.baseline(),
            b.average_performance(),
            b.telescoped_change(),
            b.guaranteed_average(),
        ];
        assert!(
            values.all_finite(),
            "Budget holds a non-finite value {values:?} for {c:?}"
        );
        let _ = b.is_type_two_safe();
    }
}

/// The inputs of one `sepg-estimators` case.
#[derive(Debug, Clone)]
pub struct EstimatorsCase {
    /// The batch (shape fields and buffers may disagree).
    pub batch: Batch,
    /// Confidence δ, range of Hoeffding/Bernstein, c, ∂c/∂σ, p, ν, variance.
    pub s: [f64; 7],
    /// Task constants (γ, R, M_φ, |A|) of the surrogate gradient.
    pub task: [f64; 4],
    /// A sample count of `width`.
    pub n: usize,
}

impl EstimatorsCase {
    /// Decodes a case: a batch of up to 6 trajectories, 4 steps, 3 actions and 3 features,
    /// with consistent buffers most of the time.
    pub fn decode(src: &mut Source<'_>) -> Self {
        let n = src.small(6);
        let horizon = src.small(4);
        let dim_w = src.small(3);
        let p = src.small(3);
        let gamma = src.f64();
        let mut batch = Batch::zeros(n, horizon, dim_w * p, dim_w, gamma);
        if src.small(7) == 0 {
            batch.dim_v = src.small(5);
        }
        for buf in [
            &mut batch.sigma,
            &mut batch.disc_rewards,
            &mut batch.cum_score_v,
            &mut batch.cum_score_w,
        ] {
            match src.small(15) {
                0 => buf.clear(),
                1 => buf.push(0.5),
                _ => {}
            }
            let dense = src.flag();
            for x in buf.iter_mut() {
                *x = if dense || src.flag() { src.f64() } else { 1.0 };
            }
        }
        for l in &mut batch.lengths {
            *l = src.small(5);
        }
        let mut s = [0.0; 7];
        for x in &mut s {
            *x = src.f64();
        }
        let task = [src.f64(), src.f64(), src.f64(), src.f64()];
        let count = match src.small(3) {
            0 => usize::MAX,
            1 => src.small(3),
            _ => src.small(255),
        };
        EstimatorsCase {
            batch,
            s,
            task,
            n: count,
        }
    }
}

/// Every confidence width of Sec 4.5 with its range argument.
fn widths(range: f64) -> [Width; 4] {
    [
        Width::StudentT,
        Width::Chebyshev,
        Width::Hoeffding { range },
        Width::EmpiricalBernstein { range },
    ]
}

/// Like [`ok`] for a confidence width.
fn ok_width<T: AllFinite + Debug, E>(c: &EstimatorsCase, name: &str, result: Result<T, E>) {
    if let Ok(value) = result {
        assert!(
            value.all_finite(),
            "{name} returned a non-finite value {value:?} for {c:?}"
        );
    }
}

/// Checks an estimate and every width and corrected norm computed from it.
fn check_estimate(c: &EstimatorsCase, name: &str, result: Result<(), impl Debug>, est: &Estimate) {
    if result.is_err() {
        return;
    }
    assert!(
        est.all_finite(),
        "{name} returned a non-finite estimate {est:?} for {c:?}"
    );
    let mut eps = vec![0.0; est.dim()];
    for method in widths(c.s[1]) {
        let r = est
            .widths_into(method, c.s[0], &mut eps)
            .map(|e| (e, eps.clone()));
        ok_width(c, "Estimate::widths_into", r);
        ok_width(c, "Estimate::confidence", est.confidence(method, c.s[0]));
    }
}

/// Calls every public function of `sepg-estimators` on `c`.
pub fn estimators_case(c: &EstimatorsCase) {
    let s = &c.s;
    ok(c, "normal_quantile", normal_quantile(s[4]));
    if let Ok(t) = student_t_quantile(s[4], s[5]) {
        assert!(t.is_finite(), "student_t_quantile returned {t} for {c:?}");
    }
    for method in widths(s[1]) {
        ok_width(c, "width", width(method, s[6], c.n, s[0]));
    }
    let batch = &c.batch;
    let mut estimator = Estimator::new();
    let mut est = Estimate::new();
    let r = estimator.value(batch, &mut est);
    check_estimate(c, "Estimator::value", r, &est);
    let kinds = [Kind::Reinforce, Kind::Gpomdp, Kind::Pgt];
    let baselines = [Baseline::None, Baseline::Mean, Baseline::Optimal];
    let fits = [BaselineFit::PlugIn, BaselineFit::LeaveOneOut];
    for fit in fits {
        for baseline in baselines {
            let r = estimator.h(batch, baseline, fit, &mut est);
            check_estimate(c, "Estimator::h", r, &est);
            for kind in kinds {
                let spec = GradientSpec {
                    kind,
                    baseline,
                    fit,
                };
                for param in [Param::V, Param::W] {
                    let r = estimator.gradient(batch, param, spec, &mut est);
                    check_estimate(c, "Estimator::gradient", r, &est);
                }
                let r = estimator.mixed(batch, spec, &mut est);
                check_estimate(c, "Estimator::mixed", r, &est);
                let mut out = SurrogateEstimate::new();
                let dc = vec![s[3]; batch.dim_w];
                let r = estimator.surrogate_gradient(batch, spec, s[2], &dc, &mut out);
                ok(c, "Estimator::surrogate_gradient", r.map(|()| out.clone()));
                let [g, rm, m, a] = c.task;
                if let Ok(k) = TaskConstants::new(g, rm, m, a) {
                    let r = estimator.surrogate_gradient_for_task(batch, spec, &k, &mut out);
                    ok(
                        c,
                        "Estimator::surrogate_gradient_for_task",
                        r.map(|()| out.clone()),
                    );
                }
            }
        }
    }
}

/// The inputs of one `sepg-mdp` case.
#[derive(Debug, Clone)]
pub struct MdpCase {
    /// Scalar model coefficients (A, B, Q, R, box bound, γ, noise).
    pub model: [f64; 7],
    /// Policy mean parameters.
    pub v: Vec<f64>,
    /// Policy log standard deviations.
    pub w: Vec<f64>,
    /// Features φ(s) / states / grid bounds.
    pub phi: Vec<f64>,
    /// Actions.
    pub a: Vec<f64>,
    /// Number of features of the policy.
    pub features: usize,
    /// Finite horizon of the oracles and rollouts (0 = infinite for the closed form).
    pub horizon: usize,
    /// Clipping of the scalar model.
    pub clipping: bool,
    /// Monte Carlo samples and confidence level.
    pub samples: Vec<f64>,
    /// Confidence level of `summarize`.
    pub level: f64,
    /// Seed of the policy sampler and rollouts.
    pub seed: u64,
    /// Grid sizes of an RBF map.
    pub grid: [usize; 2],
    /// Whether to run the (slower) clipped dynamic programme.
    pub run_dp: bool,
}

impl MdpCase {
    /// Decodes a case.
    pub fn decode(src: &mut Source<'_>) -> Self {
        let mut model = [0.0; 7];
        for x in &mut model {
            *x = src.f64();
        }
        MdpCase {
            model,
            v: src.vec(4),
            w: src.vec(2),
            phi: src.vec(4),
            a: src.vec(2),
            features: src.small(3),
            horizon: src.small(4),
            clipping: src.flag(),
            samples: src.vec(5),
            level: src.f64(),
            seed: src.u64(),
            grid: [src.small(4), src.small(4)],
            run_dp: src.small(7) == 0,
        }
    }
}

/// Calls the constructors, exact oracles and policy functions of `sepg-mdp` on `c`.
pub fn mdp_case(c: &MdpCase) {
    policy_case(c);
    features_case(c);
    ok(c, "summarize", summarize(&c.samples, c.level));
    let [a, b, q, r, bound, gamma, noise] = c.model;
    let model = LqgModel::scalar(a, b, q, r, bound)
        .and_then(|m| m.with_gamma(gamma))
        .and_then(|m| m.with_noise(nalgebra::DVector::from_element(1, noise)))
        .map(|m| m.with_clipping(c.clipping));
    if let Ok(model) = &model {
        ok(c, "LqgModel::validate", model.validate());
        ok(
            c,
            "LqgModel::constants",
            Ok::<_, ()>(vec![model.r_max(), model.m_phi(), model.action_volume()]),
        );
        if let Ok(env) = LqgEnv::new(model.clone()).and_then(|e| e.with_horizon(c.horizon)) {
            let k = env.constants();
            let values = vec![k.r_max, k.m_phi, k.action_volume, k.gamma];
            ok(c, "LqgEnv::constants", Ok::<_, ()>(values));
            rollout_case(c, &env);
        }
    }
    let general = LqgModel::new(
        nalgebra::DMatrix::from_element(1, 1, a),
        nalgebra::DMatrix::from_row_slice(1, 2, &[b, q]),
        nalgebra::DMatrix::from_element(1, 1, r),
        nalgebra::DMatrix::from_row_slice(2, 2, &[1.0, noise, noise, 1.0]),
        BoxBounds::cube(1, -bound, bound),
        BoxBounds::cube(2, -bound, gamma),
        BoxBounds::cube(1, -bound.abs() / 2.0, bound.abs() / 2.0),
    );
    let preset = LqgModel::thesis().with_clipping(c.clipping);
    for model in [model.ok(), general.ok(), Some(preset)]
        .into_iter()
        .flatten()
    {
        oracle_case(c, &model);
    }
}

fn exploration(c: &MdpCase) -> Exploration {
    if c.w.is_empty() {
        Exploration::Deterministic
    } else {
        Exploration::Gaussian { w: c.w.clone() }
    }
}

fn oracle_case(c: &MdpCase, model: &LqgModel) {
    let horizon = if c.horizon == 0 {
        Horizon::Infinite
    } else {
        Horizon::Finite(c.horizon)
    };
    if let Ok(oracle) = ClosedFormOracle::new(model) {
        ok(
            c,
            "ClosedFormOracle::evaluate",
            oracle.evaluate(&c.v, &exploration(c), horizon),
        );
        ok(
            c,
            "ClosedFormOracle::scaled_spectral_radius",
            oracle.scaled_spectral_radius(&c.v),
        );
        ok(
            c,
            "optimal_gain",
            oracle.optimal_gain().map(|g| (g.v, g.j_deterministic)),
        );
        let policy = GaussianPolicy::new(c.v.clone(), c.w.clone(), c.features.max(1));
        if let Ok(policy) = policy {
            ok(
                c,
                "ClosedFormOracle::evaluate_policy",
                oracle.evaluate_policy(&policy, horizon),
            );
        }
    }
    if c.run_dp {
        let config = DpConfig {
            max_elements: 64,
            ..DpConfig::default()
        };
        if let Ok(oracle) = ClippedDpOracle::with_config(model, config) {
            let _ = oracle.config();
            ok(
                c,
                "ClippedDpOracle::evaluate",
                oracle.evaluate(&c.v, &exploration(c), horizon),
            );
        }
    }
}

fn policy_case(c: &MdpCase) {
    let features = c.features;
    let mut policies = Vec::new();
    policies.extend(GaussianPolicy::new(c.v.clone(), c.w.clone(), features).ok());
    policies.extend(GaussianPolicy::deterministic(c.v.clone(), c.w.len(), features).ok());
    if let (Some(&v), Some(&w)) = (c.v.first(), c.w.first()) {
        policies.extend(GaussianPolicy::scalar(v, w).ok());
    }
    let mut rng = rng_from_seed(c.seed);
    for p in policies {
        let d = p.to_deterministic();
        for p in [p, d] {
            let params = [
                p.v().to_vec(),
                p.w().map(<[f64]>::to_vec).unwrap_or_default(),
            ];
            assert!(
                params.iter().all(|x| x.all_finite()),
                "policy holds non-finite values for {c:?}"
            );
            assert!(p.sigma().is_none_or(|s| s.all_finite()));
            let _ = (
                p.exploration(),
                p.is_deterministic(),
                p.feature_dim(),
                p.dim_w(),
            );
            let mut mu = vec![0.0; p.action_dim()];
            ok(
                c,
                "GaussianPolicy::mean",
                p.mean(&c.phi, &mut mu).map(|()| mu.clone()),
            );
            ok(
                c,
                "GaussianPolicy::log_density",
                p.log_density(&c.phi, &c.a),
            );
            let mut sv = vec![0.0; p.dim_v()];
            ok(
                c,
                "GaussianPolicy::score_v",
                p.score_v(&c.phi, &c.a, &mut sv).map(|()| sv.clone()),
            );
            let mut sw = vec![0.0; p.action_dim()];
            ok(
                c,
                "GaussianPolicy::score_w",
                p.score_w(&c.phi, &c.a, &mut sw).map(|()| sw.clone()),
            );
            ok(
                c,
                "GaussianPolicy::sample",
                p.sample(&c.phi, &mut rng, &mut mu).map(|()| mu.clone()),
            );
        }
    }
}

fn features_case(c: &MdpCase) {
    let dim = c.phi.len() / 2;
    let (low, high) = c.phi.split_at(dim);
    let high = &high[..dim];
    if let Ok(grid) = RbfGrid::new(low, high, &c.grid[..dim.min(2)], c.clipping) {
        let _ = (grid.len(), grid.is_empty());
        assert!(
            grid.centres().all_finite(),
            "RBF centres not finite for {c:?}"
        );
        let map = FeatureMap::Rbf(grid);
        let mut out = vec![0.0; map.dim()];
        ok(
            c,
            "FeatureMap::eval",
            map.eval(&c.a, &mut out).map(|()| out.clone()),
        );
        assert!(map.m_phi(low, high).is_finite());
    }
    for map in [
        FeatureMap::Identity { dim: c.a.len() },
        FeatureMap::StateBias { dim: c.a.len() },
    ] {
        let mut out = vec![0.0; map.dim()];
        ok(
            c,
            "FeatureMap::eval",
            map.eval(&c.a, &mut out).map(|()| out.clone()),
        );
    }
    if let Ok(car) = MountainCar::rbf([c.grid[0], c.grid[1]], c.clipping) {
        let car = car.with_gamma(c.level);
        if let Ok(car) = car {
            let k = car.constants();
            assert!([k.r_max, k.m_phi, k.action_volume, k.gamma].all_finite());
            let _ = car.feature_map();
        }
    }
}

fn rollout_case(c: &MdpCase, env: &LqgEnv) {
    let policy = match (c.v.first(), c.w.first()) {
        (Some(&v), Some(&w)) => GaussianPolicy::scalar(v, w),
        (Some(&v), None) => GaussianPolicy::deterministic(vec![v], 1, 1),
        _ => return,
    };
    let Ok(policy) = policy else { return };
    let key = SeedKey::new(c.seed, 0, 0);
    let n = c.samples.len();
    let horizon = c.horizon;
    ok(c, "rollout", rollout(env, &policy, n, horizon, key));
    ok(
        c,
        "rollout_returns",
        rollout_returns(env, &policy, n, horizon, key),
    );
}

#[cfg(test)]
mod properties {
    use proptest::prelude::*;
    use proptest::test_runner::RngSeed;

    use super::*;

    /// Bytes long enough for every field of a case, so that the tail is rarely all-zero.
    fn bytes() -> impl Strategy<Value = Vec<u8>> {
        prop::collection::vec(any::<u8>(), 0..600)
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 3000,
            rng_seed: RngSeed::Fixed(0x0b_05e),
            ..ProptestConfig::default()
        })]

        #[test]
        fn bounds_never_panic_nor_leak_non_finite_values(b in bytes()) {
            bounds_case(&BoundsCase::decode(&mut Source::new(&b)));
        }

        #[test]
        fn estimators_never_panic_nor_leak_non_finite_values(b in bytes()) {
            estimators_case(&EstimatorsCase::decode(&mut Source::new(&b)));
        }

        #[test]
        fn mdp_never_panics_nor_leaks_non_finite_values(b in bytes()) {
            mdp_case(&MdpCase::decode(&mut Source::new(&b)));
        }
    }

    /// The decoder reaches every class of f64 the properties are about.
    #[test]
    fn the_decoder_produces_every_class_of_f64() {
        let mut seen = [false; 6];
        for i in 0..=255u8 {
            for j in [0u8, 7, 128, 255] {
                let bytes = [i, j, j, j, j, j, j, j, 0x80 | j];
                let x = Source::new(&bytes).f64();
                let class = if x.is_nan() {
                    0
                } else if x.is_infinite() {
                    1
                } else if x == 0.0 {
                    2
                } else if x.is_subnormal() {
                    3
                } else if x.abs() > 1e300 {
                    4
                } else if x < 0.0 {
                    5
                } else {
                    continue;
                };
                seen[class] = true;
            }
        }
        assert_eq!(
            seen, [true; 6],
            "NaN, ±inf, zero, subnormal, huge, negative"
        );
    }
}
