r"""Inclusion functions: interval arithmetic over NumPy arrays, for sound ranges of user functions.

The interval type is :class:`intervalobs.interval.Interval` (its former names here, ``Interval`` and
``SUPPORTED_UFUNCS``, warn and go in the next release): arithmetic (``+ - * /``, integer powers) and
the NumPy functions ``sin``, ``cos``, ``exp``, ``log``, ``sqrt``, ``tanh``, ``arctan``, ``abs``,
``square`` return intervals that contain every value the operation takes on the operands' boxes (the
*natural extension*), rounded outward per operation (:func:`intervalobs.interval.round_outward`). This
module evaluates user functions over boxes with it.

User functions follow one convention everywhere in the library (``NonlinearSystem``,
:mod:`intervalobs.design.mixed_monotone`): a vector function :math:`q:\mathbb{R}^n\to\mathbb{R}^m` is a
Python callable that takes a *sequence of its n components* and returns a sequence of its m components
(a Jacobian returns m rows of n entries). Components are arrays over leading axes when evaluated at
points and :class:`~intervalobs.interval.Interval` objects when evaluated over boxes, so one definition written with
``numpy`` functions serves both, e.g.::

    def f(x):
        return (0.6 * x[0] - 0.12 * x[1] + 1.1 * np.sin(0.3 * x[1] - 0.2 * x[0]), -0.2 * x[0] - 0.14 * x[1])

Constants in the returned sequence are broadcast.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import interval
from ._docstrings import shared_docs
from .errors import DimensionError, IntervalObserverError

__all__ = [
    "evaluate_function",
    "evaluate_matrix",
    "interval_function",
    "interval_matrix",
]

FloatArray = NDArray[np.float64]
VectorFunction = Callable[[Sequence[Any]], Sequence[Any]]
MatrixFunction = Callable[[Sequence[Any]], Sequence[Sequence[Any]]]


def _stack(values: Sequence[Any], lead: tuple[int, ...], name: str, size: int | None) -> FloatArray:
    if size is not None and len(values) != size:
        raise DimensionError(f"{name}: expected {size} components, got {len(values)}")
    out = np.empty((*lead, len(values)))
    for i, v in enumerate(values):
        out[..., i] = v  # broadcast to the points' shape, as np.broadcast_to would (a wrong shape raises)
    return out


@shared_docs
def evaluate_function(
    func: VectorFunction, x: ArrayLike, size: int | None = None, name: str = "function"
) -> FloatArray:
    """Evaluate a component-convention vector function at points ``x`` of shape (..., n).

    Parameters
    ----------
    func : callable
        Takes a sequence of n component arrays (each of shape (N,): the points, leading axes
        flattened), returns a sequence of m components; a matrix product ``A @ x`` is such a function.
    x : array_like, shape (..., n)
        Points; leading axes are carried through.
    %(size_name)s

    Returns
    -------
    numpy.ndarray, shape (..., m)

    Raises
    ------
    DimensionError
        ``func`` does not take or return components (the message shows the form it needs).
    """
    xa = np.asarray(x, dtype=float)
    flat = xa.reshape(-1, xa.shape[-1])  # one axis of points: `A @ x` then maps them all
    try:
        values = _stack(list(func([flat[:, j] for j in range(flat.shape[-1])])), flat.shape[:1], name, size)
    except (ValueError, TypeError, IndexError) as error:
        if isinstance(error, IntervalObserverError):
            raise
        raise DimensionError(
            f"{name}: expected a function of the list of state components x[0] … x[n-1] (each an array of "
            f"points) that returns its components, e.g. lambda x: A @ x or lambda x: [x[0] * x[1], -x[1]]; "
            f"calling it raised {type(error).__name__}: {error}"
        ) from error
    return values.reshape(*xa.shape[:-1], values.shape[-1])


@shared_docs
def interval_function(
    func: VectorFunction, lower: ArrayLike, upper: ArrayLike, size: int | None = None, name: str = "function"
) -> tuple[FloatArray, FloatArray]:
    """Natural interval extension of a vector function over boxes ``[lower, upper]`` (shape (..., n)).

    Parameters
    ----------
    func : callable
        Component-convention vector function, written with the operations
        :class:`~intervalobs.interval.Interval` supports.
    %(boxes)s
    %(size_name)s

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m)
        Bounds containing ``func(x)`` for every ``x`` in the box.
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    out = func([interval.Interval._raw(lo[..., j], hi[..., j]) for j in range(lo.shape[-1])])
    comps = [interval.Interval._wrap(c) for c in out]
    return (
        _stack([c.lower for c in comps], lo.shape[:-1], name, size),
        _stack([c.upper for c in comps], lo.shape[:-1], name, size),
    )


@shared_docs
def evaluate_matrix(
    func: MatrixFunction, x: ArrayLike, shape: tuple[int, int] | None = None, name: str = "jacobian"
) -> FloatArray:
    """Evaluate a matrix-valued function (rows of entries) at points ``x``.

    Parameters
    ----------
    func : callable
        Component convention: a sequence of n components to m rows of entries.
    x : array_like, shape (..., n)
        Points.
    %(shape_name)s

    Returns
    -------
    numpy.ndarray, shape (..., m, n)
    """
    xa = np.asarray(x, dtype=float)
    rows = list(func([xa[..., j] for j in range(xa.shape[-1])]))
    if shape is not None and len(rows) != shape[0]:
        raise DimensionError(f"{name}: expected {shape[0]} rows, got {len(rows)}")
    cols = None if shape is None else shape[1]
    return np.stack([_stack(list(r), xa.shape[:-1], name, cols) for r in rows], axis=-2)


@shared_docs
def interval_matrix(
    func: MatrixFunction,
    lower: ArrayLike,
    upper: ArrayLike,
    shape: tuple[int, int] | None = None,
    name: str = "jacobian",
) -> tuple[FloatArray, FloatArray]:
    """Natural interval extension of a matrix-valued function over boxes.

    Parameters
    ----------
    func : callable
        Component convention: a sequence of n components to m rows of entries.
    lower, upper : array_like, shape (..., n)
        Boxes.
    %(shape_name)s

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m, n)
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    rows = list(func([interval.Interval._raw(lo[..., j], hi[..., j]) for j in range(lo.shape[-1])]))
    if shape is not None and len(rows) != shape[0]:
        raise DimensionError(f"{name}: expected {shape[0]} rows, got {len(rows)}")
    cols = None if shape is None else shape[1]
    wrapped = [[interval.Interval._wrap(c) for c in r] for r in rows]
    low = np.stack([_stack([c.lower for c in r], lo.shape[:-1], name, cols) for r in wrapped], axis=-2)
    high = np.stack([_stack([c.upper for c in r], lo.shape[:-1], name, cols) for r in wrapped], axis=-2)
    return low, high


def __getattr__(name: str) -> Any:
    """``Interval`` and ``SUPPORTED_UFUNCS``, formerly at home here: the object, with a ``FutureWarning``.

    .. deprecated:: 0.2.0
       Both go from this module in the next release; import them from :mod:`intervalobs.interval`.
    """
    if name not in ("Interval", "SUPPORTED_UFUNCS"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn(
        f"intervalobs.inclusion.{name} is deprecated and goes in the next release: "
        f"use 'from intervalobs.interval import {name}'",
        FutureWarning,
        stacklevel=2,
    )
    return getattr(interval, name)
