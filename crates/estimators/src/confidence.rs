//! Confidence widths of the estimation error and the corrected gradient norms of Sec 4.5
//! (Assumption 4.6, eqs. (4.22)–(4.23)).

use std::cell::Cell;

use crate::error::EstimatorError;
use crate::estimate::Estimate;
use crate::quantile::student_t_quantile;

/// How the per-component half-width `ε_i` of the estimation error is computed (Sec 4.5).
///
/// With probability at least `1 − δ` (per component), `|∇_i F − ∇̂_i F| ≤ ε_i`:
/// exactly for Chebyshev (with the true variance), Hoeffding and empirical Bernstein;
/// asymptotically (central limit theorem) for Student-t, the choice of the thesis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Width {
    /// Student-t interval (Sec 4.5): `ε_i = t(1 − δ/2, N − 1) · √(Var_i / N)`.
    StudentT,
    /// Student-t interval corrected for the skewness of the samples by Hall's (1992) cubic
    /// transformation of the studentised mean. The CLT interval under-covers on skewed
    /// per-trajectory samples (Sec 4.5 notes it is asymptotic); the correction shifts both
    /// ends by about `(μ̂₃/Var)(1 + 2t²)/(6N)` in the direction of the skew, removing the
    /// `O(N^{-1/2})` coverage error of a skewed population.
    ///
    /// The interval is asymmetric: [`Estimate::intervals_into`] gives its ends, and the widths
    /// ([`Estimate::widths_into`], [`Estimate::confidence`]) are the half-width of the
    /// smallest interval centred on the estimate that contains it. It needs the third moment
    /// of the samples, so the free function [`width`] rejects it.
    ///
    /// # Formula
    /// ```text
    /// s = √Var,  γ̂ = (1/N) Σ_i ((x_i − x̄)/s)³,  b = γ̂/(6N),  y = t(1 − δ/2, N − 1)/√N
    /// g(T) = T + γ̂T²/3 + γ̂²T³/27 + b                    (increasing in T = (x̄ − μ)/s)
    /// g⁻¹(y) = 3(y − b) / (c² + c + 1),  c = ∛(1 + γ̂(y − b))
    /// interval: [x̄ − s g⁻¹(y), x̄ − s g⁻¹(−y)],   ε = s · max(g⁻¹(y), −g⁻¹(−y))
    /// ```
    /// With `γ̂ = 0` it is the Student-t interval. Reference: P. Hall, "On the removal of
    /// skewness by transformation", J. R. Statist. Soc. B 54 (1992) 221–228.
    SkewCorrectedT,
    /// Chebyshev's inequality with the sample variance: `ε_i = √(Var_i / (N δ))`.
    Chebyshev,
    /// Hoeffding's inequality for samples in an interval of length `range`:
    /// `ε_i = range · √(ln(2/δ) / (2N))` (two-sided).
    Hoeffding {
        /// Length `b − a` of an interval that contains every per-trajectory sample.
        range: f64,
    },
    /// Empirical Bernstein bound of Maurer & Pontil (2009, Thm 4), two-sided by a union bound
    /// over the two tails: `ε_i = √(2 Var_i ln(4/δ) / N) + 7 range ln(4/δ) / (3(N − 1))`.
    EmpiricalBernstein {
        /// Length `b − a` of an interval that contains every per-trajectory sample.
        range: f64,
    },
}

