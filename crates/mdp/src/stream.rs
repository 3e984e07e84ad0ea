//! Streaming rollouts: for a contiguous range of trajectory indices, the discounted returns,
//! the per-trajectory G(PO)MDP samples against a fixed per-step baseline, or the sums that fit
//! the variance-optimal baseline, computed inside the rollout kernels without storing any
//! trajectory. [`crate::monte_carlo`] reduces them in a fixed order.
//!
//! Trajectory `i` uses the streams `key.rngs(i)`, exactly as in [`crate::rollout`], and the
//! kernels are the same ones; only what happens to each step differs.
//!
//! # Formula
//! ```text
//! G_i     = Σ_t γ^t r_{i,t}
//! g^v_i,k = Σ_{t<H} S^v_{i,t,k} (γ^t r_{i,t} − b^v_{t,k})      (rewards 0, scores frozen after len_i)
//! b^v_t,k = Σ_i (S^v_{i,t,k})² γ^t r_{i,t} / Σ_i (S^v_{i,t,k})²   (0 when the denominator is 0)
//! ```
//! and the same for `w`.

use crate::env::{Environment, ScalarLqg};
use crate::policy::GaussianPolicy;
use crate::rng::{SeedKey, TrajectoryRngs, rngs_from_prefix};
use crate::rollout::{
    FusedPolicy, LANES, LaneSink, NoSteps, RolloutError, ScalarPolicy, ScoreAction, Scratch,
    TrajSink, check, kernel, scalar_kernel,
};

/// A per-step baseline for each v- and w-component: `v[t·dim_v + k]`, `w[t·dim_w + j]`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct StepBaseline {
    v: Vec<f64>,
    w: Vec<f64>,
}

/// The sums that fit the variance-optimal G(PO)MDP baseline (same layout as
/// [`StepBaseline`]): numerators `Σ S² γ^t r_t`, denominators `Σ S²`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BaselineSums {
    num_v: Vec<f64>,
    den_v: Vec<f64>,
    num_w: Vec<f64>,
    den_w: Vec<f64>,
}

impl BaselineSums {
    /// The baseline `num / den` (0 where `den = 0`); `None` if a value is not finite.
    pub(crate) fn baseline(&self) -> Option<StepBaseline> {
        let ratio = |num: &[f64], den: &[f64]| -> Vec<f64> {
            num.iter()
                .zip(den)
                .map(|(n, d)| if *d == 0.0 { 0.0 } else { n / d })
                .collect()
        };
        let b = StepBaseline {
            v: ratio(&self.num_v, &self.den_v),
            w: ratio(&self.num_w, &self.den_w),
        };
        b.v.iter().chain(&b.w).all(|x| x.is_finite()).then_some(b)
    }
}

/// Streaming rollouts of one policy on one environment with one key.
pub(crate) struct Streamer<'a, E: Environment + ?Sized> {
    env: &'a E,
    policy: &'a GaussianPolicy,
    scalar: Option<(ScalarLqg, ScalarPolicy)>,
    fused: Option<FusedPolicy>,
    score: ScoreAction,
    gamma: f64,
    limit: usize,
    horizon: usize,
    prefix: u64,
}

impl<'a, E: Environment + ?Sized> Streamer<'a, E> {
    /// Checks the shapes (as [`crate::rollout::rollout`] does) and prepares the kernels, whose
    /// scores are evaluated at the action chosen by `score`.
    pub(crate) fn new(
        env: &'a E,
        policy: &'a GaussianPolicy,
        horizon: usize,
        key: SeedKey,
        score: ScoreAction,
    ) -> Result<Self, RolloutError> {
        check(env, policy, 1, horizon)?;
        let (sigma, inv_sigma) = policy.sigma_raw();
        let scalar = env.as_scalar_lqg().and_then(|e| e.scalar()).map(|p| {
            let pol = if policy.is_deterministic() {
                ScalarPolicy {
                    v: policy.v()[0],
                    sigma: 0.0,
                    inv_sigma: 0.0,
                    score,
                }
            } else {
                ScalarPolicy {
                    v: policy.v()[0],
                    sigma: sigma[0],
                    inv_sigma: inv_sigma[0],
                    score,
                }
            };
            (*p, pol)
        });
        Ok(Streamer {
            env,
            policy,
            scalar,
            fused: FusedPolicy::of(env, policy, score),
            score,
            gamma: env.gamma(),
            limit: env.time_limit().map_or(horizon, |tl| tl.min(horizon)),
            horizon,
            prefix: key.prefix(),
        })
    }

