"""The conventions users of gymnasium and stable-baselines3 rely on: the version, explicit
keyword arguments, the names of log.csv and config.toml in records and summaries, progress
bars, callbacks, the CSV and TensorBoard logger, and the model's learn/predict/save/load."""

import csv
import glob
import inspect
import json
import math
import pathlib
import re
import struct
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import sepg
from sepg import gym as sg
from sepg import runs
from sepg.callbacks import BaseCallback
from sepg.logger import Logger

ROOT = pathlib.Path(__file__).resolve().parents[3]
MCC = "MountainCarContinuous-v0"
PENDULUM = dict(gamma=0.9, r_max=16.2736, n_trajectories=12, horizon=20, reference_batch=24,
                show_derivation=False)


def pendulum_run(**kw):
    args = dict(PENDULUM)
    args.update(kw)
    return sg.GymRun("Pendulum-v1", **args)


def one_feature_run(**kw):
    # one action and one feature (the position), so that log.csv has the columns of a
    # one-dimensional built-in run
    args = dict(gamma=0.99, r_max=100.0, m_phi=1.2, n_trajectories=12, horizon=30,
                reference_batch=24, show_derivation=False)
    args.update(kw)
    return sg.GymRun(MCC, lambda s: [s[0]], **args)


# --- version and signatures -------------------------------------------------------------


def test_version_is_the_crate_version():
    cargo = (ROOT / "Cargo.toml").read_text()
    workspace = cargo[cargo.index("[workspace.package]"):]
    expected = re.search(r'^version = "([^"]+)"', workspace, re.M).group(1)
    assert sepg.__version__ == expected


def test_train_and_gymrun_take_explicit_keywords():
    for f in (sg.train, sg.GymRun.__init__, sepg.SEPG.__init__):
        params = inspect.signature(f).parameters
        assert not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()), f
    params = inspect.signature(sg.train).parameters
    for name in ("gamma", "n_trajectories", "nu", "requirement", "alpha", "lr", "reference_batch",
                 "accounting", "v_direction", "adam_lr", "callback", "progress_bar", "logger"):
        assert name in params, name
    with pytest.raises(TypeError, match="unexpected keyword argument 'n_traj'"):
        sg.train(MCC, iterations=1, gamma=0.9, n_traj=5)


# --- names of log.csv and config.toml ---------------------------------------------------


def cli_header(tmp_path):
    """The header of log.csv of a one-dimensional run of the command line's library."""
    runs.run(tmp_path / "cli", env="lqg1d", algo="sepg-zv", iterations=1, batch=12)
    return (tmp_path / "cli" / "log.csv").read_text().splitlines()[0].split(",")


def test_records_and_dataframes_use_the_columns_of_log_csv(tmp_path):
    header = cli_header(tmp_path)
    run = one_feature_run()
    arrays = run.run(2)
    assert list(run.records[0]) == header
    assert "j_explore" in arrays and "required" in arrays and "j_exploratory" not in arrays
    pd = pytest.importorskip("pandas")
    assert list(run.to_pandas().columns) == header
    # ZV's target is deterministic: w_target is -inf, as in the file, in records and arrays
    assert run.records[0]["w_target"] == [-math.inf]
    assert arrays["w_target"].dtype == float and np.all(arrays["w_target"] == -math.inf)
    assert pd is not None


def test_pendulum_dataframe_splits_vectors_as_log_csv():
    run = pendulum_run()
    run.run(1)
    pytest.importorskip("pandas")
    columns = list(run.to_pandas().columns)
    assert columns[:8] == ["iteration", "v_0", "v_1", "v_2", "w", "sigma", "j_explore", "j_after_v"]
    assert columns[8:11] == ["j_target", "w_target", "budget"]


OLD_OPTIONS = {
    "w_step": "Exploring", "w_direction": "CrossFitted", "confidence": {"StudentT": {"factor": 2.0}},
    "lb1_requirement": "Split", "alternating": False, "reference_batch": 1000,
    "overrides": {"gamma": None, "r_max": None, "m_phi": None, "action_volume": None, "psi": None},
    "accounting": "Certified", "schedule": "Run", "constants": {"Tight": {"rewards": "NonPositive"}},
}


