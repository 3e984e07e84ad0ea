//! Estimators on tiny hand-made batches against values computed by hand.

use approx::relative_eq;
use sepg_estimators::{
    Baseline, BaselineFit, Estimate, Estimator, EstimatorError, GradientSpec, Kind, Param,
    SurrogateEstimate,
};
use sepg_mdp::Batch;

/// Two trajectories of two steps, one action dimension, one feature.
///
/// | traj | F = γ^t r_t | cum v-score | cum w-score |
/// |------|-------------|-------------|-------------|
/// | 1    | 1, 0.5      | 1, 3        | 0.5, 0.5    |
/// | 2    | 2, −1       | −1, −2      | 1, 0        |
fn two_by_two() -> Batch {
    let mut b = Batch::zeros(2, 2, 1, 1, 0.9);
    b.sigma[0] = 0.5;
    b.disc_rewards.copy_from_slice(&[1.0, 0.5, 2.0, -1.0]);
    b.cum_score_v.copy_from_slice(&[1.0, 3.0, -1.0, -2.0]);
    b.cum_score_w.copy_from_slice(&[0.5, 0.5, 1.0, 0.0]);
    b
}

fn spec(kind: Kind, baseline: Baseline, fit: BaselineFit) -> GradientSpec {
    GradientSpec {
        kind,
        baseline,
        fit,
    }
}

fn grad(batch: &Batch, param: Param, s: GradientSpec) -> Estimate {
    let mut est = Estimate::new();
    Estimator::new()
        .gradient(batch, param, s, &mut est)
        .unwrap();
    est
}

fn assert_close(got: &[f64], expected: &[f64]) {
    assert_eq!(got.len(), expected.len());
    for (g, e) in got.iter().zip(expected) {
        assert!(
            relative_eq!(g, e, epsilon = 1e-14, max_relative = 1e-14),
            "{got:?} vs {expected:?}"
        );
    }
}

#[test]
fn reinforce_by_hand() {
    use BaselineFit::*;
    let b = two_by_two();
    // Returns 1.5 and 1; final scores 3 and −2.
    let none = grad(&b, Param::V, spec(Kind::Reinforce, Baseline::None, PlugIn));
    assert_close(none.samples(), &[4.5, -2.0]);
    assert_close(none.mean(), &[1.25]);
    // Mean baseline 1.25; leave-one-out: the other trajectory's return.
    let mean = grad(&b, Param::V, spec(Kind::Reinforce, Baseline::Mean, PlugIn));
    assert_close(mean.samples(), &[0.75, 0.5]);
    let mean_loo = grad(
        &b,
        Param::V,
        spec(Kind::Reinforce, Baseline::Mean, LeaveOneOut),
    );
    assert_close(mean_loo.samples(), &[1.5, 1.0]);
    // Optimal b = (9·1.5 + 4·1)/13 = 17.5/13.
    let opt = grad(
        &b,
        Param::V,
        spec(Kind::Reinforce, Baseline::Optimal, PlugIn),
    );
    assert_close(opt.samples(), &[6.0 / 13.0, 9.0 / 13.0]);
    let opt_loo = grad(
        &b,
        Param::V,
        spec(Kind::Reinforce, Baseline::Optimal, LeaveOneOut),
    );
    assert_close(opt_loo.samples(), &[1.5, 1.0]);
}

