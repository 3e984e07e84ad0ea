//! `J` of the *clipped* scalar LQG (presets `lqg`, `lqg1d`) and its derivatives by
//! deterministic backward dynamic programming.
//!
//! # Method
//! The value function `V_t(s)` (expected discounted reward-to-go at step `t`, `V_H = 0`) is
//! represented on the state box by a piecewise Chebyshev interpolant (first-kind nodes on
//! each element). One backward step takes the expectation over the Gaussian action in the
//! standardised variable `z = (a − v s)/σ`:
//!
//! - the action point masses beyond the action box (`a_c = a_low` or `a_high`) are integrated
//!   exactly with the normal CDF and truncated normal moments;
//! - inside the action box the next state `y = A s + B a` is affine in `z`; where `y` leaves
//!   the state box the clipped next state is a constant (the state point mass, again exact);
//!   elsewhere `φ(z) V_{t+1}(y(z))` is integrated by Gauss–Legendre on pieces at most two
//!   units wide in `z` (five points per unit), split at the element boundaries of the
//!   interpolant, `|z| ≤ 10` (neglected mass `< 2·10⁻²³`); between element boundaries the
//!   pieces are fixed sub-intervals of the element, whose interpolation weights are tabulated
//!   once per evaluation;
//! - the reward term is integrated in closed form.
//!
//! The derivatives are carried along the recursion in score-function form, which never
//! differentiates the interpolant: with `score_v = z s/σ`, `score_w = z² − 1`,
//! ```text
//! V_t       = E[G]                                   G(s, a) = r(s, a_c) + γ W_{t+1}(s, a)
//! ∂_v V_t   = (s/σ) E[z G] + E[G_v]
//! ∂_w V_t   = E[(z² − 1) G] + E[G_w]
//! ∂²_vv V_t = (s/σ)² E[(z² − 1) G] + 2 (s/σ) E[z G_v] + E[G_vv]
//! ∂²_wv V_t = (s/σ) E[(z³ − 3z) G] + (s/σ) E[z G_w] + E[(z² − 1) G_v] + E[G_wv]
//! ∂²_ww V_t = E[(z⁴ − 4z² + 1) G] + 2 E[(z² − 1) G_w] + E[G_ww]
//! ```
//! where `W_{t+1}(s, a) = E_η V_{t+1}(clip(A s + B a_c + η))` (with transition noise `η0 > 0`
//! this is a second, θ-independent smoothing operator, represented on its own grid).
//! Finally `J = E_{s_0 ~ U[init]} V_0(s_0)` by Gauss–Legendre on each element.
//!
//! The interpolant elements are placed at the exact kinks of `V_t` (from the clipped-action
//! branches) and refined near every smoothed clipping feature, with a width proportional to
//! the feature's scale (`σ/|v|` for action clipping, `|B|σ/|A + Bv|` for state clipping, and
//! their images under the closed loop at earlier steps, which matter near `A + Bv = 1`).
//!
//! Only the channels a request needs are propagated ([`Needs`]): `J` alone integrates one
//! weight per operator entry and carries one channel; SEPG's `J`, `∂_v J`, `∂_w J`,
//! `∂²_{wv} J` integrate four and carry four; the Hessian five and six.
//!
//! The deterministic policy without transition noise is computed exactly by propagating
//! intervals of initial states on which the trajectory is affine in `s_0` (piecewise-linear
//! closed-loop map), integrating the quadratic rewards exactly on each interval.

mod deterministic;
mod features;
mod grid;
mod operator;

use super::jet::Dual;
use super::quadrature::{Chebyshev, GaussLegendre, dot, norm_cdf, norm_pdf, normal_moments};
use super::{ExactEval, ExactOracle, Exploration, Horizon, Needs, OracleError, check_params};
use crate::lqg_model::LqgModel;
use nalgebra::DMatrix;

use features::Zone;
use grid::{Grid, Quad, Target};
use operator::{Recursion, RowAcc, SpanOp};

/// Half-width of the truncated `z`-range of the Gaussian integrals.
const Z_MAX: f64 = 10.0;
/// Width in `z` of the Gauss–Legendre pieces of the Gaussian integrals (with the default 10
/// points per piece: 5 points per unit of `z`).
const PIECE_WIDTH: f64 = 2.0;
/// A smoothed feature of scale `ℓ` matters within `ZONE_HALF_WIDTH · ℓ` of its centre.
const ZONE_HALF_WIDTH: f64 = 8.0;
/// Kinks of the value function whose producing chain of clipped actions has a smaller
/// probability are not tracked.
const KINK_WEIGHT: f64 = 1e-16;
/// Maximal number of exact kinks of the value function tracked.
const MAX_KINKS: usize = 4096;
/// Maximal number of Chebyshev nodes per element.
const MAX_NODES: usize = 32;
/// Maximal number of initial-state intervals of the exact deterministic method.
const MAX_PIECES: usize = 1_000_000;

