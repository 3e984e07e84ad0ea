//! Coverage of the confidence intervals of Sec 4.5.
//!
//! Over `BATCHES` independent batches, the interval `∇̂_i ± ε_i` with
//! `ε_i = t(1 − δ/2, N − 1) √(Var_i / N)` must contain the exact component at least at the
//! nominal rate `1 − δ` minus a one-sided binomial margin `z √(δ(1 − δ)/BATCHES)`, with `z` the
//! Bonferroni critical value for a family-wise false-alarm rate of 1e-3 over the asserted
//! cases. The interval relies on the central limit theorem (Sec 4.5 says so): on this LQG the
//! per-trajectory contributions are skewed and heavy-tailed and the t-interval reaches its
//! nominal rate only for N = 1000, where it is asserted; at N = 10 and N = 100 it under-covers
//! (measured and printed, e.g. about 0.80 and 0.915 instead of 0.95 for ∇_v J).
//!
//! The skew-corrected interval (`Width::SkewCorrectedT`, Hall's transformation) is measured in
//! the same runs, both as the asymmetric interval itself and as the symmetric width around the
//! estimate that contains it (what `Estimate::confidence` returns); both are asserted at
//! N = 1000 and printed for all N. The Chebyshev interval (with the sample variance) is
//! asserted for N = 100 and N = 1000.

use approx::abs_diff_eq;
use sepg_bounds::surrogate::grad_w;
use sepg_estimators::{
    Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, Width, normal_quantile,
};
use sepg_mdp::Batch;
use sepg_mdp::lqg_model::LqgModel;

use crate::support::Setup;

const BATCHES: u64 = 1000;
/// Asserted cases: Student-t, skew-corrected (interval and symmetric width) at N = 1000 and
/// Chebyshev at N ∈ {100, 1000}, each for δ ∈ {0.05, 0.2} × {∇_v J, ∇_w J, ∇_w L}.
const ASSERTED: usize = 30;