#[test]
fn gpomdp_and_pgt_by_hand() {
    use BaselineFit::*;
    let b = two_by_two();
    for kind in [Kind::Gpomdp, Kind::Pgt] {
        let none = grad(&b, Param::V, spec(kind, Baseline::None, PlugIn));
        assert_close(none.samples(), &[2.5, 0.0]);
        // Per-step means b_0 = 1.5, b_1 = −0.25.
        let mean = grad(&b, Param::V, spec(kind, Baseline::Mean, PlugIn));
        assert_close(mean.samples(), &[1.75, 1.0]);
        // b_0 = (1·1 + 1·2)/2 = 1.5, b_1 = (9·0.5 − 4·1)/13 = 0.5/13.
        let opt = grad(&b, Param::V, spec(kind, Baseline::Optimal, PlugIn));
        assert_close(opt.samples(), &[11.5 / 13.0, 20.5 / 13.0]);
        // Leave-one-out: trajectory 1 uses b = (2, 1) from trajectory 2 (= its F since
        // S² ≠ 0), trajectory 2 uses b = (1, 0.5).
        let loo = grad(&b, Param::V, spec(kind, Baseline::Optimal, LeaveOneOut));
        assert_close(
            loo.samples(),
            &[
                1.0 * (1.0 - 2.0) + 3.0 * (0.5 + 1.0),
                -(2.0 - 1.0) - 2.0 * (-1.0 - 0.5),
            ],
        );
        // ∇_w J: w-scores (0.5, 0.5) and (1, 0).
        let w = grad(&b, Param::W, spec(kind, Baseline::None, PlugIn));
        assert_close(w.samples(), &[0.75, 2.0]);
    }
}

#[test]
fn sample_variance_by_hand() {
    let b = two_by_two();
    let none = grad(
        &b,
        Param::V,
        spec(Kind::Reinforce, Baseline::None, BaselineFit::PlugIn),
    );
    // Samples 4.5 and −2: variance (3.25² · 2)/1.
    assert_close(none.variance(), &[2.0 * 3.25 * 3.25]);
}

#[test]
fn h_by_hand() {
    use BaselineFit::*;
    let b = two_by_two();
    let run = |baseline, fit| {
        let mut est = Estimate::new();
        Estimator::new().h(&b, baseline, fit, &mut est).unwrap();
        est
    };
    // H = w-score / σ = (1, 1) and (2, 0); G = (1, 3) and (−1, −2).
    assert_close(run(Baseline::None, PlugIn).samples(), &[2.5, -4.0]);
    // b̃_0 = (1·2 + (−4)·1)/(4 + 1) = −0.4, b̃_1 = (1.5·4 + 0)/(16 + 4) = 0.3.
    assert_close(run(Baseline::Optimal, PlugIn).samples(), &[2.1, -3.0]);
    // Leave-one-out: trajectory 1 gets b̃ = (−4, 0), trajectory 2 gets (0.5, 0.375).
    assert_close(
        run(Baseline::Optimal, LeaveOneOut).samples(),
        &[10.5, -3.75],
    );
    // Mean: G H (F − ⟨F_t⟩) with ⟨F⟩ = (1.5, −0.25).
    assert_close(run(Baseline::Mean, PlugIn).samples(), &[1.75, -1.0]);
}

#[test]
fn mixed_derivative_by_hand() {
    let b = two_by_two();
    let mut est = Estimate::new();
    let s = spec(Kind::Gpomdp, Baseline::None, BaselineFit::PlugIn);
    Estimator::new().mixed(&b, s, &mut est).unwrap();
    // ĥ − (2/0.5) g = (2.5 − 4·2.5, −4 − 4·0).
    assert_close(est.samples(), &[-7.5, -4.0]);
}

#[test]
fn multi_action_pairs_by_hand() {
    // Two actions, one feature each: v = (v_0, v_1), σ = (1, 0.5), one step.
    let mut b = Batch::zeros(2, 1, 2, 2, 0.9);
    b.sigma.copy_from_slice(&[1.0, 0.5]);
    b.disc_rewards.copy_from_slice(&[1.0, 0.0]);
    b.cum_score_v.copy_from_slice(&[1.0, 2.0, 0.0, 0.0]);
    b.cum_score_w.copy_from_slice(&[1.0, 3.0, 0.0, 0.0]);
    let none = spec(Kind::Gpomdp, Baseline::None, BaselineFit::PlugIn);
    let mut h = Estimate::new();
    let mut est = Estimator::new();
    est.h(&b, Baseline::None, BaselineFit::PlugIn, &mut h)
        .unwrap();
    // Component j·dim_v + k = G_k H_j F with H = (1, 6).
    assert_close(h.sample(0).unwrap(), &[1.0, 2.0, 6.0, 12.0]);
    let mut mixed = Estimate::new();
    est.mixed(&b, none, &mut mixed).unwrap();
    // Own-action pairs (0,0) and (1,1) lose (2/σ_j) g_k: 1 − 2·1 and 12 − 4·2.
    assert_close(mixed.sample(0).unwrap(), &[-1.0, 2.0, 6.0, 4.0]);
}