/// Resolution of the dynamic programme of [`ClippedDpOracle`].
///
/// With the defaults, on a grid of `v ∈ [−1.5, 0.2]`, `σ ∈ [0.02, 2]`, `H = 20` over both
/// presets (98 points, `A + Bv = 1` included), `J` is within `7e-11 · max(|J|, 1)` and
/// `∂_v J`, `∂_w J`, `∂²_{wv} J` within `2e-8 · max(|J|, 1)` of a much finer reference (16
/// nodes, 2 to 6 times narrower elements), and within `1e-9 · max(|J|, 1)` for
/// `σ ∈ [10⁻³, 0.02]`; `tests/oracle_dp.rs` checks `1e-9` and `1e-7` on its
/// convergence-study cases. Over `v ∈ [−1.8, 0.3]`, `σ ∈ [0.1, 1.5]`, `H ∈ [1, 24]` (250
/// random points of both presets) the worst errors measured against the same reference are
/// `1.6e-10` (`J`), `2.1e-9` (`∂_v J`, `∂_w J`), `1.6e-8` (`∂²_{wv} J`) and `3.3e-8` (the
/// Hessian), all relative to `max(|J|, 1)`; the tests hold the derivatives to `2e-8` (first
/// and mixed) and `5e-8` (Hessian). The error shrinks by about two orders of magnitude per
/// two extra nodes per element. Smaller `σ` stays finite and tends to the deterministic policy, or
/// fails with [`OracleError::ResolutionExceeded`] when the features of an expanding closed
/// loop (`|A + Bv| > 1`) need more than `max_elements` elements.
///
/// # Formula
/// ```text
/// element width h ≤ min(box width / min_elements, ℓ / elements_per_scale)   near a feature of scale ℓ
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DpConfig {
    /// Chebyshev nodes per element (polynomial degree + 1), in `2..=32`.
    pub nodes_per_element: usize,
    /// Gauss–Legendre points per quadrature piece, at least 2.
    pub quad_points: usize,
    /// Elements on the state box even when the value function has no narrow feature.
    pub min_elements: usize,
    /// Elements per feature scale `ℓ` near a smoothed clipping feature (> 0).
    pub elements_per_scale: f64,
    /// Upper limit on the number of elements (beyond: [`OracleError::ResolutionExceeded`]).
    pub max_elements: usize,
}

impl Default for DpConfig {
    /// `nodes_per_element = 10`, `quad_points = 10`, `min_elements = 8`,
    /// `elements_per_scale = 0.7`, `max_elements = 2000`.
    ///
    /// ```
    /// assert_eq!(sepg_mdp::oracle::DpConfig::default().nodes_per_element, 10);
    /// ```
    fn default() -> Self {
        DpConfig {
            nodes_per_element: 10,
            quad_points: 10,
            min_elements: 8,
            elements_per_scale: 0.7,
            max_elements: 2000,
        }
    }
}

impl DpConfig {
    /// Checks the ranges listed on the fields.
    fn validate(&self) -> Result<(), OracleError> {
        let ok = (2..=MAX_NODES).contains(&self.nodes_per_element)
            && self.quad_points >= 2
            && self.min_elements >= 1
            && self.elements_per_scale.is_finite()
            && self.elements_per_scale > 0.0
            && self.max_elements >= self.min_elements;
        if ok {
            Ok(())
        } else {
            Err(OracleError::InvalidConfig(
                "need 2 ≤ nodes_per_element ≤ 32, quad_points ≥ 2, min_elements ≥ 1, \
                 elements_per_scale > 0 and max_elements ≥ min_elements",
            ))
        }
    }
}

