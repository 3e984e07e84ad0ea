//! `Penalties`: c and d of the thesis family evaluated once, against the printed formulas and
//! bit for bit against `constants::{c, d}`, with the same errors; the `_at` step functions
//! give the outcomes of the functions that take (k, σ).

use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use sepg_bounds::constants::{self, TaskConstants};
use sepg_bounds::exploring::{self, ExploringBound};
use sepg_bounds::high_probability::{self as hp, HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::penalties::{Horizon, Rewards, Tight};
use sepg_bounds::{BoundsError, Family, Penalties, papini, pirotta, v_update, w_update};

use super::common::c_ref;

#[test]
fn thesis_family_is_c_and_d_of_the_printed_formulas() {
    let k = TaskConstants::new(0.5, 1.0, 1.0, 1.0).expect("valid");
    let p = Penalties::new(&k, 1.0).expect("valid");
    // c = R M²/((1−γ)²σ²)·(|A|/(√(2π)σ) + γ/(2(1−γ))) = 4(1/√(2π) + 1/2)
    let c = 4.0 * (1.0 / (2.0 * std::f64::consts::PI).sqrt() + 0.5);
    assert!((p.c().expect("finite") - c).abs() < 1e-14);
    // d = R/(1−γ)²·(ψ|A|/(2σ) + γ/(1−γ)) = 4(ψ/2 + 1)
    let d = 4.0 * (constants::psi() / 2.0 + 1.0);
    assert!((p.d().expect("finite") - d).abs() < 1e-14);
    assert_eq!((p.sigma(), p.family(), *p.task()), (1.0, Family::Thesis, k));
    assert_eq!(Family::default(), Family::Thesis);
    let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0).expect("valid");
    let c = Penalties::new(&k, 0.3).expect("valid").c().expect("finite");
    assert!((c - c_ref(&k, 0.3)).abs() < 1e-12 * c);
}

