//! The linear-quadratic-Gaussian (LQG) problem description shared by the LQG environments and
//! the exact LQG oracles.
//!
//! The thesis's LQG (Sec 5.1) is one-dimensional; [`LqgModel`] describes the general
//! `n`-state, `l`-action problem of docs/CONVENTIONS.md §1 (`lqg-nd`), and the two presets of docs/CONVENTIONS.md §1 are
//! [`LqgModel::thesis`] (`lqg`) and [`LqgModel::lqg1d`] (`lqg1d`).
//!
//! # Formula
//! ```text
//! a_c   = clip(a, action_low, action_high)                 (component-wise)
//! r     = −(sᵀ Q s + a_cᵀ R a_c)                           (pre-step state s)
//! s'    = clip(A s + B a_c + η, state_low, state_high),    η ~ N(0, diag(noise_std²))
//! s_0   ~ U[init_low, init_high]                           (independent components)
//! ```
//! When [`LqgModel::clipping`] is `false` neither the action nor the next state is clipped
//! (the setting of the closed-form oracles); the derived constants [`LqgModel::r_max`],
//! [`LqgModel::m_phi`] and [`LqgModel::action_volume`] then describe the boxes only, and are
//! bounds on the actual rewards and states only while trajectories stay inside the boxes.

use nalgebra::{DMatrix, DVector};

/// Largest dimension for which [`LqgModel::r_max`] enumerates every box corner exactly
/// (`2^16` corners); above it a guaranteed upper bound is returned instead.
const EXACT_CORNER_MAX_DIM: usize = 16;

/// Relative tolerance used to accept `Q` and `R` as symmetric and positive semi-definite.
const PSD_TOL: f64 = 1e-10;

/// Validation errors of [`LqgModel`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// The state or action dimension is zero.
    #[error("the state and action dimensions must be at least 1 (got n = {n}, l = {l})")]
    EmptyDimension {
        /// State dimension `n`.
        n: usize,
        /// Action dimension `l`.
        l: usize,
    },
    /// A matrix or vector does not have the dimensions implied by `A` (n×n) and `B` (n×l).
    #[error("{what} has shape {found_rows}×{found_cols}, expected {expected_rows}×{expected_cols}")]
    DimensionMismatch {
        /// Name of the offending field.
        what: &'static str,
        /// Expected number of rows.
        expected_rows: usize,
        /// Expected number of columns.
        expected_cols: usize,
        /// Actual number of rows.
        found_rows: usize,
        /// Actual number of columns.
        found_cols: usize,
    },
    /// A field contains NaN or ±∞.
    #[error("{what} contains a non-finite value")]
    NonFinite {
        /// Name of the offending field.
        what: &'static str,
    },
    /// A box has `low > high` (or `low = high` for the state and action boxes) in a component.
    #[error("{what} box is not ordered in component {index}: low = {low}, high = {high}")]
    UnorderedBox {
        /// Which box (`"state"`, `"action"` or `"init"`).
        what: &'static str,
        /// Component index.
        index: usize,
        /// Lower end.
        low: f64,
        /// Upper end.
        high: f64,
    },
    /// The initial-state box is not contained in the state box (with clipping on).
    #[error("init box leaves the state box in component {index}")]
    InitOutsideState {
        /// Component index.
        index: usize,
    },
    /// The discount factor is outside `[0, 1)`.
    #[error("discount factor gamma = {0} is outside [0, 1)")]
    InvalidGamma(f64),
    /// A noise standard deviation is negative.
    #[error("noise_std[{index}] = {value} is negative")]
    NegativeNoise {
        /// Component index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// `Q` or `R` is not symmetric (relative tolerance 1e-10).
    #[error("{what} is not symmetric")]
    NotSymmetric {
        /// `"q"` or `"r"`.
        what: &'static str,
    },
    /// `Q` or `R` has a negative eigenvalue beyond the relative tolerance 1e-10.
    #[error("{what} is not positive semi-definite (smallest eigenvalue {min_eigenvalue})")]
    NotPsd {
        /// `"q"` or `"r"`.
        what: &'static str,
        /// Smallest eigenvalue found.
        min_eigenvalue: f64,
    },
}

