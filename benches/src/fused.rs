//! Fused-loop references: the rollouts and G(PO)MDP sums of `sepg_mdp::monte_carlo::
//! stream_gradients`, written as one plain loop per trajectory with every constant in a local
//! variable, no traits, no sinks, no work items. They draw from the same per-trajectory streams
//! (`SeedKey::rngs(i)`, the reproducibility contract of every rollout) and do the same
//! floating-point operations per step, so each trajectory's samples equal the engine's bit for
//! bit; only the bookkeeping around them differs. Their throughput is what a hand-written
//! program achieves on this machine, the denominator of the ratios reported in
//! docs/PERFORMANCE.md.
//!
//! The sums are reduced with rayon's `fold`/`reduce` (order not fixed: the references need not
//! be reproducible to the last bit).

use rayon::prelude::*;
use sepg_algo::core::config::{Algorithm, CheckedConfig, GradientMode, Requirement};
use sepg_algo::core::error::RunError;
use sepg_algo::core::options::{Accounting, Confidence, VDirection, WDirection, WStep};
use sepg_algo::core::seed::Block;
use sepg_algo::core::state::State;
use sepg_algo::solver::realise::{CoordinateBound, realise};
use sepg_algo::solver::source::{Grad, SurrogateParts};
use sepg_algo::solver::steps::{self, Plan};
use sepg_algo::solver::{proven_widths, width_delta};
use sepg_bounds::constants::{TaskConstants, c as penalty_c, dc_dsigma};
use sepg_estimators::proven::ProvenWidths;
use sepg_estimators::{GradientSpec, Param, student_t_quantile};
use sepg_mdp::env::Preset;
use sepg_mdp::mountain_car::{
    GOAL_POSITION, MAX_POSITION, MAX_SPEED, MIN_POSITION, POWER, TIME_LIMIT,
};
use sepg_mdp::rng::{SeedKey, standard_normal, uniform};
use sepg_mdp::rollout::ScoreAction;

/// Plain sums of the per-trajectory samples `[G, g^v_0 .., g^w]` and of their squares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sums<const C: usize> {
    /// Number of trajectories.
    pub n: u64,
    /// Environment steps.
    pub steps: u64,
    /// `Σ_i x_i` per component.
    pub sum: [f64; C],
    /// `Σ_i x_i²` per component.
    pub sum_sq: [f64; C],
}

impl<const C: usize> Default for Sums<C> {
    fn default() -> Self {
        Sums {
            n: 0,
            steps: 0,
            sum: [0.0; C],
            sum_sq: [0.0; C],
        }
    }
}

impl<const C: usize> Sums<C> {
    fn add(mut self, x: [f64; C], steps: u64) -> Self {
        self.n += 1;
        self.steps += steps;
        for ((s, q), x) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(x) {
            *s += x;
            *q += x * x;
        }
        self
    }

    fn merge(mut self, o: Self) -> Self {
        self.n += o.n;
        self.steps += o.steps;
        for (s, x) in self.sum.iter_mut().zip(o.sum) {
            *s += x;
        }
        for (q, x) in self.sum_sq.iter_mut().zip(o.sum_sq) {
            *q += x;
        }
        self
    }

    /// Sample means.
    pub fn mean(&self) -> [f64; C] {
        self.sum.map(|s| s / self.n as f64)
    }
}

/// `lqg1d` (clipped, noise-free, γ = 0.99): `n` trajectories of `h` steps of the Gaussian
/// policy `a = v s + σ z`, with the G(PO)MDP sums against the per-step baselines `bv`, `bw`
/// (length `h`). Components `[G, g^v, g^w]`. Four trajectories advance in lockstep (plain
/// arrays), so that their independent dependency chains overlap in the CPU.
///
/// # Formula
/// ```text
/// a = v s + σ z,  a_c = clip(a, ±4),  r = −(0.9 s² + 0.9 a_c²),  s ← clip(s + a_c, ±4)
/// S^v += z s / σ,  S^w += z² − 1,  g^v += S^v (γ^t r − b^v_t),  g^w += S^w (γ^t r − b^w_t)
/// ```
pub fn lqg1d(
    v: f64,
    sigma: f64,
    n: usize,
    h: usize,
    key: SeedKey,
    bv: &[f64],
    bw: &[f64],
) -> Sums<3> {
    let (bv, bw) = (&bv[..h], &bw[..h]);
    (0..n.div_ceil(4))
        .into_par_iter()
        .with_min_len(256)
        .fold(Sums::default, |mut acc, group| {
            let first = group * 4;
            if first + 4 <= n {
                for x in lqg1d_lanes::<4>(v, sigma, first, h, key, bv, bw) {
                    acc = acc.add(x, h as u64);
                }
            } else {
                for i in first..n {
                    let [x] = lqg1d_lanes::<1>(v, sigma, i, h, key, bv, bw);
                    acc = acc.add(x, h as u64);
                }
            }
            acc
        })
        .reduce(Sums::default, Sums::merge)
}

