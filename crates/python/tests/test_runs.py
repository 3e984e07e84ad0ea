"""Run folders, sweeps (local, and mapped over Dask's synchronous scheduler or a local Ray
instance), merges and audits from Python: the same folders as the command line, byte for
byte."""

import json
import pathlib
import subprocess

import numpy as np
import pytest

import sepg
from sepg import runs

ROOT = pathlib.Path(__file__).resolve().parents[3]
CLI = ROOT / "target" / "release" / "sepg"

SWEEP = {
    "presets": ["lqg", "lqg1d"],
    "seeds": [3, 4],
    "sigma0": [0.5, 1.0],
    "base": {"iterations": 6, "batch": 24},
    "variant": [
        {"name": "zv", "algo": "sepg-zv"},
        {"name": "adam", "algo": "gpomdp-adam", "lr": 1e-3, "lr_w": 1e-3},
    ],
}


WALL_CLOCK = {
    "summary.json": ("wall_time_s", "iterations_per_s", "env_steps_per_s"),
    "checkpoint.json": ("elapsed_s",),
}


def files(folder):
    """Every file of a run or sweep folder, as bytes, but the wall-clock figures of the
    summaries and checkpoints (compared as the rest of their JSON)."""
    out = {}
    for p in sorted(pathlib.Path(folder).rglob("*")):
        if p.is_file():
            rel = str(p.relative_to(folder))
            if p.name in WALL_CLOCK:
                s = json.loads(p.read_text())
                for key in WALL_CLOCK[p.name]:
                    s.pop(key)
                out[rel] = s
            else:
                out[rel] = p.read_bytes()
    return out


def test_run_read_resume_and_audit(tmp_path):
    summary = runs.run(tmp_path / "r", env="lqg1d", algo="sepg-mi", gradients="exact",
                       iterations=8, sigma0=0.5)
    assert summary["status"] == "complete" and summary["iterations"] == 8
    folder = runs.read_run(tmp_path / "r")
    assert folder.complete and folder.config["algo"] == "sepg-mi"
    assert folder.log["iteration"].tolist() == list(range(8))
    assert folder.log["v"].dtype == float and np.all(np.isfinite(folder.log["v"]))
    assert folder.log["below_noise_v"].dtype == bool
    assert folder.summary["final"]["v"] != [folder.log["v"][0]]
    # A complete run resumes to itself; an exact-gradient MI run's audit finds no failure and
    # follows the statement the run recorded.
    assert runs.resume(tmp_path / "r")["final"] == summary["final"]
    report = runs.audit(tmp_path / "r")
    expected = {"proven": "holds", "approximate": "approximate", "none": "no-guarantee"}
    assert report["checks"] and report["failures"] == []
    assert report["verdict"] == expected[summary["statement"]["kind"]]


def test_a_run_returns_its_summary_file_as_a_dict(tmp_path):
    # The options are converted without Python's json module: numpy scalars are numbers.
    summary = runs.run(tmp_path / "r", env="lqg1d", algo="sepg-zv", iterations=3, batch=12,
                       sigma0=np.float64(0.5), seed=np.int64(2))
    assert summary == json.loads((tmp_path / "r" / "summary.json").read_text())
    assert type(summary["iterations"]) is int and type(summary["final"]["v"][0]) is float
    folder = runs.read_run(tmp_path / "r")
    assert folder.summary == summary and folder.config["seed"] == 2 and folder.config["sigma0"] == 0.5
    with pytest.raises(sepg.InvalidInputError, match="finite"):
        runs.run(tmp_path / "a", env="lqg1d", iterations=2, sigma0=float("nan"))
    with pytest.raises(sepg.InvalidInputError, match="unsupported"):
        runs.run(tmp_path / "a", env=object())
    with pytest.raises(sepg.InvalidInputError, match="64-bit"):
        runs.run(tmp_path / "a", env="lqg1d", seed=2**64)


def test_run_options_and_folders_are_checked(tmp_path):
    with pytest.raises(sepg.InvalidInputError, match="unknown field"):
        runs.run(tmp_path / "a", env="lqg1d", iterations=2, batch_size=30)
    with pytest.raises(sepg.InvalidInputError):
        runs.run(tmp_path / "a", env="lqg1d", iterations=0)
    runs.run(tmp_path / "b", env="lqg1d", iterations=2, batch=12)
    with pytest.raises(sepg.InvalidInputError, match="not empty"):
        runs.run(tmp_path / "b", env="lqg1d", iterations=2, batch=12)
    with pytest.raises(sepg.InvalidInputError, match="not a run folder"):
        runs.read_run(tmp_path)
    with pytest.raises(sepg.InvalidInputError):
        runs.audit(tmp_path / "b", tolerance=float("nan"))


@pytest.mark.skipif(not CLI.is_file(), reason="the sepg binary is built by `bash scripts/test.sh`")
def test_python_and_command_line_write_the_same_run_folder(tmp_path):
    args = dict(env="mountain-car", algo="sepg-lv", iterations=3, batch=12, horizon=50, seed=7)
    runs.run(tmp_path / "py", **args)
    flags = [x for k, v in args.items() for x in (f"--{k}", str(v))]
    subprocess.run([str(CLI), "run", "--quiet", "--out", str(tmp_path / "cli"), *flags], check=True)
    assert files(tmp_path / "py") == files(tmp_path / "cli")


