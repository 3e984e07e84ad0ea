"""exact, estimate and verify of the built-in environments, as the command line."""

import numpy as np
import pytest

import sepg
from sepg import runs

V_STAR = -0.615251245663011  # the optimal gain of lqg1d (README: J(v*) = -7.753206)


def test_exact_values_and_derivatives():
    at_opt = runs.exact("lqg1d", V_STAR, 0.0)
    assert at_opt["j"] == pytest.approx(-7.753206, abs=5e-7)
    assert abs(at_opt["grad_v"]) < 1e-9
    e = runs.exact("lqg", -0.4, 0.6, clipped=True, horizon=20)
    h = 1e-5
    fd_v = (runs.exact("lqg", -0.4 + h, 0.6, clipped=True, horizon=20)["j"]
            - runs.exact("lqg", -0.4 - h, 0.6, clipped=True, horizon=20)["j"]) / (2 * h)
    fd_s = (runs.exact("lqg", -0.4, 0.6 + h, clipped=True, horizon=20)["j"]
            - runs.exact("lqg", -0.4, 0.6 - h, clipped=True, horizon=20)["j"]) / (2 * h)
    assert e["grad_v"] == pytest.approx(fd_v, rel=1e-5)
    assert e["grad_sigma"] == pytest.approx(fd_s, rel=1e-5)
    assert e["grad_w"] == pytest.approx(0.6 * e["grad_sigma"], rel=1e-12)


def test_estimate_brackets_the_exact_value():
    # Two 95% half-widths (about 3.9 standard errors) around the Monte Carlo mean: a false
    # alarm rate near 1e-4 per comparison, here with a fixed seed.
    est = runs.estimate("lqg1d", [-0.3], 0.5, 20, 4000, seed=1)
    exact = runs.exact("lqg1d", -0.3, 0.5, clipped=True, horizon=20)
    for key, truth in (("j", exact["j"]), ("grad_v", exact["grad_v"]), ("grad_w", exact["grad_w"])):
        mean, ci = est[key]
        mean, (lo, hi) = float(np.ravel(mean)[0]), np.ravel(ci)[:2]
        assert abs(mean - truth) <= hi - lo, key  # two half-widths
    assert est["steps"] == 4000 * 20


def test_verify_runs_the_checks_and_reports_expected_outcomes():
    report = runs.verify(quick=True, check="lemma-a")
    assert len(report["results"]) >= 3
    assert all(r["as_expected"] for r in report["results"])
    with pytest.raises(sepg.InvalidInputError, match="no check"):
        runs.verify(check="no-such-check")


@pytest.mark.parametrize(
    "call",
    [
        lambda: runs.exact("mountain-car", 0.0, 1.0),
        lambda: runs.exact("lqg1d", 0.0, -1.0),
        lambda: runs.exact("lqg1d", float("nan"), 1.0),
        lambda: runs.exact("lqg1d", 0.0, 1.0, horizon=0),
        lambda: runs.estimate("lqg1d", [0.0], 1.0, 20, 1),
        lambda: runs.estimate("lqg1d", [0.0, 1.0], 1.0, 20, 10),
        lambda: runs.estimate("nowhere", [0.0], 1.0, 20, 10),
        lambda: runs.estimate("lqg1d", [0.0], 0.0, 20, 10),
    ],
)
def test_bad_input_is_a_value_error(call):
    with pytest.raises(sepg.InvalidInputError):
        call()
