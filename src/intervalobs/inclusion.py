r"""Inclusion functions: interval arithmetic over NumPy arrays, for sound ranges of user functions.

An :class:`Interval` holds elementwise ``lower``/``upper`` arrays (any shape, so leading axes of time,
Monte Carlo runs or sub-boxes are carried through without a Python loop). Arithmetic (``+ - * /``,
integer powers) and the NumPy functions listed in :data:`SUPPORTED_UFUNCS` (``sin``, ``cos``, ``exp``,
``log``, ``sqrt``, ``tanh``, ``arctan``, ``abs``, ``square``) return intervals that contain every
value the operation takes on the operands' boxes (the *natural extension*). Each result is widened
outward by one ulp (two for transcendental functions, whose library implementations are accurate to
about one ulp), so the enclosure survives floating-point rounding.

User functions follow one convention everywhere in the library (``NonlinearSystem``,
:mod:`intervalobs.design.mixed_monotone`): a vector function :math:`q:\mathbb{R}^n\to\mathbb{R}^m` is a
Python callable that takes a *sequence of its n components* and returns a sequence of its m components
(a Jacobian returns m rows of n entries). Components are arrays over leading axes when evaluated at
points and :class:`Interval` objects when evaluated over boxes, so one definition written with
``numpy`` functions serves both, e.g.::

    def f(x):
        return (0.6 * x[0] - 0.12 * x[1] + 1.1 * np.sin(0.3 * x[1] - 0.2 * x[0]), -0.2 * x[0] - 0.14 * x[1])

Constants in the returned sequence are broadcast.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import BoundsError, DimensionError

__all__ = [
    "SUPPORTED_UFUNCS",
    "Interval",
    "evaluate_function",
    "evaluate_matrix",
    "interval_function",
    "interval_matrix",
]

FloatArray = NDArray[np.float64]
VectorFunction = Callable[[Sequence[Any]], Sequence[Any]]
MatrixFunction = Callable[[Sequence[Any]], Sequence[Sequence[Any]]]

_EPS = np.finfo(float).eps
_TWO_PI = 2.0 * np.pi


def _down(a: FloatArray, ulps: int = 1) -> FloatArray:
    for _ in range(ulps):
        a = np.nextafter(a, -np.inf)
    return a


def _up(a: FloatArray, ulps: int = 1) -> FloatArray:
    for _ in range(ulps):
        a = np.nextafter(a, np.inf)
    return a


def _contains_point(lo: FloatArray, hi: FloatArray, offset: float, period: float) -> NDArray[np.bool_]:
    """Whether ``[lo, hi]`` contains some ``offset + k*period`` (conservatively: a near miss counts)."""
    slack = 1e-9 * (1.0 + np.abs(lo))
    k = np.ceil((lo - slack - offset) / period)
    return offset + k * period <= hi + slack


class Interval:
    """An elementwise interval ``[lower, upper]`` of arrays, with outward-rounded arithmetic.

    Parameters
    ----------
    lower, upper : array_like
        Ends (broadcast against each other). ``lower <= upper`` is required; infinite ends are allowed.
    """

    __array_priority__ = 1000.0

    def __init__(self, lower: ArrayLike, upper: ArrayLike | None = None) -> None:
        lo = np.asarray(lower, dtype=float)
        hi = lo if upper is None else np.asarray(upper, dtype=float)
        lo, hi = np.broadcast_arrays(lo, hi)
        if np.any(np.isnan(lo)) or np.any(np.isnan(hi)):
            raise BoundsError("Interval: expected ends without NaN, got NaN")
        if np.any(lo > hi):
            raise BoundsError("Interval: expected lower <= upper, got lower > upper")
        self.lower: FloatArray = np.array(lo)
        self.upper: FloatArray = np.array(hi)

    # --- helpers -------------------------------------------------------------------------------------
    @staticmethod
    def _wrap(value: Any) -> Interval:
        if isinstance(value, Interval):
            return value
        v = np.asarray(value, dtype=float)
        return Interval._raw(v, v)

    @classmethod
    def _raw(cls, lo: FloatArray, hi: FloatArray) -> Interval:
        out = cls.__new__(cls)
        out.lower, out.upper = lo, hi
        return out

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the ends."""
        return tuple(self.lower.shape)

    @property
    def width(self) -> FloatArray:
        """``upper - lower``."""
        return self.upper - self.lower

    @property
    def mid(self) -> FloatArray:
        """Midpoint (finite ends assumed)."""
        return 0.5 * (self.lower + self.upper)

    def __getitem__(self, index: Any) -> Interval:
        return Interval._raw(self.lower[index], self.upper[index])

    def __repr__(self) -> str:
        return f"Interval({self.lower!r}, {self.upper!r})"

    # --- arithmetic ----------------------------------------------------------------------------------
    def __neg__(self) -> Interval:
        return Interval._raw(-self.upper, -self.lower)

    def __pos__(self) -> Interval:
        return self

    def __add__(self, other: Any) -> Interval:
        o = Interval._wrap(other)
        return Interval._raw(_down(self.lower + o.lower), _up(self.upper + o.upper))

    __radd__ = __add__

    def __sub__(self, other: Any) -> Interval:
        o = Interval._wrap(other)
        return Interval._raw(_down(self.lower - o.upper), _up(self.upper - o.lower))

    def __rsub__(self, other: Any) -> Interval:
        return Interval._wrap(other) - self

    def __mul__(self, other: Any) -> Interval:
        if not isinstance(other, Interval):
            c = np.asarray(other, dtype=float)
            with np.errstate(invalid="ignore"):
                a, b = c * self.lower, c * self.upper
            a, b = np.where(np.isnan(a), 0.0, a), np.where(np.isnan(b), 0.0, b)  # 0 * inf = 0
            return Interval._raw(_down(np.minimum(a, b)), _up(np.maximum(a, b)))
        o = other
        with np.errstate(invalid="ignore"):
            p1, p2 = self.lower * o.lower, self.lower * o.upper
            p3, p4 = self.upper * o.lower, self.upper * o.upper
        p1, p2, p3, p4 = (np.where(np.isnan(v), 0.0, v) for v in (p1, p2, p3, p4))  # 0 * inf = 0
        low = np.minimum(np.minimum(p1, p2), np.minimum(p3, p4))
        high = np.maximum(np.maximum(p1, p2), np.maximum(p3, p4))
        return Interval._raw(_down(low), _up(high))

    __rmul__ = __mul__

    def reciprocal(self) -> Interval:
        """``1 / self``; the interval must not contain zero.

        Returns
        -------
        Interval
        """
        if np.any((self.lower <= 0) & (self.upper >= 0)):
            raise BoundsError("Interval: division by an interval that contains 0")
        return Interval._raw(_down(1.0 / self.upper), _up(1.0 / self.lower))

    def __truediv__(self, other: Any) -> Interval:
        return self * Interval._wrap(other).reciprocal()

    def __rtruediv__(self, other: Any) -> Interval:
        return Interval._wrap(other) * self.reciprocal()

    def __pow__(self, exponent: int) -> Interval:
        if not isinstance(exponent, (int, np.integer)) or exponent < 0:
            raise BoundsError(f"Interval: expected a nonnegative integer exponent, got {exponent!r}")
        if exponent == 0:
            return Interval(np.ones_like(self.lower))
        lo_p, hi_p = self.lower**exponent, self.upper**exponent
        if exponent % 2 == 1:
            return Interval._raw(_down(lo_p, 2), _up(hi_p, 2))
        has_zero = (self.lower <= 0) & (self.upper >= 0)
        low = np.where(has_zero, 0.0, np.minimum(lo_p, hi_p))
        return Interval._raw(np.maximum(_down(low, 2), 0.0), _up(np.maximum(lo_p, hi_p), 2))

    # --- elementary functions through NumPy's ufunc protocol -----------------------------------------
    def __array_ufunc__(self, ufunc: Any, method: str, *inputs: Any, **kwargs: Any) -> Any:
        if method != "__call__" or kwargs:
            return NotImplemented
        handler = _UFUNCS.get(ufunc)
        if handler is None:
            return NotImplemented
        return handler(*inputs)


