//! `Penalties`: c and d of the thesis family evaluated once, against the printed formulas and
//! bit for bit against `constants::{c, d}`, with the same errors; the `_at` step functions
//! give the outcomes of the functions that take (k, σ).

use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use sepg_bounds::constants::{self, TaskConstants};
use sepg_bounds::exploring::{self, ExploringBound};
use sepg_bounds::high_probability::{self as hp, HighProbabilityBound, HpForm};
use sepg_bounds::{BoundsError, Family, Penalties, papini, pirotta, v_update, w_update};

use super::common::c_ref;

#[test]
fn thesis_family_is_c_and_d_of_the_printed_formulas() {
    let k = TaskConstants::new(0.5, 1.0, 1.0, 1.0).expect("valid");
    let p = Penalties::new(&k, Family::Thesis, 1.0).expect("valid");
    // c = R M²/((1−γ)²σ²)·(|A|/(√(2π)σ) + γ/(2(1−γ))) = 4(1/√(2π) + 1/2)
    let c = 4.0 * (1.0 / (2.0 * std::f64::consts::PI).sqrt() + 0.5);
    assert!((p.c().expect("finite") - c).abs() < 1e-14);
    // d = R/(1−γ)²·(ψ|A|/(2σ) + γ/(1−γ)) = 4(ψ/2 + 1)
    let d = 4.0 * (constants::psi() / 2.0 + 1.0);
    assert!((p.d().expect("finite") - d).abs() < 1e-14);
    assert_eq!((p.sigma(), p.family(), *p.task()), (1.0, Family::Thesis, k));
    assert_eq!(Family::default(), Family::Thesis);
    let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0).expect("valid");
    let c = Penalties::thesis(&k, 0.3)
        .expect("valid")
        .c()
        .expect("finite");
    assert!((c - c_ref(&k, 0.3)).abs() < 1e-12 * c);
}

#[test]
fn errors_are_those_of_c_and_d() {
    let k = TaskConstants::new(0.9, 1.0, 1.0, 2.0).expect("valid");
    for sigma in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        // compared through Debug: the error carries the NaN it received
        let e = format!("{:?}", Penalties::thesis(&k, sigma).map(|_| ()));
        assert_eq!(e, format!("{:?}", constants::c(&k, sigma).map(|_| ())));
        assert_eq!(e, format!("{:?}", constants::d(&k, sigma).map(|_| ())));
        assert!(e.starts_with("Err("));
    }
    // c overflows at a tiny σ, d (∝ 1/σ) does not yet
    let p = Penalties::thesis(&k, 1e-120).expect("valid σ");
    assert_eq!(p.c(), Err(BoundsError::Overflow { quantity: "c" }));
    assert_eq!(p.c(), constants::c(&k, 1e-120));
    assert_eq!(p.d(), constants::d(&k, 1e-120));
    assert!(p.d().is_ok());
    let p = Penalties::thesis(&k, 1e-320).expect("valid σ");
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
        let p = Penalties::thesis(&k, sigma).expect("valid");
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
