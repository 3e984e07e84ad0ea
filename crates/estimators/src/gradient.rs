//! Likelihood-ratio estimators of `J`, `∇_v J`, `∇_w J` and `h(θ)` from a [`Batch`]
//! (Sec 2.3.1–2.3.2, Theorem B.1), with baselines, computed by a reusable [`Estimator`].

use std::ops::Range;

use sepg_mdp::Batch;

use crate::error::EstimatorError;
use crate::estimate::Estimate;
use crate::kernel::{HMean, HOptimal, Output, Rows, Score, Sums, pgt_sample, row_sums};

/// Which policy parameter a gradient is taken with respect to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Param {
    /// The mean parameters `v` (`dim_v = l · p` components, action-major).
    V,
    /// The log-standard-deviations `w = ln σ` (`dim_w = l` components).
    W,
}

/// The likelihood-ratio estimator (Sec 2.3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// REINFORCE, eq. (2.1): `⟨(Σ_k ∇log π_k)(Σ_l γ^l r_l − b)⟩_N`.
    Reinforce,
    /// G(PO)MDP: `⟨Σ_l (Σ_{k≤l} ∇log π_k)(γ^l r_l − b_l)⟩_N`.
    Gpomdp,
    /// PGT: `⟨Σ_k ∇log π_k Σ_{l≥k} (γ^l r_l − b_l)⟩_N`, the same estimator as G(PO)MDP by the
    /// summation theorem, computed in the reward-to-go order (same baselines `b_l`).
    Pgt,
}

/// The baseline subtracted from the rewards (Sec 2.3.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Baseline {
    /// No baseline, `b = 0`.
    None,
    /// Mean baseline: the mean return (REINFORCE) or the per-step mean of `γ^t r_t`
    /// (G(PO)MDP, PGT, `ĥ`); the same for every component.
    Mean,
    /// Variance-optimal baseline, component-wise (Sec 2.3.2): `⟨S_k² R⟩/⟨S_k²⟩` for REINFORCE,
    /// `⟨S_{t,k}² γ^t r_t⟩/⟨S_{t,k}²⟩` per step for G(PO)MDP/PGT, and `b̃*_t` of Appendix B.2
    /// for `ĥ`. A zero denominator gives the baseline 0.
    Optimal,
    /// A constant `b` (reward units) fixed before sampling, subtracted from the reward of
    /// every step `t < H`, including the padding after an early termination (reward 0,
    /// cumulative scores frozen): `γ^t r_t − γ^t b` per step (G(PO)MDP, PGT, `ĥ`) and
    /// `R − b Σ_{t<H} γ^t` for REINFORCE. It is not fitted (`fit` is ignored), so the
    /// per-trajectory samples are i.i.d. and the estimator is exactly unbiased: the
    /// cumulative score stopped at termination is a martingale, `E[Σ_t γ^t b S_t] = 0`.
    /// Subtracting `b` on the live steps only would not be: `E[Σ_{t<L} γ^t S_t]` is the
    /// gradient of the expected discounted length. This is the centre of the proven widths
    /// of [`crate::proven`] (docs/THEOREMS.md, "Proven confidence widths"). `b` must be finite.
    Constant(f64),
}

/// How a baseline is fitted from the batch.
///
/// A baseline fitted on the same trajectories it is applied to (plug-in, as in the thesis's
/// Algorithm 2.3) correlates with each trajectory's score and biases the estimator by
/// `O(1/N)`. The leave-one-out fit applies to trajectory `i` the baseline computed from the
/// other `N − 1` trajectories only; it is independent of trajectory `i`, so the estimator is
/// exactly unbiased, at the same cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BaselineFit {
    /// One baseline from all `N` trajectories (biased by `O(1/N)`).
    PlugIn,
    /// Trajectory `i` uses the baseline fitted on the other trajectories (unbiased).
    LeaveOneOut,
}

