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

use super::jet::Dual;
use super::quadrature::{Chebyshev, GaussLegendre, dot, norm_cdf, norm_pdf, normal_moments};
use super::{ExactEval, ExactOracle, Exploration, Horizon, Needs, OracleError, check_params};
use crate::lqg_model::LqgModel;
use nalgebra::DMatrix;

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
pub(crate) const MAX_NODES: usize = 32;
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

/// A smoothed feature of the value function: centre and scale.
#[derive(Debug, Clone, Copy)]
struct Zone {
    centre: f64,
    scale: f64,
}

/// The piecewise Chebyshev grid of one represented function.
#[derive(Debug, Clone)]
struct Grid {
    breaks: Vec<f64>,
    nodes: Vec<f64>,
    p: usize,
}

/// A run of consecutive columns of one operator row.
#[derive(Debug, Clone, Copy)]
struct Seg {
    /// First column.
    start: usize,
    /// Number of columns.
    len: usize,
    /// Offset of the run's weights in [`SpanOp::vals`].
    off: usize,
}

/// A row-sparse operator whose entries carry the weights of the powers `z^0 … z^{kmax−1}`.
///
/// Each row is a list of runs of consecutive columns ([`Seg`]); the weights of power `k` of a
/// run are contiguous, at `vals[off + k·len ..][..len]`, so that applying the operator is a
/// sequence of dense dot products.
#[derive(Debug, Clone)]
struct SpanOp {
    kmax: usize,
    row_ptr: Vec<usize>,
    segs: Vec<Seg>,
    vals: Vec<f64>,
}

impl SpanOp {
    fn new(kmax: usize) -> Self {
        SpanOp {
            kmax,
            row_ptr: vec![0],
            segs: Vec::new(),
            vals: Vec::new(),
        }
    }

    fn rows(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// The runs of row `i`.
    fn row(&self, i: usize) -> &[Seg] {
        &self.segs[self.row_ptr[i]..self.row_ptr[i + 1]]
    }

    /// The weights of power `k` of a run.
    fn weights(&self, seg: &Seg, k: usize) -> &[f64] {
        &self.vals[seg.off + k * seg.len..][..seg.len]
    }

    /// `Σ_c w_k[i, c] x[c]` for `k < out.len()` over row `i`.
    fn row_dots(&self, i: usize, x: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for seg in self.row(i) {
            let xs = &x[seg.start..][..seg.len];
            for (k, o) in out.iter_mut().enumerate() {
                *o += dot(self.weights(seg, k), xs);
            }
        }
    }

    /// `y = W_0 x` (the `k = 0` weights).
    fn apply_k0(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = self
                .row(i)
                .iter()
                .map(|seg| dot(self.weights(seg, 0), &x[seg.start..][..seg.len]))
                .sum();
        }
    }
}

/// Dense row accumulator for building a [`SpanOp`].
struct RowAcc {
    acc: Vec<[f64; 5]>,
    touched: Vec<usize>,
    mark: Vec<bool>,
}

/// Columns of zeros tolerated inside a run before a new run starts.
const RUN_GAP: usize = 4;

impl RowAcc {
    fn new(n: usize) -> Self {
        RowAcc {
            acc: vec![[0.0; 5]; n],
            touched: Vec::new(),
            mark: vec![false; n],
        }
    }

    fn add(&mut self, col: usize, k: usize, x: f64) {
        if !self.mark[col] {
            self.mark[col] = true;
            self.touched.push(col);
        }
        self.acc[col][k] += x;
    }

    /// Moves the row into `op` (runs of touched columns) and resets the accumulator.
    fn flush(&mut self, op: &mut SpanOp) {
        self.touched.sort_unstable();
        let mut i = 0;
        while i < self.touched.len() {
            let mut j = i + 1;
            while j < self.touched.len() && self.touched[j] <= self.touched[j - 1] + RUN_GAP {
                j += 1;
            }
            let (first, last) = (self.touched[i], self.touched[j - 1]);
            let seg = Seg {
                start: first,
                len: last + 1 - first,
                off: op.vals.len(),
            };
            for k in 0..op.kmax {
                op.vals.extend(self.acc[first..=last].iter().map(|a| a[k]));
            }
            op.segs.push(seg);
            i = j;
        }
        for &c in &self.touched {
            self.acc[c] = [0.0; 5];
            self.mark[c] = false;
        }
        self.touched.clear();
        op.row_ptr.push(op.segs.len());
    }
}

/// Largest number of fixed sub-pieces per element with a cached weight table.
const MAX_SUB_PIECES: usize = 256;

