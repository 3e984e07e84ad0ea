//! Reference implementations written from the thesis formulas, independent of the crate's code
//! paths, and a golden-section maximiser.

use approx::relative_eq;
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::outcome::{SafeInterval, StepOutcome};
pub use sepg_testkit::close;
use sepg_testkit::simpson;

/// c(σ) of Theorem 3.14 evaluated straight from the printed formula.
pub fn c_ref(k: &TaskConstants, sigma: f64) -> f64 {
    let (g, r, m, a) = (k.gamma(), k.r_max(), k.m_phi(), k.action_volume());
    r * m * m / ((1.0 - g).powi(2) * sigma.powi(2))
        * (a / ((2.0 * std::f64::consts::PI).sqrt() * sigma) + g / (2.0 * (1.0 - g)))
}

/// ∫_ℝ |p(z)| φ(z) dz by Simpson on [0, 40] (doubled: p is even), split at the given positive
/// roots of p so that every panel integrates a smooth function.
fn abs_gaussian_moment(p: impl Fn(f64) -> f64 + Copy, roots: &[f64]) -> f64 {
    let phi = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let mut cuts = vec![0.0];
    cuts.extend_from_slice(roots);
    cuts.push(40.0);
    2.0 * cuts
        .windows(2)
        .map(|w| simpson(|z| p(z).abs() * phi(z), w[0], w[1], 20_000))
        .sum::<f64>()
}

/// K_W = ∫_ℝ |z⁴ − 4z² + 1| φ(z) dz by quadrature (roots z² = 2 ∓ √3).
pub fn k_w_numeric() -> f64 {
    let s3 = 3.0_f64.sqrt();
    abs_gaussian_moment(
        |z| z.powi(4) - 4.0 * z * z + 1.0,
        &[(2.0 - s3).sqrt(), (2.0 + s3).sqrt()],
    )
}

/// K_MU = ∫_ℝ |z² − 1| φ(z) dz by quadrature (root z = 1).
pub fn k_mu_numeric() -> f64 {
    abs_gaussian_moment(|z| z * z - 1.0, &[1.0])
}

/// ψ from a numeric maximisation of |(χ² − 4χ + 1)e^{−χ/2}| / √(2π) over χ ≥ 0.
pub fn psi_numeric() -> f64 {
    let f = |x: f64| (x * x - 4.0 * x + 1.0).abs() * (-x / 2.0).exp();
    // dense grid on [0, 60] (beyond 60, |f| < 60² e^{-30} ≈ 3e-10), then golden refinement
    let step = 1e-3;
    let best = (0..=60_000)
        .map(|i| i as f64 * step)
        .max_by(|a, b| f(*a).total_cmp(&f(*b)))
        .unwrap();
    let x = golden_max(f, (best - step).max(0.0), best + step);
    f(x) / (2.0 * std::f64::consts::PI).sqrt()
}

/// d(σ) of Theorem 4.3 from the printed formula, with ψ found numerically.
pub fn d_ref(k: &TaskConstants, sigma: f64, psi: f64) -> f64 {
    let (g, r, a) = (k.gamma(), k.r_max(), k.action_volume());
    r / (1.0 - g).powi(2) * (psi * a / (2.0 * sigma) + g / (1.0 - g))
}

/// The maximiser of a unimodal function on [lo, hi] by golden-section search.
pub fn golden_max(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let r = (5.0_f64.sqrt() - 1.0) / 2.0;
    let mut x1 = hi - r * (hi - lo);
    let mut x2 = lo + r * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..400 {
        if f1 < f2 {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + r * (hi - lo);
            f2 = f(x2);
        } else {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - r * (hi - lo);
            f1 = f(x1);
        }
        if hi - lo <= 1e-15 * (lo.abs() + hi.abs()) {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// A few task-constant sets used across the tests (the `lqg`, `lqg1d` and Mountain Car
/// presets of docs/CONVENTIONS.md §1 plus an undiscounted-ish extreme).
pub fn presets() -> Vec<TaskConstants> {
    vec![
        TaskConstants::new(0.99, 4.0, 2.0, 4.0).unwrap(),
        TaskConstants::new(0.99, 28.8, 4.0, 8.0).unwrap(),
        TaskConstants::new(0.9, 100.0, 1.0, 2.0).unwrap(),
        TaskConstants::new(0.0, 1.0, 0.5, 0.25).unwrap(),
    ]
}

/// A bound given as a function returning (value, scale of its terms).
pub fn check_interval(bound: &dyn Fn(f64) -> (f64, f64), s: &SafeInterval, required: f64) {
    for x in [s.lo, s.hi] {
        let (v, scale) = bound(x);
        assert!(
            relative_eq!(v, required, epsilon = 1e-10 * scale, max_relative = 1e-10),
            "B({x}) = {v}, C = {required}"
        );
    }
    let span = s.hi.abs().max(s.lo.abs());
    for i in 1..20 {
        let x = s.lo + (s.hi - s.lo) * f64::from(i) / 20.0;
        let (v, scale) = bound(x);
        assert!(
            v >= required - 1e-12 * scale,
            "inside: B({x}) = {v} < C = {required}"
        );
    }
    let offset = 1e-4 * (s.hi - s.lo) + 1e-6 * span;
    for x in [s.lo - offset, s.hi + offset] {
        assert!(bound(x).0 < required, "outside: B({x}) ≥ C = {required}");
    }
    let slack = 1e-12 * span;
    assert!(s.lo - slack <= s.vertex && s.vertex <= s.hi + slack);
}

pub fn feasible(o: StepOutcome) -> SafeInterval {
    match o {
        StepOutcome::Feasible(s) => s,
        other => panic!("expected a feasible outcome, got {other:?}"),
    }
}

/// Quadratic a x − b x² with its term scale.
pub fn quad(a: f64, b: f64) -> impl Fn(f64) -> (f64, f64) {
    move |x| (a * x - b * x * x, (a * x).abs().max(b * x * x))
}

/// Required improvements as fractions of C_max: required improvements, C = 0 and bounded
/// worsenings down to −10 C_max, plus tiny fractions where naive formulas cancel.
pub const FRACTIONS: [f64; 9] = [1.0, 0.999_999, 0.75, 1e-6, 0.0, -1e-6, -0.3, -2.0, -10.0];

pub const SIGMAS: [f64; 3] = [0.1, 0.5, 2.0];

pub fn l1sq(x: &[f64]) -> f64 {
    x.iter().map(|v| v.abs()).sum::<f64>().powi(2)
}

pub fn l2sq(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

/// Maximises a·x − b·x² (b > 0) numerically over the bracket between its roots.
pub fn numeric_vertex(poly: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let root = a / b;
    golden_max(poly, root.min(0.0) - 1e-300, root.max(0.0) + 1e-300)
}
