r"""Mixed-monotone decomposition functions and sound Jacobian bounds (Khajenejad & Yong, Definition 2, Prop. 3, (2)).

A decomposition function :math:`q_d(x, y)` of :math:`q:\mathbb{R}^n\to\mathbb{R}^m` is nondecreasing in
:math:`x`, nonincreasing in :math:`y` and satisfies :math:`q_d(x, x) = q(x)`; then for every
:math:`\underline{x}\le x\le\overline{x}` (Khajenejad & Yong, Proposition 3)

.. math:: q_d(\underline{x}, \overline{x}) \le q(x) \le q_d(\overline{x}, \underline{x}).

Jacobian-based decomposition (Yang, Mickelin & Ozay 2019, the construction the paper cites as
[16, Theorem 2] and its eq. (2)). If :math:`\partial q_i/\partial x_j \in [a_{ij}, b_{ij}]` on the box,
then

.. math:: q_{d,i}(x, y) = q_i(\zeta^i) + \textstyle\sum_j c_{ij}(x_j - y_j),

with, for each entry (discrete-time maps: the diagonal is treated like any other entry),

====================================  ===================  ======================
case                                  :math:`\zeta^i_j`    :math:`c_{ij}`
====================================  ===================  ======================
:math:`a_{ij} \ge 0` (increasing)     :math:`x_j`          0
:math:`b_{ij} \le 0` (decreasing)     :math:`y_j`          0
mixed, :math:`|a_{ij}| \le b_{ij}`    :math:`x_j`          :math:`|a_{ij}|`
mixed, :math:`|a_{ij}| > b_{ij}`      :math:`y_j`          :math:`b_{ij}`
====================================  ===================  ======================

Monotonicity follows from the sign of each partial derivative of :math:`q_{d,i}`; the mixed case picks
the cheaper of the two valid choices. Hence :math:`C_q = [c_{ij}] \ge 0` always — the paper's printed
:math:`C_f`, :math:`C_g` (with a negative entry, and not of this form) cannot come from (2).

Width. Along the segment between :math:`\zeta^i(\overline{x},\underline{x})` and
:math:`\zeta^i(\underline{x},\overline{x})` the mean-value theorem gives, componentwise,

.. math:: q_d(\overline{x}, \underline{x}) - q_d(\underline{x}, \overline{x}) \le W_q(\overline{x} - \underline{x}),
   \qquad W_{ij} = \begin{cases} b_{ij} + 2c_{ij} & \zeta_j = x_j\\ -a_{ij} + 2c_{ij} & \zeta_j = y_j\end{cases}

so :math:`\|q_d(\overline{x},\underline{x}) - q_d(\underline{x},\overline{x})\|
\le \|W_q\|\,\|\overline{x}-\underline{x}\|`.
This is the sound replacement of the paper's Lemma 2 constant :math:`L_q + 2\|C_q\|`, which is **not**
an upper bound in general (for :math:`q(x) = Ax` the width is :math:`|A|\Delta x` and
:math:`\||A|\| > \|A\|` is possible; see :func:`paper_lipschitz_constant`).

Vertex decomposition. If each :math:`q_i` is monotone in each argument on the box (every Jacobian
entry sign-stable), :math:`q_{d,i}(x, y) = q_i(\zeta^i)` with :math:`c = 0` is tight:
:math:`q_d(\overline{x},\underline{x})` and :math:`q_d(\underline{x},\overline{x})` are the exact maximum
and minimum of :math:`q` over the box, attained at vertices.

All functions follow the component convention of :mod:`intervalobs.inclusion` and are vectorised over
leading axes (time, runs, sub-boxes). Results are widened outward by :func:`intervalobs.interval.inflate`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..errors import AssumptionError, BoundsError, DimensionError
from ..inclusion import MatrixFunction, VectorFunction, evaluate_function, interval_matrix
from ..interval import inflate

__all__ = [
    "JacobianDecomposition",
    "VertexDecomposition",
    "decomposition_bounds",
    "jacobian_bounds",
    "jacobian_decomposition_parts",
    "lipschitz_bound",
    "paper_lipschitz_constant",
    "width_matrix",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@shared_docs
def jacobian_bounds(
    jacobian: MatrixFunction,
    lower: ArrayLike,
    upper: ArrayLike,
    shape: tuple[int, int] | None = None,
    name: str = "jacobian",
) -> tuple[FloatArray, FloatArray]:
    r"""Sound elementwise bounds :math:`[a_{ij}, b_{ij}]` of a Jacobian over boxes.

    The user's Jacobian is evaluated in interval arithmetic (:mod:`intervalobs.inclusion`), so the
    bounds hold for every point of the box — unlike sampling. Infinite boxes are allowed (global
    bounds for functions with bounded derivatives, e.g. trigonometric terms).

    Parameters
    ----------
    jacobian : callable
        Component-convention matrix function: a sequence of n components to m rows of n entries.
    %(boxes)s
    %(shape_name)s

    Returns
    -------
    j_lower, j_upper : numpy.ndarray, shape (..., m, n)

    Raises
    ------
    AssumptionError
        If an entry is unbounded on the box (the function is not Lipschitz there).
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    if lo.shape != hi.shape:
        raise DimensionError(f"{name}: lower has shape {lo.shape}, upper has shape {hi.shape}")
    if np.any(lo > hi):
        raise BoundsError(f"{name}: expected lower <= upper, got lower > upper")
    j_lo, j_hi = interval_matrix(jacobian, lo, hi, shape, name)
    if not (np.all(np.isfinite(j_lo)) and np.all(np.isfinite(j_hi))):
        raise AssumptionError(f"{name}: unbounded on the box (the map is not Lipschitz there): give a bounded domain")
    return j_lo, j_hi


