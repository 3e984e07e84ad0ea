//! Scores on raw and on clipped actions (`ScoreAction`): the clipped-action scores of every
//! kernel (fused scalar LQG lanes, generic, fused Mountain Car, the streaming sinks) against
//! an independent step-by-step replay, and the raw scores unchanged bit for bit.

use approx::relative_eq;
use sepg_mdp::Batch;
use sepg_mdp::env::{AnyEnv, Environment, LqgEnv};
use sepg_mdp::monte_carlo::{pilot_key, stream_gradients, stream_gradients_with};
use sepg_mdp::mountain_car::MountainCar;
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::{ScoreAction, rollout, rollout_into, rollout_into_with};

mod common;
use common::{lqg_2d, pool};

/// One case: environment, policy, horizon, and its action box `[−bound, bound]` per
/// component, written here from the environments' definitions (not from the engine).
struct Case {
    env: AnyEnv,
    pi: GaussianPolicy,
    h: usize,
    bound: f64,
}

/// Each kernel, with σ large enough that a good share of the actions leave the box.
fn cases() -> Vec<Case> {
    vec![
        // Fused scalar LQG kernel (lanes), box [−4, 4], σ = 2.
        Case {
            env: AnyEnv::Lqg(Box::new(LqgEnv::lqg1d())),
            pi: GaussianPolicy::scalar(-0.3, 2f64.ln()).unwrap(),
            h: 20,
            bound: 4.0,
        },
        // Generic kernel, box [−1, 1]², σ = (1, 0.6).
        Case {
            env: AnyEnv::Lqg(Box::new(lqg_2d())),
            pi: GaussianPolicy::new(vec![-0.5, 0.1, 0.0, -0.4], vec![0.0, -0.5], 2).unwrap(),
            h: 15,
            bound: 1.0,
        },
        // Fused Mountain Car kernel (state + bias features), force box [−1, 1], σ = 1.
        Case {
            env: AnyEnv::MountainCar(MountainCar::state_bias()),
            pi: GaussianPolicy::new(vec![0.0, 30.0, 0.2], vec![0.0], 3).unwrap(),
            h: 250,
            bound: 1.0,
        },
        // Generic kernel on Mountain Car (RBF features), force box [−1, 1], σ = 0.8.
        Case {
            env: AnyEnv::MountainCar(MountainCar::rbf([3, 3], true).unwrap()),
            pi: GaussianPolicy::new(vec![0.5; 10], vec![0.8f64.ln()], 10).unwrap(),
            h: 60,
            bound: 1.0,
        },
    ]
}

/// A batch of `n` trajectories of `case` with its scores evaluated at `action`.
fn scored_batch(case: &Case, n: usize, key: SeedKey, action: ScoreAction) -> Batch {
    let mut b = Batch::zeros(0, 0, 0, 0, 0.0);
    rollout_into_with(&case.env, &case.pi, n, case.h, key, action, &mut b).unwrap();
    b
}