@pytest.mark.skipif(not CLI.is_file(), reason="the sepg binary is built by `bash scripts/test.sh`")
def test_the_adaptive_batch_rule_runs_from_python_as_from_the_command_line(tmp_path):
    args = dict(env="lqg1d", algo="sepg-mi", iterations=4, batch=100, seed=3,
                batch_rule="adaptive", batch_min=60, batch_max=400)
    runs.run(tmp_path / "py", **args)
    flags = [x for k, v in args.items() for x in (f"--{k.replace('_', '-')}", str(v))]
    subprocess.run([str(CLI), "run", "--quiet", "--out", str(tmp_path / "cli"), *flags], check=True)
    assert files(tmp_path / "py") == files(tmp_path / "cli")
    log = runs.read_run(tmp_path / "py").log
    # At v0 = -0.1, sigma = 1 the proven v-width of a 50-trajectory block is about 23 times
    # |dJ/dv|, so the rule's n* = 4 b^2 / g^2 (about 1e5, docs/REPRODUCTION.md) is clamped to
    # batch_max: after the first iteration (N = 100), two blocks of 400 per iteration.
    per_iteration = np.diff(np.asarray(log["trajectories"]))
    assert list(per_iteration) == [800, 800, 800]


def test_a_dask_sweep_equals_the_local_sweep_byte_for_byte(tmp_path):
    dask = pytest.importorskip("dask")
    local = runs.sweep(SWEEP, tmp_path / "local", engine="local")
    assert len(local["runs"]) == 16
    with dask.config.set(scheduler="synchronous"):
        mapped = runs.sweep(SWEEP, tmp_path / "dask", engine="dask")
        shards = [runs.sweep(SWEEP, tmp_path / f"s{i}", shard=f"{i}/3", engine="dask") for i in range(3)]
    assert mapped == local
    assert files(tmp_path / "dask") == files(tmp_path / "local")
    merged = runs.merge([tmp_path / f"s{i}" for i in range(3)], tmp_path / "merged")
    assert merged["sweep_id"] == local["sweep_id"] and merged["merged_from"] == 3
    a, b = files(tmp_path / "merged"), files(tmp_path / "local")
    assert a.pop("sweep.json") != b.pop("sweep.json")  # merged_from differs, nothing else
    assert a == b


def test_a_ray_sweep_equals_the_local_sweep_byte_for_byte(tmp_path):
    # Ray is an optional dependency that `bash scripts/test.sh` installs only with
    # SEPG_TEST_RAY=1 (docs/PYTHON.md). Ray has no local mode any more: the test starts a
    # one-CPU local instance, whose worker processes import sepg and run the tasks.
    ray = pytest.importorskip("ray", reason="Ray is not installed (SEPG_TEST_RAY=1 bash scripts/test.sh installs it)")
    local = runs.sweep(SWEEP, tmp_path / "local", engine="local")
    started = not ray.is_initialized()
    if started:
        ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        assert runs._engine("auto") == "ray"
        mapped = runs.sweep(SWEEP, tmp_path / "ray", engine="ray")
        shard = runs.sweep(SWEEP, tmp_path / "s1", shard="1/2", engine="ray")
    finally:
        if started:
            ray.shutdown()
    assert mapped == local
    assert files(tmp_path / "ray") == files(tmp_path / "local")
    # Shard 1/2 holds the runs of odd index, the same bytes as in the local sweep.
    odd = [r["dir"] + "/" for r in local["runs"] if r["index"] % 2 == 1]
    want, got = files(tmp_path / "local"), files(tmp_path / "s1")
    got_runs = {k: v for k, v in got.items() if k.startswith("runs/")}
    assert odd and set(got_runs) == {k for k in want if k.startswith(tuple(odd))}
    assert all(want[k] == v for k, v in got_runs.items())


def test_a_sweep_summary_is_written_only_when_every_run_is_complete(tmp_path):
    from sepg import _native

    indices = _native.sweep_prepare(str(tmp_path / "p"), runs._spec_json(SWEEP))
    _native.sweep_run(str(tmp_path / "p"), indices[0])
    with pytest.raises(sepg.InvalidInputError, match="not complete"):
        _native.sweep_finish(str(tmp_path / "p"))
    assert not (tmp_path / "p" / "summary.csv").exists()


def test_sweep_errors_are_value_errors(tmp_path):
    with pytest.raises(sepg.InvalidInputError):
        runs.sweep({**SWEEP, "presets": ["nowhere"]}, tmp_path / "x", engine="local")
    with pytest.raises(sepg.InvalidInputError):
        runs.sweep(SWEEP, tmp_path / "x", shard="3/3", engine="local")
    with pytest.raises(sepg.InvalidInputError, match="engine"):
        runs.sweep(SWEEP, tmp_path / "x", engine="spark")
