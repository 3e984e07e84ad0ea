//! Second-order forward-mode differentiation ("jets") of matrix expressions.
//!
//! A [`MatJet`] carries a matrix `X(θ)` together with its first derivatives `∂X/∂θ_i` and its
//! second derivatives `∂²X/∂θ_i∂θ_j` (`i ≤ j`, packed) with respect to `p` parameters. Sums,
//! products and transposes propagate all three exactly (Leibniz rule), so any recursion built
//! from them yields derivatives exact up to rounding.
//!
//! # Formula
//! ```text
//! (XY)'_i   = X'_i Y + X Y'_i
//! (XY)''_ij = X''_ij Y + X'_i Y'_j + X'_j Y'_i + X Y''_ij
//! ```

use nalgebra::DMatrix;

/// Index of the pair `(i, j)`, `i ≤ j < p`, in the packed upper triangle.
pub(crate) fn tri(i: usize, j: usize, p: usize) -> usize {
    let (i, j) = if i <= j { (i, j) } else { (j, i) };
    i * (2 * p - i + 1) / 2 + (j - i)
}

/// Number of packed second derivatives for `p` parameters.
pub(crate) fn tri_len(p: usize) -> usize {
    p * (p + 1) / 2
}

/// A matrix with its first and second derivatives with respect to `p` parameters.
#[derive(Debug, Clone)]
pub(crate) struct MatJet {
    /// The value `X`.
    pub val: DMatrix<f64>,
    /// `∂X/∂θ_i`, `i < p`.
    pub d1: Vec<DMatrix<f64>>,
    /// `∂²X/∂θ_i∂θ_j` at packed index [`tri`]`(i, j, p)`.
    pub d2: Vec<DMatrix<f64>>,
}

/// A scalar with its gradient and packed Hessian with respect to `p` parameters.
#[derive(Debug, Clone)]
pub(crate) struct ScalarJet {
    /// The value.
    pub val: f64,
    /// Gradient.
    pub d1: Vec<f64>,
    /// Packed Hessian (upper triangle, [`tri`]).
    pub d2: Vec<f64>,
}

impl MatJet {
    /// A constant (all derivatives zero).
    pub fn constant(val: DMatrix<f64>, p: usize) -> Self {
        let (r, c) = val.shape();
        MatJet {
            val,
            d1: vec![DMatrix::zeros(r, c); p],
            d2: vec![DMatrix::zeros(r, c); tri_len(p)],
        }
    }

    /// Number of parameters.
    pub fn p(&self) -> usize {
        self.d1.len()
    }

    /// `X + Y`.
    pub fn add(&self, other: &MatJet) -> MatJet {
        MatJet {
            val: &self.val + &other.val,
            d1: self.d1.iter().zip(&other.d1).map(|(a, b)| a + b).collect(),
            d2: self.d2.iter().zip(&other.d2).map(|(a, b)| a + b).collect(),
        }
    }

    /// `c X` for a constant `c`.
    pub fn scale(&self, c: f64) -> MatJet {
        MatJet {
            val: &self.val * c,
            d1: self.d1.iter().map(|a| a * c).collect(),
            d2: self.d2.iter().map(|a| a * c).collect(),
        }
    }

    /// `Xᵀ`.
    pub fn transpose(&self) -> MatJet {
        MatJet {
            val: self.val.transpose(),
            d1: self.d1.iter().map(|a| a.transpose()).collect(),
            d2: self.d2.iter().map(|a| a.transpose()).collect(),
        }
    }

    /// `X Y` (Leibniz rule up to second order).
    pub fn mul(&self, other: &MatJet) -> MatJet {
        let p = self.p();
        let d1: Vec<DMatrix<f64>> = (0..p)
            .map(|i| &self.d1[i] * &other.val + &self.val * &other.d1[i])
            .collect();
        let mut d2 = Vec::with_capacity(tri_len(p));
        for i in 0..p {
            for j in i..p {
                let k = tri(i, j, p);
                let mut m = &self.d2[k] * &other.val + &self.val * &other.d2[k];
                m += &self.d1[i] * &other.d1[j];
                m += &self.d1[j] * &other.d1[i];
                d2.push(m);
            }
        }
        MatJet {
            val: &self.val * &other.val,
            d1,
            d2,
        }
    }

    /// `tr(X Y)` as a scalar jet.
    pub fn trace_mul(&self, other: &MatJet) -> ScalarJet {
        let p = self.p();
        let tm = |a: &DMatrix<f64>, b: &DMatrix<f64>| a.component_mul(&b.transpose()).sum();
        let d1 = (0..p)
            .map(|i| tm(&self.d1[i], &other.val) + tm(&self.val, &other.d1[i]))
            .collect();
        let mut d2 = Vec::with_capacity(tri_len(p));
        for i in 0..p {
            for j in i..p {
                let k = tri(i, j, p);
                d2.push(
                    tm(&self.d2[k], &other.val)
                        + tm(&self.val, &other.d2[k])
                        + tm(&self.d1[i], &other.d1[j])
                        + tm(&self.d1[j], &other.d1[i]),
                );
            }
        }
        ScalarJet {
            val: tm(&self.val, &other.val),
            d1,
            d2,
        }
    }

