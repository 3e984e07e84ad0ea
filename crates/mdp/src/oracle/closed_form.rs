//! Closed-form `J` of the *unclipped* LQG of any dimension, with exact gradients, mixed
//! derivatives and Hessian, and the optimal gain of the discounted Riccati equation.
//!
//! The value function of a linear Gaussian policy on an unclipped LQG is quadratic,
//! `V_t(s) = −(sᵀ P_t s + c_t)`, so `J` follows from a matrix recursion (finite `H`) or the
//! discounted Lyapunov equation (`H = ∞`). The recursion is differentiated in forward mode to
//! second order (exact up to rounding), which gives `∇_v J`, `∇_w J`, the mixed derivative
//! `∇_w ∇_v J` of Appendix B and the full Hessian in one pass.
//!
//! # Formula
//! ```text
//! K = A + B V,   M = Q + Vᵀ R V,   Σ_a = diag(e^{2w}),   W = B Σ_a Bᵀ + diag(η²)
//! X_0 = E[s_0 s_0ᵀ] = diag((hi − lo)²/12) + m mᵀ,   m = (hi + lo)/2
//! finite H:  P_H = 0, c_H = 0,
//!            P_t = M + γ Kᵀ P_{t+1} K,   c_t = tr(R Σ_a) + γ (tr(P_{t+1} W) + c_{t+1})
//!            J = −(tr(P_0 X_0) + c_0)
//! H = ∞:     P = M + γ Kᵀ P K  (requires √γ ρ(K) < 1),
//!            J = −tr(P X_0) − (tr(R Σ_a) + γ tr(P W)) / (1 − γ)
//! ```

use nalgebra::{DMatrix, DVector, Schur};

use super::jet::{MatJet, ScalarJet, tri, tri_len};
use super::{ExactEval, ExactOracle, Exploration, Horizon, OracleError, check_params};
use crate::lqg_model::LqgModel;

/// Maximal number of doubling steps of the Lyapunov solver (covers `2^80` time steps).
const MAX_DOUBLING: usize = 80;
/// Relative size of the last doubling increment at which the Lyapunov sum is converged.
const DOUBLING_TOL: f64 = 1e-20;
/// Iteration budget of the Riccati value iteration.
const MAX_RICCATI: usize = 1_000_000;
/// Iteration budget of the Schur decomposition used for the spectral radius.
const MAX_SCHUR: usize = 10_000;

/// The closed-form oracle of the unclipped LQG (any dimension, finite or infinite horizon).
///
/// The state and action boxes of the model are ignored (whatever
/// [`LqgModel::clipping`] says); only the init box is used, for the distribution of `s_0`.
/// Transition noise `η ~ N(0, diag(noise_std²))` is included.
///
/// # Formula
/// ```text
/// s' = A s + B a + η,   a ~ N(V s, diag(e^{2w})),   r = −(sᵀQs + aᵀRa),   s_0 ~ U[init]
/// ```
#[derive(Debug, Clone)]
pub struct ClosedFormOracle {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    noise_cov: DMatrix<f64>,
    x0: DMatrix<f64>,
    gamma: f64,
}

/// The optimal linear gain of the unclipped LQG (discounted Riccati equation) and its value.
///
/// `V*` maximises the infinite-horizon `J` over every stabilising gain and, because `J` is
/// `−tr(P_V Y) + const` with `P_{V*} ≤ P_V`, it is optimal for every fixed `σ` as well.
///
/// # Formula
/// ```text
/// P = Q + γ AᵀPA − γ² AᵀPB (R + γ BᵀPB)⁻¹ BᵀPA,    V* = −γ (R + γ BᵀPB)⁻¹ BᵀPA
/// scalar presets (A = B = 1, Q = R):  v* = (1 − √(1 + 4γ²)) / (2γ)
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct OptimalGain {
    /// `V*` flattened action-major (`v[j * n + i]`).
    pub v: Vec<f64>,
    /// The Riccati solution `P` (n×n); the optimal value function is `−sᵀPs − const`.
    pub p: DMatrix<f64>,
    /// `J(V*)` of the deterministic policy, infinite horizon.
    pub j_deterministic: f64,
}

