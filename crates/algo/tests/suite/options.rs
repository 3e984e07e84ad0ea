//! The SEPG options (`sepg_algo::core::options`): the exploring w-update against Theorem
//! 4.9, the reference batch of J(θ⁰), alternating iterations, the plug-in and metagradient
//! directions, constant overrides and the configuration errors of options that do not apply.
//! About 3 s in release.
use crate::suite::common::{exact, lqg, lqg1d, run};
use approx::assert_relative_eq;
use sepg_algo::core::config::{Algorithm, GradientMode, Requirement, SepgConfig};
use sepg_algo::core::error::ConfigError;
use sepg_algo::core::options::{
    Confidence, ConstantOverrides, Lb1Requirement, SepgOptions, WDirection, WStep,
};
use sepg_algo::core::record::Record;
use sepg_algo::core::seed::Block;
use sepg_estimators::student_t_quantile;
use sepg_mdp::env::{AnyEnv, Environment};
use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon, Needs};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rollout::rollout_returns_into;

const LB1: Requirement = Requirement::LbI { nu: 0.5 };

fn sampled(req: Requirement, sigma0: f64, options: SepgOptions) -> SepgConfig {
    SepgConfig {
        sigma0: vec![sigma0],
        seed: 3,
        options,
        ..SepgConfig::new(lqg1d(true), Algorithm::Sepg(req))
    }
}

fn share(records: &[Record], f: impl Fn(&Record) -> bool) -> f64 {
    records.iter().filter(|r| f(r)).count() as f64 / records.len() as f64
}

/// The exploring w-update never skips a block and every feasible step guarantees its
/// requirement (the logged bound is re-evaluated by sepg-algo at the chosen step); with
/// Theorem 4.9 most w-blocks are below noise (80% over 2000 iterations of this setting,
/// seed 0, when measured; at least half is asserted).
#[test]
fn exploring_w_step_moves_where_theorem_4_9_does_not() {
    let (records, _) = run(sampled(LB1, 1.0, SepgOptions::estimated()), 200);
    assert_eq!(share(&records, |r| r.below_noise_w), 0.0);
    let mut checked = 0;
    for r in records.iter().filter(|r| !r.infeasible_w) {
        let (g, c) = (r.guaranteed_w.expect("a w-step"), r.required_w.expect("C"));
        assert!(
            g >= c - 1e-9 * c.abs(),
            "iteration {}: {g} < {c}",
            r.iteration
        );
        checked += 1;
    }
    assert!(checked > 100);
    let thesis = SepgOptions {
        w_step: WStep::Theorem49,
        ..SepgOptions::estimated()
    };
    let (records, _) = run(sampled(LB1, 1.0, thesis), 200);
    assert!(share(&records, |r| r.below_noise_w) > 0.5);
}

/// The reference batch: LB-I's first requirement is (1 − ν)(Û⁰ − Ĵ), with Û⁰ recomputed here
/// from the reference trajectories' returns and the one-sided Student-t quantile.
#[test]
fn reference_batch_is_an_upper_confidence_bound_on_j0() {
    let cfg = sampled(LB1, 1.0, SepgOptions::estimated());
    let (records, state) = run(cfg.clone(), 1);
    let n = SepgOptions::estimated().reference_batch;
    let policy = GaussianPolicy::scalar(-0.1, 0.0).expect("policy");
    let mut returns = Vec::new();
    rollout_returns_into(
        &cfg.env,
        &policy,
        n,
        cfg.horizon,
        Block::Reference.key(cfg.seed, 0),
        &mut returns,
    )
    .expect("rollout");
    let nf = n as f64;
    let mean = returns.iter().sum::<f64>() / nf;
    let var = returns.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (nf - 1.0);
    let upper = mean + student_t_quantile(0.8, nf - 1.0).expect("quantile") * (var / nf).sqrt();
    assert_relative_eq!(state.j0.expect("J(θ⁰)"), upper, max_relative = 1e-12);
    let expected = 0.5 * (upper - records[0].j_exploratory);
    let got = records[0].required_v.expect("C");
    assert_relative_eq!(got, expected, max_relative = 1e-12);
    assert_eq!(records[0].trajectories, 100 + n as u64);
    // Without it, J(θ⁰) is the first v-block's estimate and the first requirement is 0.
    let plain = SepgOptions {
        reference_batch: 0,
        ..SepgOptions::estimated()
    };
    let (records, _) = run(sampled(LB1, 1.0, plain), 1);
    assert_eq!(records[0].required_v, Some(0.0));
}

/// Alternating LB-I with exact gradients on the clipped DP: even iterations move only v, odd
/// ones only w, and J(θᵗ) ≥ J(θ⁰) throughout (each half-step keeps the guarantee).
#[test]
fn alternating_lb1_moves_one_block_at_a_time_and_keeps_j0() {
    for lb1_requirement in [Lb1Requirement::Split, Lb1Requirement::Full] {
        let cfg = SepgConfig {
            options: SepgOptions {
                alternating: true,
                lb1_requirement,
                ..SepgOptions::estimated()
            },
            ..exact(lqg(true), Algorithm::Sepg(LB1), 1.0)
        };
        let (records, _) = run(cfg, 200);
        let j0 = records[0].j_exploratory;
        for (a, b) in records.iter().zip(&records[1..]) {
            if a.iteration.is_multiple_of(2) {
                assert!(a.beta == 0.0 && b.w == a.w && b.v != a.v);
            } else {
                assert!(a.alpha == 0.0 && b.v == a.v);
            }
            assert!(
                b.j_exploratory >= j0 - 1e-9 * j0.abs(),
                "{lb1_requirement:?}"
            );
        }
        assert!(records.iter().any(|r| r.w[0] != 0.0));
    }
    let cfg = SepgConfig {
        options: SepgOptions {
            alternating: true,
            ..SepgOptions::estimated()
        },
        ..sampled(Requirement::Mi, 1.0, SepgOptions::estimated())
    };
    let (records, _) = run(cfg, 4);
    assert_eq!(records[3].trajectories, 400);
}