    /// The largest absolute entry over the value and every derivative.
    pub fn max_abs(&self) -> f64 {
        self.d1
            .iter()
            .chain(&self.d2)
            .fold(self.val.amax(), |m, a| m.max(a.amax()))
    }

    /// Whether every entry of the value and of every derivative is finite.
    pub fn is_finite(&self) -> bool {
        std::iter::once(&self.val)
            .chain(&self.d1)
            .chain(&self.d2)
            .all(|a| a.iter().all(|x| x.is_finite()))
    }
}

impl ScalarJet {
    /// The zero scalar.
    pub fn zero(p: usize) -> Self {
        ScalarJet {
            val: 0.0,
            d1: vec![0.0; p],
            d2: vec![0.0; tri_len(p)],
        }
    }

    /// `a + b`.
    pub fn add(&self, other: &ScalarJet) -> ScalarJet {
        ScalarJet {
            val: self.val + other.val,
            d1: self.d1.iter().zip(&other.d1).map(|(a, b)| a + b).collect(),
            d2: self.d2.iter().zip(&other.d2).map(|(a, b)| a + b).collect(),
        }
    }

    /// `c a` for a constant `c`.
    pub fn scale(&self, c: f64) -> ScalarJet {
        ScalarJet {
            val: self.val * c,
            d1: self.d1.iter().map(|a| a * c).collect(),
            d2: self.d2.iter().map(|a| a * c).collect(),
        }
    }

    /// Whether the value and every derivative are finite.
    pub fn is_finite(&self) -> bool {
        self.val.is_finite()
            && self.d1.iter().all(|x| x.is_finite())
            && self.d2.iter().all(|x| x.is_finite())
    }
}

/// A first-order dual number `x + x' ε`: a value and its derivative in one parameter,
/// propagated exactly by sums and products (the clipped DP carries `∂/∂v` with it).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Dual {
    /// The value.
    pub x: f64,
    /// The derivative.
    pub d: f64,
}

impl Dual {
    /// A constant (derivative zero).
    pub fn c(x: f64) -> Self {
        Dual { x, d: 0.0 }
    }

    /// `self + o`.
    pub fn add(self, o: Dual) -> Dual {
        Dual {
            x: self.x + o.x,
            d: self.d + o.d,
        }
    }

    /// `self · o` (product rule).
    pub fn mul(self, o: Dual) -> Dual {
        Dual {
            x: self.x * o.x,
            d: self.d * o.x + self.x * o.d,
        }
    }

    /// `c · self` for a constant `c`.
    pub fn scale(self, c: f64) -> Dual {
        Dual {
            x: self.x * c,
            d: self.d * c,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_index_enumerates_the_upper_triangle() {
        for p in 1..7 {
            let mut expected = 0;
            for i in 0..p {
                for j in i..p {
                    assert_eq!(tri(i, j, p), expected);
                    assert_eq!(tri(j, i, p), expected);
                    expected += 1;
                }
            }
            assert_eq!(expected, tri_len(p));
        }
    }

    #[test]
    fn product_rule_to_second_order() {
        // x(θ) = θ0 θ1 (as 1×1 matrices built from seeds), y = x², tr(y) = θ0² θ1².
        let p = 2;
        let mut a = MatJet::constant(DMatrix::from_element(1, 1, 3.0), p);
        a.d1[0][(0, 0)] = 1.0;
        let mut b = MatJet::constant(DMatrix::from_element(1, 1, 5.0), p);
        b.d1[1][(0, 0)] = 1.0;
        let x = a.mul(&b);
        let y = x.mul(&x).add(&x.scale(2.0)).transpose();
        let s = y.trace_mul(&MatJet::constant(DMatrix::identity(1, 1), p));
        // f = θ0²θ1² + 2θ0θ1 at (3, 5).
        assert_eq!(s.val, 225.0 + 30.0);
        assert_eq!(s.d1, vec![2.0 * 3.0 * 25.0 + 10.0, 2.0 * 9.0 * 5.0 + 6.0]);
        assert_eq!(s.d2, vec![2.0 * 25.0, 4.0 * 15.0 + 2.0, 2.0 * 9.0]);
        assert!(s.is_finite() && x.is_finite());
        assert_eq!(x.max_abs(), 15.0);
        let z = ScalarJet::zero(p).add(&s).scale(0.5);
        assert_eq!(z.val, 127.5);
    }

    #[test]
    fn dual_numbers_differentiate_a_polynomial() {
        // f(x) = 3 (x² + 2x) + 1 at x = 4: f = 73, f' = 3 (2x + 2) = 30.
        let x = Dual { x: 4.0, d: 1.0 };
        let f = x.mul(x).add(x.scale(2.0)).scale(3.0).add(Dual::c(1.0));
        assert_eq!((f.x, f.d), (73.0, 30.0));
    }
}
