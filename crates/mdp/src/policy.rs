//! The factored Gaussian linear policy of Sec 4.3.1 and 4.3.4 (docs/CONVENTIONS.md §2).
//!
//! For `l` action dimensions and `p` features, `μ(s) = Vᵀφ(s)` with `V` a `p × l` matrix stored
//! flattened action-major (`v[j·p + i]` multiplies feature `i` in the mean of action `j`, as
//! [`crate::batch`] documents), and `σ_j = e^{w_j}`. Scores use the raw sampled action.
//!
//! # Formula
//! ```text
//! π(a|s) = Π_j N(a_j; μ_j(s), σ_j²),   μ_j(s) = Σ_i v[j·p+i] φ_i(s),   σ_j = e^{w_j}
//! ∇_{v[j·p+i]} log π = (a_j − μ_j) φ_i / σ_j²
//! ∇_{w_j} log π      = ((a_j − μ_j)/σ_j)² − 1
//! ```

use rand::Rng;

use crate::rng::standard_normal;

/// Validation errors of [`GaussianPolicy`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PolicyError {
    /// `features` or the number of actions is zero.
    #[error("a policy needs at least one feature and one action dimension")]
    EmptyDimension,
    /// `v` does not have `actions · features` entries.
    #[error("v has {found} entries, expected {expected} (actions × features)")]
    WrongParameterLength {
        /// `l · p`.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// An input slice has the wrong length.
    #[error("{what} has length {found}, expected {expected}")]
    WrongInputLength {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A parameter or input is NaN or infinite.
    #[error("{what} contains a non-finite value")]
    NonFinite {
        /// Which parameter or input.
        what: &'static str,
    },
    /// `w_j` gives `σ_j = e^{w_j}` whose square or inverse square is not a finite positive
    /// number (`|w_j| ≳ 354`); use [`Exploration::Deterministic`] for `w = −∞`.
    #[error("w[{index}] = {value} is outside the representable range (|w| < 354)")]
    LogStdOutOfRange {
        /// Action index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The density or a score was requested from the deterministic policy.
    #[error("the deterministic policy (w = −∞) has no density or score")]
    Deterministic,
}

/// How the policy explores: Gaussian noise with log-standard-deviations `w`, or none
/// (`w = −∞`, the deterministic policy `θ = [v | −∞]` of Sec 4.3.1, which acts `μ(s)`).
#[derive(Debug, Clone, PartialEq)]
pub enum Exploration {
    /// `σ_j = e^{w_j}` per action dimension.
    Gaussian {
        /// Log-standard-deviations, one per action dimension.
        w: Vec<f64>,
    },
    /// `σ = 0`: the action is the mean `μ(s)`.
    Deterministic,
}

/// Largest `|w|` accepted: `e^{2·354}` and `e^{−2·354}` are finite and non-zero.
const W_LIMIT: f64 = 354.0;

/// A validated factored Gaussian linear policy (Sec 4.3.4, eq. 4.21).
///
/// # Formula
/// ```text
/// a_j = μ_j(s) + σ_j z_j,  z_j ~ N(0, 1),  μ_j(s) = Σ_i v[j·p+i] φ_i(s),  σ_j = e^{w_j}
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianPolicy {
    v: Vec<f64>,
    features: usize,
    actions: usize,
    exploration: Exploration,
    sigma: Vec<f64>,
    inv_sigma: Vec<f64>,
}

impl GaussianPolicy {
    /// A stochastic policy with mean parameters `v` (length `w.len() · features`,
    /// action-major) and log-standard-deviations `w` (one per action dimension).
    ///
    /// # Formula
    /// ```text
    /// μ_j(s) = Σ_i v[j·p+i] φ_i(s),   σ_j = e^{w_j}
    /// ```
    ///
    /// ```
    /// use sepg_mdp::policy::GaussianPolicy;
    /// let p = GaussianPolicy::new(vec![-0.1], vec![0.0], 1).unwrap();
    /// assert_eq!(p.sigma(), Some(&[1.0][..]));
    /// assert!(GaussianPolicy::new(vec![0.0, 1.0], vec![0.0], 1).is_err());
    /// ```
    pub fn new(v: Vec<f64>, w: Vec<f64>, features: usize) -> Result<Self, PolicyError> {
        let actions = w.len();
        check_v(&v, actions, features)?;
        for (index, &value) in w.iter().enumerate() {
            if value.is_nan() || value.abs() > W_LIMIT {
                return Err(PolicyError::LogStdOutOfRange { index, value });
            }
        }
        let sigma: Vec<f64> = w.iter().map(|x| x.exp()).collect();
        let inv_sigma = sigma.iter().map(|s| 1.0 / s).collect();
        Ok(GaussianPolicy {
            v,
            features,
            actions,
            exploration: Exploration::Gaussian { w },
            sigma,
            inv_sigma,
        })
    }

    /// The one-feature, one-action policy `a ~ N(v s, e^{2w})` of the LQG (Sec 5.1).
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(-0.1, 0.5f64.ln()).unwrap();
    /// assert!((p.sigma().unwrap()[0] - 0.5).abs() < 1e-15);
    /// ```
    pub fn scalar(v: f64, w: f64) -> Result<Self, PolicyError> {
        GaussianPolicy::new(vec![v], vec![w], 1)
    }

    /// The deterministic policy `θ = [v | −∞]` (Sec 4.3.1) acting `μ(s)`.
    ///
    /// ```
    /// use sepg_mdp::policy::GaussianPolicy;
    /// let p = GaussianPolicy::deterministic(vec![-0.5], 1, 1).unwrap();
    /// assert!(p.is_deterministic());
    /// ```
    pub fn deterministic(
        v: Vec<f64>,
        actions: usize,
        features: usize,
    ) -> Result<Self, PolicyError> {
        check_v(&v, actions, features)?;
        Ok(GaussianPolicy {
            v,
            features,
            actions,
            exploration: Exploration::Deterministic,
            sigma: Vec::new(),
            inv_sigma: Vec::new(),
        })
    }

    /// The deterministic policy with the same mean (`w → −∞`).
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(-0.3, 0.0).unwrap();
    /// assert_eq!(p.to_deterministic().v(), p.v());
    /// ```
    pub fn to_deterministic(&self) -> Self {
        GaussianPolicy {
            v: self.v.clone(),
            features: self.features,
            actions: self.actions,
            exploration: Exploration::Deterministic,
            sigma: Vec::new(),
            inv_sigma: Vec::new(),
        }
    }

    /// Mean parameters `v` (action-major, length `l · p`).
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(-0.3, 0.0).unwrap();
    /// assert_eq!(p.v(), &[-0.3]);
    /// ```
    pub fn v(&self) -> &[f64] {
        &self.v
    }

    /// Log-standard-deviations `w`, or `None` for the deterministic policy.
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(-0.3, 0.25).unwrap();
    /// assert_eq!(p.w(), Some(&[0.25][..]));
    /// ```
    pub fn w(&self) -> Option<&[f64]> {
        match &self.exploration {
            Exploration::Gaussian { w } => Some(w),
            Exploration::Deterministic => None,
        }
    }

    /// Standard deviations `σ_j = e^{w_j}`, or `None` for the deterministic policy.
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(-0.3, 0.0).unwrap();
    /// assert_eq!(p.sigma(), Some(&[1.0][..]));
    /// ```
    pub fn sigma(&self) -> Option<&[f64]> {
        match self.exploration {
            Exploration::Gaussian { .. } => Some(&self.sigma),
            Exploration::Deterministic => None,
        }
    }

    /// The exploration mode.
    ///
    /// ```
    /// use sepg_mdp::policy::{Exploration, GaussianPolicy};
    /// let p = GaussianPolicy::deterministic(vec![1.0], 1, 1).unwrap();
    /// assert_eq!(p.exploration(), &Exploration::Deterministic);
    /// ```
    pub fn exploration(&self) -> &Exploration {
        &self.exploration
    }

    /// Whether the policy is deterministic (`w = −∞`).
    ///
    /// ```
    /// assert!(!sepg_mdp::policy::GaussianPolicy::scalar(0.0, 0.0).unwrap().is_deterministic());
    /// ```
    pub fn is_deterministic(&self) -> bool {
        matches!(self.exploration, Exploration::Deterministic)
    }

    /// Number of features `p`.
    ///
    /// ```
    /// assert_eq!(sepg_mdp::policy::GaussianPolicy::scalar(0.0, 0.0).unwrap().feature_dim(), 1);
    /// ```
    pub fn feature_dim(&self) -> usize {
        self.features
    }

    /// Number of action dimensions `l`.
    ///
    /// ```
    /// assert_eq!(sepg_mdp::policy::GaussianPolicy::scalar(0.0, 0.0).unwrap().action_dim(), 1);
    /// ```
    pub fn action_dim(&self) -> usize {
        self.actions
    }

    /// Number of mean parameters `m = l · p`.
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::new(vec![0.0; 6], vec![0.0; 2], 3).unwrap();
    /// assert_eq!(p.dim_v(), 6);
    /// ```
    pub fn dim_v(&self) -> usize {
        self.v.len()
    }

    /// Number of log-standard-deviation parameters `l`.
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::new(vec![0.0; 6], vec![0.0; 2], 3).unwrap();
    /// assert_eq!(p.dim_w(), 2);
    /// ```
    pub fn dim_w(&self) -> usize {
        self.actions
    }

    /// The mean action `μ(s) = Vᵀφ(s)` written into `out` (length `l`).
    ///
    /// # Formula
    /// ```text
    /// μ_j = Σ_i v[j·p+i] φ_i
    /// ```
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::new(vec![1.0, 2.0], vec![0.0], 2).unwrap();
    /// let mut mu = [0.0];
    /// p.mean(&[3.0, 4.0], &mut mu).unwrap();
    /// assert_eq!(mu[0], 11.0);
    /// ```
    pub fn mean(&self, phi: &[f64], out: &mut [f64]) -> Result<(), PolicyError> {
        self.check_phi(phi)?;
        check_len("out", out.len(), self.actions)?;
        self.mean_unchecked(phi, out);
        all_finite("mean μ(s) (overflow)", out)
    }

    /// Log-density `log π(a|s)` of the raw action `a` at features `φ(s)`.
    ///
    /// # Formula
    /// ```text
    /// log π = Σ_j [ −½ ((a_j − μ_j)/σ_j)² − w_j − ½ ln(2π) ]
    /// ```
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(1.0, 0.0).unwrap();
    /// let lp = p.log_density(&[0.0], &[0.0]).unwrap();
    /// assert!((lp + 0.5 * (2.0 * std::f64::consts::PI).ln()).abs() < 1e-15);
    /// ```
    pub fn log_density(&self, phi: &[f64], a: &[f64]) -> Result<f64, PolicyError> {
        let w = self.w().ok_or(PolicyError::Deterministic)?;
        self.check_phi(phi)?;
        self.check_action(a)?;
        let half_ln_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
        let mut total = 0.0;
        for j in 0..self.actions {
            let z = (a[j] - self.mean_j(phi, j)) * self.inv_sigma[j];
            total += -0.5 * z * z - w[j] - half_ln_2pi;
        }
        all_finite("log-density (overflow)", &[total])?;
        Ok(total)
    }

    /// The v-score `∇_v log π(a|s)` with the raw action, written into `out` (length `l · p`).
    ///
    /// # Formula
    /// ```text
    /// ∇_{v[j·p+i]} log π = (a_j − μ_j) φ_i / σ_j²
    /// ```
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(1.0, 0.0).unwrap();
    /// let mut g = [0.0];
    /// p.score_v(&[2.0], &[3.0], &mut g).unwrap();
    /// assert_eq!(g[0], 2.0); // (3 − 2)·2/1
    /// ```
    pub fn score_v(&self, phi: &[f64], a: &[f64], out: &mut [f64]) -> Result<(), PolicyError> {
        if self.is_deterministic() {
            return Err(PolicyError::Deterministic);
        }
        self.check_phi(phi)?;
        self.check_action(a)?;
        check_len("out", out.len(), self.v.len())?;
        let p = self.features;
        for j in 0..self.actions {
            let c = (a[j] - self.mean_j(phi, j)) * self.inv_sigma[j] * self.inv_sigma[j];
            for i in 0..p {
                out[j * p + i] = c * phi[i];
            }
        }
        all_finite("v-score (overflow)", out)
    }

    /// The w-score `∇_w log π(a|s)` with the raw action, written into `out` (length `l`).
    ///
    /// # Formula
    /// ```text
    /// ∇_{w_j} log π = ((a_j − μ_j)/σ_j)² − 1
    /// ```
    ///
    /// ```
    /// let p = sepg_mdp::policy::GaussianPolicy::scalar(1.0, 0.0).unwrap();
    /// let mut g = [0.0];
    /// p.score_w(&[2.0], &[4.0], &mut g).unwrap();
    /// assert_eq!(g[0], 3.0); // (4 − 2)² − 1
    /// ```
    pub fn score_w(&self, phi: &[f64], a: &[f64], out: &mut [f64]) -> Result<(), PolicyError> {
        if self.is_deterministic() {
            return Err(PolicyError::Deterministic);
        }
        self.check_phi(phi)?;
        self.check_action(a)?;
        check_len("out", out.len(), self.actions)?;
        for (j, o) in out.iter_mut().enumerate() {
            let z = (a[j] - self.mean_j(phi, j)) * self.inv_sigma[j];
            *o = z * z - 1.0;
        }
        all_finite("w-score (overflow)", out)
    }

    /// Samples an action `a ~ π(·|s)` into `out` (length `l`); the deterministic policy writes
    /// `μ(s)` and draws nothing.
    ///
    /// # Formula
    /// ```text
    /// a_j = μ_j + σ_j z_j,   z_j ~ N(0, 1)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::policy::GaussianPolicy;
    /// let mut rng = sepg_mdp::rng::rng_from_seed(1);
    /// let mut a = [0.0];
    /// GaussianPolicy::deterministic(vec![2.0], 1, 1).unwrap().sample(&[1.5], &mut rng, &mut a).unwrap();
    /// assert_eq!(a[0], 3.0);
    /// ```
    pub fn sample<R: Rng + ?Sized>(
        &self,
        phi: &[f64],
        rng: &mut R,
        out: &mut [f64],
    ) -> Result<(), PolicyError> {
        self.check_phi(phi)?;
        check_len("out", out.len(), self.actions)?;
        self.mean_unchecked(phi, out);
        if !self.is_deterministic() {
            for (j, o) in out.iter_mut().enumerate() {
                *o += self.sigma[j] * standard_normal(rng);
            }
        }
        all_finite("sampled action (overflow)", out)
    }

    /// `σ_j` and `1/σ_j` (empty for the deterministic policy).
    pub(crate) fn sigma_raw(&self) -> (&[f64], &[f64]) {
        (&self.sigma, &self.inv_sigma)
    }

    /// `μ_j(φ)`, summed from the first feature on (no leading `0 +`).
    #[inline(always)]
    pub(crate) fn mean_j(&self, phi: &[f64], j: usize) -> f64 {
        let row = &self.v[j * self.features..(j + 1) * self.features];
        let mut m = row[0] * phi[0];
        for (vi, fi) in row[1..].iter().zip(&phi[1..]) {
            m += vi * fi;
        }
        m
    }

    /// `μ(φ)` into `out` without length checks (callers guarantee the lengths).
    #[inline(always)]
    pub(crate) fn mean_unchecked(&self, phi: &[f64], out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o = self.mean_j(phi, j);
        }
    }

    fn check_phi(&self, phi: &[f64]) -> Result<(), PolicyError> {
        check_len("phi", phi.len(), self.features)?;
        check_finite("phi", phi)
    }

    fn check_action(&self, a: &[f64]) -> Result<(), PolicyError> {
        check_len("a", a.len(), self.actions)?;
        check_finite("a", a)
    }
}

fn check_v(v: &[f64], actions: usize, features: usize) -> Result<(), PolicyError> {
    if actions == 0 || features == 0 {
        return Err(PolicyError::EmptyDimension);
    }
    let expected = actions.saturating_mul(features);
    if v.len() != expected {
        return Err(PolicyError::WrongParameterLength {
            expected,
            found: v.len(),
        });
    }
    check_finite("v", v)
}

/// `Ok` if every value is finite, else [`PolicyError::NonFinite`] naming `what` (finite
/// parameters and features can still overflow in μ = Vᵀφ or in the scores).
fn all_finite(what: &'static str, values: &[f64]) -> Result<(), PolicyError> {
    if values.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(PolicyError::NonFinite { what })
    }
}