#[test]
fn errors_are_those_of_c_and_d() {
    let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0).expect("valid");
    for sigma in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        // compared through Debug: the error carries the NaN it received
        let e = format!("{:?}", Penalties::new(&k, sigma).map(|_| ()));
        assert_eq!(e, format!("{:?}", constants::c(&k, sigma).map(|_| ())));
        assert_eq!(e, format!("{:?}", constants::d(&k, sigma).map(|_| ())));
        assert!(e.starts_with("Err("));
    }
    // c overflows at a tiny σ, d (∝ 1/σ) does not yet
    let p = Penalties::new(&k, 1e-120).expect("valid σ");
    assert_eq!(p.c(), Err(BoundsError::Overflow { quantity: "c" }));
    assert_eq!(p.c(), constants::c(&k, 1e-120));
    assert_eq!(p.d(), constants::d(&k, 1e-120));
    assert!(p.d().is_ok());
    let p = Penalties::new(&k, 1e-320).expect("valid σ");
    assert_eq!(p.d(), Err(BoundsError::Overflow { quantity: "d" }));
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: RngSeed::Fixed(0x9e_7a1),
        cases: 2048,
        ..ProptestConfig::default()
    })]

    /// Every value and outcome through `Penalties` is bit for bit the one through (k, σ),
    /// including ψ overrides.
    #[test]
    fn penalties_agree_with_the_free_functions(
        g in 0.0..0.999_f64, r in 0.01..100.0_f64, m in 0.01..10.0_f64, a in 0.01..10.0_f64,
        psi in prop::option::of(0.1..2.0_f64),
        sigma in 1e-3..100.0_f64,
        grad in -10.0..10.0_f64, grad_l in -10.0..10.0_f64, eps in 0.0..2.0_f64,
        required in -1.0..1.0_f64,
    ) {
        let mut k = TaskConstants::new(g, r, m, a).expect("valid");
        if let Some(psi) = psi {
            k = k.with_psi(psi).expect("valid");
        }
        let p = Penalties::new(&k, sigma).expect("valid");
        prop_assert_eq!(p.c().map(f64::to_bits), constants::c(&k, sigma).map(f64::to_bits));
        prop_assert_eq!(p.d().map(f64::to_bits), constants::d(&k, sigma).map(f64::to_bits));
        prop_assert_eq!(
            v_update::safe_step_at(&p, &[grad, grad_l], required),
            v_update::safe_step(&k, sigma, &[grad, grad_l], required)
        );
        prop_assert_eq!(
            w_update::safe_step_along_j_at(&p, grad, required),
            w_update::safe_step_along_j(&k, sigma, grad, required)
        );
        prop_assert_eq!(
            w_update::safe_step_along_l_at(&p, grad, grad_l, required),
            w_update::safe_step_along_l(&k, sigma, grad, grad_l, required)
        );
        prop_assert_eq!(
            HighProbabilityBound::v_update_at(&p, &[grad], eps),
            HighProbabilityBound::v_update(&k, sigma, &[grad], eps)
        );
        prop_assert_eq!(
            HighProbabilityBound::w_along_l_at(&p, grad, eps, grad_l, eps),
            HighProbabilityBound::w_along_l(&k, sigma, grad, eps, grad_l, eps)
        );
        let g = [grad, grad_l];
        let bits = |r: Result<f64, BoundsError>| r.map(f64::to_bits);
        prop_assert_eq!(bits(v_update::alpha_star_at(&p)), bits(v_update::alpha_star(&k, sigma)));
        prop_assert_eq!(bits(v_update::c_max_at(&p, &g)), bits(v_update::c_max(&k, sigma, &g)));
        prop_assert_eq!(
            bits(v_update::bound_at(&p, &g, required)),
            bits(v_update::bound(&k, sigma, &g, required))
        );
        prop_assert_eq!(bits(w_update::beta_star_at(&p)), bits(w_update::beta_star(&k, sigma)));
        prop_assert_eq!(bits(w_update::c_max_at(&p, grad)), bits(w_update::c_max(&k, sigma, grad)));
        prop_assert_eq!(
            bits(w_update::bound_along_j_at(&p, grad, required)),
            bits(w_update::bound_along_j(&k, sigma, grad, required))
        );
        prop_assert_eq!(
            bits(w_update::bound_along_l_at(&p, grad, grad_l, required)),
            bits(w_update::bound_along_l(&k, sigma, grad, grad_l, required))
        );
        prop_assert_eq!(
            bits(w_update::beta_tilde_at(&p, grad, grad_l)),
            bits(w_update::beta_tilde(&k, sigma, grad, grad_l))
        );
        prop_assert_eq!(
            bits(pirotta::bound_at(&p, &g, required)),
            bits(pirotta::bound(&k, sigma, &g, required))
        );
        prop_assert_eq!(pirotta::optimal_step_at(&p, &g), pirotta::optimal_step(&k, sigma, &g));
        prop_assert_eq!(
            bits(pirotta::hp_bound_at(&p, &g, &[eps, eps], required)),
            bits(pirotta::hp_bound(&k, sigma, &g, &[eps, eps], required))
        );
        prop_assert_eq!(
            pirotta::hp_optimal_step_at(&p, &g, &[eps, eps]),
            pirotta::hp_optimal_step(&k, sigma, &g, &[eps, eps])
        );
        prop_assert_eq!(
            bits(papini::bound_at(&p, &g, &[required, eps])),
            bits(papini::bound(&k, sigma, &g, &[required, eps]))
        );
        prop_assert_eq!(papini::greedy_step_at(&p, &g), papini::greedy_step(&k, sigma, &g));
        for form in [HpForm::Thesis, HpForm::SignAware] {
            prop_assert_eq!(
                hp::v_safe_step_at(&p, &g, eps, required, form),
                hp::v_safe_step(&k, sigma, &g, eps, required, form)
            );
            prop_assert_eq!(
                hp::w_safe_step_along_j_at(&p, grad, eps, required, form),
                hp::w_safe_step_along_j(&k, sigma, grad, eps, required, form)
            );
            prop_assert_eq!(
                hp::w_safe_step_along_l_at(&p, grad, eps, grad_l, eps, required, form),
                hp::w_safe_step_along_l(&k, sigma, grad, eps, grad_l, eps, required, form)
            );
        }
        prop_assert_eq!(
            ExploringBound::at(&p, grad, eps),
            ExploringBound::new(&k, sigma, grad, eps)
        );
        prop_assert_eq!(
            exploring::w_exploring_step_at(&p, grad, eps, grad_l, required),
            exploring::w_exploring_step(&k, sigma, grad, eps, grad_l, required)
        );
    }
}