impl ClosedFormOracle {
    /// Builds the oracle from a model (validated with [`LqgModel::validate`]).
    ///
    /// # Formula
    /// ```text
    /// X_0 = diag((hi − lo)² / 12) + m mᵀ,   m = (hi + lo) / 2   (s_0 ~ U[lo, hi])
    /// ```
    ///
    /// # Errors
    /// [`OracleError::Model`] when the model is invalid.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::ClosedFormOracle;
    /// assert!(ClosedFormOracle::new(&LqgModel::lqg1d()).is_ok());
    /// ```
    pub fn new(model: &LqgModel) -> Result<Self, OracleError> {
        model.validate()?;
        let n = model.state_dim();
        let mean = (&model.init_high + &model.init_low) * 0.5;
        let width = &model.init_high - &model.init_low;
        let var = DVector::from_iterator(n, width.iter().map(|w| w * w / 12.0));
        let x0 = DMatrix::from_diagonal(&var) + &mean * mean.transpose();
        let noise_var = model.noise_std.map(|x| x * x);
        Ok(ClosedFormOracle {
            a: model.a.clone(),
            b: model.b.clone(),
            q: (&model.q + model.q.transpose()) * 0.5,
            r: (&model.r + model.r.transpose()) * 0.5,
            noise_cov: DMatrix::from_diagonal(&noise_var),
            x0,
            gamma: model.gamma,
        })
    }

    fn n(&self) -> usize {
        self.a.nrows()
    }

    fn l(&self) -> usize {
        self.b.ncols()
    }

    /// `√γ ρ(A + BV)`, the discounted spectral radius of the closed loop; the infinite-horizon
    /// `J` is finite iff it is below 1.
    ///
    /// # Formula
    /// ```text
    /// √γ · max_i |λ_i(A + B V)|
    /// ```
    ///
    /// # Errors
    /// Wrong length or non-finite `v`; [`OracleError::NotConverged`] if the Schur
    /// decomposition fails; [`OracleError::Overflow`] if `A + BV` or the radius overflows.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::ClosedFormOracle;
    /// let o = ClosedFormOracle::new(&LqgModel::thesis()).unwrap();
    /// assert!((o.scaled_spectral_radius(&[-0.5]).unwrap() - 0.99f64.sqrt() * 0.5).abs() < 1e-15);
    /// ```
    pub fn scaled_spectral_radius(&self, v: &[f64]) -> Result<f64, OracleError> {
        check_params(v, &Exploration::Deterministic, self.dim_v(), self.dim_w())?;
        let k = &self.a + &self.b * self.gain_matrix(v);
        if !k.iter().all(|x| x.is_finite()) {
            return Err(OracleError::Overflow);
        }
        let rho = self.gamma.sqrt() * spectral_radius(k)?;
        if rho.is_finite() {
            Ok(rho)
        } else {
            Err(OracleError::Overflow)
        }
    }

    /// The matrix `V` (l×n) from its action-major flattening.
    fn gain_matrix(&self, v: &[f64]) -> DMatrix<f64> {
        DMatrix::from_row_slice(self.l(), self.n(), v)
    }

