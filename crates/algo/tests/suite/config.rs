//! Bad configurations are rejected before the run with typed errors.
use sepg_algo::core::config::{Algorithm, GradientMode, Requirement, SepgConfig};
use sepg_algo::core::error::ConfigError;
use sepg_mdp::env::Preset;

fn base() -> SepgConfig {
    SepgConfig::new(Preset::Lqg1d.build(), Algorithm::Sepg(Requirement::Zv))
}

#[test]
fn default_configuration_is_valid() {
    assert!(base().check().is_ok());
}

#[test]
fn nu_outside_unit_interval_is_rejected() {
    for nu in [-0.1, 1.5, f64::NAN] {
        for alg in [
            Algorithm::Sepg(Requirement::LbI { nu }),
            Algorithm::Sepg(Requirement::Sim { nu }),
        ] {
            let cfg = SepgConfig {
                algorithm: alg,
                ..base()
            };
            assert!(
                matches!(cfg.check(), Err(ConfigError::NuOutOfRange { .. })),
                "{alg:?}"
            );
        }
    }
}

#[test]
fn too_few_trajectories_for_the_blocks_is_rejected() {
    // ZV runs 3 blocks, each estimating with at least 4 (∇_w L is cross-fitted on halves).
    let cfg = SepgConfig {
        n_trajectories: 11,
        ..base()
    };
    assert_eq!(
        cfg.check().unwrap_err(),
        ConfigError::TooFewTrajectories {
            n: 11,
            blocks: 3,
            per_block: 4
        }
    );
    assert!(
        SepgConfig {
            n_trajectories: 12,
            ..base()
        }
        .check()
        .is_ok()
    );
    // A single-block comparison algorithm needs 2.
    let adam = SepgConfig {
        algorithm: Algorithm::adam(1e-3, 0.0),
        n_trajectories: 1,
        ..base()
    };
    assert!(matches!(
        adam.check(),
        Err(ConfigError::TooFewTrajectories { .. })
    ));
}

#[test]
fn bad_sigma_delta_iterations_horizon_budget_are_rejected() {
    for s in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let cfg = SepgConfig {
            sigma0: vec![s],
            ..base()
        };
        assert!(matches!(
            cfg.check(),
            Err(ConfigError::InvalidSigma { index: 0, .. })
        ));
    }
    for delta in [0.0, 1.0, -0.5, f64::NAN] {
        let cfg = SepgConfig {
            gradient: GradientMode::Sampled { delta },
            ..base()
        };
        assert!(matches!(cfg.check(), Err(ConfigError::InvalidDelta { .. })));
    }
    let cfg = SepgConfig {
        iterations: 0,
        ..base()
    };
    assert_eq!(cfg.check().unwrap_err(), ConfigError::ZeroIterations);
    let cfg = SepgConfig {
        horizon: 0,
        ..base()
    };
    assert_eq!(cfg.check().unwrap_err(), ConfigError::ZeroHorizon);
    for b in [-1.0, f64::NAN, f64::INFINITY] {
        let cfg = SepgConfig {
            initial_budget: b,
            ..base()
        };
        assert!(matches!(
            cfg.check(),
            Err(ConfigError::InvalidBudget { .. })
        ));
    }
}

#[test]
fn wrong_lengths_and_non_finite_mean_are_rejected() {
    let cfg = SepgConfig {
        v0: vec![0.0, 0.0],
        ..base()
    };
    assert!(matches!(
        cfg.check(),
        Err(ConfigError::DimensionMismatch {
            what: "v0",
            expected: 1,
            got: 2
        })
    ));
    let cfg = SepgConfig {
        v0: vec![f64::NAN],
        ..base()
    };
    assert!(matches!(
        cfg.check(),
        Err(ConfigError::InvalidMean { index: 0, .. })
    ));
}

#[test]
fn bad_hyper_parameters_are_rejected() {
    for alg in [
        Algorithm::GpomdpConst {
            alpha: 0.0,
            beta: 0.0,
        },
        Algorithm::GpomdpConst {
            alpha: 1e-3,
            beta: -1.0,
        },
        Algorithm::adam(-1.0, 0.0),
        Algorithm::GpomdpAdam {
            lr_v: 1e-3,
            lr_w: 0.0,
            beta1: 1.0,
            beta2: 0.999,
            epsilon: 1e-8,
        },
        Algorithm::GpomdpAdam {
            lr_v: 1e-3,
            lr_w: 0.0,
            beta1: 0.9,
            beta2: 0.999,
            epsilon: 0.0,
        },
    ] {
        let cfg = SepgConfig {
            algorithm: alg,
            ..base()
        };
        assert!(
            matches!(cfg.check(), Err(ConfigError::InvalidHyperParameter { .. })),
            "{alg:?}"
        );
    }
}

#[test]
fn exact_mode_needs_an_exact_oracle() {
    let cfg = SepgConfig {
        gradient: GradientMode::Exact,
        ..SepgConfig::new(
            Preset::MountainCar.build(),
            Algorithm::Sepg(Requirement::Zv),
        )
    };
    assert!(matches!(
        cfg.check(),
        Err(ConfigError::ExactUnsupported { .. })
    ));
}
