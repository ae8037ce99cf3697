r"""The interval type and the two rounding policies: the bottom layer every bound is built from.

**Interval vectors and matrices.** :class:`Interval` holds elementwise ``lower``/``upper`` arrays of
any shape, so leading axes (time, Monte Carlo runs, sub-boxes) are carried through without a Python
loop: a vector is ``(..., n)``, a matrix ``(..., m, n)``. Infinite ends are allowed; NaN ends and
``lower > upper`` are refused on construction.

Conventions (DESIGN.md): for a real matrix :math:`A`, :math:`A^+ = \max(A, 0)` and
:math:`A^- = \max(-A, 0)`, so :math:`A = A^+ - A^-` with both parts nonnegative. For
:math:`\underline{x} \le x \le \overline{x}`,

.. math:: A^+\underline{x} - A^-\overline{x} \;\le\; Ax \;\le\; A^+\overline{x} - A^-\underline{x},

which is the exact interval hull of :math:`\{Ax\}` (Khajenejad & Yong, Proposition 2 / Lemma 1);
:func:`matvec_bounds` and :func:`interval_matvec_bounds` compute it (and its interval-matrix form) on
plain arrays for the observers' hot loops, and ``A @ x`` computes it on :class:`Interval` objects.

Notes
-----
**Floating-point rounding: two policies.** Sums and products are computed in ordinary
round-to-nearest arithmetic, whose error per operation is at most half a unit in the last place
(relative :math:`u = 2^{-53} \approx 1.1\cdot 10^{-16}`). NumPy cannot switch the rounding mode, so
every computed bound is widened outward by one of two named functions; no other rounding pad exists
in the library.

1. **Per-operation outward rounding**, :func:`round_outward`, for inclusion functions
   (:class:`Interval` arithmetic, the elementary functions, interval forward-mode differentiation):
   each end of a correctly rounded operation is moved one floating-point number outward
   (``nextafter``), which contains the exact result because the rounded value is within half an ulp
   of it. Library functions accurate to about one ulp (``sin``, ``exp``, ``x**k``) are moved two. A
   sum of :math:`k` nonnegative computed terms is within :math:`(k-1)u` of its exact value relative,
   and each ulp of the result is at least :math:`u` of it relative, so ``ulps=k`` covers it.
   ``A @ x`` on :class:`Interval` objects pads the row sums by the dot-product bound
   :math:`|\mathrm{fl}(a^\top x) - a^\top x| \le \gamma_n |a|^\top|x|`,
   :math:`\gamma_n = nu/(1 - nu)` (Higham 2002, Section 3.1) before rounding outward.
2. **Output inflation for linear recursions**, :func:`inflate`: the observers' recursions run on
   plain arrays in round-to-nearest (carrying an interval type through them would cost far more than
   the recursion: ``crival``'s IEEE 1788 intervals allocate an object per operation), and their
   *outputs* are widened by a relative margin of the magnitude involved plus the smallest normal
   number. The rounding error of an :math:`n`-term dot product is at most :math:`\gamma_n` of
   :math:`\sum|a_i x_i|`; one step of a framer or tube recursion is a :math:`2n`-term dot product
   (:math:`A^+\underline{x} - A^-\overline{x}`) plus a few additions, so its error is below
   :math:`8 n\,\varepsilon` (:math:`\varepsilon = 2u`) of the magnitude; a recursion contracting at
   rate :math:`\rho` accumulates at most :math:`1/(1-\rho)` of one step's error, and an evaluation
   through a change of coordinates (modal filters) amplifies it by at most the condition number of
   the coordinates. :func:`recursion_margin` returns that
   :math:`8 n \varepsilon\,\mathrm{cond}/(1-\rho)`, never below ``ROUNDING_MARGIN`` (1e-12, about
   4500 ulp), which alone covers every recursion with :math:`n\,\mathrm{cond}/(1-\rho) < 560`. Design
   routines round their constants (noise-integral bounds, norms) upward with the same function.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._docstrings import shared_docs
from .errors import AssumptionError, BoundsError, DimensionError

__all__ = [
    "ROUNDING_MARGIN",
    "SUPPORTED_UFUNCS",
    "Interval",
    "inflate",
    "interval_matvec_bounds",
    "matvec_bounds",
    "neg",
    "pos",
    "product_bounds",
    "recursion_margin",
    "round_outward",
    "sandwich_bounds",
]

FloatArray = NDArray[np.float64]

ROUNDING_MARGIN = 1e-12
"""Smallest relative margin of :func:`inflate` (see the module docstring)."""

_TINY = np.finfo(float).tiny
_EPS = float(np.finfo(float).eps)
_UNIT_ROUNDOFF = 0.5 * _EPS
_TWO_PI = 2.0 * np.pi


def round_outward(lower: ArrayLike, upper: ArrayLike, ulps: int = 1) -> tuple[FloatArray, FloatArray]:
    """Per-operation outward rounding: move each end ``ulps`` floating-point numbers outward.

    The policy of inclusion functions (module docstring, policy 1): an end computed by one
    correctly rounded operation is within half an ulp of the exact value, so one ulp outward contains
    it. Infinite ends stay infinite; an exact zero moves to the smallest subnormal.

    Parameters
    ----------
    lower, upper : array_like
        Computed ends (any shapes that broadcast).
    ulps : int
        Number of floating-point numbers to move each end (at least 1).

    Returns
    -------
    lower, upper : numpy.ndarray
        ``lower`` rounded towards ``-inf``, ``upper`` towards ``+inf``.

    Raises
    ------
    BoundsError
        If ``ulps`` is not a positive integer.
    """
    if ulps == 1:  # the common case, kept lean: it runs on every interval operation
        return np.nextafter(lower, -np.inf), np.nextafter(upper, np.inf)
    if not (isinstance(ulps, (int, np.integer)) and ulps >= 1):
        raise BoundsError(f"ulps: expected a positive integer, got {ulps!r}")
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    for _ in range(int(ulps)):
        lo, hi = np.nextafter(lo, -np.inf), np.nextafter(hi, np.inf)
    return lo, hi


def inflate(
    lower: ArrayLike,
    upper: ArrayLike,
    margin: float | FloatArray = ROUNDING_MARGIN,
    scale: ArrayLike | None = None,
    floor: float = _TINY,
) -> tuple[FloatArray, FloatArray]:
    """Output inflation of a linear recursion: widen an interval outward by a relative margin.

    The policy of the observers' outputs and of design constants (module docstring, policy 2):
    ``pad = margin * scale + floor`` is subtracted from ``lower`` and added to ``upper``.

    Parameters
    ----------
    lower, upper : array_like
        Interval ends (shapes that broadcast). A nonnegative radius ``r`` is rounded up by
        ``inflate(-r, r)[1]``.
    margin : float or numpy.ndarray
        Relative margin, at least ``ROUNDING_MARGIN`` for recursions (:func:`recursion_margin`); an array
        broadcasts against the ends (one margin per recursion along an axis).
    scale : array_like, optional
        Magnitude the rounding errors are relative to (e.g. the sum of the absolute terms that were
        added); default ``max(|lower|, |upper|)``.
    floor : float
        Absolute part of the pad: the smallest normal number by default (it covers products that
        underflow); 0 keeps exact zeros exact where the caller knows them to be structural (a sum of
        exactly zero terms).

    Returns
    -------
    lower, upper : numpy.ndarray
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    size = np.maximum(np.abs(lo), np.abs(hi)) if scale is None else np.asarray(scale, dtype=float)
    pad = margin * size + floor
    return lo - pad, hi + pad