/// Trajectories `first .. first + K` of [`lqg1d`] in lockstep.
#[inline(always)]
fn lqg1d_lanes<const K: usize>(
    v: f64,
    sigma: f64,
    first: usize,
    h: usize,
    key: SeedKey,
    bv: &[f64],
    bw: &[f64],
) -> [[f64; 3]; K] {
    let (a_, b_, q, r, lim, gamma) = (1.0, 1.0, 0.9, 0.9, 4.0, 0.99);
    let inv_sigma = 1.0 / sigma;
    let mut rngs: [_; K] = std::array::from_fn(|k| key.rngs((first + k) as u64));
    let mut s: [f64; K] = std::array::from_fn(|k| uniform(&mut rngs[k].env, -lim, lim));
    let (mut g, mut gv, mut gw, mut cv, mut cw) =
        ([0.0; K], [0.0; K], [0.0; K], [0.0; K], [0.0; K]);
    let mut disc = 1.0;
    let mut z = [0.0; K];
    for t in 0..h {
        for (zk, rng) in z.iter_mut().zip(rngs.iter_mut()) {
            *zk = standard_normal(&mut rng.policy);
        }
        for k in 0..K {
            let (sk, zk) = (s[k], z[k]);
            cv[k] += zk * inv_sigma * sk;
            cw[k] += zk * zk - 1.0;
            let ac = (v * sk + sigma * zk).clamp(-lim, lim);
            let dr = disc * -(sk * (q * sk) + ac * (r * ac));
            gv[k] += cv[k] * (dr - bv[t]);
            gw[k] += cw[k] * (dr - bw[t]);
            g[k] += dr;
            s[k] = (a_ * sk + b_ * ac).clamp(-lim, lim);
        }
        disc *= gamma;
    }
    std::array::from_fn(|k| [g[k], gv[k], gw[k]])
}

/// Mountain Car (gymnasium `MountainCarContinuous-v0` rules, state + bias features, γ =
/// 0.99, time limit 999): `n` trajectories of at most `h` steps with the G(PO)MDP sums against
/// the per-step baselines `bv` (length `3h`, step-major) and `bw` (length `h`), padded after
/// termination (reward 0, scores frozen). Components `[G, g^v_0, g^v_1, g^v_2, g^w]`.
pub fn mountain_car(
    v: [f64; 3],
    sigma: f64,
    n: usize,
    h: usize,
    key: SeedKey,
    bv: &[f64],
    bw: &[f64],
) -> Sums<5> {
    let gamma = 0.99;
    let inv_sigma = 1.0 / sigma;
    let limit = h.min(TIME_LIMIT);
    (0..n)
        .into_par_iter()
        .with_min_len(64)
        .fold(Sums::default, |acc, i| {
            let mut rngs = key.rngs(i as u64);
            let mut pos = uniform(&mut rngs.env, -0.6, -0.4);
            let mut vel = 0.0;
            let (mut disc, mut g) = (1.0, 0.0);
            let (mut cv, mut cw) = ([0.0; 3], 0.0);
            let (mut gv, mut gw) = ([0.0; 3], 0.0);
            let mut len = limit;
            for t in 0..limit {
                let phi = [pos, vel, 1.0];
                let mu = v[0] * phi[0] + v[1] * phi[1] + v[2] * phi[2];
                let z = standard_normal(&mut rngs.policy);
                let c = z * inv_sigma;
                for k in 0..3 {
                    cv[k] += c * phi[k];
                }
                cw += z * z - 1.0;
                let a = mu + sigma * z;
                let force = a.clamp(-1.0, 1.0);
                vel += force * POWER - 0.0025 * (3.0 * pos).cos();
                vel = vel.clamp(-MAX_SPEED, MAX_SPEED);
                pos += vel;
                pos = pos.clamp(MIN_POSITION, MAX_POSITION);
                if pos == MIN_POSITION && vel < 0.0 {
                    vel = 0.0;
                }
                let done = pos >= GOAL_POSITION && vel >= 0.0;
                let reward = if done { 100.0 } else { 0.0 } - a * a * 0.1;
                let dr = disc * reward;
                for k in 0..3 {
                    gv[k] += cv[k] * (dr - bv[t * 3 + k]);
                }
                gw += cw * (dr - bw[t]);
                g += dr;
                disc *= gamma;
                if done {
                    len = t + 1;
                    break;
                }
            }
            for t in len..h {
                for k in 0..3 {
                    gv[k] += cv[k] * (0.0 - bv[t * 3 + k]);
                }
                gw += cw * (0.0 - bw[t]);
            }
            acc.add([g, gv[0], gv[1], gv[2], gw], len as u64)
        })
        .reduce(Sums::default, Sums::merge)
}

/// Why [`ZvIteration::new`] refused a configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Unsupported(pub String);

