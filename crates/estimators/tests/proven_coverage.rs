//! Coverage of the proven widths (`sepg_estimators::proven`) by Monte Carlo on adversarial
//! trajectories, with the Student-t width of Sec 4.5 measured beside them.
//!
//! The trajectory model is built to make the per-trajectory G(PO)MDP sample as large as the
//! proof allows: one feature `φ = M_φ` (the worst case of the v-score martingale), action
//! noise `ξ_t ~ N(0, 1)`, and rewards `r_t = b + R' sign(D_t)` that follow the sign of the
//! driving cumulative score `D_t` (the v-score `X_t = (M_φ/σ) Σ_{k≤t} ξ_k` or the w-score
//! `W_t = Σ_{k≤t} (ξ_k² − 1)`), so that `g = Σ_t γ^t R' |D_t|`: every term of the bound
//! `|g| ≤ Σ_t a_t |X_t|` is attained. `r_t ∈ {−R, R}` (two-sided, `b = 0`) or `{−R, 0}`
//! (non-positive, `b = −R/2`). The v-model is an MDP: the state is `Σ_k a_k` and the policy
//! mean 0, so `r_t = R' sign(s_{t+1}) + b`. The exact means are closed forms:
//! `E|X_t| = (M_φ/σ)√(t+1)√(2/π)`, `E|χ²_n − n| = 4n f_{n+2}(n)` (`f_k` the χ²_k density),
//! `E sign(χ²_n − n) = 1 − 2P(n/2, n/2)`. A fifth case terminates the v-model early (after
//! step `t` when `X_t > 1.5 √(t+1) M_φ/σ`, a stopping time), with a reference mean from an
//! independent run of 400 000 trajectories.
//!
//! For each case, `BATCHES` batches of `N` trajectories: the miss count of the proven
//! width (gradient component and `Ĵ`) must not exceed the `1 − α/ASSERTED` quantile of
//! `Bin(BATCHES, δ)` (false-alarm rate α = 1e-3 over all assertions, Bonferroni). The
//! Student-t misses and the ratio proven / Student-t width are printed.

use sepg_estimators::binomial::upper_tail;
use sepg_estimators::proven::ProvenWidths;
use sepg_estimators::{Estimate, Estimator, Param, Width};
use sepg_mdp::Batch;
use sepg_mdp::rng::{TrajRng, rng_from_seed, standard_normal};
use statrs::function::gamma::{gamma_lr, ln_gamma};

const N: usize = 50;
const H: usize = 20;
const GAMMA: f64 = 0.9;
const SIGMA: f64 = 0.5;
const M_PHI: f64 = 2.0;
const R: f64 = 4.0;
const DELTA: f64 = 0.05;
const BATCHES: u64 = 20_000;
const ALPHA: f64 = 1e-3;
/// Five cases × (gradient component, Ĵ).
const ASSERTED: usize = 10;

/// Which cumulative score drives the rewards.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Driver {
    V,
    W,
}

/// One case of the adversarial model.
#[derive(Clone, Copy, Debug)]
struct Case {
    driver: Driver,
    non_positive: bool,
    terminates: bool,
}

/// One trajectory into row `i` of `batch` (padded after a termination as the rollout
/// engine does: reward 0, cumulative scores frozen). Returns its sample
/// `g = Σ_{t<H} γ^t (r_t − b) D_t` computed directly, and its discounted return.
fn trajectory(
    case: Case,
    p: &ProvenWidths,
    rng: &mut TrajRng,
    batch: &mut Batch,
    i: usize,
) -> (f64, f64) {
    let (b, dev) = (p.baseline(), p.reward_deviation());
    let (mut x, mut w, mut disc) = (0.0, 0.0, 1.0);
    let (mut g, mut ret) = (0.0, 0.0);
    let mut alive = true;
    let mut len = H;
    for t in 0..H {
        let r = if alive {
            let xi = standard_normal(rng);
            x += xi * M_PHI / SIGMA;
            w += xi * xi - 1.0;
            let d = if case.driver == Driver::V { x } else { w };
            b + dev * if d >= 0.0 { 1.0 } else { -1.0 }
        } else {
            0.0
        };
        batch.disc_rewards[i * H + t] = disc * r;
        batch.cum_score_v[i * H + t] = x;
        batch.cum_score_w[i * H + t] = w;
        let score = if case.driver == Driver::V { x } else { w };
        g += disc * (r - b) * score;
        ret += disc * r;
        if alive && case.terminates && x > 1.5 * ((t + 1) as f64).sqrt() * M_PHI / SIGMA {
            alive = false;
            len = t + 1;
        }
        disc *= GAMMA;
    }
    batch.lengths[i] = len;
    (g, ret)
}