/// The `lqg1d` task (R = 28.8, M_φ = 4, γ = 0.99, |A| = 8) with the tight family at H = 20.
fn lqg1d_tight(rewards: Rewards) -> (TaskConstants, TaskConstants) {
    let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("valid");
    let t = k
        .with_family(Family::Tight(Tight::new(Horizon::Finite(20), rewards)))
        .expect("valid");
    (k, t)
}

/// S_20 at γ = 0.99 from the closed form (1 − (H + 1)γ^H + Hγ^{H+1}) / (1 − γ)².
fn s20() -> f64 {
    (1.0 - 21.0 * 0.99f64.powi(20) + 20.0 * 0.99f64.powi(21)) / (0.01f64 * 0.01)
}

#[test]
fn tight_family_is_the_printed_formula_on_lqg1d() {
    let (k, one_sided) = lqg1d_tight(Rewards::NonPositive);
    let (_, two_sided) = lqg1d_tight(Rewards::TwoSided);
    let s = s20();
    assert!((s - 185.1).abs() < 0.2, "S_20 = {s}");
    for sigma in [0.05, 0.1, 0.2, 0.5, 1.0, 4.0] {
        // c = ρ R M_φ² S_H / σ², d = 2ρ R S_H with ρ = 1/2 (non-positive rewards) or 1
        let c2 = 28.8 * 16.0 * s / (sigma * sigma);
        let d2 = 2.0 * 28.8 * s;
        let p = Penalties::new(&two_sided, sigma).expect("valid");
        assert!((p.c().expect("finite") - c2).abs() < 1e-12 * c2);
        assert!((p.d().expect("finite") - d2).abs() < 1e-12 * d2);
        let p = Penalties::new(&one_sided, sigma).expect("valid");
        assert!((p.c().expect("finite") - c2 / 2.0).abs() < 1e-12 * c2);
        assert!((p.d().expect("finite") - d2 / 2.0).abs() < 1e-12 * d2);
        assert_eq!(p.c(), constants::c(&one_sided, sigma));
        assert_eq!(p.d(), constants::d(&one_sided, sigma));
        // ∂c/∂σ = −2c/σ, against a central difference
        let h = 1e-6 * sigma;
        let fd = (constants::c(&one_sided, sigma + h).expect("finite")
            - constants::c(&one_sided, sigma - h).expect("finite"))
            / (2.0 * h);
        let dc = constants::dc_dsigma(&one_sided, sigma).expect("finite");
        assert!(
            (dc - fd).abs() < 1e-6 * fd.abs(),
            "σ = {sigma}: {dc} vs {fd}"
        );
    }
    // d = R S_H ≈ 5,331 one-sided, against the thesis's 2.9e7 – 3.5e7
    let d = constants::d(&one_sided, 1.0).expect("finite");
    assert!((d - 5331.0).abs() < 5.0, "d = {d}");
    // how many times smaller c is than the thesis's: 8,800 / 7,100 / 6,000 / 5,700 at
    // σ = 0.1 / 0.2 / 0.5 / 1 (the thesis's c falls as σ⁻³, the tight one as σ⁻²)
    for (sigma, ratio) in [(0.1, 8800.0), (0.2, 7100.0), (0.5, 6000.0), (1.0, 5700.0)] {
        let r = constants::c(&k, sigma).expect("finite")
            / constants::c(&one_sided, sigma).expect("finite");
        assert!((r / ratio - 1.0).abs() < 0.02, "σ = {sigma}: {r}");
    }
}