/// The whole-iteration reference: one sampled SEPG-ZV iteration on `lqg1d` written as plain
/// loops (rollouts with their G(PO)MDP sums fused into the step loop, the leave-one-out fits
/// of ∇̂_w L as flat loops over local arrays, the surrogate's delta-method samples inline),
/// followed by the same certified steps as the engine (`sepg_algo::solver::steps`,
/// `sepg_algo::solver::realise`: a handful of scalar bound evaluations, not a loop to fuse).
///
/// It supports the configuration of the `algo` bench and of `zv_iterations`: the `lqg1d`
/// preset, SEPG-ZV, the certified accounting, raw scores, the greedy v-direction, the default
/// G(PO)MDP estimator (optimal baseline fitted leave-one-out) and either proven widths
/// (`Confidence::SubGaussian`, the default: ∇̂_v J and ∇̂_w J are then G(PO)MDP with the
/// constant baseline of the proven widths, summed inside the step loop) or Student-t widths
/// (`Confidence::StudentT`, `Confidence::None`: every gradient with the leave-one-out fit). Its state after an iteration is the engine's bit for bit
/// (`the_iteration_reference_computes_what_the_engine_computes`). The certified accounting
/// runs no reference batch, so every iteration, the first included, is one of these.
#[derive(Debug, Clone)]
pub struct ZvIteration {
    k: TaskConstants,
    widths: ProvenWidths,
    /// δ of every width (the run's schedule applied).
    level: f64,
    /// The Student-t factor of the widths (∇̂_w L's only, with proven widths).
    factor: f64,
    /// Proven widths: ∇̂_v J and ∇̂_w J with the constant baseline of `widths`.
    proven: bool,
    /// Block sizes (v, target, w).
    sizes: [usize; 3],
    h: usize,
    seed: u64,
    certify: bool,
    w_direction: WDirection,
    w_step: WStep,
    /// The w-block's cumulative scores and discounted rewards, `n × h` row-major.
    sv: Vec<f64>,
    sw: Vec<f64>,
    dr: Vec<f64>,
    /// The target block's returns.
    returns: Vec<f64>,
    /// The buffers of the leave-one-out fits.
    loo: Loo,
    /// Per-trajectory samples of ∇̂_v J, ∂̂_σ ∇_v J and ∇̂_w L (w-block).
    g: Vec<f64>,
    d: Vec<f64>,
    z: Vec<f64>,
    /// Student-t factors `t(1 − δ/2, n − 1)/√n` of the sizes seen.
    t_scales: Vec<(usize, f64)>,
}

/// The estimates of one [`ZvIteration::iterate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Estimates {
    /// Ĵ(vᵗ, wᵗ), Ĵ of the deterministic target, Ĵ(vᵗ⁺¹, wᵗ) (the record's `j_exploratory`,
    /// `j_target`, `j_after_v`).
    pub j: [f64; 3],
    /// ∇̂_v J of the v-block with its half-width.
    pub grad_v: Grad,
    /// ∇̂_w J of the w-block with its half-width.
    pub grad_wj: Grad,
    /// ∇̂_w L of the w-block with its half-width.
    pub grad_wl: Grad,
}

/// lqg1d's dynamics: `(A, B, Q, R, clip, γ)`.
const LQG1D: (f64, f64, f64, f64, f64, f64) = (1.0, 1.0, 0.9, 0.9, 4.0, 0.99);

impl ZvIteration {
    /// The reference of the sampled SEPG-ZV iterations of `config`.
    ///
    /// # Errors
    /// [`Unsupported`] for any configuration outside the one described on [`ZvIteration`].
    pub fn new(config: &CheckedConfig) -> Result<Self, Unsupported> {
        let cfg = config.config();
        let o = &cfg.options;
        let no = |what: &str| Err(Unsupported(what.to_string()));
        if cfg.env != Preset::Lqg1d.build() {
            return no("the environment is not the lqg1d preset");
        }
        if cfg.algorithm != Algorithm::Sepg(Requirement::Zv) {
            return no("the algorithm is not SEPG-ZV");
        }
        let GradientMode::Sampled { delta } = cfg.gradient else {
            return no("the gradients are not sampled");
        };
        if o.accounting != Accounting::Certified
            || matches!(o.confidence, Confidence::StudentT { factor } if factor < 0.0)
            || o.v_direction != VDirection::Greedy
            || cfg.score_action != ScoreAction::Raw
            || cfg.estimator != GradientSpec::default()
        {
            return no("the options are not those of the reference");
        }
        let n = cfg.n_trajectories;
        // The engine's split: n / 3 each, the remainder to the first blocks.
        let sizes: [usize; 3] = std::array::from_fn(|b| n / 3 + usize::from(b < n % 3));
        if sizes[2] < 4 {
            return no("fewer than 4 trajectories in the w-block");
        }
        let widths = proven_widths(config).map_err(|e| Unsupported(e.to_string()))?;
        Ok(ZvIteration {
            k: *config.constants(),
            widths,
            level: width_delta(config, delta),
            factor: o.confidence.factor(),
            proven: o.confidence == Confidence::SubGaussian,
            sizes,
            h: cfg.horizon,
            seed: cfg.seed,
            certify: config.certified(),
            w_direction: o.w_direction,
            w_step: o.w_step,
            sv: Vec::new(),
            sw: Vec::new(),
            dr: Vec::new(),
            returns: Vec::new(),
            loo: Loo::default(),
            g: Vec::new(),
            d: Vec::new(),
            z: Vec::new(),
            t_scales: Vec::new(),
        })
    }