#[test]
fn surrogate_gradient_by_hand() {
    // Four one-step trajectories, σ = 1, c = 2, ∂c/∂σ = −1, no baseline.
    let mut b = Batch::zeros(4, 1, 1, 1, 0.9);
    b.disc_rewards.copy_from_slice(&[2.0, 2.0, 2.0, 1.0]);
    b.cum_score_v.copy_from_slice(&[1.0, -0.5, 0.5, 1.0]);
    b.cum_score_w.copy_from_slice(&[0.5, 1.0, 0.0, 0.5]);
    let mut out = SurrogateEstimate::new();
    let s = spec(Kind::Gpomdp, Baseline::None, BaselineFit::PlugIn);
    Estimator::new()
        .surrogate_gradient(&b, s, 2.0, &[-1.0], &mut out)
        .unwrap();
    // g = (2, −1, 1, 1): g_A = 0.5, g_B = 1. ĥ = (1, −1, 0, 0.5), D = ĥ − 2g = (−3, 1, −2, −1.5):
    // D_A = −1, D_B = −1.75. ∇_w L = (1/8)(0.5·(−1.75) + 1·(−1) + 0.5·1·0.5) = −0.203125.
    assert_close(out.grad_w_l().mean(), &[-0.203125]);
    assert_close(&[out.surrogate()], &[0.0625]);
    // Linearisation at ḡ = 0.75, D̄ = −1.375: ∂/∂g = 2D̄ − 2ḡ(−1/2) = −2, ∂/∂D = 2ḡ = 1.5;
    // x_0 = f + (1/8)(−2·1.25 + 1.5·(−1.625)).
    let x0 = -0.203125 + (-2.0 * 1.25 + 1.5 * -1.625) / 8.0;
    assert_close(&out.grad_w_l().samples()[..1], &[x0]);
    assert_close(out.grad_v().samples(), &[2.0, -1.0, 1.0, 1.0]);
    assert_close(out.mixed().samples(), &[-3.0, 1.0, -2.0, -1.5]);
}

