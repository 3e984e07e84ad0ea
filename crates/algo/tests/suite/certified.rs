//! Certified steps (`sepg_certified`) are the default of every SEPG variant, can be
//! turned off, and are recorded. That a certified step meets its requirement in exact
//! arithmetic is the subject of the exact campaign of `sepg-verification`; here the plumbing.
use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::core::record::Record;
use sepg_algo::solver::PolicySolver;

use crate::suite::common::{exact, lqg, lqg1d};

fn run_with(cfg: SepgConfig, iterations: u64, certified: bool) -> Vec<Record> {
    let checked = cfg
        .check()
        .expect("valid configuration")
        .with_certified_steps(certified);
    let solver = PolicySolver::new(&checked).expect("solver");
    let mut log = Collect::default();
    let mut exec = Executor::new(solver, checked.initial_state()).observe(&mut log);
    exec.run(iterations).expect("run");
    drop(exec);
    log.records
}

/// Every update is flagged; a certified one records the enclosure's lower end, which meets
/// the requirement, and a non-certified one is flagged infeasible.
fn assert_flags(records: &[Record], label: &str) {
    for r in records {
        let blocks = [
            (
                r.alpha,
                r.certified_v,
                r.guaranteed_v,
                r.required_v,
                r.infeasible_v,
            ),
            (
                r.beta,
                r.certified_w,
                r.guaranteed_w,
                r.required_w,
                r.infeasible_w,
            ),
        ];
        for (size, certified, guaranteed, required, infeasible) in blocks {
            if size == 0.0 {
                continue;
            }
            match certified {
                Some(true) => {
                    let (g, c) = (guaranteed.expect("guarantee"), required.expect("C"));
                    assert!(g >= c, "{label} iteration {}: {g} < {c}", r.iteration);
                    assert!(!infeasible);
                }
                Some(false) => assert!(infeasible, "{label} iteration {}", r.iteration),
                None => panic!("{label} iteration {}: step not flagged", r.iteration),
            }
        }
    }
}

#[test]
fn every_sepg_variant_certifies_by_default() {
    let requirements = [
        Requirement::Mi,
        Requirement::LbI { nu: 0.5 },
        Requirement::LbII,
        Requirement::Lv,
        Requirement::Zv,
        Requirement::Sim { nu: 0.5 },
    ];
    for req in requirements {
        for alg in [Algorithm::Sepg(req), Algorithm::SepgNaiveW(req)] {
            // exact gradients: the unclipped closed form (cheap)
            let records = run_with(exact(lqg(false), alg, 0.5), 20, true);
            assert_flags(&records, &format!("exact {alg:?}"));
            assert!(records.iter().any(|r| r.certified_v == Some(true)));
            // sampled gradients: the high-probability forms
            let cfg = SepgConfig {
                n_trajectories: 60,
                ..SepgConfig::new(lqg1d(true), alg)
            };
            let records = run_with(cfg, 10, true);
            assert_flags(&records, &format!("sampled {alg:?}"));
        }
    }
}

#[test]
fn certification_can_be_turned_off_and_only_shortens_steps() {
    let alg = Algorithm::Sepg(Requirement::Mi);
    let on = run_with(exact(lqg(false), alg, 0.5), 1, true);
    let off = run_with(exact(lqg(false), alg, 0.5), 1, false);
    assert!(
        off.iter()
            .all(|r| r.certified_v.is_none() && r.certified_w.is_none())
    );
    // same state at iteration 0: the certified α is the f64 one moved toward α* by a few ulps
    let (a_on, a_off) = (on[0].alpha, off[0].alpha);
    assert!(a_on <= a_off && a_off - a_on <= 64.0 * f64::EPSILON * a_off);
}