/// An axis-aligned box `[low, high]` (component-wise), used for the state, action and
/// initial-state sets of an [`LqgModel`].
#[derive(Debug, Clone, PartialEq)]
pub struct BoxBounds {
    /// Lower corner.
    pub low: DVector<f64>,
    /// Upper corner.
    pub high: DVector<f64>,
}

impl BoxBounds {
    /// The box `[low, high]` from its two corners (validated when used in [`LqgModel::new`]).
    ///
    /// ```
    /// use nalgebra::DVector;
    /// use sepg_mdp::lqg_model::BoxBounds;
    /// let b = BoxBounds::new(DVector::from_vec(vec![-1.0, 0.0]), DVector::from_vec(vec![1.0, 2.0]));
    /// assert_eq!(b.high[1], 2.0);
    /// ```
    pub fn new(low: DVector<f64>, high: DVector<f64>) -> Self {
        BoxBounds { low, high }
    }

    /// The cube `[low, high]^dim` (every component has the same range).
    ///
    /// ```
    /// use sepg_mdp::lqg_model::BoxBounds;
    /// let b = BoxBounds::cube(3, -2.0, 2.0);
    /// assert_eq!(b.low.len(), 3);
    /// assert_eq!(b.low[2], -2.0);
    /// ```
    pub fn cube(dim: usize, low: f64, high: f64) -> Self {
        BoxBounds {
            low: DVector::from_element(dim, low),
            high: DVector::from_element(dim, high),
        }
    }
}

/// A linear-quadratic-Gaussian problem (thesis Sec 5.1; docs/CONVENTIONS.md §1 `lqg`, `lqg1d`, `lqg-nd`):
/// `s' = A s + B a_c + η`, `η ~ N(0, diag(noise_std²))`, reward `r = −(sᵀQs + a_cᵀ R a_c)` on
/// the pre-step state, `a_c` the action clipped to the action box, `s'` clipped to the state box
/// (when [`clipping`](Self::clipping) is on), `s_0 ~ U[init_low, init_high]` per component.
///
/// Build it with [`LqgModel::new`] (validated) or a preset. The fields are public for reading;
/// a model mutated by hand should be re-checked with [`LqgModel::validate`].
///
/// # Formula
/// ```text
/// a_c = clip(a),  r = −(sᵀQs + a_cᵀRa_c),  s' = clip(A s + B a_c + η)
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct LqgModel {
    /// State transition matrix `A` (n×n).
    pub a: DMatrix<f64>,
    /// Control matrix `B` (n×l).
    pub b: DMatrix<f64>,
    /// State cost `Q` (n×n, symmetric positive semi-definite).
    pub q: DMatrix<f64>,
    /// Action cost `R` (l×l, symmetric positive semi-definite).
    pub r: DMatrix<f64>,
    /// Per-component transition-noise standard deviations (length n, ≥ 0; default 0, docs/CONVENTIONS.md §1).
    pub noise_std: DVector<f64>,
    /// Lower corner of the state box `S`.
    pub state_low: DVector<f64>,
    /// Upper corner of the state box `S`.
    pub state_high: DVector<f64>,
    /// Lower corner of the action box `A`.
    pub action_low: DVector<f64>,
    /// Upper corner of the action box `A`.
    pub action_high: DVector<f64>,
    /// Lower corner of the initial-state box.
    pub init_low: DVector<f64>,
    /// Upper corner of the initial-state box.
    pub init_high: DVector<f64>,
    /// Discount factor `γ ∈ [0, 1)` (default 0.99, docs/CONVENTIONS.md §1).
    pub gamma: f64,
    /// Whether actions and next states are clipped to their boxes (default `true`).
    pub clipping: bool,
}