    /// Work buffers for the generic kernel.
    pub(crate) fn scratch(&self) -> Scratch {
        let e = self.env;
        Scratch::new((e.state_dim(), e.action_dim(), e.feature_dim()))
    }

    /// Number of v-components `dim_v`.
    pub(crate) fn dim_v(&self) -> usize {
        self.policy.dim_v()
    }

    /// Number of w-components `dim_w`.
    pub(crate) fn dim_w(&self) -> usize {
        self.policy.dim_w()
    }

    /// Zero sums for fitting a baseline.
    pub(crate) fn baseline_sums(&self) -> BaselineSums {
        let (v, w) = (self.horizon * self.dim_v(), self.horizon * self.dim_w());
        BaselineSums {
            num_v: vec![0.0; v],
            den_v: vec![0.0; v],
            num_w: vec![0.0; w],
            den_w: vec![0.0; w],
        }
    }

    /// The zero baseline (plain G(PO)MDP).
    pub(crate) fn zero_baseline(&self) -> StepBaseline {
        StepBaseline {
            v: vec![0.0; self.horizon * self.dim_v()],
            w: vec![0.0; self.horizon * self.dim_w()],
        }
    }

    /// The streams of the `K` trajectories from `first`.
    #[inline(always)]
    fn rngs<const K: usize>(&self, first: u64) -> [TrajectoryRngs; K] {
        std::array::from_fn(|k| rngs_from_prefix(self.prefix, first + k as u64))
    }

    /// The discounted returns of trajectories `first, first + 1, …` into `out`; returns the
    /// number of environment steps taken.
    pub(crate) fn returns(&self, first: u64, out: &mut [f64], sc: &mut Scratch) -> u64 {
        match self.scalar {
            Some((p, pol)) if self.policy.is_deterministic() => {
                self.scalar_returns::<false>(&p, pol, first, out)
            }
            Some((p, pol)) => self.scalar_returns::<true>(&p, pol, first, out),
            None => {
                let mut steps = 0;
                for (k, g) in out.iter_mut().enumerate() {
                    let mut rngs = rngs_from_prefix(self.prefix, first + k as u64);
                    let (len, ret) = kernel(
                        self.env,
                        self.policy,
                        self.fused,
                        self.score,
                        self.gamma,
                        self.limit,
                        &mut rngs,
                        &mut NoSteps,
                        sc,
                    );
                    *g = ret;
                    steps += len as u64;
                }
                steps
            }
        }
    }

    fn scalar_returns<const STOCH: bool>(
        &self,
        p: &ScalarLqg,
        pol: ScalarPolicy,
        first: u64,
        out: &mut [f64],
    ) -> u64 {
        let mut groups = out.chunks_exact_mut(LANES);
        let mut index = first;
        for group in &mut groups {
            let mut rngs = self.rngs::<LANES>(index);
            let g = scalar_kernel::<LANES, _, STOCH>(p, pol, self.limit, &mut rngs, &mut NoSteps);
            group.copy_from_slice(&g);
            index += LANES as u64;
        }
        for g in groups.into_remainder() {
            let mut rngs = self.rngs::<1>(index);
            *g = scalar_kernel::<1, _, STOCH>(p, pol, self.limit, &mut rngs, &mut NoSteps)[0];
            index += 1;
        }
        (out.len() * self.limit) as u64
    }

