//! Coverage of the Student-t confidence interval of Sec 4.5.
//!
//! Over `BATCHES` independent batches, the interval `∇̂_i ± ε_i` with
//! `ε_i = t(1 − δ/2, N − 1) √(Var_i / N)` must contain the exact component at least at the
//! nominal rate `1 − δ` minus a one-sided binomial margin `z √(δ(1 − δ)/BATCHES)`, with `z` the
//! Bonferroni critical value for a family-wise false-alarm rate of 1e-3 over the asserted
//! cases. The interval relies on the central limit theorem (Sec 4.5 says so): on this LQG the
//! per-trajectory contributions are heavy-tailed and the t-interval reaches its nominal rate
//! only for N = 1000, where it is asserted; at N = 10 and N = 100 it under-covers (measured
//! and printed, e.g. about 0.80 and 0.915 instead of 0.95 for ∇_v J). The Chebyshev interval
//! (with the sample variance) is asserted for N = 100 and N = 1000.

use sepg_bounds::surrogate::grad_w;
use sepg_estimators::{
    Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, Width, normal_quantile,
};
use sepg_mdp::Batch;
use sepg_mdp::lqg_model::LqgModel;

use crate::support::Setup;

const BATCHES: u64 = 1000;
/// Asserted cases: Student-t at N = 1000 and Chebyshev at N ∈ {100, 1000}, each for
/// δ ∈ {0.05, 0.2} × {∇_v J, ∇_w J, ∇_w L}.
const ASSERTED: usize = 18;

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
        for b in 0..BATCHES {
            setup.batch_into(n, seed, b, &mut batch);
            est.gradient(&batch, Param::V, GradientSpec::default(), &mut gv)
                .unwrap();
            est.gradient(&batch, Param::W, GradientSpec::default(), &mut gw)
                .unwrap();
            est.surrogate_gradient_for_task(&batch, GradientSpec::default(), &task, &mut sur)
                .unwrap();
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
                }
            }
        }
        for (d, &delta) in deltas.iter().enumerate() {
            let floor = 1.0 - delta - z * (delta * (1.0 - delta) / BATCHES as f64).sqrt();
            for (q, name) in ["grad_v J", "grad_w J", "grad_w L"].iter().enumerate() {
                let cov = f64::from(hits[d][q]) / BATCHES as f64;
                let cov_cheb = f64::from(cheb[d][q]) / BATCHES as f64;
                eprintln!(
                    "coverage N={n} delta={delta} {name}: t {cov:.3} chebyshev {cov_cheb:.3} (floor {floor:.3})"
                );
                if n >= 1000 && cov < floor {
                    failures.push(format!("student-t N={n} delta={delta} {name}: {cov}"));
                }
                if n >= 100 && cov_cheb < floor {
                    failures.push(format!("chebyshev N={n} delta={delta} {name}: {cov_cheb}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "under-coverage: {failures:?}");
}