/// The per-component confidence half-width `ε_i` for a sample variance `variance` of `n`
/// per-trajectory samples (Sec 4.5, eq. (4.22)).
///
/// # Formula
/// ```text
/// StudentT:           ε = t(1 − δ/2, n − 1) · √(Var / n)
/// SkewCorrectedT:     needs the samples, see Estimate::widths_into
/// Chebyshev:          ε = √(Var / (n δ))
/// Hoeffding:          ε = range · √(ln(2/δ) / (2n))
/// EmpiricalBernstein: ε = √(2 Var ln(4/δ) / n) + 7 range ln(4/δ) / (3(n − 1))
/// ```
/// `variance` is the unbiased sample variance of the samples (units of the samples squared);
/// `ε` has the units of the samples.
///
/// # Errors
/// [`EstimatorError::TooFewTrajectories`] if `n < 2`; [`EstimatorError::InvalidDelta`] unless
/// `0 < δ < 1`; [`EstimatorError::NonFinite`] if `variance` is negative or not finite;
/// [`EstimatorError::InvalidRange`] for a range that is not finite and positive;
/// [`EstimatorError::NeedsSamples`] for [`Width::SkewCorrectedT`].
///
/// # Examples
/// ```
/// use sepg_estimators::{width, Width};
/// // Chebyshev with Var = 4, n = 100, δ = 0.04: √(4 / 4) = 1.
/// assert_eq!(width(Width::Chebyshev, 4.0, 100, 0.04)?, 1.0);
/// assert!(width(Width::StudentT, 4.0, 100, 1.5).is_err());
/// assert!(width(Width::SkewCorrectedT, 4.0, 100, 0.05).is_err());
/// # Ok::<(), sepg_estimators::EstimatorError>(())
/// ```
pub fn width(method: Width, variance: f64, n: usize, delta: f64) -> Result<f64, EstimatorError> {
    if !(variance >= 0.0 && variance.is_finite()) {
        return Err(EstimatorError::NonFinite { what: "variance" });
    }
    if method == Width::SkewCorrectedT {
        return Err(EstimatorError::NeedsSamples {
            method: "skew-corrected Student-t",
        });
    }
    finite_width(Factors::new(method, n, delta)?.width(variance))
}

/// A width, or [`EstimatorError::NonFinite`] if it overflowed (e.g. δ near the smallest
/// positive f64, or a range near f64::MAX): never returned as `+∞`.
fn finite_width(w: f64) -> Result<f64, EstimatorError> {
    if w.is_finite() {
        Ok(w)
    } else {
        Err(EstimatorError::NonFinite {
            what: "confidence width",
        })
    }
}

/// The variance-independent parts of a width, computed once per call.
struct Factors {
    /// Multiplies `√Var`.
    scale: f64,
    /// Added to the width.
    offset: f64,
}

impl Factors {
    fn new(method: Width, n: usize, delta: f64) -> Result<Self, EstimatorError> {
        if n < 2 {
            return Err(EstimatorError::TooFewTrajectories { n, min: 2 });
        }
        if !(delta > 0.0 && delta < 1.0) {
            return Err(EstimatorError::InvalidDelta { delta });
        }
        let nf = n as f64;
        let check_range = |range: f64| {
            if range > 0.0 && range.is_finite() {
                Ok(range)
            } else {
                Err(EstimatorError::InvalidRange { range })
            }
        };
        Ok(match method {
            Width::StudentT | Width::SkewCorrectedT => Factors {
                scale: cached_t_quantile(1.0 - 0.5 * delta, nf - 1.0)? / nf.sqrt(),
                offset: 0.0,
            },
            Width::Chebyshev => Factors {
                scale: 1.0 / (nf * delta).sqrt(),
                offset: 0.0,
            },
            Width::Hoeffding { range } => Factors {
                scale: 0.0,
                offset: check_range(range)?
                    * ((std::f64::consts::LN_2 - delta.ln()) / (2.0 * nf)).sqrt(),
            },
            Width::EmpiricalBernstein { range } => {
                let log_term = 2.0 * std::f64::consts::LN_2 - delta.ln();
                Factors {
                    scale: (2.0 * log_term / nf).sqrt(),
                    offset: 7.0 * check_range(range)? * log_term / (3.0 * (nf - 1.0)),
                }
            }
        })
    }

    fn width(&self, variance: f64) -> f64 {
        self.scale * variance.sqrt() + self.offset
    }
}

/// Ends of Hall's skew-corrected interval relative to the estimate, `(lo, hi)` with
/// `lo ≤ 0 ≤ hi` (see [`Width::SkewCorrectedT`]); `y = t/√n`, `s = √Var`, `gamma = γ̂`.
fn hall_offsets(y: f64, s: f64, gamma: f64, n: f64) -> (f64, f64) {
    let b = gamma / (6.0 * n);
    let g_inv = |y: f64| {
        let c = (1.0 + gamma * (y - b)).cbrt();
        3.0 * (y - b) / (c * c + c + 1.0)
    };
    (-s * g_inv(y), -s * g_inv(-y))
}

thread_local! {
    /// The last `(p, ν, t(p, ν))` evaluated on this thread: a learner asks for the same
    /// quantile every iteration.
    static LAST_T: Cell<(f64, f64, f64)> = const { Cell::new((f64::NAN, f64::NAN, f64::NAN)) };
}

