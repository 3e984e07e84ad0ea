//! Likelihood-ratio estimators of `J`, `∇_v J`, `∇_w J` and `h(θ)` from a [`Batch`]
//! (Sec 2.3.1–2.3.2, Theorem B.1), with baselines, computed by a reusable [`Estimator`].

use std::ops::Range;

use sepg_mdp::Batch;

use crate::error::EstimatorError;
use crate::estimate::Estimate;

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
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
    /// Baseline of the current row per (step, component).
    row_base: Vec<f64>,
    /// Running prefix sums (leave-one-out) or totals (plug-in) of the baseline terms
    /// `(num, den)` per (step, component).
    pre: Vec<f64>,
    /// Suffix sums over rows of the baseline terms (leave-one-out fit).
    suf: Vec<f64>,
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
    let steps = batch.n * batch.horizon;
    mismatch("sigma", batch.dim_w, batch.sigma.len())?;
    mismatch("disc_rewards", steps, batch.disc_rewards.len())?;
    mismatch("cum_score_v", steps * batch.dim_v, batch.cum_score_v.len())?;
    mismatch("cum_score_w", steps * batch.dim_w, batch.cum_score_w.len())?;
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

/// Cumulative score of `param` for trajectory `i` at step `t`.
fn score(batch: &Batch, param: Param, i: usize, t: usize) -> &[f64] {
    match param {
        Param::V => batch.score_v(i, t),
        Param::W => batch.score_w(i, t),
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
        for (i, s) in samples.iter_mut().enumerate() {
            *s = batch.discounted_return(i);
        }
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
    /// ```
    /// Units: return units per parameter unit.
    ///
    /// # Errors
    /// [`EstimatorError`] for an empty batch, `N < 2`, inconsistent buffer sizes, invalid `σ`,
    /// non-finite data or overflow.
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

    /// Runs one estimator on the trajectories `rows`, writing `rows.len() × comps` samples.
    ///
    /// Two passes over the batch: the baseline sums (suffix sums over rows for the
    /// leave-one-out fit, totals for the plug-in fit), then per row its baseline and samples
    /// (and the running prefix sums). Terms are recomputed from the batch on the fly.
    pub(crate) fn kernel(
        &mut self,
        batch: &Batch,
        rows: Range<usize>,
        target: Target,
        baseline: Baseline,
        fit: BaselineFit,
        out: &mut [f64],
    ) {
        let (steps, comps) = match target {
            Target::Reinforce(p) => (1, dim_of(batch, p)),
            Target::Gpomdp(p) | Target::Pgt(p) => (batch.horizon, dim_of(batch, p)),
            Target::H => (batch.horizon, batch.dim_w * batch.dim_v),
        };
        let width = steps * comps;
        let nr = rows.len();
        let fit = match baseline {
            Baseline::None => None,
            Baseline::Mean | Baseline::Optimal => Some(fit),
        };
        self.row_base.clear();
        self.row_base.resize(width, 0.0);
        self.pre.clear();
        self.pre.resize(2 * width, 0.0);
        match fit {
            None => {}
            Some(BaselineFit::PlugIn) => {
                for i in rows.clone() {
                    add_terms(batch, target, baseline, i, steps, comps, &mut self.pre);
                }
                for (b, nd) in self.row_base.iter_mut().zip(self.pre.chunks_exact(2)) {
                    *b = ratio(nd[0], nd[1]);
                }
            }
            Some(BaselineFit::LeaveOneOut) => {
                self.suf.clear();
                self.suf.resize((nr + 1) * 2 * width, 0.0);
                for (li, i) in rows.clone().enumerate().rev() {
                    let (head, tail) = self.suf.split_at_mut((li + 1) * 2 * width);
                    let row = &mut head[li * 2 * width..];
                    row.copy_from_slice(&tail[..2 * width]);
                    add_terms(batch, target, baseline, i, steps, comps, row);
                }
            }
        }
        for ((li, i), x) in rows.enumerate().zip(out.chunks_exact_mut(comps)) {
            if fit == Some(BaselineFit::LeaveOneOut) {
                let others = &self.suf[(li + 1) * 2 * width..(li + 2) * 2 * width];
                for ((b, p), o) in self
                    .row_base
                    .iter_mut()
                    .zip(self.pre.chunks_exact(2))
                    .zip(others.chunks_exact(2))
                {
                    *b = ratio(p[0] + o[0], p[1] + o[1]);
                }
                add_terms(batch, target, baseline, i, steps, comps, &mut self.pre);
            }
            match target {
                Target::Pgt(p) => pgt_row(batch, p, i, &self.row_base, x),
                _ => {
                    x.fill(0.0);
                    match row_view(batch, target, i) {
                        Row::Score { s, f } => score_samples(s, f, &self.row_base, x),
                        Row::Reinforce { s, ret } => score_samples(s, &[ret], &self.row_base, x),
                        Row::H => {
                            for t in 0..steps {
                                let b = &self.row_base[t * comps..(t + 1) * comps];
                                h_terms(batch, baseline, i, t, |c, u, z, _, _| {
                                    x[c] += u - b[c] * z;
                                });
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Calls `f(c, u, z, num, den)` for every pair `c = j · dim_v + k` of `ĥ` at step `t` of
/// trajectory `i`: the sample is `Σ_t (u − b z)` and the baseline `b = Σ num / Σ den`, with
/// `u = G H F`; optimal (B.2): `z = G + H`, `(num, den) = (u z, z²)`; mean: `z = G H`,
/// `(num, den) = (F, 1)`.
#[inline(always)]
fn h_terms(
    batch: &Batch,
    baseline: Baseline,
    i: usize,
    t: usize,
    mut f: impl FnMut(usize, f64, f64, f64, f64),
) {
    let g = batch.score_v(i, t);
    let w = batch.score_w(i, t);
    let fr = batch.rewards(i)[t];
    let m = batch.dim_v;
    for (j, (wj, sj)) in w.iter().zip(&batch.sigma).enumerate() {
        let hj = wj / sj;
        for (k, gk) in g.iter().enumerate() {
            let u = gk * hj * fr;
            let (z, num, den) = match baseline {
                Baseline::None => (0.0, 0.0, 0.0),
                Baseline::Mean => (gk * hj, fr, 1.0),
                Baseline::Optimal => {
                    let z = gk + hj;
                    (z, u * z, z * z)
                }
            };
            f(j * m + k, u, z, num, den);
        }
    }
}

/// Adds the baseline terms `(num, den)` of trajectory `i` to `acc` (layout `[(t · comps + c) · 2]`).
fn add_terms(
    batch: &Batch,
    target: Target,
    baseline: Baseline,
    i: usize,
    steps: usize,
    comps: usize,
    acc: &mut [f64],
) {
    match row_view(batch, target, i) {
        Row::Score { s, f } => return score_add_terms(s, f, baseline, acc),
        Row::Reinforce { s, ret } => return score_add_terms(s, &[ret], baseline, acc),
        Row::H => {}
    }
    for t in 0..steps {
        let row = &mut acc[2 * t * comps..2 * (t + 1) * comps];
        h_terms(batch, baseline, i, t, |c, _, _, num, den| {
            row[2 * c] += num;
            row[2 * c + 1] += den;
        });
    }
}

/// The data of one trajectory for a score target, as contiguous slices.
enum Row<'a> {
    /// G(PO)MDP, PGT: cumulative scores (`steps × comps`) and `F_t = γ^t r_t`.
    Score { s: &'a [f64], f: &'a [f64] },
    /// REINFORCE: the last cumulative score and the return.
    Reinforce { s: &'a [f64], ret: f64 },
    /// `ĥ`: computed term by term.
    H,
}

fn row_view(batch: &Batch, target: Target, i: usize) -> Row<'_> {
    let steps = batch.horizon;
    let row = |p: Param| match p {
        Param::V => &batch.cum_score_v[i * steps * batch.dim_v..(i + 1) * steps * batch.dim_v],
        Param::W => &batch.cum_score_w[i * steps * batch.dim_w..(i + 1) * steps * batch.dim_w],
    };
    match target {
        Target::Gpomdp(p) | Target::Pgt(p) => Row::Score {
            s: row(p),
            f: batch.rewards(i),
        },
        Target::Reinforce(p) => Row::Reinforce {
            s: score(batch, p, i, steps - 1),
            ret: batch.discounted_return(i),
        },
        Target::H => Row::H,
    }
}

/// `x_c = Σ_t S_{t,c} (F_t − b_{t,c})` for one trajectory (`comps = x.len()`).
fn score_samples(s: &[f64], f: &[f64], base: &[f64], x: &mut [f64]) {
    let comps = x.len();
    for ((st, bt), ft) in s.chunks_exact(comps).zip(base.chunks_exact(comps)).zip(f) {
        for ((xc, sc), bc) in x.iter_mut().zip(st).zip(bt) {
            *xc += sc * (ft - bc);
        }
    }
}

/// Adds the baseline terms of one trajectory: `(S² F, S²)` (optimal) or `(F, 1)` (mean).
fn score_add_terms(s: &[f64], f: &[f64], baseline: Baseline, acc: &mut [f64]) {
    let comps = s.len() / f.len();
    for ((st, at), &ft) in s
        .chunks_exact(comps)
        .zip(acc.chunks_exact_mut(2 * comps))
        .zip(f)
    {
        for (sc, a) in st.iter().zip(at.chunks_exact_mut(2)) {
            match baseline {
                Baseline::None => {}
                Baseline::Mean => {
                    a[0] += ft;
                    a[1] += 1.0;
                }
                Baseline::Optimal => {
                    let s2 = sc * sc;
                    a[0] += s2 * ft;
                    a[1] += s2;
                }
            }
        }
    }
}

/// PGT order for one trajectory: `x_c = Σ_k (S_k − S_{k−1})_c Σ_{l≥k} (F_l − b_{l,c})`.
fn pgt_row(batch: &Batch, param: Param, i: usize, base: &[f64], x: &mut [f64]) {
    let comps = x.len();
    let rewards = batch.rewards(i);
    for (c, xc) in x.iter_mut().enumerate() {
        let mut acc = 0.0;
        let mut to_go = 0.0;
        for t in (0..batch.horizon).rev() {
            to_go += rewards[t] - base[t * comps + c];
            let prev = if t == 0 {
                0.0
            } else {
                score(batch, param, i, t - 1)[c]
            };
            acc += (score(batch, param, i, t)[c] - prev) * to_go;
        }
        *xc = acc;
    }
}

/// Baseline ratio with the explicit convention `0/0 = 0` (Sec 2.3.2, SPEC §3).
fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 { num / den } else { 0.0 }
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
