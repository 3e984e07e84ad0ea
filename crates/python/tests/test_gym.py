"""SEPG on gymnasium environments: determinism, vector environments, constants, errors, and
the cross-check of the built-in mountain-car against gymnasium's MountainCarContinuous-v0."""


import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import sepg
from sepg import gym as sg

MCC = "MountainCarContinuous-v0"


def small_run(env, **kw):
    args = dict(gamma=0.99, r_max=100.0, n_trajectories=12, horizon=60, seed=3, show_derivation=False)
    args.update(kw)
    return sg.GymRun(env, **args)


def test_same_seed_same_records_other_seed_other_records():
    # The thesis's bookkeeping with a small reference batch of J(theta^0) keeps the test
    # short; its 20 trajectories are collected before iteration 0, once for J(theta^0) of the
    # exploratory policy and once for the target's (type-II requirement ZV): 2 x 20 + 3
    # iterations x 12.
    a = small_run(MCC, reference_batch=20, accounting="estimated")
    a.run(3)
    b = small_run(MCC, reference_batch=20, accounting="estimated")
    b.run(2)
    b.run(1)  # resuming between iterations changes nothing
    c = small_run(MCC, seed=4, reference_batch=20, accounting="estimated")
    c.run(3)
    assert a.records == b.records
    assert a.records != c.records
    assert [r["iteration"] for r in a.records] == [0, 1, 2]
    assert [r["trajectories"] for r in a.records] == [52, 64, 76]


def test_a_vector_env_gives_the_records_of_a_single_env():
    # Batches of 30 (the reference batch) and 5 (a third of 15) trajectories leave a partial
    # last group of the 4 environments.
    single = small_run(gymnasium.make(MCC), algorithm="sepg-lv", n_trajectories=15, reference_batch=30)
    single.run(2)
    vec = gymnasium.make_vec(MCC, num_envs=4, vectorization_mode="sync")
    vector = small_run(vec, algorithm="sepg-lv", n_trajectories=15, reference_batch=30)
    vector.run(2)
    assert single.records == vector.records


@pytest.mark.parametrize(
    "algorithm,options",
    [
        ("sepg-mi", {}),
        ("sepg-lb1", {"nu": 0.5}),
        ("sepg-lb2", {}),
        ("sepg-sim", {"nu": 0.3}),
        ("sepg-naive-w", {"requirement": "zv"}),
        ("gpomdp-const", {"alpha": 1e-3}),
        ("gpomdp-adam", {"lr": 1e-2}),
        ("adastep", {}),
    ],
)
def test_every_algorithm_runs_on_pendulum(algorithm, options):
    # A reference batch of 24 trajectories (not the default 1000) keeps the type-II
    # requirements (LB1, LB2, SIM, naive-w) as short as the others.
    run = sg.GymRun(
        "Pendulum-v1", gamma=0.9, r_max=16.2736, n_trajectories=12, horizon=20,
        algorithm=algorithm, show_derivation=False, reference_batch=24, **options,
    )
    arrays = run.run(2)
    assert arrays["iteration"].tolist() == [0, 1]
    assert np.all(np.isfinite(arrays["j_explore"]))
    assert np.all(np.isfinite(run.mean)) and np.all(run.sigma > 0)


def test_constants_are_derived_from_bounded_spaces_and_shown(capsys):
    k, derivation = sg.derive_constants(gymnasium.make(MCC), gamma=0.99, r_max=100.0)
    assert k.action_volume == 2.0
    assert k.m_phi == pytest.approx(1.2, rel=1e-6)
    assert any(line.startswith("|A| = prod(high - low) = 2") for line in derivation)
    small_run(MCC, show_derivation=True)
    assert "M_phi = max |bound| = 1.2" in capsys.readouterr().err
    k, derivation = sg.derive_constants(
        gymnasium.make(MCC), gamma=0.99, r_max=1.0, m_phi=2.0, action_volume=3.0
    )
    assert derivation == [] and (k.m_phi, k.action_volume) == (2.0, 3.0)


