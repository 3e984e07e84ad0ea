"""Safely-Exploring Policy Gradient (SEPG) from Python.

- :mod:`sepg.bounds`: every closed-form safety quantity of the thesis (Chapters 3 and 4).
- The safe-step API (:func:`v_step`, :func:`w_step`, :func:`ada_step`,
  :func:`direction_safe_step`, :func:`confidence_widths`, :func:`estimate_block`, :func:`required_improvement`): a training
  loop written with any framework passes its own gradient estimates, per-trajectory samples
  or widths and gets SEPG's safe step sizes, the improvement they guarantee and their flags.
- :mod:`sepg.gym`: SEPG and the comparison algorithms on any gymnasium environment with a
  ``Box`` action space (imported on demand; needs ``gymnasium``).
- :class:`Trainer`: the same algorithms on batches collected by any Python callable.
- :class:`SEPG`: a model object with stable-baselines3's ``learn``/``predict``/``save``/
  ``load`` on a gymnasium environment; :mod:`sepg.callbacks` and :mod:`sepg.logger` serve it
  and :mod:`sepg.gym`.
- :mod:`sepg.runs`: run folders, sweeps (mapped over Dask or Ray), merges and audits of the
  built-in environments, as the command line writes them.

Errors are the classes of :mod:`sepg.errors`; bad input raises
:class:`~sepg.errors.InvalidInputError`, a ``ValueError``. numpy is imported when first
needed, and neither ``typing`` nor ``json`` at import, so that ``import sepg`` stays cheap for
runs of the built-in environments (docs/PYTHON.md, "Speed").
"""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any, Dict, Optional, Sequence, Tuple

from sepg import bounds, errors, runs
from sepg._native import __version__
from sepg._native import (
    _REQUIREMENTS,
    _required_improvement,
    mountain_car_trajectory,
    BatchRequest,
    Budget,
    HighProbabilityBound,
    SafeStep,
    StepOutcome,
    TaskConstants,
    Trainer,
    ada_step,
    confidence_widths,
    direction_safe_step,
    estimate_block,
    v_step,
    w_step,
)
from sepg.errors import InvalidInputError, MissingConstantError, RunFailedError, SepgError


def required_improvement(
    requirement: str,
    *,
    budget: float = 0.0,
    nu: float = 0.5,
    j_initial: Optional[float] = None,
    j_current: Optional[float] = None,
) -> Tuple[float, float]:
    """The required improvements ``(C_v, C_w)`` of the v- and w-updates for a safety
    requirement of Table 4.1, as SEPG (Algorithm 4.3) sets them.

    - ``"mi"`` (monotonic improvement): ``(0, 0)``.
    - ``"lb1"`` (lower-bounded I): C = J(theta^0) - J(theta^t) split ``((1 - nu) C, nu C)``
      (eqs. 4.13, 4.14); needs ``j_initial`` and ``j_current``.
    - ``"lb2"``, ``"lv"``, ``"zv"`` (type II): ``(-B, -B)`` for the budget B (Definition 4.3).
      SEPG updates B between the two updates (Sec 4.4.4): call again with the new budget
      for the w-update.
    - ``"sim"`` (simultaneous updates): ``(-nu B, -(1 - nu) B)``.
    """
    if requirement not in _REQUIREMENTS:
        raise InvalidInputError(
            f"unknown requirement {requirement!r}: expected one of {', '.join(_REQUIREMENTS)}"
        )
    import math

    for name, value in (("budget", budget), ("nu", nu), ("j_initial", j_initial), ("j_current", j_current)):
        if value is not None and (isinstance(value, (bool, str, complex)) or not hasattr(value, "__float__")):
            raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    if not math.isfinite(budget) or budget < 0.0:
        raise InvalidInputError(f"budget = {budget} must be finite and non-negative")
    j_drop = 0.0
    if requirement == "lb1":
        if j_initial is None or j_current is None:
            raise InvalidInputError("requirement lb1 needs j_initial and j_current")
        j_drop = j_initial - j_current
    return _required_improvement(requirement, budget, nu, j_drop)


def records_to_arrays(records: Sequence[Dict[str, Any]]) -> Dict[str, Any]:
    """Per-iteration records (dicts with the columns of ``log.csv``: ``j_explore``,
    ``required``, ...) as one numpy array per field: floats, integers and booleans as typed
    arrays, vectors as 2-D arrays (one row per iteration; the deterministic target's
    ``w_target`` is -inf, as in the file), and fields that are sometimes absent as object
    arrays holding ``None`` where absent (never NaN)."""
    import numpy as np

    if not records:
        return {}
    out: Dict[str, Any] = {}
    for key in records[0]:
        values = [r[key] for r in records]
        if any(v is None for v in values):
            column = np.empty(len(values), dtype=object)
            for i, v in enumerate(values):
                column[i] = None if v is None else (np.asarray(v, dtype=float) if isinstance(v, list) else v)
            out[key] = column
        elif isinstance(values[0], list):
            out[key] = np.asarray(values, dtype=float)
        elif isinstance(values[0], bool):
            out[key] = np.asarray(values, dtype=bool)
        elif isinstance(values[0], int):
            out[key] = np.asarray(values, dtype=np.int64)
        else:
            out[key] = np.asarray(values, dtype=float)
    return out


def _column(key: str, j: int, n: int) -> str:
    """The column of ``log.csv`` for component ``j`` of the vector ``key`` of length ``n``."""
    return key if n == 1 else f"{key}_{j}"


def records_to_pandas(records: Sequence[Dict[str, Any]]) -> Any:
    """The records as a pandas DataFrame (needs pandas) with the columns of ``log.csv``:
    vectors are split into one column per component (``v_0``, ``v_1``, ..., or ``v`` alone for
    one component), absent values are ``pd.NA`` in nullable columns."""
    import numpy as np
    import pandas as pd

    columns: Dict[str, Any] = {}
    for key, column in records_to_arrays(records).items():
        if column.dtype == object:
            first = next((v for v in column if v is not None), None)
            if isinstance(first, np.ndarray):
                for j in range(first.shape[0]):
                    columns[_column(key, j, first.shape[0])] = pd.array(
                        [None if v is None else float(v[j]) for v in column], dtype="Float64"
                    )
            else:
                columns[key] = pd.array(
                    [None if v is None else float(v) for v in column], dtype="Float64"
                )
        elif column.ndim == 2:
            for j in range(column.shape[1]):
                columns[_column(key, j, column.shape[1])] = column[:, j]
        else:
            columns[key] = column
    return pd.DataFrame(columns)


def __getattr__(name: str) -> Any:
    # sepg.SEPG needs numpy and gymnasium: imported when first used, so that ``import sepg``
    # stays cheap
    if name == "SEPG":
        from sepg.model import SEPG

        return SEPG
    raise AttributeError(f"module 'sepg' has no attribute {name!r}")


__all__ = [
    "BatchRequest",
    "Budget",
    "HighProbabilityBound",
    "InvalidInputError",
    "MissingConstantError",
    "RunFailedError",
    "SEPG",
    "SafeStep",
    "SepgError",
    "StepOutcome",
    "TaskConstants",
    "Trainer",
    "ada_step",
    "bounds",
    "confidence_widths",
    "direction_safe_step",
    "errors",
    "estimate_block",
    "mountain_car_trajectory",
    "records_to_arrays",
    "records_to_pandas",
    "required_improvement",
    "runs",
    "v_step",
    "w_step",
    "__version__",
]
