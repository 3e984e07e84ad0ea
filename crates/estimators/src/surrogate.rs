//! The cross-fitted estimator of `∇_w L`, the gradient of the surrogate objective
//! `L = ‖∇_v J‖² / (4 m c(σ))` (Corollary 4.4, Appendix B, docs/CONVENTIONS.md §3).
//!
//! `∇_w L` is a product of two gradient estimates, so the plug-in estimator is biased by the
//! covariance of `∇̂_v J` with itself (`E‖ĝ‖² = ‖g‖² + tr Cov ĝ`). Here the batch is split into
//! two independent halves `A` (first `⌊N/2⌋` trajectories) and `B` (the rest), every baseline is
//! fitted within its own half, and each product takes one factor from each half:
//!
//! ```text
//! ‖g‖²     ≈ ⟨g_A, g_B⟩                        (unbiased: E⟨g_A, g_B⟩ = ⟨E g_A, E g_B⟩)
//! 2⟨g, D_j⟩ ≈ ⟨g_A, D_{j,B}⟩ + ⟨g_B, D_{j,A}⟩   (D_j = ∂_{σ_j} ∇_v J)
//! ```
//!
//! which is exactly unbiased when the half estimators are (no baseline, or leave-one-out).

use sepg_bounds::constants::{TaskConstants, c as penalty_c, dc_dsigma};
use sepg_mdp::Batch;

use crate::error::EstimatorError;
use crate::estimate::Estimate;
use crate::gradient::{
    Estimator, GradientSpec, Param, Target, check_baseline, subtract_score_term, validate,
};

/// The outputs of [`Estimator::surrogate_gradient`], reused across calls.
#[derive(Debug, Clone, Default)]
pub struct SurrogateEstimate {
    grad_w_l: Estimate,
    grad_v: Estimate,
    mixed: Estimate,
    surrogate: f64,
}

impl SurrogateEstimate {
    /// Empty outputs, to be filled by [`Estimator::surrogate_gradient`].
    ///
    /// # Examples
    /// ```
    /// let s = sepg_estimators::SurrogateEstimate::new();
    /// assert_eq!(s.surrogate(), 0.0);
    /// ```
    pub fn new() -> Self {
        Self::default()
    }

    /// `∇̂_w L`, one component per action dimension: the cross-fitted estimate as mean and its
    /// delta-method linearisation as per-trajectory samples (so a Student-t width applies).
    ///
    /// # Examples
    /// ```
    /// assert_eq!(sepg_estimators::SurrogateEstimate::new().grad_w_l().dim(), 0);
    /// ```
    pub fn grad_w_l(&self) -> &Estimate {
        &self.grad_w_l
    }

    /// `∇̂_v J` from the same batch, every baseline fitted within its half (samples of half `A`
    /// first): an unbiased estimate of `∇_v J` in its own right.
    ///
    /// # Examples
    /// ```
    /// assert_eq!(sepg_estimators::SurrogateEstimate::new().grad_v().dim(), 0);
    /// ```
    pub fn grad_v(&self) -> &Estimate {
        &self.grad_v
    }

    /// `∂_σ ∇_v J` estimated with half-wise baselines, component `j · dim_v + k`
    /// (see [`Estimator::mixed`]).
    ///
    /// # Examples
    /// ```
    /// assert_eq!(sepg_estimators::SurrogateEstimate::new().mixed().dim(), 0);
    /// ```
    pub fn mixed(&self) -> &Estimate {
        &self.mixed
    }

