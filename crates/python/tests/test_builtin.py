"""exact, estimate and verify of the built-in environments, as the command line."""

import json
import pathlib
import subprocess

import numpy as np
import pytest

import sepg
from sepg import runs

ROOT = pathlib.Path(__file__).resolve().parents[3]
CLI = ROOT / "target" / "release" / "sepg"
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
    # The deterministic policy has J only.
    det = runs.estimate("lqg1d", [-0.3], 0.0, 20, 100, seed=1)
    assert det["grad_v"] is None and det["grad_w"] is None and det["steps"] == 100 * 20


@pytest.mark.skipif(not CLI.is_file(), reason="the sepg binary is built by `bash scripts/test.sh`")
def test_exact_and_estimate_are_those_of_the_command_line():
    def cli(*args):
        out = subprocess.run([str(CLI), *args, "--json"], check=True, capture_output=True, text=True)
        return json.loads(out.stdout)

    e = cli("exact", "--env", "lqg", "--v", "-0.4", "--sigma", "0.6", "--clipped", "--horizon", "15")
    ours = runs.exact("lqg", -0.4, 0.6, clipped=True, horizon=15)
    assert [ours[k] for k in ("j", "grad_v", "grad_w", "mixed_wv")] == [e[k] for k in ("j", "grad_v", "grad_w", "mixed_wv")]
    m = cli("estimate", "--env", "mountain-car", "--v", "0.1,-0.2,0.3", "--sigma", "0.5",
            "--horizon", "30", "--n", "50", "--seed", "7")
    ours = runs.estimate("mountain-car", [0.1, -0.2, 0.3], 0.5, 30, 50, seed=7)
    assert (ours["j"][0], ours["j"][1]) == (m["j"]["mean"], m["j"]["ci95"])
    assert ours["grad_v"][0].tolist() == m["grad_v"]["mean"]
    assert ours["grad_v"][1].tolist() == m["grad_v"]["ci95"]
    assert ours["steps"] == m["steps"]
    for bad in (["--sigma", "-1"], ["--v", "nan"]):
        flags = {"--env": "lqg1d", "--v": "0", "--sigma": "1", **dict(zip(bad[::2], bad[1::2]))}
        args = [x for kv in flags.items() for x in kv]
        out = subprocess.run([str(CLI), "exact", *args], capture_output=True, text=True)
        with pytest.raises(sepg.InvalidInputError) as err:
            runs.exact("lqg1d", float(flags["--v"]), float(flags["--sigma"]))
        assert out.returncode == 2 and str(err.value) in out.stderr


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
        lambda: runs.estimate("lqg1d", [0.0], -1.0, 20, 10),
        lambda: runs.estimate("lqg1d", [0.0], 1.0, 0, 10),
    ],
)
def test_bad_input_is_a_value_error(call):
    with pytest.raises(sepg.InvalidInputError):
        call()
