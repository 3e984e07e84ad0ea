//! One file per file of `src/` (`checks/<file>.rs` tests `src/<file>.rs`), plus `common`
//! (reference implementations and helpers) and `properties` (property-based checks across
//! modules).
mod batch_size;
mod budget;
mod common;
mod constants;
mod direction;
mod error;
mod exploring;
mod high_probability;
mod papini;
mod parabola;
mod penalties;
mod pirotta;
mod properties;
mod rigorous;
mod surrogate;
mod v_update;
mod w_update;