    /// The samples `G_i`, `g^v_i`, `g^w_i` of trajectories `first .. first + count` (stochastic
    /// policy only) against baseline `b`, component-major into `out`
    /// (`out[c · count + i]`, components `[G, v_0 .., w_0 ..]`, length
    /// `(1 + dim_v + dim_w) · count`). Returns the number of environment steps taken.
    pub(crate) fn gpomdp(
        &self,
        first: u64,
        count: usize,
        b: &StepBaseline,
        out: &mut [f64],
        sc: &mut Scratch,
    ) -> u64 {
        let (dv, dw, h) = (self.dim_v(), self.dim_w(), self.horizon);
        let (ret, rest) = out.split_at_mut(count);
        let (gv, gw) = rest.split_at_mut(dv * count);
        if let Some((p, pol)) = self.scalar {
            let mut i = 0;
            while i < count {
                let k = if count - i >= LANES { LANES } else { 1 };
                let index = first + i as u64;
                if k == LANES {
                    self.scalar_gpomdp::<LANES>(
                        &p,
                        pol,
                        index,
                        b,
                        &mut ret[i..i + LANES],
                        &mut gv[i..i + LANES],
                        &mut gw[i..i + LANES],
                    );
                } else {
                    self.scalar_gpomdp::<1>(
                        &p,
                        pol,
                        index,
                        b,
                        &mut ret[i..=i],
                        &mut gv[i..=i],
                        &mut gw[i..=i],
                    );
                }
                i += k;
            }
            return (count * self.limit) as u64;
        }
        let mut acc_v = vec![0.0; dv];
        let mut acc_w = vec![0.0; dw];
        let mut steps = 0;
        for i in 0..count {
            acc_v.fill(0.0);
            acc_w.fill(0.0);
            let mut rngs = rngs_from_prefix(self.prefix, first + i as u64);
            let mut sink = GpomdpTraj {
                bv: &b.v,
                bw: &b.w,
                gv: &mut acc_v,
                gw: &mut acc_w,
            };
            let (len, g) = kernel(
                self.env,
                self.policy,
                self.fused,
                self.score,
                self.gamma,
                self.limit,
                &mut rngs,
                &mut sink,
                sc,
            );
            for t in len..h {
                sink.record(t, 0.0, &sc.cum_v, &sc.cum_w);
            }
            ret[i] = g;
            for (k, a) in acc_v.iter().enumerate() {
                gv[k * count + i] = *a;
            }
            for (j, a) in acc_w.iter().enumerate() {
                gw[j * count + i] = *a;
            }
            steps += len as u64;
        }
        steps
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn scalar_gpomdp<const K: usize>(
        &self,
        p: &ScalarLqg,
        pol: ScalarPolicy,
        first: u64,
        b: &StepBaseline,
        ret: &mut [f64],
        gv: &mut [f64],
        gw: &mut [f64],
    ) {
        let mut rngs = self.rngs::<K>(first);
        let mut sink = GpomdpLanes::<K> {
            bv: &b.v[..self.horizon],
            bw: &b.w[..self.horizon],
            gv: [0.0; K],
            gw: [0.0; K],
            last: [(0.0, 0.0); K],
        };
        let g = scalar_kernel::<K, _, true>(p, pol, self.limit, &mut rngs, &mut sink);
        for t in self.limit..self.horizon {
            for k in 0..K {
                let (cv, cw) = sink.last[k];
                LaneSink::<K>::record(&mut sink, k, t, 0.0, cv, cw);
            }
        }
        ret.copy_from_slice(&g);
        gv.copy_from_slice(&sink.gv);
        gw.copy_from_slice(&sink.gw);
    }

    /// Adds the baseline-fitting sums of trajectories `first .. first + count` (stochastic
    /// policy only) to `sums`, trajectory by trajectory for each step. Returns the number of
    /// environment steps taken.
    pub(crate) fn fit(
        &self,
        first: u64,
        count: usize,
        sums: &mut BaselineSums,
        sc: &mut Scratch,
    ) -> u64 {
        let h = self.horizon;
        if let Some((p, pol)) = self.scalar {
            for i in 0..count {
                let mut rngs = self.rngs::<1>(first + i as u64);
                let mut sink = FitSink {
                    sums: &mut *sums,
                    last: (0.0, 0.0),
                };
                scalar_kernel::<1, _, true>(&p, pol, self.limit, &mut rngs, &mut sink);
                let (cv, cw) = sink.last;
                for t in self.limit..h {
                    LaneSink::<1>::record(&mut sink, 0, t, 0.0, cv, cw);
                }
            }
            return (count * self.limit) as u64;
        }
        let mut steps = 0;
        for i in 0..count {
            let mut rngs = rngs_from_prefix(self.prefix, first + i as u64);
            let mut sink = FitSink {
                sums: &mut *sums,
                last: (0.0, 0.0),
            };
            let (len, _) = kernel(
                self.env,
                self.policy,
                self.fused,
                self.score,
                self.gamma,
                self.limit,
                &mut rngs,
                &mut sink,
                sc,
            );
            for t in len..h {
                TrajSink::record(&mut sink, t, 0.0, &sc.cum_v, &sc.cum_w);
            }
            steps += len as u64;
        }
        steps
    }
}

/// Accumulates the G(PO)MDP sums of one trajectory (generic kernel).
struct GpomdpTraj<'a> {
    bv: &'a [f64],
    bw: &'a [f64],
    gv: &'a mut [f64],
    gw: &'a mut [f64],
}