    /// Runs iteration `state.iteration` and updates `state` as the engine does; returns the
    /// iteration's estimates.
    ///
    /// # Errors
    /// The engine's errors of the steps; a state with other than one v and one w.
    pub fn iterate(&mut self, state: &mut State) -> Result<Estimates, RunError> {
        if state.v.len() != 1 || state.w.len() != 1 {
            return Err(RunError::Estimator(
                "the reference needs one mean parameter and one log σ".into(),
            ));
        }
        let t = state.iteration;
        let (k, certify, h) = (&self.k.clone(), self.certify, self.h);
        let [n_v, n_t, n_w] = self.sizes;
        let (v, w) = (state.v[0], state.w[0]);
        let sigma = w.exp();
        let b = self.widths.baseline();
        let be = |e: sepg_bounds::BoundsError| RunError::Bounds(e.to_string());
        let ee = |e: sepg_estimators::EstimatorError| RunError::Estimator(e.to_string());

        // v-block: Ĵ and ∇̂_v J (with the constant baseline: summed inside the step loop).
        let key = Block::V.key(self.seed, t);
        let (j_v, gv) = self.block((v, sigma, b), n_v, key, Param::V);
        let grad_v = if self.proven {
            Grad {
                value: vec![mean(&gv)],
                eps: vec![self.widths.v_width(sigma, n_v, self.level).map_err(ee)?],
            }
        } else {
            self.fitted(Param::V, n_v)?
        };
        let b0 = state.budget;
        let required_v = -b0;
        let v_plan = steps::v_step(k, sigma, &grad_v, required_v, certify)?;
        let mut v_new = state.v.clone();
        let eps_v = grad_v.eps[0];
        let (g_v, alpha) = apply(&mut v_new, &v_plan, required_v, certify, || {
            CoordinateBound::mean(k, sigma, grad_v.value[0], eps_v).map_err(be)
        })?;
        let b1 = add_down(b0, g_v);

        // Target block: the deterministic policy's returns.
        let key = Block::Target.key(self.seed, t);
        deterministic_returns(v, n_t, h, key, &mut self.returns);
        let j_target = self.returns.iter().sum::<f64>() / n_t as f64;

        // w-block at (vᵗ⁺¹, wᵗ): Ĵ and ∇̂_w J fused as above, the rows kept for ∇̂_w L.
        let required_w = -b1;
        let key = Block::W.key(self.seed, t);
        let v1 = v_new[0];
        let (j_w, gw) = self.block((v1, sigma, b), n_w, key, Param::W);
        let grad_wj = if self.proven {
            Grad {
                value: vec![mean(&gw)],
                eps: vec![self.widths.w_width(n_w, self.level).map_err(ee)?],
            }
        } else {
            self.fitted(Param::W, n_w)?
        };
        let (grad_wl, parts) = self.surrogate(sigma, n_w)?;
        let sigmas = [sigma];
        let gl = steps::w_direction(
            k,
            &sigmas,
            self.w_direction,
            &grad_wl,
            Some(&parts),
            &grad_wj,
            alpha,
        )?;
        let w_plan =
            steps::w_step_surrogate(k, &sigmas, &gl, &grad_wj, required_w, certify, self.w_step)?;
        let mut w_new = state.w.clone();
        let (gj, ej) = (grad_wj.value[0], grad_wj.eps[0]);
        let (g_w, _) = apply(&mut w_new, &w_plan, required_w, certify, || {
            CoordinateBound::log_sigma(k, sigma, gj, ej).map_err(be)
        })?;
        let b2 = add_down(b1, g_w);

        let steps = (n_v + n_t + n_w) * h;
        state.iteration += 1;
        state.v = v_new;
        state.w = w_new;
        state.budget = b2;
        state.trajectories += (n_v + n_t + n_w) as u64;
        state.steps += steps as u64;
        state.last_alpha = Some(alpha);
        Ok(Estimates {
            j: [j_v, j_target, j_w],
            grad_v,
            grad_wj,
            grad_wl,
        })
    }

    /// The scored rollouts of one block at (`v`, σ) with constant baseline `b`: its Ĵ and the
    /// G(PO)MDP samples of `param` against `b` (those of the proven widths); the rows are kept
    /// for the fits when they are needed (the w-block's ∇̂_w L; every gradient without proven
    /// widths).
    fn block(
        &mut self,
        pol: (f64, f64, f64),
        n: usize,
        key: SeedKey,
        param: Param,
    ) -> (f64, Vec<f64>) {
        let h = self.h;
        let (mut j_sum, mut x) = (0.0, Vec::with_capacity(n));
        let mut done = |[ret, gv, gw]: [f64; 3]| {
            j_sum += ret;
            x.push(if param == Param::V { gv } else { gw });
        };
        if param == Param::V && self.proven {
            let none = [&mut [][..], &mut [][..], &mut [][..]];
            scored::<false>(pol, n, h, key, none, &mut done);
        } else {
            for buf in [&mut self.sv, &mut self.sw, &mut self.dr] {
                if buf.len() < n * h {
                    buf.resize(n * h, 0.0);
                }
            }
            let rows = [
                &mut self.sv[..n * h],
                &mut self.sw[..n * h],
                &mut self.dr[..n * h],
            ];
            scored::<true>(pol, n, h, key, rows, &mut done);
        }
        (j_sum * (1.0 / n as f64), x)
    }

    /// ∇̂ of `param` (G(PO)MDP, optimal baseline fitted leave-one-out) from the kept rows of
    /// `n` trajectories, with its Student-t width.
    fn fitted(&mut self, param: Param, n: usize) -> Result<Grad, RunError> {
        let h = self.h;
        let s = if param == Param::V {
            &self.sv
        } else {
            &self.sw
        };
        let (s, dr) = (&s[..n * h], &self.dr[..n * h]);
        self.g.resize(n, 0.0);
        self.loo.run(
            [s, dr],
            h,
            |[s, f]| score_term(s, f),
            |[s, f], b| s * (f - b),
            &mut self.g[..n],
        );
        let m = mean(&self.g[..n]);
        let var = variance(&self.g[..n], m);
        let scale = self.t_scale(n)?;
        Ok(Grad {
            value: vec![m],
            eps: vec![scale * var.sqrt()],
        })
    }

