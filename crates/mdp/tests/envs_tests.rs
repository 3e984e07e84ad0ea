//! Environment semantics (docs/CONVENTIONS.md §1) on hand-derived vectors, preset constants and the registry.

use approx::{abs_diff_eq, assert_abs_diff_eq};
use nalgebra::{DMatrix, DVector};
use sepg_mdp::env::{AnyEnv, EnvError, Environment, LqgEnv, Preset};
use sepg_mdp::features::FeatureMap;
use sepg_mdp::lqg_model::{BoxBounds, LqgModel};
use sepg_mdp::mountain_car::MountainCar;
use sepg_mdp::rng::{rng_from_seed, standard_normal};

fn step(env: &impl Environment, s: &[f64], a: &[f64]) -> (Vec<f64>, f64, bool) {
    let mut rng = rng_from_seed(0);
    let mut next = vec![0.0; env.state_dim()];
    let (r, done) = env.step(s, a, &mut rng, &mut next);
    (next, r, done)
}

#[test]
fn lqg_step_clips_action_then_rewards_pre_step_state_then_clips_state() {
    let env = LqgEnv::thesis();
    // s = 1.5, a = 1: r = −0.5(2.25 + 1) = −1.625, s' = clip(2.5, ±2) = 2.
    assert_eq!(step(&env, &[1.5], &[1.0]), (vec![2.0], -1.625, false));
    // s = −1, a = −3 → a_c = −2: r = −0.5(1 + 4) = −2.5, s' = clip(−3) = −2.
    assert_eq!(step(&env, &[-1.0], &[-3.0]), (vec![-2.0], -2.5, false));
    let env = LqgEnv::lqg1d();
    // s = 3, a = 5 → a_c = 4: r = −0.9(9 + 16) = −22.5, s' = clip(7, ±4) = 4.
    assert_eq!(step(&env, &[3.0], &[5.0]), (vec![4.0], -22.5, false));
    // Clipping off: r = −0.9(9 + 25) = −30.6, s' = 8.
    let env = LqgEnv::new(LqgModel::lqg1d().with_clipping(false)).unwrap();
    let (next, r, _) = step(&env, &[3.0], &[5.0]);
    assert_eq!(next, vec![8.0]);
    assert_abs_diff_eq!(r, -30.6, epsilon = 1e-12);
}

#[test]
fn lqg_nd_step_matches_hand_computation() {
    // A = [[1, .5], [0, 1]], B = [[0], [1]], Q = diag(1, 2), R = 3, S = [−2, 2]², A = [−1.5, 1.5].
    let model = LqgModel::new(
        DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 1.0]),
        DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
        DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 2.0]),
        DMatrix::from_element(1, 1, 3.0),
        BoxBounds::cube(2, -2.0, 2.0),
        BoxBounds::cube(1, -1.5, 1.5),
        BoxBounds::cube(2, -1.0, 1.0),
    )
    .unwrap();
    let env = LqgEnv::new(model.clone()).unwrap();
    // s = (1, −1), a = 2 → a_c = 1.5: r = −(1 + 2 + 3·2.25) = −9.75,
    // s' = (1 − 0.5 + 0, −1 + 1.5) = (0.5, 0.5).
    assert_eq!(
        step(&env, &[1.0, -1.0], &[2.0]),
        (vec![0.5, 0.5], -9.75, false)
    );
    // s = (2, 2), a = 1: s' = clip((3, 3)) = (2, 2).
    assert_eq!(step(&env, &[2.0, 2.0], &[1.0]).0, vec![2.0, 2.0]);
    let c = env.constants();
    // r_max: max sᵀQs over corners = 4 + 8 = 12, plus 3·1.5² = 6.75.
    assert_eq!((c.r_max, c.m_phi, c.action_volume), (18.75, 2.0, 3.0));

    // Transition noise: s' = A s + B a_c + η with η_i = noise_std_i · z_i drawn in order from
    // the environment stream.
    let noisy = LqgEnv::new(model.with_noise(DVector::from_vec(vec![0.1, 0.2])).unwrap()).unwrap();
    let mut rng = rng_from_seed(5);
    let mut reference = rng.clone();
    let (z0, z1) = (
        standard_normal(&mut reference),
        standard_normal(&mut reference),
    );
    let mut next = [0.0; 2];
    noisy.step(&[1.0, -1.0], &[0.0], &mut rng, &mut next);
    assert_abs_diff_eq!(next[0], 0.5 + 0.1 * z0, epsilon = 1e-15);
    assert_abs_diff_eq!(next[1], -1.0 + 0.2 * z1, epsilon = 1e-15);
}