def lipschitz_bound(j_lower: ArrayLike, j_upper: ArrayLike) -> FloatArray:
    r"""Upper bound of :math:`\sup\|J\|_2` over an interval matrix: :math:`\|\max(|\underline J|, |\overline J|)\|_2`.

    Valid because :math:`\|J\|_2 \le \||J|\|_2` and the spectral norm is monotone on nonnegative
    matrices.

    Parameters
    ----------
    j_lower, j_upper : array_like, shape (..., m, n)
        The interval matrix (Jacobian bounds).

    Returns
    -------
    numpy.ndarray, shape (...)
        One bound per leading index.
    """
    bound = np.maximum(np.abs(np.asarray(j_lower, dtype=float)), np.abs(np.asarray(j_upper, dtype=float)))
    return inflate(0.0, np.linalg.norm(bound, ord=2, axis=(-2, -1)), floor=0.0)[1]


def jacobian_decomposition_parts(j_lower: ArrayLike, j_upper: ArrayLike) -> tuple[BoolArray, FloatArray]:
    r"""The case split of the Yang–Mickelin–Ozay decomposition: which argument feeds :math:`\zeta`, and
    :math:`C`.

    Parameters
    ----------
    j_lower, j_upper : array_like, shape (..., m, n)
        Jacobian bounds :math:`a_{ij} \le \partial q_i/\partial x_j \le b_{ij}`.

    Returns
    -------
    from_first : numpy.ndarray of bool, shape (..., m, n)
        True where :math:`\zeta^i_j` is taken from the first argument :math:`x`.
    C : numpy.ndarray, shape (..., m, n)
        The nonnegative matrix :math:`C_q` of the decomposition.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): the decomposition (2).
    """
    a = np.asarray(j_lower, dtype=float)
    b = np.asarray(j_upper, dtype=float)
    if a.shape != b.shape:
        raise DimensionError(f"jacobian bounds: lower has shape {a.shape}, upper has shape {b.shape}")
    if np.any(a > b):
        raise BoundsError("jacobian bounds: expected lower <= upper, got lower > upper")
    increasing = a >= 0
    decreasing = (b <= 0) & ~increasing
    mixed = ~increasing & ~decreasing
    first = increasing | (mixed & (-a <= b))
    c = np.where(mixed & first, -a, 0.0) + np.where(mixed & ~first, b, 0.0)
    return first, c


def width_matrix(j_lower: ArrayLike, j_upper: ArrayLike) -> FloatArray:
    r"""Nonnegative :math:`W_q`: :math:`q_d(\overline x,\underline x) - q_d(\underline x,\overline x) \le W_q\Delta x`.

    See the module docstring.

    Parameters
    ----------
    j_lower, j_upper : array_like, shape (..., m, n)
        Jacobian bounds, as from :func:`jacobian_bounds`.

    Returns
    -------
    numpy.ndarray, shape (..., m, n)
    """
    a = np.asarray(j_lower, dtype=float)
    b = np.asarray(j_upper, dtype=float)
    first, c = jacobian_decomposition_parts(a, b)
    return np.where(first, b, -a) + 2.0 * c


