//! The Adam optimiser (Kingma and Ba 2015), used by the G(PO)MDP + Adam baseline of Table 5.1.
use serde::{Deserialize, Serialize};

/// Moment estimates of Adam for one parameter vector, part of the resumable state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdamMoments {
    /// First-moment estimate `m` (exponential average of gradients).
    pub m: Vec<f64>,
    /// Second-moment estimate `s` (exponential average of squared gradients).
    pub s: Vec<f64>,
    /// Number of steps taken so far.
    pub t: u64,
}

impl AdamMoments {
    /// Zero moments for a parameter vector of length `dim`.
    ///
    /// # Examples
    /// ```
    /// let m = sepg_algo::core::adam::AdamMoments::zeros(3);
    /// assert_eq!(m.m, vec![0.0; 3]);
    /// assert_eq!(m.t, 0);
    /// ```
    pub fn zeros(dim: usize) -> Self {
        AdamMoments {
            m: vec![0.0; dim],
            s: vec![0.0; dim],
            t: 0,
        }
    }

    /// One Adam ascent step: updates the moments with gradient `g` and returns the increment
    /// to add to the parameters.
    ///
    /// # Formula
    /// ```text
    /// t ← t + 1
    /// m ← β₁ m + (1 − β₁) g,      s ← β₂ s + (1 − β₂) g²
    /// Δθ = lr · (m / (1 − β₁ᵗ)) / (√(s / (1 − β₂ᵗ)) + ε)
    /// ```
    /// `lr > 0`, `β₁, β₂ ∈ [0, 1)`, `ε > 0` are validated by the configuration; `g` must
    /// have the length of the moments (a shorter `g` updates a prefix only).
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::adam::AdamMoments;
    /// let mut m = AdamMoments::zeros(1);
    /// // The first bias-corrected step has magnitude ≈ lr whatever the gradient scale.
    /// let d = m.step(&[250.0], 0.01, 0.9, 0.999, 1e-8);
    /// assert!((d[0] - 0.01).abs() < 1e-9);
    /// ```
    pub fn step(&mut self, g: &[f64], lr: f64, beta1: f64, beta2: f64, eps: f64) -> Vec<f64> {
        self.t += 1;
        let t = i32::try_from(self.t).unwrap_or(i32::MAX);
        let c1 = 1.0 - beta1.powi(t);
        let c2 = 1.0 - beta2.powi(t);
        g.iter()
            .zip(self.m.iter_mut().zip(self.s.iter_mut()))
            .map(|(&gi, (mi, si))| {
                *mi = beta1 * *mi + (1.0 - beta1) * gi;
                *si = beta2 * *si + (1.0 - beta2) * gi * gi;
                lr * (*mi / c1) / ((*si / c2).sqrt() + eps)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_hand_computed_second_step() {
        let (lr, b1, b2, eps) = (0.1, 0.9, 0.999, 1e-8);
        let mut m = AdamMoments::zeros(1);
        m.step(&[2.0], lr, b1, b2, eps);
        let d = m.step(&[-1.0], lr, b1, b2, eps);
        // m = 0.9·0.2 − 0.1 = 0.08, s = 0.999·0.004 + 0.001 = 0.004996
        let mhat = 0.08 / (1.0 - 0.81);
        let shat = 0.004996 / (1.0 - 0.999f64 * 0.999);
        let expected = lr * mhat / (shat.sqrt() + eps);
        assert!((d[0] - expected).abs() < 1e-12, "{} vs {expected}", d[0]);
        assert_eq!(m.t, 2);
    }
}
