//! Reference implementations written from the thesis formulas, independent of the crate's code
//! paths, and a golden-section maximiser.

use sepg_bounds::constants::TaskConstants;

/// c(σ) of Theorem 3.14 evaluated straight from the printed formula.
pub fn c_ref(k: &TaskConstants, sigma: f64) -> f64 {
    let (g, r, m, a) = (k.gamma(), k.r_max(), k.m_phi(), k.action_volume());
    r * m * m / ((1.0 - g).powi(2) * sigma.powi(2))
        * (a / ((2.0 * std::f64::consts::PI).sqrt() * sigma) + g / (2.0 * (1.0 - g)))
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

/// Relative closeness with an absolute floor given by `scale`.
pub fn close(a: f64, b: f64, rel: f64, scale: f64) -> bool {
    (a - b).abs() <= rel * (a.abs().max(b.abs()).max(scale))
}

/// A few task-constant sets used across the tests (the `lqg`, `lqg1d` and Mountain Car
/// presets of SPEC §1 plus an undiscounted-ish extreme).
pub fn presets() -> Vec<TaskConstants> {
    vec![
        TaskConstants::new(0.99, 4.0, 2.0, 4.0).unwrap(),
        TaskConstants::new(0.99, 28.8, 4.0, 8.0).unwrap(),
        TaskConstants::new(0.9, 100.0, 1.0, 2.0).unwrap(),
        TaskConstants::new(0.0, 1.0, 0.5, 0.25).unwrap(),
    ]
}