/// The full choice of a gradient estimator. The default is G(PO)MDP with the
/// variance-optimal per-step baseline fitted leave-one-out (unbiased, lowest variance here).
///
/// # Examples
/// ```
/// use sepg_estimators::{Baseline, BaselineFit, GradientSpec, Kind};
/// let s = GradientSpec::default();
/// assert_eq!((s.kind, s.baseline, s.fit), (Kind::Gpomdp, Baseline::Optimal, BaselineFit::LeaveOneOut));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GradientSpec {
    /// The estimator.
    pub kind: Kind,
    /// The baseline.
    pub baseline: Baseline,
    /// How the baseline is fitted.
    pub fit: BaselineFit,
}

impl Default for GradientSpec {
    fn default() -> Self {
        GradientSpec {
            kind: Kind::Gpomdp,
            baseline: Baseline::Optimal,
            fit: BaselineFit::LeaveOneOut,
        }
    }
}

/// What the internal kernel estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Target {
    Reinforce(Param),
    Gpomdp(Param),
    Pgt(Param),
    /// `ĥ` of Theorem B.1, all `dim_w × dim_v` pairs.
    H,
}

impl Target {
    pub(crate) fn gradient(kind: Kind, param: Param) -> Self {
        match kind {
            Kind::Reinforce => Target::Reinforce(param),
            Kind::Gpomdp => Target::Gpomdp(param),
            Kind::Pgt => Target::Pgt(param),
        }
    }
}

/// A reusable workspace that computes every estimator of this crate from a [`Batch`] without
/// allocating once its buffers have grown to the batch size (keep one per learner and pass
/// the same [`Estimate`]s each iteration).
///
/// All estimates are deterministic functions of the batch: the same batch gives the same bits.
///
/// # Examples
/// ```
/// use sepg_estimators::{Estimate, Estimator, GradientSpec, Param};
/// use sepg_mdp::Batch;
/// let mut batch = Batch::zeros(2, 1, 1, 1, 0.9);
/// batch.disc_rewards.copy_from_slice(&[1.0, 2.0]);
/// batch.cum_score_v.copy_from_slice(&[1.0, -1.0]);
/// let mut est = Estimate::new();
/// let mut estimator = Estimator::new();
/// estimator.gradient(&batch, Param::V, GradientSpec::default(), &mut est)?;
/// assert_eq!(est.dim(), 1);
/// # Ok::<(), sepg_estimators::EstimatorError>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct Estimator {
    /// Buffers of the baseline fit.
    sums: Sums,
    /// Per-trajectory returns (REINFORCE).
    returns: Vec<f64>,
    /// Per-step values repeated over the components of their step.
    bcast: Vec<f64>,
    /// Products `u = G H F` and control variates `z` of `ĥ`, per (trajectory, step, pair).
    h_u: Vec<f64>,
    h_z: Vec<f64>,
    /// Discounted rewards minus a constant baseline, `γ^t (r_t − b)`.
    shifted: Vec<f64>,
    /// Scratch estimates and vectors of the composite estimators.
    pub(crate) tmp_g: Estimate,
    pub(crate) vec_a: Vec<f64>,
    pub(crate) vec_b: Vec<f64>,
    pub(crate) vec_c: Vec<f64>,
    pub(crate) vec_d: Vec<f64>,
    pub(crate) vec_f: Vec<f64>,
}

