//! The output of every estimator: the estimate, its per-trajectory samples and their variance.

use crate::error::EstimatorError;

/// An estimate of a `dim`-dimensional quantity from `n` trajectories, with the `n`
/// per-trajectory contributions whose mean is the estimate (Sec 4.5 needs them for the
/// sample variance of the confidence width).
///
/// # Formula
/// ```text
/// mean_k     = (1/n) Σ_i x_{i,k}
/// variance_k = (1/(n − 1)) Σ_i (x_{i,k} − mean_k)²      (unbiased sample variance)
/// ```
/// For the cross-fitted surrogate gradient the mean is the cross-fitted value and the samples
/// are its linearisation (see [`crate::Estimator::surrogate_gradient`]).
///
/// The buffers are reused: an `Estimate` passed again to an estimator of the same shape is
/// overwritten without allocating.
///
/// # Examples
/// ```
/// use sepg_estimators::{Estimate, Estimator};
/// use sepg_mdp::Batch;
/// let mut batch = Batch::zeros(2, 1, 1, 1, 0.99);
/// batch.disc_rewards.copy_from_slice(&[1.0, 3.0]);
/// let mut est = Estimate::new();
/// Estimator::new().value(&batch, &mut est)?;
/// assert_eq!(est.mean(), &[2.0]);
/// assert_eq!(est.samples(), &[1.0, 3.0]);
/// assert_eq!(est.variance(), &[2.0]);
/// # Ok::<(), sepg_estimators::EstimatorError>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct Estimate {
    n: usize,
    dim: usize,
    mean: Vec<f64>,
    samples: Vec<f64>,
    variance: Vec<f64>,
    centre: Vec<f64>,
}

impl Estimate {
    /// An empty estimate, to be filled by an [`crate::Estimator`].
    ///
    /// # Examples
    /// ```
    /// let est = sepg_estimators::Estimate::new();
    /// assert_eq!(est.n(), 0);
    /// assert!(est.mean().is_empty());
    /// ```
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of trajectories `n` (rows of [`Estimate::samples`]).
    ///
    /// # Examples
    /// ```
    /// assert_eq!(sepg_estimators::Estimate::new().n(), 0);
    /// ```
    pub fn n(&self) -> usize {
        self.n
    }

    /// Dimension of the estimated quantity (columns of [`Estimate::samples`]).
    ///
    /// # Examples
    /// ```
    /// assert_eq!(sepg_estimators::Estimate::new().dim(), 0);
    /// ```
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The estimate, length `dim`.
    ///
    /// # Examples
    /// ```
    /// assert!(sepg_estimators::Estimate::new().mean().is_empty());
    /// ```
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Per-trajectory samples, row-major: `samples()[i * dim + k]` is the contribution of
    /// trajectory `i` to component `k`; length `n · dim`.
    ///
    /// # Examples
    /// ```
    /// assert!(sepg_estimators::Estimate::new().samples().is_empty());
    /// ```
    pub fn samples(&self) -> &[f64] {
        &self.samples
    }

    /// The samples of trajectory `i` (length `dim`), or `None` if `i ≥ n`.
    ///
    /// # Examples
    /// ```
    /// assert!(sepg_estimators::Estimate::new().sample(0).is_none());
    /// ```
    pub fn sample(&self, i: usize) -> Option<&[f64]> {
        (i < self.n).then(|| &self.samples[i * self.dim..(i + 1) * self.dim])
    }

    /// Unbiased sample variance of the per-trajectory samples, per component (length `dim`):
    /// the `Var̂` of Sec 4.5. The variance of the estimate itself is `variance()[k] / n`.
    ///
    /// # Formula
    /// ```text
    /// variance_k = (1/(n − 1)) Σ_i (x_{i,k} − x̄_k)²
    /// ```
    ///
    /// # Examples
    /// ```
    /// assert!(sepg_estimators::Estimate::new().variance().is_empty());
    /// ```
    pub fn variance(&self) -> &[f64] {
        &self.variance
    }