def test_missing_constants_are_a_clear_error():
    with pytest.raises(sepg.MissingConstantError, match="r_max") as info:
        small_run(MCC, r_max=None)
    assert isinstance(info.value, ValueError)
    with pytest.raises(sepg.MissingConstantError, match="m_phi"):
        small_run(MCC, features=lambda s: np.append(s, 1.0))
    assert small_run(MCC, features=lambda s: np.append(s, 1.0), m_phi=1.2).n_features == 3


def test_bad_environments_and_arguments_are_value_errors():
    with pytest.raises(sepg.InvalidInputError, match="Box action space"):
        small_run("CartPole-v1")
    with pytest.raises(sepg.InvalidInputError, match="unknown algorithm"):
        small_run(MCC, algorithm="sepg-xx")
    with pytest.raises(sepg.InvalidInputError, match="needs alpha"):
        small_run(MCC, algorithm="gpomdp-const")
    with pytest.raises(sepg.InvalidInputError, match="v0"):
        small_run(MCC, v0=[1.0])
    with pytest.raises(sepg.InvalidInputError, match="TooFew|trajectories"):
        small_run(MCC, n_trajectories=5)
    with pytest.raises(ValueError):
        small_run(MCC, gamma=1.0)
    with pytest.raises(sepg.InvalidInputError):
        small_run(MCC, horizon=0)


class Boom(Exception):
    pass


def test_a_collector_exception_is_raised_as_it_is_and_the_state_is_kept():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)
    calls = []

    def collector(req):
        calls.append((req.iteration, req.block))
        if req.iteration >= 1:
            raise Boom("no more trajectories")
        n = req.n
        return np.ones((n, 2)), np.zeros((n, 2, 1)), np.ones((n, 2, 1)), np.full(n, 2)

    trainer = sepg.Trainer("sepg-zv", k, 1, 1, collector, n_trajectories=12)
    trainer.run(1)
    with pytest.raises(Boom, match="no more"):
        trainer.run(1)
    assert calls[-1][0] == 1
    assert '"iteration":1' in trainer.state()


def fake_collector(requests):
    """A collector of constant trajectories (reward 1, two steps) that records each request
    as (iteration, block, n)."""

    def collect(req):
        requests.append((req.iteration, req.block, req.n))
        n = req.n
        return np.ones((n, 2)), np.zeros((n, 2, 1)), np.ones((n, 2, 1)), np.full(n, 2)

    return collect


@pytest.mark.parametrize("reference_batch,first", [(None, 1000), (0, None), (7, 7)])
def test_the_reference_batch_is_collected_once_before_the_first_iteration(reference_batch, first):
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)
    requests = []
    # the reference batch is the thesis's bookkeeping's; the certified accounting has none
    options = {"accounting": "estimated"}
    if reference_batch is not None:
        options["reference_batch"] = reference_batch
    trainer = sepg.Trainer("sepg-zv", k, 1, 1, fake_collector(requests), n_trajectories=12, **options)
    records = trainer.run(2)
    reference = [r for r in requests if r[1].startswith("reference")]
    if first is None:
        assert reference == []
    else:
        assert reference and all(r[0] == 0 and r[2] == first for r in reference)
    # Every trajectory asked for is counted, the reference batch once in iteration 0.
    assert records[-1]["trajectories"] == sum(r[2] for r in requests)
    assert sum(r[2] for r in requests if r[1] in ("v", "target", "w")) == 2 * 12


def test_the_certified_accounting_collects_no_reference_batch_and_names_a_bad_value():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)
    requests = []
    trainer = sepg.Trainer("sepg-zv", k, 1, 1, fake_collector(requests), n_trajectories=12)
    records = trainer.run(2)
    assert [r for r in requests if r[1].startswith("reference")] == []
    assert records[-1]["trajectories"] == 2 * 12
    with pytest.raises(sepg.InvalidInputError, match="accounting"):
        sepg.Trainer("sepg-zv", k, 1, 1, fake_collector([]), n_trajectories=12, accounting="thesis")


