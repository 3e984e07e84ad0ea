//! Set-up shared by the rollout, streaming and scored-action tests.

use nalgebra::{DMatrix, DVector};
use sepg_mdp::env::LqgEnv;
use sepg_mdp::lqg_model::{BoxBounds, LqgModel};

pub use sepg_testkit::pool;

/// A clipped two-dimensional LQG with noise (the generic kernel): state box `[−3, 3]²`,
/// action box `[−1, 1]²`, initial states in `[−2, 2]²`, noise standard deviations (0.1, 0.05).
pub fn lqg_2d() -> LqgEnv {
    let model = LqgModel::new(
        DMatrix::from_row_slice(2, 2, &[0.9, 0.2, -0.1, 1.0]),
        DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.5, 1.0]),
        DMatrix::identity(2, 2),
        DMatrix::from_row_slice(2, 2, &[0.5, 0.1, 0.1, 0.5]),
        BoxBounds::cube(2, -3.0, 3.0),
        BoxBounds::cube(2, -1.0, 1.0),
        BoxBounds::cube(2, -2.0, 2.0),
    )
    .and_then(|m| m.with_noise(DVector::from_vec(vec![0.1, 0.05])))
    .expect("valid model");
    LqgEnv::new(model).expect("valid env")
}