/// The dynamic-programming oracle of the clipped scalar LQG (finite horizon).
///
/// # Formula
/// ```text
/// V_H = 0,   V_t(s) = E_{a ~ N(vs, σ²)} [ −(q s² + r a_c²) + γ E_η V_{t+1}(clip(A s + B a_c + η)) ]
/// J(v, w) = (1 / (hi − lo)) ∫_lo^hi V_0(s) ds,    a_c = clip(a, a_low, a_high),  σ = e^w
/// ```
#[derive(Debug, Clone)]
pub struct ClippedDpOracle {
    a: f64,
    b: f64,
    q: f64,
    r: f64,
    noise: f64,
    gamma: f64,
    s_lo: f64,
    s_hi: f64,
    a_lo: f64,
    a_hi: f64,
    i_lo: f64,
    i_hi: f64,
    config: DpConfig,
    gl: GaussLegendre,
    cheb: Chebyshev,
}

/// the Hessian everything.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Level {
    /// `V`.
    Value,
    /// `V`, `∂_v V`.
    GradV,
    /// `V`, `∂_v V`, `∂_w V`.
    Grad,
    /// `V`, `∂_v V`, `∂_w V`, `∂²_wv V`.
    Mixed,
    /// All six channels.
    Hessian,
}

impl From<Needs> for Level {
    fn from(needs: Needs) -> Self {
        if needs.hessian {
            Level::Hessian
        } else if needs.mixed {
            Level::Mixed
        } else if needs.grad_w {
            Level::Grad
        } else if needs.grad_v {
            Level::GradV
        } else {
            Level::Value
        }
    }
}

impl Level {
    /// Powers `z^k`, `k < kmax`, of the operator weights the level integrates.
    fn kmax(self) -> usize {
        match self {
            Level::Value => 1,
            Level::GradV => 2,
            Level::Grad => 3,
            Level::Mixed => 4,
            Level::Hessian => 5,
        }
    }
}

impl ClippedDpOracle {
    /// The oracle with the default [`DpConfig`].
    ///
    /// # Errors
    /// [`OracleError::Model`] for an invalid model; [`OracleError::Unsupported`] unless the
    /// model is scalar (`n = l = 1`), clipped ([`LqgModel::clipping`]) and has `B ≠ 0`.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::ClippedDpOracle;
    /// assert!(ClippedDpOracle::new(&LqgModel::thesis()).is_ok());
    /// assert!(ClippedDpOracle::new(&LqgModel::thesis().with_clipping(false)).is_err());
    /// ```
    pub fn new(model: &LqgModel) -> Result<Self, OracleError> {
        ClippedDpOracle::with_config(model, DpConfig::default())
    }

