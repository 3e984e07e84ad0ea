//! The task constants as the certified steps use them: with the decision, taken once, whether
//! they lie in the range of the a-priori rounding analysis.

use sepg_bounds::TaskConstants;

use crate::rounding;

/// [`TaskConstants`] together with whether R, M_φ, |A| and γ lie in the range where the
/// a-priori rounding-error bound of c(σ) and d(σ) holds (R, M_φ, |A| ∈ [2⁻¹⁰⁰, 2¹⁰⁰], γ = 0
/// or γ ≥ 2⁻¹⁰⁰, and the platform's ψ within one ulp of its enclosure; docs/THEOREMS.md,
/// "Certified steps"), decided once when it is built.
///
/// Every certified step function takes an [`AsCertifiedTask`]: pass `&TaskConstants` and the
/// range is decided at each call (a handful of comparisons), or build a `CertifiedTask` once
/// and pass `&CertifiedTask` to decide it once. The outcome is the same.
///
/// ```
/// use sepg_bounds::TaskConstants;
/// use sepg_certified::{CertifiedTask, v_safe_step};
/// let k = TaskConstants::new(0.99, 4.0, 2.0, 4.0)?;
/// let task = CertifiedTask::new(&k);
/// assert!(task.in_rounding_range());
/// assert_eq!(v_safe_step(&task, 1.0, &[0.8], 0.0)?, v_safe_step(&k, 1.0, &[0.8], 0.0)?);
/// let tiny = TaskConstants::new(0.99, 1e-31, 2.0, 4.0)?;
/// assert!(!CertifiedTask::new(&tiny).in_rounding_range());
/// # Ok::<(), sepg_bounds::BoundsError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CertifiedTask {
    constants: TaskConstants,
    in_range: bool,
}

impl CertifiedTask {
    /// The task constants `k` with their range decided.
    #[inline]
    pub fn new(k: &TaskConstants) -> Self {
        Self {
            constants: *k,
            in_range: rounding::task_in_box(k),
        }
    }

    /// The task constants.
    #[inline]
    pub fn constants(&self) -> &TaskConstants {
        &self.constants
    }

    /// Whether R, M_φ, |A| and γ lie in the range of the a-priori rounding analysis (σ is
    /// checked at each step).
    #[inline]
    pub fn in_rounding_range(&self) -> bool {
        self.in_range
    }
}

/// What a certified step function accepts as its task: `&TaskConstants`, whose rounding range
/// is then decided at each call, or `&CertifiedTask`, which decided it once.
pub trait AsCertifiedTask: Copy {
    /// The task constants.
    fn constants(&self) -> &TaskConstants;
    /// Whether R, M_φ, |A| and γ lie in the range of the a-priori rounding analysis.
    fn in_rounding_range(&self) -> bool;
}

impl AsCertifiedTask for &TaskConstants {
    #[inline(always)]
    fn constants(&self) -> &TaskConstants {
        self
    }

    #[inline(always)]
    fn in_rounding_range(&self) -> bool {
        rounding::task_in_box(self)
    }
}

impl AsCertifiedTask for &CertifiedTask {
    #[inline(always)]
    fn constants(&self) -> &TaskConstants {
        &self.constants
    }

    #[inline(always)]
    fn in_rounding_range(&self) -> bool {
        self.in_range
    }
}
