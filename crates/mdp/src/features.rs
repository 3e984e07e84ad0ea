//! State feature maps `φ(s)` for the linear policy mean `μ(s) = Vᵀφ(s)` (eq. 4.7), with the
//! feature bound `M_φ ≥ max_{s ∈ S, i} |φ_i(s)|` used by the bounds of Chapter 4.

/// Validation errors of feature maps.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FeatureError {
    /// The state dimension or a grid size is zero.
    #[error("feature maps need a state dimension and grid sizes of at least 1")]
    EmptyDimension,
    /// Two inputs that must have the same length do not.
    #[error("{what} has length {found}, expected {expected}")]
    WrongLength {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A bound or state is NaN or infinite.
    #[error("{what} contains a non-finite value")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A grid box has `low ≥ high` in a component.
    #[error("grid box is not ordered in component {index}")]
    UnorderedBox {
        /// Component index.
        index: usize,
    },
    /// The grid has more than 2^20 centres.
    #[error("the RBF grid would have more than 2^20 centres")]
    TooManyCentres,
}

/// A grid of Gaussian radial basis functions over a box, optionally followed by a constant
/// bias feature.
///
/// Centres are evenly spaced, `k_d` per state component `d` (both ends included when
/// `k_d ≥ 2`, the midpoint when `k_d = 1`); the width in component `d` is the spacing
/// `h_d = (high_d − low_d)/(k_d − 1)` (the box width when `k_d = 1`). Centres are ordered with
/// the first state component varying slowest.
///
/// # Formula
/// ```text
/// φ_c(s) = exp(−½ Σ_d ((s_d − c_d)/h_d)²)   ∈ (0, 1],   M_φ = 1
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct RbfGrid {
    input_dim: usize,
    centres: Vec<f64>,
    inv_width: Vec<f64>,
    bias: bool,
}

impl RbfGrid {
    /// A grid of `per_dim[d]` centres in state component `d` over `[low, high]`, plus a
    /// constant feature 1 when `bias` is set.
    ///
    /// # Formula
    /// ```text
    /// c_d ∈ {low_d + i h_d},  h_d = (high_d − low_d)/(k_d − 1)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::features::RbfGrid;
    /// let g = RbfGrid::new(&[-1.2, -0.07], &[0.6, 0.07], &[5, 4], true).unwrap();
    /// assert_eq!(g.len(), 21);
    /// ```
    pub fn new(
        low: &[f64],
        high: &[f64],
        per_dim: &[usize],
        bias: bool,
    ) -> Result<Self, FeatureError> {
        let d = low.len();
        if d == 0 || per_dim.contains(&0) {
            return Err(FeatureError::EmptyDimension);
        }
        for (what, len) in [("high", high.len()), ("per_dim", per_dim.len())] {
            if len != d {
                return Err(FeatureError::WrongLength {
                    what,
                    expected: d,
                    found: len,
                });
            }
        }
        if !low.iter().chain(high).all(|x| x.is_finite()) {
            return Err(FeatureError::NonFinite { what: "grid box" });
        }
        if let Some(index) = (0..d).find(|&i| low[i] >= high[i]) {
            return Err(FeatureError::UnorderedBox { index });
        }
        let count = per_dim
            .iter()
            .try_fold(1usize, |acc, &k| {
                acc.checked_mul(k).filter(|&c| c <= 1 << 20)
            })
            .ok_or(FeatureError::TooManyCentres)?;
        let mut axes = Vec::with_capacity(d);
        let mut inv_width = Vec::with_capacity(d);
        for i in 0..d {
            let k = per_dim[i];
            let span = high[i] - low[i];
            let h = if k == 1 { span } else { span / (k - 1) as f64 };
            // A box wider than f64::MAX, or a spacing whose inverse overflows, has no usable
            // width (the features would be NaN).
            if !(span.is_finite() && (1.0 / h).is_finite()) {
                return Err(FeatureError::NonFinite {
                    what: "grid spacing (box too wide or too narrow)",
                });
            }
            let axis: Vec<f64> = if k == 1 {
                vec![low[i] + 0.5 * span]
            } else {
                (0..k).map(|j| low[i] + h * j as f64).collect()
            };
            if !axis.iter().all(|c| c.is_finite()) {
                return Err(FeatureError::NonFinite {
                    what: "grid centres (box too wide)",
                });
            }
            axes.push(axis);
            inv_width.push(1.0 / h);
        }
        let mut centres = Vec::with_capacity(count * d);
        for c in 0..count {
            let mut rem = c;
            let mut coords = vec![0.0; d];
            for i in (0..d).rev() {
                coords[i] = axes[i][rem % per_dim[i]];
                rem /= per_dim[i];
            }
            centres.extend_from_slice(&coords);
        }
        Ok(RbfGrid {
            input_dim: d,
            centres,
            inv_width,
            bias,
        })
    }

