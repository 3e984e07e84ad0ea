"""A logger of the records of :meth:`sepg.gym.GymRun.run` and :meth:`sepg.SEPG.learn`: the
run folder's ``log.csv``, written by the same code as ``sepg run`` (same columns, names and
number format), and optionally TensorBoard event files through tensorboardX (an optional
dependency: ``pip install sepg[tensorboard]``).

TensorBoard receives every column of ``log.csv`` that has a value at the iteration as the
scalar ``sepg/<column>`` at step ``iteration`` (vector columns as ``v_0``, ``v_1``, ... as in
the file; flags as 0/1; the deterministic target's ``w_target`` as -inf). TensorBoard stores
scalars in single precision: the values read back are the records rounded to float32.
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Tuple, Union

from sepg import _native
from sepg.errors import InvalidInputError

PathLike = Union[str, "os.PathLike[str]"]


def log_columns(record: Dict[str, Any]) -> List[Tuple[str, Any]]:
    """The cells of ``record`` (a dict with the columns of ``log.csv``) as ``(column,
    value)`` pairs in the file's order, vectors split as the file splits them (``v`` for
    one component, ``v_0``, ``v_1``, ... for several); ``None`` where the file's cell is
    empty."""
    cells: List[Tuple[str, Any]] = []
    for key, value in record.items():
        if isinstance(value, list):
            if len(value) == 1:
                cells.append((key, value[0]))
            else:
                cells.extend((f"{key}_{j}", x) for j, x in enumerate(value))
        else:
            cells.append((key, value))
    return cells


class Logger:
    """Writes ``folder/log.csv`` (created or truncated on the first record) and, with
    ``tensorboard=True``, TensorBoard event files in ``folder`` (needs tensorboardX; raises
    ``ImportError`` naming it otherwise). ``csv=False`` writes the event files only. Lines are
    flushed after every record, so that the file can be read while the run goes on. Use it
    as a context manager or call :meth:`close`."""

    def __init__(self, folder: PathLike, *, csv: bool = True, tensorboard: bool = False) -> None:
        if not csv and not tensorboard:
            raise InvalidInputError("the logger needs csv=True or tensorboard=True")
        self.folder = os.fspath(folder)
        os.makedirs(self.folder, exist_ok=True)
        self.csv_path: Optional[str] = os.path.join(self.folder, "log.csv") if csv else None
        self._csv: Any = None
        self._dims: Optional[Tuple[int, int]] = None
        self._writer: Any = None
        self._closed = False
        if tensorboard:
            try:
                from tensorboardX import SummaryWriter
            except ImportError as e:
                raise ImportError(
                    "TensorBoard logging needs tensorboardX (pip install tensorboardX, or "
                    "sepg[tensorboard])"
                ) from e
            self._writer = SummaryWriter(logdir=self.folder)

    def record(self, record: Dict[str, Any]) -> None:
        """Writes one record (a dict with the columns of ``log.csv``)."""
        if self._closed:
            raise InvalidInputError("the logger is closed")
        dims = (len(record["v"]), len(record["w"]))
        if self._dims is None:
            self._dims = dims
            if self.csv_path is not None:
                self._csv = open(self.csv_path, "w", encoding="utf-8", newline="")
                self._csv.write(_native.log_header(*dims))
        elif dims != self._dims:
            raise InvalidInputError(
                f"the record has {dims[0]} mean parameters and {dims[1]} standard deviations, "
                f"the log {self._dims[0]} and {self._dims[1]}"
            )
        if self._csv is not None:
            self._csv.write(_native.log_row(record))
            self._csv.flush()
        if self._writer is not None:
            step = int(record["iteration"])
            for name, value in log_columns(record):
                if name != "iteration" and value is not None:
                    self._writer.add_scalar(f"sepg/{name}", float(value), step)
            self._writer.flush()

    def close(self) -> None:
        """Closes the files (the logger takes no more records)."""
        self._closed = True
        if self._csv is not None:
            self._csv.close()
            self._csv = None
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def __enter__(self) -> "Logger":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


__all__ = ["Logger", "log_columns"]