def recursion_margin(n: int, amplification: float = 1.0, contraction: float = 0.0) -> float:
    r"""The relative margin of :func:`inflate` that covers a linear recursion's rounding.

    .. math:: \max\Big(\texttt{ROUNDING\_MARGIN},\; \frac{8 n \varepsilon\, \mathrm{cond}}{1 - \rho}\Big)

    (module docstring, policy 2): ``8 n eps`` bounds one step's rounding relative to the magnitude of
    its terms, a recursion contracting at rate :math:`\rho` accumulates at most :math:`1/(1-\rho)`
    steps of it, and an evaluation in other coordinates amplifies it by their condition number.

    Parameters
    ----------
    n : int
        State dimension (terms per row of one step).
    amplification : float
        Condition number of the coordinates the recursion is evaluated in (1 for the identity).
    contraction : float
        Contraction rate :math:`\rho` of the recursion (spectral radius), in ``[0, 1)``.

    Returns
    -------
    float

    Raises
    ------
    AssumptionError
        If ``contraction`` is not in ``[0, 1)`` or ``amplification < 1``.
    """
    if not 0.0 <= contraction < 1.0:
        raise AssumptionError(f"contraction: expected a rate in [0, 1), got {contraction!r}")
    if not amplification >= 1.0:
        raise AssumptionError(f"amplification: expected a condition number >= 1, got {amplification!r}")
    return max(ROUNDING_MARGIN, 8 * int(n) * _EPS * float(amplification) / (1.0 - float(contraction)))


