"""The progress bar of :meth:`sepg.gym.GymRun.run` and :meth:`sepg.SEPG.learn`: tqdm's, on
standard error. tqdm is an optional dependency (``pip install sepg[progress]``); without it
there is no bar, and one warning says so."""

from __future__ import annotations

import sys
import warnings
from typing import Any, Optional

_warned = False


def progress_bar(enabled: Optional[bool], *, total: int, unit: str, desc: str) -> Any:
    """A tqdm bar of ``total`` ``unit``\\ s labelled ``desc``, or ``None``. ``enabled`` ``None``
    means: when standard error is a terminal. A bar asked for without tqdm installed warns
    once per process (``UserWarning``) and gives ``None``."""
    global _warned
    if enabled is None:
        isatty = getattr(sys.stderr, "isatty", None)
        enabled = bool(isatty is not None and isatty())
    if not enabled:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        if not _warned:
            _warned = True
            warnings.warn(
                "no progress bar: tqdm is not installed (pip install tqdm, or sepg[progress])",
                UserWarning,
                stacklevel=3,
            )
        return None
    return tqdm(total=total, unit=unit, desc=desc, file=sys.stderr)
