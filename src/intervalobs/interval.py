r"""Interval vectors and matrices: the bounds every observer is built from.

Conventions (DESIGN.md): for a real matrix :math:`A`, :math:`A^+ = \max(A, 0)` and
:math:`A^- = \max(-A, 0)`, so :math:`A = A^+ - A^-` with both parts nonnegative. For
:math:`\underline{x} \le x \le \overline{x}`,

.. math:: A^+\underline{x} - A^-\overline{x} \;\le\; Ax \;\le\; A^+\overline{x} - A^-\underline{x},

which is the exact interval hull of :math:`\{Ax\}` (seed 003, Proposition 2 / Lemma 1).

Every function works on arrays with leading axes (time, Monte Carlo runs): vectors are ``(..., n)``.

Notes
-----
**Floating-point rounding.** Sums and products are computed in ordinary round-to-nearest arithmetic,
whose error per operation is at most one unit in the last place. Instead of switching the rounding
mode (which NumPy cannot do) or carrying a full interval-arithmetic type through the hot loops
(``crival`` was evaluated: correct, but each elementary operation allocates a new interval object
and the recursion becomes several times slower), observers widen their *outputs* outward by
:func:`inflate`: a relative margin of ``ROUNDING_MARGIN`` (1e-12, i.e. about 4500 ulp) of the
magnitude involved, plus the smallest normal number. The rounding error of an n-term dot product is
at most ``n·u·Σ|a_i x_i|`` (u = 1.1e-16), and a contractive recursion accumulates at most
``1/(1-ρ)`` of it, so the margin covers recursions with ``n/(1-ρ) < 4500``; design routines round
their own constants (e.g. noise-integral bounds) upward with the same margin. This is documented in
docs/design.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import BoundsError, DimensionError

__all__ = [
    "ROUNDING_MARGIN",
    "Box",
    "inflate",
    "interval_matvec_bounds",
    "matvec_bounds",
    "neg",
    "pos",
]

FloatArray = NDArray[np.float64]

ROUNDING_MARGIN = 1e-12
"""Relative outward margin applied to computed bounds (see the module docstring)."""

_TINY = np.finfo(float).tiny


def pos(a: ArrayLike) -> FloatArray:
    """Positive part :math:`A^+ = \\max(A, 0)` (elementwise).

    Parameters
    ----------
    a : array_like
        Matrix or vector (any shape).

    Returns
    -------
    numpy.ndarray
        ``max(a, 0)``, same shape, nonnegative.
    """
    return np.maximum(np.asarray(a, dtype=float), 0.0)


def neg(a: ArrayLike) -> FloatArray:
    """Negative part :math:`A^- = \\max(-A, 0)` (elementwise), so that ``A = pos(A) - neg(A)``.

    Parameters
    ----------
    a : array_like
        Matrix or vector (any shape).

    Returns
    -------
    numpy.ndarray
        ``max(-a, 0)``, same shape, nonnegative.
    """
    return np.maximum(-np.asarray(a, dtype=float), 0.0)


def matvec_bounds(a: ArrayLike, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
    r"""Exact bounds of :math:`Ax` for a point matrix and an interval vector.

    .. math:: A^+\underline{x} - A^-\overline{x} \le Ax \le A^+\overline{x} - A^-\underline{x}

    (seed 003, Proposition 2 / Lemma 1). The bounds are attained at vertices of the box, so they are
    the interval hull of :math:`\{Ax : \underline{x} \le x \le \overline{x}\}`.

    Parameters
    ----------
    a : array_like, shape (m, n)
        Point matrix.
    lower, upper : array_like, shape (..., n)
        Interval vector; leading axes (time, runs) are carried through.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m)
    """
    a = np.asarray(a, dtype=float)
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    ap, an = pos(a), neg(a)
    return lo @ ap.T - hi @ an.T, hi @ ap.T - lo @ an.T


def interval_matvec_bounds(
    a_lower: ArrayLike, a_upper: ArrayLike, lower: ArrayLike, upper: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    r"""Exact bounds of :math:`Ax` for an interval matrix and an interval vector.

    Each term :math:`a_{ij}x_j` ranges over the hull of the four products of the ends, and the terms of
    one row involve distinct variables, so the row sums of those hulls are the exact range of
    :math:`(Ax)_i` over :math:`\underline{A} \le A \le \overline{A}`,
    :math:`\underline{x} \le x \le \overline{x}`. This is the bound of seed 002, Lemma A.1, computed
    without its case split.

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


def inflate(lower: ArrayLike, upper: ArrayLike, margin: float = ROUNDING_MARGIN) -> tuple[FloatArray, FloatArray]:
    """Widen an interval outward by a relative margin to absorb floating-point rounding.

    Parameters
    ----------
    lower, upper : array_like
        Interval ends (any shape).
    margin : float
        Relative margin, applied to ``max(|lower|, |upper|)``, plus the smallest normal number.

    Returns
    -------
    lower, upper : numpy.ndarray
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    pad = margin * np.maximum(np.abs(lo), np.abs(hi)) + _TINY
    return lo - pad, hi + pad


@dataclass(frozen=True)
class Box:
    """An interval vector ``[lower, upper]``, validated (finite, ``lower <= upper``) on construction.

    Parameters
    ----------
    lower, upper : array_like, shape (..., n)
        Ends of the box; leading axes are allowed (a box per time step or run).
    """

    lower: FloatArray
    upper: FloatArray

    def __init__(self, lower: ArrayLike, upper: ArrayLike) -> None:
        lo = np.array(lower, dtype=float)
        hi = np.array(upper, dtype=float)
        if lo.shape != hi.shape:
            raise DimensionError(f"Box: lower has shape {lo.shape}, upper has shape {hi.shape}")
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise BoundsError("Box: expected finite ends, got NaN or inf")
        if np.any(lo > hi):
            i = np.argwhere(lo > hi)[0]
            raise BoundsError(f"Box: expected lower <= upper, got lower > upper at index {tuple(int(k) for k in i)}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)

    @property
    def center(self) -> FloatArray:
        """Midpoint ``(lower + upper) / 2``."""
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
        """All ``2**n`` vertices of a single box.

        Returns
        -------
        numpy.ndarray, shape (2**n, n)
            One vertex per row; row ``k`` takes ``upper[i]`` where bit ``i`` of ``k`` is set.

        Raises
        ------
        DimensionError
            When the box has leading axes (only a single 1-D box has vertices).
        """
        if self.lower.ndim != 1:
            raise DimensionError(f"Box.vertices: expected a single box (1-D), got shape {self.lower.shape}")
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
