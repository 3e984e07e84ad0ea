"""A certified step along any direction (docs/THEOREMS.md, "A step along any direction"):
sepg.direction_safe_step against the largest t with
B(t) = t (u.g) - t sum |u_i| eps_i - c kappa t^2 |u|^2 >= C, solved here in closed form with
c = rho R M_phi^2 S_H / sigma^2 written out; and safe Adam in a Trainer."""

import math

import numpy as np
import pytest

import sepg

GAMMA, R, M, VOL, H = 0.99, 28.8, 4.0, 8.0, 20


def s_h(gamma, h):
    """S_H = sum_{t<H} (t + 1) gamma^t, summed term by term."""
    return sum((t + 1) * gamma**t for t in range(h))


def tight_c(sigma, rho):
    """The tight c(sigma) = rho R M_phi^2 S_H / sigma^2 of Theorem T."""
    return rho * R * M * M * s_h(GAMMA, H) / sigma**2


def largest_t(u, g, eps, c2, required, cap):
    """The largest t in [0, cap] with a t - b t^2 >= C (a = u.g - sum |u_i| eps_i,
    b = c2 |u|^2), from the larger root of b t^2 - a t + C = 0; None when no t >= 0 meets C."""
    u, g, eps = (np.asarray(x, dtype=float) for x in (u, g, eps))
    a = float(u @ g - np.abs(u) @ eps)
    b = c2 * float(u @ u)
    disc = a * a - 4.0 * b * required
    if disc < 0:
        return None, a, b
    hi = (a + math.sqrt(disc)) / (2.0 * b)
    if hi < 0:
        return None, a, b
    return min(hi, cap), a, b


TIGHT = sepg.TaskConstants(GAMMA, R, M, VOL, constants="tight", horizon=H, rewards="non-positive")
THESIS = sepg.TaskConstants(GAMMA, R, M, VOL)


@pytest.mark.parametrize(
    "u,g,eps,sigma,required,cap,features,norm,kappa",
    [
        # two features of one action, from |phi_i| <= M_phi: kappa = p = 2 (the default p)
        ([1e-3, -2e-3], [40.0, -10.0], [5.0, 2.0], 0.5, 0.0, 1e9, None, None, 2.0),
        # a bounded worsening C < 0 with wide intervals; p stated
        ([0.3, 0.1, -0.2], [3.0, 1.0, 2.0], [1.0, 0.5, 4.0], 1.0, -0.05, 1e9, 3, None, 3.0),
        # a stated 2-norm bound M2 = 5: kappa = (5 / 4)^2
        ([2e-3, 1e-3], [20.0, 30.0], [1.0, 1.0], 0.2, 1e-4, 1e9, None, 5.0, (5.0 / 4.0) ** 2),
        # the cap binds: Adam's own change (t = 1) is safe
        ([1e-6, 1e-6], [40.0, 30.0], [0.5, 0.5], 1.0, 0.0, 1.0, 2, None, 2.0),
        # a coordinate direction: kappa = 1 whatever p
        ([0.0, -1e-3], [4.0, -30.0], [0.0, 3.0], 0.5, 0.0, 1e9, 7, None, 1.0),
    ],
)
def test_the_step_is_the_largest_t_of_the_bound(u, g, eps, sigma, required, cap, features, norm, kappa):
    c2 = tight_c(sigma, 0.5) * kappa
    want, a, b = largest_t(u, g, eps, c2, required, cap)
    assert want is not None and want > 0
    t, guaranteed, certified = sepg.direction_safe_step(
        TIGHT, sigma, np.array(u), g, eps, required, max_step=cap, features=features, feature_norm=norm
    )
    assert certified
    # The certified step may sit a few ulps inside the largest safe step.
    assert t <= want * (1 + 1e-12)
    assert t == pytest.approx(want, rel=1e-9)
    assert guaranteed >= required
    assert guaranteed == pytest.approx(a * t - b * t * t, rel=1e-9, abs=1e-15)


def test_scalar_widths_apply_to_every_component():
    u, g = [1e-3, -2e-3, 5e-4], [40.0, -10.0, 3.0]
    one = sepg.direction_safe_step(TIGHT, 0.5, u, g, 2.0, 0.0)
    each = sepg.direction_safe_step(TIGHT, 0.5, u, g, [2.0, 2.0, 2.0], 0.0)
    assert one == each