impl TrajSink for GpomdpTraj<'_> {
    const SCORES: bool = true;
    #[inline(always)]
    fn record(&mut self, t: usize, dr: f64, cum_v: &[f64], cum_w: &[f64]) {
        let (dv, dw) = (cum_v.len(), cum_w.len());
        let bv = &self.bv[t * dv..(t + 1) * dv];
        for ((g, s), b) in self.gv.iter_mut().zip(cum_v).zip(bv) {
            *g += s * (dr - b);
        }
        let bw = &self.bw[t * dw..(t + 1) * dw];
        for ((g, s), b) in self.gw.iter_mut().zip(cum_w).zip(bw) {
            *g += s * (dr - b);
        }
    }
}

/// Accumulates the G(PO)MDP sums of `K` lanes of the scalar kernel, keeping each lane's last
/// cumulative scores for the padding after the time limit.
struct GpomdpLanes<'a, const K: usize> {
    bv: &'a [f64],
    bw: &'a [f64],
    gv: [f64; K],
    gw: [f64; K],
    last: [(f64, f64); K],
}

impl<const K: usize> LaneSink<K> for GpomdpLanes<'_, K> {
    const SCORES: bool = true;
    #[inline(always)]
    fn record(&mut self, k: usize, t: usize, dr: f64, cv: f64, cw: f64) {
        self.gv[k] += cv * (dr - self.bv[t]);
        self.gw[k] += cw * (dr - self.bw[t]);
        self.last[k] = (cv, cw);
    }
}

/// Adds one trajectory's steps to the baseline-fitting sums.
struct FitSink<'a> {
    sums: &'a mut BaselineSums,
    last: (f64, f64),
}

impl TrajSink for FitSink<'_> {
    const SCORES: bool = true;
    #[inline(always)]
    fn record(&mut self, t: usize, dr: f64, cum_v: &[f64], cum_w: &[f64]) {
        let (dv, dw) = (cum_v.len(), cum_w.len());
        let s = &mut *self.sums;
        let v = t * dv..(t + 1) * dv;
        for ((n, d), c) in s.num_v[v.clone()]
            .iter_mut()
            .zip(&mut s.den_v[v])
            .zip(cum_v)
        {
            *n += c * c * dr;
            *d += c * c;
        }
        let w = t * dw..(t + 1) * dw;
        for ((n, d), c) in s.num_w[w.clone()]
            .iter_mut()
            .zip(&mut s.den_w[w])
            .zip(cum_w)
        {
            *n += c * c * dr;
            *d += c * c;
        }
    }
}

impl LaneSink<1> for FitSink<'_> {
    const SCORES: bool = true;
    #[inline(always)]
    fn record(&mut self, _: usize, t: usize, dr: f64, cv: f64, cw: f64) {
        TrajSink::record(self, t, dr, &[cv], &[cw]);
        self.last = (cv, cw);
    }
}
