"""The framework-agnostic safe-step API against independent computations."""

import math

import numpy as np
import pytest

import sepg
from sepg import bounds

K = sepg.TaskConstants(0.95, 1.0, 1.0, 2.0)


def test_v_step_is_the_greedy_coordinate_step_of_theorems_4_2_and_4_7():
    g = np.array([0.2, -0.9, 0.4])
    exact = sepg.v_step(K, 0.7, g, required=-0.01)
    o = bounds.v_update_safe_step(K, 0.7, g, -0.01)
    assert (exact.index, exact.size, exact.delta) == (1, o.hi, o.hi * -0.9)
    assert exact.guaranteed == pytest.approx(-0.01, rel=1e-9)
    assert not exact.infeasible and not exact.below_noise
    eps = np.array([0.05, 0.1, 0.3])
    est = sepg.v_step(K, 0.7, g, eps=eps, required=-0.01)
    hp = bounds.high_probability_v_safe_step(K, 0.7, g, 0.3, -0.01)
    assert (est.index, est.size) == (1, hp.hi)
    assert est.size < exact.size  # the widths shrink the safe step
    new = est.apply(np.zeros(3))
    assert new.tolist() == [0.0, est.delta, 0.0]
    assert sepg.v_step(K, 0.7, g, eps=1.0).below_noise
    assert sepg.v_step(K, 0.7, g, eps=1.0).apply([1.0, 2.0, 3.0]).tolist() == [1.0, 2.0, 3.0]


def test_w_step_moves_along_l_or_along_j():
    sig = [1.0, 0.5]
    along_l = sepg.w_step(K, sig, [0.1, -0.2], [0.05, 0.3], required=-1e-3)
    o = bounds.w_update_safe_step_along_l(K, 0.5, -0.2, 0.3, -1e-3)
    assert (along_l.index, along_l.size, along_l.delta) == (1, o.hi, o.hi * 0.3)
    naive = sepg.w_step(K, sig, [0.1, -0.2], required=-1e-3)
    oj = bounds.w_update_safe_step_along_j(K, 0.5, -0.2, -1e-3)
    assert (naive.index, naive.size) == (1, oj.hi)
    infeasible = sepg.w_step(K, sig, [0.1, -0.2], required=1.0)
    assert infeasible.infeasible and infeasible.lam == 0.0


def test_required_improvement_follows_table_4_1():
    assert sepg.required_improvement("mi") == (0.0, 0.0)
    assert sepg.required_improvement("zv", budget=2.0) == (-2.0, -2.0)
    assert sepg.required_improvement("sim", budget=2.0, nu=0.25) == (-0.5, -1.5)
    assert sepg.required_improvement("lb1", nu=0.25, j_initial=-1.0, j_current=1.0) == (-1.5, -0.5)
    with pytest.raises(sepg.InvalidInputError):
        sepg.required_improvement("lb1")
    with pytest.raises(ValueError):
        sepg.required_improvement("zz")


def test_confidence_widths_use_the_student_t_quantile():
    # t quantiles from standard tables: t(0.9, 9) = 1.383029, t(0.975, 4) = 2.776445.
    rng = np.random.Generator(np.random.PCG64(7))
    for n, delta, t in ((10, 0.2, 1.383029), (5, 0.05, 2.776445)):
        x = rng.standard_normal((n, 3))
        mean, eps = sepg.confidence_widths(x, delta=delta)
        np.testing.assert_allclose(mean, x.mean(axis=0), rtol=1e-14)
        np.testing.assert_allclose(eps, t * x.std(axis=0, ddof=1) / math.sqrt(n), rtol=2e-6)


def gpomdp_loo(rewards, scores, gamma):
    """G(PO)MDP with the per-step variance-optimal baseline fitted leave-one-out, written
    from its definition: trajectory i uses b_{t,k} = sum_{j != i} S_{j,t,k}^2 g^t r_{j,t} /
    sum_{j != i} S_{j,t,k}^2, with S the cumulative score."""
    n, h = rewards.shape
    disc = rewards * gamma ** np.arange(h)
    cum = np.cumsum(scores, axis=1)
    s2 = cum**2
    num = (s2 * disc[:, :, None]).sum(axis=0)
    den = s2.sum(axis=0)
    samples = []
    for i in range(n):
        d = den - s2[i]
        b = np.where(d > 0, (num - s2[i] * disc[i][:, None]) / np.where(d > 0, d, 1.0), 0.0)
        samples.append((cum[i] * (disc[i][:, None] - b)).sum(axis=0))
    return np.asarray(samples)


def test_estimate_block_matches_gpomdp_written_from_its_definition():
    rng = np.random.Generator(np.random.PCG64(11))
    n, h, m, l = 40, 6, 2, 1
    rewards = rng.standard_normal((n, h))
    score_v = rng.standard_normal((n, h, m))
    score_w = rng.standard_normal((n, h, l))
    e = sepg.estimate_block(K, [0.8], rewards, score_v, score_w, np.full(n, h), delta=0.2)
    disc = rewards * K.gamma ** np.arange(h)
    assert e["j"] == pytest.approx(disc.sum(axis=1).mean(), rel=1e-13)
    for grad, eps, scores in (("grad_v", "eps_v", score_v), ("grad_w_j", "eps_w_j", score_w)):
        samples = gpomdp_loo(rewards, scores, K.gamma)
        mean, width = sepg.confidence_widths(samples, delta=0.2)
        np.testing.assert_allclose(e[grad], mean, rtol=1e-10)
        np.testing.assert_allclose(e[eps], width, rtol=1e-8)
    assert e["grad_w_l"].shape == (1,) and np.all(np.isfinite(e["grad_w_l"]))
    assert (e["trajectories"], e["steps"]) == (n, n * h)


def test_estimate_block_ignores_steps_after_a_trajectory_ends():
    rng = np.random.Generator(np.random.PCG64(12))
    n, h = 8, 5
    rewards, sv, sw = rng.standard_normal((n, h)), rng.standard_normal((n, h, 1)), rng.standard_normal((n, h, 1))
    lengths = np.array([5, 3, 5, 1, 2, 5, 4, 5])
    e = sepg.estimate_block(K, [1.0], rewards, sv, sw, lengths, grad_w_l=False)
    junk = rewards.copy()
    for i, length in enumerate(lengths):
        junk[i, length:] = 1e6
    f = sepg.estimate_block(K, [1.0], junk, sv, sw, lengths, grad_w_l=False)
    assert e["j"] == f["j"] and e["grad_v"].tolist() == f["grad_v"].tolist()
    assert e["grad_w_l"] is None and e["steps"] == lengths.sum()
    with pytest.raises(sepg.InvalidInputError):
        sepg.estimate_block(K, [1.0], rewards, sv, sw, np.full(n, h + 1))
    with pytest.raises(sepg.InvalidInputError):
        sepg.estimate_block(K, [1.0], rewards, sv[:, :3], sw, lengths)