fn check_len(what: &'static str, found: usize, expected: usize) -> Result<(), PolicyError> {
    if found == expected {
        Ok(())
    } else {
        Err(PolicyError::WrongInputLength {
            what,
            expected,
            found,
        })
    }
}

fn check_finite(what: &'static str, xs: &[f64]) -> Result<(), PolicyError> {
    if xs.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(PolicyError::NonFinite { what })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::rng_from_seed;
    use proptest::prelude::*;
    use proptest::test_runner::RngSeed;

    /// Closed-form log-density of a product of independent normals, written independently of
    /// the implementation (through the density itself).
    fn log_density_reference(v: &[f64], w: &[f64], p: usize, phi: &[f64], a: &[f64]) -> f64 {
        let mut density = 1.0;
        for (j, &wj) in w.iter().enumerate() {
            let mu: f64 = (0..p).map(|i| v[j * p + i] * phi[i]).sum();
            let sigma = wj.exp();
            density *= (-(a[j] - mu).powi(2) / (2.0 * sigma * sigma)).exp()
                / (sigma * (2.0 * std::f64::consts::PI).sqrt());
        }
        density.ln()
    }

    #[test]
    fn log_density_matches_closed_form() {
        let v = vec![0.5, -1.0, 2.0, 0.25, 0.0, -0.75];
        let w = vec![-0.3, 0.4];
        let pi = GaussianPolicy::new(v.clone(), w.clone(), 3).unwrap();
        let phi = [0.3, -1.2, 0.8];
        let a = [1.1, -0.4];
        let got = pi.log_density(&phi, &a).unwrap();
        let want = log_density_reference(&v, &w, 3, &phi, &a);
        assert!((got - want).abs() < 1e-13, "{got} vs {want}");
    }

    #[test]
    fn invalid_inputs_are_typed_errors() {
        assert_eq!(
            GaussianPolicy::new(vec![0.0], vec![], 1),
            Err(PolicyError::EmptyDimension)
        );
        assert!(matches!(
            GaussianPolicy::new(vec![f64::NAN], vec![0.0], 1),
            Err(PolicyError::NonFinite { what: "v" })
        ));
        assert!(matches!(
            GaussianPolicy::new(vec![0.0], vec![f64::NEG_INFINITY], 1),
            Err(PolicyError::LogStdOutOfRange { index: 0, .. })
        ));
        assert!(matches!(
            GaussianPolicy::new(vec![0.0], vec![400.0], 1),
            Err(PolicyError::LogStdOutOfRange { .. })
        ));
        let det = GaussianPolicy::deterministic(vec![1.0], 1, 1).unwrap();
        assert_eq!(
            det.log_density(&[1.0], &[1.0]),
            Err(PolicyError::Deterministic)
        );
        assert_eq!(
            det.score_v(&[1.0], &[1.0], &mut [0.0]),
            Err(PolicyError::Deterministic)
        );
        let pi = GaussianPolicy::scalar(1.0, 0.0).unwrap();
        assert!(matches!(
            pi.log_density(&[1.0, 2.0], &[1.0]),
            Err(PolicyError::WrongInputLength { what: "phi", .. })
        ));
        assert!(matches!(
            pi.log_density(&[1.0], &[f64::INFINITY]),
            Err(PolicyError::NonFinite { what: "a" })
        ));
    }

    #[test]
    fn sampling_moments_match_mean_and_sigma() {
        // 2e5 draws of a ~ N(μ, σ²) with μ = 0.5·2 − 1·(−1) = 2, σ = e^{-0.5}. The mean has
        // standard error σ/√n and the sample variance ≈ σ²√(2/n); 5-sigma bands give a
        // false-alarm rate below 1.2e-6 for the two asserts together.
        let pi = GaussianPolicy::new(vec![0.5, -1.0], vec![-0.5], 2).unwrap();
        let mut rng = rng_from_seed(17);
        let n = 200_000;
        let mut a = [0.0];
        let xs: Vec<f64> = (0..n)
            .map(|_| {
                pi.sample(&[2.0, -1.0], &mut rng, &mut a).unwrap();
                a[0]
            })
            .collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let sigma2 = (-1.0f64).exp();
        assert!((mean - 2.0).abs() < 5.0 * sigma2.sqrt() / (n as f64).sqrt());
        assert!((var - sigma2).abs() < 5.0 * sigma2 * (2.0 / n as f64).sqrt());
        let det = pi.to_deterministic();
        det.sample(&[2.0, -1.0], &mut rng, &mut a).unwrap();
        assert_eq!(a[0], 2.0);
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            rng_seed: RngSeed::Fixed(0x5c_0e5),
            ..ProptestConfig::default()
        })]

        /// ∇_v log π and ∇_w log π against central finite differences of the log-density
        /// (step 1e-6, tolerance 1e-5 relative to the score's scale).
        #[test]
        fn scores_match_finite_differences(
            v in proptest::collection::vec(-2.0f64..2.0, 4),
            w in proptest::collection::vec(-1.0f64..1.0, 2),
            phi in proptest::collection::vec(-2.0f64..2.0, 2),
            a in proptest::collection::vec(-3.0f64..3.0, 2),
        ) {
            let pi = GaussianPolicy::new(v.clone(), w.clone(), 2).unwrap();
            let mut gv = [0.0; 4];
            let mut gw = [0.0; 2];
            pi.score_v(&phi, &a, &mut gv).unwrap();
            pi.score_w(&phi, &a, &mut gw).unwrap();
            let h = 1e-6;
            for k in 0..4 {
                let (mut vp, mut vm) = (v.clone(), v.clone());
                vp[k] += h;
                vm[k] -= h;
                let lp = GaussianPolicy::new(vp, w.clone(), 2).unwrap().log_density(&phi, &a).unwrap();
                let lm = GaussianPolicy::new(vm, w.clone(), 2).unwrap().log_density(&phi, &a).unwrap();
                let fd = (lp - lm) / (2.0 * h);
                prop_assert!((fd - gv[k]).abs() < 1e-5 * (1.0 + gv[k].abs()), "v[{}]: {} vs {}", k, fd, gv[k]);
            }
            for j in 0..2 {
                let (mut wp, mut wm) = (w.clone(), w.clone());
                wp[j] += h;
                wm[j] -= h;
                let lp = GaussianPolicy::new(v.clone(), wp, 2).unwrap().log_density(&phi, &a).unwrap();
                let lm = GaussianPolicy::new(v.clone(), wm, 2).unwrap().log_density(&phi, &a).unwrap();
                let fd = (lp - lm) / (2.0 * h);
                prop_assert!((fd - gw[j]).abs() < 1e-5 * (1.0 + gw[j].abs()), "w[{}]: {} vs {}", j, fd, gw[j]);
            }
        }
    }
}