    /// The oracle with an explicit resolution.
    ///
    /// # Errors
    /// As [`ClippedDpOracle::new`], plus [`OracleError::InvalidConfig`].
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClippedDpOracle, DpConfig};
    /// let fine = DpConfig { nodes_per_element: 16, ..DpConfig::default() };
    /// assert!(ClippedDpOracle::with_config(&LqgModel::lqg1d(), fine).is_ok());
    /// ```
    pub fn with_config(model: &LqgModel, config: DpConfig) -> Result<Self, OracleError> {
        model.validate()?;
        config.validate()?;
        if !model.is_scalar() {
            return Err(OracleError::Unsupported(
                "the clipped DP oracle covers scalar models only (n = l = 1)",
            ));
        }
        if !model.clipping {
            return Err(OracleError::Unsupported(
                "the clipped DP oracle needs clipping on; use ClosedFormOracle",
            ));
        }
        if model.b[(0, 0)] == 0.0 {
            return Err(OracleError::Unsupported("B = 0: the action has no effect"));
        }
        Ok(ClippedDpOracle {
            a: model.a[(0, 0)],
            b: model.b[(0, 0)],
            q: model.q[(0, 0)],
            r: model.r[(0, 0)],
            noise: model.noise_std[0],
            gamma: model.gamma,
            s_lo: model.state_low[0],
            s_hi: model.state_high[0],
            a_lo: model.action_low[0],
            a_hi: model.action_high[0],
            i_lo: model.init_low[0],
            i_hi: model.init_high[0],
            config,
            gl: GaussLegendre::new(config.quad_points),
            cheb: Chebyshev::new(config.nodes_per_element),
        })
    }

    /// The resolution in use.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClippedDpOracle, DpConfig};
    /// let o = ClippedDpOracle::new(&LqgModel::thesis()).unwrap();
    /// assert_eq!(o.config(), DpConfig::default());
    /// ```
    pub fn config(&self) -> DpConfig {
        self.config
    }

    // ---------------------------------------------------------------- operators

    /// The θ-independent noise operator `W(y) = E_η V(clip(y + η))` (and, for `k = 1`,
    /// `η0 · W'(y)`) from `V`-grid values to `W`-grid values.
    fn noise_operator(&self, vgrid: &Grid, wgrid: &Grid) -> SpanOp {
        let target = Target {
            grid: vgrid,
            clip: Some((self.s_lo, self.s_hi)),
        };
        let mut op = SpanOp::new(2);
        let mut row = RowAcc::new(vgrid.nodes.len());
        let mut quad = Quad::new(vgrid.p);
        for &y in &wgrid.nodes {
            self.add_gauss(
                &mut row, &target, y, self.noise, -Z_MAX, Z_MAX, 2, &mut quad,
            );
            row.flush(&mut op);
        }
        op
    }

    /// The action-expectation operator of the stochastic policy: for each `V`-grid node `s`,
    /// the weights of `E[z^k W(A s + B a_c)]` (`k < kmax ≤ 5`) and the reward moments
    /// `E[z^k r(s, a_c)]` (`k ≤ 4`).
    fn action_operator(
        &self,
        v: f64,
        sigma: f64,
        vgrid: &Grid,
        target: &Target<'_>,
        kmax: usize,
    ) -> (SpanOp, Vec<[f64; 5]>) {
        let mut op = SpanOp::new(kmax);
        let mut rew = Vec::with_capacity(vgrid.nodes.len());
        let mut row = RowAcc::new(target.grid.nodes.len());
        let mut quad = Quad::new(target.grid.p);
        let full = [1.0, 0.0, 1.0, 0.0, 3.0];
        for &s in &vgrid.nodes {
            let mu = v * s;
            let zl = (self.a_lo - mu) / sigma;
            let zh = (self.a_hi - mu) / sigma;
            let ml = normal_moments(f64::NEG_INFINITY, zl);
            let mh = normal_moments(zh, f64::INFINITY);
            let mi = normal_moments(zl, zh);
            let mut rk = [0.0; 5];
            for k in 0..5 {
                let interior =
                    mu * mu * mi[k] + 2.0 * mu * sigma * mi[k + 1] + sigma * sigma * mi[k + 2];
                rk[k] = -self.q * s * s * full[k]
                    - self.r
                        * (self.a_lo * self.a_lo * ml[k]
                            + self.a_hi * self.a_hi * mh[k]
                            + interior);
            }
            rew.push(rk);
            self.add_point(
                &mut row,
                target,
                self.a * s + self.b * self.a_lo,
                &ml[..kmax],
                &mut quad.lw,
            );
            self.add_point(
                &mut row,
                target,
                self.a * s + self.b * self.a_hi,
                &mh[..kmax],
                &mut quad.lw,
            );
            self.add_gauss(
                &mut row,
                target,
                self.a * s + self.b * mu,
                self.b * sigma,
                zl,
                zh,
                kmax,
                &mut quad,
            );
            row.flush(&mut op);
        }
        (op, rew)
    }

    /// Weights of `(1/(hi − lo)) ∫_lo^hi f` over the `V`-grid node values (`f(lo)` for a
    /// degenerate init box).
    fn init_weights(&self, vgrid: &Grid) -> Vec<f64> {
        let mut out = vec![0.0; vgrid.nodes.len()];
        let mut lw = vec![0.0; vgrid.p];
        let (lo, hi) = (self.i_lo, self.i_hi);
        let mut add = |x: f64, w: f64, out: &mut Vec<f64>| {
            let first = self.interp(vgrid, x, &mut lw);
            for (j, l) in lw[..vgrid.p].iter().enumerate() {
                out[first + j] += w * l;
            }
        };
        if hi <= lo {
            add(lo, 1.0, &mut out);
            return out;
        }
        let mut cuts = vec![lo, hi];
        cuts.extend(vgrid.breaks.iter().copied().filter(|&b| b > lo && b < hi));
        cuts.sort_by(f64::total_cmp);
        for w in cuts.windows(2) {
            let (mid, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
            for (x, wq) in self.gl.nodes.iter().zip(&self.gl.weights) {
                add(mid + half * x, wq * half / (hi - lo), &mut out);
            }
        }
        out
    }

    // ---------------------------------------------------------------- evaluations

    /// Stochastic policy: the channels `needs` asks for (see [`Active`]), then `J` and the
    /// requested derivatives.
    fn eval_stochastic(
        &self,
        v: f64,
        sigma: f64,
        horizon: usize,
        needs: Needs,
    ) -> Result<ExactEval, OracleError> {
        let level = Level::from(needs);
        let (vgrid, wgrid) = self.grids(v, sigma, horizon)?;
        let noise_op = wgrid.as_ref().map(|wg| self.noise_operator(&vgrid, wg));
        let target = match &wgrid {
            Some(wg) => Target {
                grid: wg,
                clip: None,
            },
            None => Target {
                grid: &vgrid,
                clip: Some((self.s_lo, self.s_hi)),
            },
        };
        let (op, rew) = self.action_operator(v, sigma, &vgrid, &target, level.kmax());
        let rec = Recursion {
            op: &op,
            noise: noise_op.as_ref(),
            rew: &rew,
            nodes: &vgrid.nodes,
            sigma,
            gamma: self.gamma,
            horizon,
        };
        let ch = match level {
            Level::Hessian => rec.run::<5, 3, 3, 3>(),
            Level::Mixed => rec.run::<4, 3, 2, 1>(),
            Level::Grad => rec.run::<3, 1, 1, 0>(),
            Level::GradV => rec.run::<2, 1, 0, 0>(),
            Level::Value => rec.run::<1, 0, 0, 0>(),
        };
        let iw = self.init_weights(&vgrid);
        let [j, dv, dw, dvw, dvv, dww] =
            ch.map(|x| iw.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>());
        finish(ExactEval {
            j,
            grad_v: if level >= Level::GradV {
                vec![dv]
            } else {
                Vec::new()
            },
            grad_w: if level >= Level::Grad {
                vec![dw]
            } else {
                Vec::new()
            },
            mixed_wv: if level >= Level::Mixed {
                vec![dvw]
            } else {
                Vec::new()
            },
            hessian: (level == Level::Hessian)
                .then(|| DMatrix::from_row_slice(2, 2, &[dvv, dvw, dvw, dww])),
            sigma: vec![sigma],
        })
    }

    /// Deterministic policy with transition noise: channels `V`, `∂_v V` on the `V` grid,
    /// `W`, `W'`, `∂_v W` on the `W` grid.
    fn eval_deterministic_noisy(&self, v: f64, horizon: usize) -> Result<ExactEval, OracleError> {
        let (vgrid, wgrid) = self.grids(v, 0.0, horizon)?;
        let wgrid = wgrid.ok_or(OracleError::Unsupported("internal: missing W grid"))?;
        let nop = self.noise_operator(&vgrid, &wgrid);
        let n = vgrid.nodes.len();
        let mut lw = vec![0.0; wgrid.p];
        let mut at = Vec::with_capacity(n);
        for &s in &vgrid.nodes {
            let ac = (v * s).clamp(self.a_lo, self.a_hi);
            let first = self.interp(&wgrid, self.a * s + self.b * ac, &mut lw);
            at.push((
                first,
                lw.clone(),
                ac,
                v * s > self.a_lo && v * s < self.a_hi,
            ));
        }
        let g = self.gamma;
        let (mut val, mut dv) = (vec![0.0; n], vec![0.0; n]);
        for _ in 0..horizon {
            if crate::cancel::requested() {
                break;
            }
            let (mut w, mut wd, mut wv) = (
                vec![0.0; wgrid.nodes.len()],
                vec![0.0; wgrid.nodes.len()],
                vec![0.0; wgrid.nodes.len()],
            );
            let mut d = [0.0; 2];
            for i in 0..nop.rows() {
                nop.row_dots(i, &val, &mut d);
                w[i] = d[0];
                wd[i] = d[1] / self.noise;
                nop.row_dots(i, &dv, &mut d[..1]);
                wv[i] = d[0];
            }
            for (i, (first, l, ac, interior)) in at.iter().enumerate() {
                let ev = |f: &Vec<f64>| {
                    l.iter()
                        .enumerate()
                        .map(|(j, x)| x * f[first + j])
                        .sum::<f64>()
                };
                let s = vgrid.nodes[i];
                val[i] = -(self.q * s * s + self.r * ac * ac) + g * ev(&w);
                let slope = if *interior {
                    (-2.0 * self.r * ac + g * self.b * ev(&wd)) * s
                } else {
                    0.0
                };
                dv[i] = slope + g * ev(&wv);
            }
        }
        let iw = self.init_weights(&vgrid);
        let dot = |x: &Vec<f64>| iw.iter().zip(x).map(|(a, b)| a * b).sum::<f64>();
        finish(ExactEval {
            j: dot(&val),
            grad_v: vec![dot(&dv)],
            grad_w: Vec::new(),
            mixed_wv: Vec::new(),
            hessian: None,
            sigma: Vec::new(),
        })
    }
}

