//! Student-t and normal quantiles against the 60-digit table of `scripts/gen_t_quantiles.py`
//! (ν from 1 to 10⁹ and ∞, p from 0.5 to 1 − 10⁻¹⁰). Stated relative tolerance: 1e-13
//! (worst case measured: 3.5e-14, at ν = 1000, p = 1 − 10⁻¹⁰).

use approx::relative_eq;
use sepg_estimators::{normal_quantile, student_t_quantile};

const TABLE: &str = include_str!("data/t_quantiles.csv");
const TOLERANCE: f64 = 1e-13;

/// (ν, p, t(p, ν)) rows; ν = ∞ rows hold the normal quantile.
fn rows() -> Vec<(f64, f64, f64)> {
    TABLE
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("nu"))
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
            (f[0], f[1], f[2])
        })
        .collect()
}

fn rel_err(got: f64, expected: f64) -> f64 {
    if expected == 0.0 {
        got.abs()
    } else {
        (got / expected - 1.0).abs()
    }
}

#[test]
fn t_quantile_matches_high_precision_table() {
    let rows = rows();
    assert!(rows.len() > 800);
    let mut worst = (0.0f64, 0.0, 0.0);
    for &(nu, p, expected) in &rows {
        let got = student_t_quantile(p, nu).unwrap();
        let err = rel_err(got, expected);
        if err > worst.0 {
            worst = (err, nu, p);
        }
        // Lower tail by symmetry: 1 − p is exact for p ≥ 1/2.
        assert_eq!(student_t_quantile(1.0 - p, nu).unwrap(), -got);
    }
    eprintln!("worst relative error {worst:?}");
    assert!(worst.0 < TOLERANCE, "worst relative error {worst:?}");
}

#[test]
fn normal_quantile_matches_table_limit() {
    for &(nu, p, expected) in rows().iter().filter(|r| r.0.is_infinite()) {
        let got = normal_quantile(p).unwrap();
        assert!(
            relative_eq!(got, expected, epsilon = TOLERANCE, max_relative = TOLERANCE),
            "nu {nu} p {p}: {got} vs {expected}"
        );
    }
}

#[test]
fn invalid_arguments_are_errors() {
    for p in [0.0, 1.0, -0.1, 1.5, f64::NAN] {
        assert!(student_t_quantile(p, 5.0).is_err());
        assert!(normal_quantile(p).is_err());
    }
    for nu in [0.0, 0.999, -1.0, f64::NAN] {
        assert!(student_t_quantile(0.9, nu).is_err());
    }
}