#[test]
fn confidence_intervals_cover_at_nominal_rate() {
    let sigma = 0.5;
    let setup = Setup::new(LqgModel::thesis(), &[-0.3], &[sigma], 20);
    let task = setup.task();
    let exact_wl = grad_w(
        &task,
        sigma,
        &setup.exact.grad_v,
        &setup.exact.mixed_sigma_v(),
    )
    .unwrap();
    let exact = [setup.exact.grad_v[0], setup.exact.grad_w[0], exact_wl];
    let z = normal_quantile(1.0 - 1e-3 / ASSERTED as f64).unwrap();
    let mut batch = Batch::zeros(0, 0, 0, 0, 0.0);
    let mut est = Estimator::new();
    let (mut gv, mut gw) = (Estimate::new(), Estimate::new());
    let mut sur = SurrogateEstimate::new();
    let mut failures = Vec::new();
    for (seed, n) in [(1u64, 10usize), (2, 100), (3, 1000)] {
        let deltas = [0.05, 0.2];
        let mut hits = [[0u32; 3]; 2];
        let mut cheb = [[0u32; 3]; 2];
        let mut skew = [[0u32; 3]; 2];
        let mut skew_sym = [[0u32; 3]; 2];
        // Mean sample skewness and excess kurtosis of the per-trajectory samples.
        let mut shape = [[0.0f64; 2]; 3];
        for b in 0..BATCHES {
            setup.batch_into(n, seed, b, &mut batch);
            est.gradient(&batch, Param::V, GradientSpec::default(), &mut gv)
                .unwrap();
            est.gradient(&batch, Param::W, GradientSpec::default(), &mut gw)
                .unwrap();
            est.surrogate_gradient_for_task(&batch, GradientSpec::default(), &task, &mut sur)
                .unwrap();
            for (q, e) in [&gv, &gw, sur.grad_w_l()].iter().enumerate() {
                let (g, k) = skewness_kurtosis(e.samples());
                shape[q][0] += g / BATCHES as f64;
                shape[q][1] += k / BATCHES as f64;
            }
            for (d, &delta) in deltas.iter().enumerate() {
                for (q, e) in [&gv, &gw, sur.grad_w_l()].iter().enumerate() {
                    let mut eps = [0.0];
                    e.widths_into(Width::StudentT, delta, &mut eps).unwrap();
                    if (e.mean()[0] - exact[q]).abs() <= eps[0] {
                        hits[d][q] += 1;
                    }
                    e.widths_into(Width::Chebyshev, delta, &mut eps).unwrap();
                    if (e.mean()[0] - exact[q]).abs() <= eps[0] {
                        cheb[d][q] += 1;
                    }
                    let (mut lo, mut hi) = ([0.0], [0.0]);
                    e.intervals_into(Width::SkewCorrectedT, delta, &mut lo, &mut hi)
                        .unwrap();
                    if lo[0] <= exact[q] && exact[q] <= hi[0] {
                        skew[d][q] += 1;
                    }
                    e.widths_into(Width::SkewCorrectedT, delta, &mut eps)
                        .unwrap();
                    if (e.mean()[0] - exact[q]).abs() <= eps[0] {
                        skew_sym[d][q] += 1;
                    }
                }
            }
        }
        for (q, name) in ["grad_v J", "grad_w J", "grad_w L"].iter().enumerate() {
            let [g, k] = shape[q];
            eprintln!("samples N={n} {name}: mean skewness {g:.2}, mean excess kurtosis {k:.2}");
        }
        for (d, &delta) in deltas.iter().enumerate() {
            let floor = 1.0 - delta - z * (delta * (1.0 - delta) / BATCHES as f64).sqrt();
            for (q, name) in ["grad_v J", "grad_w J", "grad_w L"].iter().enumerate() {
                let rate = |hits: u32| f64::from(hits) / BATCHES as f64;
                let cov = rate(hits[d][q]);
                let cov_cheb = rate(cheb[d][q]);
                let cov_skew = rate(skew[d][q]);
                let cov_skew_sym = rate(skew_sym[d][q]);
                eprintln!(
                    "coverage N={n} delta={delta} {name}: t {cov:.3} skew-corrected {cov_skew:.3} \
                     (symmetric {cov_skew_sym:.3}) chebyshev {cov_cheb:.3} (floor {floor:.3})"
                );
                for (label, c) in [
                    ("student-t", cov),
                    ("skew-corrected", cov_skew),
                    ("skew-corrected symmetric", cov_skew_sym),
                ] {
                    if n >= 1000 && c < floor {
                        failures.push(format!("{label} N={n} delta={delta} {name}: {c}"));
                    }
                }
                if n >= 100 && cov_cheb < floor {
                    failures.push(format!("chebyshev N={n} delta={delta} {name}: {cov_cheb}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "under-coverage: {failures:?}");
}

/// Sample skewness and excess kurtosis of `x` (moments with divisor n).
fn skewness_kurtosis(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let moment = |p: i32| x.iter().map(|v| (v - m).powi(p)).sum::<f64>() / n;
    let m2 = moment(2);
    (moment(3) / m2.powf(1.5), moment(4) / (m2 * m2) - 3.0)
}

/// Hall's correction on a textbook skewed population: exponential samples (skewness 2,
/// mean 1), N = 20, δ = 0.05. The Student-t interval is known to under-cover there (about
/// 0.92), the skew-corrected interval to come close to the nominal 0.95. Over `REPS` data sets
/// the standard error of a coverage is about 0.0016; the asserted gaps are 4 standard errors
/// of a difference or more (false-alarm rate below 1e-4 each).
#[test]
fn skew_correction_fixes_exponential_coverage() {
    use rand::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;
    const REPS: usize = 20_000;
    let n = 20;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    let mut batch = Batch::zeros(n, 1, 1, 1, 0.9);
    let mut est = Estimator::new();
    let mut e = Estimate::new();
    let (mut t_hits, mut skew_hits) = (0u32, 0u32);
    for _ in 0..REPS {
        for x in &mut batch.disc_rewards {
            *x = -(1.0 - rng.random::<f64>()).ln();
        }
        est.value(&batch, &mut e).unwrap();
        let (mut lo, mut hi) = ([0.0], [0.0]);
        e.intervals_into(Width::StudentT, 0.05, &mut lo, &mut hi)
            .unwrap();
        t_hits += u32::from(lo[0] <= 1.0 && 1.0 <= hi[0]);
        e.intervals_into(Width::SkewCorrectedT, 0.05, &mut lo, &mut hi)
            .unwrap();
        skew_hits += u32::from(lo[0] <= 1.0 && 1.0 <= hi[0]);
    }
    let (t, skew) = (
        f64::from(t_hits) / REPS as f64,
        f64::from(skew_hits) / REPS as f64,
    );
    eprintln!("exponential N={n} delta=0.05: t {t:.4} skew-corrected {skew:.4}");
    assert!(t < 0.935, "t coverage {t}");
    assert!(skew > t + 0.01, "skew-corrected {skew} vs t {t}");
    assert!(
        abs_diff_eq!(skew, 0.95, epsilon = 0.01),
        "skew-corrected {skew}"
    );
}