/// Checks the batch layout and `σ` once per estimator call. Non-finite data is detected on
/// the outputs instead (every value an estimator uses reaches its own trajectory's sample,
/// and NaN/∞ propagate), which costs `O(N · dim)` instead of a scan of the whole batch.
pub(crate) fn validate(batch: &Batch, min_n: usize) -> Result<(), EstimatorError> {
    if batch.n == 0 || batch.horizon == 0 {
        return Err(EstimatorError::EmptyBatch);
    }
    if batch.n < min_n {
        return Err(EstimatorError::TooFewTrajectories {
            n: batch.n,
            min: min_n,
        });
    }
    let mismatch = |what, expected, found| {
        if expected == found {
            Ok(())
        } else {
            Err(EstimatorError::DimensionMismatch {
                what,
                expected,
                found,
            })
        }
    };
    if batch.dim_v == 0 || batch.dim_w == 0 {
        return Err(EstimatorError::DimensionMismatch {
            what: "dim_v and dim_w (must be positive)",
            expected: 1,
            found: 0,
        });
    }
    mismatch(
        "dim_v modulo dim_w (dim_v = l · p)",
        0,
        batch.dim_v % batch.dim_w,
    )?;
    // Saturating: a shape whose size overflows can match no vector length.
    let steps = batch.n.saturating_mul(batch.horizon);
    mismatch("sigma", batch.dim_w, batch.sigma.len())?;
    mismatch("disc_rewards", steps, batch.disc_rewards.len())?;
    mismatch(
        "cum_score_v",
        steps.saturating_mul(batch.dim_v),
        batch.cum_score_v.len(),
    )?;
    mismatch(
        "cum_score_w",
        steps.saturating_mul(batch.dim_w),
        batch.cum_score_w.len(),
    )?;
    mismatch("lengths", batch.n, batch.lengths.len())?;
    if let Some(&len) = batch.lengths.iter().find(|&&l| l > batch.horizon) {
        return Err(EstimatorError::DimensionMismatch {
            what: "trajectory length (at most the horizon)",
            expected: batch.horizon,
            found: len,
        });
    }
    if let Some((index, &value)) = batch
        .sigma
        .iter()
        .enumerate()
        .find(|(_, s)| !(s.is_finite() && **s > 0.0))
    {
        return Err(EstimatorError::InvalidSigma { index, value });
    }
    Ok(())
}

/// Checks that a [`Baseline::Constant`] is finite.
pub(crate) fn check_baseline(baseline: Baseline) -> Result<(), EstimatorError> {
    match baseline {
        Baseline::Constant(b) if !b.is_finite() => Err(EstimatorError::NonFinite {
            what: "constant baseline",
        }),
        _ => Ok(()),
    }
}

fn dim_of(batch: &Batch, param: Param) -> usize {
    match param {
        Param::V => batch.dim_v,
        Param::W => batch.dim_w,
    }
}

impl Estimator {
    /// A workspace with empty buffers (they grow on first use).
    ///
    /// # Examples
    /// ```
    /// let _estimator = sepg_estimators::Estimator::new();
    /// ```
    pub fn new() -> Self {
        Self::default()
    }

