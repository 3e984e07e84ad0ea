use sepg_algo::core::options::{
    Accounting, Confidence, Lb1Requirement, VDirection, WDirection, WStep,
};
use sepg_mdp::rollout::ScoreAction;

use crate::error::Result;

use super::*;

fn lqg1d(f: impl FnOnce(&mut RunSpec)) -> Result<Resolved> {
    let mut spec = RunSpec {
        env: Some(EnvName::Lqg1d),
        iterations: Some(1),
        ..RunSpec::default()
    };
    f(&mut spec);
    spec.resolve()
}

#[test]
fn sizes_are_refused_at_resolution_exactly_above_their_limits() {
    // lqg1d, H = 20, one parameter of each kind: (20 · 3 + 1) · 8 = 488 bytes per
    // trajectory; 8 GiB = 8,589,934,592 bytes hold 17,602,324 of them
    // (8,589,934,112 bytes), one more needs 8,589,934,600.
    assert!(lqg1d(|s| s.batch = Some(17_602_324)).is_ok());
    let e = lqg1d(|s| s.batch = Some(17_602_325)).expect_err("too large");
    assert!(e.is_invalid_input(), "{e}");
    let e = lqg1d(|s| s.batch = Some(usize::MAX)).expect_err("overflow");
    assert!(e.to_string().contains("more than 2^64 bytes"), "{e}");
    assert!(lqg1d(|s| s.horizon = Some(MAX_HORIZON)).is_ok());
    let e = lqg1d(|s| s.horizon = Some(MAX_HORIZON + 1)).expect_err("horizon");
    assert!(e.is_invalid_input(), "{e}");
    let e = lqg1d(|s| s.iterations = Some(MAX_ITERATIONS + 1)).expect_err("iterations");
    assert!(e.is_invalid_input(), "{e}");
    // 2^30 returns of 8 bytes are exactly 8 GiB.
    assert!(lqg1d(|s| s.reference_batch = Some(1 << 30)).is_ok());
    assert!(lqg1d(|s| s.reference_batch = Some((1 << 30) + 1)).is_err());
}

#[test]
fn an_initial_policy_the_policy_cannot_represent_is_refused_at_resolution() {
    // w = ln σ must satisfy |w| < 354: ln(1e153) = 352.3 passes, ln(1e154) = 354.6 not.
    assert!(lqg1d(|s| s.sigma0 = Some(Values::One(1e153))).is_ok());
    for sigma in [1e154, 1e300, 1e-154] {
        let e = lqg1d(|s| s.sigma0 = Some(Values::One(sigma))).expect_err("refused");
        assert!(
            e.is_invalid_input() && e.to_string().contains("sigma0"),
            "{e}"
        );
    }
}

#[test]
fn resolving_a_resolved_configuration_changes_nothing() {
    let spec = RunSpec {
        env: Some(EnvName::Lqg1d),
        algo: Some(AlgoName::GpomdpAdam),
        lr: Some(1e-5),
        sigma0: Some(Values::One(0.1)),
        ..RunSpec::default()
    };
    let once = spec.resolve().expect("valid");
    let text = once.toml().expect("toml");
    let again: RunSpec = toml::from_str(&text).expect("parse");
    let twice = again.resolve().expect("valid");
    assert_eq!(once.spec, twice.spec);
    assert_eq!(once.checked, twice.checked);
    assert_eq!(twice.spec.lr_w, Some(1e-5));
}

#[test]
fn inapplicable_options_are_rejected() {
    let spec = RunSpec {
        algo: Some(AlgoName::SepgZv),
        alpha: Some(0.1),
        ..RunSpec::default()
    };
    assert!(spec.resolve().is_err());
    let spec = RunSpec {
        gradients: Some(GradientsName::Exact),
        delta: Some(0.1),
        ..RunSpec::default()
    };
    assert!(spec.resolve().is_err());
    let spec = RunSpec {
        algo: Some(AlgoName::GpomdpConst),
        ..RunSpec::default()
    };
    assert!(spec.resolve().is_err());
}