def test_a_reference_batch_of_one_trajectory_is_refused():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)
    with pytest.raises(sepg.InvalidInputError, match="reference batch"):
        sepg.Trainer("sepg-zv", k, 1, 1, fake_collector([]), n_trajectories=12, reference_batch=1)


@pytest.mark.parametrize(
    "output",
    [
        "not a tuple",
        (np.ones((4, 2)),),
        (np.ones((3, 2)), np.zeros((4, 2, 1)), np.ones((4, 2, 1)), np.full(4, 2)),
        (np.full((4, 2), np.nan), np.zeros((4, 2, 1)), np.ones((4, 2, 1)), np.full(4, 2)),
        (np.ones((4, 2)), np.zeros((4, 2, 1)), np.ones((4, 2, 3)), np.full(4, 2)),
        (np.ones((4, 2)), np.zeros((4, 2, 1)), np.ones((4, 2, 1)), np.full(4, 3)),
        (np.ones((4, 2)), np.zeros((4, 2, 1)), np.ones((4, 2, 1)), np.full(4, 1.5)),
    ],
)
def test_inconsistent_collector_output_is_a_value_error(output):
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)
    trainer = sepg.Trainer("adastep", k, 1, 1, lambda req: output, n_trajectories=4)
    with pytest.raises(sepg.InvalidInputError):
        trainer.run(1)


def f32_ulp(x):
    return float(np.spacing(np.float32(abs(x))))


def f32_tolerance(before, after):
    """Four float32 roundings at the scale of the operands of one transition: gymnasium
    updates the float32 state in float32 arithmetic (velocity terms of size up to
    0.0015 + 0.0025), the built-in environment in f64."""
    tol_v = 4 * f32_ulp(max(abs(before[1]), abs(after[1]), 0.004))
    tol_p = 4 * f32_ulp(max(abs(before[0]), abs(after[0]))) + tol_v
    return np.array([tol_p, tol_v])


def test_builtin_mountain_car_matches_gymnasium_to_float32_precision():
    env = gymnasium.make(MCC).unwrapped
    rng = np.random.Generator(np.random.PCG64(5))
    transitions = 0
    for episode in range(4):
        obs, _ = env.reset(seed=episode)
        gym_states, gym_rewards, actions = [np.asarray(obs, dtype=float)], [], []
        terminated = False
        for _ in range(400):
            # Random raw actions, some outside [-1, 1] (clipped as force, penalised raw);
            # a push in the direction of the velocity so that some episodes terminate.
            a = float(np.sign(gym_states[-1][1] + 1e-9) * 1.5 + rng.normal(0.0, 0.5))
            obs, r, terminated, _, _ = env.step(np.array([a]))
            actions.append(a)
            gym_states.append(np.asarray(obs, dtype=float))
            gym_rewards.append(float(r))
            if terminated:
                break
        # One transition at a time from gymnasium's (float32) state: the same up to float32
        # rounding.
        for t, a in enumerate(actions):
            states, rewards, done = sepg.mountain_car_trajectory(gym_states[t], [a])
            tol = f32_tolerance(gym_states[t], gym_states[t + 1])
            assert np.all(np.abs(states[1] - gym_states[t + 1]) <= tol), (episode, t)
            assert rewards[0] == pytest.approx(gym_rewards[t], rel=1e-12)
            assert done == (terminated and t == len(actions) - 1)
            transitions += 1
        # The whole trajectory from the same start: float32 rounding accumulates but stays
        # within 1e-4 (relative to the ranges 1.8 and 0.14) and the episodes end together.
        states, rewards, done = sepg.mountain_car_trajectory(gym_states[0], actions)
        assert done == terminated and len(rewards) == len(actions)
        np.testing.assert_allclose(states, np.asarray(gym_states), rtol=0, atol=1e-4)
    assert transitions > 400