impl LqgModel {
    /// A validated model with zero transition noise, `γ = 0.99` and clipping on (docs/CONVENTIONS.md §1
    /// defaults); change them with [`with_noise`](Self::with_noise),
    /// [`with_gamma`](Self::with_gamma) and [`with_clipping`](Self::with_clipping).
    ///
    /// Checks: `n, l ≥ 1`; shapes `A` n×n, `B` n×l, `Q` n×n, `R` l×l, boxes of lengths n, l, n;
    /// finiteness; `state_low < state_high`, `action_low < action_high`,
    /// `init_low ≤ init_high` component-wise; init box inside the state box; `Q`, `R`
    /// symmetric and positive semi-definite (relative tolerance 1e-10).
    ///
    /// # Formula
    /// ```text
    /// s' = clip(A s + B clip(a)),   r = −(sᵀQs + clip(a)ᵀ R clip(a))
    /// ```
    ///
    /// ```
    /// use nalgebra::DMatrix;
    /// use sepg_mdp::lqg_model::{BoxBounds, LqgModel};
    /// let m = LqgModel::new(
    ///     DMatrix::identity(2, 2),
    ///     DMatrix::identity(2, 1),
    ///     DMatrix::identity(2, 2),
    ///     DMatrix::identity(1, 1),
    ///     BoxBounds::cube(2, -1.0, 1.0),
    ///     BoxBounds::cube(1, -1.0, 1.0),
    ///     BoxBounds::cube(2, -0.5, 0.5),
    /// )
    /// .unwrap();
    /// assert_eq!(m.state_dim(), 2);
    /// assert_eq!(m.r_max(), 3.0); // corners: sᵀs = 2, a² = 1
    /// ```
    pub fn new(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        q: DMatrix<f64>,
        r: DMatrix<f64>,
        state_box: BoxBounds,
        action_box: BoxBounds,
        init_box: BoxBounds,
    ) -> Result<Self, ModelError> {
        let n = a.nrows();
        let model = LqgModel {
            a,
            b,
            q,
            r,
            noise_std: DVector::zeros(n),
            state_low: state_box.low,
            state_high: state_box.high,
            action_low: action_box.low,
            action_high: action_box.high,
            init_low: init_box.low,
            init_high: init_box.high,
            gamma: 0.99,
            clipping: true,
        };
        model.validate()?;
        Ok(model)
    }

    /// The scalar LQG `s' = a_s s + b_s a` with `r = −(q_s s² + r_s a²)`, state and action in
    /// `[−bound, bound]`, `s_0 ~ U[−bound, bound]`, `γ = 0.99`, no noise, clipping on.
    ///
    /// # Formula
    /// ```text
    /// s' = clip(a_s s + b_s clip(a)),   r = −(q_s s² + r_s clip(a)²)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// let m = LqgModel::scalar(1.0, 1.0, 0.5, 0.5, 2.0).unwrap();
    /// assert_eq!(m, LqgModel::thesis());
    /// ```
    pub fn scalar(a_s: f64, b_s: f64, q_s: f64, r_s: f64, bound: f64) -> Result<Self, ModelError> {
        LqgModel::new(
            DMatrix::from_element(1, 1, a_s),
            DMatrix::from_element(1, 1, b_s),
            DMatrix::from_element(1, 1, q_s),
            DMatrix::from_element(1, 1, r_s),
            BoxBounds::cube(1, -bound, bound),
            BoxBounds::cube(1, -bound, bound),
            BoxBounds::cube(1, -bound, bound),
        )
    }

    /// docs/CONVENTIONS.md §1 preset `lqg`, the LQG of thesis Sec 5.1 as written: `A = B = 1`,
    /// `Q = R = 0.5`, `S = A = [−2, 2]`, `s_0 ~ U[−2, 2]`, `γ = 0.99`, no noise.
    /// Its constants are `r_max = 4`, `m_phi = 2`, `|A| = 4`.
    ///
    /// # Formula
    /// ```text
    /// s' = clip(s + clip(a), −2, 2),   r = −0.5 (s² + clip(a)²)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// let m = LqgModel::thesis();
    /// assert_eq!((m.r_max(), m.m_phi(), m.action_volume()), (4.0, 2.0, 4.0));
    /// ```
    pub fn thesis() -> Self {
        LqgModel::scalar_preset(0.5, 2.0)
    }