    /// ∇̂_w L (cross-fitted halves, delta-method samples, Student-t widths) and its parts
    /// from the w-block's rows of `n` trajectories.
    fn surrogate(&mut self, sigma: f64, n: usize) -> Result<(Grad, SurrogateParts), RunError> {
        let h = self.h;
        let be = |e: sepg_bounds::BoundsError| RunError::Bounds(e.to_string());
        let c = penalty_c(&self.k, sigma).map_err(be)?;
        let dc = dc_dsigma(&self.k, sigma).map_err(be)?;
        let half = n / 2;
        self.g.resize(n, 0.0);
        self.d.resize(n, 0.0);
        for (lo, hi) in [(0, half), (half, n)] {
            let (sv, sw, dr) = (
                &self.sv[lo * h..hi * h],
                &self.sw[lo * h..hi * h],
                &self.dr[lo * h..hi * h],
            );
            let fit = &mut self.loo;
            // ∇̂_v J, optimal baseline: terms (S² F, S²), sample S (F − b).
            fit.run(
                [sv, dr],
                h,
                |[s, f]| score_term(s, f),
                |[s, f], b| s * (f - b),
                &mut self.g[lo..hi],
            );
            // ĥ with the baseline of Appendix B.2: u = G H F, z = G + H, H = S^w/σ.
            let uz = |[g, w, f]: [f64; 3]| {
                let hj = w / sigma;
                (g * hj * f, g + hj)
            };
            fit.run(
                [sv, sw, dr],
                h,
                |x| {
                    let (u, z) = uz(x);
                    (u * z, z * z)
                },
                |x, b| {
                    let (u, z) = uz(x);
                    u - b * z
                },
                &mut self.d[lo..hi],
            );
        }
        let two_over = 2.0 / sigma;
        for (d, g) in self.d.iter_mut().zip(&self.g) {
            *d -= two_over * g;
        }
        let (g_bar, d_bar) = (mean(&self.g), mean(&self.d));
        let half_mean = |x: &[f64]| x.iter().fold(0.0, |m, x| m + x) / x.len() as f64;
        let (ga, gb) = (half_mean(&self.g[..half]), half_mean(&self.g[half..]));
        let (da, db) = (half_mean(&self.d[..half]), half_mean(&self.d[half..]));
        let dot = |a: f64, b: f64| [a].iter().zip(&[b]).map(|(x, y)| x * y).sum::<f64>();
        let g_ab = dot(ga, gb);
        let scale = sigma / (4.0 * 1.0 * c);
        let f = scale * (dot(ga, db) + dot(gb, da) - g_ab * dc / c);
        let ratio = dc / c;
        let dg = 2.0 * d_bar - 2.0 * g_bar * ratio;
        self.z.clear();
        for (gi, di) in self.g.iter().zip(&self.d) {
            let lin = 0.0 + (dg * (gi - g_bar) + 2.0 * g_bar * (di - d_bar));
            self.z.push(f + scale * lin);
        }
        let centre = mean(&self.z);
        let var = variance(&self.z, centre);
        let t_scale = self.t_scale(n)?;
        let grad_wl = Grad {
            value: vec![f],
            eps: vec![t_scale * var.sqrt()],
        };
        let parts = SurrogateParts {
            grad_v: vec![g_bar],
            mixed_sigma: vec![d_bar],
        };
        Ok((grad_wl, parts))
    }

    /// `factor · t(1 − δ/2, n − 1)/√n`, memoised per `n`.
    fn t_scale(&mut self, n: usize) -> Result<f64, RunError> {
        if self.factor == 0.0 {
            return Ok(0.0);
        }
        if let Some(&(_, s)) = self.t_scales.iter().find(|(m, _)| *m == n) {
            return Ok(s);
        }
        let nf = n as f64;
        let t = student_t_quantile(1.0 - 0.5 * self.level, nf - 1.0)
            .map_err(|e| RunError::Estimator(e.to_string()))?;
        let s = self.factor * t / nf.sqrt();
        self.t_scales.push((n, s));
        Ok(s)
    }
}

/// The leave-one-out fit of one estimator on `rows` trajectories of `h` steps: the baseline
/// of trajectory `r` at step `t` is `Σ_{i≠r} num / Σ_{i≠r} den`, summed as prefix + suffix
/// (the exact sum over the others), and `out[r] = Σ_t sample(r, t; b)`.
#[derive(Debug, Clone, Default)]
struct Loo {
    /// Suffix sums over trajectories, `(rows + 1) × h`.
    suf_n: Vec<f64>,
    suf_d: Vec<f64>,
    /// Prefix sums over trajectories, `h`.
    pre_n: Vec<f64>,
    pre_d: Vec<f64>,
}