    /// `Ĵ`, the sample mean of the discounted return `Σ_t γ^t r_t` (samples: the `N` returns).
    ///
    /// # Formula
    /// ```text
    /// Ĵ = (1/N) Σ_i Σ_t γ^t r_{i,t}
    /// ```
    ///
    /// # Errors
    /// [`EstimatorError`] for an empty batch, `N < 2`, inconsistent buffer sizes, invalid `σ`
    /// or non-finite data.
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Estimate, Estimator};
    /// use sepg_mdp::Batch;
    /// let mut batch = Batch::zeros(2, 2, 1, 1, 0.5);
    /// batch.disc_rewards.copy_from_slice(&[1.0, 0.5, 2.0, 1.0]);
    /// let mut est = Estimate::new();
    /// Estimator::new().value(&batch, &mut est)?;
    /// assert_eq!(est.mean(), &[2.25]);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn value(&mut self, batch: &Batch, out: &mut Estimate) -> Result<(), EstimatorError> {
        validate(batch, 2)?;
        let samples = out.reset(batch.n, 1);
        returns_into(batch, 0..batch.n, samples);
        out.finish()
    }

    /// Estimates `∇_v J` or `∇_w J` (REINFORCE eq. (2.1), G(PO)MDP or PGT, Sec 2.3.1) with the
    /// chosen baseline (Sec 2.3.2) into `out` (`dim = dim_v` or `dim_w`).
    ///
    /// # Formula
    /// ```text
    /// S_{i,t} = Σ_{k≤t} ∇ log π(a_{i,k} | s_{i,k}),  F_{i,t} = γ^t r_{i,t},  R_i = Σ_t F_{i,t}
    /// REINFORCE:  x_i = S_{i,H−1} (R_i − b)          b = ⟨S²R⟩/⟨S²⟩ (optimal) or ⟨R⟩ (mean)
    /// G(PO)MDP:   x_i = Σ_t S_{i,t} (F_{i,t} − b_t)   b_t = ⟨S_t² F_t⟩/⟨S_t²⟩ or ⟨F_t⟩
    /// PGT:        x_i = Σ_k (S_{i,k} − S_{i,k−1}) Σ_{l≥k} (F_{i,l} − b_l)
    /// estimate = (1/N) Σ_i x_i      (component-wise; ⟨·⟩ over all, or the other N − 1, rows)
    /// Constant(c): b = c Σ_{t<H} γ^t (REINFORCE),  b_t = γ^t c (G(PO)MDP, PGT)
    /// ```
    /// Units: return units per parameter unit.
    ///
    /// # Errors
    /// [`EstimatorError`] for an empty batch, `N < 2`, inconsistent buffer sizes, invalid `σ`,
    /// non-finite data or constant baseline, or overflow.
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Baseline, BaselineFit, Estimate, Estimator, GradientSpec, Kind, Param};
    /// use sepg_mdp::Batch;
    /// // Two one-step trajectories: scores ±1, rewards 3 and 1.
    /// let mut batch = Batch::zeros(2, 1, 1, 1, 0.9);
    /// batch.disc_rewards.copy_from_slice(&[3.0, 1.0]);
    /// batch.cum_score_v.copy_from_slice(&[1.0, -1.0]);
    /// let spec = GradientSpec { kind: Kind::Reinforce, baseline: Baseline::None, fit: BaselineFit::PlugIn };
    /// let mut est = Estimate::new();
    /// Estimator::new().gradient(&batch, Param::V, spec, &mut est)?;
    /// assert_eq!(est.mean(), &[1.0]); // (1·3 + (−1)·1) / 2
    /// assert_eq!(est.samples(), &[3.0, -1.0]);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn gradient(
        &mut self,
        batch: &Batch,
        param: Param,
        spec: GradientSpec,
        out: &mut Estimate,
    ) -> Result<(), EstimatorError> {
        validate(batch, 2)?;
        check_baseline(spec.baseline)?;
        let samples = out.reset(batch.n, dim_of(batch, param));
        self.kernel(
            batch,
            0..batch.n,
            Target::gradient(spec.kind, param),
            spec.baseline,
            spec.fit,
            samples,
        );
        out.finish()
    }

    /// Estimates `h(θ) = E[∇_σ log p(τ) ∇_v log p(τ) R(τ)]` by (B.3) of Theorem B.1 with the
    /// baseline of Appendix B.2, for every pair (action dimension `j`, mean parameter `k`):
    /// `out` gets `dim = dim_w · dim_v`, component `j · dim_v + k`.
    ///
    /// # Formula
    /// ```text
    /// G_{t,k} = Σ_{s≤t} ∇_{v_k} log π_s,   H_{t,j} = Σ_{s≤t} ∇_{w_j} log π_s / σ_j,   F_t = γ^t r_t
    /// Optimal (B.2): x_{jk} = Σ_t [G H F − b̃_t (G + H)],   b̃_t = ⟨G H F (G + H)⟩ / ⟨(G + H)²⟩
    /// Mean:          x_{jk} = Σ_t G H (F − ⟨F_t⟩)           (valid since E[G_t H_t] = 0)
    /// None:          x_{jk} = Σ_t G H F
    /// Constant(c):   x_{jk} = Σ_t G H (F − γ^t c)           (also valid since E[G_t H_t] = 0)
    /// ```
    /// The σ-score of action `j` is the w-score divided by `σ_j`. The pairs with `j` equal to
    /// the action of `v_k` (`k / p`, `p = dim_v / dim_w`) form the `h` of the thesis; the
    /// other pairs (zero-mean for `l = 1`, absent) are needed for `∂_{σ_j} ∇_v J` when several
    /// action dimensions interact through the dynamics.
    ///
    /// # Errors
    /// As [`Estimator::gradient`].
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Baseline, BaselineFit, Estimate, Estimator};
    /// use sepg_mdp::Batch;
    /// let mut batch = Batch::zeros(2, 1, 1, 1, 0.9);
    /// batch.sigma[0] = 0.5;
    /// batch.disc_rewards.copy_from_slice(&[2.0, 1.0]);
    /// batch.cum_score_v.copy_from_slice(&[1.0, 3.0]);
    /// batch.cum_score_w.copy_from_slice(&[0.5, -1.0]);
    /// let mut est = Estimate::new();
    /// Estimator::new().h(&batch, Baseline::None, BaselineFit::PlugIn, &mut est)?;
    /// // x_1 = 1 · (0.5/0.5) · 2 = 2,  x_2 = 3 · (−1/0.5) · 1 = −6.
    /// assert_eq!(est.samples(), &[2.0, -6.0]);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn h(
        &mut self,
        batch: &Batch,
        baseline: Baseline,
        fit: BaselineFit,
        out: &mut Estimate,
    ) -> Result<(), EstimatorError> {
        validate(batch, 2)?;
        check_baseline(baseline)?;
        let samples = out.reset(batch.n, batch.dim_w * batch.dim_v);
        self.kernel(batch, 0..batch.n, Target::H, baseline, fit, samples);
        out.finish()
    }

    /// Estimates the mixed derivative `∂_σ ∇_v J = h(θ) − (2/σ) ∇_v J` (Appendix B) for every
    /// pair (action `j`, mean parameter `k`), component `j · dim_v + k`; `∇_v J` uses
    /// `spec`, `ĥ` uses `spec.baseline` and `spec.fit`. Multiply by `σ_j` for `∂²J/∂w_j∂v_k`.
    ///
    /// # Formula
    /// ```text
    /// x_{i,jk} = ĥ_{i,jk} − [k / p = j] (2/σ_j) ∇̂_{v_k}J_i       (p = dim_v / dim_w)
    /// ```
    ///
    /// # Errors
    /// As [`Estimator::gradient`].
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Baseline, BaselineFit, Estimate, Estimator, GradientSpec, Kind};
    /// use sepg_mdp::Batch;
    /// let mut batch = Batch::zeros(2, 1, 1, 1, 0.9);
    /// batch.sigma[0] = 0.5;
    /// batch.disc_rewards.copy_from_slice(&[2.0, 1.0]);
    /// batch.cum_score_v.copy_from_slice(&[1.0, 3.0]);
    /// batch.cum_score_w.copy_from_slice(&[0.5, -1.0]);
    /// let spec = GradientSpec { kind: Kind::Gpomdp, baseline: Baseline::None, fit: BaselineFit::PlugIn };
    /// let mut est = Estimate::new();
    /// Estimator::new().mixed(&batch, spec, &mut est)?;
    /// // h samples 2, −6; gradient samples 2, 3; minus (2/0.5)·gradient.
    /// assert_eq!(est.samples(), &[2.0 - 8.0, -6.0 - 12.0]);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn mixed(
        &mut self,
        batch: &Batch,
        spec: GradientSpec,
        out: &mut Estimate,
    ) -> Result<(), EstimatorError> {
        validate(batch, 2)?;
        check_baseline(spec.baseline)?;
        let mut g = std::mem::take(&mut self.tmp_g);
        let gs = g.reset(batch.n, batch.dim_v);
        let target = Target::gradient(spec.kind, Param::V);
        self.kernel(batch, 0..batch.n, target, spec.baseline, spec.fit, gs);
        let hs = out.reset(batch.n, batch.dim_w * batch.dim_v);
        self.kernel(batch, 0..batch.n, Target::H, spec.baseline, spec.fit, hs);
        subtract_score_term(batch, g.samples(), hs);
        self.tmp_g = g;
        out.finish()
    }

    /// Runs one estimator on the trajectories `rows`, writing `rows.len() × comps` samples
    /// (see [`crate::kernel`]; every baseline is fitted on `rows` only). G(PO)MDP with a
    /// constant baseline is summed in one pass ([`gpomdp_constant`]); for the other
    /// estimators a constant baseline is applied by running the estimator without baseline on
    /// the shifted rewards
    /// `γ^t (r_t − b)`.
    pub(crate) fn kernel(
        &mut self,
        batch: &Batch,
        rows: Range<usize>,
        target: Target,
        baseline: Baseline,
        fit: BaselineFit,
        out: &mut [f64],
    ) {
        let h = batch.horizon;
        let nr = rows.len();
        if let (Target::Gpomdp(p), Baseline::Constant(b)) = (target, baseline) {
            let (s, comps) = match p {
                Param::V => (&batch.cum_score_v, batch.dim_v),
                Param::W => (&batch.cum_score_w, batch.dim_w),
            };
            let s = &s[rows.start * h * comps..rows.end * h * comps];
            let rewards = &batch.disc_rewards[rows.start * h..rows.end * h];
            gpomdp_constant(
                s,
                comps,
                rewards,
                (h, batch.gamma, b),
                &mut self.shifted,
                &mut out[..nr * comps],
            );
            return;
        }
        let mut shifted = std::mem::take(&mut self.shifted);
        let rewards = &batch.disc_rewards[rows.start * h..rows.end * h];
        let (rewards, baseline) = match baseline {
            Baseline::Constant(b) => {
                shift_rewards(&mut shifted, rewards, h, batch.gamma, b);
                (&shifted[..], Baseline::None)
            }
            fitted => (rewards, fitted),
        };
        let scores = |p: Param| match p {
            Param::V => (
                &batch.cum_score_v[rows.start * h * batch.dim_v..],
                batch.dim_v,
            ),
            Param::W => (
                &batch.cum_score_w[rows.start * h * batch.dim_w..],
                batch.dim_w,
            ),
        };
        match target {
            Target::Gpomdp(p) | Target::Pgt(p) => {
                let (s, comps) = scores(p);
                let pgt = matches!(target, Target::Pgt(_));
                self.score_target(s, comps, rewards, (h, nr), pgt, (baseline, fit), out);
            }
            Target::Reinforce(p) => {
                let (s, comps) = scores(p);
                self.returns.resize(nr, 0.0);
                row_returns(rewards, h, &mut self.returns);
                let s = Rows::new(&s[(h - 1) * comps..], h * comps);
                let f = broadcast(&mut self.bcast, &self.returns, 1, comps);
                run_score(
                    &mut self.sums,
                    s,
                    f,
                    nr,
                    comps,
                    comps,
                    baseline,
                    fit,
                    Output::Sums(out),
                );
            }
            Target::H => self.h_target(batch, rows, rewards, (baseline, fit), out),
        }
        self.shifted = shifted;
    }

    /// G(PO)MDP or PGT (`pgt`) samples of one parameter: scores `s` with `comps` components per
    /// step, the rows' discounted `rewards`, `(h, nr)` = (horizon, rows).
    #[allow(clippy::too_many_arguments)]
    fn score_target(
        &mut self,
        s: &[f64],
        comps: usize,
        rewards: &[f64],
        (h, nr): (usize, usize),
        pgt: bool,
        (baseline, fit): (Baseline, BaselineFit),
        out: &mut [f64],
    ) {
        let w = h * comps;
        let s = Rows::new(s, w);
        let f = broadcast(&mut self.bcast, rewards, h, comps);
        if pgt {
            run_score(
                &mut self.sums,
                s,
                f,
                nr,
                w,
                comps,
                baseline,
                fit,
                Output::Baselines,
            );
            let base = self.sums.baselines(w);
            let f = Rows::new(rewards, h);
            for (r, x) in out[..nr * comps].chunks_exact_mut(comps).enumerate() {
                pgt_sample(s.row(r, w), f.row(r, h), base.row(r, w), x);
            }
        } else {
            run_score(
                &mut self.sums,
                s,
                f,
                nr,
                w,
                comps,
                baseline,
                fit,
                Output::Sums(out),
            );
        }
    }

    /// The samples of ĥ (Theorem B.1) with the mean or the B.2 baseline.
    fn h_target(
        &mut self,
        batch: &Batch,
        rows: Range<usize>,
        rewards: &[f64],
        (baseline, fit): (Baseline, BaselineFit),
        out: &mut [f64],
    ) {
        let (h, nr) = (batch.horizon, rows.len());
        self.fill_h(batch, rows, rewards, baseline);
        let comps = batch.dim_w * batch.dim_v;
        let w = h * comps;
        let (u, z) = (Rows::new(&self.h_u, w), Rows::new(&self.h_z, w));
        let out = Output::Sums(out);
        if baseline == Baseline::Mean {
            let f = broadcast(&mut self.bcast, rewards, h, comps);
            self.sums
                .run::<3, HMean>([u, z, f], nr, w, comps, baseline, fit, out);
        } else {
            self.sums
                .run::<2, HOptimal>([u, z], nr, w, comps, baseline, fit, out);
        }
    }

    /// Fills `h_u` with `u = G_k H_j F` and `h_z` with the control variate of `baseline`
    /// (`G_k + H_j` optimal, `G_k H_j` mean, 0 without baseline) for the trajectories `rows`
    /// with discounted rewards `rewards` (`rows.len() × steps`), entry
    /// `(r · steps + t) · dim_w · dim_v + j · dim_v + k`, where `H_j` is the cumulative
    /// w-score divided by `σ_j` (the σ-score). A constant baseline has no control variate:
    /// it is already subtracted from `rewards`.
    fn fill_h(&mut self, batch: &Batch, rows: Range<usize>, rewards: &[f64], baseline: Baseline) {
        match baseline {
            Baseline::None | Baseline::Constant(_) => {
                self.fill_h_with(batch, rows, rewards, |_, _| 0.0)
            }
            Baseline::Mean => self.fill_h_with(batch, rows, rewards, |g, h| g * h),
            Baseline::Optimal => self.fill_h_with(batch, rows, rewards, |g, h| g + h),
        }
    }

    /// [`Estimator::fill_h`] with the control variate `z = control(G_k, H_j)`.
    #[inline(always)]
    fn fill_h_with(
        &mut self,
        batch: &Batch,
        rows: Range<usize>,
        rewards: &[f64],
        control: impl Fn(f64, f64) -> f64,
    ) {
        let (h, m, l) = (batch.horizon, batch.dim_v, batch.dim_w);
        let width = l * m;
        let len = rows.len() * h * width;
        // Every entry is overwritten.
        self.h_u.resize(len, 0.0);
        self.h_z.resize(len, 0.0);
        let g_all = &batch.cum_score_v[rows.start * h * m..rows.end * h * m];
        let w_all = &batch.cum_score_w[rows.start * h * l..rows.end * h * l];
        let f_all = rewards;
        if width == 1 {
            // One action, one feature: one flat loop over all steps.
            let sigma = batch.sigma[0];
            let terms = g_all.iter().zip(w_all).zip(f_all);
            for (((g, w), fr), (u, z)) in terms.zip(self.h_u.iter_mut().zip(self.h_z.iter_mut())) {
                let hj = w / sigma;
                *u = g * hj * fr;
                *z = control(*g, hj);
            }
            return;
        }
        for ((((g, w), fr), u), z) in g_all
            .chunks_exact(m)
            .zip(w_all.chunks_exact(l))
            .zip(f_all)
            .zip(self.h_u.chunks_exact_mut(width))
            .zip(self.h_z.chunks_exact_mut(width))
        {
            for (((wj, sj), uj), zj) in w
                .iter()
                .zip(&batch.sigma)
                .zip(u.chunks_exact_mut(m))
                .zip(z.chunks_exact_mut(m))
            {
                let hj = wj / sj;
                for ((gk, uk), zk) in g.iter().zip(uj).zip(zj) {
                    *uk = gk * hj * fr;
                    *zk = control(*gk, hj);
                }
            }
        }
    }
}

