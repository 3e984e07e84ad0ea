"""The families of constants: sepg.TaskConstants with the tight constants of docs/THEOREMS.md
("Tight constants"), checked against the printed formulas c = rho R M_phi^2 S_H / sigma^2 and
d = 2 rho R S_H written out here, and a Trainer's step under each family."""

import math

import numpy as np
import pytest

import sepg
from sepg import bounds


def s_h_closed(gamma, h):
    """S_H = sum_{t<H} (t + 1) gamma^t = (1 - (H + 1) gamma^H + H gamma^(H + 1)) / (1 - gamma)^2."""
    return (1.0 - (h + 1) * gamma**h + h * gamma ** (h + 1)) / (1.0 - gamma) ** 2


def thesis_c(gamma, r, m, vol, sigma):
    """c of Theorems 3.14 / 4.2."""
    return r * m * m / ((1 - gamma) ** 2 * sigma**2) * (
        vol / (math.sqrt(2 * math.pi) * sigma) + gamma / (2 * (1 - gamma))
    )


@pytest.mark.parametrize("sigma", [0.1, 0.5, 1.0, 2.5])
def test_tight_c_and_d_are_the_printed_formulas(sigma):
    gamma, r, m, vol = 0.99, 28.8, 4.0, 8.0
    s_h = s_h_closed(gamma, 20)
    two = sepg.TaskConstants(gamma, r, m, vol, constants="tight", horizon=20)
    assert (two.family, two.horizon, two.rewards) == ("tight", 20, "two-sided")
    assert two.horizon_weight == pytest.approx(s_h, rel=1e-13)
    assert bounds.constants_c(two, sigma) == pytest.approx(r * m * m * s_h / sigma**2, rel=1e-13)
    assert bounds.constants_d(two, sigma) == pytest.approx(2 * r * s_h, rel=1e-13)
    half = sepg.TaskConstants(gamma, r, m, vol, constants="tight", horizon=20, rewards="non-positive")
    assert bounds.constants_c(half, sigma) == pytest.approx(0.5 * r * m * m * s_h / sigma**2, rel=1e-13)
    assert bounds.constants_d(half, sigma) == pytest.approx(r * s_h, rel=1e-13)
    # with_family gives the same constants as the constructor
    plain = sepg.TaskConstants(gamma, r, m, vol)
    assert plain.family == "thesis" and plain.horizon is None and plain.horizon_weight is None
    assert plain.with_family("tight", horizon=20, rewards="non-positive") == half
    assert bounds.constants_c(plain, sigma) == pytest.approx(thesis_c(gamma, r, m, vol, sigma), rel=1e-12)


def test_an_infinite_horizon_and_bad_values():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0, constants="tight", horizon=math.inf)
    assert k.horizon == math.inf
    assert k.horizon_weight == pytest.approx(100.0, rel=1e-13)
    assert sepg.TaskConstants(0.9, 1.0, 1.0, 2.0, constants="tight", horizon="inf") == k
    assert "constants='tight'" in repr(k)
    for kwargs in [
        {"constants": "tight"},
        {"constants": "tight", "horizon": 0},
        {"constants": "tight", "horizon": -2},
        {"constants": "tight", "horizon": 1.5},
        {"constants": "tight", "horizon": 20, "rewards": "up"},
        {"constants": "thesis", "horizon": 20},
        {"constants": "foo"},
    ]:
        with pytest.raises(sepg.InvalidInputError):
            sepg.TaskConstants(0.9, 1.0, 1.0, 2.0, **kwargs)


def collector(req):
    """Trajectories of two steps with feature 1 and the policy's actions, reward clip(a, -1, 1):
    the data depend only on the request, so two trainers asked for the same batch get the same
    one."""
    n = req.n
    rng = np.random.default_rng([req.iteration, len(req.block), n])
    mean = float(np.asarray(req.mean)[0, 0])
    sigma = 0.0 if req.sigma is None else float(req.sigma[0])
    actions = mean + sigma * rng.standard_normal((n, 2, 1))
    rewards = np.clip(actions[:, :, 0], -1.0, 1.0)
    return rewards, actions, np.ones((n, 2, 1)), np.full(n, 2)


def test_a_trainer_step_with_tight_constants_is_larger_by_the_ratio_of_c():
    # SEPG-MI's first v-step (C = 0) is the high-probability step of Theorem 4.7,
    # (||g||^-)^2 / (c (||g||^+)^2): the same batch under both families, so the steps differ by
    # the ratio of the two c only.
    gamma, r, m, vol, sigma = 0.9, 1.0, 1.0, 2.0, 1.0
    thesis = sepg.TaskConstants(gamma, r, m, vol)
    tight = thesis.with_family("tight", horizon=2)
    steps = {}
    for name, k in [("thesis", thesis), ("tight", tight)]:
        trainer = sepg.Trainer("sepg-mi", k, 1, 1, collector, n_trajectories=400)
        steps[name] = trainer.run(1)[0]["alpha"]
    c_thesis = thesis_c(gamma, r, m, vol, sigma)
    c_tight = r * m * m * s_h_closed(gamma, 2) / sigma**2  # S_2 = 1 + 2 gamma
    assert steps["thesis"] > 0
    assert steps["tight"] > 100 * steps["thesis"]
    # The certified step may sit a few ulps inside the largest safe step.
    assert steps["tight"] / steps["thesis"] == pytest.approx(c_thesis / c_tight, rel=1e-9)


def test_a_gym_run_takes_the_tight_two_sided_constants_of_its_horizon_unless_told():
    pytest.importorskip("gymnasium")
    from sepg import gym as sg

    args = dict(gamma=0.99, r_max=100.0, n_trajectories=12, horizon=60, show_derivation=False)
    run = sg.GymRun("MountainCarContinuous-v0", **args)
    k = run.constants
    assert (k.family, k.horizon, k.rewards) == ("tight", 60, "two-sided")
    assert k.horizon_weight == pytest.approx(s_h_closed(0.99, 60), rel=1e-13)
    thesis = sg.GymRun("MountainCarContinuous-v0", constants="thesis", **args)
    assert thesis.constants.family == "thesis"
    with pytest.raises(sepg.InvalidInputError):
        sg.GymRun("MountainCarContinuous-v0", constants="thesis", rewards="non-positive", **args)