    /// docs/CONVENTIONS.md §1 preset `lqg1d`, the 1-D LQG of the public code the thesis's numbers came from:
    /// `A = B = 1`, `Q = R = 0.9`, `S = A = [−4, 4]`, `s_0 ~ U[−4, 4]`, `γ = 0.99`, no noise.
    /// Its constants are `r_max = 28.8`, `m_phi = 4`, `|A| = 8`.
    ///
    /// # Formula
    /// ```text
    /// s' = clip(s + clip(a), −4, 4),   r = −0.9 (s² + clip(a)²)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// let m = LqgModel::lqg1d();
    /// assert!((m.r_max() - 28.8).abs() < 1e-12);
    /// assert_eq!((m.m_phi(), m.action_volume()), (4.0, 8.0));
    /// ```
    pub fn lqg1d() -> Self {
        LqgModel::scalar_preset(0.9, 4.0)
    }

    /// The presets `A = B = 1`, `Q = R = cost`, every box `[−bound, bound]` (infallible).
    fn scalar_preset(cost: f64, bound: f64) -> Self {
        let one = DMatrix::from_element(1, 1, 1.0);
        let c = DMatrix::from_element(1, 1, cost);
        let lo = DVector::from_element(1, -bound);
        let hi = DVector::from_element(1, bound);
        LqgModel {
            a: one.clone(),
            b: one,
            q: c.clone(),
            r: c,
            noise_std: DVector::zeros(1),
            state_low: lo.clone(),
            state_high: hi.clone(),
            action_low: lo.clone(),
            action_high: hi.clone(),
            init_low: lo,
            init_high: hi,
            gamma: 0.99,
            clipping: true,
        }
    }

    /// The same model with discount factor `gamma ∈ [0, 1)`.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// assert_eq!(LqgModel::thesis().with_gamma(0.9).unwrap().gamma, 0.9);
    /// assert!(LqgModel::thesis().with_gamma(1.0).is_err());
    /// ```
    pub fn with_gamma(mut self, gamma: f64) -> Result<Self, ModelError> {
        self.gamma = gamma;
        self.validate()?;
        Ok(self)
    }

    /// The same model with transition-noise standard deviations `noise_std` (length n, ≥ 0).
    ///
    /// # Formula
    /// ```text
    /// η ~ N(0, diag(noise_std²))
    /// ```
    ///
    /// ```
    /// use nalgebra::DVector;
    /// use sepg_mdp::lqg_model::LqgModel;
    /// let m = LqgModel::thesis().with_noise(DVector::from_element(1, 0.1)).unwrap();
    /// assert_eq!(m.noise_std[0], 0.1);
    /// assert!(LqgModel::thesis().with_noise(DVector::from_element(1, -0.1)).is_err());
    /// ```
    pub fn with_noise(mut self, noise_std: DVector<f64>) -> Result<Self, ModelError> {
        self.noise_std = noise_std;
        self.validate()?;
        Ok(self)
    }

    /// The same model with clipping of actions and next states switched on or off.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// assert!(!LqgModel::thesis().with_clipping(false).clipping);
    /// ```
    pub fn with_clipping(mut self, clipping: bool) -> Self {
        self.clipping = clipping;
        self
    }

