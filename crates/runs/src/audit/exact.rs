//! Exact J of the logged points: the oracle of the run's environment, evaluated in parallel.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;
use sepg_mdp::env::AnyEnv;
use sepg_mdp::oracle::{
    ClippedDpOracle, ClosedFormOracle, ExactOracle, Exploration, Horizon, Needs,
};

use super::{AUDIT_NODES_PER_ELEMENT, audit_dp_config};
use crate::error::{Error, Result};
use crate::run::RunObserver;

/// Exact J of the run's environment.
pub(super) struct ExactJ {
    pub(super) oracle: Box<dyn ExactOracle + Send + Sync>,
    pub(super) horizon: Horizon,
    pub(super) dim_v: usize,
}

impl ExactJ {
    /// J at the point `v ++ w`; `w` all −∞ is the deterministic policy.
    pub(super) fn j(&self, point: &[f64]) -> Result<f64> {
        let (v, w) = point.split_at(self.dim_v.min(point.len()));
        let exploration = if w.iter().all(|x| *x == f64::NEG_INFINITY) {
            Exploration::Deterministic
        } else {
            Exploration::Gaussian { w: w.to_vec() }
        };
        let j = self
            .oracle
            .evaluate_with(v, &exploration, self.horizon, Needs::VALUE)
            .map_err(|e| Error::failed_from(format_args!("exact J at v = {v:?}, w = {w:?}"), e))?
            .j;
        if !j.is_finite() {
            return Err(Error::failed(format!(
                "exact J at v = {v:?}, w = {w:?} is not finite"
            )));
        }
        Ok(j)
    }
}

/// The key of the point (v, w): the bits of `v ++ w`.
pub(super) fn key(v: &[f64], w: &[f64]) -> Vec<u64> {
    v.iter().chain(w).map(|x| x.to_bits()).collect()
}

/// Exact J at every point of `points` (keys of [`key`]), evaluated in parallel; the first
/// error in key order is returned, so the outcome does not depend on the number of threads.
/// Progress goes to `observer` in units of the audited iterations: `begin(0, iterations)`,
/// then `advance` with the share of the distinct points evaluated so far (at most every
/// [`PROGRESS_EVERY`] points), then `end`.
pub(super) fn evaluate_all(
    exact: &ExactJ,
    points: Vec<Vec<u64>>,
    iterations: u64,
    observer: &dyn RunObserver,
) -> Result<HashMap<Vec<u64>, f64>> {
    let mut points = points;
    points.sort_unstable();
    points.dedup();
    let total = points.len() as u64;
    observer.begin(0, iterations);
    let done = AtomicU64::new(0);
    let values: Vec<Result<f64>> = points
        .par_iter()
        .map(|k| {
            let point: Vec<f64> = k.iter().map(|b| f64::from_bits(*b)).collect();
            let value = exact.j(&point);
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            if n.is_multiple_of(PROGRESS_EVERY) || n == total {
                observer.advance(iterations * n / total.max(1));
            }
            value
        })
        .collect();
    observer.end();
    let mut out = HashMap::with_capacity(points.len());
    for (k, value) in points.into_iter().zip(values) {
        out.insert(k, value?);
    }
    Ok(out)
}

/// Points evaluated between two progress reports of [`evaluate_all`].
const PROGRESS_EVERY: u64 = 64;

/// Where J comes from for the environment of the run, and its label.
pub(super) fn source(
    env: &AnyEnv,
    horizon: usize,
    dim_v: usize,
) -> Result<(Option<ExactJ>, String)> {
    let AnyEnv::Lqg(env) = env else {
        return Ok((
            None,
            "none (no exact oracle for this environment)".to_owned(),
        ));
    };
    let model = env.model();
    let (oracle, name): (Box<dyn ExactOracle + Send + Sync>, String) = if model.clipping {
        let o = ClippedDpOracle::with_config(model, audit_dp_config())
            .map_err(|e| Error::failed(e.to_string()).with_source(e))?;
        (
            Box::new(o),
            format!("ClippedDpOracle, {AUDIT_NODES_PER_ELEMENT} nodes per element"),
        )
    } else {
        let o = ClosedFormOracle::new(model)
            .map_err(|e| Error::failed(e.to_string()).with_source(e))?;
        (Box::new(o), "ClosedFormOracle".to_owned())
    };
    let exact = ExactJ {
        oracle,
        horizon: Horizon::Finite(horizon),
        dim_v,
    };
    Ok((Some(exact), format!("exact ({name}, H = {horizon})")))
}