def paper_lipschitz_constant(lipschitz: float, c: ArrayLike) -> float:
    r"""Khajenejad & Yong's Lipschitz-like constant :math:`L_{q_d} = L_q + 2\|C_q\|_2` (for comparison only).

    It is not a valid bound of the decomposition width in general: for :math:`q(x) = Ax` with
    :math:`A = [[1, 1], [1, -1]]`, :math:`C = 0`, :math:`L_q = \sqrt 2`, but the width is
    :math:`|A|\Delta x`, of norm :math:`2\|\Delta x\|` for :math:`\Delta x = (1, 1)`. Use
    :func:`width_matrix` (its spectral norm) instead.

    Parameters
    ----------
    lipschitz : float
        Lipschitz constant :math:`L_q`.
    c : array_like, shape (m, n)
        The matrix :math:`C_q` of the decomposition.

    Returns
    -------
    float

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): Lemma 2, the decomposition (2).
    """
    return float(lipschitz + 2.0 * np.linalg.norm(np.asarray(c, dtype=float), ord=2))


def _diagonal_evaluate(func: VectorFunction, points: FloatArray, m: int, name: str) -> FloatArray:
    """Evaluate ``func`` at ``points`` (..., m, n) and keep component i of the i-th point."""
    values = evaluate_function(func, points, m, name)
    return np.asarray(np.diagonal(values, axis1=-2, axis2=-1))


def decomposition_bounds(
    func: VectorFunction,
    lower: ArrayLike,
    upper: ArrayLike,
    j_lower: ArrayLike,
    j_upper: ArrayLike,
    name: str = "function",
) -> tuple[FloatArray, FloatArray]:
    r"""Bounds :math:`q_d(\underline x, \overline x) \le q(x) \le q_d(\overline x, \underline x)`.

    Parameters
    ----------
    func : callable
        Component-convention vector function :math:`q`.
    lower, upper : array_like, shape (..., n)
        Boxes.
    j_lower, j_upper : array_like, shape (m, n) or (..., m, n)
        Jacobian bounds valid on the boxes (global ones, or local ones per box).
    name : str
        Name used in error messages.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., m)
        Outward-rounded.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): Proposition 3 with the decomposition (2).
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    first, c = jacobian_decomposition_parts(j_lower, j_upper)
    m = first.shape[-2]
    zeta_hi = np.where(first, hi[..., None, :], lo[..., None, :])
    zeta_lo = np.where(first, lo[..., None, :], hi[..., None, :])
    spread = np.einsum("...ij,...j->...i", c, hi - lo)
    up = _diagonal_evaluate(func, zeta_hi, m, name) + spread
    down = _diagonal_evaluate(func, zeta_lo, m, name) - spread
    return inflate(down, up)


@dataclass(frozen=True)
class JacobianDecomposition:
    r"""Yang–Mickelin–Ozay decomposition function with fixed Jacobian bounds.

    Parameters
    ----------
    func : callable
        Component-convention vector function :math:`q:\mathbb{R}^n\to\mathbb{R}^m`.
    j_lower, j_upper : numpy.ndarray, shape (m, n)
        Bounds of its Jacobian, valid on the domain where the decomposition is used.

    Attributes
    ----------
    from_first : numpy.ndarray of bool
        Where :math:`\zeta_j` is the first argument.
    C : numpy.ndarray
        :math:`C_q \ge 0` of the decomposition.
    W : numpy.ndarray
        Width matrix (see :func:`width_matrix`).
    lipschitz_width : float
        :math:`\|W\|_2`, the sound "Lipschitz-like" constant of the decomposition.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): the decomposition (2); the constant of Lemma 2.
    """

    func: VectorFunction
    j_lower: FloatArray
    j_upper: FloatArray

    def __post_init__(self) -> None:
        lo = np.array(self.j_lower, dtype=float)
        hi = np.array(self.j_upper, dtype=float)
        if lo.ndim != 2 or lo.shape != hi.shape:
            raise DimensionError(f"JacobianDecomposition: expected two (m, n) bounds, got {lo.shape} and {hi.shape}")
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise AssumptionError("JacobianDecomposition: Jacobian bounds must be finite (a Lipschitz map on the box)")
        object.__setattr__(self, "j_lower", lo)
        object.__setattr__(self, "j_upper", hi)

    @classmethod
    def from_jacobian(
        cls, func: VectorFunction, jacobian: MatrixFunction, lower: ArrayLike, upper: ArrayLike
    ) -> JacobianDecomposition:
        """Build from a user Jacobian bounded by interval evaluation over the domain ``[lower, upper]``.

        Parameters
        ----------
        func : callable
            Component-convention vector function.
        jacobian : callable
            Its Jacobian (rows of entries).
        lower, upper : array_like, shape (n,)
            Domain (infinite ends allowed).

        Returns
        -------
        JacobianDecomposition
        """
        j_lo, j_hi = jacobian_bounds(jacobian, lower, upper)
        return cls(func, j_lo, j_hi)

    @property
    def from_first(self) -> BoolArray:
        """Where :math:`\\zeta^i_j = x_j`."""
        return jacobian_decomposition_parts(self.j_lower, self.j_upper)[0]

    @property
    def C(self) -> FloatArray:
        """:math:`C_q` of the decomposition.

        References
        ----------
        Khajenejad & Yong (:mod:`intervalobs.references`): the decomposition (2).
        """
        return jacobian_decomposition_parts(self.j_lower, self.j_upper)[1]

    @property
    def W(self) -> FloatArray:
        """Width matrix :math:`W_q`."""
        return width_matrix(self.j_lower, self.j_upper)

    @property
    def lipschitz_width(self) -> float:
        """:math:`\\|W_q\\|_2`."""
        return float(inflate(0.0, np.linalg.norm(self.W, ord=2), floor=0.0)[1])

    @shared_docs
    def __call__(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        r"""Evaluate :math:`q_d(x, y)` (no rounding margin; for analysis and tests).

        %(pair_arguments)s
        """
        xa = np.asarray(x, dtype=float)
        ya = np.asarray(y, dtype=float)
        first, c = self.from_first, self.C
        zeta = np.where(first, xa[..., None, :], ya[..., None, :])
        return _diagonal_evaluate(self.func, zeta, first.shape[0], "function") + (xa - ya) @ c.T

    @shared_docs
    def bounds(self, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Outward-rounded :math:`(q_d(\\underline x, \\overline x), q_d(\\overline x, \\underline x))`.

        %(boxes_range)s
        """
        return decomposition_bounds(self.func, lower, upper, self.j_lower, self.j_upper)


