"""Callbacks of :meth:`sepg.gym.GymRun.run` and :meth:`sepg.SEPG.learn`, with the conventions
of stable-baselines3.

A callback is called once per iteration, after the iteration is complete, with the
iteration's record (a dict with the columns of ``log.csv``). Returning ``False`` stops the
run after that iteration: the iteration is kept, and the run's state is the state after it,
so that a later ``run``/``learn`` continues exactly as an uninterrupted run would.

``callback`` may be

- a callable ``f(record)``; it stops the run by returning ``False`` (``None`` and any other
  value continue);
- an object with a method ``on_step(record)`` (stops on ``False``) and optionally
  ``on_training_start(run)`` and ``on_training_end()``, such as a subclass of
  :class:`BaseCallback`;
- a list or tuple of these (:class:`CallbackList`): all are called in order, and the run
  stops when any of them returns ``False``.
"""

from __future__ import annotations

from typing import Any, Callable, Dict, List, Optional, Sequence, Union

from sepg.errors import InvalidInputError

Record = Dict[str, Any]


class BaseCallback:
    """The base class of callbacks, as stable-baselines3's ``BaseCallback``: override
    :meth:`_on_step` (return ``False`` to stop) and optionally :meth:`_on_training_start` and
    :meth:`_on_training_end`. ``run`` is the :class:`sepg.gym.GymRun` being trained,
    ``n_calls`` the number of iterations seen and ``num_timesteps`` the environment steps
    the run has used (the ``steps`` column of the last record)."""

    def __init__(self) -> None:
        self.run: Any = None
        self.n_calls = 0
        self.num_timesteps = 0

    def on_training_start(self, run: Any) -> None:
        """Called by ``run``/``learn`` before its first iteration."""
        self.run = run
        self._on_training_start()

    def on_step(self, record: Record) -> bool:
        """Called after each iteration with its record; ``False`` stops the run."""
        self.n_calls += 1
        self.num_timesteps = int(record["steps"])
        return self._on_step(record) is not False

    def on_training_end(self) -> None:
        """Called when ``run``/``learn`` returns (also when it stops early or raises)."""
        self._on_training_end()

    def _on_training_start(self) -> None:
        pass

    def _on_step(self, record: Record) -> Optional[bool]:
        return True

    def _on_training_end(self) -> None:
        pass


class FunctionCallback(BaseCallback):
    """A callable ``f(record)`` as a callback: it stops the run by returning ``False``."""

    def __init__(self, function: Callable[[Record], Any]) -> None:
        super().__init__()
        self.function = function

    def _on_step(self, record: Record) -> Optional[bool]:
        return self.function(record) is not False


class _ObjectCallback(BaseCallback):
    """An object with ``on_step`` (and optionally the other hooks) that does not derive from
    :class:`BaseCallback`."""

    def __init__(self, target: Any) -> None:
        super().__init__()
        self.target = target

    def _on_training_start(self) -> None:
        hook = getattr(self.target, "on_training_start", None)
        if hook is not None:
            hook(self.run)

    def _on_step(self, record: Record) -> Optional[bool]:
        return self.target.on_step(record) is not False

    def _on_training_end(self) -> None:
        hook = getattr(self.target, "on_training_end", None)
        if hook is not None:
            hook()


class CallbackList(BaseCallback):
    """Several callbacks called in order; the run stops when any returns ``False`` (the
    others are still called for that iteration)."""

    def __init__(self, callbacks: Sequence[Any]) -> None:
        super().__init__()
        self.callbacks: List[BaseCallback] = [_one(c) for c in callbacks]

    def _on_training_start(self) -> None:
        for c in self.callbacks:
            c.on_training_start(self.run)

    def _on_step(self, record: Record) -> Optional[bool]:
        results = [c.on_step(record) for c in self.callbacks]
        return all(results)

    def _on_training_end(self) -> None:
        for c in self.callbacks:
            c.on_training_end()


class StopTrainingOnMaxSteps(BaseCallback):
    """Stops the run after the first iteration at which it has used at least ``max_steps``
    environment steps in all."""

    def __init__(self, max_steps: int) -> None:
        super().__init__()
        if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1:
            raise InvalidInputError(f"max_steps must be a positive integer, got {max_steps!r}")
        self.max_steps = max_steps

    def _on_step(self, record: Record) -> Optional[bool]:
        return int(record["steps"]) < self.max_steps


CallbackArg = Union[None, Callable[[Record], Any], BaseCallback, Sequence[Any]]


def _one(callback: Any) -> BaseCallback:
    if isinstance(callback, BaseCallback):
        return callback
    if callable(getattr(callback, "on_step", None)):
        return _ObjectCallback(callback)
    if callable(callback):
        return FunctionCallback(callback)
    raise InvalidInputError(
        "callback must be a callable f(record), an object with on_step(record), or a list "
        f"of these; got {callback!r}"
    )


def as_callback(callback: CallbackArg) -> Optional[BaseCallback]:
    """``callback`` (as :meth:`sepg.gym.GymRun.run` takes it) as one :class:`BaseCallback`,
    or ``None`` for no callback."""
    if callback is None:
        return None
    if isinstance(callback, (list, tuple)):
        return CallbackList(callback)
    return _one(callback)


__all__ = [
    "BaseCallback",
    "CallbackList",
    "FunctionCallback",
    "StopTrainingOnMaxSteps",
    "as_callback",
]
