"""The exceptions raised by sepg.

Every error sepg raises is a :class:`SepgError`. Bad input (a value outside its domain, a
non-finite number, an array of the wrong shape, a missing task constant) is an
:class:`InvalidInputError`, which is also a :class:`ValueError`; a run that fails on valid
input (a quantity that overflows, a collector that returns inconsistent data) raises
:class:`RunFailedError`.
"""


class SepgError(Exception):
    """Base class of every exception raised by sepg."""


class InvalidInputError(SepgError, ValueError):
    """An argument is outside its domain, not finite, or of the wrong shape."""


class MissingConstantError(InvalidInputError):
    """A task constant (R_max, M_phi or |A|) was neither given nor derivable from the
    environment's spaces."""


class RunFailedError(SepgError, RuntimeError):
    """A run failed on valid input (for example a quantity became non-finite)."""


__all__ = ["SepgError", "InvalidInputError", "MissingConstantError", "RunFailedError"]
