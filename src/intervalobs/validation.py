"""Validation of user input at the boundary of the library.

Every model class, observer and simulation converts its arrays through these functions, so that a
wrong shape or an empty interval is reported once, with the argument's name, the expected and the
actual value, and never surfaces as a traceback from deep inside NumPy.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import BoundsError, DataError, DimensionError

__all__ = ["as_box", "as_matrix", "as_signal", "as_time", "as_vector", "check_no_kwargs"]

FloatArray = NDArray[np.float64]


def _as_float(name: str, value: ArrayLike) -> FloatArray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DimensionError(f"{name}: expected a numeric array, got {type(value).__name__}") from exc
    return arr


def as_matrix(
    name: str, value: ArrayLike, shape: tuple[int | None, int | None] = (None, None), finite: bool = True
) -> FloatArray:
    """Convert ``value`` to a 2-D float array and check its shape.

    Parameters
    ----------
    name : str
        Argument name used in error messages.
    value : array_like
        Matrix; a scalar or a 1-D array is accepted where the expected shape makes it unambiguous
        (a scalar for a 1×1 matrix, a 1-D array for one row or one column).
    shape : tuple of int or None
        Expected shape; ``None`` leaves a dimension free.
    finite : bool
        Reject NaN and inf.

    Returns
    -------
    numpy.ndarray
        The matrix, shape ``shape``.
    """
    arr = _as_float(name, value)
    rows, cols = shape
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        if cols == 1 and rows in (None, arr.size):
            arr = arr.reshape(-1, 1)
        elif rows == 1 or rows is None or cols in (None, arr.size):
            arr = arr.reshape(1, -1)
    if arr.ndim != 2 or (rows is not None and arr.shape[0] != rows) or (cols is not None and arr.shape[1] != cols):
        want = "×".join("any" if d is None else str(d) for d in shape)
        raise DimensionError(f"{name}: expected shape {want}, got {np.shape(value)}")
    if finite and not np.all(np.isfinite(arr)):
        raise BoundsError(f"{name}: expected finite entries, got NaN or inf")
    return arr


def as_vector(name: str, value: ArrayLike, size: int | None = None, finite: bool = True) -> FloatArray:
    """Convert ``value`` to a 1-D float array of length ``size`` (a scalar is broadcast).

    Parameters
    ----------
    name : str
        Argument name used in error messages.
    value : array_like
        The user's value.
    size : int, optional
        Expected length (any length when None).
    finite : bool
        Reject NaN and inf entries.

    Returns
    -------
    numpy.ndarray, shape (size,)

    Raises
    ------
    DimensionError
        When ``value`` is not numeric or not a vector of length ``size``.
    BoundsError
        When ``finite`` and an entry is NaN or inf.
    """
    arr = _as_float(name, value)
    if arr.ndim == 0 and size is not None:
        arr = np.full(size, float(arr))
    if arr.ndim != 1 or (size is not None and arr.size != size):
        raise DimensionError(f"{name}: expected a vector of length {size}, got shape {np.shape(value)}")
    if finite and not np.all(np.isfinite(arr)):
        raise BoundsError(f"{name}: expected finite entries, got NaN or inf")
    return arr


def as_box(
    name: str, value: Sequence[ArrayLike] | tuple[ArrayLike, ArrayLike], size: int | None = None
) -> tuple[FloatArray, FloatArray]:
    """Convert a ``(lower, upper)`` pair to two finite vectors with ``lower <= upper``.

    Parameters
    ----------
    name : str
        Argument name used in error messages.
    value : tuple of array_like
        ``(lower, upper)``; scalars are broadcast to ``size``.
    size : int, optional
        Expected length.

    Returns
    -------
    lower, upper : numpy.ndarray
    """
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise BoundsError(f"{name}: expected a (lower, upper) pair, got {type(value).__name__}")
    lower = as_vector(f"{name} lower", value[0], size)
    upper = as_vector(f"{name} upper", value[1], size if size is not None else lower.size)
    if lower.shape != upper.shape:
        raise DimensionError(f"{name}: lower has shape {lower.shape}, upper has shape {upper.shape}")
    bad = np.flatnonzero(lower > upper)
    if bad.size:
        i = int(bad[0])
        raise BoundsError(f"{name}: expected lower <= upper, got lower[{i}]={lower[i]:g} > upper[{i}]={upper[i]:g}")
    return lower, upper


def as_time(name: str, value: ArrayLike) -> FloatArray:
    """Convert a time vector: 1-D, finite, strictly increasing, at least one sample.

    Parameters
    ----------
    name : str
        Argument name used in error messages.
    value : array_like
        The user's time vector.

    Returns
    -------
    numpy.ndarray, shape (T,)

    Raises
    ------
    DimensionError
        When ``value`` is not a non-empty 1-D array.
    DataError
        When a time is not finite or the times do not increase strictly.
    """
    arr = _as_float(name, value)
    if arr.ndim != 1 or arr.size == 0:
        raise DimensionError(f"{name}: expected a non-empty 1-D time vector, got shape {np.shape(value)}")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{name}: expected finite times, got NaN or inf")
    if arr.size > 1 and np.any(np.diff(arr) <= 0):
        raise DataError(f"{name}: expected strictly increasing times")
    return arr


def as_signal(name: str, value: ArrayLike, steps: int, width: int) -> FloatArray:
    """Convert a time-first signal of shape (T, width) or (M, T, width) and check it is finite.

    A 1-D array is read as (T,) when ``width == 1``.

    Parameters
    ----------
    name : str
        Argument name used in error messages.
    value : array_like
        The user's signal.
    steps : int
        Expected number of samples ``T``.
    width : int
        Expected number of channels.

    Returns
    -------
    numpy.ndarray, shape (T, width) or (M, T, width)

    Raises
    ------
    DataError
        When the shape is wrong or a value is NaN or inf.
    """
    arr = _as_float(name, value)
    if arr.ndim == 1 and width == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim not in (2, 3) or arr.shape[-2:] != (steps, width):
        raise DataError(f"{name}: expected shape ({steps}, {width}) or (runs, {steps}, {width}), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise DataError(f"{name}: expected finite values, got NaN or inf at index {tuple(int(i) for i in bad)}")
    return arr


def check_no_kwargs(function: str, kwargs: dict[str, Any], allowed: Sequence[str] = ()) -> None:
    """Raise ``TypeError`` naming the first keyword of ``kwargs`` that is not in ``allowed``.

    Every public function that takes ``**kwargs`` calls this first, so a misspelt option fails loudly
    instead of being ignored (``tests/test_kwargs.py`` checks it).

    Parameters
    ----------
    function : str
        Name of the calling function, used in the message.
    kwargs : dict of str to object
        The keywords the caller received.
    allowed : sequence of str
        The keywords it understands.

    Raises
    ------
    TypeError
        ``"<function>: unexpected keyword argument '<name>'; allowed: [...]"``.
    """
    unknown = [k for k in kwargs if k not in allowed]
    if unknown:
        raise TypeError(f"{function}: unexpected keyword argument {unknown[0]!r}; allowed: {sorted(allowed)}")