def _sin(x: Interval) -> Interval:
    lo, hi = x.lower, x.upper
    finite = np.isfinite(lo) & np.isfinite(hi)
    lo_f, hi_f = np.where(finite, lo, 0.0), np.where(finite, hi, 0.0)
    s_lo, s_hi = np.sin(lo_f), np.sin(hi_f)
    low, high = np.minimum(s_lo, s_hi), np.maximum(s_lo, s_hi)
    full = ~finite | (hi_f - lo_f >= _TWO_PI)
    high = np.where(full | _contains_point(lo_f, hi_f, 0.5 * np.pi, _TWO_PI), 1.0, high)
    low = np.where(full | _contains_point(lo_f, hi_f, -0.5 * np.pi, _TWO_PI), -1.0, low)
    return Interval._raw(np.maximum(_down(low, 2) - _EPS, -1.0), np.minimum(_up(high, 2) + _EPS, 1.0))


def _cos(x: Interval) -> Interval:
    lo, hi = x.lower, x.upper
    finite = np.isfinite(lo) & np.isfinite(hi)
    lo_f, hi_f = np.where(finite, lo, 0.0), np.where(finite, hi, 0.0)
    c_lo, c_hi = np.cos(lo_f), np.cos(hi_f)
    low, high = np.minimum(c_lo, c_hi), np.maximum(c_lo, c_hi)
    full = ~finite | (hi_f - lo_f >= _TWO_PI)
    high = np.where(full | _contains_point(lo_f, hi_f, 0.0, _TWO_PI), 1.0, high)
    low = np.where(full | _contains_point(lo_f, hi_f, np.pi, _TWO_PI), -1.0, low)
    return Interval._raw(np.maximum(_down(low, 2) - _EPS, -1.0), np.minimum(_up(high, 2) + _EPS, 1.0))