/// With exact gradients the plug-in ∇_w L is the exact ∇_w L, so the run equals the default
/// (cross-fitted) one to rounding.
#[test]
fn plug_in_direction_is_exact_with_exact_gradients() {
    let base = exact(lqg1d(true), Algorithm::Sepg(LB1), 0.5);
    let plug = SepgConfig {
        options: SepgOptions {
            w_direction: WDirection::PlugIn,
            ..SepgOptions::estimated()
        },
        ..base.clone()
    };
    let ((a, _), (b, _)) = (run(base, 30), run(plug, 30));
    for (x, y) in a.iter().zip(&b) {
        for (p, q) in x.v.iter().chain(&x.w).zip(y.v.iter().chain(&y.w)) {
            assert_relative_eq!(p, q, epsilon = 1e-12, max_relative = 1e-12);
        }
    }
    assert!(a.last().expect("records").w[0] != a[0].w[0]);
}

/// The metagradient direction m = ∇_w J + 2α‖∇_v J‖² + clip(2σα⟨∇_v J, ∂_σ∇_v J⟩, ±100),
/// recomputed from the DP oracle at (v¹, w⁰) with the logged α: Δw = β·m.
#[test]
fn metagradient_direction_matches_its_formula() {
    let cfg = SepgConfig {
        options: SepgOptions {
            w_direction: WDirection::Metagradient { clip: 100.0 },
            ..SepgOptions::estimated()
        },
        ..exact(lqg(true), Algorithm::Sepg(LB1), 1.0)
    };
    let AnyEnv::Lqg(env) = &cfg.env else {
        unreachable!()
    };
    let oracle = ClippedDpOracle::new(env.model()).expect("oracle");
    let (records, state) = run(cfg.clone(), 1);
    let r = &records[0];
    let e = oracle
        .evaluate_with(
            &state.v,
            &Exploration::Gaussian { w: r.w.clone() },
            Horizon::Finite(cfg.horizon),
            Needs::SEPG,
        )
        .expect("oracle");
    let (g, alpha, sigma) = (e.grad_v[0], r.alpha, r.sigma[0]);
    let mixed_sigma = e.mixed_wv[0] / sigma;
    let m = e.grad_w[0]
        + 2.0 * alpha * g * g
        + (2.0 * sigma * alpha * g * mixed_sigma).clamp(-100.0, 100.0);
    let dw = state.w[0] - r.w[0];
    assert!(dw != 0.0);
    assert_relative_eq!(dw, r.beta * m, max_relative = 1e-9);
}

#[test]
fn overrides_reach_the_bounds_and_the_environment() {
    let cfg = SepgConfig {
        options: SepgOptions {
            overrides: ConstantOverrides {
                gamma: Some(0.9),
                r_max: Some(10.0),
                m_phi: None,
                action_volume: Some(3.0),
                psi: Some(0.53),
            },
            ..SepgOptions::estimated()
        },
        ..sampled(LB1, 1.0, SepgOptions::estimated())
    };
    let checked = cfg.check().expect("valid");
    let k = checked.constants();
    assert_eq!(
        (k.gamma(), k.r_max(), k.m_phi(), k.action_volume()),
        (0.9, 10.0, 4.0, 3.0)
    );
    // d = R/(1 − γ)² (ψ|A|/(2σ) + γ/(1 − γ)) with ψ = 0.53, computed by hand at σ = 1.
    let d = sepg_bounds::constants::d(k, 1.0).expect("d");
    let expected = 10.0 / 0.01 * (0.53 * 3.0 / 2.0 + 9.0);
    assert_relative_eq!(d, expected, max_relative = 1e-9);
    assert_eq!(checked.config().env.constants().gamma, 0.9);
}

#[test]
fn options_that_do_not_apply_are_rejected() {
    let alternating = SepgOptions {
        alternating: true,
        ..SepgOptions::estimated()
    };
    let bad = [
        sampled(Requirement::Zv, 1.0, alternating),
        sampled(
            LB1,
            1.0,
            SepgOptions {
                confidence: Confidence::StudentT { factor: -1.0 },
                ..SepgOptions::estimated()
            },
        ),
        sampled(
            LB1,
            1.0,
            SepgOptions {
                reference_batch: 1,
                ..SepgOptions::estimated()
            },
        ),
        sampled(
            LB1,
            1.0,
            SepgOptions {
                overrides: ConstantOverrides {
                    gamma: Some(1.0),
                    ..ConstantOverrides::default()
                },
                ..SepgOptions::estimated()
            },
        ),
        SepgConfig {
            gradient: GradientMode::Sampled { delta: 0.2 },
            options: alternating,
            ..SepgConfig::new(lqg(true), Algorithm::adam(1e-3, 1e-3))
        },
    ];
    for cfg in bad {
        let e = cfg.check().expect_err("rejected");
        assert!(matches!(
            e,
            ConfigError::UnsupportedOption { .. }
                | ConfigError::InvalidHyperParameter { .. }
                | ConfigError::Environment(_)
        ));
    }
}
