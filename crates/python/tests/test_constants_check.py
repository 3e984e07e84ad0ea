"""The declared constants checked against the data a run collects (docs/RELIABILITY.md,
"Declared constants checked against the data"): a reward beyond R_max or a feature vector
beyond M_phi stops the run by default, or marks it "no guarantee" with
on_contradiction="continue"."""

import json

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import sepg
from sepg import gym as sg


class ConstantReward(gymnasium.Env):
    """A one-dimensional task whose every reward is `reward` and whose observation is 0.5:
    the values a check must report are known without running it."""

    def __init__(self, reward=3.0):
        self.reward = reward
        self.observation_space = gymnasium.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float64)
        self.action_space = gymnasium.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float64)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.array([0.5]), {}

    def step(self, action):
        return np.array([0.5]), self.reward, False, False, {}


def run(env, features=None, **kw):
    args = dict(
        gamma=0.9,
        r_max=1.0,
        m_phi=1.0,
        action_volume=2.0,
        n_trajectories=12,
        horizon=5,
        seed=1,
        show_derivation=False,
    )
    args.update(kw)
    return sg.GymRun(env, features, **args)


def test_rewards_above_r_max_stop_the_run_naming_the_constant_and_the_value():
    r = run(ConstantReward(3.0))
    with pytest.raises(sepg.RunFailedError) as e:
        r.run(2)
    message = str(e.value)
    # every reward is 3 > R_max = 1: the first one, trajectory 0, step 0, of iteration 0
    assert "|reward| = 3 exceeds r-max = 1" in message
    assert "iteration 0, block v, trajectory 0, step 0" in message
    assert r.records == [] and r.state["iteration"] == 0


def test_continue_goes_on_and_the_state_says_no_guarantee():
    r = run(ConstantReward(3.0), on_contradiction="continue")
    r.run(2)
    check = r.state["constants_check"]
    assert check["first"]["what"] == "r-max"
    assert (check["first"]["value"], check["first"]["bound"]) == (3.0, 1.0)
    # every reward collected (all trajectories run the full horizon) contradicts R_max
    assert check["r_max"] == check["rewards_checked"] > 0
    assert check["m_phi"] == 0 and check["features_checked"] > 0
    assert len(r.records) == 2


def test_rewards_within_r_max_pass():
    r = run(ConstantReward(-1.0))
    r.run(2)  # |r| = R_max exactly is allowed
    assert "constants_check" in r.state
    assert r.state["constants_check"]["first"] is None


@pytest.mark.parametrize(
    "v_direction,norm",
    [
        ("greedy", 80.0),  # the greedy coordinate needs |phi_i| <= M_phi: max(60, 80)
        ("adam", 100.0),  # any other direction needs ||phi||_2 <= M_phi: |(60, 80)| = 100
    ],
)
def test_features_above_m_phi_stop_the_run_in_the_norm_the_update_needs(v_direction, norm):
    extra = {"adam_lr": 0.01} if v_direction == "adam" else {}
    r = run(
        ConstantReward(-0.5),
        lambda obs: np.array([60.0, 80.0]),
        m_phi=1.2,
        v_direction=v_direction,
        **extra,
    )
    with pytest.raises(sepg.RunFailedError, match=f"feature norm {norm:g} exceeds m-phi = 1.2"):
        r.run(1)


def test_pendulum_with_tiny_constants_is_stopped_and_continues_without_guarantee():
    kw = dict(r_max=0.01, m_phi=0.01, gamma=0.99, horizon=10, n_trajectories=12)
    with pytest.raises(sepg.RunFailedError, match=r"exceeds (r-max = 0.01|m-phi = 0.01)"):
        run("Pendulum-v1", **kw).run(1)
    cont = run("Pendulum-v1", on_contradiction="continue", **kw)
    cont.run(1)
    check = cont.state["constants_check"]
    # cos(theta)^2 + sin(theta)^2 = 1: every observation has a component of size >= 0.707
    assert check["m_phi"] == check["features_checked"] > 0
    assert check["first"] is not None


def test_the_trainer_refuses_an_unknown_policy():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)
    with pytest.raises(sepg.InvalidInputError, match="on_contradiction"):
        sepg.Trainer("sepg-zv", k, 1, 1, lambda req: None, on_contradiction="ignore")


def test_the_trainer_checks_the_collected_rewards():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0)

    def collect(req):
        n, h = req.n, 3
        rewards = np.full((n, h), -0.25)
        rewards[1, 2] = -7.5  # the only value beyond R_max = 1
        actions = np.zeros((n, h, 1)) if req.scores else None
        feats = np.full((n, h, 1), 0.5) if req.scores else None
        return rewards, actions, feats, np.full(n, h)

    t = sepg.Trainer("sepg-zv", k, 1, 1, collect, n_trajectories=12, on_contradiction="continue")
    t.run(1)
    check = json.loads(t.state())["constants_check"]
    assert check["first"]["value"] == -7.5
    assert (check["first"]["trajectory"], check["first"]["step"]) == (1, 2)
    with pytest.raises(sepg.RunFailedError, match=r"\|reward\| = 7.5 exceeds r-max = 1"):
        sepg.Trainer("sepg-zv", k, 1, 1, collect, n_trajectories=12).run(1)
