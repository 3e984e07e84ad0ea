//! The leave-one-out fit (prefix plus suffix sums over the other trajectories, in separate
//! passes) against its definition computed directly: for each trajectory `i` and entry, the
//! sums over `j < i` and over `j > i`, the baseline, the sample terms, their sum over time.
//!
//! Tolerance. Any correct evaluation computes the other trajectories' sums `Σ_{j≠i} num_j`
//! and `Σ_{j≠i} den_j` of one entry with an error of at most `γ_N` times the sum of the
//! absolute terms (recursive summation, `γ_n = n ε / (1 − n ε)`), so the baseline of entry
//! `(t, c)` moves by at most `|Δb| ≤ γ_N (Σ_{j≠i}|num_j| + |b| Σ_{j≠i} den_j) / Σ_{j≠i} den_j`,
//! and the sample of trajectory `i` by `Σ_t |S_t| |Δb_t|` plus the rounding of its `H` sample
//! terms, `γ_H Σ_t |S_t (F_t − b_t)|`. The test allows twice the sum of these bounds. The data
//! include a trajectory whose terms exceed every other trajectory's by a factor 10¹⁶: a fit
//! that subtracts the own term from the total (`total − own`) loses the other trajectories'
//! share of the totals there entirely and fails this test by orders of magnitude (checked by
//! substituting that subtraction for the prefix-plus-suffix sums).

use rand::RngCore;
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use sepg_estimators::{Baseline, BaselineFit, Estimate, Estimator, GradientSpec, Kind, Param};
use sepg_mdp::Batch;

/// Uniform on [lo, hi) from the top 53 bits of one Xoshiro256++ output.
fn uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * ((rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64))
}

/// `n` trajectories of `h` steps, two features of one action (dim_v = 2, dim_w = 1); the
/// scores of trajectory `big` (if any) are multiplied by 10⁸, so its optimal-baseline terms
/// `S²F`, `S²` are 10¹⁶ times the others'.
fn batch(seed: u64, n: usize, h: usize, big: Option<usize>) -> Batch {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut b = Batch::zeros(n, h, 2, 1, 0.9);
    b.sigma[0] = 0.6;
    for i in 0..n {
        let scale = if big == Some(i) { 1e8 } else { 1.0 };
        let (mut cv, mut cw) = ([0.0; 2], 0.0);
        for t in 0..h {
            b.disc_rewards[i * h + t] = uniform(&mut rng, -3.0, 1.0);
            for (k, c) in cv.iter_mut().enumerate() {
                *c += scale * uniform(&mut rng, -1.0, 1.0);
                b.cum_score_v[(i * h + t) * 2 + k] = *c;
            }
            cw += scale * uniform(&mut rng, -1.0, 1.5);
            b.cum_score_w[i * h + t] = cw;
        }
    }
    b
}

fn gamma(n: usize) -> f64 {
    let ne = n as f64 * f64::EPSILON;
    ne / (1.0 - ne)
}

/// The leave-one-out G(PO)MDP samples from the definition and their tolerances, `n × comps` each.
fn definition(b: &Batch, param: Param, optimal: bool) -> (Vec<f64>, Vec<f64>) {
    let (n, h) = (b.n, b.horizon);
    let (scores, comps) = match param {
        Param::V => (&b.cum_score_v, b.dim_v),
        Param::W => (&b.cum_score_w, b.dim_w),
    };
    let s = |i: usize, t: usize, c: usize| scores[(i * h + t) * comps + c];
    let f = |i: usize, t: usize| b.disc_rewards[i * h + t];
    let term = |j: usize, t: usize, c: usize| {
        if optimal {
            let s2 = s(j, t, c) * s(j, t, c);
            (s2 * f(j, t), s2)
        } else {
            (f(j, t), 1.0)
        }
    };
    let (mut x, mut tol) = (vec![0.0; n * comps], vec![0.0; n * comps]);
    for i in 0..n {
        for c in 0..comps {
            let (mut acc, mut bound_b, mut bound_sum) = (0.0, 0.0, 0.0);
            for t in 0..h {
                // Prefix over j < i plus suffix over j > i.
                let (mut pn, mut pd, mut sn, mut sd, mut abs_n) = (0.0, 0.0, 0.0, 0.0, 0.0);
                for j in 0..i {
                    let (nj, dj) = term(j, t, c);
                    pn += nj;
                    pd += dj;
                    abs_n += nj.abs();
                }
                for j in (i + 1..n).rev() {
                    let (nj, dj) = term(j, t, c);
                    sn += nj;
                    sd += dj;
                    abs_n += nj.abs();
                }
                let (num, den) = (pn + sn, pd + sd);
                let base = if den > 0.0 { num / den } else { 0.0 };
                let p = s(i, t, c) * (f(i, t) - base);
                acc += p;
                bound_b += s(i, t, c).abs() * gamma(n) * (abs_n + base.abs() * den) / den;
                bound_sum += p.abs();
            }
            x[i * comps + c] = acc;
            tol[i * comps + c] = 2.0 * (bound_b + gamma(h) * bound_sum);
        }
    }
    (x, tol)
}

fn check(b: &Batch, what: &str) {
    let mut est = Estimator::new();
    let mut out = Estimate::new();
    for param in [Param::V, Param::W] {
        for (baseline, optimal) in [(Baseline::Optimal, true), (Baseline::Mean, false)] {
            let spec = GradientSpec {
                kind: Kind::Gpomdp,
                baseline,
                fit: BaselineFit::LeaveOneOut,
            };
            est.gradient(b, param, spec, &mut out).unwrap();
            let (expected, tol) = definition(b, param, optimal);
            for (k, ((got, want), tol)) in out.samples().iter().zip(&expected).zip(&tol).enumerate()
            {
                assert!(
                    (got - want).abs() <= *tol,
                    "{what} {param:?} {baseline:?} sample {k}: {got} vs {want} (tolerance {tol:e})"
                );
            }
        }
    }
}

/// Nine trajectories (two blocks of four and a remainder) of seven steps, one component
/// (∇_w) and two (∇_v), optimal and mean baselines.
#[test]
fn leave_one_out_equals_its_definition() {
    for seed in [1, 2, 3] {
        check(&batch(seed, 9, 7, None), "ordinary");
    }
}

/// One trajectory dominates the totals by 10¹⁶ (first, middle, last).
#[test]
fn leave_one_out_with_a_dominant_trajectory() {
    for big in [0, 4, 8] {
        check(&batch(7, 9, 7, Some(big)), "dominant");
    }
}