/// [`Sums::run`] of a score-function estimator with inputs `[s, f]`.
#[allow(clippy::too_many_arguments)]
fn run_score(
    sums: &mut Sums,
    s: Rows<'_>,
    f: Rows<'_>,
    rows: usize,
    width: usize,
    comps: usize,
    baseline: Baseline,
    fit: BaselineFit,
    output: Output<'_>,
) {
    let inputs = [s, f];
    if baseline == Baseline::Optimal {
        sums.run::<2, Score<true>>(inputs, rows, width, comps, baseline, fit, output);
    } else {
        sums.run::<2, Score<false>>(inputs, rows, width, comps, baseline, fit, output);
    }
}

/// The per-step values `values[r · steps + t]` as rows of `steps · comps` entries, each value
/// repeated for the `comps` components of its step (no copy when `comps = 1`).
fn broadcast<'a>(
    buffer: &'a mut Vec<f64>,
    values: &'a [f64],
    steps: usize,
    comps: usize,
) -> Rows<'a> {
    if comps == 1 {
        return Rows::new(values, steps);
    }
    buffer.clear();
    buffer.extend(values.iter().flat_map(|v| std::iter::repeat_n(*v, comps)));
    Rows::new(buffer, steps * comps)
}

/// The discounted returns `Σ_t γ^t r_t` of the trajectories `rows` into `out`, summed from
/// `−0.0` in the order of `t` (the same bits as [`Batch::discounted_return`]).
pub(crate) fn returns_into(batch: &Batch, rows: Range<usize>, out: &mut [f64]) {
    let h = batch.horizon;
    row_returns(&batch.disc_rewards[rows.start * h..rows.end * h], h, out);
}