/// Scratch of the quadrature: interpolation weights, cut points, and the interpolation
/// weights at the Gauss–Legendre nodes of an element split into `P` equal sub-pieces.
struct Quad {
    lw: Vec<f64>,
    cuts: Vec<(f64, bool)>,
    /// `tables[P]`: `P · quad_points · p` weights (empty until first use), row
    /// `(i · quad_points + q)` for node `q` of sub-piece `i`.
    tables: Vec<Vec<f64>>,
}

impl Quad {
    fn new(p: usize) -> Self {
        Quad {
            lw: vec![0.0; p],
            cuts: Vec::new(),
            tables: Vec::new(),
        }
    }

    /// The table for `P = sub` sub-pieces (computed on first use).
    fn table(&mut self, o: &ClippedDpOracle, sub: usize) -> Option<&[f64]> {
        if sub > MAX_SUB_PIECES {
            return None;
        }
        if self.tables.len() <= sub {
            self.tables.resize_with(sub + 1, Vec::new);
        }
        if self.tables[sub].is_empty() {
            let p = o.config.nodes_per_element;
            let mut tab = Vec::with_capacity(sub * o.gl.nodes.len() * p);
            for i in 0..sub {
                for x in &o.gl.nodes {
                    let tq = -1.0 + (2 * i + 1) as f64 / sub as f64 + x / sub as f64;
                    o.cheb.weights(tq, &mut self.lw);
                    tab.extend_from_slice(&self.lw[..p]);
                }
            }
            self.tables[sub] = tab;
        }
        Some(&self.tables[sub])
    }
}

/// The integrals `Σ weight · φ(z) z^k · l_j` of one segment of [`ClippedDpOracle::add_gauss`],
/// per power `k < kmax` and node `j < p` of its element.
struct SegmentSums {
    sums: [[f64; MAX_NODES]; 5],
    kmax: usize,
    p: usize,
}

impl SegmentSums {
    /// Adds the quadrature point `z` of weight `weight`, `l` the interpolation weights of
    /// the element's nodes at the point.
    fn add(&mut self, z: f64, weight: f64, l: &[f64]) {
        let base = weight * norm_pdf(z);
        let mut coef = [0.0; 5];
        let mut zk = 1.0;
        for c in coef.iter_mut().take(self.kmax) {
            *c = base * zk;
            zk *= z;
        }
        for (lk, &ck) in self.sums.iter_mut().zip(&coef[..self.kmax]) {
            for (a, &lj) in lk[..self.p].iter_mut().zip(l) {
                *a += ck * lj;
            }
        }
    }
}

/// The channels a request needs: `∂_w` comes with `∂_v` (nearly free), `∂²_wv` needs both,
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

/// Where a Gaussian integral evaluates the represented function: on a grid, with the next
/// state clipped to the state box or not.
struct Target<'g> {
    grid: &'g Grid,
    clip: Option<(f64, f64)>,
}

/// An interval of initial states on which `s_t = α s_0 + β` (exact deterministic method).
#[derive(Debug, Clone, Copy)]
struct Piece {
    lo: f64,
    hi: f64,
    alpha: Dual,
    beta: Dual,
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

    // ---------------------------------------------------------------- grids

    /// Breakpoints of a grid on `[lo, hi]`: the exact kinks, the ends of every zone, then a
    /// uniform subdivision of each sub-interval to the local target width.
    fn breaks(
        &self,
        lo: f64,
        hi: f64,
        kinks: &[f64],
        zones: &[Zone],
        global_scale: f64,
    ) -> Result<Vec<f64>, OracleError> {
        let width = hi - lo;
        let eps = 1e-12 * width;
        let mut pts = vec![lo, hi];
        pts.extend(
            kinks
                .iter()
                .copied()
                .filter(|&k| k > lo + eps && k < hi - eps),
        );
        for z in zones {
            for e in [
                z.centre - ZONE_HALF_WIDTH * z.scale,
                z.centre + ZONE_HALF_WIDTH * z.scale,
            ] {
                if e > lo + eps && e < hi - eps {
                    pts.push(e);
                }
            }
        }
        pts.sort_by(f64::total_cmp);
        pts.dedup_by(|x, y| (*x - *y).abs() <= eps);
        let base = width / self.config.min_elements as f64;
        let per = self.config.elements_per_scale;
        let mut out = vec![lo];
        let mut needed = 0usize;
        for w in pts.windows(2) {
            let (x0, x1) = (w[0], w[1]);
            let mid = 0.5 * (x0 + x1);
            let mut h = base.min(global_scale / per);
            for z in zones {
                if (mid - z.centre).abs() <= ZONE_HALF_WIDTH * z.scale {
                    h = h.min(z.scale / per);
                }
            }
            let count = ((x1 - x0) / h).ceil();
            let count = if count.is_finite() && count >= 1.0 {
                count
            } else {
                f64::from(u32::MAX)
            };
            needed = needed.saturating_add(count as usize);
            if needed > self.config.max_elements {
                return Err(OracleError::ResolutionExceeded {
                    needed,
                    max: self.config.max_elements,
                });
            }
            let c = count as usize;
            for i in 1..c {
                out.push(x0 + (x1 - x0) * i as f64 / count);
            }
            out.push(x1);
        }
        Ok(out)
    }

