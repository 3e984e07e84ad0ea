"""Runs of the built-in environments (``lqg``, ``lqg1d``, ``lqg-nd``, ``mountain-car``) from
Python, through the library behind ``sepg run``, ``sepg sweep``, ``sepg merge`` and
``sepg audit``: the same run folders, byte for byte, and the same options (the flags of
``sepg run`` with ``_`` for ``-``: ``env``, ``algo``, ``iterations``, ``batch``, ``horizon``,
``seed``, ``sigma0``, ``v0``, ``delta``, ``nu``, ``gradients``, ``lr``, ``lr_w``, ...).

:func:`exact`, :func:`estimate` and :func:`verify` are ``sepg exact``, ``sepg estimate`` and
``sepg verify``.

A sweep maps its runs over Dask or Ray when asked (``engine="dask"``/``"ray"``) or, with
``engine="auto"``, when Ray is initialised or Dask is installed. Every run is the same
deterministic unit wherever it runs, so the folder is byte-identical to a sweep run on one
machine (wall-clock figures in ``summary.json`` aside).
"""

from __future__ import annotations

import os

from sepg import _native
from sepg.errors import InvalidInputError

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any, Dict, List, Optional, Sequence, Union

    PathLike = Union[str, "os.PathLike[str]"]


def _kebab(options: Dict[str, Any]) -> Dict[str, Any]:
    return {key.replace("_", "-"): value for key, value in options.items()}


def _spec_json(spec: Union[PathLike, Dict[str, Any]]) -> str:
    if isinstance(spec, dict):
        import json

        out = _kebab(spec)
        if isinstance(out.get("base"), dict):
            out["base"] = _kebab(out["base"])
        if isinstance(out.get("variant"), list):
            out["variant"] = [_kebab(v) if isinstance(v, dict) else v for v in out["variant"]]
        return json.dumps(out)
    return _native.read_sweep_file(os.fspath(spec))


def run(
    out: PathLike,
    *,
    config: Optional[PathLike] = None,
    force: bool = False,
    checkpoint_every: int = 500,
    **options: Any,
) -> Dict[str, Any]:
    """Runs SEPG or a comparison algorithm on a built-in environment into the run folder
    ``out`` (``config.toml``, ``log.csv``, ``checkpoint.json``, ``summary.json``), as
    ``sepg run --out out`` with the same options; ``config`` is a TOML file of options that
    ``options`` override. Returns the summary. Ctrl-C stops the run after checkpointing
    (resume it with :func:`resume`)."""
    return _native.run_folder(
        os.fspath(out),
        _kebab(options),
        None if config is None else os.fspath(config),
        force,
        checkpoint_every,
    )


def resume(dir: PathLike, *, checkpoint_every: int = 500) -> Dict[str, Any]:
    """Resumes the run folder ``dir`` from its checkpoint, bit for bit; returns the summary."""
    return _native.resume_folder(os.fspath(dir), checkpoint_every)


class RunFolder:
    """A run folder read back: ``config`` (the resolved options), ``log`` (one numpy array
    per column of ``log.csv``; a column with empty cells, "not applicable", is an object
    array holding ``None`` there; the deterministic target's ``w_target`` is ``-inf``),
    ``summary`` (``None`` while incomplete) and ``complete``."""

    def __init__(self, dir: PathLike) -> None:
        import numpy as np

        config, columns, rows, summary = _native.read_folder(os.fspath(dir))
        self.dir = os.fspath(dir)
        self.config: Dict[str, Any] = config
        self.summary: Optional[Dict[str, Any]] = summary
        self.complete = self.summary is not None
        self.columns: List[str] = list(columns)
        self.log: Dict[str, Any] = {}
        for j, name in enumerate(columns):
            values = [row[j] for row in rows]
            if any(v is None for v in values):
                column = np.empty(len(values), dtype=object)
                column[:] = values
            elif name in _INTEGER_COLUMNS:
                column = np.asarray(values, dtype=np.int64)
            elif name in _FLAG_COLUMNS:
                column = np.asarray(values, dtype=float) != 0.0
            else:
                column = np.asarray(values, dtype=float)
            self.log[name] = column

    def to_pandas(self) -> Any:
        """The log as a pandas DataFrame (needs pandas); absent values are ``pd.NA``."""
        import pandas as pd

        data = {}
        for name, column in self.log.items():
            if column.dtype == object:
                data[name] = pd.array(list(column), dtype="Float64")
            else:
                data[name] = column
        return pd.DataFrame(data)


