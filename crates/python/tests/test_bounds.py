"""The bound functions against closed forms recomputed here, and the contract on bad input."""

import math

import numpy as np
import pytest

import sepg
from sepg import bounds

K = sepg.TaskConstants(0.9, 2.0, 1.5, 3.0)


def c_closed_form(k, sigma):
    # c(sigma) = R M^2 / ((1 - g)^2 sigma^2) * (|A| / (sqrt(2 pi) sigma) + g / (2 (1 - g)))
    g = k.gamma
    return (
        k.r_max
        * k.m_phi**2
        / ((1 - g) ** 2 * sigma**2)
        * (k.action_volume / (math.sqrt(2 * math.pi) * sigma) + g / (2 * (1 - g)))
    )


def psi_closed_form():
    r7 = math.sqrt(7.0)
    return 4 * (r7 - 2) * math.exp(r7 / 2 - 2) / math.sqrt(2 * math.pi)


def test_constants_match_their_closed_forms():
    assert bounds.constants_psi() == pytest.approx(psi_closed_form(), rel=1e-14)
    # psi is the maximum of |(x^2 - 4x + 1) exp(-x/2)| / sqrt(2 pi) on x >= 0: check on a grid.
    x = np.linspace(0.0, 20.0, 200001)
    grid_max = np.max(np.abs((x**2 - 4 * x + 1) * np.exp(-x / 2))) / math.sqrt(2 * math.pi)
    assert bounds.constants_psi() == pytest.approx(grid_max, rel=1e-8)
    for sigma in (0.1, 0.5, 1.0, 4.0):
        assert bounds.constants_c(K, sigma) == pytest.approx(c_closed_form(K, sigma), rel=1e-13)
        d = K.r_max / (1 - K.gamma) ** 2 * (
            psi_closed_form() * K.action_volume / (2 * sigma) + K.gamma / (1 - K.gamma)
        )
        assert bounds.constants_d(K, sigma) == pytest.approx(d, rel=1e-13)
        h = 1e-6 * sigma
        fd = (bounds.constants_c(K, sigma + h) - bounds.constants_c(K, sigma - h)) / (2 * h)
        assert bounds.constants_dc_dsigma(K, sigma) == pytest.approx(fd, rel=1e-6)


def test_v_update_bound_and_safe_interval():
    g = np.array([0.3, -0.7, 0.1])
    sigma = 0.8
    c = c_closed_form(K, sigma)
    n2 = np.max(np.abs(g)) ** 2
    alpha = 1.3e-4
    assert bounds.v_update_bound(K, sigma, g, alpha) == pytest.approx(
        alpha * n2 - alpha**2 * c * n2, rel=1e-12
    )
    assert bounds.v_update_alpha_star(K, sigma) == pytest.approx(1 / (2 * c), rel=1e-13)
    c_max = bounds.v_update_c_max(K, sigma, g)
    assert c_max == pytest.approx(n2 / (4 * c), rel=1e-13)
    required = 0.5 * c_max
    o = bounds.v_update_safe_step(K, sigma, g, required)
    assert o.kind == "feasible" and o.is_feasible
    assert o.lam == pytest.approx(math.sqrt(1 - required / c_max), rel=1e-12)
    for step in (o.lo, o.hi):
        assert bounds.v_update_bound(K, sigma, g, step) == pytest.approx(required, rel=1e-9)
    assert o.chosen_step == o.hi
    bad = bounds.v_update_safe_step(K, sigma, g, 2 * c_max)
    assert bad.kind == "infeasible" and not bad.is_feasible
    assert bad.chosen_step == pytest.approx(1 / (2 * c), rel=1e-12)
    assert bounds.v_update_safe_step(K, sigma, [0.0, 0.0], 0.0).kind == "zero_gradient"


def test_w_update_and_high_probability_bounds_are_consistent():
    sigma, gj, gl = 1.2, 0.4, -0.3
    o = bounds.w_update_safe_step_along_j(K, sigma, gj, 0.0)
    assert o.kind == "feasible"
    assert bounds.w_update_bound_along_j(K, sigma, gj, o.hi) == pytest.approx(0.0, abs=1e-12)
    assert bounds.w_update_c_max(K, sigma, gj) == pytest.approx(
        bounds.w_update_bound_along_j(K, sigma, gj, bounds.w_update_beta_star(K, sigma)), rel=1e-12
    )
    ol = bounds.w_update_safe_step_along_l(K, sigma, gj, gl, -1e-3)
    assert bounds.w_update_bound_along_l(K, sigma, gj, gl, ol.hi) == pytest.approx(-1e-3, rel=1e-6)
    hp = sepg.HighProbabilityBound.v_update(K, sigma, [0.5, -0.2], 0.1)
    # Theorem 4.7: a- = (|g|inf - eps)^2, b = c (|g|inf + eps)^2.
    assert hp.linear_lower == pytest.approx(0.4**2, rel=1e-12)
    assert hp.quadratic == pytest.approx(c_closed_form(K, sigma) * 0.6**2, rel=1e-12)
    assert sepg.HighProbabilityBound.v_update(K, sigma, [0.05], 0.1) is None
    assert bounds.high_probability_corrected_norm([0.5, -0.2], 0.1) == pytest.approx((0.4, 0.6))
    assert bounds.high_probability_v_safe_step(K, sigma, [0.05], 0.1, 0.0).kind == "below_noise"


