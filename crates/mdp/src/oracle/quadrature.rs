//! Gauss–Legendre rules, the standard normal distribution and truncated normal moments.
//!
//! The complementary error function is the FreeBSD `s_erf.c` algorithm (rational
//! approximations on five ranges, error below one unit in the last place):
//!
//! ```text
//! Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
//! Developed at SunPro, a Sun Microsystems, Inc. business.
//! Permission to use, copy, modify, and distribute this software is freely granted,
//! provided that this notice is preserved.
//! ```
//!
//! It replaces `statrs::function::erf::erfc`, whose relative error reaches `1e-10` near
//! `x = 0.5` (statrs 0.19.1), too large for the masses of the clipped DP.

/// The `p` first-kind Chebyshev nodes on `[−1, 1]` and their barycentric weights: the
/// interpolation of a function from its values at the nodes (Berrut & Trefethen, "Barycentric
/// Lagrange interpolation", SIAM Review 46(3), 2004, eq. 5.3 with first-kind nodes).
#[derive(Debug, Clone)]
pub(crate) struct Chebyshev {
    /// `cos((2j + 1)π / 2p)`, `j < p` (decreasing).
    pub nodes: Vec<f64>,
    /// `(−1)^j sin((2j + 1)π / 2p)`.
    bary: Vec<f64>,
}

impl Chebyshev {
    /// The rule with `p` nodes.
    pub fn new(p: usize) -> Self {
        let pf = p as f64;
        let theta = |j: usize| std::f64::consts::PI * (2 * j + 1) as f64 / (2.0 * pf);
        let nodes = (0..p).map(|j| theta(j).cos()).collect();
        let bary = (0..p)
            .map(|j| if j % 2 == 0 { 1.0 } else { -1.0 } * theta(j).sin())
            .collect();
        Chebyshev { nodes, bary }
    }

    /// The weights of the nodes at `t ∈ [−1, 1]` into `out[..p]` (barycentric formula; the
    /// unit vector at a node): the interpolant at `t` is `Σ out[j] f(nodes[j])`.
    pub fn weights(&self, t: f64, out: &mut [f64]) {
        let p = self.nodes.len();
        let mut total = 0.0;
        for j in 0..p {
            let d = t - self.nodes[j];
            if d == 0.0 {
                out[..p].iter_mut().for_each(|x| *x = 0.0);
                out[j] = 1.0;
                return;
            }
            out[j] = self.bary[j] / d;
            total += out[j];
        }
        let inv = 1.0 / total;
        out[..p].iter_mut().for_each(|x| *x *= inv);
    }
}

/// `Σ a_i b_i` with four independent partial sums (a fixed order: deterministic).
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let (ca, ra) = a.as_chunks::<4>();
    let (cb, rb) = b.as_chunks::<4>();
    let (mut s0, mut s1, mut s2, mut s3) = (0.0, 0.0, 0.0, 0.0);
    for (x, y) in ca.iter().zip(cb) {
        s0 += x[0] * y[0];
        s1 += x[1] * y[1];
        s2 += x[2] * y[2];
        s3 += x[3] * y[3];
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (s0 + s2) + (s1 + s3) + tail
}

/// `1/√(2π)`.
const INV_SQRT_2PI: f64 = 0.398_942_280_401_432_7;

/// An `n`-point Gauss–Legendre rule on `[−1, 1]` (exact for polynomials of degree `2n − 1`).
#[derive(Debug, Clone)]
pub(crate) struct GaussLegendre {
    /// Nodes in `(−1, 1)`, increasing.
    pub nodes: Vec<f64>,
    /// Positive weights summing to 2.
    pub weights: Vec<f64>,
}