    /// `L̂ = ⟨g_A, g_B⟩ / (4 m c)`, the cross-fitted (unbiased) estimate of the surrogate
    /// objective of Corollary 4.4.
    ///
    /// # Examples
    /// ```
    /// assert_eq!(sepg_estimators::SurrogateEstimate::new().surrogate(), 0.0);
    /// ```
    pub fn surrogate(&self) -> f64 {
        self.surrogate
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Mean of the rows `rows` of a row-major `n × dim` sample matrix, into `out`.
fn row_mean(samples: &[f64], dim: usize, rows: std::ops::Range<usize>, out: &mut Vec<f64>) {
    out.clear();
    out.resize(dim, 0.0);
    let count = rows.len() as f64;
    for row in samples[rows.start * dim..rows.end * dim].chunks_exact(dim) {
        for (o, x) in out.iter_mut().zip(row) {
            *o += x;
        }
    }
    for o in out.iter_mut() {
        *o /= count;
    }
}

impl Estimator {
    /// Cross-fitted, unbiased estimate of `∇_w L` (Appendix B, docs/CONVENTIONS.md §3) for a penalty
    /// coefficient `c = c(σ) > 0` and its partial derivatives `dc_dsigma[j] = ∂c/∂σ_j`.
    ///
    /// # Formula
    /// ```text
    /// L = ‖∇_v J‖² / (4 m c(σ)),   m = dim_v,   ∂_{σ_j} ∇_v J = h_j − (2/σ_j) ∇_v J  (own action)
    /// ∇_{w_j} L = σ_j ∂_{σ_j} L = σ_j / (4 m c) · [2⟨g, D_j⟩ − ‖g‖² (∂c/∂σ_j) / c]
    /// estimate:  σ_j / (4 m c) · [⟨g_A, D_{j,B}⟩ + ⟨g_B, D_{j,A}⟩ − ⟨g_A, g_B⟩ (∂c/∂σ_j) / c]
    /// samples:   x_{i,j} = est_j + ∂est_j/∂g · (g_i − ḡ) + ∂est_j/∂D_j · (D_{i,j} − D̄_j)
    /// ```
    /// `g` uses `spec` (G(PO)MDP with the leave-one-out optimal baseline by default), `ĥ` uses
    /// `spec.baseline` with `spec.fit`, all fitted within each half. The estimate is unbiased
    /// for `BaselineFit::LeaveOneOut`, `Baseline::None` or `Baseline::Constant`. The samples
    /// (delta method, evaluated at the full-batch means) have the estimate as mean and, to first order, the
    /// per-trajectory variance of the estimate; their variance feeds the Student-t width.
    ///
    /// # Errors
    /// [`EstimatorError::TooFewTrajectories`] if `N < 4`; [`EstimatorError::InvalidConstant`]
    /// if `c` is not finite and positive or a `dc_dsigma` entry is not finite;
    /// [`EstimatorError::DimensionMismatch`] if `dc_dsigma.len() != dim_w`; otherwise as
    /// [`Estimator::gradient`].
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Estimator, GradientSpec, SurrogateEstimate};
    /// use sepg_mdp::Batch;
    /// let mut batch = Batch::zeros(4, 1, 1, 1, 0.9);
    /// batch.disc_rewards.copy_from_slice(&[1.0, 2.0, 1.5, 0.5]);
    /// batch.cum_score_v.copy_from_slice(&[1.0, -0.5, 0.3, 0.2]);
    /// batch.cum_score_w.copy_from_slice(&[0.1, -0.2, 0.4, 0.0]);
    /// let mut out = SurrogateEstimate::new();
    /// Estimator::new().surrogate_gradient(&batch, GradientSpec::default(), 2.0, &[-1.0], &mut out)?;
    /// assert_eq!(out.grad_w_l().dim(), 1);
    /// assert_eq!(out.grad_w_l().n(), 4);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn surrogate_gradient(
        &mut self,
        batch: &Batch,
        spec: GradientSpec,
        c: f64,
        dc_dsigma: &[f64],
        out: &mut SurrogateEstimate,
    ) -> Result<(), EstimatorError> {
        validate(batch, 4)?;
        check_baseline(spec.baseline)?;
        check_surrogate_constants(batch, c, dc_dsigma)?;
        let n = batch.n;
        let m = batch.dim_v;
        let l = batch.dim_w;
        let half = n / 2;
        let halves = [0..half, half..n];

        // ∇_v J samples, baselines per half.
        let gs = out.grad_v.reset(n, m);
        let target = Target::gradient(spec.kind, Param::V);
        for rows in halves.clone() {
            let slice = &mut gs[rows.start * m..rows.end * m];
            self.kernel(batch, rows, target, spec.baseline, spec.fit, slice);
        }
        out.grad_v.finish()?;

        // ∂_σ ∇_v J samples = ĥ − (2/σ) g, baselines per half.
        let ds = out.mixed.reset(n, l * m);
        for rows in halves.clone() {
            let slice = &mut ds[rows.start * l * m..rows.end * l * m];
            self.kernel(batch, rows, Target::H, spec.baseline, spec.fit, slice);
        }
        subtract_score_term(batch, out.grad_v.samples(), ds);
        out.mixed.finish()?;

        // Half means.
        let (mut ga, mut gb, mut da, mut db, mut f) = (
            std::mem::take(&mut self.vec_a),
            std::mem::take(&mut self.vec_b),
            std::mem::take(&mut self.vec_c),
            std::mem::take(&mut self.vec_d),
            std::mem::take(&mut self.vec_f),
        );
        row_mean(out.grad_v.samples(), m, halves[0].clone(), &mut ga);
        row_mean(out.grad_v.samples(), m, halves[1].clone(), &mut gb);
        row_mean(out.mixed.samples(), l * m, halves[0].clone(), &mut da);
        row_mean(out.mixed.samples(), l * m, halves[1].clone(), &mut db);

        let mf = m as f64;
        let g_ab = dot(&ga, &gb);
        out.surrogate = g_ab / (4.0 * mf * c);
        f.clear();
        for j in 0..l {
            let scale = batch.sigma[j] / (4.0 * mf * c);
            let d_a = &da[j * m..(j + 1) * m];
            let d_b = &db[j * m..(j + 1) * m];
            f.push(scale * (dot(&ga, d_b) + dot(&gb, d_a) - g_ab * dc_dsigma[j] / c));
        }

        delta_method_samples(batch, (c, dc_dsigma), &f, out);
        let result = out.grad_w_l.finish_with_mean(&f);
        if !out.surrogate.is_finite() {
            return Err(EstimatorError::NonFinite {
                what: "surrogate (intermediate overflow)",
            });
        }
        self.vec_a = ga;
        self.vec_b = gb;
        self.vec_c = da;
        self.vec_d = db;
        self.vec_f = f;
        result
    }