def test_budget_split_and_tracking():
    assert bounds.budget_split_requirement(-2.0, 0.25) == (-1.5, -0.5)
    b = sepg.Budget(1.0, -10.0, -8.0)
    assert (b.value, b.baseline) == (1.0, -9.0)
    b.record_exploratory(-9.5)
    assert b.value == pytest.approx(1.5)
    assert b.is_type_two_safe


def test_pirotta_papini_and_batch_size():
    g = [0.2, -0.4]
    alpha, guarantee, kind = bounds.pirotta_optimal_step(K, 1.0, g)
    assert kind == "step" and alpha > 0
    assert bounds.pirotta_bound(K, 1.0, g, alpha) == pytest.approx(guarantee, rel=1e-12)
    assert bounds.pirotta_hp_optimal_step(K, 1.0, g, [1.0, 1.0])[2] == "below_noise"
    index, a, steps, guarantee = bounds.papini_greedy_step(K, 1.0, g)
    assert index == 1 and steps == [0.0, a]
    assert guarantee == pytest.approx(0.4**2 / (4 * c_closed_form(K, 1.0)), rel=1e-12)
    assert bounds.papini_bound(K, 1.0, g, steps) == pytest.approx(guarantee, rel=1e-12)
    assert bounds.batch_size_gpomdp(K, 1.0, 0.1, 0.5, 10) >= 1


NAN, INF = float("nan"), float("inf")

INVALID = [
    lambda: sepg.TaskConstants(1.0, 1.0, 1.0, 1.0),
    lambda: sepg.TaskConstants(NAN, 1.0, 1.0, 1.0),
    lambda: sepg.TaskConstants(0.9, -1.0, 1.0, 1.0),
    lambda: sepg.TaskConstants(0.9, 1.0, INF, 1.0),
    lambda: sepg.TaskConstants(0.9, 1.0, 1.0, 0.0),
    lambda: bounds.constants_c(K, 0.0),
    lambda: bounds.constants_d(K, NAN),
    lambda: bounds.v_update_safe_step(K, -1.0, [1.0], 0.0),
    lambda: bounds.v_update_safe_step(K, 1.0, [NAN], 0.0),
    lambda: bounds.v_update_safe_step(K, 1.0, [1.0], INF),
    lambda: bounds.w_update_safe_step_along_l(K, INF, 0.1, 0.1, 0.0),
    lambda: bounds.high_probability_v_safe_step(K, 1.0, [1.0], -1.0, 0.0),
    lambda: bounds.rigorous_bound(K, 0.0, 0.1, 0.1),
    lambda: bounds.budget_split_requirement(1.0, 1.5),
    lambda: sepg.Budget(NAN, 0.0),
    lambda: sepg.v_step(K, 0.0, [1.0]),
    lambda: sepg.w_step(K, [-1.0], [0.1]),
    lambda: sepg.confidence_widths([[NAN, 1.0], [1.0, 1.0]]),
    lambda: sepg.confidence_widths([[1.0]]),
    lambda: sepg.confidence_widths([[1.0], [2.0]], delta=1.0),
]


@pytest.mark.parametrize("call", INVALID)
def test_bad_input_raises_one_typed_value_error(call):
    with pytest.raises(ValueError) as info:
        call()
    assert isinstance(info.value, sepg.InvalidInputError)
    assert str(info.value) and "\n" not in str(info.value)


def test_shape_and_type_errors_are_value_errors():
    for call in (
        lambda: sepg.v_step(K, 1.0, "abc"),
        lambda: sepg.v_step(K, 1.0, []),
        lambda: sepg.v_step(K, 1.0, [[1.0]]),
        lambda: sepg.v_step(K, 1.0, [1.0, 2.0], eps=[0.1, 0.2, 0.3]),
        lambda: sepg.v_step(K, 1.0, [1.0], eps=[-0.1]),
        lambda: sepg.w_step(K, [1.0], [0.1, 0.2]),
        lambda: sepg.HighProbabilityBound.v_update(K, 1.0, [1.0], 0.1).safe_step(0.0, "other"),
    ):
        with pytest.raises(sepg.InvalidInputError):
            call()


def test_random_inputs_give_finite_results_or_typed_errors():
    rng = np.random.Generator(np.random.PCG64(20261124))
    for _ in range(300):
        sigma = float(np.exp(rng.uniform(-40, 40)))
        g = rng.standard_normal(3) * np.exp(rng.uniform(-300, 300))
        required = float(rng.standard_normal() * np.exp(rng.uniform(-50, 50)))
        for call in (
            lambda: sepg.v_step(K, sigma, g, eps=abs(g[0]) / 2, required=required),
            lambda: sepg.w_step(K, [sigma], g[:1], g[1:2], eps_j=0.1, eps_l=0.1, required=required),
            lambda: bounds.v_update_safe_step(K, sigma, g, required),
        ):
            try:
                out = call()
            except sepg.InvalidInputError:
                continue
            values = [getattr(out, name) for name in ("size", "delta", "guaranteed", "lam", "lo", "hi", "c_max") if hasattr(out, name)]
            assert all(v is None or math.isfinite(v) for v in values), out