impl Loo {
    /// The fit on the rows of `inputs` (`out.len()` rows of `h` entries each): `term` gives
    /// an entry's `(num, den)`, `sample` its sample term with the baseline.
    #[inline(always)]
    fn run<const K: usize>(
        &mut self,
        inputs: [&[f64]; K],
        h: usize,
        term: impl Fn([f64; K]) -> (f64, f64),
        sample: impl Fn([f64; K], f64) -> f64,
        out: &mut [f64],
    ) {
        let rows = out.len();
        let used = (rows + 1) * h;
        for buf in [&mut self.suf_n, &mut self.suf_d] {
            if buf.len() < used {
                buf.resize(used, 0.0);
            }
            buf[rows * h..used].fill(0.0);
        }
        let row = |r: usize| -> [&[f64]; K] { std::array::from_fn(|k| &inputs[k][r * h..][..h]) };
        for r in (0..rows).rev() {
            let x = row(r);
            let (sn, sn_next) = self.suf_n[r * h..(r + 2) * h].split_at_mut(h);
            let (sd, sd_next) = self.suf_d[r * h..(r + 2) * h].split_at_mut(h);
            for t in 0..h {
                let (n, d) = term(std::array::from_fn(|k| x[k][t]));
                sn[t] = sn_next[t] + n;
                sd[t] = sd_next[t] + d;
            }
        }
        for buf in [&mut self.pre_n, &mut self.pre_d] {
            buf.clear();
            buf.resize(h, 0.0);
        }
        let (pre_n, pre_d) = (&mut self.pre_n[..h], &mut self.pre_d[..h]);
        for (r, x_out) in out.iter_mut().enumerate() {
            let x = row(r);
            let (on, od) = (
                &self.suf_n[(r + 1) * h..][..h],
                &self.suf_d[(r + 1) * h..][..h],
            );
            let mut acc = 0.0;
            for t in 0..h {
                let v = std::array::from_fn(|k| x[k][t]);
                let num = pre_n[t] + on[t];
                let den = pre_d[t] + od[t];
                let q = num / den;
                let b = if den > 0.0 { q } else { 0.0 };
                let (n, d) = term(v);
                pre_n[t] += n;
                pre_d[t] += d;
                acc += sample(v, b);
            }
            *x_out = acc;
        }
    }
}

/// The optimal baseline's terms `(S² F, S²)` of one entry.
#[inline(always)]
fn score_term(s: f64, f: f64) -> (f64, f64) {
    let s2 = s * s;
    (s2 * f, s2)
}

/// `Σ x · (1/n)`, summed from 0 in order.
fn mean(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, x| m + x) * (1.0 / x.len() as f64)
}

/// `Σ (x − c)² / (n − 1)`, summed from 0 in order.
fn variance(x: &[f64], c: f64) -> f64 {
    x.iter().fold(0.0, |v, x| v + (x - c) * (x - c)) * (1.0 / (x.len() as f64 - 1.0))
}

/// `a + g` rounded down (the error term of TwoSum decides).
fn add_down(a: f64, g: f64) -> f64 {
    let s = a + g;
    let bb = s - a;
    let err = (a - (s - bb)) + (g - bb);
    if err < 0.0 { s.next_down() } else { s }
}

/// Applies `plan` to `x`, certified again at the realised change when `certify`; returns
/// the guaranteed improvement and the realised step size (0 for no change).
fn apply(
    x: &mut [f64],
    plan: &Plan,
    required: f64,
    certify: bool,
    bound: impl FnOnce() -> Result<CoordinateBound, RunError>,
) -> Result<(f64, f64), RunError> {
    let Plan::Update(s) = plan else {
        return Ok((0.0, 0.0));
    };
    if !certify {
        x[s.index] += s.delta;
        return Ok((s.guaranteed, s.size));
    }
    let b = bound()?;
    let x0 = x[s.index];
    let r = realise(x0, s.delta, &b, required, s.certified == Some(true));
    x[s.index] = r.value;
    let size = if s.delta == 0.0 {
        0.0
    } else {
        s.size * ((r.value - x0) / s.delta)
    };
    Ok((r.guaranteed, size))
}

/// `n` scored `lqg1d` trajectories of `h` steps of `a = v s + σ z` drawn from `key`, four in
/// lockstep. With `KEEP`, `S^v_t`, `S^w_t` and `γ^t r_t` of trajectory `i` are written to
/// `rows[0..3][i · h + t]` (the rows of a batch). Returns, per trajectory, its discounted
/// return `G` (summed from −0 in the order of `t`) and its G(PO)MDP samples
/// `Σ_t S^v_t (γ^t r_t − γ^t b)`, `Σ_t S^w_t (γ^t r_t − γ^t b)` for the constant baseline
/// `b` (summed from 0), through `done(G, g^v, g^w)`.
#[allow(clippy::too_many_arguments)]
fn scored<const KEEP: bool>(
    (v, sigma, b): (f64, f64, f64),
    n: usize,
    h: usize,
    key: SeedKey,
    rows: [&mut [f64]; 3],
    mut done: impl FnMut([f64; 3]),
) {
    let [sv, sw, dr] = rows;
    let mut first = 0;
    while first < n {
        let k = if first + 4 <= n { 4 } else { 1 };
        let span = if KEEP {
            first * h..(first + k) * h
        } else {
            0..0
        };
        let out = [&mut sv[span.clone()], &mut sw[span.clone()], &mut dr[span]];
        if k == 4 {
            scored_lanes::<4, KEEP>((v, sigma, b), first, h, key, out)
                .into_iter()
                .for_each(&mut done);
        } else {
            let [x] = scored_lanes::<1, KEEP>((v, sigma, b), first, h, key, out);
            done(x);
        }
        first += k;
    }
}