    /// Checks every invariant listed in [`LqgModel::new`].
    ///
    /// ```
    /// use sepg_mdp::lqg_model::{LqgModel, ModelError};
    /// let mut m = LqgModel::thesis();
    /// assert!(m.validate().is_ok());
    /// m.gamma = f64::NAN;
    /// assert!(matches!(m.validate(), Err(ModelError::InvalidGamma(_))));
    /// ```
    pub fn validate(&self) -> Result<(), ModelError> {
        let n = self.a.nrows();
        let l = self.b.ncols();
        if n == 0 || l == 0 {
            return Err(ModelError::EmptyDimension { n, l });
        }
        check_shape("a", self.a.shape(), (n, n))?;
        check_shape("b", self.b.shape(), (n, l))?;
        check_shape("q", self.q.shape(), (n, n))?;
        check_shape("r", self.r.shape(), (l, l))?;
        for (what, v, len) in [
            ("noise_std", &self.noise_std, n),
            ("state_low", &self.state_low, n),
            ("state_high", &self.state_high, n),
            ("action_low", &self.action_low, l),
            ("action_high", &self.action_high, l),
            ("init_low", &self.init_low, n),
            ("init_high", &self.init_high, n),
        ] {
            check_shape(what, (v.len(), 1), (len, 1))?;
            check_finite(what, v.as_slice())?;
        }
        for (what, m) in [
            ("a", &self.a),
            ("b", &self.b),
            ("q", &self.q),
            ("r", &self.r),
        ] {
            check_finite(what, m.as_slice())?;
        }
        if !(0.0..1.0).contains(&self.gamma) {
            return Err(ModelError::InvalidGamma(self.gamma));
        }
        if let Some((index, &value)) = self.noise_std.iter().enumerate().find(|(_, x)| **x < 0.0) {
            return Err(ModelError::NegativeNoise { index, value });
        }
        check_box("state", &self.state_low, &self.state_high, true)?;
        check_box("action", &self.action_low, &self.action_high, true)?;
        check_box("init", &self.init_low, &self.init_high, false)?;
        if self.clipping {
            for i in 0..n {
                if self.init_low[i] < self.state_low[i] || self.init_high[i] > self.state_high[i] {
                    return Err(ModelError::InitOutsideState { index: i });
                }
            }
        }
        check_psd("q", &self.q)?;
        check_psd("r", &self.r)?;
        // Finite but huge entries can make the bound constants overflow.
        for (what, value) in [
            ("R_max", self.r_max()),
            ("action volume |A|", self.action_volume()),
        ] {
            if !value.is_finite() {
                return Err(ModelError::NonFinite { what });
            }
        }
        Ok(())
    }

    /// State dimension `n`.
    ///
    /// ```
    /// assert_eq!(sepg_mdp::lqg_model::LqgModel::thesis().state_dim(), 1);
    /// ```
    pub fn state_dim(&self) -> usize {
        self.a.nrows()
    }

    /// Action dimension `l`.
    ///
    /// ```
    /// assert_eq!(sepg_mdp::lqg_model::LqgModel::thesis().action_dim(), 1);
    /// ```
    pub fn action_dim(&self) -> usize {
        self.b.ncols()
    }

    /// `R_max`, the largest |reward| over the state and action boxes (the constant of
    /// Theorem 4.3 and Sec 5.1). The cost is a sum of two convex quadratics, so each maximum
    /// over a box is reached at a corner; for dimensions up to 16 (`2^16` corners) every
    /// corner is enumerated (exact), above it the upper bound `Σ_ij |Q_ij| m_i m_j` with
    /// `m_i = max(|low_i|, |high_i|)` is returned.
    ///
    /// # Formula
    /// ```text
    /// R_max = max_{s ∈ corners(S)} sᵀQs + max_{a ∈ corners(A)} aᵀRa
    /// 1-D:    R_max = Q s_max² + R a_max²
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// assert_eq!(LqgModel::thesis().r_max(), 4.0);
    /// ```
    pub fn r_max(&self) -> f64 {
        max_quadratic_over_box(&self.q, &self.state_low, &self.state_high)
            + max_quadratic_over_box(&self.r, &self.action_low, &self.action_high)
    }

    /// `M_φ`, the largest |feature| when the features are the state itself (φ(s) = s): the
    /// largest absolute state component over the state box.
    ///
    /// # Formula
    /// ```text
    /// M_φ = max_i max(|state_low_i|, |state_high_i|)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// assert_eq!(LqgModel::lqg1d().m_phi(), 4.0);
    /// ```
    pub fn m_phi(&self) -> f64 {
        self.state_low
            .iter()
            .chain(self.state_high.iter())
            .fold(0.0, |m, x| m.max(x.abs()))
    }

