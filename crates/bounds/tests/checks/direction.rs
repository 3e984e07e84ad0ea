//! The step along any direction (`sepg_bounds::direction`) against an independent evaluation
//! of its bound, the closed-form root, and Theorem 4.2's greedy step.

use sepg_bounds::BoundsError;
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::direction::{Direction, DirectionBound, FeatureNorm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
use sepg_bounds::v_update;

/// SplitMix64: a fixed, portable sequence of test inputs (not a statistical test).
struct Inputs(u64);

impl Inputs {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform on [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// `lqg1d`'s constants (R = 28.8, M_φ = 4, γ = 0.99) with the tight family, H = 20, rewards
/// non-positive.
fn tight() -> TaskConstants {
    TaskConstants::new(0.99, 28.8, 4.0, 8.0)
        .and_then(|k| {
            k.with_family(Family::Tight(Tight::new(
                Horizon::Finite(20),
                Rewards::NonPositive,
            )))
        })
        .expect("constants")
}

/// c = ρ R M_φ² S_H / σ² of Theorem T from the printed formula, S_H by its closed form.
fn c_printed(sigma: f64) -> f64 {
    let (g, h) = (0.99_f64, 20.0_f64);
    let s_h = (1.0 - (h + 1.0) * g.powf(h) + h * g.powf(h + 1.0)) / (1.0 - g).powi(2);
    0.5 * 28.8 * 16.0 * s_h / (sigma * sigma)
}

/// B(t) of the module documentation written out from the inputs.
fn b_ref(c2: f64, u: &[f64], g: &[f64], eps: &[f64], t: f64) -> f64 {
    let dot: f64 = u.iter().zip(g).map(|(a, b)| a * b).sum();
    let abs: f64 = u.iter().zip(eps).map(|(a, e)| a.abs() * e).sum();
    let n2: f64 = u.iter().map(|a| a * a).sum();
    t * dot - t * abs - c2 * t * t * n2
}

/// For random u, ĝ, ε, C and p: the chosen t meets C by the independent evaluation (to a
/// relative 1e-9 of the terms' size), and t(1 + 1e-9) does not, unless t is the cap; with
/// ε = 0 the step is the closed-form root.
#[test]
fn the_largest_step_meets_the_requirement_and_is_the_largest() {
    let k = tight();
    let mut r = Inputs(24);
    let mut checked = (0, 0);
    for case in 0..2_000 {
        let n = 1 + case % 5;
        let p = 1 + case % 3;
        let sigma = r.uniform(0.1, 2.0);
        let u: Vec<f64> = (0..n).map(|_| r.uniform(-1e-2, 1e-2)).collect();
        let g: Vec<f64> = (0..n).map(|_| r.uniform(-50.0, 50.0)).collect();
        let exact = case % 4 == 0;
        let eps: Vec<f64> = (0..n)
            .map(|_| if exact { 0.0 } else { r.uniform(0.0, 20.0) })
            .collect();
        let d = Direction {
            direction: &u,
            grad_hat: &g,
            eps: &eps,
            features: FeatureNorm::FromMax { features: p },
        };
        let coordinate = n == 1;
        let c2 = c_printed(sigma) * if coordinate { 1.0 } else { p as f64 };
        let a = b_ref(c2, &u, &g, &eps, 1.0) + c2 * u.iter().map(|x| x * x).sum::<f64>();
        let bq = c2 * u.iter().map(|x| x * x).sum::<f64>();
        let c_max = if a > 0.0 { a * a / (4.0 * bq) } else { 0.0 };
        // requirements from a loss of up to C_max + 1 to 0.9 C_max
        let required = r.uniform(-(c_max + 1.0), 0.9 * c_max);
        let cap = if case % 7 == 0 { 1e-3 } else { f64::INFINITY };
        let s = DirectionBound::new(&k, sigma, &d)
            .and_then(|b| b.safe_step(required, cap))
            .expect("valid inputs");
        assert!(matches!(s.outcome, StepOutcome::Feasible(_)), "case {case}");
        let t = s.step;
        assert!(t >= 0.0 && t <= cap);
        let scale = (t * a.abs()).max(required.abs()).max(1e-300);
        let at = b_ref(c2, &u, &g, &eps, t);
        assert!(
            at >= required - 1e-9 * scale,
            "case {case}: B({t}) = {at} < {required}"
        );
        assert!((s.guaranteed - at).abs() <= 1e-9 * scale, "case {case}");
        if t < cap && t > 0.0 {
            let beyond = b_ref(c2, &u, &g, &eps, t * (1.0 + 1e-9));
            assert!(beyond < required, "case {case}: t = {t} is not the largest");
            checked.0 += 1;
        }
        if exact && t < cap {
            let root = (a + (a * a - 4.0 * bq * required).sqrt()) / (2.0 * bq);
            assert!(
                (t - root).abs() <= 1e-10 * root,
                "case {case}: {t} vs {root}"
            );
            checked.1 += 1;
        }
    }
    // the maximality and closed-form checks ran on most cases
    assert!(checked.0 > 1_500 && checked.1 > 400, "{checked:?}");
}

/// A coordinate direction u = ĝ_k e_k (k the greedy coordinate) gives Theorem 4.2's step of
/// `v_update::safe_step`, t·u equal to its α·ĝ_k bit for bit, whatever p (c₂ = c).
#[test]
fn a_coordinate_direction_is_theorem_4_2s_greedy_step() {
    let mut r = Inputs(7);
    for family in [Family::Thesis, tight().family()] {
        let k = TaskConstants::new(0.99, 28.8, 4.0, 8.0)
            .and_then(|k| k.with_family(family))
            .expect("constants");
        for case in 0..500 {
            let g: Vec<f64> = (0..3).map(|_| r.uniform(-50.0, 50.0)).collect();
            let sigma = r.uniform(0.1, 2.0);
            let kk = sepg_bounds::greedy::argmax_abs(&g).expect("finite");
            let mut u = vec![0.0; 3];
            u[kk] = g[kk];
            let d = Direction {
                direction: &u,
                grad_hat: &g,
                eps: &[0.0; 3],
                features: FeatureNorm::FromMax { features: 3 },
            };
            let c_max = v_update::c_max(&k, sigma, &g).expect("c_max");
            let required = r.uniform(-c_max, 0.9 * c_max);
            let s = DirectionBound::new(&k, sigma, &d)
                .and_then(|b| b.safe_step(required, f64::INFINITY))
                .expect("step");
            let alpha = v_update::safe_step(&k, sigma, &g, required)
                .expect("step")
                .chosen_step()
                .expect("feasible");
            assert_eq!(s.step * u[kk], alpha * g[kk], "case {case}");
        }
    }
}

/// c₂ is c·p for a non-coordinate direction without a stated norm, c·(M₂/M_φ)² with one, c
/// for a coordinate; the thesis's constants refuse a non-coordinate direction.
#[test]
fn the_penalty_follows_the_feature_norm_and_the_family() {
    let k = tight();
    let c = c_printed(0.5);
    let u = [1e-3, -2e-3];
    let g = [1.0, 1.0];
    let penalty = |features| {
        DirectionBound::new(
            &k,
            0.5,
            &Direction {
                direction: &u,
                grad_hat: &g,
                eps: &[0.0, 0.0],
                features,
            },
        )
        .map(|b| b.penalty)
    };
    let rel = |x: f64, y: f64| (x - y).abs() <= 1e-12 * y;
    assert!(rel(
        penalty(FeatureNorm::FromMax { features: 5 }).expect("c2"),
        5.0 * c
    ));
    assert!(rel(
        penalty(FeatureNorm::Stated(6.0)).expect("c2"),
        c * 36.0 / 16.0
    ));
    let thesis = TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("constants");
    let d = Direction {
        direction: &u,
        grad_hat: &g,
        eps: &[0.0, 0.0],
        features: FeatureNorm::FromMax { features: 2 },
    };
    assert_eq!(
        DirectionBound::new(&thesis, 0.5, &d),
        Err(BoundsError::UnprovenDirection)
    );
}

/// Bad inputs are typed errors, never NaN or a panic.
#[test]
fn bad_inputs_are_typed_errors() {
    let k = tight();
    let f = FeatureNorm::FromMax { features: 1 };
    let make = |u: &'static [f64], g: &'static [f64], e: &'static [f64], features| Direction {
        direction: u,
        grad_hat: g,
        eps: e,
        features,
    };
    let err = |d: Direction| DirectionBound::new(&k, 1.0, &d).err();
    assert!(matches!(
        err(make(&[0.0], &[1.0], &[0.0], f)),
        Some(BoundsError::OutOfDomain {
            name: "direction",
            ..
        })
    ));
    assert!(matches!(
        err(make(&[1.0, 1.0], &[1.0], &[0.0, 0.0], f)),
        Some(BoundsError::LengthMismatch { .. })
    ));
    assert!(matches!(
        err(make(&[f64::NAN], &[1.0], &[0.0], f)),
        Some(BoundsError::NonFinite { .. })
    ));
    assert!(matches!(
        err(make(&[1.0], &[1.0], &[-1.0], f)),
        Some(BoundsError::OutOfDomain { name: "eps", .. })
    ));
    assert!(matches!(
        err(make(
            &[1.0],
            &[1.0],
            &[0.0],
            FeatureNorm::FromMax { features: 0 }
        )),
        Some(BoundsError::OutOfDomain { .. })
    ));
    assert!(matches!(
        err(make(
            &[1.0, 1.0],
            &[1.0, 1.0],
            &[0.0, 0.0],
            FeatureNorm::Stated(-1.0)
        )),
        Some(BoundsError::OutOfDomain { .. })
    ));
    assert!(err(make(&[], &[], &[], f)).is_some());
    assert!(DirectionBound::new(&k, 0.0, &make(&[1.0], &[1.0], &[0.0], f)).is_err());
    let b = DirectionBound::new(&k, 1.0, &make(&[1.0], &[1.0], &[0.0], f)).expect("bound");
    assert!(b.safe_step(f64::NAN, 1.0).is_err());
    assert!(b.safe_step(0.0, f64::NAN).is_err());
    assert!(b.safe_step(0.0, 0.0).is_err());
    assert!(b.bound(f64::INFINITY).is_err());
}