/// Trajectories `first .. first + K` of [`scored`] in lockstep (`rows`: their `K · h`
/// entries).
#[inline(always)]
fn scored_lanes<const K: usize, const KEEP: bool>(
    (v, sigma, b): (f64, f64, f64),
    first: usize,
    h: usize,
    key: SeedKey,
    rows: [&mut [f64]; 3],
) -> [[f64; 3]; K] {
    let (a_, b_, q, r, lim, gamma) = LQG1D;
    let [sv, sw, rw] = rows;
    let inv_sigma = 1.0 / sigma;
    let mut rngs: [_; K] = std::array::from_fn(|k| key.rngs((first + k) as u64));
    let mut s: [f64; K] = std::array::from_fn(|k| uniform(&mut rngs[k].env, -lim, lim));
    let (mut g, mut gv, mut gw) = ([-0.0; K], [0.0; K], [0.0; K]);
    let (mut cv, mut cw) = ([0.0; K], [0.0; K]);
    let mut disc = 1.0;
    let mut z = [0.0; K];
    for t in 0..h {
        for (zk, rng) in z.iter_mut().zip(rngs.iter_mut()) {
            *zk = standard_normal(&mut rng.policy);
        }
        let db = disc * b;
        for k in 0..K {
            let (sk, zk) = (s[k], z[k]);
            cv[k] += zk * inv_sigma * sk;
            cw[k] += zk * zk - 1.0;
            let ac = clip(v * sk + sigma * zk, -lim, lim);
            let dr = disc * -(sk * (q * sk) + ac * (r * ac));
            let f = dr - db;
            gv[k] += cv[k] * f;
            gw[k] += cw[k] * f;
            g[k] += dr;
            if KEEP {
                sv[k * h + t] = cv[k];
                sw[k * h + t] = cw[k];
                rw[k * h + t] = dr;
            }
            s[k] = clip(a_ * sk + b_ * ac, -lim, lim);
        }
        disc *= gamma;
    }
    std::array::from_fn(|k| [g[k], gv[k], gw[k]])
}

/// The discounted returns of `n` `lqg1d` trajectories of `h` steps of the deterministic
/// policy `a = v s` drawn from `key` (summed from 0 in the order of `t`), four in lockstep.
fn deterministic_returns(v: f64, n: usize, h: usize, key: SeedKey, out: &mut Vec<f64>) {
    out.clear();
    let mut first = 0;
    while first < n {
        if first + 4 <= n {
            out.extend(deterministic_lanes::<4>(v, first, h, key));
            first += 4;
        } else {
            out.extend(deterministic_lanes::<1>(v, first, h, key));
            first += 1;
        }
    }
}

/// Trajectories `first .. first + K` of [`deterministic_returns`] in lockstep.
#[inline(always)]
fn deterministic_lanes<const K: usize>(v: f64, first: usize, h: usize, key: SeedKey) -> [f64; K] {
    let (a_, b_, q, r, lim, gamma) = LQG1D;
    let mut s: [f64; K] = std::array::from_fn(|k| {
        let mut rngs = key.rngs((first + k) as u64);
        uniform(&mut rngs.env, -lim, lim)
    });
    let (mut ret, mut disc) = ([0.0; K], 1.0);
    for _ in 0..h {
        for k in 0..K {
            let sk = s[k];
            let ac = clip(v * sk, -lim, lim);
            ret[k] += disc * -(sk * (q * sk) + ac * (r * ac));
            s[k] = clip(a_ * sk + b_ * ac, -lim, lim);
        }
        disc *= gamma;
    }
    ret
}

