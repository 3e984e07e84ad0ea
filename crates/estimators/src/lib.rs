//! Policy-gradient estimators of Safely-Exploring Policy Gradient: REINFORCE, G(PO)MDP and PGT
//! with baselines (thesis Sec 2.3.1–2.3.2), the estimator of `h(θ)` and the cross-fitted
//! surrogate gradient `∇_w L` (Appendix B), and the confidence widths and corrected norms of
//! Sec 4.5, with a Student-t quantile valid for any number of degrees of freedom, and the
//! confidence widths proven at every number of trajectories of [`proven`].
//!
//! Everything is computed from a [`sepg_mdp::Batch`] by a reusable [`Estimator`] workspace into
//! caller-owned [`Estimate`]s, without allocation once the buffers have grown:
//!
//! ```
//! use sepg_estimators::{Estimate, Estimator, GradientSpec, Param, Width};
//! use sepg_mdp::Batch;
//! let mut batch = Batch::zeros(3, 2, 1, 1, 0.9);
//! batch.disc_rewards.copy_from_slice(&[1.0, 0.9, 0.5, 0.45, 2.0, 0.0]);
//! batch.cum_score_v.copy_from_slice(&[0.5, 1.0, -1.0, -0.5, 0.2, 0.2]);
//! let mut estimator = Estimator::new();
//! let mut grad = Estimate::new();
//! estimator.gradient(&batch, Param::V, GradientSpec::default(), &mut grad)?;
//! let conf = grad.confidence(Width::StudentT, 0.05)?;
//! assert!(conf.upper() >= conf.lower());
//! # Ok::<(), sepg_estimators::EstimatorError>(())
//! ```
//!
//! # Unbiasedness
//! A baseline fitted on the batch it is applied to biases the estimator by `O(1/N)`; the
//! default [`BaselineFit::LeaveOneOut`] removes this bias exactly. The surrogate gradient is a
//! product of two gradients and is cross-fitted on two halves of the batch, see
//! [`Estimator::surrogate_gradient`].

#![deny(missing_docs)]

pub mod binomial;
pub mod confidence;
pub mod error;
pub mod estimate;
pub mod gradient;
mod kernel;
pub mod proven;
pub mod quantile;
pub mod surrogate;

pub use confidence::{Confidence, Width, width};
pub use error::EstimatorError;
pub use estimate::Estimate;
pub use gradient::{Baseline, BaselineFit, Estimator, GradientSpec, Kind, Param};
pub use proven::ProvenWidths;
pub use quantile::{QuantileError, normal_quantile, student_t_quantile};
pub use surrogate::SurrogateEstimate;
