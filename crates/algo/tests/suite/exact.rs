//! Exact-gradient guarantees on the LQG presets (Sec 4.3, no estimation error).
//!
//! The guarantees of Theorems 4.2–4.5 need a bounded reward, which only the clipped presets
//! `lqg` and `lqg1d` have: their exact J comes from the clipped-LQG dynamic programme (about
//! 2.4 ms of CPU per iteration). CI runs a short matrix on them; the full claim of the issue —
//! 10,000 iterations for every σ⁰ ∈ {0.1, 0.2, 0.5, 1.0} and every requirement on both clipped
//! presets — is `#[ignore]`d (about 10 minutes on 2 cores):
//! `cargo test -p sepg-algo --release --test lib -- --ignored clipped_dp_10000`.
//! The unclipped closed form (reward unbounded, so the theorems do not formally apply) is also
//! run, as a stress test of the step logic.
use sepg_algo::core::config::{Algorithm, Requirement};
use sepg_algo::core::record::Record;
use sepg_mdp::env::AnyEnv;

use crate::suite::common::{exact, lqg, lqg1d, run};

const SIGMAS: [f64; 4] = [0.1, 0.2, 0.5, 1.0];

/// Rounding slack of an exact J comparison: J is O(100) and computed to ~1e-13 relative.
fn slack(j: f64) -> f64 {
    1e-10 * j.abs().max(1.0)
}

/// The first iteration at which a run breaks its requirement, described, or `None`.
fn first_violation(req: Requirement, records: &[Record], label: &str) -> Option<String> {
    let j0 = records[0].j_exploratory;
    for (a, b) in records.iter().zip(records.iter().skip(1)) {
        match req {
            // MI: J(θᵗ⁺¹) ≥ J(θᵗ).
            Requirement::Mi if b.j_exploratory < a.j_exploratory - slack(a.j_exploratory) => {
                return Some(format!(
                    "{label}: MI decreased J at iteration {}: {} -> {}",
                    b.iteration, a.j_exploratory, b.j_exploratory
                ));
            }
            // LB-I: J(θᵗ) ≥ J(θ⁰).
            Requirement::LbI { .. } if b.j_exploratory < j0 - slack(j0) => {
                return Some(format!(
                    "{label}: LB-I fell below J(θ⁰) at iteration {}: {} < {j0}",
                    b.iteration, b.j_exploratory
                ));
            }
            _ => {}
        }
    }
    let negative = records.iter().find(|r| r.budget < -slack(r.j_exploratory));
    match negative {
        Some(r) if req.is_type_two() => Some(format!(
            "{label}: budget {} < 0 at iteration {}",
            r.budget, r.iteration
        )),
        _ => None,
    }
}

/// Runs every (preset, requirement, σ⁰) combination in parallel (each run is sequential and
/// deterministic) and returns the violations found, one line per failing run.
fn matrix(clipped: bool, iterations: u64, reqs: &[Requirement]) -> Vec<String> {
    use rayon::prelude::*;
    let presets: [(&str, AnyEnv); 2] = [("lqg", lqg(clipped)), ("lqg1d", lqg1d(clipped))];
    let cases: Vec<(&str, &AnyEnv, Requirement, f64)> = presets
        .iter()
        .flat_map(|(name, env)| {
            reqs.iter()
                .flat_map(move |&req| SIGMAS.iter().map(move |&s| (*name, env, req, s)))
        })
        .collect();
    cases
        .par_iter()
        .filter_map(|&(name, env, req, s)| {
            let (records, _) = run(exact(env.clone(), Algorithm::Sepg(req), s), iterations);
            assert!(
                records.iter().all(|r| r.trajectories == 0),
                "exact mode samples nothing"
            );
            let kind = if clipped { "clipped" } else { "unclipped" };
            first_violation(req, &records, &format!("{kind} {name} {req:?} sigma0={s}"))
        })
        .collect()
}

const ALL: [Requirement; 5] = [
    Requirement::Mi,
    Requirement::LbI { nu: 0.5 },
    Requirement::LbII,
    Requirement::Lv,
    Requirement::Zv,
];

#[test]
fn guarantees_hold_closed_form_short() {
    let failures = matrix(false, 300, &ALL);
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
#[ignore = "about 2 minutes: 40 runs of 10,000 exact iterations"]
fn guarantees_hold_closed_form_10000_iterations() {
    let failures = matrix(false, 10_000, &ALL);
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn guarantees_hold_clipped_dp_short() {
    let failures = matrix(true, 30, &ALL);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// MI, LB-I, LB-II and ZV keep their guarantee for 10,000 exact iterations on both clipped
/// presets and every σ⁰.
#[test]
#[ignore = "about 10 minutes on 2 cores: 32 runs of 10,000 iterations of the clipped DP"]
fn guarantees_hold_clipped_dp_10000_iterations() {
    let reqs = [
        Requirement::Mi,
        Requirement::LbI { nu: 0.5 },
        Requirement::LbII,
        Requirement::Zv,
    ];
    let failures = matrix(true, 10_000, &reqs);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// SEPG-LV does not keep the exact budget non-negative: its low-variance target takes the
/// lowest w that the thesis-form interval (4.17) allows for a bounded worsening of B, a step
/// with Δw < 0, where the thesis form neglects a positive O(Δw³) term (Lemma A.2, see
/// docs/ERRATA.md); on clipped `lqg` with σ⁰ = 1 the exact budget first goes negative at
/// iteration 531 (−8.6e-5). This test pins that finding; it fails if the violation disappears.
#[test]
#[ignore = "about 3 minutes on 2 cores: 8 runs of 10,000 iterations of the clipped DP"]
fn lv_budget_goes_negative_clipped_dp_10000_iterations() {
    let failures = matrix(true, 10_000, &[Requirement::Lv]);
    eprintln!("{failures:#?}");
    assert!(
        failures
            .iter()
            .any(|f| f.starts_with("clipped lqg Lv sigma0=1: budget")),
        "{failures:#?}"
    );
}

#[test]
fn exact_mi_improves_and_moves_towards_v_star() {
    // Exact MI from v⁰ = −0.1 (σ = 1) must move v towards v* ≈ −0.615 (∇_v J < 0 there) with
    // a non-negative guaranteed improvement: ᾱ = 2α* makes the bound exactly 0 up to rounding.
    let (records, state) = run(exact(lqg(false), Algorithm::Sepg(Requirement::Mi), 1.0), 50);
    assert!(state.v[0] < -0.1);
    assert!(
        records
            .iter()
            .all(|r| r.guaranteed_v.unwrap_or(0.0) >= -1e-12)
    );
    assert!(records[49].j_exploratory > records[0].j_exploratory);
}
