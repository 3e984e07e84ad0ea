//! The report of `sepg exact`: the exact J and derivatives of [`crate::exact::exact`] with the
//! evaluation they belong to (preset, oracle, horizon, v, σ, η), serialising to the JSON
//! object of `sepg exact --json`.

use sepg_mdp::oracle::Horizon;
use serde::Serialize;

use crate::error::Result;
use crate::exact::{ExactSpec, exact};

/// Exact J and derivatives of one policy on an LQG preset (units of J; derivatives per unit
/// of v, w = log σ and σ). Optional fields are absent when the policy does not determine them
/// (σ = 0, or no Hessian from the oracle).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExactReport {
    /// The preset: `lqg` or `lqg1d`.
    pub env: String,
    /// `closed-form` (unclipped model) or `clipped-dp` (dynamic programming).
    pub oracle: &'static str,
    /// The horizon evaluated: an integer or `inf`.
    pub horizon: String,
    /// Mean parameter v.
    pub v: f64,
    /// Standard deviation σ.
    pub sigma: f64,
    /// Standard deviation η of the transition noise.
    pub eta: f64,
    /// J.
    pub j: f64,
    /// ∂J/∂v.
    pub grad_v: f64,
    /// ∂J/∂w.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grad_w: Option<f64>,
    /// ∂J/∂σ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grad_sigma: Option<f64>,
    /// ∂²J/∂w∂v.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mixed_wv: Option<f64>,
    /// The Hessian of J in (v, w), row by row.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hessian: Option<Vec<Vec<f64>>>,
}

/// Evaluates `spec` exactly ([`exact`]) and reports the values with the evaluation's inputs.
///
/// # Errors
/// As [`exact`].
pub fn exact_report(spec: &ExactSpec) -> Result<ExactReport> {
    let (eval, horizon) = exact(spec)?;
    Ok(ExactReport {
        env: spec.env.clone(),
        oracle: if spec.clipped {
            "clipped-dp"
        } else {
            "closed-form"
        },
        horizon: match horizon {
            Horizon::Finite(h) => h.to_string(),
            Horizon::Infinite => "inf".to_string(),
        },
        v: spec.v,
        sigma: spec.sigma,
        eta: spec.eta,
        j: eval.j,
        grad_v: eval.grad_v[0],
        grad_w: eval.grad_w.first().copied(),
        grad_sigma: eval.grad_sigma().first().copied(),
        mixed_wv: eval.mixed_wv.first().copied(),
        hessian: eval.hessian.as_ref().map(|h| {
            (0..h.nrows())
                .map(|i| (0..h.ncols()).map(|j| h[(i, j)]).collect())
                .collect()
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_deterministic_policy_reports_no_derivative_in_w() {
        // lqg (thesis Sec 5.1): s' = s + a, r = −0.5(s² + a²), s₀ ~ U[−2, 2]; a = −s brings
        // the state to 0 in one step, so J = E[−0.5(s₀² + s₀²)] = −E[s₀²] = −4/3.
        let spec = ExactSpec {
            env: "lqg".into(),
            v: -1.0,
            sigma: 0.0,
            horizon: Some(Horizon::Finite(10)),
            eta: 0.0,
            clipped: false,
        };
        let r = exact_report(&spec).unwrap();
        assert_eq!(
            (r.oracle, r.horizon.as_str(), r.env.as_str()),
            ("closed-form", "10", "lqg")
        );
        assert!((r.j + 4.0 / 3.0).abs() < 1e-12, "{}", r.j);
        let json = serde_json::to_value(&r).unwrap();
        assert!(json.get("grad_w").is_none());
    }
}