/// The row sums of `rewards` (rows of `h` steps) into `out`, summed from `−0.0` in the order
/// of `t`.
fn row_returns(rewards: &[f64], h: usize, out: &mut [f64]) {
    let rows = rewards.len() / h;
    row_sums(&mut out[..rows], h, -0.0, [Rows::new(rewards, h)], |[f]| f);
}

/// `shifted[r · h + t] = rewards[r · h + t] − γ^t b`: the discounted rewards minus the
/// discounted constant baseline, at every step `t < h` (padding included).
fn shift_rewards(shifted: &mut Vec<f64>, rewards: &[f64], h: usize, gamma: f64, b: f64) {
    shifted.clear();
    shifted.extend_from_slice(rewards);
    for row in shifted.chunks_exact_mut(h) {
        let mut discount = 1.0;
        for f in row {
            *f -= discount * b;
            discount *= gamma;
        }
    }
}

/// G(PO)MDP with the constant baseline `b` in one pass over each trajectory's rows:
/// `x_{r,c} = Σ_t S_{r,t,c} (F_{r,t} − γ^t b)`, summed from 0 in the order of `t`, with
/// `γ^t` the running product and `F − γ^t b` rounded as [`shift_rewards`] rounds it, so the
/// samples are those of the estimator without baseline on the shifted rewards, bit for bit,
/// without the shifted copy and the stored sample terms.
fn gpomdp_constant(
    s: &[f64],
    comps: usize,
    rewards: &[f64],
    (h, gamma, b): (usize, f64, f64),
    shift: &mut Vec<f64>,
    out: &mut [f64],
) {
    if comps == 1 {
        // γ^t b once per step, in a row shared by every trajectory (stride 0); the sums over
        // time then run four trajectories at a time (`row_sums`), each in the order of `t`.
        shift.clear();
        let mut discount = 1.0;
        for _ in 0..h {
            shift.push(discount * b);
            discount *= gamma;
        }
        let inputs = [Rows::new(s, h), Rows::new(rewards, h), Rows::new(shift, 0)];
        let n = out.len().min(rewards.len() / h);
        row_sums(&mut out[..n], h, 0.0, inputs, |[s, f, b]| s * (f - b));
        return;
    }
    let rows = s.chunks_exact(h * comps).zip(rewards.chunks_exact(h));
    for (x, (s, f)) in out.chunks_exact_mut(comps).zip(rows) {
        x.fill(0.0);
        let mut discount = 1.0;
        for (st, f) in s.chunks_exact(comps).zip(f) {
            let f = f - discount * b;
            discount *= gamma;
            for (xc, sc) in x.iter_mut().zip(st) {
                *xc += sc * f;
            }
        }
    }
}

/// Turns `ĥ` samples into `∂_σ ∇_v J` samples: subtracts `(2/σ_j) g_k` where `v_k` belongs to
/// action `j`.
pub(crate) fn subtract_score_term(batch: &Batch, g: &[f64], hs: &mut [f64]) {
    let m = batch.dim_v;
    let p = m / batch.dim_w;
    for (grow, hrow) in g.chunks_exact(m).zip(hs.chunks_exact_mut(batch.dim_w * m)) {
        for (j, sj) in batch.sigma.iter().enumerate() {
            let two_over = 2.0 / sj;
            for k in j * p..(j + 1) * p {
                hrow[j * m + k] -= two_over * grow[k];
            }
        }
    }
}