def _monotone(fn: Callable[[FloatArray], FloatArray], lo_limit: float = -np.inf) -> Callable[[Interval], Interval]:
    def apply(x: Interval) -> Interval:
        if np.any(x.lower < lo_limit):
            raise BoundsError(f"Interval: argument below the domain bound {lo_limit:g} of {fn.__name__}")
        with np.errstate(over="ignore", divide="ignore"):
            return Interval._raw(_down(fn(x.lower), 2), _up(fn(x.upper), 2))

    return apply


def _abs(x: Interval) -> Interval:
    has_zero = (x.lower <= 0) & (x.upper >= 0)
    a, b = np.abs(x.lower), np.abs(x.upper)
    return Interval._raw(np.where(has_zero, 0.0, np.minimum(a, b)), np.maximum(a, b))


def _binary(
    op: Callable[[Interval, Any], Interval], reflected: Callable[[Interval, Any], Interval]
) -> Callable[..., Interval]:
    def apply(a: Any, b: Any) -> Interval:
        return op(a, b) if isinstance(a, Interval) else reflected(b, a)

    return apply


def _tanh(x: Interval) -> Interval:
    return Interval._raw(np.maximum(_down(np.tanh(x.lower), 2), -1.0), np.minimum(_up(np.tanh(x.upper), 2), 1.0))


_UFUNCS: dict[Any, Callable[..., Interval]] = {
    np.sin: _sin,
    np.cos: _cos,
    np.exp: _monotone(np.exp),
    np.log: _monotone(np.log, 0.0),
    np.sqrt: _monotone(np.sqrt, 0.0),
    np.tanh: _tanh,
    np.arctan: _monotone(np.arctan),
    np.absolute: _abs,
    np.square: lambda x: x**2,
    np.negative: lambda x: -x,
    np.add: _binary(Interval.__add__, Interval.__radd__),
    np.subtract: _binary(Interval.__sub__, Interval.__rsub__),
    np.multiply: _binary(Interval.__mul__, Interval.__rmul__),
    np.true_divide: _binary(Interval.__truediv__, Interval.__rtruediv__),
}

SUPPORTED_UFUNCS = tuple(sorted(u.__name__ for u in _UFUNCS))
"""NumPy functions that accept :class:`Interval` arguments."""


def _stack(values: Sequence[Any], lead: tuple[int, ...], name: str, size: int | None) -> FloatArray:
    if size is not None and len(values) != size:
        raise DimensionError(f"{name}: expected {size} components, got {len(values)}")
    return np.stack([np.broadcast_to(np.asarray(v, dtype=float), lead) for v in values], axis=-1)


def evaluate_function(
    func: VectorFunction, x: ArrayLike, size: int | None = None, name: str = "function"
) -> FloatArray:
    """Evaluate a component-convention vector function at points ``x`` of shape (..., n).

    Parameters
    ----------
    func : callable
        Takes a sequence of n component arrays, returns a sequence of m components.
    x : array_like, shape (..., n)
        Points; leading axes are carried through.
    size : int, optional
        Expected number of returned components.
    name : str
        Name used in error messages.

    Returns
    -------
    numpy.ndarray, shape (..., m)
    """
    xa = np.asarray(x, dtype=float)
    out = func([xa[..., j] for j in range(xa.shape[-1])])
    return _stack(list(out), xa.shape[:-1], name, size)


def interval_function(
    func: VectorFunction, lower: ArrayLike, upper: ArrayLike, size: int | None = None, name: str = "function"
) -> tuple[FloatArray, FloatArray]:
    """Natural interval extension of a vector function over boxes ``[lower, upper]`` (shape (..., n)).

    Parameters
    ----------
    func : callable
        Component-convention vector function, written with operations :class:`Interval` supports.
    lower, upper : array_like, shape (..., n)
        Boxes; leading axes are carried through.
    size : int, optional
        Expected number of returned components.
    name : str
        Name used in error messages.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m)
        Bounds containing ``func(x)`` for every ``x`` in the box.
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    out = func([Interval._raw(lo[..., j], hi[..., j]) for j in range(lo.shape[-1])])
    comps = [Interval._wrap(c) for c in out]
    return (
        _stack([c.lower for c in comps], lo.shape[:-1], name, size),
        _stack([c.upper for c in comps], lo.shape[:-1], name, size),
    )


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
    shape : tuple of int, optional
        Expected (m, n).
    name : str
        Name used in error messages.

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
    shape : tuple of int, optional
        Expected (m, n).
    name : str
        Name used in error messages.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m, n)
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    rows = list(func([Interval._raw(lo[..., j], hi[..., j]) for j in range(lo.shape[-1])]))
    if shape is not None and len(rows) != shape[0]:
        raise DimensionError(f"{name}: expected {shape[0]} rows, got {len(rows)}")
    cols = None if shape is None else shape[1]
    wrapped = [[Interval._wrap(c) for c in r] for r in rows]
    low = np.stack([_stack([c.lower for c in r], lo.shape[:-1], name, cols) for r in wrapped], axis=-2)
    high = np.stack([_stack([c.upper for c in r], lo.shape[:-1], name, cols) for r in wrapped], axis=-2)
    return low, high