#[test]
fn preset_constants_and_registry() {
    let c = Preset::Lqg.build().constants();
    assert_eq!(
        (c.r_max, c.m_phi, c.action_volume, c.gamma, c.horizon),
        (4.0, 2.0, 4.0, 0.99, 20)
    );
    let c = Preset::Lqg1d.build().constants();
    assert_abs_diff_eq!(c.r_max, 28.8, epsilon = 1e-12);
    assert_eq!((c.m_phi, c.action_volume), (4.0, 8.0));
    let mc = Preset::MountainCar.build();
    let c = mc.constants();
    assert_eq!(
        (c.r_max, c.m_phi, c.action_volume, c.horizon),
        (100.0, 1.2, 2.0, 999)
    );
    assert_eq!(mc.time_limit(), Some(999));
    assert_eq!(
        MountainCar::rbf([4, 3], false).unwrap().constants().m_phi,
        1.0
    );
    for p in Preset::ALL {
        assert_eq!(p.name().parse::<Preset>(), Ok(p));
    }
    assert_eq!(
        Preset::from_name("pendulum"),
        Err(EnvError::UnknownPreset("pendulum".into()))
    );
    assert!(matches!(Preset::Lqg.build(), AnyEnv::Lqg(_)));
    assert!(Preset::Lqg1d.build().as_scalar_lqg().is_some());
    assert!(mc.as_scalar_lqg().is_none());
}

#[test]
fn resets_stay_in_their_boxes() {
    let mut rng = rng_from_seed(1);
    let lqg = LqgEnv::lqg1d();
    let mc = MountainCar::state_bias();
    let (mut s1, mut s2) = ([0.0], [0.0; 2]);
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for _ in 0..10_000 {
        lqg.reset(&mut rng, &mut s1);
        assert!((-4.0..4.0).contains(&s1[0]));
        mc.reset(&mut rng, &mut s2);
        assert!((-0.6..-0.4).contains(&s2[0]) && s2[1] == 0.0);
        lo = lo.min(s2[0]);
        hi = hi.max(s2[0]);
    }
    // 1e4 uniform draws leave a gap larger than 1e-3 at an end with probability
    // 2·(1 − 0.005)^1e4 ≈ 4e-22.
    assert!(lo < -0.599 && hi > -0.401);
}

/// An independent transcription of gymnasium's `MountainCarContinuous-v0.step` (docs/CONVENTIONS.md §1),
/// keeping its `if` form on purpose.
#[allow(clippy::manual_clamp)]
fn reference_mc_step(pos: f64, vel: f64, action: f64) -> (f64, f64, f64, bool) {
    let force = if action > 1.0 {
        1.0
    } else if action < -1.0 {
        -1.0
    } else {
        action
    };
    // gymnasium: `velocity += force * power - 0.0025 * cos(3 * position)`.
    let mut velocity = vel + (force * 0.0015 - 0.0025 * (3.0 * pos).cos());
    if velocity > 0.07 {
        velocity = 0.07;
    }
    if velocity < -0.07 {
        velocity = -0.07;
    }
    let mut position = pos + velocity;
    if position > 0.6 {
        position = 0.6;
    }
    if position < -1.2 {
        position = -1.2;
    }
    if position == -1.2 && velocity < 0.0 {
        velocity = 0.0;
    }
    let terminated = position >= 0.45 && velocity >= 0.0;
    let mut reward = 0.0;
    if terminated {
        reward = 100.0;
    }
    reward -= action.powi(2) * 0.1;
    (position, velocity, reward, terminated)
}

