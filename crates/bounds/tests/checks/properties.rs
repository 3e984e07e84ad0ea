//! Property-based checks over random task constants, gradients and requirements.

use approx::{abs_diff_eq, relative_eq};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use sepg_bounds::budget::Budget;
use sepg_bounds::constants::{TaskConstants, c, d, psi};
use sepg_bounds::high_probability::{HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::{greedy, papini, pirotta, rigorous, surrogate, v_update, w_update};

fn constants() -> impl Strategy<Value = TaskConstants> {
    (
        0.0..0.999_f64,
        0.01..100.0_f64,
        0.01..10.0_f64,
        0.01..100.0_f64,
    )
        .prop_map(|(g, r, m, a)| TaskConstants::new(g, r, m, a).unwrap())
}

/// Valid constants spanning the whole positive f64 range.
fn extreme_constants() -> impl Strategy<Value = TaskConstants> {
    let pos = || prop::num::f64::NORMAL.prop_map(f64::abs);
    (0.0..1.0_f64, pos(), pos(), pos())
        .prop_map(|(g, r, m, a)| TaskConstants::new(g, r, m, a).unwrap())
}

fn nonzero() -> impl Strategy<Value = f64> {
    prop_oneof![-100.0..-1e-3_f64, 1e-3..100.0_f64]
}

/// Any finite f64, with extra weight on moderate values.
fn any_finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        -10.0..10.0_f64,
        prop::num::f64::NORMAL,
        prop::num::f64::SUBNORMAL,
        prop::num::f64::ZERO,
    ]
}