    /// The optimal gain `V*` of the discounted Riccati equation and `J(V*)` of the
    /// deterministic policy, infinite horizon (thesis Sec 5.1: `v* ≈ −0.615`).
    ///
    /// # Formula
    /// ```text
    /// P_{k+1} = Q + γ AᵀP_kA − γ² AᵀP_kB (R + γ BᵀP_kB)⁻¹ BᵀP_kA,   P_0 = Q
    /// V* = −γ (R + γ BᵀPB)⁻¹ BᵀPA
    /// ```
    ///
    /// # Errors
    /// [`OracleError::NotConverged`] when the value iteration does not converge or
    /// `R + γBᵀPB` is singular; [`OracleError::Unstable`] when the limit gain does not
    /// stabilise the discounted closed loop.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::ClosedFormOracle;
    /// let opt = ClosedFormOracle::new(&LqgModel::lqg1d()).unwrap().optimal_gain().unwrap();
    /// assert!((opt.v[0] + 0.615251245663011).abs() < 1e-12);
    /// assert!((opt.j_deterministic + 7.753206).abs() < 1e-6);
    /// ```
    pub fn optimal_gain(&self) -> Result<OptimalGain, OracleError> {
        let g = self.gamma;
        let (a, b, q, r) = (&self.a, &self.b, &self.q, &self.r);
        let gain = |p: &DMatrix<f64>| -> Option<DMatrix<f64>> {
            let s = r + b.transpose() * p * b * g;
            let rhs = b.transpose() * p * a * g;
            s.lu().solve(&rhs).map(|x| -x)
        };
        let mut p = q.clone();
        for _ in 0..MAX_RICCATI {
            let k = gain(&p).ok_or(OracleError::NotConverged {
                what: "Riccati iteration (singular R + γBᵀPB)",
                iterations: 0,
            })?;
            let closed = a + b * &k;
            let next = q + k.transpose() * r * &k + closed.transpose() * &p * &closed * g;
            let next = (&next + next.transpose()) * 0.5;
            if !next.iter().all(|x| x.is_finite()) {
                return Err(OracleError::Overflow);
            }
            let done = (&next - &p).amax() <= 1e-15 * next.amax().max(f64::MIN_POSITIVE);
            p = next;
            if done {
                let k = gain(&p).ok_or(OracleError::NotConverged {
                    what: "Riccati iteration (singular R + γBᵀPB)",
                    iterations: 0,
                })?;
                let v: Vec<f64> = k.transpose().iter().copied().collect();
                let eval = self.evaluate(&v, &Exploration::Deterministic, Horizon::Infinite)?;
                return Ok(OptimalGain {
                    v,
                    p,
                    j_deterministic: eval.j,
                });
            }
        }
        Err(OracleError::NotConverged {
            what: "Riccati iteration",
            iterations: MAX_RICCATI,
        })
    }

    /// The jets of `K = A + BV`, `M = Q + VᵀRV`, `W = BΣ_aBᵀ + Σ_η` and `tr(RΣ_a)` with
    /// respect to `θ = [v | w]` (`w` only when `sigma` is non-empty).
    fn building_blocks(&self, v: &[f64], sigma: &[f64]) -> (MatJet, MatJet, MatJet, ScalarJet) {
        let (n, l) = (self.n(), self.l());
        let m = n * l;
        let p = m + sigma.len();
        let mut vj = MatJet::constant(self.gain_matrix(v), p);
        for (k, d) in vj.d1.iter_mut().enumerate().take(m) {
            d[(k / n, k % n)] = 1.0;
        }
        let bj = MatJet::constant(self.b.clone(), p);
        let k = MatJet::constant(self.a.clone(), p).add(&bj.mul(&vj));
        let rv = MatJet::constant(self.r.clone(), p).mul(&vj);
        let mmat = MatJet::constant(self.q.clone(), p).add(&vj.transpose().mul(&rv));
        let mut sa = MatJet::constant(DMatrix::zeros(l, l), p);
        for (j, s) in sigma.iter().enumerate() {
            sa.val[(j, j)] = s * s;
            sa.d1[m + j][(j, j)] = 2.0 * s * s;
            sa.d2[tri(m + j, m + j, p)][(j, j)] = 4.0 * s * s;
        }
        let w = bj
            .mul(&sa)
            .mul(&bj.transpose())
            .add(&MatJet::constant(self.noise_cov.clone(), p));
        let tr_ra = MatJet::constant(self.r.clone(), p).trace_mul(&sa);
        (k, mmat, w, tr_ra)
    }