#[test]
fn zero_denominators_give_zero_baseline() {
    // All scores zero: every optimal-baseline denominator is 0.
    let mut b = Batch::zeros(3, 2, 1, 1, 0.9);
    b.disc_rewards
        .copy_from_slice(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    for kind in [Kind::Reinforce, Kind::Gpomdp, Kind::Pgt] {
        for fit in [BaselineFit::PlugIn, BaselineFit::LeaveOneOut] {
            let e = grad(&b, Param::V, spec(kind, Baseline::Optimal, fit));
            assert_eq!(e.samples(), &[0.0; 3]);
            assert_eq!(e.variance(), &[0.0]);
        }
    }
    let mut h = Estimate::new();
    Estimator::new()
        .h(&b, Baseline::Optimal, BaselineFit::LeaveOneOut, &mut h)
        .unwrap();
    assert_eq!(h.mean(), &[0.0]);
}

#[test]
fn invalid_batches_are_typed_errors() {
    let mut est = Estimate::new();
    let mut e = Estimator::new();
    let s = GradientSpec::default();
    assert_eq!(
        e.gradient(&Batch::zeros(0, 2, 1, 1, 0.9), Param::V, s, &mut est),
        Err(EstimatorError::EmptyBatch)
    );
    assert_eq!(
        e.gradient(&Batch::zeros(1, 2, 1, 1, 0.9), Param::V, s, &mut est),
        Err(EstimatorError::TooFewTrajectories { n: 1, min: 2 })
    );
    let mut short = two_by_two();
    short.cum_score_v.pop();
    assert!(matches!(
        e.gradient(&short, Param::V, s, &mut est),
        Err(EstimatorError::DimensionMismatch {
            what: "cum_score_v",
            ..
        })
    ));
    let mut nan = two_by_two();
    nan.disc_rewards[1] = f64::NAN;
    assert!(matches!(
        e.value(&nan, &mut est),
        Err(EstimatorError::NonFinite { .. })
    ));
    let mut inf = two_by_two();
    inf.cum_score_w[0] = f64::INFINITY;
    assert!(matches!(
        e.gradient(&inf, Param::W, s, &mut est),
        Err(EstimatorError::NonFinite { .. })
    ));
    let mut sig = two_by_two();
    sig.sigma[0] = 0.0;
    assert!(matches!(
        e.h(&sig, Baseline::None, BaselineFit::PlugIn, &mut est),
        Err(EstimatorError::InvalidSigma { .. })
    ));
    // Overflow inside the estimator is reported, not returned as NaN or ∞.
    let mut huge = two_by_two();
    huge.cum_score_v
        .copy_from_slice(&[1e200, 1e200, -1e200, 1e200]);
    assert!(matches!(
        e.gradient(
            &huge,
            Param::V,
            spec(Kind::Gpomdp, Baseline::Optimal, BaselineFit::PlugIn),
            &mut est
        ),
        Err(EstimatorError::NonFinite { .. })
    ));
    let mut out = SurrogateEstimate::new();
    assert_eq!(
        e.surrogate_gradient(&two_by_two(), s, 1.0, &[0.0], &mut out),
        Err(EstimatorError::TooFewTrajectories { n: 2, min: 4 })
    );
    let four = Batch::zeros(4, 1, 1, 1, 0.9);
    assert!(matches!(
        e.surrogate_gradient(&four, s, 0.0, &[0.0], &mut out),
        Err(EstimatorError::InvalidConstant { .. })
    ));
    assert!(matches!(
        e.surrogate_gradient(&four, s, 1.0, &[], &mut out),
        Err(EstimatorError::DimensionMismatch { .. })
    ));
}

/// Inputs found by the fuzz campaign (docs/RELIABILITY.md): each overflowed to ±∞ or panicked
/// before; each is now a typed error.
#[test]
fn overflowing_inputs_are_typed_errors() {
    use sepg_estimators::{QuantileError, Width, student_t_quantile, width};
    // A δ near the smallest positive f64 with a huge variance or range.
    let eb = Width::EmpiricalBernstein { range: 1e16 };
    assert!(width(eb, 93.35546875, 3, 2.2250738585072014e-308).is_ok_and(f64::is_finite));
    assert!(matches!(
        width(Width::Chebyshev, 1e308, 2, 5e-324),
        Err(EstimatorError::NonFinite { .. })
    ));
    let huge = Width::EmpiricalBernstein { range: 1e308 };
    assert!(matches!(
        width(huge, 1.0, 2, 0.5),
        Err(EstimatorError::NonFinite { .. })
    ));
    // The Cauchy quantile at the smallest positive probability is beyond f64.
    assert!(matches!(
        student_t_quantile(5e-324, 1.0),
        Err(QuantileError::Overflow { .. })
    ));
    // A batch whose shape overflows usize matches no buffer.
    let mut b = Batch::zeros(0, 4, 1, 1, 0.9);
    b.n = 1 << 63;
    let mut est = Estimate::new();
    assert!(matches!(
        Estimator::new().value(&b, &mut est),
        Err(EstimatorError::DimensionMismatch { .. })
    ));
}