/// [`student_t_quantile`] memoised on its last arguments (a pure function, so the result is
/// the same bits with or without the memo).
fn cached_t_quantile(p: f64, nu: f64) -> Result<f64, EstimatorError> {
    let (lp, lnu, lt) = LAST_T.with(Cell::get);
    if lp == p && lnu == nu {
        return Ok(lt);
    }
    let t = student_t_quantile(p, nu)?;
    LAST_T.with(|c| c.set((p, nu, t)));
    Ok(t)
}

/// Corrected infinity norms of an estimated gradient (Sec 4.5):
/// `‖∇̂‖∞⁻ = ‖∇̂‖∞ − ε` and `‖∇̂‖∞⁺ = ‖∇̂‖∞ + ε` with `ε = max_i ε_i`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Confidence {
    /// `‖∇̂‖∞ = max_i |∇̂_i|`.
    pub norm_inf: f64,
    /// `ε = max_i ε_i`, the largest per-component half-width.
    pub eps: f64,
}

impl Confidence {
    /// Lower-corrected norm `‖∇̂‖∞⁻ = ‖∇̂‖∞ − ε` (may be negative when (4.23) fails).
    ///
    /// # Examples
    /// ```
    /// let c = sepg_estimators::Confidence { norm_inf: 3.0, eps: 1.0 };
    /// assert_eq!(c.lower(), 2.0);
    /// ```
    pub fn lower(&self) -> f64 {
        self.norm_inf - self.eps
    }

    /// Upper-corrected norm `‖∇̂‖∞⁺ = ‖∇̂‖∞ + ε`.
    ///
    /// # Examples
    /// ```
    /// let c = sepg_estimators::Confidence { norm_inf: 3.0, eps: 1.0 };
    /// assert_eq!(c.upper(), 4.0);
    /// ```
    pub fn upper(&self) -> f64 {
        self.norm_inf + self.eps
    }

    /// Condition (4.23), `‖∇̂‖∞ > ε`: some component stands out of the estimation noise, so
    /// `‖∇̂‖∞⁻ > 0` and a reliable update can be made.
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::Confidence;
    /// assert!(Confidence { norm_inf: 3.0, eps: 1.0 }.above_noise());
    /// assert!(!Confidence { norm_inf: 1.0, eps: 1.0 }.above_noise());
    /// ```
    pub fn above_noise(&self) -> bool {
        self.norm_inf > self.eps
    }
}