#[test]
fn s_h_sums_the_discounted_score_counts() {
    use constants::s_h;
    // γ = 0: one reward, one score term
    for h in [1, 2, 20, 1 << 21] {
        assert_eq!(s_h(0.0, Horizon::Finite(h)), Ok(1.0));
    }
    // γ = 1/2: 1, 1 + 2/2, 1 + 1 + 3/4 (exact in f64), and 1/(1 − γ)² = 4 at H = ∞
    assert_eq!(s_h(0.5, Horizon::Finite(1)), Ok(1.0));
    assert_eq!(s_h(0.5, Horizon::Finite(2)), Ok(2.0));
    assert_eq!(s_h(0.5, Horizon::Finite(3)), Ok(2.75));
    assert_eq!(s_h(0.5, Horizon::Infinite), Ok(4.0));
    assert!((s_h(0.99, Horizon::Finite(20)).expect("valid") - s20()).abs() < 1e-11 * s20());
    // the closed form beyond 2²⁰ continues Horner's sum: a term-by-term sum at H = 2²⁰ + 1
    // (γ close to 1, where the closed form cancels most)
    for gamma in [0.9, 0.999_999, 0.999_999_9] {
        let h: u64 = (1 << 20) + 1;
        let (mut sum, mut power) = (0.0f64, 1.0f64);
        for t in 0..h {
            sum += (t + 1) as f64 * power;
            power *= gamma;
        }
        let s = s_h(gamma, Horizon::Finite(h)).expect("valid");
        assert!((s - sum).abs() < 1e-7 * sum, "γ = {gamma}: {s} vs {sum}");
        let inf = s_h(gamma, Horizon::Infinite).expect("valid");
        assert!(s <= inf && s >= 1.0);
    }
    assert!(s_h(0.9, Horizon::Finite(0)).is_err());
    assert!(s_h(1.0, Horizon::Finite(3)).is_err());
    assert!(s_h(f64::NAN, Horizon::Infinite).is_err());
    let k = TaskConstants::new(0.9, 1.0, 1.0, 1.0).expect("valid");
    let zero = Tight::new(Horizon::Finite(0), Rewards::TwoSided);
    assert!(k.with_family(Family::Tight(zero)).is_err());
}

#[test]
fn tight_w_bound_is_proven_for_every_change_so_the_rigorous_form_is_the_plain_one() {
    use sepg_bounds::rigorous;
    let (_, t) = lqg1d_tight(Rewards::NonPositive);
    let d = constants::d(&t, 0.7).expect("finite");
    assert_eq!(rigorous::c(&t, 0.7), constants::c(&t, 0.7));
    for dw in [-0.3, -1e-4, 0.0, 1e-4, 0.3] {
        let plain = dw * 2.5 - d * dw * dw;
        let rig = rigorous::bound(&t, 0.7, 2.5, dw).expect("finite");
        assert!(
            (rig - plain).abs() <= 1e-12 * (1.0 + plain.abs()),
            "Δw = {dw}"
        );
        assert_eq!(rigorous::gap(&t, 0.7, dw), Ok(0.0));
    }
    assert!(rigorous::gap(&t, 0.0, 0.1).is_err());
    // the safe interval of the rigorous form is the parabola's: [0, ∇J/d] for C = 0
    let outcome = rigorous::safe_delta_w(&t, 0.7, 2.5, 0.0).expect("valid");
    let StepOutcome::Feasible(steps) = outcome else {
        panic!("C = 0 is feasible")
    };
    assert!((steps.largest() - 2.5 / d).abs() < 1e-9 * 2.5 / d);
}