    fn grid(&self, breaks: Vec<f64>) -> Grid {
        let p = self.config.nodes_per_element;
        let mut nodes = Vec::with_capacity((breaks.len() - 1) * p);
        for w in breaks.windows(2) {
            let (mid, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
            nodes.extend(self.cheb.nodes.iter().map(|x| mid + half * x));
        }
        Grid { breaks, nodes, p }
    }

    /// Index of the element of the grid containing `y` (clamped to the grid).
    fn element(grid: &Grid, y: f64) -> usize {
        let nel = grid.breaks.len() - 1;
        grid.breaks[1..nel]
            .partition_point(|&b| b <= y)
            .min(nel - 1)
    }

    /// Barycentric interpolation weights at `y` on element `e` into `out[..p]`.
    fn weights_in(&self, grid: &Grid, e: usize, y: f64, out: &mut [f64]) {
        let (b0, b1) = (grid.breaks[e], grid.breaks[e + 1]);
        self.cheb
            .weights(((2.0 * y - b0 - b1) / (b1 - b0)).clamp(-1.0, 1.0), out);
    }

    /// Barycentric interpolation weights at `y` (clamped to the grid) into `out`; returns the
    /// index of the first node of the element.
    fn interp(&self, grid: &Grid, y: f64, out: &mut [f64]) -> usize {
        let e = Self::element(grid, y);
        self.weights_in(grid, e, y, out);
        e * grid.p
    }

    /// Adds `coef[k] · f(clip(y))` (`k = 0..kmax`) to the row, `f` the interpolant on the grid.
    fn add_point(&self, row: &mut RowAcc, t: &Target<'_>, y: f64, coef: &[f64], lw: &mut [f64]) {
        let y = match t.clip {
            Some((lo, hi)) => y.clamp(lo, hi),
            None => y,
        };
        let first = self.interp(t.grid, y, lw);
        for (j, &l) in lw[..t.grid.p].iter().enumerate() {
            if l != 0.0 {
                for (k, &c) in coef.iter().enumerate() {
                    row.add(first + j, k, c * l);
                }
            }
        }
    }

    /// Adds `∫_{z0}^{z1} z^k φ(z) f(clip(y0 + y1 z)) dz` (`k < kmax`) to the row, the range
    /// truncated to `|z| ≤ Z_MAX`.
    ///
    /// The range is cut at the clip points and at the element boundaries ([`Self::cuts`]),
    /// and each piece is integrated by [`Self::add_segment`].
    #[allow(clippy::too_many_arguments)]
    fn add_gauss(
        &self,
        row: &mut RowAcc,
        t: &Target<'_>,
        y0: f64,
        y1: f64,
        z0: f64,
        z1: f64,
        kmax: usize,
        quad: &mut Quad,
    ) {
        let hard0 = z0 > -Z_MAX;
        let hard1 = z1 < Z_MAX;
        let (z0, z1) = (z0.max(-Z_MAX), z1.min(Z_MAX));
        if z0 >= z1 {
            return;
        }
        if y1 == 0.0 {
            let m = normal_moments(z0, z1);
            self.add_point(row, t, y0, &m[..kmax], &mut quad.lw);
            return;
        }
        let mut cuts = std::mem::take(&mut quad.cuts);
        Self::cuts(t, (y0, y1), (z0, hard0), (z1, hard1), &mut cuts);
        for w in cuts.windows(2) {
            if w[1].0 <= w[0].0 {
                continue;
            }
            self.add_segment(row, t, (y0, y1), (w[0], w[1]), kmax, quad);
        }
        quad.cuts = cuts;
    }

    /// The points cutting `[z0, z1]` into `cuts`, sorted: the ends, where `y0 + y1 z` meets a
    /// clip point, and where it crosses an element boundary of the grid, each with whether
    /// the integrand is discontinuous there (the ends when inside the truncation range, the
    /// clip points).
    fn cuts(
        t: &Target<'_>,
        (y0, y1): (f64, f64),
        (z0, hard0): (f64, bool),
        (z1, hard1): (f64, bool),
        cuts: &mut Vec<(f64, bool)>,
    ) {
        let zof = |y: f64| (y - y0) / y1;
        cuts.clear();
        cuts.extend([(z0, hard0), (z1, hard1)]);
        let (ya, yb) = {
            let (p, q) = (y0 + y1 * z0, y0 + y1 * z1);
            (p.min(q), p.max(q))
        };
        if let Some((lo, hi)) = t.clip {
            for c in [lo, hi] {
                let z = zof(c);
                if z > z0 && z < z1 {
                    cuts.push((z, true));
                }
            }
        }
        let br = &t.grid.breaks;
        let first = br.partition_point(|&b| b <= ya);
        let last = br.partition_point(|&b| b < yb);
        for &b in &br[first..last] {
            let z = zof(b);
            if z > z0 && z < z1 {
                cuts.push((z, false));
            }
        }
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
    }

    /// Adds the integral over one piece `[za, zb]` between two cuts (`ha`, `hb`: whether the
    /// integrand is discontinuous at its ends). A piece whose next state is clipped is a point
    /// mass; otherwise it lies in one element of the grid and is integrated with the element's
    /// fixed sub-pieces ([`Quad::table`], no per-point interpolation weights) when both ends
    /// are continuous, else with pieces at most [`PIECE_WIDTH`] wide in `z` and barycentric
    /// weights.
    fn add_segment(
        &self,
        row: &mut RowAcc,
        t: &Target<'_>,
        (y0, y1): (f64, f64),
        ((za, ha), (zb, hb)): ((f64, bool), (f64, bool)),
        kmax: usize,
        quad: &mut Quad,
    ) {
        let ymid = y0 + y1 * 0.5 * (za + zb);
        if let Some((lo, hi)) = t.clip
            && (ymid < lo || ymid > hi)
        {
            let m = normal_moments(za, zb);
            self.add_point(row, t, ymid, &m[..kmax], &mut quad.lw);
            return;
        }
        // The segment lies in one element: accumulate locally, flush once.
        let e = Self::element(
            t.grid,
            ymid.clamp(t.grid.breaks[0], t.grid.breaks[t.grid.breaks.len() - 1]),
        );
        let p = t.grid.p;
        let mut local = SegmentSums {
            sums: [[0.0; MAX_NODES]; 5],
            kmax,
            p,
        };
        let (b0, b1) = (t.grid.breaks[e], t.grid.breaks[e + 1]);
        let sub = ((b1 - b0) / (y1.abs() * PIECE_WIDTH)).ceil();
        let table = if !ha && !hb && sub <= MAX_SUB_PIECES as f64 {
            quad.table(self, sub.max(1.0) as usize)
        } else {
            None
        };
        if let Some(table) = table {
            self.sum_sub_pieces(&mut local, (b0, b1), (y0, y1), (za, zb), sub, table);
        } else {
            let pieces = ((zb - za) / PIECE_WIDTH).ceil().max(1.0);
            let hz = (zb - za) / pieces;
            for i in 0..pieces as usize {
                let pa = za + hz * i as f64;
                let (mid, half) = (pa + 0.5 * hz, 0.5 * hz);
                for (x, wq) in self.gl.nodes.iter().zip(&self.gl.weights) {
                    let z = mid + half * x;
                    self.weights_in(t.grid, e, y0 + y1 * z, &mut quad.lw);
                    local.add(z, wq * half, &quad.lw[..p]);
                }
            }
        }
        for (k, lk) in local.sums[..kmax].iter().enumerate() {
            for (j, &x) in lk[..p].iter().enumerate() {
                row.add(e * p + j, k, x);
            }
        }
    }

    /// The fixed sub-pieces (`sub` of them, each at most one unit wide in `z`) of the element
    /// `[b0, b1]` that meet the segment `[za, zb]`, with the interpolation weights `table` of
    /// [`Quad::table`]. The ends of the segment are element boundaries or the truncation
    /// points, where the integrand is continuous and negligible respectively.
    fn sum_sub_pieces(
        &self,
        local: &mut SegmentSums,
        (b0, b1): (f64, f64),
        (y0, y1): (f64, f64),
        (za, zb): (f64, f64),
        sub: f64,
        table: &[f64],
    ) {
        let p = local.p;
        let (mid_e, half_e) = (0.5 * (b0 + b1), 0.5 * (b1 - b0));
        let nsub = sub.max(1.0) as usize;
        let tof = |z: f64| ((y0 + y1 * z - mid_e) / half_e).clamp(-1.0, 1.0);
        let (ta, tb) = {
            let (u, v) = (tof(za), tof(zb));
            (u.min(v), u.max(v))
        };
        let scale = 0.5 * nsub as f64;
        let i0 = ((ta + 1.0) * scale).floor() as usize;
        let i1 = (((tb + 1.0) * scale).ceil() as usize).clamp(i0 + 1, nsub);
        let nq = self.gl.nodes.len();
        let dz = half_e / (nsub as f64 * y1.abs());
        for i in i0..i1 {
            for (q, (x, wq)) in self.gl.nodes.iter().zip(&self.gl.weights).enumerate() {
                let tq = -1.0 + (2 * i + 1) as f64 / nsub as f64 + x / nsub as f64;
                let z = (mid_e + half_e * tq - y0) / y1;
                local.add(z, wq * dz, &table[(i * nq + q) * p..][..p]);
            }
        }
    }

    // ---------------------------------------------------------------- features

    /// Exact kinks of `V_t` from the clipped-action branches (no transition noise): the
    /// points where `A s + B a_bound` hits a state bound, and their preimages under the same
    /// maps for `horizon` steps. Each kink carries the probability of the chain of clipped
    /// actions that produces it (times `γ` per step); kinks below [`KINK_WEIGHT`] change the
    /// value function by less than rounding and are not tracked.
    fn exact_kinks(&self, v: f64, sigma: f64, horizon: usize) -> Result<Vec<f64>, OracleError> {
        let mut kinks: Vec<f64> = Vec::new();
        if self.a == 0.0 {
            return Ok(kinks);
        }
        let eps = 1e-12 * (self.s_hi - self.s_lo);
        let inside = |x: f64| x > self.s_lo + eps && x < self.s_hi - eps;
        let tail = |ab: f64, s: f64| {
            if ab == self.a_lo {
                norm_cdf((self.a_lo - v * s) / sigma)
            } else {
                norm_cdf((v * s - self.a_hi) / sigma)
            }
        };
        let mut frontier = vec![(self.s_lo, 1.0), (self.s_hi, 1.0)];
        for _ in 0..horizon {
            if crate::cancel::requested() {
                break;
            }
            let mut next = Vec::new();
            for &(k, weight) in &frontier {
                for ab in [self.a_lo, self.a_hi] {
                    let s = (k - self.b * ab) / self.a;
                    let w = weight * self.gamma * tail(ab, s);
                    if inside(s) && w >= KINK_WEIGHT && !kinks.iter().any(|x| (x - s).abs() <= eps)
                    {
                        kinks.push(s);
                        next.push((s, w));
                    }
                }
            }
            if kinks.len() > MAX_KINKS {
                return Err(OracleError::ResolutionExceeded {
                    needed: kinks.len(),
                    max: MAX_KINKS,
                });
            }
            if next.is_empty() {
                break;
            }
            frontier = next;
        }
        Ok(kinks)
    }

    /// Zones of the smoothed clipping features of `V_t` and the global scale of features
    /// created by an expanding closed loop (`|A + Bv| > 1`).
    fn zones(&self, v: f64, sigma: f64, horizon: usize) -> (Vec<Zone>, f64) {
        let mut zones = Vec::new();
        let lam = self.a + self.b * v;
        let spread = (self.b * self.b * sigma * sigma + self.noise * self.noise).sqrt();
        if sigma > 0.0 && v != 0.0 {
            for ab in [self.a_lo, self.a_hi] {
                zones.push(Zone {
                    centre: ab / v,
                    scale: sigma / v.abs(),
                });
            }
        }
        if lam != 0.0 && spread > 0.0 {
            for sb in [self.s_lo, self.s_hi] {
                zones.push(Zone {
                    centre: sb / lam,
                    scale: spread / lam.abs(),
                });
            }
        }
        // Earlier steps see each feature through the closed loop `s ↦ λ s + spread · ξ`: at
        // `c/λ`, widened to `√(ℓ² + spread²)/|λ|`. With `|λ| > 1` the global scale covers
        // these; with `|λ| ≤ 1` they leave the box or widen beyond the base resolution,
        // except near `λ = 1`, where the features at the state bounds pile up with scales
        // `spread·√k` (a diffusion). Only zones that refine the base grid are kept.
        let coarse = (self.s_hi - self.s_lo) / self.config.min_elements as f64
            * self.config.elements_per_scale;
        if lam != 0.0 && lam.abs() <= 1.0 && spread > 0.0 {
            let base = zones.len();
            for z in 0..base {
                let Zone {
                    mut centre,
                    mut scale,
                } = zones[z];
                for _ in 1..horizon {
                    if crate::cancel::requested() {
                        break;
                    }
                    centre /= lam;
                    scale = scale.hypot(spread) / lam.abs();
                    if scale >= coarse {
                        break;
                    }
                    let reach = ZONE_HALF_WIDTH * scale;
                    if centre - reach < self.s_hi && centre + reach > self.s_lo {
                        zones.push(Zone { centre, scale });
                    }
                }
            }
        }
        if self.noise > 0.0 && self.a != 0.0 {
            for sb in [self.s_lo, self.s_hi] {
                for ab in [self.a_lo, self.a_hi] {
                    zones.push(Zone {
                        centre: (sb - self.b * ab) / self.a,
                        scale: self.noise / self.a.abs(),
                    });
                }
            }
        }
        let global = if lam.abs() > 1.0 && spread > 0.0 {
            spread / (lam * lam - 1.0).sqrt()
        } else {
            f64::INFINITY
        };
        (zones, global)
    }

    /// Range of the pre-noise next state `A s + B a_c` over the boxes.
    fn pre_noise_range(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for s in [self.s_lo, self.s_hi] {
            for a in [self.a_lo, self.a_hi] {
                let y = self.a * s + self.b * a;
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        (lo, hi)
    }

    /// Grids of `V` (state box) and, with transition noise, of `W` (pre-noise range).
    fn grids(
        &self,
        v: f64,
        sigma: f64,
        horizon: usize,
    ) -> Result<(Grid, Option<Grid>), OracleError> {
        let (zones, global) = self.zones(v, sigma, horizon);
        let mut kinks = if self.noise == 0.0 && sigma > 0.0 {
            self.exact_kinks(v, sigma, horizon)?
        } else {
            Vec::new()
        };
        if sigma == 0.0 && v != 0.0 {
            kinks.extend([self.a_lo / v, self.a_hi / v]);
        }
        let vgrid = self.grid(self.breaks(self.s_lo, self.s_hi, &kinks, &zones, global)?);
        if self.noise == 0.0 {
            return Ok((vgrid, None));
        }
        let mut wz: Vec<Zone> = zones
            .iter()
            .map(|z| Zone {
                centre: z.centre,
                scale: (z.scale * z.scale + self.noise * self.noise).sqrt(),
            })
            .collect();
        for c in [self.s_lo, self.s_hi].iter().chain(&kinks) {
            wz.push(Zone {
                centre: *c,
                scale: self.noise,
            });
        }
        let (lo, hi) = self.pre_noise_range();
        let (lo, hi) = if hi - lo > 0.0 {
            (lo, hi)
        } else {
            (lo - 1.0, hi + 1.0)
        };
        let wgrid = self.grid(self.breaks(lo, hi, &[], &wz, global)?);
        Ok((vgrid, Some(wgrid)))
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

    /// Deterministic policy without noise: exact propagation of initial-state intervals on
    /// which `s_t` is affine in `s_0`, with first derivatives in `v` (dual numbers); the
    /// quadratic rewards are integrated exactly (2-point Gauss–Legendre). The integrand is
    /// continuous in `s_0`, so the moving interval ends contribute no boundary terms.
    fn eval_deterministic_exact(&self, v: f64, horizon: usize) -> Result<ExactEval, OracleError> {
        let (lo, hi) = (self.i_lo, self.i_hi);
        let width = hi - lo;
        let vd = Dual { x: v, d: 1.0 };
        let mut pieces = vec![Piece {
            lo,
            hi,
            alpha: Dual::c(1.0),
            beta: Dual::c(0.0),
        }];
        let mut j = Dual::c(0.0);
        let mut disc = 1.0;
        let action_kinks: Vec<f64> = if v == 0.0 {
            Vec::new()
        } else {
            vec![self.a_lo / v, self.a_hi / v]
        };
        for _ in 0..horizon {
            if crate::cancel::requested() {
                break;
            }
            let mut next = Vec::with_capacity(pieces.len());
            for pc in &pieces {
                for (l0, l1) in split(pc.lo, pc.hi, pc.alpha.x, pc.beta.x, &action_kinks) {
                    let weight = if width > 0.0 { (l1 - l0) / width } else { 1.0 };
                    let (ca, cb) = self.clipped_action(pc, vd, 0.5 * (l0 + l1));
                    for rwd in self.node_rewards(pc, (ca, cb), (l0, l1)) {
                        j = j.add(rwd.scale(0.5 * weight * disc));
                    }
                    self.next_pieces(pc, (ca, cb), (l0, l1), &mut next);
                }
            }
            if next.len() > MAX_PIECES {
                return Err(OracleError::ResolutionExceeded {
                    needed: next.len(),
                    max: MAX_PIECES,
                });
            }
            pieces = next;
            disc *= self.gamma;
        }
        finish(ExactEval {
            j: j.x,
            grad_v: vec![j.d],
            grad_w: Vec::new(),
            mixed_wv: Vec::new(),
            hessian: None,
            sigma: Vec::new(),
        })
    }

    /// The action `a_c = ca·s₀ + cb` on the piece `pc` of initial states (dual coefficients
    /// in `v`; `vd` = v with derivative 1), clipped or not as at the initial state `mid`: the
    /// piece is split at the action kinks, so one side holds on all of it.
    fn clipped_action(&self, pc: &Piece, vd: Dual, mid: f64) -> (Dual, Dual) {
        let s_mid = pc.alpha.x * mid + pc.beta.x;
        let u = vd.x * s_mid;
        if u <= self.a_lo {
            (Dual::c(0.0), Dual::c(self.a_lo))
        } else if u >= self.a_hi {
            (Dual::c(0.0), Dual::c(self.a_hi))
        } else {
            (vd.mul(pc.alpha), vd.mul(pc.beta))
        }
    }

    /// The rewards `r(s(s₀), a(s₀))` at the 2-point Gauss–Legendre nodes `s₀` of `[l0, l1]`
    /// (exact for the quadratic reward), `s = α s₀ + β` on the piece `pc`, `a = ca s₀ + cb`.
    fn node_rewards(&self, pc: &Piece, (ca, cb): (Dual, Dual), (l0, l1): (f64, f64)) -> [Dual; 2] {
        let gl2 = [-(1.0f64 / 3.0).sqrt(), (1.0f64 / 3.0).sqrt()];
        let mid = 0.5 * (l0 + l1);
        gl2.map(|x| {
            let s0 = Dual::c(mid + 0.5 * (l1 - l0) * x);
            let s = pc.alpha.mul(s0).add(pc.beta);
            let a = ca.mul(s0).add(cb);
            s.mul(s).scale(-self.q).add(a.mul(a).scale(-self.r))
        })
    }

    /// The pieces of `[l0, l1]` after one step, `s' = clip(A s + B a_c)`: split where the
    /// unclipped next state crosses a state bound, clipped pieces constant.
    fn next_pieces(
        &self,
        pc: &Piece,
        (ca, cb): (Dual, Dual),
        (l0, l1): (f64, f64),
        next: &mut Vec<Piece>,
    ) {
        let ya = pc.alpha.scale(self.a).add(ca.scale(self.b));
        let yb = pc.beta.scale(self.a).add(cb.scale(self.b));
        for (m0, m1) in split(l0, l1, ya.x, yb.x, &[self.s_lo, self.s_hi]) {
            let y_mid = ya.x * 0.5 * (m0 + m1) + yb.x;
            let (alpha, beta) = if y_mid <= self.s_lo {
                (Dual::c(0.0), Dual::c(self.s_lo))
            } else if y_mid >= self.s_hi {
                (Dual::c(0.0), Dual::c(self.s_hi))
            } else {
                (ya, yb)
            };
            next.push(Piece {
                lo: m0,
                hi: m1,
                alpha,
                beta,
            });
        }
    }
}

/// The backward recursion of the stochastic policy (module documentation) on the `V` grid.
struct Recursion<'a> {
    op: &'a SpanOp,
    noise: Option<&'a SpanOp>,
    rew: &'a [[f64; 5]],
    nodes: &'a [f64],
    sigma: f64,
    gamma: f64,
    horizon: usize,
}

impl Recursion<'_> {
    /// Runs `horizon` steps and returns the channels `[V, ∂_v V, ∂_w V, ∂²_wv V, ∂²_vv V,
    /// ∂²_ww V]` at the nodes (empty when not propagated). `KX`, `KV`, `KW`: powers of `z`
    /// integrated against `V`, `∂_v V`, `∂_w V`; `K2`: second-order channels propagated
    /// (`∂²_wv`, then `∂²_vv`, `∂²_ww`).
    fn run<const KX: usize, const KV: usize, const KW: usize, const K2: usize>(
        &self,
    ) -> [Vec<f64>; 6] {
        let n = self.nodes.len();
        let sized = |on: bool| vec![0.0; if on { n } else { 0 }];
        let mut cur: [Vec<f64>; 6] = [
            sized(true),
            sized(KV > 0),
            sized(KW > 0),
            sized(K2 > 0),
            sized(K2 > 1),
            sized(K2 > 2),
        ];
        let mut next = cur.clone();
        let mut smooth: [Vec<f64>; 6] = match self.noise {
            Some(nop) => {
                std::array::from_fn(|c| vec![0.0; if cur[c].is_empty() { 0 } else { nop.rows() }])
            }
            None => Default::default(),
        };
        let (g, sigma) = (self.gamma, self.sigma);
        for _ in 0..self.horizon {
            if crate::cancel::requested() {
                break;
            }
            if let Some(nop) = self.noise {
                for (out, x) in smooth.iter_mut().zip(&cur) {
                    if !x.is_empty() {
                        nop.apply_k0(x, out);
                    }
                }
            }
            let src = if self.noise.is_some() { &smooth } else { &cur };
            let x2: [&[f64]; K2] = std::array::from_fn(|j| src[3 + j].as_slice());
            for (i, (rw, &s)) in self.rew.iter().zip(self.nodes).enumerate() {
                let (mut sx, mut sv, mut sw, mut s2) = ([0.0; KX], [0.0; KV], [0.0; KW], [0.0; K2]);
                for seg in self.op.row(i) {
                    seg_sums(
                        self.op, seg, &src[0], &src[1], &src[2], &x2, &mut sx, &mut sv, &mut sw,
                        &mut s2,
                    );
                }
                let eg: [f64; KX] = std::array::from_fn(|k| rw[k] + g * sx[k]);
                next[0][i] = eg[0];
                let so = s / sigma;
                if KV > 0 {
                    next[1][i] = so * eg[1] + g * sv[0];
                }
                if KW > 0 {
                    next[2][i] = eg[2] - eg[0] + g * sw[0];
                }
                if K2 > 0 {
                    next[3][i] =
                        so * (eg[3] - 3.0 * eg[1]) + g * (so * sw[1] + sv[2] - sv[0] + s2[0]);
                }
                if K2 > 2 {
                    next[4][i] = so * so * (eg[2] - eg[0]) + g * (2.0 * so * sv[1] + s2[1]);
                    next[5][i] =
                        (eg[4] - 4.0 * eg[2] + eg[0]) + g * (2.0 * (sw[2] - sw[0]) + s2[2]);
                }
            }
            std::mem::swap(&mut cur, &mut next);
        }
        cur
    }
}

/// Adds one run's contributions `Σ_c w_k[c] x[c]` to `sx[k]` (`k < KX`), likewise `sv` for
/// `∂_v V`, `sw` for `∂_w V`, and `Σ_c w_0[c] x2_j[c]` to `s2[j]`; two interleaved partial
/// sums per quantity (a fixed order: deterministic).
#[allow(clippy::too_many_arguments)]
#[inline]
fn seg_sums<const KX: usize, const KV: usize, const KW: usize, const K2: usize>(
    op: &SpanOp,
    seg: &Seg,
    x: &[f64],
    xv: &[f64],
    xw: &[f64],
    x2: &[&[f64]; K2],
    sx: &mut [f64; KX],
    sv: &mut [f64; KV],
    sw: &mut [f64; KW],
    s2: &mut [f64; K2],
) {
    let len = seg.len;
    let w: [&[f64]; KX] = std::array::from_fn(|k| op.weights(seg, k));
    let cols = seg.start..seg.start + len;
    let x = &x[cols.clone()];
    let xv = if KV > 0 { &xv[cols.clone()] } else { &[][..] };
    let xw = if KW > 0 { &xw[cols.clone()] } else { &[][..] };
    let x2: [&[f64]; K2] = std::array::from_fn(|j| &x2[j][cols.clone()]);
    let (mut ax, mut av, mut aw, mut a2) = (
        [[0.0; 2]; KX],
        [[0.0; 2]; KV],
        [[0.0; 2]; KW],
        [[0.0; 2]; K2],
    );
    let mut c = 0;
    while c + 2 <= len {
        for l in 0..2 {
            let cc = c + l;
            for k in 0..KX {
                ax[k][l] += w[k][cc] * x[cc];
            }
            for k in 0..KV {
                av[k][l] += w[k][cc] * xv[cc];
            }
            for k in 0..KW {
                aw[k][l] += w[k][cc] * xw[cc];
            }
            for j in 0..K2 {
                a2[j][l] += w[0][cc] * x2[j][cc];
            }
        }
        c += 2;
    }
    if c < len {
        for k in 0..KX {
            ax[k][0] += w[k][c] * x[c];
        }
        for k in 0..KV {
            av[k][0] += w[k][c] * xv[c];
        }
        for k in 0..KW {
            aw[k][0] += w[k][c] * xw[c];
        }
        for j in 0..K2 {
            a2[j][0] += w[0][c] * x2[j][c];
        }
    }
    for (s, a) in sx.iter_mut().zip(&ax) {
        *s += a[0] + a[1];
    }
    for (s, a) in sv.iter_mut().zip(&av) {
        *s += a[0] + a[1];
    }
    for (s, a) in sw.iter_mut().zip(&aw) {
        *s += a[0] + a[1];
    }
    for (s, a) in s2.iter_mut().zip(&a2) {
        *s += a[0] + a[1];
    }
}

/// Sub-intervals of `[lo, hi]` separated by the points where `α x + β` crosses a level.
fn split(lo: f64, hi: f64, alpha: f64, beta: f64, levels: &[f64]) -> Vec<(f64, f64)> {
    let mut cuts = vec![lo, hi];
    if alpha != 0.0 {
        for &k in levels {
            let x = (k - beta) / alpha;
            if x > lo && x < hi {
                cuts.push(x);
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.windows(2)
        .filter(|w| w[1] > w[0] || lo == hi)
        .map(|w| (w[0], w[1]))
        .collect()
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