impl Estimate {
    /// Writes the per-component half-widths `ε_i` into `out` (length `dim`) and returns
    /// `ε = max_i ε_i` (Sec 4.5).
    ///
    /// # Formula
    /// See [`width`]; `Var_i` is [`Estimate::variance`] and `N` is [`Estimate::n`].
    ///
    /// # Errors
    /// As [`width`], plus [`EstimatorError::DimensionMismatch`] if `out.len() != dim`.
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Estimate, Estimator, Width};
    /// use sepg_mdp::Batch;
    /// let mut batch = Batch::zeros(4, 1, 1, 1, 0.9);
    /// batch.disc_rewards.copy_from_slice(&[1.0, 2.0, 3.0, 4.0]);
    /// let mut est = Estimate::new();
    /// Estimator::new().value(&batch, &mut est)?;
    /// let mut eps = [0.0];
    /// // Var = 5/3, Chebyshev with δ = 0.5: √(5/3 / 2).
    /// let e = est.widths_into(Width::Chebyshev, 0.5, &mut eps)?;
    /// assert!((e - (5.0f64 / 6.0).sqrt()).abs() < 1e-15);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn widths_into(
        &self,
        method: Width,
        delta: f64,
        out: &mut [f64],
    ) -> Result<f64, EstimatorError> {
        if out.len() != self.dim() {
            return Err(EstimatorError::DimensionMismatch {
                what: "widths buffer",
                expected: self.dim(),
                found: out.len(),
            });
        }
        let f = Factors::new(method, self.n(), delta)?;
        let mut eps = 0.0f64;
        for (k, (o, v)) in out.iter_mut().zip(self.variance()).enumerate() {
            *o = if method == Width::SkewCorrectedT {
                let (lo, hi) = self.hall(f.scale, k);
                hi.max(-lo)
            } else {
                f.width(*v)
            };
            eps = eps.max(*o);
        }
        finite_width(eps)
    }

    /// Writes the confidence interval `[lower_i, upper_i]` of every component (Sec 4.5):
    /// `mean_i ∓ ε_i` for the symmetric methods, the asymmetric ends of Hall's interval for
    /// [`Width::SkewCorrectedT`].
    ///
    /// # Formula
    /// ```text
    /// symmetric:        [mean_i − ε_i, mean_i + ε_i]       (ε_i of `width`)
    /// SkewCorrectedT:   [mean_i − s_i g⁻¹(y), mean_i − s_i g⁻¹(−y)]
    /// ```
    ///
    /// # Errors
    /// As [`Estimate::widths_into`], for either buffer.
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Estimate, Estimator, Width};
    /// use sepg_mdp::Batch;
    /// // Right-skewed returns: the corrected interval is shifted up.
    /// let mut batch = Batch::zeros(6, 1, 1, 1, 0.9);
    /// batch.disc_rewards.copy_from_slice(&[0.0, 0.1, 0.0, 0.2, 0.1, 3.0]);
    /// let mut est = Estimate::new();
    /// Estimator::new().value(&batch, &mut est)?;
    /// let (mut lo, mut hi) = ([0.0], [0.0]);
    /// est.intervals_into(Width::SkewCorrectedT, 0.1, &mut lo, &mut hi)?;
    /// let mean = est.mean()[0];
    /// assert!(hi[0] - mean > mean - lo[0]);
    /// est.intervals_into(Width::StudentT, 0.1, &mut lo, &mut hi)?;
    /// assert!((hi[0] - mean - (mean - lo[0])).abs() < 1e-15);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn intervals_into(
        &self,
        method: Width,
        delta: f64,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), EstimatorError> {
        for buffer in [&*lower, &*upper] {
            if buffer.len() != self.dim() {
                return Err(EstimatorError::DimensionMismatch {
                    what: "interval buffer",
                    expected: self.dim(),
                    found: buffer.len(),
                });
            }
        }
        let f = Factors::new(method, self.n(), delta)?;
        let parts = lower.iter_mut().zip(upper.iter_mut());
        for (k, ((lo, hi), (m, v))) in parts
            .zip(self.mean().iter().zip(self.variance()))
            .enumerate()
        {
            let (dlo, dhi) = if method == Width::SkewCorrectedT {
                self.hall(f.scale, k)
            } else {
                let e = f.width(*v);
                (-e, e)
            };
            *lo = m + dlo;
            *hi = m + dhi;
        }
        Ok(())
    }

    /// Hall's interval ends of component `k` relative to the estimate, for `y = t/√n`.
    fn hall(&self, y: f64, k: usize) -> (f64, f64) {
        let s = self.variance()[k].sqrt();
        let gamma = self.standardized_third_moment(k);
        hall_offsets(y, s, gamma, self.n() as f64)
    }

    /// The corrected norms of Sec 4.5 for this estimate: `‖∇̂‖∞` and `ε = max_i ε_i`
    /// (no allocation).
    ///
    /// # Formula
    /// ```text
    /// ‖∇̂‖∞⁻ = max_i |∇̂_i| − max_i ε_i,   ‖∇̂‖∞⁺ = max_i |∇̂_i| + max_i ε_i
    /// ```
    ///
    /// # Errors
    /// As [`width`].
    ///
    /// # Examples
    /// ```
    /// use sepg_estimators::{Estimate, Estimator, Width};
    /// use sepg_mdp::Batch;
    /// let mut batch = Batch::zeros(4, 1, 1, 1, 0.9);
    /// batch.disc_rewards.copy_from_slice(&[1.0, 2.0, 3.0, 4.0]);
    /// let mut est = Estimate::new();
    /// Estimator::new().value(&batch, &mut est)?;
    /// let c = est.confidence(Width::Hoeffding { range: 3.0 }, 0.1)?;
    /// assert_eq!(c.norm_inf, 2.5);
    /// assert!((c.eps - 3.0 * (20f64.ln() / 8.0).sqrt()).abs() < 1e-15);
    /// # Ok::<(), sepg_estimators::EstimatorError>(())
    /// ```
    pub fn confidence(&self, method: Width, delta: f64) -> Result<Confidence, EstimatorError> {
        let f = Factors::new(method, self.n(), delta)?;
        let eps = if method == Width::SkewCorrectedT {
            (0..self.dim()).fold(0.0f64, |e, k| {
                let (lo, hi) = self.hall(f.scale, k);
                e.max(hi).max(-lo)
            })
        } else {
            self.variance()
                .iter()
                .fold(0.0f64, |e, v| e.max(f.width(*v)))
        };
        let eps = finite_width(eps)?;
        Ok(Confidence {
            norm_inf: self.norm_inf(),
            eps,
        })
    }
}