/// Rejects a result with a non-finite entry.
fn finish(e: ExactEval) -> Result<ExactEval, OracleError> {
    let finite = e.j.is_finite()
        && e.grad_v
            .iter()
            .chain(&e.grad_w)
            .chain(&e.mixed_wv)
            .all(|x| x.is_finite())
        && e.hessian
            .as_ref()
            .is_none_or(|h| h.iter().all(|x| x.is_finite()));
    if finite {
        Ok(e)
    } else {
        Err(OracleError::Overflow)
    }
}

impl ExactOracle for ClippedDpOracle {
    fn dim_v(&self) -> usize {
        1
    }

    fn dim_w(&self) -> usize {
        1
    }

    /// `J`, `∂_v J`, `∂_w J`, `∂²_{wv} J` and the 2×2 Hessian of the clipped scalar LQG for
    /// a finite horizon (stochastic policy); `J` and `∂_v J` for the deterministic policy
    /// (Hessian `None`).
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon};
    /// let o = ClippedDpOracle::new(&LqgModel::thesis()).unwrap();
    /// let e = o
    ///     .evaluate(&[-0.5], &Exploration::Gaussian { w: vec![(0.5f64).ln()] }, Horizon::Finite(20))
    ///     .unwrap();
    /// assert!(e.j < 0.0 && e.grad_w[0] < 0.0);
    /// assert!(o.evaluate(&[-0.5], &Exploration::Deterministic, Horizon::Infinite).is_err());
    /// ```
    fn evaluate(
        &self,
        v: &[f64],
        exploration: &Exploration,
        horizon: Horizon,
    ) -> Result<ExactEval, OracleError> {
        self.evaluate_with(v, exploration, horizon, Needs::ALL)
    }

    /// As [`evaluate`](ExactOracle::evaluate), propagating only the channels `needs` asks
    /// for: `J` alone costs about a third of the full evaluation, `J` with `∂_v J`, `∂_w J`
    /// and `∂²_{wv} J` (what SEPG uses) about two thirds. Requested quantities are computed
    /// to the same accuracy as by [`evaluate`](ExactOracle::evaluate) (identical up to
    /// rounding); `∂²_{wv} J` brings `∂_v J` and `∂_w J` along, the Hessian everything.
    /// Fields of quantities not computed are empty (`hessian: None`). The deterministic policy
    /// always returns `J` and `∂_v J`.
    ///
    /// ```
    /// use sepg_mdp::lqg_model::LqgModel;
    /// use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon, Needs};
    /// let o = ClippedDpOracle::new(&LqgModel::thesis()).unwrap();
    /// let ex = Exploration::Gaussian { w: vec![(0.5f64).ln()] };
    /// let all = o.evaluate(&[-0.5], &ex, Horizon::Finite(20)).unwrap();
    /// let sepg = o.evaluate_with(&[-0.5], &ex, Horizon::Finite(20), Needs::SEPG).unwrap();
    /// assert!((sepg.mixed_wv[0] - all.mixed_wv[0]).abs() < 1e-12 * all.j.abs());
    /// assert!(sepg.hessian.is_none());
    /// let j = o.evaluate_with(&[-0.5], &ex, Horizon::Finite(20), Needs::VALUE).unwrap();
    /// assert!((j.j - all.j).abs() < 1e-12 * all.j.abs() && j.grad_v.is_empty());
    /// ```
    fn evaluate_with(
        &self,
        v: &[f64],
        exploration: &Exploration,
        horizon: Horizon,
        needs: Needs,
    ) -> Result<ExactEval, OracleError> {
        let params = check_params(v, exploration, 1, 1)?;
        let h = match horizon {
            Horizon::Finite(0) => return Err(OracleError::ZeroHorizon),
            Horizon::Finite(h) => h,
            Horizon::Infinite => {
                return Err(OracleError::Unsupported(
                    "the clipped DP oracle covers finite horizons only",
                ));
            }
        };
        let eval = match params.sigma.first() {
            Some(&sigma) => self.eval_stochastic(v[0], sigma, h, needs),
            None if self.noise > 0.0 => self.eval_deterministic_noisy(v[0], h),
            None => self.eval_deterministic_exact(v[0], h),
        };
        // The recursions stop early when cancelled; what they return then is discarded.
        if crate::cancel::requested() {
            return Err(OracleError::Cancelled);
        }
        eval
    }
}