    /// [`Estimator::surrogate_gradient`] for a one-dimensional action, with `c(σ)` and
    /// `∂c/∂σ` of Theorem 4.2 taken from `sepg_bounds` at `σ = batch.sigma[0]`.
    ///
    /// # Formula
    /// ```text
    /// c(σ) = R M_φ² / ((1 − γ)² σ²) · (|A| / (√(2π) σ) + γ / (2(1 − γ)))
    /// ```
    ///
    /// # Errors
    /// [`EstimatorError::DimensionMismatch`] if `dim_w != 1`, [`EstimatorError::Bounds`] if
    /// `c` cannot be evaluated; otherwise as [`Estimator::surrogate_gradient`].
    ///
    /// # Examples
    /// ```
    /// use sepg_bounds::constants::TaskConstants;
    /// use sepg_estimators::{Estimator, GradientSpec, SurrogateEstimate};
    /// use sepg_mdp::Batch;
    /// let mut batch = Batch::zeros(4, 1, 1, 1, 0.9);
    /// batch.disc_rewards.copy_from_slice(&[1.0, 2.0, 1.5, 0.5]);
    /// batch.cum_score_v.copy_from_slice(&[1.0, -0.5, 0.3, 0.2]);
    /// let k = TaskConstants::new(0.9, 4.0, 2.0, 4.0)?;
    /// let mut out = SurrogateEstimate::new();
    /// Estimator::new().surrogate_gradient_for_task(&batch, GradientSpec::default(), &k, &mut out)?;
    /// assert!(out.grad_w_l().mean()[0].is_finite());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn surrogate_gradient_for_task(
        &mut self,
        batch: &Batch,
        spec: GradientSpec,
        task: &TaskConstants,
        out: &mut SurrogateEstimate,
    ) -> Result<(), EstimatorError> {
        if batch.dim_w != 1 || batch.sigma.len() != 1 {
            return Err(EstimatorError::DimensionMismatch {
                what: "dim_w (one action dimension)",
                expected: 1,
                found: batch.dim_w,
            });
        }
        let sigma = batch.sigma[0];
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(EstimatorError::InvalidSigma {
                index: 0,
                value: sigma,
            });
        }
        let c = penalty_c(task, sigma)?;
        let dc = dc_dsigma(task, sigma)?;
        self.surrogate_gradient(batch, spec, c, &[dc], out)
    }
}
/// Checks the penalty `c > 0` and its derivatives `∂c/∂σ_j` (one per exploration parameter,
/// finite) that the surrogate gradient takes.
fn check_surrogate_constants(
    batch: &Batch,
    c: f64,
    dc_dsigma: &[f64],
) -> Result<(), EstimatorError> {
    if !(c.is_finite() && c > 0.0) {
        return Err(EstimatorError::InvalidConstant {
            what: "c",
            value: c,
        });
    }
    if dc_dsigma.len() != batch.dim_w {
        return Err(EstimatorError::DimensionMismatch {
            what: "dc_dsigma",
            expected: batch.dim_w,
            found: dc_dsigma.len(),
        });
    }
    if let Some(&value) = dc_dsigma.iter().find(|x| !x.is_finite()) {
        return Err(EstimatorError::InvalidConstant {
            what: "dc/dsigma",
            value,
        });
    }
    Ok(())
}

/// The delta-method samples of ∇_w L around the full-batch means: the linearisation of `f`
/// (the cross-fitted ∇_w L) in each trajectory's ∇_v J and ∂_σ∇_v J samples, written into
/// `out.grad_w_l`; `(c, ∂c/∂σ)` as in [`Estimator::surrogate_gradient`].
fn delta_method_samples(
    batch: &Batch,
    (c, dc_dsigma): (f64, &[f64]),
    f: &[f64],
    out: &mut SurrogateEstimate,
) {
    let (n, m, l) = (batch.n, batch.dim_v, batch.dim_w);
    let mf = m as f64;
    let g_bar = out.grad_v.mean();
    let d_bar = out.mixed.mean();
    let zs = out.grad_w_l.reset(n, l);
    for i in 0..n {
        let gi = &out.grad_v.samples()[i * m..(i + 1) * m];
        let di = &out.mixed.samples()[i * l * m..(i + 1) * l * m];
        for j in 0..l {
            let scale = batch.sigma[j] / (4.0 * mf * c);
            let ratio = dc_dsigma[j] / c;
            let mut lin = 0.0;
            for k in 0..m {
                let dj = d_bar[j * m + k];
                let dg = 2.0 * dj - 2.0 * g_bar[k] * ratio;
                lin += dg * (gi[k] - g_bar[k]) + 2.0 * g_bar[k] * (di[j * m + k] - dj);
            }
            zs[i * l + j] = f[j] + scale * lin;
        }
    }
}
