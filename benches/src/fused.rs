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
use sepg_mdp::mountain_car::{
    GOAL_POSITION, MAX_POSITION, MAX_SPEED, MIN_POSITION, POWER, TIME_LIMIT,
};
use sepg_mdp::rng::{SeedKey, standard_normal, uniform};

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
}