    /// Number of features (centres, plus one with the bias).
    ///
    /// ```
    /// let g = sepg_mdp::features::RbfGrid::new(&[0.0], &[1.0], &[3], false).unwrap();
    /// assert_eq!(g.len(), 3);
    /// ```
    pub fn len(&self) -> usize {
        self.centres.len() / self.input_dim + usize::from(self.bias)
    }

    /// Always `false`: a grid has at least one centre.
    ///
    /// ```
    /// assert!(!sepg_mdp::features::RbfGrid::new(&[0.0], &[1.0], &[1], false).unwrap().is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The centres, row-major (`len_centres × input_dim`).
    ///
    /// ```
    /// let g = sepg_mdp::features::RbfGrid::new(&[0.0], &[1.0], &[3], false).unwrap();
    /// assert_eq!(g.centres(), &[0.0, 0.5, 1.0]);
    /// ```
    pub fn centres(&self) -> &[f64] {
        &self.centres
    }

    fn eval_unchecked(&self, s: &[f64], out: &mut [f64]) {
        let d = self.input_dim;
        let (rbf, rest) = out.split_at_mut(self.centres.len() / d);
        for (o, c) in rbf.iter_mut().zip(self.centres.chunks_exact(d)) {
            let mut q = 0.0;
            for ((si, ci), iw) in s.iter().zip(c).zip(&self.inv_width) {
                let u = (si - ci) * iw;
                q += u * u;
            }
            *o = (-0.5 * q).exp();
        }
        if let Some(b) = rest.first_mut() {
            *b = 1.0;
        }
    }
}

/// A feature map `φ: R^n → R^p`.
#[derive(Debug, Clone, PartialEq)]
pub enum FeatureMap {
    /// `φ(s) = s` (`p = n`), the LQG features of Sec 5.1.
    Identity {
        /// State dimension `n`.
        dim: usize,
    },
    /// `φ(s) = [s, 1]` (`p = n + 1`).
    StateBias {
        /// State dimension `n`.
        dim: usize,
    },
    /// A Gaussian RBF grid ([`RbfGrid`]).
    Rbf(RbfGrid),
}

impl FeatureMap {
    /// State dimension `n` the map reads.
    ///
    /// ```
    /// use sepg_mdp::features::FeatureMap;
    /// assert_eq!(FeatureMap::StateBias { dim: 2 }.input_dim(), 2);
    /// ```
    pub fn input_dim(&self) -> usize {
        match self {
            FeatureMap::Identity { dim } | FeatureMap::StateBias { dim } => *dim,
            FeatureMap::Rbf(g) => g.input_dim,
        }
    }

    /// Number of features `p`.
    ///
    /// ```
    /// use sepg_mdp::features::FeatureMap;
    /// assert_eq!(FeatureMap::StateBias { dim: 2 }.dim(), 3);
    /// ```
    pub fn dim(&self) -> usize {
        match self {
            FeatureMap::Identity { dim } => *dim,
            FeatureMap::StateBias { dim } => dim + 1,
            FeatureMap::Rbf(g) => g.len(),
        }
    }

    /// `M_φ`, the largest `|φ_i(s)|` over the state box `[low, high]` (eq. 4.7's feature
    /// bound): `max_d max(|low_d|, |high_d|)` for the identity, the same or 1 with the bias,
    /// 1 for an RBF grid.
    ///
    /// # Formula
    /// ```text
    /// identity: M_φ = max_d max(|low_d|, |high_d|)
    /// state+bias: M_φ = max(1, max_d max(|low_d|, |high_d|))
    /// RBF: M_φ = 1
    /// ```
    ///
    /// ```
    /// use sepg_mdp::features::FeatureMap;
    /// let m = FeatureMap::StateBias { dim: 2 }.m_phi(&[-1.2, -0.07], &[0.6, 0.07]);
    /// assert_eq!(m, 1.2);
    /// ```
    pub fn m_phi(&self, low: &[f64], high: &[f64]) -> f64 {
        let state_max = low.iter().chain(high).fold(0.0_f64, |m, x| m.max(x.abs()));
        match self {
            FeatureMap::Identity { .. } => state_max,
            FeatureMap::StateBias { .. } => state_max.max(1.0),
            FeatureMap::Rbf(_) => 1.0,
        }
    }