@shared_docs
def pos(a: ArrayLike) -> FloatArray:
    """Positive part :math:`A^+ = \\max(A, 0)` (elementwise).

    %(any_array)s

    Returns
    -------
    numpy.ndarray
        ``max(a, 0)``, same shape, nonnegative.
    """
    return np.maximum(np.asarray(a, dtype=float), 0.0)


@shared_docs
def neg(a: ArrayLike) -> FloatArray:
    """Negative part :math:`A^- = \\max(-A, 0)` (elementwise), so that ``A = pos(A) - neg(A)``.

    %(any_array)s

    Returns
    -------
    numpy.ndarray
        ``max(-a, 0)``, same shape, nonnegative.
    """
    return np.maximum(-np.asarray(a, dtype=float), 0.0)


def matvec_bounds(a: ArrayLike, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
    r"""Exact bounds of :math:`Ax` for a point matrix and an interval vector (round to nearest).

    .. math:: A^+\underline{x} - A^-\overline{x} \le Ax \le A^+\overline{x} - A^-\underline{x}

    The bounds are attained at vertices of the box, so they are
    the interval hull of :math:`\{Ax : \underline{x} \le x \le \overline{x}\}`. Computed in
    round-to-nearest for the hot loops, whose outputs :func:`inflate` widens; ``a @ Interval(lower,
    upper)`` is the outward-rounded form.

    Parameters
    ----------
    a : array_like, shape (m, n) or (..., m, n)
        Point matrix; a matrix with leading axes is applied to the vectors of the same leading index.
    lower, upper : array_like, shape (..., n)
        Interval vector; leading axes (time, runs) are carried through.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m)

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`), Proposition 2 / Lemma 1.
    """
    a = np.asarray(a, dtype=float)
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    ap, an = pos(a), neg(a)
    if a.ndim > 2:
        rows = "...ij,...j->...i"
        return (
            np.einsum(rows, ap, lo) - np.einsum(rows, an, hi),
            np.einsum(rows, ap, hi) - np.einsum(rows, an, lo),
        )
    return lo @ ap.T - hi @ an.T, hi @ ap.T - lo @ an.T


def sandwich_bounds(
    p: ArrayLike, j_lower: ArrayLike, j_upper: ArrayLike, q: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    r"""Bounds of :math:`PJQ` for point matrices :math:`P, Q` and an interval matrix :math:`J` (round to nearest).

    :func:`matvec_bounds` twice: first :math:`PJ` column by column (exact), then its rows times :math:`Q`
    (the hull of the interval rows' images, exact for each entry separately).

    Parameters
    ----------
    p : array_like, shape (..., r, j)
        Left point matrix (leading axes allowed).
    j_lower, j_upper : array_like, shape (..., j, k)
        Interval matrix.
    q : array_like, shape (k, c)
        Right point matrix.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., r, c)
    """
    pa = np.asarray(p, dtype=float)
    jl = np.swapaxes(np.asarray(j_lower, dtype=float), -1, -2)
    jh = np.swapaxes(np.asarray(j_upper, dtype=float), -1, -2)
    cols_lo, cols_hi = matvec_bounds(pa[..., None, :, :], jl, jh)  # (..., k, r): the columns of PJ
    return matvec_bounds(np.asarray(q, dtype=float).T, np.swapaxes(cols_lo, -1, -2), np.swapaxes(cols_hi, -1, -2))


def interval_matvec_bounds(
    a_lower: ArrayLike, a_upper: ArrayLike, lower: ArrayLike, upper: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    r"""Exact bounds of :math:`Ax` for an interval matrix and an interval vector (round to nearest).

    Each term :math:`a_{ij}x_j` ranges over the hull of the four products of the ends, and the terms of
    one row involve distinct variables, so the row sums of those hulls are the exact range of
    :math:`(Ax)_i` over :math:`\underline{A} \le A \le \overline{A}`,
    :math:`\underline{x} \le x \le \overline{x}`. This is the bound of the integrated-observer paper, Lemma A.1,
    computed without its case split. ``Interval(a_lower, a_upper) @ Interval(lower, upper)`` is the
    outward-rounded form.

    Parameters
    ----------
    a_lower, a_upper : array_like, shape (m, n)
        Interval matrix.
    lower, upper : array_like, shape (..., n)
        Interval vector; leading axes are carried through.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m)
    """
    al = np.asarray(a_lower, dtype=float)
    au = np.asarray(a_upper, dtype=float)
    lo = np.asarray(lower, dtype=float)[..., None, :]
    hi = np.asarray(upper, dtype=float)[..., None, :]
    products = np.stack([al * lo, al * hi, au * lo, au * hi])
    return products.min(axis=0).sum(axis=-1), products.max(axis=0).sum(axis=-1)


def product_bounds(
    a_lower: ArrayLike, a_upper: ArrayLike, b_lower: ArrayLike, b_upper: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Exact bounds of the elementwise product of two interval arrays with finite ends (round to nearest).

    The hull of the four products of the ends (broadcasting). The array form for hot loops whose outputs
    :func:`inflate` widens; ``Interval(a_lower, a_upper) * Interval(b_lower, b_upper)`` is the
    outward-rounded form (which also takes infinite ends, with ``0 * inf = 0``).

    Parameters
    ----------
    a_lower, a_upper, b_lower, b_upper : array_like
        Ends of the two factors (shapes that broadcast).

    Returns
    -------
    lower, upper : numpy.ndarray
    """
    alo, ahi = np.asarray(a_lower, dtype=float), np.asarray(a_upper, dtype=float)
    blo, bhi = np.asarray(b_lower, dtype=float), np.asarray(b_upper, dtype=float)
    p1, p2, p3, p4 = alo * blo, alo * bhi, ahi * blo, ahi * bhi
    return np.minimum(np.minimum(p1, p2), np.minimum(p3, p4)), np.maximum(np.maximum(p1, p2), np.maximum(p3, p4))


def _product_hull(alo: FloatArray, ahi: FloatArray, blo: FloatArray, bhi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """:func:`product_bounds` for ends that may be infinite: ``0 * inf = 0`` (a NaN product).

    A point factor (the same array as both ends, as ``Interval._wrap`` and the seeds of forward-mode
    differentiation build it) has two distinct products, not four: the same hull with half the operations.
    """
    with np.errstate(invalid="ignore"):
        if alo is ahi or blo is bhi:
            first, second = (alo * blo, alo * bhi) if alo is ahi else (alo * blo, ahi * blo)
            low, high = np.minimum(first, second), np.maximum(first, second)
        else:
            low, high = product_bounds(alo, ahi, blo, bhi)
    if np.isnan(low).any():  # np.minimum and np.maximum both propagate a NaN product
        with np.errstate(invalid="ignore"):
            p1, p2, p3, p4 = (np.where(np.isnan(v), 0.0, v) for v in (alo * blo, alo * bhi, ahi * blo, ahi * bhi))
        low = np.minimum(np.minimum(p1, p2), np.minimum(p3, p4))
        high = np.maximum(np.maximum(p1, p2), np.maximum(p3, p4))
    return low, high


def _first_index(mask: NDArray[np.bool_]) -> tuple[int, ...]:
    return tuple(int(k) for k in np.argwhere(mask)[0])


class Interval:
    """An elementwise interval ``[lower, upper]`` of arrays, with outward-rounded arithmetic.

    Leading axes (time, Monte Carlo runs) are carried through every operation. ``+ - * /``, integer
    powers and the NumPy functions of :data:`SUPPORTED_UFUNCS` take scalars, arrays and intervals
    and return intervals containing every value the operation takes on the operands' boxes (the
    natural extension), rounded outward by :func:`round_outward`. ``A @ x`` applies a point or
    interval matrix ``A`` (shape ``(..., m, n)``) to the vectors along the last axis of ``x``
    (shape ``(..., n)``): the exact hull of :func:`matvec_bounds` / :func:`interval_matvec_bounds`,
    padded by the dot-product rounding bound.

    Parameters
    ----------
    lower : array_like
        Lower ends.
    upper : array_like, optional
        Upper ends, broadcast against ``lower`` (default: the point interval ``[lower, lower]``).
        Infinite ends are allowed; NaN ends and ``lower > upper`` are refused.

    Raises
    ------
    DimensionError
        If the shapes of ``lower`` and ``upper`` do not broadcast.
    BoundsError
        If an end is NaN or ``lower > upper`` somewhere.
    """

    __array_priority__ = 1000.0

    def __init__(self, lower: ArrayLike, upper: ArrayLike | None = None) -> None:
        lo = np.asarray(lower, dtype=float)
        hi = lo if upper is None else np.asarray(upper, dtype=float)
        if lo.shape != hi.shape:
            try:
                lo, hi = np.broadcast_arrays(lo, hi)
            except ValueError:
                raise DimensionError(
                    f"upper: expected a shape that broadcasts with lower's {lo.shape}, got {hi.shape}"
                ) from None
        for name, end in (("lower", lo), ("upper", hi)):
            if np.isnan(end).any():
                raise BoundsError(f"{name}: expected no NaN, got NaN at index {_first_index(np.isnan(end))}")
        if (lo > hi).any():
            i = _first_index(lo > hi)
            raise BoundsError(
                f"lower: expected lower <= upper, got lower {float(lo[i])!r} > upper {float(hi[i])!r} at index {i}"
            )
        self.lower: FloatArray = np.array(lo)
        self.upper: FloatArray = np.array(hi)

    @classmethod
    def _raw(cls, lo: FloatArray, hi: FloatArray) -> Interval:
        """Build without validation (ends computed by a sound operation)."""
        out = cls.__new__(cls)
        out.lower, out.upper = lo, hi
        return out

    @staticmethod
    def _wrap(value: Any) -> Interval:
        if isinstance(value, Interval):
            return value
        v = np.asarray(value, dtype=float)
        return Interval._raw(v, v)

    # --- shape and size -------------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the ends."""
        return tuple(self.lower.shape)

    @property
    def centre(self) -> FloatArray:
        """Midpoint ``(lower + upper) / 2`` (NaN where an end is infinite)."""
        with np.errstate(invalid="ignore"):
            return 0.5 * (self.lower + self.upper)

    @property
    def radius(self) -> FloatArray:
        """Half-width ``(upper - lower) / 2``."""
        return 0.5 * (self.upper - self.lower)

    @property
    def width(self) -> FloatArray:
        """Width ``upper - lower``."""
        return self.upper - self.lower

    def vertices(self) -> FloatArray:
        """All ``2**n`` vertices of a single box (finite ends).

        Returns
        -------
        numpy.ndarray, shape (2**n, n)
            One vertex per row; row ``k`` takes ``upper[i]`` where bit ``i`` of ``k`` is set.

        Raises
        ------
        DimensionError
            When the interval is not a single vector (1-D).
        """
        if self.lower.ndim != 1:
            raise DimensionError(f"vertices: expected a single box (1-D), got shape {self.lower.shape}")
        n = self.lower.size
        corners = (np.arange(2**n)[:, None] >> np.arange(n)) & 1
        return np.where(corners == 1, self.upper, self.lower)

    def contains(self, x: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point lies in the box (last axis reduced).

        Parameters
        ----------
        x : array_like, shape (..., n)
            Points; leading axes broadcast against the box's.

        Returns
        -------
        numpy.ndarray of bool, shape (...)
        """
        xa = np.asarray(x, dtype=float)
        return np.all((self.lower <= xa) & (xa <= self.upper), axis=-1)

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
        return Interval._raw(*round_outward(self.lower + o.lower, self.upper + o.upper))

    __radd__ = __add__

    def __sub__(self, other: Any) -> Interval:
        o = Interval._wrap(other)
        return Interval._raw(*round_outward(self.lower - o.upper, self.upper - o.lower))

    def __rsub__(self, other: Any) -> Interval:
        return Interval._wrap(other) - self

    def __mul__(self, other: Any) -> Interval:
        if isinstance(other, Interval):
            return Interval._raw(*round_outward(*_product_hull(self.lower, self.upper, other.lower, other.upper)))
        c = np.asarray(other, dtype=float)
        if c.ndim == 0 and c != 0.0 and np.isfinite(c):  # a finite nonzero number: no 0 * inf to mend
            a, b = c * self.lower, c * self.upper
            return Interval._raw(*round_outward(np.minimum(a, b), np.maximum(a, b)))
        with np.errstate(invalid="ignore"):
            a, b = c * self.lower, c * self.upper
        if not (np.isfinite(a).all() and np.isfinite(b).all()):  # an infinite end: 0 * inf = 0
            a, b = np.where(np.isnan(a), 0.0, a), np.where(np.isnan(b), 0.0, b)
        return Interval._raw(*round_outward(np.minimum(a, b), np.maximum(a, b)))

    __rmul__ = __mul__

    def reciprocal(self) -> Interval:
        """``1 / self``; the interval must not contain zero.

        Returns
        -------
        Interval

        Raises
        ------
        BoundsError
            If an element contains 0.
        """
        if np.any((self.lower <= 0) & (self.upper >= 0)):
            raise BoundsError(
                "divisor: expected an interval excluding 0, got one that contains 0 at index "
                f"{_first_index((self.lower <= 0) & (self.upper >= 0))}"
            )
        return Interval._raw(*round_outward(1.0 / self.upper, 1.0 / self.lower))

    def __truediv__(self, other: Any) -> Interval:
        return self * Interval._wrap(other).reciprocal()

    def __rtruediv__(self, other: Any) -> Interval:
        return Interval._wrap(other) * self.reciprocal()

    def __pow__(self, exponent: int) -> Interval:
        if not isinstance(exponent, (int, np.integer)) or exponent < 0:
            raise BoundsError(f"exponent: expected a nonnegative integer, got {exponent!r}")
        if exponent == 0:
            return Interval(np.ones_like(self.lower))
        lo_p, hi_p = self.lower**exponent, self.upper**exponent
        if exponent % 2 == 1:
            return Interval._raw(*round_outward(lo_p, hi_p, 2))
        has_zero = (self.lower <= 0) & (self.upper >= 0)
        low, high = round_outward(np.where(has_zero, 0.0, np.minimum(lo_p, hi_p)), np.maximum(lo_p, hi_p), 2)
        return Interval._raw(np.maximum(low, 0.0), high)

    def __matmul__(self, vector: Any) -> Interval:
        """``self @ vector``: this interval matrix (..., m, n) applied to vectors (..., n)."""
        v = Interval._wrap(vector)
        return _matvec(self.lower, self.upper, v.lower, v.upper)

    def __rmatmul__(self, matrix: Any) -> Interval:
        """``matrix @ self``: a point matrix (..., m, n) applied to this interval vector (..., n)."""
        a = np.asarray(matrix, dtype=float)
        return _matvec(a, a, self.lower, self.upper)

    # --- elementary functions through NumPy's ufunc protocol -----------------------------------------
    def __array_ufunc__(self, ufunc: Any, method: str, *inputs: Any, **kwargs: Any) -> Any:
        if method != "__call__" or kwargs:
            return NotImplemented
        handler = _UFUNCS.get(ufunc)
        if handler is None:
            return NotImplemented
        return handler(*inputs)


def __getattr__(name: str) -> Any:
    """``Box``, the former name of :class:`Interval`: the class, with a ``FutureWarning``.

    .. deprecated:: 0.2.0
       ``Box`` goes in the next release; use :class:`Interval`.
    """
    if name != "Box":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn(
        "intervalobs.interval.Box is deprecated and goes in the next release: use Interval", FutureWarning, stacklevel=2
    )
    return Interval


def _matvec(alo: FloatArray, ahi: FloatArray, xlo: FloatArray, xhi: FloatArray) -> Interval:
    """Outward-rounded hull of ``A x`` over an interval matrix and an interval vector (batched)."""
    if alo.ndim < 2 or alo.shape[-1] != xlo.shape[-1]:
        raise DimensionError(f"matrix: expected shape (..., m, {xlo.shape[-1]}), got {alo.shape}")
    t_lo, t_hi = _product_hull(alo, ahi, xlo[..., None, :], xhi[..., None, :])
    n = t_lo.shape[-1]
    gamma = 2 * (n + 2) * _UNIT_ROUNDOFF  # > γ_{n+1}: n products, n - 1 sums, the pad's own rounding
    with np.errstate(invalid="ignore"):
        low = t_lo.sum(axis=-1) - (gamma * np.abs(t_lo).sum(axis=-1) + _TINY)
        high = t_hi.sum(axis=-1) + (gamma * np.abs(t_hi).sum(axis=-1) + _TINY)
    low, high = round_outward(np.where(np.isnan(low), -np.inf, low), np.where(np.isnan(high), np.inf, high))
    return Interval._raw(low, high)


def _contains_point(lo: FloatArray, hi: FloatArray, offset: float, period: float) -> NDArray[np.bool_]:
    """Whether ``[lo, hi]`` contains some ``offset + k*period`` (conservatively: a near miss counts)."""
    slack = _PERIOD_SLACK * (1.0 + np.abs(lo))
    k = np.ceil((lo - slack - offset) / period)
    return offset + k * period <= hi + slack


_PERIOD_SLACK = 1e-9
"""Relative slack of :func:`_contains_point`: an extremum of sin/cos counted as inside when it misses the
interval by less (the reduction ``(lo - offset) / period`` is inexact); it only widens the result."""


def _trig(fn: Callable[[FloatArray], FloatArray], top: float, bottom: float) -> Callable[[Interval], Interval]:
    """sin or cos: the ends' values, widened to ±1 where a maximum (``top``) or minimum lies inside."""

    def apply(x: Interval) -> Interval:
        lo, hi = x.lower, x.upper
        finite = np.isfinite(lo) & np.isfinite(hi)
        lo_f, hi_f = np.where(finite, lo, 0.0), np.where(finite, hi, 0.0)
        f_lo, f_hi = fn(lo_f), fn(hi_f)
        low, high = np.minimum(f_lo, f_hi), np.maximum(f_lo, f_hi)
        full = ~finite | (hi_f - lo_f >= _TWO_PI)
        high = np.where(full | _contains_point(lo_f, hi_f, top, _TWO_PI), 1.0, high)
        low = np.where(full | _contains_point(lo_f, hi_f, bottom, _TWO_PI), -1.0, low)
        low, high = round_outward(low, high, 2)
        return Interval._raw(np.maximum(low - _EPS, -1.0), np.minimum(high + _EPS, 1.0))

    return apply


def _monotone(fn: Callable[[FloatArray], FloatArray], lo_limit: float = -np.inf) -> Callable[[Interval], Interval]:
    def apply(x: Interval) -> Interval:
        if np.any(x.lower < lo_limit):
            raise BoundsError(
                f"{fn.__name__}: expected an argument >= {lo_limit:g}, got lower end {float(np.min(x.lower))!r}"
            )
        with np.errstate(over="ignore", divide="ignore"):
            return Interval._raw(*round_outward(fn(x.lower), fn(x.upper), 2))

    return apply


def _abs(x: Interval) -> Interval:
    has_zero = (x.lower <= 0) & (x.upper >= 0)
    a, b = np.abs(x.lower), np.abs(x.upper)
    return Interval._raw(np.where(has_zero, 0.0, np.minimum(a, b)), np.maximum(a, b))


def _tanh(x: Interval) -> Interval:
    low, high = round_outward(np.tanh(x.lower), np.tanh(x.upper), 2)
    return Interval._raw(np.maximum(low, -1.0), np.minimum(high, 1.0))


def _binary(
    op: Callable[[Interval, Any], Interval], reflected: Callable[[Interval, Any], Interval]
) -> Callable[..., Interval]:
    def apply(a: Any, b: Any) -> Interval:
        return op(a, b) if isinstance(a, Interval) else reflected(b, a)

    return apply


_UFUNCS: dict[Any, Callable[..., Interval]] = {
    np.sin: _trig(np.sin, 0.5 * np.pi, -0.5 * np.pi),
    np.cos: _trig(np.cos, 0.0, np.pi),
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
    np.matmul: _binary(Interval.__matmul__, Interval.__rmatmul__),
}

SUPPORTED_UFUNCS = tuple(sorted(u.__name__ for u in _UFUNCS if u is not np.matmul))
"""Elementwise NumPy functions that accept :class:`Interval` arguments (``matmul`` is ``@``)."""
