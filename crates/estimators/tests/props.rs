//! Properties: estimators never return NaN for finite batches; the t-quantile is monotone.

use approx::{abs_diff_eq, relative_eq};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use sepg_estimators::{
    Baseline, BaselineFit, Estimate, Estimator, EstimatorError, GradientSpec, Kind, Param,
    SurrogateEstimate, Width, student_t_quantile,
};
use sepg_mdp::Batch;

/// A batch of the given shape whose entries are taken cyclically from `values`.
fn batch_from(n: usize, h: usize, p: usize, l: usize, values: &[f64], sigma: f64) -> Batch {
    let mut b = Batch::zeros(n, h, l * p, l, 0.9);
    b.sigma.fill(sigma);
    let mut it = values.iter().cycle();
    for x in b
        .disc_rewards
        .iter_mut()
        .chain(b.cum_score_v.iter_mut())
        .chain(b.cum_score_w.iter_mut())
    {
        *x = *it.next().expect("non-empty");
    }
    b
}

fn all_finite(e: &Estimate) -> bool {
    e.mean()
        .iter()
        .chain(e.samples())
        .chain(e.variance())
        .all(|x| x.is_finite())
}

/// Runs every estimator; each result must be finite, or a typed non-finite error when
/// `allow_overflow`.
fn check_all(b: &Batch, allow_overflow: bool) -> Result<(), TestCaseError> {
    let mut est = Estimator::new();
    let mut out = Estimate::new();
    let ok = |r: Result<(), EstimatorError>, out: &Estimate| -> Result<(), TestCaseError> {
        match r {
            Ok(()) => prop_assert!(all_finite(out)),
            Err(EstimatorError::NonFinite { .. }) if allow_overflow => {}
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
        Ok(())
    };
    for kind in [Kind::Reinforce, Kind::Gpomdp, Kind::Pgt] {
        for baseline in [Baseline::None, Baseline::Mean, Baseline::Optimal] {
            for fit in [BaselineFit::PlugIn, BaselineFit::LeaveOneOut] {
                let s = GradientSpec {
                    kind,
                    baseline,
                    fit,
                };
                for param in [Param::V, Param::W] {
                    let r = est.gradient(b, param, s, &mut out);
                    ok(r, &out)?;
                    if r.is_ok() {
                        let c = out.confidence(Width::StudentT, 0.05).unwrap();
                        prop_assert!(c.eps.is_finite() && c.eps >= 0.0);
                    }
                }
                let r = est.h(b, baseline, fit, &mut out);
                ok(r, &out)?;
                let r = est.mixed(b, s, &mut out);
                ok(r, &out)?;
                if b.n >= 4 {
                    let mut sur = SurrogateEstimate::new();
                    let dc = vec![-1.0; b.dim_w];
                    let r = est.surrogate_gradient(b, s, 3.0, &dc, &mut sur);
                    ok(r, sur.grad_w_l())?;
                    if r.is_ok() {
                        prop_assert!(sur.surrogate().is_finite());
                    }
                }
            }
        }
    }
    let r = est.value(b, &mut out);
    ok(r, &out)
}

/// Naive reference of every baseline-fitted estimator: for each trajectory `i` and entry
/// `(t, c)`, the baseline is summed directly over the fitting set (all trajectories, or all
/// but `i`) and the sample is `Σ_t p(entry; b)`; returns `n × comps` samples.
fn naive(b: &Batch, target: &str, baseline: Baseline, fit: BaselineFit) -> Vec<f64> {
    let (n, h, m, l) = (b.n, b.horizon, b.dim_v, b.dim_w);
    // Entries (num, den, p(b) = a − b·z) of trajectory i: (steps, comps, closure).
    let entry = |i: usize, t: usize, c: usize| -> (f64, f64, f64, f64) {
        let f = b.disc_rewards[i * h + t];
        let opt = baseline == Baseline::Optimal;
        let score = |s: f64, f: f64| {
            let (num, den) = if opt { (s * s * f, s * s) } else { (f, 1.0) };
            (num, den, s * f, s)
        };
        match target {
            "v" => score(b.cum_score_v[(i * h + t) * m + c], f),
            "w" => score(b.cum_score_w[(i * h + t) * l + c], f),
            "reinforce" => {
                let ret: f64 = b.disc_rewards[i * h..(i + 1) * h].iter().sum();
                score(b.cum_score_v[(i * h + h - 1) * m + c], ret)
            }
            _ => {
                let (j, k) = (c / m, c % m);
                let g = b.cum_score_v[(i * h + t) * m + k];
                let hs = b.cum_score_w[(i * h + t) * l + j] / b.sigma[j];
                let u = g * hs * f;
                if opt {
                    let z = g + hs;
                    (u * z, z * z, u, z)
                } else {
                    (f, 1.0, u, g * hs)
                }
            }
        }
    };
    let (steps, comps) = match target {
        "v" => (h, m),
        "w" => (h, l),
        "reinforce" => (1, m),
        _ => (h, l * m),
    };
    let mut out = vec![0.0; n * comps];
    for i in 0..n {
        for t in 0..steps {
            for c in 0..comps {
                let (mut num, mut den) = (0.0, 0.0);
                for r in (0..n).filter(|&r| fit == BaselineFit::PlugIn || r != i) {
                    let (a, d, _, _) = entry(r, t, c);
                    num += a;
                    den += d;
                }
                let base = match baseline {
                    Baseline::None => 0.0,
                    _ if den > 0.0 => num / den,
                    _ => 0.0,
                };
                let (_, _, a, z) = entry(i, t, c);
                out[i * comps + c] += a - base * z;
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: RngSeed::Fixed(0xe57_1a7e),
        ..ProptestConfig::default()
    })]

    #[test]
    fn baselines_match_naive_reference(
        n in 2usize..7, h in 1usize..5, p in 1usize..3, l in 1usize..3,
        values in prop::collection::vec(-10f64..10.0, 1..64),
        zeros in prop::collection::vec(any::<bool>(), 1..16),
        sigma in 0.1f64..3.0,
    ) {
        let mut b = batch_from(n, h, p, l, &values, sigma);
        // Zero scores in places, so that some baseline denominators vanish.
        for (x, z) in b.cum_score_v.iter_mut().zip(zeros.iter().cycle()) {
            if *z {
                *x = 0.0;
            }
        }
        let mut est = Estimator::new();
        let mut out = Estimate::new();
        for baseline in [Baseline::None, Baseline::Mean, Baseline::Optimal] {
            for fit in [BaselineFit::PlugIn, BaselineFit::LeaveOneOut] {
                let gp = GradientSpec { kind: Kind::Gpomdp, baseline, fit };
                let rf = GradientSpec { kind: Kind::Reinforce, baseline, fit };
                for (target, run) in [
                    ("v", est.gradient(&b, Param::V, gp, &mut out).map(|_| out.samples().to_vec())),
                    ("w", est.gradient(&b, Param::W, gp, &mut out).map(|_| out.samples().to_vec())),
                    ("reinforce", est.gradient(&b, Param::V, rf, &mut out).map(|_| out.samples().to_vec())),
                    ("h", est.h(&b, baseline, fit, &mut out).map(|_| out.samples().to_vec())),
                ] {
                    let got = run.unwrap();
                    let expected = naive(&b, target, baseline, fit);
                    let scale = expected.iter().fold(1.0f64, |s, x| s.max(x.abs()));
                    for (g, e) in got.iter().zip(&expected) {
                        prop_assert!(
                            abs_diff_eq!(*g, *e, epsilon = 1e-9 * scale),
                            "{target} {baseline:?} {fit:?}: {got:?} vs {expected:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn moderate_batches_give_finite_estimates(
        n in 2usize..7, h in 1usize..5, p in 1usize..3, l in 1usize..3,
        values in prop::collection::vec(-1e3f64..1e3, 1..64),
        sigma in 1e-3f64..1e3,
    ) {
        check_all(&batch_from(n, h, p, l, &values, sigma), false)?;
    }

    #[test]
    fn pgt_equals_gpomdp(
        n in 2usize..7, h in 1usize..6, p in 1usize..3,
        values in prop::collection::vec(-10f64..10.0, 1..64),
        baseline in prop_oneof![Just(Baseline::None), Just(Baseline::Mean), Just(Baseline::Optimal)],
    ) {
        // Summation theorem: Σ_t S_t (F_t − b_t) = Σ_k (S_k − S_{k−1}) Σ_{l≥k} (F_l − b_l).
        let b = batch_from(n, h, p, 1, &values, 0.5);
        let mut est = Estimator::new();
        let (mut g, mut q) = (Estimate::new(), Estimate::new());
        for fit in [BaselineFit::PlugIn, BaselineFit::LeaveOneOut] {
            est.gradient(&b, Param::V, GradientSpec { kind: Kind::Gpomdp, baseline, fit }, &mut g).unwrap();
            est.gradient(&b, Param::V, GradientSpec { kind: Kind::Pgt, baseline, fit }, &mut q).unwrap();
            let scale = g.samples().iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for (x, y) in g.samples().iter().zip(q.samples()) {
                prop_assert!(abs_diff_eq!(x, y, epsilon = 1e-12 * scale * (h as f64)), "{x} vs {y}");
            }
        }
    }

    #[test]
    fn extreme_batches_never_give_nan(
        n in 2usize..6, h in 1usize..4,
        values in prop::collection::vec(prop_oneof![
            -1e300f64..1e300, -1e-300f64..1e-300, Just(0.0), Just(f64::MAX), Just(f64::MIN_POSITIVE)
        ], 1..32),
    ) {
        check_all(&batch_from(n, h, 1, 1, &values, 1.0), true)?;
    }

    #[test]
    fn skew_corrected_ends_invert_halls_transformation(
        values in prop::collection::vec(-10f64..10.0, 3..40),
        skew in 0.0f64..3.0,
        delta in 0.01f64..0.5,
    ) {
        // Skewed data: x ↦ x + skew · x² / 10.
        let n = values.len();
        let mut b = Batch::zeros(n, 1, 1, 1, 0.9);
        for (r, v) in b.disc_rewards.iter_mut().zip(&values) {
            *r = v + skew * v * v / 10.0;
        }
        let mut e = Estimate::new();
        Estimator::new().value(&b, &mut e).unwrap();
        let (mut lo, mut hi) = ([0.0], [0.0]);
        e.intervals_into(Width::SkewCorrectedT, delta, &mut lo, &mut hi).unwrap();
        // Hall's g(T) = T + γT²/3 + γ²T³/27 + γ/(6n) at T = (x̄ − end)/s must be ±t/√n.
        let (mean, s) = (e.mean()[0], e.variance()[0].sqrt());
        prop_assume!(s > 1e-6);
        let x = &b.disc_rewards;
        let gamma = x.iter().map(|v| ((v - mean) / s).powi(3)).sum::<f64>() / n as f64;
        let g = |t: f64| t + gamma * t * t / 3.0 + gamma * gamma * t.powi(3) / 27.0
            + gamma / (6.0 * n as f64);
        let y = student_t_quantile(1.0 - delta / 2.0, n as f64 - 1.0).unwrap() / (n as f64).sqrt();
        prop_assert!(relative_eq!(g((mean - lo[0]) / s), y, epsilon = 1e-9, max_relative = 1e-9), "lower end");
        prop_assert!(relative_eq!(g((mean - hi[0]) / s), -y, epsilon = 1e-9, max_relative = 1e-9), "upper end");
        let mut eps = [0.0];
        e.widths_into(Width::SkewCorrectedT, delta, &mut eps).unwrap();
        let enclosing = (mean - lo[0]).max(hi[0] - mean);
        prop_assert!(relative_eq!(eps[0], enclosing, epsilon = 0.0, max_relative = 1e-14), "width");
    }

    #[test]
    fn t_quantile_is_monotone_in_p(p in 1e-6f64..0.999_999, f in 1e-3f64..1.0, nu in 1.0f64..1e9) {
        let q = p + (1.0 - p) * f;
        prop_assume!(q < 1.0);
        let (a, b) = (student_t_quantile(p, nu).unwrap(), student_t_quantile(q, nu).unwrap());
        prop_assert!(a < b, "t({p}, {nu}) = {a} >= t({q}, {nu}) = {b}");
    }

    #[test]
    fn t_quantile_decreases_in_nu(p in 0.5001f64..0.999_999_9, nu in 1.0f64..1e8, f in 1e-3f64..10.0) {
        let nu2 = nu * (1.0 + f);
        let (a, b) = (student_t_quantile(p, nu).unwrap(), student_t_quantile(p, nu2).unwrap());
        prop_assert!(a > b, "t({p}, {nu}) = {a} <= t({p}, {nu2}) = {b}");
        // Odd in p − 1/2 (1 − p is exact for p ≥ 1/2).
        prop_assert_eq!(student_t_quantile(1.0 - p, nu).unwrap(), -a);
    }
}
