//! Variance reduction: G(PO)MDP against REINFORCE, and baselines on top of G(PO)MDP
//! (Sec 2.3.1–2.3.2), measured on the per-trajectory samples of the same trajectories.
//!
//! For two estimators with samples `x_i`, `y_i` on the same trajectories, the difference of
//! variances is the mean of `D_i = (x_i − x̄)² − (y_i − ȳ)²`; "`y` has lower variance" is
//! asserted as `mean(D) > z · SE(D)` with `z` the one-sided Bonferroni critical value for a
//! family-wise false-alarm rate of 1e-3 over the assertions of this file.
//!
//! For `ĥ` (Theorem B.1) the baseline of Appendix B.2 is compared with no baseline and with the
//! per-step mean baseline `G_t H_t (F_t − ⟨F_t⟩)`, which turns out to be much stronger.

use sepg_estimators::{
    Baseline, BaselineFit, Estimate, Estimator, GradientSpec, Kind, Param, normal_quantile,
};
use sepg_mdp::Batch;
use sepg_mdp::lqg_model::LqgModel;

use crate::support::{Moments, Setup};

const BATCHES: u64 = 500;
const N: usize = 100;
/// Set-ups × (parameters × four gradient comparisons + two comparisons for ĥ).
const ASSERTED: usize = 2 * (2 * 4 + 2);

fn spec(kind: Kind, baseline: Baseline) -> GradientSpec {
    GradientSpec {
        kind,
        baseline,
        fit: BaselineFit::LeaveOneOut,
    }
}

#[test]
fn gpomdp_and_baselines_reduce_variance() {
    let z = normal_quantile(1.0 - 1e-3 / ASSERTED as f64).unwrap();
    let specs = [
        ("reinforce", spec(Kind::Reinforce, Baseline::None)),
        ("reinforce-opt", spec(Kind::Reinforce, Baseline::Optimal)),
        ("gpomdp", spec(Kind::Gpomdp, Baseline::None)),
        ("gpomdp-mean", spec(Kind::Gpomdp, Baseline::Mean)),
        ("gpomdp-opt", spec(Kind::Gpomdp, Baseline::Optimal)),
    ];
    // Asserted pairs (higher variance, lower variance), as indices into `specs`.
    let pairs = [(0, 2), (2, 3), (2, 4), (3, 4)];
    let mut failures = Vec::new();
    for (label, model, v, sigma) in [
        ("lqg", LqgModel::thesis(), -0.3, 0.5),
        ("lqg1d", LqgModel::lqg1d(), -0.6, 1.0),
    ] {
        let setup = Setup::new(model, &[v], &[sigma], 20);
        let mut batch = Batch::zeros(0, 0, 0, 0, 0.0);
        let mut est = Estimator::new();
        let mut outs: Vec<Estimate> = specs.iter().map(|_| Estimate::new()).collect();
        for param in [Param::V, Param::W] {
            let mut samples: Vec<Vec<f64>> = vec![Vec::new(); specs.len()];
            for b in 0..BATCHES {
                setup.batch_into(N, 21, b, &mut batch);
                for ((_, s), (out, pool)) in specs.iter().zip(outs.iter_mut().zip(&mut samples)) {
                    est.gradient(&batch, param, *s, out).unwrap();
                    pool.extend_from_slice(out.samples());
                }
            }
            let means: Vec<f64> = samples
                .iter()
                .map(|p| p.iter().sum::<f64>() / p.len() as f64)
                .collect();
            let var = |k: usize| {
                samples[k]
                    .iter()
                    .map(|x| (x - means[k]).powi(2))
                    .sum::<f64>()
                    / (samples[k].len() - 1) as f64
            };
            let base = var(0);
            for (k, (name, _)) in specs.iter().enumerate() {
                eprintln!(
                    "{label} {param:?} {name}: per-trajectory variance {:.4e} (REINFORCE / this = {:.2})",
                    var(k),
                    base / var(k)
                );
            }
            for &(hi, lo) in &pairs {
                let score = lower_variance_score(&samples[hi], &samples[lo]);
                if score < z {
                    failures.push(format!(
                        "{label} {param:?}: {} not below {} (z = {score:.2})",
                        specs[lo].0, specs[hi].0
                    ));
                }
            }
        }
        // ĥ (Theorem B.1) without baseline against the baseline of Appendix B.2.
        let mut pools = [Vec::new(), Vec::new(), Vec::new()];
        let baselines = [Baseline::None, Baseline::Mean, Baseline::Optimal];
        let mut out = Estimate::new();
        for b in 0..BATCHES {
            setup.batch_into(N, 22, b, &mut batch);
            for (baseline, pool) in baselines.iter().zip(&mut pools) {
                est.h(&batch, *baseline, BaselineFit::LeaveOneOut, &mut out)
                    .unwrap();
                pool.extend_from_slice(out.samples());
            }
        }
        let var = |p: &[f64]| {
            let m = p.iter().sum::<f64>() / p.len() as f64;
            p.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (p.len() - 1) as f64
        };
        eprintln!(
            "{label} h: variance none {:.4e}, mean {:.4e}, B.2 optimal {:.4e} (none / optimal = {:.2})",
            var(&pools[0]),
            var(&pools[1]),
            var(&pools[2]),
            var(&pools[0]) / var(&pools[2])
        );
        let score = lower_variance_score(&pools[0], &pools[2]);
        if score < z {
            failures.push(format!(
                "{label} h: B.2 baseline not below none (z = {score:.2})"
            ));
        }
        // The simple per-step mean baseline G H (F − ⟨F_t⟩) beats the B.2 control variate.
        let score = lower_variance_score(&pools[2], &pools[1]);
        if score < z {
            failures.push(format!(
                "{label} h: mean baseline not below B.2 (z = {score:.2})"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// `mean(D) / SE(D)` with `D_i = (x_i − x̄)² − (y_i − ȳ)²`: large when `y` has lower variance.
fn lower_variance_score(x: &[f64], y: &[f64]) -> f64 {
    let mx = x.iter().sum::<f64>() / x.len() as f64;
    let my = y.iter().sum::<f64>() / y.len() as f64;
    let mut d = Moments::default();
    for (a, b) in x.iter().zip(y) {
        d.push((a - mx).powi(2) - (b - my).powi(2));
    }
    d.mean() / d.se()
}