fn finite_outcome(o: &StepOutcome) -> bool {
    match o {
        StepOutcome::Feasible(s) => {
            [s.c_max, s.vertex, s.lo, s.hi]
                .iter()
                .all(|v| v.is_finite())
                && s.lambda.is_none_or(f64::is_finite)
                && s.lo <= s.hi
        }
        StepOutcome::Infeasible { c_max, vertex } => c_max.is_finite() && vertex.is_finite(),
        StepOutcome::ZeroGradient { .. } | StepOutcome::BelowNoise => true,
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: RngSeed::Fixed(0xb0_0d5),
        ..ProptestConfig::default()
    })]

    #[test]
    fn c_and_d_decrease_in_sigma(k in constants(), s1 in 1e-3..100.0_f64, ratio in 1.001..10.0_f64) {
        let s2 = s1 * ratio;
        prop_assert!(c(&k, s1).unwrap() > c(&k, s2).unwrap());
        prop_assert!(d(&k, s1).unwrap() > d(&k, s2).unwrap());
    }

    /// Feasible ⇔ C ≤ C_max, and λ ∈ [0, 1] ⇔ C ≥ 0, for the three exact updates.
    #[test]
    fn feasibility_and_lambda(
        k in constants(), sigma in 1e-2..10.0_f64, gj in nonzero(), gl in nonzero(),
        gv in prop::collection::vec(-100.0..100.0_f64, 1..5), frac in -5.0..1.5_f64,
    ) {
        prop_assume!(gv.iter().any(|x| x.abs() > 1e-3));
        let c_v = v_update::c_max(&k, sigma, &gv).unwrap();
        let c_w = w_update::c_max(&k, sigma, gj).unwrap();
        let outcomes = [
            (c_v, v_update::safe_step(&k, sigma, &gv, frac * c_v).unwrap()),
            (c_w, w_update::safe_step_along_j(&k, sigma, gj, frac * c_w).unwrap()),
            (c_w, w_update::safe_step_along_l(&k, sigma, gj, gl, frac * c_w).unwrap()),
        ];
        for (c_max, o) in outcomes {
            let required = frac * c_max;
            prop_assert!(finite_outcome(&o));
            prop_assert_eq!(o.is_feasible(), required <= c_max);
            if let StepOutcome::Feasible(s) = o {
                let l = s.lambda.unwrap();
                prop_assert_eq!((0.0..=1.0).contains(&l), required >= 0.0);
                prop_assert!(relative_eq!(s.c_max, c_max, epsilon = 0.0, max_relative = 1e-12));
            }
        }
    }

    /// The bound at the interval ends equals C (relative to the size of its terms).
    #[test]
    fn interval_end_points(
        k in constants(), sigma in 1e-2..10.0_f64, gj in nonzero(), gl in nonzero(), frac in -5.0..1.0_f64,
    ) {
        let required = frac * w_update::c_max(&k, sigma, gj).unwrap();
        let StepOutcome::Feasible(s) = w_update::safe_step_along_l(&k, sigma, gj, gl, required).unwrap() else {
            panic!("C ≤ C_max")
        };
        let dd = d(&k, sigma).unwrap();
        for b in [s.lo, s.hi] {
            let value = w_update::bound_along_l(&k, sigma, gj, gl, b).unwrap();
            let scale = (b * gl * gj).abs().max(dd * b * b * gl * gl).max(required.abs());
            prop_assert!(abs_diff_eq!(value, required, epsilon = 1e-10 * scale), "{} vs {}", value, required);
        }
    }

    /// Rigorous vs thesis: |f − f_T| = O(Δw³) with explicit constants while the box term is
    /// the larger curvature; f ≥ f_T for Δw ≥ 0 there; beyond σ = ψ|A|/K_W the difference is
    /// the second-order term (a_ℝ − a)Δw².
    #[test]
    fn rigorous_versus_thesis(k in constants(), sigma in 1e-2..10.0_f64, x in -1.0..1.0_f64) {
        let (g, r) = (k.gamma(), k.r_max());
        let a = r * psi() * k.action_volume() / (2.0 * (1.0 - g).powi(2) * sigma);
        let a_line = r * rigorous::k_w() / (2.0 * (1.0 - g).powi(2));
        let excess = (a_line - a).max(0.0) * x * x;
        let big_g = g * r / (2.0 * (1.0 - g).powi(3));
        let gap = rigorous::gap(&k, sigma, x).unwrap();
        let cube = x.abs().powi(3);
        let tol = 1e-12 * (a + a_line + big_g) * x * x;
        prop_assert!(-gap <= 4.0 / 3.0 * big_g * cube + tol, "rigorous ≤ thesis + (4/3)G|Δw|³");
        prop_assert!(
            gap <= a * cube * x.abs().exp() + excess + tol,
            "rigorous ≥ thesis − a|Δw|³e^|Δw| − (a_ℝ − a)⁺Δw²"
        );
        prop_assert!(gap >= excess - 4.0 / 3.0 * big_g * cube - tol);
        if x >= 0.0 {
            prop_assert!(gap <= excess + tol, "Δw ≥ 0: rigorous ≥ thesis − (a_ℝ − a)⁺Δw²");
        }
    }

    /// The rigorous safe interval is contained in the region where the bound ≥ C and is never
    /// empty when C ≤ C_max.
    #[test]
    fn rigorous_interval_is_safe(
        k in constants(), sigma in 1e-2..10.0_f64, gj in nonzero(), frac in -3.0..1.0_f64,
    ) {
        let StepOutcome::Infeasible { c_max, .. } = rigorous::safe_delta_w(&k, sigma, gj, f64::MAX).unwrap() else {
            panic!("C = MAX is infeasible")
        };
        let required = frac * c_max;
        let StepOutcome::Feasible(s) = rigorous::safe_delta_w(&k, sigma, gj, required).unwrap() else {
            panic!("C ≤ C_max")
        };
        for t in [0.0, 0.3, 0.7, 1.0] {
            let x = s.lo + t * (s.hi - s.lo);
            prop_assert!(rigorous::bound(&k, sigma, gj, x).unwrap() >= required - 1e-12 * c_max.abs());
        }
    }

    /// Invalid constants are rejected, valid ones accepted, with no panic.
    #[test]
    fn constants_validation(g in any_finite(), r in any_finite(), m in any_finite(), a in any_finite()) {
        let valid = (0.0..1.0).contains(&g) && r > 0.0 && m > 0.0 && a > 0.0;
        prop_assert_eq!(TaskConstants::new(g, r, m, a).is_ok(), valid);
    }

    #[test]
    fn budget_identity(
        start in -100.0..100.0_f64, b0 in 0.0..5.0_f64,
        diffs in prop::collection::vec((-1.0..1.0_f64, -1.0..1.0_f64), 0..30),
    ) {
        let mut b = Budget::new(b0, start, Some(start - 1.0)).unwrap();
        for (de, dt) in diffs {
            b.add_exploratory_difference(de).unwrap();
            b.add_target_difference(dt).unwrap();
            prop_assert!(abs_diff_eq!(b.telescoped_change(), b.value() - b.initial(), epsilon = 1e-9));
            if b.is_type_two_safe() {
                prop_assert!(b.average_performance() >= b.guaranteed_average() - 1e-9);
            }
        }
    }

    /// No public function returns NaN or ±∞ for finite input: either a finite value or an error.
    #[test]
    fn never_nan(
        k in prop_oneof![constants(), extreme_constants()],
        sigma in any_finite(), x in any_finite(), y in any_finite(), e in any_finite(), req in any_finite(),
    ) {
        let ok = |v: Result<f64, _>| v.is_ok_and(f64::is_finite) || v.is_err();
        let ok_o = |v: Result<StepOutcome, sepg_bounds::BoundsError>| v.as_ref().is_ok_and(finite_outcome) || v.is_err();
        prop_assert!(ok(c(&k, sigma)) && ok(d(&k, sigma)));
        prop_assert!(ok(v_update::bound(&k, sigma, &[x, y], req)));
        prop_assert!(ok_o(v_update::safe_step(&k, sigma, &[x, y], req)));
        prop_assert!(ok_o(w_update::safe_step_along_j(&k, sigma, x, req)));
        prop_assert!(ok_o(w_update::safe_step_along_l(&k, sigma, x, y, req)));
        prop_assert!(ok(w_update::beta_tilde(&k, sigma, x, y)));
        prop_assert!(ok(surrogate::surrogate(&k, sigma, &[x, y])));
        prop_assert!(ok(surrogate::grad_w(&k, sigma, &[x], &[y])));
        prop_assert!(ok(papini::bound(&k, sigma, &[x, y], &[req, e])));
        prop_assert!(ok(pirotta::bound(&k, sigma, &[x, y], req)));
        let p = pirotta::hp_optimal_step(&k, sigma, &[x, y], &[e.abs(), e.abs()]);
        let finite_step = match p {
            Ok(pirotta::AdaptiveStep::Step { alpha, guarantee }) => alpha.is_finite() && guarantee.is_finite(),
            _ => true,
        };
        prop_assert!(finite_step);
        prop_assert!(ok_o(greedy::w_step(&k, &[sigma], &[x], &[y], req).map(|s| s.outcome)));
        prop_assert!(ok(rigorous::bound(&k, sigma, x, y)));
        prop_assert!(ok(rigorous::gap(&k, sigma, y)));
        prop_assert!(ok_o(rigorous::safe_step_along_l(&k, sigma, x, y, req)));
        if let Ok(Some(b)) = HighProbabilityBound::w_along_l(&k, sigma, x, e.abs(), y, e.abs()) {
            prop_assert!(ok_o(b.safe_step(req, HpForm::Thesis)));
            prop_assert!(ok_o(b.safe_step(req, HpForm::SignAware)));
            prop_assert!(ok(b.sign_aware_value(req)));
        }
    }
}