/// Every SEPG option reaches the algorithm's configuration, is written back into the
/// resolved specification, and survives a round trip through config.toml.
#[test]
fn sepg_options_resolve_and_round_trip() {
    let spec = RunSpec {
        env: Some(EnvName::Lqg1d),
        algo: Some(AlgoName::SepgLb1),
        w_step: Some(WStepName::Theorem49),
        w_direction: Some(WDirectionName::Metagradient),
        metagradient_clip: Some(50.0),
        confidence: Some(ConfidenceName::StudentT),
        quantile_factor: Some(2.0),
        lb1_requirement: Some(Lb1Name::Full),
        alternating: Some(true),
        accounting: Some(AccountingName::Estimated),
        reference_batch: Some(0),
        gamma: Some(0.9),
        r_max: Some(30.0),
        psi: Some(0.53),
        scores: Some(ScoresName::Clipped),
        ..RunSpec::default()
    };
    let once = spec.resolve().expect("valid");
    assert_eq!(once.checked.config().score_action, ScoreAction::Clipped);
    let o = once.checked.config().options;
    assert_eq!(o.w_step, WStep::Theorem49);
    assert_eq!(o.w_direction, WDirection::Metagradient { clip: 50.0 });
    assert_eq!(o.confidence, Confidence::StudentT { factor: 2.0 });
    assert_eq!(o.lb1_requirement, Lb1Requirement::Full);
    assert!(o.alternating);
    assert_eq!(o.accounting, Accounting::Estimated);
    assert_eq!(o.reference_batch, 0);
    assert_eq!(once.checked.constants().gamma(), 0.9);
    assert_eq!(once.checked.constants().r_max(), 30.0);
    assert_eq!(once.checked.constants().psi_override(), Some(0.53));
    assert_eq!(once.spec.m_phi, None);
    let text = once.toml().expect("toml");
    assert!(text.contains("w-step = \"theorem-4.9\"") && text.contains("quantile-factor = 2.0"));
    assert!(text.contains("psi = 0.53"), "{text}");
    assert!(text.contains("scores = \"clipped\""), "{text}");
    let again: RunSpec = toml::from_str(&text).expect("parse");
    let twice = again.resolve().expect("valid");
    assert_eq!(once.spec, twice.spec);
    assert_eq!(once.checked, twice.checked);
    // The defaults are written out too.
    let plain = RunSpec {
        algo: Some(AlgoName::SepgZv),
        ..RunSpec::default()
    }
    .resolve()
    .expect("valid");
    assert_eq!(plain.spec.w_step, Some(WStepName::Exploring));
    assert_eq!(plain.spec.confidence, Some(ConfidenceName::SubGaussian));
    assert_eq!(plain.spec.reference_batch, Some(1000));
    assert_eq!(plain.spec.lb1_requirement, None);
    assert_eq!(plain.checked.constants().psi_override(), None);
    assert_eq!(plain.spec.scores, Some(ScoresName::Raw));
    assert_eq!(plain.checked.config().score_action, ScoreAction::Raw);
}

#[test]
fn sepg_options_that_do_not_apply_are_rejected() {
    let bad = [
        RunSpec {
            algo: Some(AlgoName::GpomdpAdam),
            lr: Some(1e-3),
            w_step: Some(WStepName::Exploring),
            ..RunSpec::default()
        },
        RunSpec {
            algo: Some(AlgoName::SepgZv),
            lb1_requirement: Some(Lb1Name::Full),
            ..RunSpec::default()
        },
        RunSpec {
            algo: Some(AlgoName::SepgZv),
            alternating: Some(true),
            ..RunSpec::default()
        },
        RunSpec {
            algo: Some(AlgoName::SepgZv),
            metagradient_clip: Some(1.0),
            ..RunSpec::default()
        },
        RunSpec {
            algo: Some(AlgoName::SepgZv),
            confidence: Some(ConfidenceName::None),
            quantile_factor: Some(2.0),
            ..RunSpec::default()
        },
        RunSpec {
            gradients: Some(GradientsName::Exact),
            reference_batch: Some(10),
            ..RunSpec::default()
        },
        RunSpec {
            gradients: Some(GradientsName::Exact),
            scores: Some(ScoresName::Clipped),
            ..RunSpec::default()
        },
        RunSpec {
            algo: Some(AlgoName::SepgNaiveW),
            w_direction: Some(WDirectionName::PlugIn),
            ..RunSpec::default()
        },
    ];
    for spec in bad {
        assert!(spec.resolve().is_err(), "{spec:?}");
    }
}