    /// Evaluates `φ(s)` into `out` (length [`dim`](Self::dim)).
    ///
    /// # Formula
    /// ```text
    /// see the variants
    /// ```
    ///
    /// ```
    /// use sepg_mdp::features::FeatureMap;
    /// let mut phi = [0.0; 3];
    /// FeatureMap::StateBias { dim: 2 }.eval(&[0.5, -0.25], &mut phi).unwrap();
    /// assert_eq!(phi, [0.5, -0.25, 1.0]);
    /// ```
    pub fn eval(&self, s: &[f64], out: &mut [f64]) -> Result<(), FeatureError> {
        for (what, found, expected) in [
            ("s", s.len(), self.input_dim()),
            ("out", out.len(), self.dim()),
        ] {
            if found != expected {
                return Err(FeatureError::WrongLength {
                    what,
                    expected,
                    found,
                });
            }
        }
        if !s.iter().all(|x| x.is_finite()) {
            return Err(FeatureError::NonFinite { what: "s" });
        }
        self.eval_unchecked(s, out);
        Ok(())
    }

    /// `φ(s)` without checks (lengths guaranteed by the caller).
    #[inline]
    pub(crate) fn eval_unchecked(&self, s: &[f64], out: &mut [f64]) {
        match self {
            FeatureMap::Identity { .. } => out.copy_from_slice(s),
            FeatureMap::StateBias { dim } => {
                out[..*dim].copy_from_slice(s);
                out[*dim] = 1.0;
            }
            FeatureMap::Rbf(g) => g.eval_unchecked(s, out),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rbf_values_match_the_closed_form() {
        let g = RbfGrid::new(&[0.0, -1.0], &[2.0, 1.0], &[3, 2], true).unwrap();
        // Centres (first component slowest): (0,-1), (0,1), (1,-1), (1,1), (2,-1), (2,1);
        // widths h = (1, 2).
        assert_eq!(
            g.centres(),
            &[
                0.0, -1.0, 0.0, 1.0, 1.0, -1.0, 1.0, 1.0, 2.0, -1.0, 2.0, 1.0
            ]
        );
        let map = FeatureMap::Rbf(g);
        let mut phi = vec![0.0; map.dim()];
        map.eval(&[0.5, 0.0], &mut phi).unwrap();
        let expect =
            |c0: f64, c1: f64| (-0.5 * ((0.5 - c0).powi(2) + ((0.0 - c1) / 2.0).powi(2))).exp();
        let want = [
            expect(0.0, -1.0),
            expect(0.0, 1.0),
            expect(1.0, -1.0),
            expect(1.0, 1.0),
            expect(2.0, -1.0),
            expect(2.0, 1.0),
            1.0,
        ];
        for (a, b) in phi.iter().zip(want) {
            assert!((a - b).abs() < 1e-15);
        }
        assert_eq!(map.m_phi(&[0.0, -1.0], &[2.0, 1.0]), 1.0);
        assert!(phi.iter().all(|x| *x <= 1.0 && *x > 0.0));
    }

    #[test]
    fn bad_inputs_are_rejected() {
        assert_eq!(
            RbfGrid::new(&[0.0], &[0.0], &[2], false),
            Err(FeatureError::UnorderedBox { index: 0 })
        );
        assert_eq!(
            RbfGrid::new(&[0.0], &[1.0], &[0], false),
            Err(FeatureError::EmptyDimension)
        );
        assert_eq!(
            RbfGrid::new(&[0.0; 3], &[1.0; 3], &[128; 3], false),
            Err(FeatureError::TooManyCentres)
        );
        let mut out = [0.0; 2];
        assert!(
            FeatureMap::Identity { dim: 2 }
                .eval(&[f64::NAN, 0.0], &mut out)
                .is_err()
        );
        assert!(
            FeatureMap::Identity { dim: 2 }
                .eval(&[0.0], &mut out)
                .is_err()
        );
    }
}
