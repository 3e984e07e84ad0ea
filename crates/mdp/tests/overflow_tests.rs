//! Regressions found by the robustness property test of the workspace (`tests/robustness.rs`):
//! finite but extreme inputs used to overflow into ±∞ or NaN that public functions returned
//! as values. Each now gives a typed error.

use approx::assert_abs_diff_eq;
use nalgebra::DVector;
use sepg_mdp::env::LqgEnv;
use sepg_mdp::features::{FeatureError, RbfGrid};
use sepg_mdp::lqg_model::{LqgModel, ModelError};
use sepg_mdp::monte_carlo::summarize;
use sepg_mdp::oracle::{ClosedFormOracle, OracleError};
use sepg_mdp::policy::{GaussianPolicy, PolicyError};
use sepg_mdp::rng::{SeedKey, rng_from_seed};
use sepg_mdp::rollout::{RolloutError, mean_return, rollout, rollout_returns};

fn non_finite<T: std::fmt::Debug>(r: Result<T, PolicyError>) {
    assert!(matches!(r, Err(PolicyError::NonFinite { .. })), "{r:?}");
}

#[test]
fn policy_outputs_that_overflow_are_errors() {
    // μ = Σ v_i φ_i = 1e300·1e300 − 1e300·1e300 = ∞ − ∞ = NaN before the fix.
    let p = GaussianPolicy::new(vec![1e300, 1e300], vec![0.0], 2).unwrap();
    let mut mu = [0.0];
    non_finite(p.mean(&[1e300, -1e300], &mut mu));
    // Finite μ, but (a − μ)² overflows.
    let p = GaussianPolicy::scalar(1.0, 0.0).unwrap();
    non_finite(p.log_density(&[1.0], &[1.7e308]));
    let mut g = [0.0];
    non_finite(p.score_w(&[1.0], &[1.7e308], &mut g));
    non_finite(p.score_v(&[1e300], &[-1.7e308], &mut g));
    let mut rng = rng_from_seed(0);
    non_finite(
        GaussianPolicy::scalar(1e300, 0.0)
            .unwrap()
            .sample(&[1e300], &mut rng, &mut g),
    );
    // Ordinary inputs are unaffected.
    assert_eq!(p.score_w(&[1.0], &[3.0], &mut g).map(|()| g[0]), Ok(3.0));
}

#[test]
fn rbf_grids_wider_than_f64_are_rejected() {
    // high − low = ∞: the widths were 0 and the features NaN.
    let r = RbfGrid::new(&[-1.7e308], &[1.7e308], &[3], false);
    assert!(matches!(r, Err(FeatureError::NonFinite { .. })), "{r:?}");
    // A spacing whose inverse overflows.
    let r = RbfGrid::new(&[0.0], &[5e-324], &[1], false);
    assert!(matches!(r, Err(FeatureError::NonFinite { .. })), "{r:?}");
    // The box width fits but a centre low + h·j rounds past f64::MAX.
    match RbfGrid::new(&[-f64::MAX], &[1e16], &[4], false) {
        Ok(g) => assert!(g.centres().iter().all(|c| c.is_finite()), "{g:?}"),
        Err(e) => assert!(matches!(e, FeatureError::NonFinite { .. }), "{e:?}"),
    }
}

#[test]
fn models_whose_bound_constants_overflow_are_rejected() {
    // R_max = Q s² + R a² = ∞ with finite coefficients.
    let r = LqgModel::scalar(1.0, 1.0, 1e300, 1.0, 1e10);
    assert!(matches!(r, Err(ModelError::NonFinite { .. })), "{r:?}");
}

#[test]
fn spectral_radius_overflow_is_an_error() {
    let model = LqgModel::scalar(1.0, 1e300, 1.0, 1.0, 1.0)
        .unwrap()
        .with_clipping(false);
    let o = ClosedFormOracle::new(&model).unwrap();
    assert_eq!(
        o.scaled_spectral_radius(&[1e300]),
        Err(OracleError::Overflow)
    );
}

#[test]
fn diverging_rollouts_are_errors() {
    // Unclipped s' = 1e154 s + a: the state overflows within a few steps.
    let model = LqgModel::scalar(1e154, 1.0, 1.0, 1.0, 1.0)
        .unwrap()
        .with_clipping(false)
        .with_noise(DVector::from_element(1, 0.0))
        .unwrap();
    let env = LqgEnv::new(model).unwrap();
    let p = GaussianPolicy::scalar(0.0, 0.0).unwrap();
    let key = SeedKey::new(1, 0, 0);
    assert_eq!(rollout(&env, &p, 4, 6, key), Err(RolloutError::NonFinite));
    assert_eq!(
        rollout_returns(&env, &p, 4, 6, key),
        Err(RolloutError::NonFinite)
    );
    assert_eq!(
        mean_return(&env, &p, 4, 6, key),
        Err(RolloutError::NonFinite)
    );
}

#[test]
fn confidence_levels_within_an_ulp_of_one_keep_a_finite_interval() {
    // 0.5 + 0.5·level rounded to 1, so z was ∞ and the interval (−∞, ∞).
    let level = 1.0 - f64::EPSILON / 2.0;
    let e = summarize(&[57.0, 0.0, 1e-154, -44.0], level).unwrap();
    assert!(
        e.ci_low.is_finite() && e.ci_high.is_finite() && e.ci_low < e.mean,
        "{e:?}"
    );
    // z(1 − 2^-53) ≈ 8.29 (normal upper quantile of 5.55e-17).
    let z = (e.ci_high - e.mean) / e.std_error;
    assert_abs_diff_eq!(z, 8.292, epsilon = 1e-3);
    // Overflow of mean ± z·SE is an error.
    assert!(summarize(&[f64::MAX, -f64::MAX, f64::MAX], 0.95).is_err());
}