_INTEGER_COLUMNS = {"iteration", "trajectories", "steps"}
_FLAG_COLUMNS = {"infeasible", "infeasible_v", "infeasible_w", "below_noise_v", "below_noise_w"}


def read_run(dir: PathLike) -> RunFolder:
    """Reads the run folder ``dir`` (complete, or the checkpointed part of an incomplete run)."""
    return RunFolder(dir)


def _engine(engine: str) -> str:
    if engine not in ("auto", "local", "dask", "ray"):
        raise InvalidInputError(f"engine must be auto, local, dask or ray, got {engine!r}")
    if engine != "auto":
        return engine
    try:
        import ray

        if ray.is_initialized():
            return "ray"
    except ImportError:
        pass
    try:
        import dask  # noqa: F401

        return "dask"
    except ImportError:
        return "local"


def _sweep_run(out: str, index: int, checkpoint_every: int) -> str:
    """Run ``index`` of the sweep folder ``out``: the task that Dask or Ray map (a Python
    function, which Ray's ``remote`` needs and a worker process imports by name)."""
    return os.fspath(_native.sweep_run(out, index, checkpoint_every))


def sweep(
    spec: Union[PathLike, Dict[str, Any]],
    out: PathLike,
    *,
    shard: Optional[str] = None,
    force: bool = False,
    engine: str = "auto",
    checkpoint_every: int = 2000,
) -> Dict[str, Any]:
    """Runs a sweep (a sweep file's path, or a dict with its keys ``presets``, ``seeds``,
    ``sigma0``, ``base``, ``variant``) into the sweep folder ``out``, optionally only shard
    ``"I/N"``, as ``sepg sweep``. ``engine``: ``"local"`` (threads of this process),
    ``"dask"`` (``dask.delayed`` on the current Dask scheduler or client), ``"ray"``
    (``ray.remote`` tasks; Ray must be initialised), or ``"auto"`` (Ray if initialised, else
    Dask if installed, else local). Returns ``sweep.json``."""
    text = _spec_json(spec)
    out = os.fspath(out)
    chosen = _engine(engine)
    if chosen == "local":
        return _native.sweep_folder(out, text, shard, force, checkpoint_every)
    indices = _native.sweep_prepare(out, text, shard, force)
    if chosen == "dask":
        import dask

        dask.compute(*[dask.delayed(_sweep_run)(out, i, checkpoint_every) for i in indices])
    else:
        import ray

        task = ray.remote(_sweep_run)
        ray.get([task.remote(out, i, checkpoint_every) for i in indices])
    return _native.sweep_finish(out)


def merge(shards: Sequence[PathLike], out: PathLike, *, force: bool = False) -> Dict[str, Any]:
    """Merges the complete shard folders of one sweep into ``out``, as ``sepg merge``."""
    return _native.merge_folders([os.fspath(s) for s in shards], os.fspath(out), force)


def audit(dir: PathLike, *, tolerance: float = 1e-12, alpha: float = 0.01) -> Dict[str, Any]:
    """Re-checks the run folder's log against exactly what its statement promises, as
    ``sepg audit``: the report has each check with its failures and a ``verdict`` (``holds``,
    ``broken``, ``approximate``, ``no-guarantee``, ``not-checked``, ``incomplete``);
    ``tolerance`` is relative to max(1, |J|), ``alpha`` the family-wise level of the tests."""
    return _native.audit_folder(os.fspath(dir), tolerance, alpha)


def verify(*, quick: bool = True, check: Optional[str] = None, seed: int = 0) -> Dict[str, Any]:
    """Runs the numerical checks of the thesis's statements, as ``sepg verify``: every check,
    or those whose identifier contains ``check``; ``quick`` is the CI subset. Returns the
    report; ``report["results"][i]["as_expected"]`` says whether each outcome is the one
    recorded."""
    return _native.verify(quick, check, seed)


exact = _native.exact
estimate = _native.estimate

__all__ = ["RunFolder", "audit", "estimate", "exact", "merge", "read_run", "resume", "run", "sweep", "verify"]