#[test]
fn mountain_car_hand_derived_transitions() {
    let env = MountainCar::state_bias();
    let close = |x: f64, y: f64| abs_diff_eq!(x, y, epsilon = 1e-12);

    // Left wall: pos −1.19, vel −0.07, a = 0: vel = −0.07 − 0.0025·cos(−3.57) ≈ −0.06772,
    // pos ≈ −1.2577 → clipped to −1.2, and vel < 0 there → vel = 0.
    let (next, r, done) = step(&env, &[-1.19, -0.07], &[0.0]);
    assert_eq!((next, r, done), (vec![-1.2, 0.0], 0.0, false));

    // Velocity clip: pos −0.5, vel 0.0695, a = 1: vel ≈ 0.0695 + 0.0015 − 0.0025·cos(−1.5)
    // = 0.070823 → 0.07; pos = −0.43; reward −0.1.
    let (next, r, done) = step(&env, &[-0.5, 0.0695], &[1.0]);
    assert_eq!(next[1], 0.07);
    assert!(close(next[0], -0.43) && close(r, -0.1) && !done);

    // Termination with a clipped force and the RAW action in the reward: pos 0.44, vel 0.02,
    // a = −2 → force −1: vel = 0.02 − 0.0015 − 0.0025·cos(1.32) ≈ 0.017880, pos ≈ 0.457880
    // ≥ 0.45 with vel ≥ 0 → terminated, reward 100 − 0.1·4 = 99.6.
    let (next, r, done) = step(&env, &[0.44, 0.02], &[-2.0]);
    let vel = 0.02 - 0.0015 - 0.0025 * 1.32f64.cos();
    assert!(close(next[1], vel) && close(next[0], 0.44 + vel));
    assert!(done && close(r, 99.6));

    // Past the goal but moving left: not terminated. pos 0.5, vel −0.01, a = −1.
    let (next, r, done) = step(&env, &[0.5, -0.01], &[-1.0]);
    assert!(next[0] >= 0.45 && next[1] < 0.0 && !done && close(r, -0.1));

    // Force clip in the dynamics, raw action in the reward: a = 3 acts like a = 1.
    let (n3, r3, _) = step(&env, &[-0.5, 0.0], &[3.0]);
    let (n1, _, _) = step(&env, &[-0.5, 0.0], &[1.0]);
    assert_eq!(n3, n1);
    assert!(close(r3, -0.9));
}

#[test]
fn mountain_car_trajectories_match_the_reference_implementation() {
    let env = MountainCar::state_bias();
    let mut rng = rng_from_seed(0);
    // Action sequences covering both walls, speed limits, force clipping and the goal:
    // bang-bang energy pumping (reaches the goal), constant left push (hits the left wall),
    // large raw actions, and a full push from near the speed limit.
    type ActionRule = fn(usize, f64) -> f64;
    let policies: [(f64, f64, ActionRule); 4] = [
        (-0.5, 0.0695, |_, _| 1.0),
        (-0.5, 0.0, |_, vel| if vel >= 0.0 { 1.0 } else { -1.0 }),
        (-1.0, -0.03, |_, _| -5.0),
        (-0.3, 0.05, |t, _| 3.0 * ((t as f64) * 0.05).sin()),
    ];
    let mut saw = [false; 4]; // left wall, speed limit, terminated, |a| > 1
    for (pos0, vel0, act) in policies {
        let (mut pos, mut vel) = (pos0, vel0);
        let mut state = [pos0, vel0];
        let mut next = [0.0; 2];
        for t in 0..999 {
            let a = act(t, vel);
            let (rp, rv, rr, rd) = reference_mc_step(pos, vel, a);
            let (r, d) = env.step(&state, &[a], &mut rng, &mut next);
            assert_eq!((next[0], next[1], r, d), (rp, rv, rr, rd), "step {t}");
            saw[0] |= rp == -1.2;
            saw[1] |= rv.abs() == 0.07;
            saw[2] |= rd;
            saw[3] |= a.abs() > 1.0;
            (pos, vel) = (rp, rv);
            state = next;
            if d {
                break;
            }
        }
    }
    assert_eq!(saw, [true, true, true, true]);
}

#[test]
fn features_of_the_environments() {
    let mut phi = [0.0; 3];
    let mc = MountainCar::state_bias();
    mc.features(&[-0.5, 0.01], &mut phi);
    assert_eq!(phi, [-0.5, 0.01, 1.0]);
    let rbf = MountainCar::rbf([3, 3], false).unwrap();
    let mut phi = vec![0.0; rbf.feature_dim()];
    // At the centre (−0.3, 0) of the 3×3 grid, feature 4 (middle) is exactly 1.
    rbf.features(&[-0.3, 0.0], &mut phi);
    assert_abs_diff_eq!(phi[4], 1.0, epsilon = 1e-15);
    // Neighbour at one spacing in position: exp(−½).
    assert_abs_diff_eq!(phi[1], (-0.5f64).exp(), epsilon = 1e-12);
    assert!(MountainCar::new(FeatureMap::Identity { dim: 1 }).is_err());
    let lqg = LqgEnv::thesis();
    let mut phi = [0.0];
    lqg.features(&[1.25], &mut phi);
    assert_eq!(phi, [1.25]);
}