    /// Infinity norm of the estimate, `max_k |mean_k|` (0 for an empty estimate).
    ///
    /// # Examples
    /// ```
    /// assert_eq!(sepg_estimators::Estimate::new().norm_inf(), 0.0);
    /// ```
    pub fn norm_inf(&self) -> f64 {
        self.mean.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// Sample skewness of component `k`, `γ̂_k = (1/n) Σ_i ((x_{i,k} − x̄_k)/s_k)³` with
    /// `s_k = √variance_k` (0 when `s_k = 0`). Standardising before cubing keeps every term
    /// below `n^{3/2}` in magnitude, so no overflow (and dividing, rather than multiplying by
    /// `1/s_k`, keeps a subnormal `s_k` finite).
    pub(crate) fn standardized_third_moment(&self, k: usize) -> f64 {
        let s = self.variance[k].sqrt();
        if s <= 0.0 {
            return 0.0;
        }
        let c = self.centre[k];
        let sum: f64 = self
            .samples
            .iter()
            .skip(k)
            .step_by(self.dim)
            .map(|x| {
                let z = (x - c) / s;
                z * z * z
            })
            .sum();
        sum / self.n as f64
    }

    /// Resizes the buffers to `n × dim` (no allocation when the capacity suffices) and returns
    /// the sample buffer to fill.
    pub(crate) fn reset(&mut self, n: usize, dim: usize) -> &mut [f64] {
        self.n = n;
        self.dim = dim;
        self.mean.resize(dim, 0.0);
        self.variance.resize(dim, 0.0);
        self.samples.resize(n * dim, 0.0);
        &mut self.samples
    }

    /// Computes the mean and the variance from the samples and checks that all are finite.
    pub(crate) fn finish(&mut self) -> Result<(), EstimatorError> {
        column_means(&self.samples, self.n, &mut self.mean);
        self.centre.clear();
        self.centre.extend_from_slice(&self.mean);
        self.finish_variance()
    }

    /// Sets the mean to `mean` (the samples are a linearisation whose mean is `mean` up to
    /// rounding), then computes the variance and checks finiteness.
    pub(crate) fn finish_with_mean(&mut self, mean: &[f64]) -> Result<(), EstimatorError> {
        self.mean.copy_from_slice(mean);
        self.centre.resize(self.dim, 0.0);
        column_means(&self.samples, self.n, &mut self.centre);
        self.finish_variance()
    }

    /// Two-pass variance, centred on the sample mean `centre`. A non-finite sample makes its
    /// column's variance NaN or infinite (`∞ − ∞`, NaN propagation), so checking the mean and
    /// the variance also checks every sample.
    fn finish_variance(&mut self) -> Result<(), EstimatorError> {
        if self.dim == 1 {
            // The same sum in the same order, without the per-row bookkeeping.
            let c = self.centre[0];
            self.variance[0] = self.samples.iter().fold(0.0, |v, x| v + (x - c) * (x - c));
        } else {
            self.variance.fill(0.0);
            for row in self.samples.chunks_exact(self.dim) {
                for ((v, x), c) in self.variance.iter_mut().zip(row).zip(&self.centre) {
                    *v += (x - c) * (x - c);
                }
            }
        }
        let inv_dof = 1.0 / (self.n as f64 - 1.0);
        for v in &mut self.variance {
            *v *= inv_dof;
        }
        let finite = |x: &f64| x.is_finite();
        if self.mean.iter().all(finite) && self.variance.iter().all(finite) {
            Ok(())
        } else {
            Err(EstimatorError::NonFinite {
                what: "estimate (non-finite batch data or overflow)",
            })
        }
    }
}

/// Column means of a row-major `n × dim` matrix (`dim = out.len()`), summed in row order.
fn column_means(samples: &[f64], n: usize, out: &mut [f64]) {
    if let [m] = out {
        // The same sum in the same order, without the per-row bookkeeping.
        *m = samples.iter().fold(0.0, |m, x| m + x);
    } else {
        out.fill(0.0);
        for row in samples.chunks_exact(out.len()) {
            for (m, x) in out.iter_mut().zip(row) {
                *m += x;
            }
        }
    }
    let inv_n = 1.0 / n as f64;
    for m in out.iter_mut() {
        *m *= inv_n;
    }
}