/// Replays trajectory `i` with the public step-by-step API and checks its rows of `b`:
/// rewards bit for bit (the trajectory does not depend on the scored action), cumulative
/// scores against `policy.score_v/score_w` evaluated at `clip(a)` (relative 1e-12), and the
/// padding. Returns `(steps, clipped steps)`.
fn replay_clipped(case: &Case, b: &Batch, key: SeedKey, i: usize) -> (usize, usize) {
    let Case { env, pi, bound, .. } = case;
    let (n, l, p) = (env.state_dim(), env.action_dim(), env.feature_dim());
    let mut rngs = key.rngs(i as u64);
    let (mut s, mut next, mut phi) = (vec![0.0; n], vec![0.0; n], vec![0.0; p]);
    let (mut a, mut ac) = (vec![0.0; l], vec![0.0; l]);
    let (mut gv, mut gw) = (vec![0.0; l * p], vec![0.0; l]);
    let (mut cv, mut cw) = (vec![0.0; l * p], vec![0.0; l]);
    env.reset(&mut rngs.env, &mut s);
    let (mut disc, mut len, mut clipped) = (1.0, b.horizon, 0);
    for t in 0..b.horizon {
        env.features(&s, &mut phi);
        pi.sample(&phi, &mut rngs.policy, &mut a).unwrap();
        for (c, x) in ac.iter_mut().zip(&a) {
            *c = x.clamp(-bound, *bound);
            clipped += usize::from(*c != *x);
        }
        pi.score_v(&phi, &ac, &mut gv).unwrap();
        pi.score_w(&phi, &ac, &mut gw).unwrap();
        let (r, done) = env.step(&s, &a, &mut rngs.env, &mut next);
        assert_eq!(
            b.rewards(i)[t].to_bits(),
            (disc * r).to_bits(),
            "reward {i} {t}"
        );
        disc *= b.gamma;
        for (c, g) in cv.iter_mut().zip(&gv).chain(cw.iter_mut().zip(&gw)) {
            *c += g;
        }
        let got = b.score_v(i, t).iter().chain(b.score_w(i, t));
        for (x, y) in got.zip(cv.iter().chain(&cw)) {
            assert!(
                relative_eq!(x, y, epsilon = 1e-12, max_relative = 1e-12),
                "score {i} {t}: {x} vs {y}"
            );
        }
        std::mem::swap(&mut s, &mut next);
        if done {
            len = t + 1;
            break;
        }
    }
    assert_eq!(b.lengths[i], len);
    for t in len..b.horizon {
        assert_eq!(b.rewards(i)[t], 0.0);
        assert_eq!(b.score_v(i, t), b.score_v(i, len - 1));
        assert_eq!(b.score_w(i, t), b.score_w(i, len - 1));
    }
    (len * l, clipped)
}

/// Clipped-action scores of a batch (n = 70: a full chunk of lanes and a partial one) equal
/// the independent replay for every kernel; at least 5% of the actions were clipped, so the
/// raw scores would fail the comparison (the rows of the raw batch differ).
#[test]
fn clipped_scores_match_an_independent_replay() {
    for case in cases() {
        let key = SeedKey::new(21, 0, 2);
        let b = scored_batch(&case, 70, key, ScoreAction::Clipped);
        let (mut steps, mut clipped) = (0, 0);
        for i in 0..b.n {
            let (s, c) = replay_clipped(&case, &b, key, i);
            steps += s;
            clipped += c;
        }
        assert!(20 * clipped >= steps, "{clipped} of {steps} clipped");
        let raw = rollout(&case.env, &case.pi, 70, case.h, key).unwrap();
        assert_eq!(raw.disc_rewards, b.disc_rewards);
        assert_ne!(raw.cum_score_w, b.cum_score_w);
    }
}

/// Without clipping (an action box that is never reached), the clipped-action scores are the
/// raw scores up to rounding.
#[test]
fn clipped_scores_equal_raw_scores_inside_the_box() {
    let env = LqgEnv::lqg1d();
    let pi = GaussianPolicy::scalar(-0.3, 0.05f64.ln()).unwrap();
    let key = SeedKey::new(4, 1, 0);
    let raw = rollout(&env, &pi, 30, 20, key).unwrap();
    let mut clipped = Batch::zeros(0, 0, 0, 0, 0.0);
    rollout_into_with(&env, &pi, 30, 20, key, ScoreAction::Clipped, &mut clipped).unwrap();
    let pairs = raw.cum_score_v.iter().zip(&clipped.cum_score_v);
    for (x, y) in pairs.chain(raw.cum_score_w.iter().zip(&clipped.cum_score_w)) {
        assert!(
            relative_eq!(x, y, epsilon = 1e-9, max_relative = 1e-9),
            "{x} vs {y}"
        );
    }
}

