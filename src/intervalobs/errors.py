"""Exception hierarchy of intervalobs.

Every error raised on purpose by the library derives from :class:`IntervalObserverError`, and its
message is one line naming the argument, the expected value and the actual value.
"""

from __future__ import annotations

__all__ = [
    "ArgumentError",
    "ArgumentTypeError",
    "AssumptionError",
    "BoundsError",
    "DataError",
    "DesignError",
    "DimensionError",
    "DivergenceWarning",
    "FileError",
    "InconsistentDataError",
    "IntervalObserverError",
    "SchedulerError",
]


class IntervalObserverError(Exception):
    """Base class of every error raised on purpose by intervalobs."""


class DimensionError(IntervalObserverError, ValueError):
    """An array has the wrong shape or the dimensions of a model do not agree."""


class BoundsError(IntervalObserverError, ValueError):
    """An interval is empty (lower > upper) or has non-finite ends."""


class AssumptionError(IntervalObserverError, ValueError):
    """A hypothesis of the method fails (the message names which one)."""


class DesignError(IntervalObserverError, RuntimeError):
    """A design problem (LMI, LP, pole placement) is infeasible or its result fails verification."""


class DataError(IntervalObserverError, ValueError):
    """Measurements or inputs contain NaN/inf or do not match the time vector."""


class InconsistentDataError(DataError):
    """The data contradict the model and its bounds: no admissible realisation explains them.

    An observer's ``step`` raises it when its box becomes empty (a parameter outside its box, a unit
    error, a wrong time grid, a fault); ``run`` does not: it returns the estimate up to that time,
    with ``Estimate.consistent`` False and ``Estimate.inconsistent_from`` the time.
    """


class ArgumentError(IntervalObserverError, ValueError):
    """A scalar argument or command-line option is out of its range or not one of its choices."""


class ArgumentTypeError(IntervalObserverError, TypeError):
    """An argument has the wrong type: text or complex numbers for a real array, None for an observer state."""


class FileError(IntervalObserverError, OSError):
    """A file or folder is missing, cannot be written, or is not what the function reads."""


class SchedulerError(IntervalObserverError, ConnectionError):
    """The Dask scheduler at the given address did not answer in time."""


class DivergenceWarning(RuntimeWarning):
    """The widths of a run grow without bound: the bounds still hold, but they say nothing about the state.

    The run records the growth in ``Estimate.meta`` (``width_growth``, ``diverging``) as well.
    """