    /// The jet of `J` for validated parameters.
    fn j_jet(&self, v: &[f64], sigma: &[f64], horizon: Horizon) -> Result<ScalarJet, OracleError> {
        let n = self.n();
        let g = self.gamma;
        let (k, mmat, w, tr_ra) = self.building_blocks(v, sigma);
        let p = k.p();
        let x0 = MatJet::constant(self.x0.clone(), p);
        let kt = k.transpose();
        let j = match horizon {
            Horizon::Finite(0) => return Err(OracleError::ZeroHorizon),
            Horizon::Finite(h) => {
                let mut pm = MatJet::constant(DMatrix::zeros(n, n), p);
                let mut c = ScalarJet::zero(p);
                for _ in 0..h {
                    c = tr_ra.add(&pm.trace_mul(&w).add(&c).scale(g));
                    pm = mmat.add(&kt.mul(&pm).mul(&k).scale(g));
                }
                pm.trace_mul(&x0).add(&c).scale(-1.0)
            }
            Horizon::Infinite => {
                let scaled_radius = g.sqrt() * spectral_radius(k.val.clone())?;
                if scaled_radius >= 1.0 {
                    return Err(OracleError::Unstable { scaled_radius });
                }
                let pm = discounted_lyapunov(&k.scale(g.sqrt()), &mmat)?;
                let c = tr_ra.add(&pm.trace_mul(&w).scale(g)).scale(1.0 / (1.0 - g));
                pm.trace_mul(&x0).add(&c).scale(-1.0)
            }
        };
        if j.is_finite() {
            Ok(j)
        } else {
            Err(OracleError::Overflow)
        }
    }
}

/// Solves `P = M + Lᵀ P L` (jets) by doubling: `P_{2N} = P_N + (L^N)ᵀ P_N L^N`.
fn discounted_lyapunov(l: &MatJet, m: &MatJet) -> Result<MatJet, OracleError> {
    let mut p = m.clone();
    let mut lk = l.clone();
    for _ in 0..MAX_DOUBLING {
        let inc = lk.transpose().mul(&p).mul(&lk);
        p = p.add(&inc);
        if !p.is_finite() {
            return Err(OracleError::Overflow);
        }
        if inc.max_abs() <= DOUBLING_TOL * p.max_abs() {
            return Ok(p);
        }
        lk = lk.mul(&lk);
    }
    Err(OracleError::NotConverged {
        what: "discounted Lyapunov doubling",
        iterations: MAX_DOUBLING,
    })
}

/// The spectral radius of a square matrix (Schur decomposition).
fn spectral_radius(k: DMatrix<f64>) -> Result<f64, OracleError> {
    let schur = Schur::try_new(k, f64::EPSILON, MAX_SCHUR).ok_or(OracleError::NotConverged {
        what: "Schur decomposition",
        iterations: MAX_SCHUR,
    })?;
    Ok(schur
        .complex_eigenvalues()
        .iter()
        .fold(0.0, |m: f64, z| m.max(z.norm())))
}

impl ExactOracle for ClosedFormOracle {
    fn dim_v(&self) -> usize {
        self.n() * self.l()
    }

    fn dim_w(&self) -> usize {
        self.l()
    }

    /// `J`, `∇_v J`, `∇_w J`, `∇_w∇_v J` and the full Hessian, exact up to rounding
    /// (forward-mode differentiation of the Lyapunov recursion).
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClosedFormOracle, ExactOracle, Exploration, Horizon};
    /// let o = ClosedFormOracle::new(&LqgModel::thesis()).unwrap();
    /// let v_star = -0.615251245663011;
    /// let e = o.evaluate(&[v_star], &Exploration::Deterministic, Horizon::Infinite).unwrap();
    /// assert!((e.j + 1.076834).abs() < 1e-6);
    /// assert!(e.grad_v[0].abs() < 1e-12);
    /// ```
    fn evaluate(
        &self,
        v: &[f64],
        exploration: &Exploration,
        horizon: Horizon,
    ) -> Result<ExactEval, OracleError> {
        let params = check_params(v, exploration, self.dim_v(), self.dim_w())?;
        let j = self.j_jet(v, &params.sigma, horizon)?;
        let m = self.dim_v();
        let p = j.d1.len();
        debug_assert_eq!(j.d2.len(), tri_len(p));
        let hessian = DMatrix::from_fn(p, p, |a, b| j.d2[tri(a, b, p)]);
        let mixed_wv = (m..p)
            .flat_map(|wj| (0..m).map(move |k| (wj, k)))
            .map(|(wj, k)| j.d2[tri(k, wj, p)])
            .collect();
        Ok(ExactEval {
            j: j.val,
            grad_v: j.d1[..m].to_vec(),
            grad_w: j.d1[m..].to_vec(),
            mixed_wv,
            hessian: Some(hessian),
            sigma: params.sigma,
        })
    }
}