/// Clipped-action rollouts are the same bits for 1, 2 and 3 threads (n = 203 spans four
/// chunks and ends in a partial group of lanes).
#[test]
fn clipped_scores_are_the_same_bits_for_any_thread_count() {
    for case in cases() {
        let key = SeedKey::new(7, 3, 1);
        let run = |threads: usize| {
            pool(threads).install(|| scored_batch(&case, 203, key, ScoreAction::Clipped))
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
    }
}

/// The streamed G(PO)MDP estimates with clipped-action scores (pilot baseline fitted on
/// clipped-action scores too) equal their computation from stored clipped-action batches
/// (relative 1e-12, the sums being taken in another order).
#[test]
fn streamed_gradients_on_clipped_scores_match_stored_batches() {
    for case in cases() {
        let (n, pilot, key) = (150, 40, SeedKey::new(9, 2, 1));
        let (env, pi, h) = (&case.env, &case.pi, case.h);
        let clipped = ScoreAction::Clipped;
        let g = stream_gradients_with(env, pi, n, h, key, pilot, clipped).unwrap();
        let (mut pb, mut b) = (Batch::zeros(0, 0, 0, 0, 0.0), Batch::zeros(0, 0, 0, 0, 0.0));
        rollout_into_with(env, pi, pilot, h, pilot_key(key), clipped, &mut pb).unwrap();
        rollout_into_with(env, pi, n, h, key, clipped, &mut b).unwrap();
        let (dv, dw) = (b.dim_v, b.dim_w);
        let score = |b: &Batch, i: usize, t: usize, k: usize| {
            if k < dv {
                b.score_v(i, t)[k]
            } else {
                b.score_w(i, t)[k - dv]
            }
        };
        for k in 0..dv + dw {
            // Baseline b_{t,k} = Σ S² γ^t r / Σ S² over the pilot batch.
            let baseline = (0..h).map(|t| {
                let (mut num, mut den) = (0.0, 0.0);
                for i in 0..pilot {
                    let s = score(&pb, i, t, k);
                    num += s * s * pb.rewards(i)[t];
                    den += s * s;
                }
                if den == 0.0 { 0.0 } else { num / den }
            });
            let baseline: Vec<f64> = baseline.collect();
            let mut mean = 0.0;
            for i in 0..n {
                for (t, bt) in baseline.iter().enumerate() {
                    mean += score(&b, i, t, k) * (b.rewards(i)[t] - bt);
                }
            }
            mean /= n as f64;
            let got = if k < dv {
                g.grad_v[k].mean()
            } else {
                g.grad_w[k - dv].mean()
            };
            assert!(
                relative_eq!(got, mean, epsilon = 1e-12, max_relative = 1e-12),
                "component {k}: {got} vs {mean}"
            );
        }
        let raw = stream_gradients(env, pi, n, h, key, pilot).unwrap();
        assert_eq!(raw.j, g.j);
        assert_ne!(raw.grad_w, g.grad_w);
    }
}

/// FNV-1a over the bits of every value of a batch.
fn digest(b: &Batch) -> u64 {
    let words = b
        .disc_rewards
        .iter()
        .chain(&b.cum_score_v)
        .chain(&b.cum_score_w);
    let lengths = b.lengths.iter().map(|l| *l as u64);
    words
        .map(|x| x.to_bits())
        .chain(lengths)
        .fold(0xcbf2_9ce4_8422_2325, |h, w| {
            (h ^ w).wrapping_mul(0x0000_0100_0000_01b3)
        })
}

/// Raw-action scores are unchanged bit for bit by the option: `rollout_into` and
/// `ScoreAction::Raw` give the same batches, whose digests were recorded with the engine as it
/// was before scores on clipped actions existed (one digest per kernel, n = 70).
#[test]
fn raw_scores_are_unchanged() {
    let recorded: [u64; 4] = [
        0x5f30_3b6c_0488_3769,
        0xf039_a2af_ad54_73e9,
        0x8e1b_6bdd_378a_3543,
        0x1b4b_3a86_7320_87bd,
    ];
    for (case, want) in cases().iter().zip(recorded) {
        let key = SeedKey::new(21, 0, 2);
        let mut b = Batch::zeros(0, 0, 0, 0, 0.0);
        rollout_into(&case.env, &case.pi, 70, case.h, key, &mut b).unwrap();
        assert_eq!(b, scored_batch(case, 70, key, ScoreAction::Raw));
        assert_eq!(digest(&b), want, "{:#018x}", digest(&b));
    }
}