@dataclass(frozen=True)
class VertexDecomposition:
    r"""Tight decomposition of a function monotone in each argument: :math:`q_{d,i}(x, y) = q_i(\zeta^i)`.

    Parameters
    ----------
    func : callable
        Component-convention vector function.
    signs : array_like, shape (m, n)
        +1 where :math:`q_i` is nondecreasing in :math:`x_j`, -1 where nonincreasing (0: independent).
    """

    func: VectorFunction
    signs: FloatArray

    def __post_init__(self) -> None:
        s = np.array(self.signs, dtype=float)
        if s.ndim != 2 or not np.all(np.isin(s, (-1.0, 0.0, 1.0))):
            raise DimensionError("VertexDecomposition: signs must be an (m, n) array of -1, 0, +1")
        object.__setattr__(self, "signs", s)

    @classmethod
    def from_jacobian_bounds(cls, func: VectorFunction, j_lower: ArrayLike, j_upper: ArrayLike) -> VertexDecomposition:
        """Signs from Jacobian bounds; raises ``AssumptionError`` if an entry changes sign on the domain.

        Parameters
        ----------
        func : callable
            Component-convention vector function.
        j_lower, j_upper : array_like, shape (m, n)
            Jacobian bounds on the domain.

        Returns
        -------
        VertexDecomposition
        """
        a = np.asarray(j_lower, dtype=float)
        b = np.asarray(j_upper, dtype=float)
        mixed = (a < 0) & (b > 0)
        if np.any(mixed):
            i, j = (int(k) for k in np.argwhere(mixed)[0])
            raise AssumptionError(
                f"VertexDecomposition: dq_{i + 1}/dx_{j + 1} takes both signs on the domain "
                f"([{a[i, j]:.3g}, {b[i, j]:.3g}]): the function is not monotone in each argument"
            )
        return cls(func, np.where(a >= 0, np.where(b > 0, 1.0, 0.0), -1.0))

    @shared_docs
    def __call__(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """Evaluate :math:`q_d(x, y)`.

        %(pair_arguments)s
        """
        xa = np.asarray(x, dtype=float)
        ya = np.asarray(y, dtype=float)
        zeta = np.where(self.signs >= 0, xa[..., None, :], ya[..., None, :])
        return _diagonal_evaluate(self.func, zeta, self.signs.shape[0], "function")

    @shared_docs
    def bounds(self, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """The exact range of ``func`` over the boxes, outward-rounded.

        %(boxes_range)s
        """
        return inflate(self(lower, upper), self(upper, lower))
