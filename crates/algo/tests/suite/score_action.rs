//! The configuration's `score_action` reaches the sampled rollouts of every algorithm (the
//! SEPG variants and the comparison algorithms): a run with scores on clipped actions gives,
//! record for record, the run of a collector that hands in clipped-action rollouts, and
//! differs from the default (raw-action scores) run.
use sepg_algo::core::config::{Algorithm, Requirement, SepgConfig};
use sepg_algo::core::error::RunError;
use sepg_algo::core::executor::{Collect, Executor};
use sepg_algo::core::options::{Confidence, Schedule, SepgOptions};
use sepg_algo::core::record::Record;
use sepg_algo::core::state::State;
use sepg_algo::solver::sampled::{BatchCollector, BatchRequest};
use sepg_algo::solver::{CollectedConfig, PolicySolver};
use sepg_mdp::Batch;
use sepg_mdp::env::{AnyEnv, Environment, Preset};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rollout::{ScoreAction, rollout_into_with, rollout_returns};

/// Collects the requested blocks with the built-in engine, scores on clipped actions.
struct ClippedCollector {
    env: AnyEnv,
    horizon: usize,
}

impl BatchCollector for ClippedCollector {
    fn collect(&mut self, r: &BatchRequest<'_>) -> Result<Batch, RunError> {
        let (p, l) = (self.env.feature_dim(), self.env.action_dim());
        let err = |e: String| RunError::Mdp(e);
        let policy = match r.w {
            Some(w) => GaussianPolicy::new(r.v.to_vec(), w.to_vec(), p),
            None => GaussianPolicy::deterministic(r.v.to_vec(), l, p),
        }
        .map_err(|e| err(e.to_string()))?;
        let h = self.horizon;
        if r.scores {
            let mut b = Batch::zeros(0, 0, 0, 0, 0.0);
            rollout_into_with(
                &self.env,
                &policy,
                r.n,
                h,
                r.key,
                ScoreAction::Clipped,
                &mut b,
            )
            .map_err(|e| err(e.to_string()))?;
            return Ok(b);
        }
        let g =
            rollout_returns(&self.env, &policy, r.n, h, r.key).map_err(|e| err(e.to_string()))?;
        let mut rewards = vec![0.0; r.n * h];
        for (i, gi) in g.iter().enumerate() {
            rewards[i * h] = *gi;
        }
        Batch::from_steps(h, 1.0, &[], &rewards, &[], &[], &vec![h; r.n])
            .map_err(|e| err(e.to_string()))
    }
}

fn records(solver: PolicySolver, state: State) -> Vec<Record> {
    let mut log = Collect::default();
    Executor::new(solver, state)
        .observe(&mut log)
        .run(4)
        .expect("run");
    log.records
}

/// σ⁰ = 3 on `lqg1d` (action box [−4, 4]): a few percent of the actions are clipped.
#[test]
fn clipped_action_scores_reach_the_sampled_rollouts() {
    for algorithm in [
        Algorithm::Sepg(Requirement::Zv),
        Algorithm::Sepg(Requirement::Mi),
        Algorithm::GpomdpConst {
            alpha: 1e-6,
            beta: 1e-6,
        },
        Algorithm::adam(1e-4, 1e-4),
        Algorithm::AdaStep,
    ] {
        let cfg = SepgConfig {
            sigma0: vec![3.0],
            n_trajectories: 60,
            seed: 5,
            score_action: ScoreAction::Clipped,
            // a collector run knows no iteration count: Student-t widths at level δ
            options: SepgOptions {
                schedule: Schedule::Iteration,
                confidence: Confidence::StudentT { factor: 1.0 },
                ..SepgOptions::default()
            },
            ..SepgConfig::new(Preset::Lqg1d.build(), algorithm)
        };
        let checked = cfg.clone().check().expect("config");
        let built_in = records(
            PolicySolver::new(&checked).expect("solver"),
            checked.initial_state(),
        );
        let external = CollectedConfig {
            algorithm,
            constants: *checked.constants(),
            delta: 0.2,
            estimator: cfg.estimator,
            n_trajectories: cfg.n_trajectories,
            seed: cfg.seed,
            actions: 1,
            features: 1,
        };
        let collector = ClippedCollector {
            env: cfg.env.clone(),
            horizon: cfg.horizon,
        };
        let solver = PolicySolver::with_collector(&external, Box::new(collector)).expect("solver");
        assert_eq!(records(solver, checked.initial_state()), built_in);
        let raw = SepgConfig {
            score_action: ScoreAction::Raw,
            ..cfg
        }
        .check()
        .expect("config");
        let raw = records(
            PolicySolver::new(&raw).expect("solver"),
            raw.initial_state(),
        );
        assert_ne!(raw, built_in);
    }
}