/// `x` clipped to `[lo, hi]` (`lo ≤ hi`), as the engine's kernels clip.
#[inline(always)]
fn clip(x: f64, lo: f64, hi: f64) -> f64 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sepg_mdp::monte_carlo::{Moments, stream_gradients};
    use sepg_mdp::policy::GaussianPolicy;
    use sepg_mdp::{LqgEnv, MountainCar};

    /// Means of the engine (no baseline) and of a reference agree to rounding: the per-
    /// trajectory samples are the same bits, only the order of the final sums differs.
    fn assert_same<const C: usize>(engine: &[Moments], reference: Sums<C>, steps: u64) {
        assert_eq!(reference.steps, steps);
        for (m, r) in engine.iter().zip(reference.mean()) {
            assert_eq!(m.count(), reference.n);
            assert!(
                (m.mean() - r).abs() <= 1e-12 * r.abs().max(1.0),
                "{} vs {r}",
                m.mean()
            );
        }
    }

    #[test]
    fn references_compute_what_the_engine_computes() {
        let key = SeedKey::new(3, 1, 0);
        let (n, h) = (1001, 20);
        let pi = GaussianPolicy::scalar(-0.3, 0.5f64.ln()).unwrap();
        let g = stream_gradients(&LqgEnv::lqg1d(), &pi, n, h, key, 0).unwrap();
        let r = lqg1d(-0.3, 0.5, n, h, key, &[0.0; 20], &[0.0; 20]);
        assert_same(&[g.j, g.grad_v[0], g.grad_w[0]], r, g.steps);

        // Energy pumping reaches the goal within the horizon: terminations and padding.
        let (n, h) = (300, 400);
        let v = [0.0, 100.0, 0.0];
        let pi = GaussianPolicy::new(v.to_vec(), vec![-3.0], 3).unwrap();
        let g = stream_gradients(&MountainCar::state_bias(), &pi, n, h, key, 0).unwrap();
        let r = mountain_car(v, (-3.0f64).exp(), n, h, key, &[0.0; 1200], &[0.0; 400]);
        let engine = [g.j, g.grad_v[0], g.grad_v[1], g.grad_v[2], g.grad_w[0]];
        assert!(g.steps < (n * h) as u64);
        assert_same(&engine, r, g.steps);
    }

    /// The whole-iteration reference follows the engine bit for bit: the parameters, budget
    /// and counters after each iteration and the three Ĵ of its record, for the three
    /// confidence options, two seeds and block sizes with and without partial lane groups.
    /// With the proven widths of the default no step moves in the first 40 iterations (the
    /// widths exceed the gradients at N = 100); with Student-t widths, and with none, v and w
    /// move, so the certified steps and their realisation are compared too.
    #[test]
    fn the_iteration_reference_computes_what_the_engine_computes() {
        use sepg_algo::core::config::SepgConfig;
        use sepg_algo::core::executor::Solver;
        use sepg_algo::solver::PolicySolver;
        use sepg_algo::solver::sampled::BlockEstimator;
        use sepg_algo::solver::source::Need;
        use sepg_mdp::rollout::rollout;
        let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let student = Confidence::StudentT { factor: 1.0 };
        let cases = [
            (1, 100, Confidence::SubGaussian, false),
            (7, 60, Confidence::SubGaussian, false),
            (1, 100, student, true),
            (3, 62, student, true),
            (1, 100, Confidence::None, true),
        ];
        for (seed, n, confidence, moves) in cases {
            let mut cfg = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv));
            cfg.seed = seed;
            cfg.n_trajectories = n;
            cfg.options.confidence = confidence;
            let checked = cfg.check().expect("configuration");
            let mut solver = PolicySolver::new(&checked).expect("solver");
            let mut state = checked.initial_state();
            let mut fused = ZvIteration::new(&checked).expect("supported");
            let level = width_delta(&checked, 0.2);
            assert_eq!(
                checked.config().gradient,
                GradientMode::Sampled { delta: 0.2 }
            );
            let spec = checked.config().estimator;
            let mut engine = BlockEstimator::new(level, spec, *checked.constants())
                .with_confidence_factor(confidence.factor());
            if confidence == Confidence::SubGaussian {
                engine = engine.with_proven_widths(proven_widths(&checked).unwrap(), level);
            }
            let need_v = Need {
                grad_v: true,
                ..Need::default()
            };
            let need_w = Need {
                grad_wj: true,
                grad_wl: true,
                ..Need::default()
            };
            let mut mirror = state.clone();
            let (mut v_moves, mut w_moves) = (0, 0);
            for _ in 0..40 {
                let before = state.clone();
                let record = solver.next_iter(&mut state).expect("iteration");
                let e = fused.iterate(&mut mirror).expect("reference iteration");
                // The gradients, recomputed by the estimators of the engine from batches of
                // the same streams (their values decide the steps even when none moves).
                let (t, sigma) = (before.iteration, before.sigma());
                let mut estimate = |block: Block, v: &[f64], n, need| {
                    let pi = GaussianPolicy::new(v.to_vec(), before.w.clone(), 1).unwrap();
                    let key = block.key(seed, t);
                    let batch = rollout(&LqgEnv::lqg1d(), &pi, n, 20, key).unwrap();
                    assert_eq!(batch.sigma, sigma);
                    engine.estimate(&batch, need).expect("estimate")
                };
                let sizes = [n.div_ceil(3), n / 3];
                let ev = estimate(Block::V, &before.v, sizes[0], need_v);
                let ew = estimate(Block::W, &state.v, sizes[1], need_w);
                let grad = |g: &Grad| (bits(&g.value), bits(&g.eps));
                assert_eq!(grad(&e.grad_v), grad(ev.grad_v.as_ref().unwrap()));
                assert_eq!(grad(&e.grad_wj), grad(ew.grad_wj.as_ref().unwrap()));
                assert_eq!(grad(&e.grad_wl), grad(ew.grad_wl.as_ref().unwrap()));
                let j = e.j;
                assert_eq!(bits(&mirror.v), bits(&state.v));
                assert_eq!(bits(&mirror.w), bits(&state.w));
                assert_eq!(mirror.budget.to_bits(), state.budget.to_bits());
                let counters = |s: &State| (s.iteration, s.trajectories, s.steps);
                assert_eq!(counters(&mirror), counters(&state));
                assert_eq!(
                    mirror.last_alpha.map(f64::to_bits),
                    state.last_alpha.map(f64::to_bits)
                );
                let expected = [
                    record.j_exploratory,
                    record.j_target,
                    record.j_after_v.expect("w-block"),
                ];
                assert_eq!(bits(&j), bits(&expected));
                v_moves += usize::from(state.v != before.v);
                w_moves += usize::from(state.w != before.w);
            }
            assert_eq!(
                v_moves > 0 && w_moves > 0,
                moves,
                "{confidence:?}: {v_moves} {w_moves}"
            );
        }
        let mut other = SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Lv));
        other.n_trajectories = 60;
        assert!(ZvIteration::new(&other.check().expect("configuration")).is_err());
    }
}
