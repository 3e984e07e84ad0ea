//! # sepg — Safely-Exploring Policy Gradient with executable safety guarantees
//!
//! This facade re-exports the workspace crates so that a single dependency gives access to the
//! whole toolkit:
//!
//! - [`bounds`]: every closed-form quantity of the thesis (ψ, c, d, α*, β̃, λ, C_max, batch
//!   sizes, high-probability and rigorous variants, the budget of Theorem 4.1), in `f64`;
//! - [`certified`]: the safe steps of [`bounds`] whose guarantee survives floating-point
//!   rounding (interval arithmetic and a-priori rounding-error bounds);
//! - [`mdp`]: environments (LQG presets, n-D LQG, Mountain Car), the factored Gaussian linear
//!   policy, the deterministic parallel rollout engine and the exact LQG oracles;
//! - [`estimators`]: REINFORCE, G(PO)MDP, baselines, ∇_w L and confidence widths;
//! - [`algo`]: SEPG with every safety requirement and the comparison algorithms;
//! - [`runs`]: run folders (checkpoint, resume), sweeps, shards and merging, the audit, the
//!   reproduction of the thesis experiments, tables and figures;
//! - [`verification`]: the registry of numerical checks of every theorem of the thesis.
//!
//! The `sepg` binary built from this package is the command-line interface.

#![deny(missing_docs)]

pub use sepg_algo as algo;
pub use sepg_bounds as bounds;
pub use sepg_certified as certified;
pub use sepg_estimators as estimators;
pub use sepg_mdp as mdp;
pub use sepg_runs as runs;
pub use sepg_verification as verification;