def test_summary_json_names_options_as_config_toml(tmp_path):
    summary = runs.run(tmp_path / "r", env="lqg1d", algo="sepg-zv", iterations=2, batch=12,
                       confidence="student-t", w_direction="plug-in", w_step="theorem-4.9")
    config = (tmp_path / "r" / "config.toml").read_text()
    options = summary["options"]
    assert 'w-direction = "plug-in"' in config and options["w_direction"] == "plug-in"
    assert 'w-step = "theorem-4.9"' in config and options["w_step"] == "theorem-4.9"
    assert 'confidence = "student-t"' in config and list(options["confidence"]) == ["student-t"]
    assert 'rewards = "non-positive"' in config
    assert options["constants"] == {"tight": {"rewards": "non-positive"}}
    assert (options["accounting"], options["schedule"], options["lb1_requirement"]) == (
        "certified", "run", "split")
    on_disk = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert on_disk["options"] == options


def test_old_summaries_with_pascal_case_options_still_read_audit_and_resume(tmp_path):
    summary = runs.run(tmp_path / "r", env="lqg1d", algo="sepg-mi", gradients="exact",
                       iterations=4, sigma0=0.5)
    path = tmp_path / "r" / "summary.json"
    old = json.loads(path.read_text())
    old["options"] = dict(OLD_OPTIONS, confidence="SubGaussian", constants="Thesis")
    old["options"]["constants"] = {"Tight": {"rewards": "NonPositive"}}
    path.write_text(json.dumps(old, indent=2))
    folder = runs.read_run(tmp_path / "r")
    assert folder.summary["options"]["w_direction"] == "cross-fitted"
    assert folder.summary["options"]["constants"] == {"tight": {"rewards": "non-positive"}}
    assert runs.resume(tmp_path / "r")["final"] == summary["final"]
    report = runs.audit(tmp_path / "r")
    assert report["checks"] and report["failures"] == []


# --- progress bar -----------------------------------------------------------------------


def test_progress_bar_on_request_off_by_default_without_a_terminal(capsys, monkeypatch):
    pytest.importorskip("tqdm")
    run = one_feature_run()
    run.run(3, progress_bar=True)
    err = capsys.readouterr().err
    assert "3/3" in err and "sepg-zv on MountainCarContinuous-v0" in err
    run.run(2)  # pytest's captured stderr is not a terminal: no bar
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    run.run(1)
    assert "1/1" in capsys.readouterr().err
    run.run(1, progress_bar=False)
    assert capsys.readouterr().err == ""


def test_total_timesteps_bar_counts_environment_steps(capsys):
    pytest.importorskip("tqdm")
    run = one_feature_run(reference_batch=0)
    run.run(total_timesteps=500, progress_bar=True)
    steps = [r["steps"] for r in run.records]
    # the run stops at the first iteration that reaches 500 more steps
    assert steps[-1] >= 500 and (len(steps) == 1 or steps[-2] < 500)
    assert "500/500" in capsys.readouterr().err


