r"""Forward-mode automatic differentiation in interval arithmetic: sound Jacobian bounds from f alone.

An :class:`IntervalDual` is a pair of :class:`~intervalobs.interval.Interval` objects: a *value* box
(shape ``(...)``) and a *derivative* box (shape ``(..., n)``, one entry per independent variable).
Seeding variable :math:`j` with value :math:`[\underline x_j, \overline x_j]` and derivative
:math:`e_j` and pushing the duals through a user function written with NumPy functions gives, for
every output component :math:`q_i`, a value box containing :math:`q_i(x)` and a derivative box
containing :math:`\nabla q_i(x)` for **every** :math:`x` of the box. Each rule is the chain rule
evaluated in the interval arithmetic of :mod:`intervalobs.interval` (outward rounded):

=================  ======================================================================
operation          derivative box
=================  ======================================================================
:math:`u \pm v`    :math:`u' \pm v'`
:math:`uv`         :math:`u'V + Uv'`
:math:`u/v`        :math:`(u' - Qv')/V`, :math:`Q \ni u/v`
:math:`u^k`        :math:`kU^{k-1}u'` (integer :math:`k \ge 0`)
sin, cos           :math:`\cos(U)u'`, :math:`-\sin(U)u'`
exp                :math:`\exp(U)u'`
log, sqrt          :math:`u'/U`, :math:`u'/(2\sqrt U)` (upper end :math:`+\infty` where :math:`U` reaches 0)
tanh               :math:`(1 - \tanh(U)^2)u'`, intersected with :math:`[0, 1]u'`
arctan             :math:`u'/(1 + U^2)`
abs                :math:`\mathrm{sign}(U)u'`, with :math:`\mathrm{sign} = [-1, 1]` where :math:`U \ni 0`
square             :math:`2Uu'`
=================  ======================================================================

(:math:`U, V` the value boxes). Because every sub-expression's box contains its exact value at each
point of the input box, the interval evaluation of the chain-rule expression contains the exact
derivative there (the fundamental theorem of interval arithmetic). For ``abs``, which is not
differentiable at 0, the box is a Clarke generalised gradient: it still bounds every difference
quotient (Lebourg's mean-value theorem), which is all the decomposition functions, the mean-value form
and the affine abstraction of :mod:`intervalobs.design` use.

:func:`automatic_jacobian` turns a component-convention vector function (:mod:`intervalobs.inclusion`)
into a component-convention Jacobian, so it can be used wherever a user-written Jacobian is accepted.
:func:`value_and_jacobian` returns both boxes as arrays from one pass (the hot loops': no per-entry objects).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._docstrings import shared_docs
from .errors import DimensionError
from .inclusion import MatrixFunction, VectorFunction
from .interval import Interval, round_outward

__all__ = ["IntervalDual", "automatic_jacobian", "value_and_jacobian"]

FloatArray = NDArray[np.float64]


def _col(x: Interval) -> Interval:
    """Append an axis, so a value box multiplies a derivative box ``(..., n)``."""
    return x[..., None]


def _reciprocal_nonnegative(x: Interval) -> Interval:
    """``1/x`` for ``x >= 0``; the upper end is ``+inf`` where ``x`` reaches 0."""
    lo, hi = x.lower, x.upper
    with np.errstate(divide="ignore"):
        low, high = round_outward(1.0 / hi, 1.0 / np.where(lo > 0, lo, 1.0))
    return Interval._raw(np.maximum(low, 0.0), np.where(lo > 0, high, np.inf))


def _zero(d: Interval) -> NDArray[np.bool_]:
    return (d.lower == 0.0) & (d.upper == 0.0)


def _keep_zeros(d: Interval, *sources: Interval) -> Interval:
    """Exact zeros where every source derivative is exactly zero (outward rounding would pad them).

    A partial derivative that is identically zero stays an exact 0, so structural zeros of a Jacobian
    (a variable that a component does not depend on) stay sign-definite for the decompositions.
    """
    mask = _zero(sources[0])
    for s in sources[1:]:
        mask = mask & _zero(s)
    if not np.any(mask):
        return d
    return Interval._raw(np.where(mask, 0.0, d.lower), np.where(mask, 0.0, d.upper))


class IntervalDual:
    """A value box and a derivative box (forward-mode automatic differentiation over intervals).

    Parameters
    ----------
    value : Interval
        Box of the value, shape ``(...)``.
    derivative : Interval
        Box of the gradient with respect to the seeded variables, shape ``(..., n)``.
    """

    __array_priority__ = 2000.0

    def __init__(self, value: Interval, derivative: Interval) -> None:
        self.value = value
        self.derivative = derivative

    @classmethod
    @shared_docs
    def variables(cls, lower: ArrayLike, upper: ArrayLike, along: int | None = None) -> list[IntervalDual]:
        """Seed the n variables of boxes ``[lower, upper]`` (shape ``(..., n)``): derivative of x_j is e_j.

        Parameters
        ----------
        %(boxes)s
        along : int, optional
            Seed only the partial derivative along variable ``along``: the derivative boxes have shape
            ``(..., 1)``, and hold the same numbers as column ``along`` of the full seed (every rule works
            on each column alone), at a fraction of the cost.

        Returns
        -------
        list of IntervalDual
            One dual per variable.

        Raises
        ------
        DimensionError
            If ``along`` is not the index of a variable.
        """
        lo = np.asarray(lower, dtype=float)
        hi = np.asarray(upper, dtype=float)
        n = lo.shape[-1]
        eye = np.eye(n)
        if along is not None:
            if not 0 <= along < n:
                raise DimensionError(f"along: expected a variable index in 0..{n - 1}, got {along}")
            eye = eye[:, [along]]
        out = []
        for j in range(n):
            seed = np.broadcast_to(eye[j], (*lo.shape[:-1], eye.shape[1]))
            out.append(cls(Interval(lo[..., j], hi[..., j]), Interval._raw(seed, seed)))
        return out

    def __repr__(self) -> str:
        return f"IntervalDual(value={self.value!r}, derivative={self.derivative!r})"

    # --- arithmetic ----------------------------------------------------------------------------------
    def __neg__(self) -> IntervalDual:
        return IntervalDual(-self.value, -self.derivative)

    def __pos__(self) -> IntervalDual:
        return self

    def __add__(self, other: Any) -> IntervalDual:
        if isinstance(other, IntervalDual):
            d = _keep_zeros(self.derivative + other.derivative, self.derivative, other.derivative)
            return IntervalDual(self.value + other.value, d)
        return IntervalDual(self.value + other, self.derivative)

    __radd__ = __add__

    def __sub__(self, other: Any) -> IntervalDual:
        if isinstance(other, IntervalDual):
            d = _keep_zeros(self.derivative - other.derivative, self.derivative, other.derivative)
            return IntervalDual(self.value - other.value, d)
        return IntervalDual(self.value - other, self.derivative)

    def __rsub__(self, other: Any) -> IntervalDual:
        return IntervalDual(other - self.value, -self.derivative)

    def __mul__(self, other: Any) -> IntervalDual:
        if isinstance(other, IntervalDual):
            d = self.derivative * _col(other.value) + _col(self.value) * other.derivative
            return IntervalDual(self.value * other.value, _keep_zeros(d, self.derivative, other.derivative))
        c = Interval._wrap(other)
        return IntervalDual(self.value * c, _keep_zeros(self.derivative * _col(c), self.derivative))

    __rmul__ = __mul__

    def __truediv__(self, other: Any) -> IntervalDual:
        if isinstance(other, IntervalDual):
            quotient = self.value / other.value
            numerator = self.derivative - _col(quotient) * other.derivative
            d = numerator * _col(other.value.reciprocal())
            return IntervalDual(quotient, _keep_zeros(d, self.derivative, other.derivative))
        inverse = Interval._wrap(other).reciprocal()
        return IntervalDual(self.value * inverse, _keep_zeros(self.derivative * _col(inverse), self.derivative))

    def __rtruediv__(self, other: Any) -> IntervalDual:
        quotient = Interval._wrap(other) / self.value
        d = -(self.derivative * _col(quotient * self.value.reciprocal()))
        return IntervalDual(quotient, _keep_zeros(d, self.derivative))

    def __pow__(self, exponent: int) -> IntervalDual:
        value = self.value**exponent
        if exponent == 0:
            zero = np.zeros(self.derivative.shape)
            return IntervalDual(value, Interval._raw(zero, zero))
        d = self.derivative * _col(self.value ** (exponent - 1) * float(exponent))
        return IntervalDual(value, _keep_zeros(d, self.derivative))

    # --- elementary functions through NumPy's ufunc protocol -----------------------------------------
    def __array_ufunc__(self, ufunc: Any, method: str, *inputs: Any, **kwargs: Any) -> Any:
        handler = _RULES.get(ufunc) if method == "__call__" and not kwargs else None
        return NotImplemented if handler is None else handler(*inputs)


def _chain(fn: Callable[[Interval], tuple[Interval, Interval]]) -> Callable[[IntervalDual], IntervalDual]:
    """Unary rule from ``U -> (f(U), f'(U))``."""

    def apply(u: IntervalDual) -> IntervalDual:
        value, slope = fn(u.value)
        return IntervalDual(value, _keep_zeros(u.derivative * _col(slope), u.derivative))

    return apply


def _tanh(u: Interval) -> tuple[Interval, Interval]:
    t = np.tanh(u)
    s = 1.0 - t * t
    return t, Interval._raw(np.maximum(s.lower, 0.0), np.minimum(s.upper, 1.0))


def _sqrt(u: Interval) -> tuple[Interval, Interval]:
    r = np.sqrt(u)
    return r, _reciprocal_nonnegative(r) * 0.5


def _abs(u: Interval) -> tuple[Interval, Interval]:
    low = np.where(u.lower > 0, 1.0, -1.0)
    high = np.where(u.upper < 0, -1.0, 1.0)
    return np.absolute(u), Interval._raw(low, high)


def _exp(u: Interval) -> tuple[Interval, Interval]:
    e = np.exp(u)
    return e, e


def _log(u: Interval) -> tuple[Interval, Interval]:
    return np.log(u), _reciprocal_nonnegative(u)


def _binary(name: str, reflected: str) -> Callable[[Any, Any], IntervalDual]:
    """``np.add(a, b)`` and friends: the dual operand's method, reflected when the dual is second."""
    return lambda a, b: getattr(a, name)(b) if isinstance(a, IntervalDual) else getattr(b, reflected)(a)


_RULES: dict[Any, Callable[..., IntervalDual]] = {
    np.sin: _chain(lambda u: (np.sin(u), np.cos(u))),
    np.cos: _chain(lambda u: (np.cos(u), -np.sin(u))),
    np.exp: _chain(_exp),
    np.log: _chain(_log),
    np.sqrt: _chain(_sqrt),
    np.tanh: _chain(_tanh),
    np.arctan: _chain(lambda u: (np.arctan(u), (1.0 + u**2).reciprocal())),
    np.absolute: _chain(_abs),
    np.square: lambda u: u**2,
    np.negative: lambda u: -u,
    np.add: _binary("__add__", "__radd__"),
    np.subtract: _binary("__sub__", "__rsub__"),
    np.multiply: _binary("__mul__", "__rmul__"),
    np.true_divide: _binary("__truediv__", "__rtruediv__"),
}


def automatic_jacobian(func: VectorFunction, n: int) -> MatrixFunction:
    """The Jacobian of a component-convention vector function, by interval forward-mode differentiation.

    Parameters
    ----------
    func : callable
        Component-convention vector function of ``n`` variables, written with the operations listed in
        the module docstring (those of :data:`intervalobs.interval.SUPPORTED_UFUNCS`).
    n : int
        Number of variables.

    Returns
    -------
    callable
        Component-convention matrix function (rows of entries). Given :class:`Interval` components it
        returns interval entries that contain every partial derivative over the box; given arrays, the
        midpoints of the (ulp-wide) enclosures at those points.
    """

    def jacobian(x: Sequence[Any]) -> list[list[Any]]:
        if len(x) != n:
            raise DimensionError(f"jacobian: expected {n} components, got {len(x)}")
        boxes = any(isinstance(c, Interval) for c in x)
        parts = [c if isinstance(c, Interval) else Interval._wrap(c) for c in x]
        lead = np.broadcast_shapes(*(p.shape for p in parts))
        lo = np.stack([np.broadcast_to(p.lower, lead) for p in parts], axis=-1)
        hi = np.stack([np.broadcast_to(p.upper, lead) for p in parts], axis=-1)
        rows = []
        for component in func(IntervalDual.variables(lo, hi)):
            if isinstance(component, IntervalDual):
                d = component.derivative
                entries: list[Any] = [d[..., j] for j in range(n)]
            else:
                entries = [Interval(np.zeros(lead)) for _ in range(n)]
            rows.append(entries if boxes else [e.centre for e in entries])
        return rows

    return jacobian


def value_and_jacobian(
    func: VectorFunction, lower: FloatArray, upper: FloatArray, size: int
) -> tuple[Interval, Interval]:
    """The boxes of a vector function and of its Jacobian over boxes, from one forward-mode pass.

    The value box is the natural interval extension (each dual's value is computed by the same
    :class:`~intervalobs.interval.Interval` operations as :func:`intervalobs.inclusion.interval_function`,
    so the two agree bit for bit); the Jacobian box is :func:`automatic_jacobian`'s, without building an
    object per entry.

    Parameters
    ----------
    func : callable
        Component-convention vector function of ``lower.shape[-1]`` variables returning ``size`` components.
    lower, upper : numpy.ndarray, shape (..., n)
        Boxes (sound ends, not validated again).
    size : int
        Number of components ``func`` returns.

    Returns
    -------
    value : Interval, shape (..., size)
    jacobian : Interval, shape (..., size, n)

    Raises
    ------
    DimensionError
        ``func`` returns another number of components.
    """
    n = lower.shape[-1]
    lead = lower.shape[:-1]
    eye = np.eye(n)
    seeds = [np.broadcast_to(eye[j], (*lead, n)) for j in range(n)]
    variables = [
        IntervalDual(Interval._raw(lower[..., j], upper[..., j]), Interval._raw(seeds[j], seeds[j])) for j in range(n)
    ]
    out = list(func(variables))
    if len(out) != size:
        raise DimensionError(f"function: expected {size} components, got {len(out)}")
    ends = [np.empty((*lead, size)) for _ in range(2)]
    slopes = [np.zeros((*lead, size, n)) for _ in range(2)]
    for i, component in enumerate(out):
        value = component.value if isinstance(component, IntervalDual) else Interval._wrap(component)
        ends[0][..., i], ends[1][..., i] = value.lower, value.upper
        if isinstance(component, IntervalDual):
            slopes[0][..., i, :], slopes[1][..., i, :] = component.derivative.lower, component.derivative.upper
    return Interval._raw(*ends), Interval._raw(*slopes)