def test_an_unreachable_requirement_is_not_certified():
    u, g, eps = [1e-3, -2e-3], [40.0, -10.0], [5.0, 2.0]
    c2 = tight_c(0.5, 0.5) * 2
    _, a, b = largest_t(u, g, eps, c2, 0.0, math.inf)
    c_max = a * a / (4 * b)
    t, guaranteed, certified = sepg.direction_safe_step(TIGHT, 0.5, u, g, eps, 2 * c_max, max_step=1e9)
    assert not certified
    assert t == pytest.approx(a / (2 * b), rel=1e-9)  # the step of largest guarantee
    assert guaranteed < 2 * c_max


def test_the_thesis_constants_refuse_a_non_coordinate_direction():
    with pytest.raises(ValueError):
        sepg.direction_safe_step(THESIS, 0.5, [1e-3, 1e-3], [1.0, 1.0], 0.0, 0.0)
    # a coordinate direction is Theorem 4.2's case, proven with the thesis's c (kappa = 1)
    t, _, certified = sepg.direction_safe_step(THESIS, 0.5, [0.0, 1e-3], [1.0, 1.0], 0.0, 0.0, max_step=1e9)
    assert certified and t > 0


@pytest.mark.parametrize(
    "kwargs",
    [
        {"direction": [0.0, 0.0]},
        {"direction": [1.0, 1.0, 1.0]},
        {"eps": [-1.0, 0.0]},
        {"features": 0},
        {"feature_norm": -1.0},
        {"features": 2, "feature_norm": 5.0},
        {"grad": [math.nan, 1.0]},
    ],
)
def test_bad_input_raises_invalid_input(kwargs):
    args = {"direction": [1e-3, 1e-3], "grad": [1.0, 1.0], "eps": [0.0, 0.0]}
    args.update(kwargs)
    with pytest.raises(sepg.InvalidInputError):
        sepg.direction_safe_step(TIGHT, 0.5, required=0.0, **args)


def collector(req):
    """Two-step trajectories with feature 1 and the policy's actions, reward -min(a^2, 1): the
    data depend only on the request."""
    n = req.n
    rng = np.random.default_rng([req.iteration, len(req.block), n])
    mean = float(np.asarray(req.mean)[0, 0])
    sigma = 0.0 if req.sigma is None else float(req.sigma[0])
    actions = mean + sigma * rng.standard_normal((n, 2, 1))
    rewards = -np.minimum(actions[:, :, 0] ** 2, 1.0)
    return rewards, actions, np.ones((n, 2, 1)), np.full(n, 2)


def test_a_trainer_runs_safe_adam_and_refuses_it_where_unproven():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 2.0, constants="tight", horizon=2, rewards="non-positive")
    lr = 0.05
    trainer = sepg.Trainer(
        "sepg-mi", k, 1, 1, collector, n_trajectories=400, v0=[0.5], v_direction="adam", adam_lr=lr
    )
    records = trainer.run(5)
    assert len(records) == 5
    v = [0.5] + [r["v"][0] for r in records]
    # Adam's first change is lr sign(g), and t <= 1: no change is longer than lr
    # (|m_hat / sqrt(v_hat)| <= 1 holds at the first step exactly, and below
    # (1 - beta1) / sqrt(1 - beta2) ~ 3.2 later).
    assert abs(v[1] - v[0]) <= lr * (1 + 1e-12)
    assert all(abs(b - a) <= 3.2 * lr for a, b in zip(v, v[1:]))
    assert v[-1] < v[0]  # toward the optimum a = 0 of -a^2
    bad = [
        dict(v_direction="adam"),
        dict(adam_lr=lr),
        dict(v_direction="greedy", adam_eps=1e-6),
        dict(v_direction="adam", adam_lr=lr, accounting="estimated"),
        dict(v_direction="newton"),
    ]
    for kwargs in bad:
        with pytest.raises(sepg.InvalidInputError):
            sepg.Trainer("sepg-mi", k, 1, 1, collector, n_trajectories=400, **kwargs)
    with pytest.raises(sepg.InvalidInputError):
        sepg.Trainer("sepg-mi", sepg.TaskConstants(0.9, 1.0, 1.0, 2.0), 1, 1, collector, v_direction="adam", adam_lr=lr)