/// Exact `(E g, E J)` of a case without termination.
fn exact_means(case: Case, p: &ProvenWidths) -> (f64, f64) {
    let (b, dev) = (p.baseline(), p.reward_deviation());
    let (mut eg, mut ej) = (0.0, 0.0);
    for t in 0..H {
        let disc = GAMMA.powi(t as i32);
        let n = (t + 1) as f64;
        let (abs_mean, sign_mean) = match case.driver {
            Driver::V => (
                M_PHI / SIGMA * n.sqrt() * (2.0 / std::f64::consts::PI).sqrt(),
                0.0,
            ),
            Driver::W => {
                let log_f = 0.5 * n * n.ln()
                    - 0.5 * n
                    - (0.5 * n + 1.0) * std::f64::consts::LN_2
                    - ln_gamma(0.5 * n + 1.0);
                (
                    4.0 * n * log_f.exp(),
                    1.0 - 2.0 * gamma_lr(0.5 * n, 0.5 * n),
                )
            }
        };
        eg += disc * dev * abs_mean;
        ej += disc * (b + dev * sign_mean);
    }
    (eg, ej)
}

/// Reference `(E g, E J)` of a terminating case from `n` independent trajectories.
fn reference_means(case: Case, p: &ProvenWidths, n: usize) -> (f64, f64) {
    let mut batch = Batch::zeros(1, H, 1, 1, GAMMA);
    let mut rng = rng_from_seed(999);
    let (mut sg, mut sj) = (0.0, 0.0);
    for _ in 0..n {
        let (g, j) = trajectory(case, p, &mut rng, &mut batch, 0);
        sg += g;
        sj += j;
    }
    (sg / n as f64, sj / n as f64)
}

/// The largest miss count `c` with `P(Bin(BATCHES, δ) > c) > α/ASSERTED`, i.e. the count
/// above which a valid width is rejected.
fn miss_threshold() -> u64 {
    let level = ALPHA / ASSERTED as f64;
    (0..BATCHES)
        .find(|&c| upper_tail(c + 1, BATCHES, DELTA).unwrap() <= level)
        .unwrap()
}

#[test]
fn proven_widths_cover_adversarial_trajectories() {
    let threshold = miss_threshold();
    let cases = [
        (Driver::V, false, false),
        (Driver::V, true, false),
        (Driver::W, false, false),
        (Driver::W, true, false),
        (Driver::V, true, true),
    ];
    let mut failures = Vec::new();
    for (seed, (driver, non_positive, terminates)) in cases.into_iter().enumerate() {
        let case = Case {
            driver,
            non_positive,
            terminates,
        };
        let p = ProvenWidths::new(R, case.non_positive, M_PHI, GAMMA, H).unwrap();
        let (eg, ej) = if terminates {
            reference_means(case, &p, 400_000)
        } else {
            exact_means(case, &p)
        };
        let param = if driver == Driver::V {
            Param::V
        } else {
            Param::W
        };
        let eps = match driver {
            Driver::V => p.v_width(SIGMA, N, DELTA).unwrap(),
            Driver::W => p.w_width(N, DELTA).unwrap(),
        };
        let eps_j = p.j_width(N, DELTA).unwrap();
        let mut batch = Batch::zeros(N, H, 1, 1, GAMMA);
        batch.sigma[0] = SIGMA;
        let mut rng = rng_from_seed(100 + seed as u64);
        let mut est = Estimator::new();
        let (mut grad, mut value) = (Estimate::new(), Estimate::new());
        let (mut miss, mut miss_j, mut miss_t, mut miss_tj) = (0u64, 0u64, 0u64, 0u64);
        let (mut ratio, mut ratio_j) = (0.0, 0.0);
        for _ in 0..BATCHES {
            let mut direct = 0.0;
            for i in 0..N {
                direct += trajectory(case, &p, &mut rng, &mut batch, i).0 / N as f64;
            }
            est.gradient(&batch, param, p.gradient_spec(), &mut grad)
                .unwrap();
            est.value(&batch, &mut value).unwrap();
            // The estimator with the constant baseline is the sample of the proof.
            assert!((grad.mean()[0] - direct).abs() <= 1e-9 * (1.0 + direct.abs()));
            let mut t = [0.0];
            grad.widths_into(Width::StudentT, DELTA, &mut t).unwrap();
            let mut tj = [0.0];
            value.widths_into(Width::StudentT, DELTA, &mut tj).unwrap();
            let err = (grad.mean()[0] - eg).abs();
            let err_j = (value.mean()[0] - ej).abs();
            miss += u64::from(err > eps);
            miss_t += u64::from(err > t[0]);
            miss_j += u64::from(err_j > eps_j);
            miss_tj += u64::from(err_j > tj[0]);
            ratio += eps / t[0] / BATCHES as f64;
            ratio_j += eps_j / tj[0] / BATCHES as f64;
        }
        let rate = |m: u64| m as f64 / BATCHES as f64;
        eprintln!(
            "{case:?}: E g {eg:.4} | proven ε {eps:.4} misses {:.4} | Student-t misses {:.4} | \
             mean ratio proven/t {ratio:.2}; J: E J {ej:.4} proven ε {eps_j:.4} misses {:.4} | \
             t misses {:.4} | ratio {ratio_j:.2}",
            rate(miss),
            rate(miss_t),
            rate(miss_j),
            rate(miss_tj)
        );
        if miss > threshold || miss_j > threshold {
            failures.push(format!(
                "{case:?}: misses {miss}, J misses {miss_j} > {threshold}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