    /// `|A|`, the volume (Lebesgue measure) of the action box, used by the bounds of
    /// Theorem 4.3 (eq. 4.16).
    ///
    /// # Formula
    /// ```text
    /// |A| = Π_j (action_high_j − action_low_j)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// assert_eq!(LqgModel::thesis().action_volume(), 4.0);
    /// ```
    pub fn action_volume(&self) -> f64 {
        self.action_low
            .iter()
            .zip(self.action_high.iter())
            .map(|(lo, hi)| hi - lo)
            .product()
    }

    /// Whether the model is the scalar problem (`n = l = 1`), which the rollout engine runs on
    /// a specialised path.
    ///
    /// ```
    /// assert!(sepg_mdp::lqg_model::LqgModel::thesis().is_scalar());
    /// ```
    pub fn is_scalar(&self) -> bool {
        self.state_dim() == 1 && self.action_dim() == 1
    }
}

fn check_shape(
    what: &'static str,
    found: (usize, usize),
    expected: (usize, usize),
) -> Result<(), ModelError> {
    if found == expected {
        Ok(())
    } else {
        Err(ModelError::DimensionMismatch {
            what,
            expected_rows: expected.0,
            expected_cols: expected.1,
            found_rows: found.0,
            found_cols: found.1,
        })
    }
}

fn check_finite(what: &'static str, xs: &[f64]) -> Result<(), ModelError> {
    if xs.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::NonFinite { what })
    }
}

fn check_box(
    what: &'static str,
    low: &DVector<f64>,
    high: &DVector<f64>,
    strict: bool,
) -> Result<(), ModelError> {
    for (index, (&lo, &hi)) in low.iter().zip(high.iter()).enumerate() {
        let ordered = if strict { lo < hi } else { lo <= hi };
        if !ordered {
            return Err(ModelError::UnorderedBox {
                what,
                index,
                low: lo,
                high: hi,
            });
        }
    }
    Ok(())
}

fn check_psd(what: &'static str, m: &DMatrix<f64>) -> Result<(), ModelError> {
    let scale = m.amax().max(f64::MIN_POSITIVE);
    if (m - m.transpose()).amax() > PSD_TOL * scale {
        return Err(ModelError::NotSymmetric { what });
    }
    let sym = (m + m.transpose()) * 0.5;
    let min_eigenvalue = sym.symmetric_eigenvalues().min();
    if min_eigenvalue < -PSD_TOL * scale {
        return Err(ModelError::NotPsd {
            what,
            min_eigenvalue,
        });
    }
    Ok(())
}