/// The constants family: tight by default with the preset's reward sign and the run's
/// horizon, the thesis's on request; `rewards` only with the tight family, and
/// non-positive refused on Mountain Car; every choice survives config.toml.
#[test]
fn the_constants_family_resolves_and_round_trips() {
    use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
    let tight = |h, r| Family::Tight(Tight::new(Horizon::Finite(h), r));
    let cases = [
        (RunSpec::default(), tight(20, Rewards::NonPositive)),
        (
            RunSpec {
                env: Some(EnvName::MountainCar),
                horizon: Some(30),
                ..RunSpec::default()
            },
            tight(30, Rewards::TwoSided),
        ),
        (
            RunSpec {
                rewards: Some(RewardsName::TwoSided),
                algo: Some(AlgoName::Adastep),
                ..RunSpec::default()
            },
            tight(20, Rewards::TwoSided),
        ),
        (
            RunSpec {
                constants: Some(ConstantsName::Thesis),
                r_max: Some(3.0),
                ..RunSpec::default()
            },
            Family::Thesis,
        ),
    ];
    for (spec, family) in cases {
        let once = spec.resolve().expect("valid");
        assert_eq!(once.checked.constants().family(), family, "{spec:?}");
        let again: RunSpec = toml::from_str(&once.toml().expect("toml")).expect("parse");
        let twice = again.resolve().expect("valid");
        assert_eq!(once.spec, twice.spec);
        assert_eq!(once.checked, twice.checked);
    }
    for bad in [
        RunSpec {
            constants: Some(ConstantsName::Thesis),
            rewards: Some(RewardsName::TwoSided),
            ..RunSpec::default()
        },
        RunSpec {
            env: Some(EnvName::MountainCar),
            rewards: Some(RewardsName::NonPositive),
            ..RunSpec::default()
        },
    ] {
        assert!(bad.resolve().is_err(), "{bad:?}");
    }
}

/// Safe Adam: the TOML keys build the algorithm's `VDirection::Adam` with the usual betas
/// by default, survive config.toml, and are refused without `v_direction = "adam"`, without
/// a learning rate, with the thesis's constants, with the estimated accounting and for the
/// comparison algorithms.
#[test]
fn the_adam_v_direction_resolves_round_trips_and_is_refused_where_unproven() {
    let spec: RunSpec = toml::from_str(
        "algo = \"sepg-mi\"\nv-direction = \"adam\"\nadam-lr = 0.1\nadam-beta2 = 0.99\n",
    )
    .expect("parse");
    let once = spec.resolve().expect("valid");
    assert_eq!(
        once.checked.config().options.v_direction,
        VDirection::Adam {
            lr: 0.1,
            beta1: 0.9,
            beta2: 0.99,
            eps: 1e-8
        }
    );
    let again: RunSpec = toml::from_str(&once.toml().expect("toml")).expect("parse");
    let twice = again.resolve().expect("valid");
    assert_eq!(once.spec, twice.spec);
    assert_eq!(once.checked, twice.checked);
    let greedy = RunSpec::default().resolve().expect("valid");
    assert_eq!(greedy.spec.v_direction, Some(VDirectionName::Greedy));
    assert_eq!(
        greedy.checked.config().options.v_direction,
        VDirection::Greedy
    );
    let adam = |more: RunSpec| RunSpec {
        v_direction: Some(VDirectionName::Adam),
        adam_lr: Some(0.1),
        ..more
    };
    for bad in [
        RunSpec {
            adam_lr: Some(0.1),
            ..RunSpec::default()
        },
        RunSpec {
            v_direction: Some(VDirectionName::Greedy),
            adam_eps: Some(1e-6),
            ..RunSpec::default()
        },
        RunSpec {
            v_direction: Some(VDirectionName::Adam),
            ..RunSpec::default()
        },
        adam(RunSpec {
            constants: Some(ConstantsName::Thesis),
            ..RunSpec::default()
        }),
        adam(RunSpec {
            accounting: Some(AccountingName::Estimated),
            ..RunSpec::default()
        }),
        adam(RunSpec {
            algo: Some(AlgoName::Adastep),
            ..RunSpec::default()
        }),
        adam(RunSpec {
            adam_beta1: Some(1.0),
            ..RunSpec::default()
        }),
    ] {
        assert!(bad.resolve().is_err(), "{bad:?}");
    }
}

#[test]
fn algorithm_names_are_the_configuration_names() {
    for algo in AlgoName::ALL {
        let spec = RunSpec {
            algo: Some(algo),
            ..RunSpec::default()
        };
        let text = toml::to_string(&spec).expect("toml");
        assert_eq!(text.trim(), format!("algo = \"{}\"", algo.name()));
    }
}