def test_without_tqdm_no_bar_and_one_warning(monkeypatch, capsys):
    import sepg._progress as progress

    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setattr(progress, "_warned", False)
    run = one_feature_run()
    with pytest.warns(UserWarning, match="tqdm is not installed"):
        run.run(1, progress_bar=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run.run(1, progress_bar=True)
    assert capsys.readouterr().err == ""
    assert len(run.records) == 2


# --- callbacks ----------------------------------------------------------------------------


def test_a_callable_sees_every_record_and_false_stops_cleanly():
    seen = []

    def stop_at_second(record):
        seen.append(record)
        return False if record["iteration"] == 1 else None

    stopped = pendulum_run()
    stopped.run(5, callback=stop_at_second)
    assert [r["iteration"] for r in stopped.records] == [0, 1]
    assert seen == stopped.records
    stopped.run(1)
    uninterrupted = pendulum_run()
    uninterrupted.run(3)
    assert stopped.records == uninterrupted.records
    assert stopped.state == uninterrupted.state


class Counting(BaseCallback):
    def __init__(self, stop_after):
        super().__init__()
        self.stop_after = stop_after
        self.events = []

    def _on_training_start(self):
        self.events.append("start")

    def _on_step(self, record):
        self.events.append(record["iteration"])
        return self.n_calls < self.stop_after

    def _on_training_end(self):
        self.events.append("end")


class Plain:
    """Not a BaseCallback: only the hooks' names."""

    def __init__(self):
        self.steps = []
        self.run = None

    def on_training_start(self, run):
        self.run = run

    def on_step(self, record):
        self.steps.append(record["steps"])
        return True


def test_callback_objects_and_lists():
    a, b = Counting(stop_after=2), Plain()
    run = pendulum_run()
    run.run(4, callback=[a, b])
    assert a.events == ["start", 0, 1, "end"]
    assert b.run is run and b.steps == [r["steps"] for r in run.records]
    assert a.num_timesteps == run.records[-1]["steps"] and a.n_calls == 2
    with pytest.raises(sepg.InvalidInputError, match="callback must be"):
        run.run(1, callback=3)


# --- logger -----------------------------------------------------------------------------


def cell(value):
    """The value of a record that a cell of log.csv stands for, compared exactly: empty for
    None, 0/1 for flags, integers as integers, and every float read back bit for bit."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int):
        return str(value)
    return float(value)


def parse(text):
    """A cell of log.csv: integers and empty cells as text, floats as floats."""
    return text if text == "" or re.fullmatch(r"-?[0-9]+", text) else float(text)


def test_logger_writes_log_csv_as_the_command_line(tmp_path):
    header = cli_header(tmp_path)
    run = one_feature_run()
    with Logger(tmp_path / "gym") as logger:
        run.run(3, logger=logger)
    rows = list(csv.reader((tmp_path / "gym" / "log.csv").read_text().splitlines()))
    assert rows[0] == header
    assert len(rows) == 4
    for row, record in zip(rows[1:], run.records):
        expected = [cell(v[0]) if isinstance(v, list) else cell(v) for v in record.values()]
        got = [parse(c) for c in row]
        assert [type(x) for x in got] == [type(x) for x in expected]
        assert got == expected
        assert "-inf" in row  # the deterministic target's w_target


def read_events(folder):
    """(tag, step) -> value of every scalar of the TensorBoard event files in ``folder``,
    read as TFRecords (length, CRC, data, CRC) of Event protos."""
    from tensorboardX.proto import event_pb2

    values = {}
    for path in glob.glob(str(folder / "events.out.tfevents.*")):
        data = pathlib.Path(path).read_bytes()
        i = 0
        while i < len(data):
            (n,) = struct.unpack("<Q", data[i:i + 8])
            event = event_pb2.Event.FromString(data[i + 12:i + 12 + n])
            i += 12 + n + 4
            for v in event.summary.value:
                values[(v.tag, event.step)] = v.simple_value
    return values


def test_logger_writes_tensorboard_scalars_equal_to_the_records(tmp_path):
    pytest.importorskip("tensorboardX")
    run = pendulum_run()
    with Logger(tmp_path / "tb", csv=False, tensorboard=True) as logger:
        run.run(2, logger=logger)
    assert not (tmp_path / "tb" / "log.csv").exists()
    values = read_events(tmp_path / "tb")
    expected = {}
    for r in run.records:
        for key, value in r.items():
            if key == "iteration" or value is None:
                continue
            items = [(f"{key}_{j}" if len(value) > 1 else key, x) for j, x in enumerate(value)] \
                if isinstance(value, list) else [(key, value)]
            for name, x in items:
                expected[(f"sepg/{name}", r["iteration"])] = float(np.float32(float(x)))
    assert ("sepg/j_explore", 1) in expected and ("sepg/v_2", 0) in expected
    assert values == expected


# --- the model ------------------------------------------------------------------------------


def model(**kw):
    args = dict(PENDULUM, seed=5)
    args.update(kw)
    return sepg.SEPG("Pendulum-v1", **args)


def test_predict_is_the_mean_or_a_seeded_sample():
    m = model()
    m.learn(2)
    obs = np.array([0.6, -0.8, 1.5])
    mean = m.run.mean @ obs
    action, state = m.predict(obs)
    assert state is None and np.array_equal(action, mean)
    batch, _ = m.predict(np.stack([obs, -obs]))
    assert batch.shape == (2, 1) and np.array_equal(batch[1], m.run.mean @ -obs)
    z = np.random.default_rng(5).standard_normal(1)
    sampled, _ = m.predict(obs, deterministic=False)
    assert np.array_equal(sampled, mean + m.run.sigma * z)


def test_save_load_round_trips_bit_for_bit(tmp_path):
    saved = model()
    saved.learn(2)
    saved.predict(np.zeros(3), deterministic=False)
    saved.save(tmp_path / "m.json")
    loaded = sepg.SEPG.load(tmp_path / "m.json")
    assert loaded.run.state == saved.run.state
    assert np.array_equal(loaded.run.mean, saved.run.mean)
    assert np.array_equal(loaded.run.sigma, saved.run.sigma)
    obs = np.array([0.1, 0.99, -3.0])
    for deterministic in (True, False, False):
        a, _ = loaded.predict(obs, deterministic=deterministic)
        b, _ = saved.predict(obs, deterministic=deterministic)
        assert np.array_equal(a, b)
    loaded.learn(2)
    saved.learn(2)
    never = model()
    never.learn(4)
    assert loaded.records == saved.records[2:] == never.records[2:]
    assert loaded.run.state == never.run.state


def test_learn_total_timesteps_and_load_errors(tmp_path):
    m = model()
    m.learn(total_timesteps=600)
    # reference batches (2 x 24 trajectories of 20 steps) and 12 per iteration
    assert m.num_timesteps >= 600
    m.save(tmp_path / "m.json")
    custom = sepg.SEPG("Pendulum-v1", lambda s: s[:2], m_phi=1.0, **PENDULUM)
    custom.save(tmp_path / "c.json")
    with pytest.raises(sepg.InvalidInputError, match="pass features="):
        sepg.SEPG.load(tmp_path / "c.json")
    assert sepg.SEPG.load(tmp_path / "c.json", features=lambda s: s[:2]).run.n_features == 2
    with pytest.raises(sepg.InvalidInputError, match="unknown requirement 'naive-w'"):
        model(requirement="naive-w")
    (tmp_path / "x.json").write_text('{"format": "other"}')
    with pytest.raises(sepg.InvalidInputError, match="not a saved sepg model"):
        sepg.SEPG.load(tmp_path / "x.json")


# --- error messages -------------------------------------------------------------------------


def test_nan_features_are_reported_as_features():
    run = pendulum_run(features=lambda s: np.array([s[0], np.nan, s[2]]), m_phi=8.0)
    with pytest.raises(sepg.InvalidInputError, match="features must be finite"):
        run.run(1)


def test_trainer_collector_nan_features_are_named():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 4.0)

    def collector(req):
        n, h = req.n, 3
        return (np.full((n, h), np.nan), np.zeros((n, h, 1)), np.full((n, h, 1), np.nan),
                np.full(n, h))

    trainer = sepg.Trainer("sepg-mi", k, 1, 1, collector, n_trajectories=10)
    with pytest.raises(sepg.InvalidInputError, match="features must be finite"):
        trainer.run(1)


def test_unknown_trainer_keyword_names_the_class_not_new():
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 4.0)
    with pytest.raises(TypeError) as info:
        sepg.Trainer("sepg-mi", k, 1, 1, lambda r: None, n_trajectory=10)
    message = str(info.value)
    assert "__new__" not in message
    assert "Trainer() got an unexpected keyword argument n_trajectory" in message
    assert "n_trajectories" in message


@pytest.mark.parametrize("bad", [np.array([1.0 + 2.0j, 0.5]), ["0.5", "1"], [True, False]])
def test_complex_string_and_boolean_arrays_are_refused(bad):
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 4.0)
    with pytest.raises(sepg.InvalidInputError, match="grad_v must be an array of real numbers"):
        sepg.v_step(k, 1.0, bad)


def test_scalar_arguments_of_the_wrong_type_name_the_argument():
    # str(e), not only the note pyo3 attaches (which pytest's match would also search)
    k = sepg.TaskConstants(0.9, 1.0, 1.0, 4.0)
    cases = [
        ("gamma", lambda: sepg.TaskConstants(gamma="0.9", r_max=1.0, m_phi=1.0, action_volume=1.0)),
        ("action_volume", lambda: sepg.TaskConstants(0.9, 1.0, 1.0, 2j)),
        ("psi", lambda: k.with_psi("0.5")),
        ("seed", lambda: sepg.Trainer("sepg-mi", k, 1, 1, print, seed=1.5)),
        ("delta", lambda: sepg.Trainer("sepg-mi", k, 1, 1, print, delta="0.2")),
        ("budget", lambda: sepg.required_improvement("zv", budget="1")),
        ("nu", lambda: sepg.required_improvement("sim", nu="0.5")),
    ]
    for name, call in cases:
        with pytest.raises(TypeError) as info:
            call()
        assert str(info.value).startswith(f"{name} must be"), str(info.value)
    with pytest.raises(sepg.InvalidInputError, match="^seed = -1 must be a non-negative integer"):
        sepg.Trainer("sepg-mi", k, 1, 1, print, seed=-1)


def test_gym_arguments_are_not_converted_silently():
    with pytest.raises(sepg.InvalidInputError, match="sigma0 must be an array of real numbers"):
        pendulum_run(sigma0="1")
    with pytest.raises(sepg.InvalidInputError, match="horizon must be a positive integer"):
        pendulum_run(horizon=True)
    assert pendulum_run(horizon=np.int64(7)).collector.horizon == 7


def test_a_model_logs_to_its_logger(tmp_path):
    m = model()
    with Logger(tmp_path / "log") as logger:
        m.set_logger(logger)
        m.learn(2)
    lines = (tmp_path / "log" / "log.csv").read_text().splitlines()
    assert len(lines) == 3 and lines[0].startswith("iteration,v_0,v_1,v_2,w,sigma,j_explore,")
    assert [int(line.split(",")[0]) for line in lines[1:]] == [r["iteration"] for r in m.records]