impl GaussLegendre {
    /// Nodes by Newton's method on `P_n` from the Chebyshev-like initial guesses (converged
    /// to machine precision), weights `2 / ((1 − x²) P_n'(x)²)`.
    pub fn new(n: usize) -> Self {
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n {
            let mut x = -(std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() <= 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            if d.is_finite() {
                dp = d;
            }
            nodes[i] = x;
            weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
        }
        GaussLegendre { nodes, weights }
    }
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

/// Standard normal density `φ(z)`.
pub(crate) fn norm_pdf(z: f64) -> f64 {
    INV_SQRT_2PI * (-0.5 * z * z).exp()
}

/// Standard normal CDF `Φ(z)` with full relative accuracy in the lower tail.
pub(crate) fn norm_cdf(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

/// Coefficients of s_erf.c (see the module documentation for the notice), as published: the
/// decimal expansions are longer than binary64 needs and round to the intended values.
mod coeffs {
    #![allow(clippy::excessive_precision)]
    pub(super) const ERX: f64 = 8.45062911510467529297e-01;
    pub(super) const PP: [f64; 5] = [
        1.28379167095512558561e-01,
        -3.25042107247001499370e-01,
        -2.84817495755985104766e-02,
        -5.77027029648944159157e-03,
        -2.37630166566501626084e-05,
    ];
    pub(super) const QQ: [f64; 6] = [
        1.0,
        3.97917223959155352819e-01,
        6.50222499887672944485e-02,
        5.08130628187576562776e-03,
        1.32494738004321644526e-04,
        -3.96022827877536812320e-06,
    ];
    pub(super) const PA: [f64; 7] = [
        -2.36211856075265944077e-03,
        4.14856118683748331666e-01,
        -3.72207876035701323847e-01,
        3.18346619901161753674e-01,
        -1.10894694282396677476e-01,
        3.54783043256182359371e-02,
        -2.16637559486879084300e-03,
    ];
    pub(super) const QA: [f64; 7] = [
        1.0,
        1.06420880400844228286e-01,
        5.40397917702171048937e-01,
        7.18286544141962662868e-02,
        1.26171219808761642112e-01,
        1.36370839120290507362e-02,
        1.19844998467991074170e-02,
    ];
    pub(super) const RA: [f64; 8] = [
        -9.86494403484714822705e-03,
        -6.93858572707181764372e-01,
        -1.05586262253232909814e+01,
        -6.23753324503260060396e+01,
        -1.62396669462573470355e+02,
        -1.84605092906711035994e+02,
        -8.12874355063065934246e+01,
        -9.81432934416914548592e+00,
    ];
    pub(super) const SA: [f64; 9] = [
        1.0,
        1.96512716674392571292e+01,
        1.37657754143519042600e+02,
        4.34565877475229228821e+02,
        6.45387271733267880336e+02,
        4.29008140027567833386e+02,
        1.08635005541779435134e+02,
        6.57024977031928170135e+00,
        -6.04244152148580987438e-02,
    ];
    pub(super) const RB: [f64; 7] = [
        -9.86494292470009928597e-03,
        -7.99283237680523006574e-01,
        -1.77579549177547519889e+01,
        -1.60636384855821916062e+02,
        -6.37566443368389627722e+02,
        -1.02509513161107724954e+03,
        -4.83519191608651397019e+02,
    ];
    pub(super) const SB: [f64; 8] = [
        1.0,
        3.03380607434824582924e+01,
        3.25792512996573918826e+02,
        1.53672958608443695994e+03,
        3.19985821950859553908e+03,
        2.55305040643316442583e+03,
        4.74528541206955367215e+02,
        -2.24409524465858183362e+01,
    ];
}

use coeffs::{ERX, PA, PP, QA, QQ, RA, RB, SA, SB};

/// Horner evaluation of `Σ c_k x^k`.
fn poly(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * x + ck)
}

/// `erfc(|x|)` for `0.84375 ≤ |x| < 28` (s_erf.c `erfc2`, `ix` the high word of `|x|`).
fn erfc_mid(ix: u32, x: f64) -> f64 {
    let x = x.abs();
    if ix < 0x3ff4_0000 {
        let s = x - 1.0;
        return 1.0 - ERX - poly(&PA, s) / poly(&QA, s);
    }
    let s = 1.0 / (x * x);
    let (r, big_s) = if ix < 0x4006_db6d {
        (poly(&RA, s), poly(&SA, s))
    } else {
        (poly(&RB, s), poly(&SB, s))
    };
    let z = f64::from_bits(x.to_bits() & 0xffff_ffff_0000_0000);
    (-z * z - 0.5625).exp() * ((z - x) * (z + x) + r / big_s).exp() / x
}

/// The complementary error function `erfc(x) = (2/√π) ∫_x^∞ e^{−t²} dt`, error below one
/// unit in the last place (s_erf.c).
pub(crate) fn erfc(x: f64) -> f64 {
    let hi = (x.to_bits() >> 32) as u32;
    let negative = hi >> 31 != 0;
    let ix = hi & 0x7fff_ffff;
    if ix >= 0x7ff0_0000 {
        return if x.is_nan() {
            x
        } else if negative {
            2.0
        } else {
            0.0
        };
    }
    if ix < 0x3feb_0000 {
        if ix < 0x3c70_0000 {
            return 1.0 - x;
        }
        let z = x * x;
        let y = poly(&PP, z) / poly(&QQ, z);
        if negative || ix < 0x3fd0_0000 {
            return 1.0 - (x + x * y);
        }
        return 0.5 - (x - 0.5 + x * y);
    }
    if ix < 0x403c_0000 {
        let t = erfc_mid(ix, x);
        return if negative { 2.0 - t } else { t };
    }
    if negative { 2.0 } else { 0.0 }
}

/// `∫_α^β z^k φ(z) dz` for `k = 0..=6` (either end may be infinite), by the recurrence
/// `M_k = (k − 1) M_{k−2} + α^{k−1} φ(α) − β^{k−1} φ(β)`.
///
/// On a finite interval of width at most 1 the recurrence would cancel; a 16-point
/// Gauss–Legendre rule is used there instead (exact to rounding: `φ` is entire and the rule
/// integrates polynomials of degree 31).
pub(crate) fn normal_moments(alpha: f64, beta: f64) -> [f64; 7] {
    if beta - alpha <= 1.0 {
        static RULE: std::sync::OnceLock<GaussLegendre> = std::sync::OnceLock::new();
        let rule = RULE.get_or_init(|| GaussLegendre::new(16));
        let (mid, half) = (0.5 * (alpha + beta), 0.5 * (beta - alpha));
        let mut m = [0.0; 7];
        for (x, w) in rule.nodes.iter().zip(&rule.weights) {
            let z = mid + half * x;
            let mut term = w * half * norm_pdf(z);
            for mk in m.iter_mut() {
                *mk += term;
                term *= z;
            }
        }
        return m;
    }
    let mass = if alpha > 0.0 {
        norm_cdf(-alpha) - norm_cdf(-beta)
    } else {
        norm_cdf(beta) - norm_cdf(alpha)
    };
    let pa = if alpha.is_finite() {
        norm_pdf(alpha)
    } else {
        0.0
    };
    let pb = if beta.is_finite() {
        norm_pdf(beta)
    } else {
        0.0
    };
    let pow = |x: f64, k: i32, px: f64| if px == 0.0 { 0.0 } else { x.powi(k) * px };
    let mut m = [0.0; 7];
    m[0] = mass;
    m[1] = pa - pb;
    for k in 2..7 {
        let e = (k - 1) as i32;
        m[k] = (k as f64 - 1.0) * m[k - 2] + pow(alpha, e, pa) - pow(beta, e, pb);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Φ(z)` at 50 digits by `scripts/gen_lqg_reference.py`.
    const NORMAL_CDF: &str = include_str!("../../tests/data/normal_cdf.csv");

    #[test]
    fn normal_cdf_matches_the_high_precision_table() {
        let mut rows = 0;
        for line in NORMAL_CDF.lines().skip(1) {
            let mut it = line.split(',').map(|x| x.parse::<f64>().unwrap());
            let (z, phi) = (it.next().unwrap(), it.next().unwrap());
            let got = norm_cdf(z);
            // A few units in the last place, plus the conditioning of Φ in its argument
            // (relative error ≈ z² ε from rounding z/√2); subnormal results lose bits.
            let tol = if phi > 1e-300 {
                (2e-15 + 2.0 * z * z * f64::EPSILON) * phi
            } else {
                1e-310
            };
            assert!((got - phi).abs() <= tol, "Φ({z}) = {got}, table {phi}");
            rows += 1;
        }
        assert!(rows > 150);
        assert_eq!(erfc(f64::INFINITY), 0.0);
        assert_eq!(erfc(f64::NEG_INFINITY), 2.0);
        assert!(erfc(f64::NAN).is_nan());
        assert_eq!(erfc(30.0), 0.0);
        assert_eq!(erfc(-30.0), 2.0);
    }

    #[test]
    fn chebyshev_interpolation_reproduces_polynomials_below_its_degree() {
        // f(x) = x³ − 2x + 0.5 (degree 3 < p = 6): the interpolant is f itself.
        let f = |x: f64| x * x * x - 2.0 * x + 0.5;
        let rule = Chebyshev::new(6);
        let mut w = vec![0.0; 6];
        for t in [-1.0, -0.7, 0.0, 0.3, 0.95, 1.0, rule.nodes[2]] {
            rule.weights(t, &mut w);
            let value: f64 = w.iter().zip(&rule.nodes).map(|(wj, x)| wj * f(*x)).sum();
            assert!((value - f(t)).abs() < 1e-14, "t = {t}: {value} vs {}", f(t));
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        }
        // `dot` is Σ aᵢbᵢ whatever the length (a multiple of 4 or not).
        let a: Vec<f64> = (1..=7).map(f64::from).collect();
        assert_eq!(dot(&a, &a), 140.0);
        assert_eq!(dot(&a[..4], &a[..4]), 30.0);
    }

    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
        for n in [2, 5, 10, 24] {
            let gl = GaussLegendre::new(n);
            assert!((gl.weights.iter().sum::<f64>() - 2.0).abs() < 1e-14);
            for k in 0..2 * n {
                let q: f64 = gl
                    .nodes
                    .iter()
                    .zip(&gl.weights)
                    .map(|(x, w)| w * x.powi(k as i32))
                    .sum();
                let exact = if k % 2 == 1 {
                    0.0
                } else {
                    2.0 / (k as f64 + 1.0)
                };
                assert!((q - exact).abs() < 1e-14, "n={n} k={k}: {q} vs {exact}");
            }
        }
    }

    #[test]
    fn normal_moments_match_full_line_and_quadrature() {
        let full = normal_moments(f64::NEG_INFINITY, f64::INFINITY);
        for (m, e) in full.iter().zip([1.0, 0.0, 1.0, 0.0, 3.0, 0.0, 15.0]) {
            assert!((m - e).abs() < 1e-15);
        }
        // Against a 24-point rule on 200 sub-intervals (error far below 1e-13).
        let gl = GaussLegendre::new(24);
        for (a, b) in [
            (-1.0, 0.5),
            (-1.0, 1.5),
            (2.0, 7.0),
            (-9.0, -8.5),
            (0.3, 0.3001),
        ] {
            let m = normal_moments(a, b);
            for (k, mk) in m.iter().enumerate() {
                let h = (b - a) / 200.0;
                let mut q = 0.0;
                for i in 0..200 {
                    let mid = a + h * (i as f64 + 0.5);
                    for (x, w) in gl.nodes.iter().zip(&gl.weights) {
                        let z = mid + 0.5 * h * x;
                        q += 0.5 * h * w * z.powi(k as i32) * norm_pdf(z);
                    }
                }
                assert!(
                    (mk - q).abs() < 1e-13 * q.abs() + 1e-17,
                    "[{a},{b}] k={k}: {mk} vs {q}"
                );
            }
        }
        // Lower tail keeps full relative accuracy far from the mean.
        let tail = normal_moments(f64::NEG_INFINITY, -30.0)[0];
        assert!((tail / 4.906713927148187e-198 - 1.0).abs() < 1e-12);
    }
}
