//! Environments, Gaussian linear policies, deterministic parallel rollouts and exact LQG
//! oracles for sepg.
//!
//! - [`lqg_model`]: the LQG problem description shared with the exact oracles.
//! - [`env`](mod@env), [`mountain_car`], [`features`]: environments, presets and feature maps
//!   (docs/CONVENTIONS.md §1).
//! - [`policy`]: the factored Gaussian linear policy (Sec 4.3.1, 4.3.4; docs/CONVENTIONS.md §2).
//! - [`rng`], [`rollout`]: per-trajectory random streams and the deterministic parallel rollout
//!   engine producing [`Batch`]es.
//! - [`monte_carlo`]: Monte Carlo estimates of `J` and of paired differences of `J`.
//! - [`oracle`]: exact LQG oracles.

#![deny(missing_docs)]

pub mod batch;
pub mod cancel;
pub mod env;
pub mod features;
pub mod lqg_model;
pub mod monte_carlo;
pub mod mountain_car;
pub mod oracle;
pub mod policy;
pub mod rng;
pub mod rollout;
mod stream;

pub use batch::{Batch, BatchError};
pub use env::{AnyEnv, EnvConstants, EnvError, Environment, LqgEnv, LqgPreset, Preset};
pub use lqg_model::{BoxBounds, LqgModel, ModelError};
pub use mountain_car::MountainCar;
pub use policy::{Exploration, GaussianPolicy, PolicyError};
pub use rng::SeedKey;
