//! The process-wide cancellation request (`sepg_mdp::cancel`): once raised, every rollout,
//! streamed estimate and clipped dynamic programme returns its `Cancelled` error; once
//! cleared, each returns exactly what it returned before the request, bit for bit.
//!
//! The request is global to the process, so this file holds a single test (its own test
//! binary): no other test can observe the raised flag.

use sepg_mdp::cancel;
use sepg_mdp::env::LqgEnv;
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::monte_carlo::{McError, stream_returns};
use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon, OracleError};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::{RolloutError, rollout, rollout_returns};

#[test]
fn a_cancelled_computation_fails_and_a_cleared_request_changes_no_bit() {
    let env = LqgEnv::thesis();
    let policy = GaussianPolicy::scalar(-0.4, (0.5f64).ln()).expect("policy");
    let key = SeedKey::new(7, 3, 1);
    // Several chunks of trajectories, so that the parallel path runs too.
    let n = 1000;
    let oracle = ClippedDpOracle::new(&LqgModel::thesis()).expect("oracle");
    let gaussian = Exploration::Gaussian {
        w: vec![(0.5f64).ln()],
    };
    let batch = rollout(&env, &policy, n, 20, key).expect("rollout");
    let returns = rollout_returns(&env, &policy, n, 20, key).expect("returns");
    let streamed = stream_returns(&env, &policy, n, 20, key).expect("stream");
    let exact = oracle
        .evaluate(&[-0.4], &gaussian, Horizon::Finite(20))
        .expect("dp");

    cancel::request();
    assert!(cancel::requested());
    assert_eq!(
        rollout(&env, &policy, n, 20, key).map(|_| ()),
        Err(RolloutError::Cancelled)
    );
    assert_eq!(
        rollout(&env, &policy, 3, 20, key).map(|_| ()),
        Err(RolloutError::Cancelled),
        "a batch of a single chunk too"
    );
    assert_eq!(
        rollout_returns(&env, &policy, n, 20, key).map(|_| ()),
        Err(RolloutError::Cancelled)
    );
    assert!(matches!(
        stream_returns(&env, &policy, n, 20, key),
        Err(McError::Rollout(RolloutError::Cancelled))
    ));
    for exploration in [gaussian.clone(), Exploration::Deterministic] {
        assert_eq!(
            oracle
                .evaluate(&[-0.4], &exploration, Horizon::Finite(20))
                .map(|_| ()),
            Err(OracleError::Cancelled)
        );
    }

    cancel::clear();
    assert!(!cancel::requested());
    assert_eq!(rollout(&env, &policy, n, 20, key).expect("rollout"), batch);
    assert_eq!(
        rollout_returns(&env, &policy, n, 20, key).expect("returns"),
        returns
    );
    let again = stream_returns(&env, &policy, n, 20, key).expect("stream");
    assert_eq!(format!("{again:?}"), format!("{streamed:?}"));
    assert_eq!(
        oracle
            .evaluate(&[-0.4], &gaussian, Horizon::Finite(20))
            .expect("dp"),
        exact
    );
}
