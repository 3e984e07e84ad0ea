//! `Parabola`: vertex, C_max and safe intervals of a·x − b·x² against the closed forms of the
//! quadratic formula, the outcomes at the edges (zero gradient, C > C_max, the 8-ulp slack),
//! and `feasible` against `solve`, bit for bit.

use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use sepg_bounds::outcome::{SafeInterval, StepOutcome};
use sepg_bounds::{BoundsError, Parabola};

fn feasible(o: StepOutcome) -> SafeInterval {
    match o {
        StepOutcome::Feasible(s) => s,
        other => panic!("expected a feasible outcome, got {other:?}"),
    }
}

#[test]
fn vertex_c_max_and_interval_match_the_quadratic_formula() {
    // x − 2x²: vertex 1/4, C_max 1/8; x − 2x² ≥ 1/16 ⇔ x ∈ (1 ∓ 1/√2)/4, λ = √(1 − 1/2)
    let p = Parabola::new(1.0, 2.0);
    assert_eq!(p.vertex_and_c_max(), Ok((0.25, 0.125)));
    assert_eq!(p.c_max(), Ok(0.125));
    let s = feasible(p.solve(0.0625).expect("valid"));
    let r = std::f64::consts::FRAC_1_SQRT_2;
    assert!((s.lo - (1.0 - r) / 4.0).abs() < 1e-16);
    assert!((s.hi - (1.0 + r) / 4.0).abs() < 1e-16);
    assert!((s.lambda.expect("C_max > 0") - r).abs() < 1e-16);
    assert_eq!((s.vertex, s.c_max), (0.25, 0.125));
    // C = 0: the roots are 0 and a/b
    let s = feasible(p.solve(0.0).expect("valid"));
    assert_eq!((s.lo, s.hi), (0.0, 0.5));
}

#[test]
fn negative_linear_coefficient_mirrors_the_interval() {
    let s = feasible(Parabola::new(-1.0, 2.0).solve(0.0).expect("valid"));
    assert_eq!((s.lo, s.vertex, s.hi), (-0.5, -0.25, 0.0));
    // C < 0 admits steps of both signs: −x − 2x² ≥ −1 ⇔ x ∈ [−1, 1/2]
    let s = feasible(Parabola::new(-1.0, 2.0).solve(-1.0).expect("valid"));
    assert!((s.lo + 1.0).abs() < 1e-15 && (s.hi - 0.5).abs() < 1e-15);
    assert!(s.lambda.expect("C_max > 0") > 1.0);
}

#[test]
fn edge_outcomes() {
    let zero = Parabola::new(0.0, 0.0);
    assert_eq!(zero.c_max(), Ok(0.0));
    assert_eq!(
        zero.solve(0.0),
        Ok(StepOutcome::ZeroGradient {
            requirement_met: true
        })
    );
    assert_eq!(
        zero.solve(1e-3),
        Ok(StepOutcome::ZeroGradient {
            requirement_met: false
        })
    );
    assert_eq!(zero.feasible(0.0), None);
    // b underflowed to 0 with a ≠ 0: no vertex
    let flat = Parabola::new(1.0, 0.0);
    assert!(matches!(flat.solve(0.0), Err(BoundsError::Overflow { .. })));
    assert!(matches!(flat.c_max(), Err(BoundsError::Overflow { .. })));
    assert_eq!(flat.feasible(0.0), None);
    // non-finite coefficients are overflow errors
    assert!(matches!(
        Parabola::new(f64::INFINITY, 1.0).solve(0.0),
        Err(BoundsError::Overflow { .. })
    ));
    // C > C_max: the vertex and C_max
    let p = Parabola::new(1.0, 2.0);
    assert_eq!(
        p.solve(0.2),
        Ok(StepOutcome::Infeasible {
            c_max: 0.125,
            vertex: 0.25
        })
    );
    assert_eq!(p.feasible(0.2), None);
}

#[test]
fn requirements_within_eight_ulps_of_c_max_are_c_max() {
    let p = Parabola::new(1.0, 2.0);
    let just_above = 0.125 * (1.0 + 4.0 * f64::EPSILON);
    let s = feasible(p.solve(just_above).expect("valid"));
    assert_eq!((s.lo, s.hi, s.lambda), (0.25, 0.25, Some(0.0)));
    let beyond = 0.125 * (1.0 + 16.0 * f64::EPSILON);
    assert!(matches!(
        p.solve(beyond),
        Ok(StepOutcome::Infeasible { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: RngSeed::Fixed(0x9a7a_b01a),
        cases: 4096,
        ..ProptestConfig::default()
    })]

    /// `feasible` returns the interval of `solve` bit for bit, and `None` exactly when `solve`
    /// returns anything else.
    #[test]
    fn feasible_is_solve_bit_for_bit(
        a in prop_oneof![-1e3..1e3_f64, Just(0.0), -1e-300..1e-300_f64, -1e200..1e200_f64],
        b in prop_oneof![0.0..1e3_f64, Just(0.0), 0.0..1e-300_f64, 0.0..1e300_f64],
        c in prop_oneof![-1e3..1e3_f64, Just(0.0), -1e-300..1e-300_f64],
    ) {
        let p = Parabola::new(a, b);
        match p.solve(c) {
            Ok(StepOutcome::Feasible(s)) => {
                let f = p.feasible(c).expect("feasible");
                prop_assert_eq!(f.lo.to_bits(), s.lo.to_bits());
                prop_assert_eq!(f.hi.to_bits(), s.hi.to_bits());
                prop_assert_eq!(f.vertex.to_bits(), s.vertex.to_bits());
                prop_assert_eq!(f.c_max.to_bits(), s.c_max.to_bits());
                prop_assert_eq!(f.lambda.map(f64::to_bits), s.lambda.map(f64::to_bits));
                prop_assert!(s.lo <= s.vertex && s.vertex <= s.hi);
            }
            _ => prop_assert_eq!(p.feasible(c), None),
        }
    }
}