/// `max_{x ∈ [low, high]} xᵀMx` for a PSD `M` (convex, so a corner is optimal): exact corner
/// enumeration up to [`EXACT_CORNER_MAX_DIM`], else the bound `Σ_ij |M_ij| m_i m_j`.
fn max_quadratic_over_box(m: &DMatrix<f64>, low: &DVector<f64>, high: &DVector<f64>) -> f64 {
    let d = low.len();
    if d > EXACT_CORNER_MAX_DIM {
        let mag: Vec<f64> = low
            .iter()
            .zip(high.iter())
            .map(|(lo, hi)| lo.abs().max(hi.abs()))
            .collect();
        let mut total = 0.0;
        for i in 0..d {
            for j in 0..d {
                total += m[(i, j)].abs() * mag[i] * mag[j];
            }
        }
        return total;
    }
    let mut x = vec![0.0; d];
    let mut best = 0.0_f64;
    for mask in 0u32..(1u32 << d) {
        for (k, xk) in x.iter_mut().enumerate() {
            *xk = if mask >> k & 1 == 1 { high[k] } else { low[k] };
        }
        let mut value = 0.0;
        for i in 0..d {
            let mut row = 0.0;
            for j in 0..d {
                row += m[(i, j)] * x[j];
            }
            value += x[i] * row;
        }
        best = best.max(value);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preset_constants() {
        let t = LqgModel::thesis();
        assert_eq!((t.r_max(), t.m_phi(), t.action_volume()), (4.0, 2.0, 4.0));
        let l = LqgModel::lqg1d();
        assert!((l.r_max() - 28.8).abs() < 1e-12);
        assert_eq!((l.m_phi(), l.action_volume()), (4.0, 8.0));
        assert!(t.validate().is_ok() && l.validate().is_ok());
    }

    #[test]
    fn r_max_uses_the_worst_corner() {
        // Q = [[1, 1], [1, 1]] over [-1, 2] × [-1, 1]: (s1 + s2)² is largest at (2, 1) → 9.
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let m = LqgModel::new(
            DMatrix::identity(2, 2),
            DMatrix::identity(2, 1),
            q,
            DMatrix::from_element(1, 1, 2.0),
            BoxBounds::new(
                DVector::from_vec(vec![-1.0, -1.0]),
                DVector::from_vec(vec![2.0, 1.0]),
            ),
            BoxBounds::new(
                DVector::from_element(1, -3.0),
                DVector::from_element(1, 1.0),
            ),
            BoxBounds::cube(2, -0.5, 0.5),
        )
        .unwrap();
        assert_eq!(m.r_max(), 9.0 + 2.0 * 9.0);
        assert_eq!(m.m_phi(), 2.0);
        assert_eq!(m.action_volume(), 4.0);
    }

    #[test]
    fn validation_rejects_bad_models() {
        let base = LqgModel::thesis();
        let mut m = base.clone();
        m.q[(0, 0)] = -1.0;
        assert!(matches!(m.validate(), Err(ModelError::NotPsd { .. })));
        let mut m = base.clone();
        m.state_low[0] = 3.0;
        assert!(matches!(m.validate(), Err(ModelError::UnorderedBox { .. })));
        let mut m = base.clone();
        m.init_high[0] = 3.0;
        assert!(matches!(
            m.validate(),
            Err(ModelError::InitOutsideState { index: 0 })
        ));
        assert!(m.with_clipping(false).validate().is_ok());
        let mut m = base.clone();
        m.a[(0, 0)] = f64::INFINITY;
        assert!(matches!(
            m.validate(),
            Err(ModelError::NonFinite { what: "a" })
        ));
        let r = LqgModel::new(
            DMatrix::identity(2, 2),
            DMatrix::identity(2, 1),
            DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 1.0]),
            DMatrix::identity(1, 1),
            BoxBounds::cube(2, -1.0, 1.0),
            BoxBounds::cube(1, -1.0, 1.0),
            BoxBounds::cube(2, -1.0, 1.0),
        );
        assert!(matches!(r, Err(ModelError::NotSymmetric { what: "q" })));
        let r = LqgModel::new(
            DMatrix::identity(2, 2),
            DMatrix::identity(3, 1),
            DMatrix::identity(2, 2),
            DMatrix::identity(1, 1),
            BoxBounds::cube(2, -1.0, 1.0),
            BoxBounds::cube(1, -1.0, 1.0),
            BoxBounds::cube(2, -1.0, 1.0),
        );
        assert!(matches!(
            r,
            Err(ModelError::DimensionMismatch { what: "b", .. })
        ));
        assert!(matches!(
            LqgModel::scalar(1.0, 1.0, 1.0, 1.0, 0.0),
            Err(ModelError::UnorderedBox { .. })
        ));
    }

    #[test]
    fn large_dimension_uses_a_valid_upper_bound() {
        let d = EXACT_CORNER_MAX_DIM + 1;
        let m = LqgModel::new(
            DMatrix::identity(d, d),
            DMatrix::identity(d, 1),
            DMatrix::identity(d, d),
            DMatrix::identity(1, 1),
            BoxBounds::cube(d, -1.0, 1.0),
            BoxBounds::cube(1, -1.0, 1.0),
            BoxBounds::cube(d, -1.0, 1.0),
        )
        .unwrap();
        // For a diagonal Q the bound is exact: Σ_i 1 · 1 = d, plus a² = 1.
        assert_eq!(m.r_max(), d as f64 + 1.0);
    }
}
