r"""Zonotopes: affine map, Minkowski sum, interval-matrix map, order reduction, interval hull, radii.

A zonotope (the integrated-observer paper, Definition A.1) is the affine image of a unit hypercube,

.. math:: \langle c, R\rangle = \{c + Rs : s \in [-1, 1]^m\},\qquad c \in \mathbb{R}^n,\ R \in \mathbb{R}^{n\times m}.

The array functions of this module (:func:`interval_matrix_image`, :func:`reduce_order`,
:func:`hull_radius`) work on centres ``(..., n)`` and generator matrices ``(..., n, m)`` with leading
axes (time, Monte Carlo runs), so observers call them in their hot loops without creating objects;
:class:`Zonotope` wraps them for a single, validated set.

Notes
-----
**Soundness.** Every operation returns a set that *contains* the exact image: Minkowski sum and linear image are
exact (Property 1, Definition A.2); the interval-matrix map (Properties 3–4) and the reduction
(Property 2) over-approximate. Property 4 of the paper adds the term of the centre as the single
generator ``diam(A)/2 · c``, which is not an enclosure of ``{ΔA c : |ΔA| ≤ diam(A)/2}`` (that set is a
box, not a segment); here the centre and the generators share one sound diagonal term (see
:func:`interval_matrix_image`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._docstrings import shared_docs
from .errors import BoundsError, DimensionError
from .validation import as_matrix, as_vector

__all__ = ["Zonotope", "hull_radius", "interval_matrix_image", "reduce_order"]

FloatArray = NDArray[np.float64]

_MAX_EXACT_GENERATORS = 20
"""Largest number of generators for which :meth:`Zonotope.w_radius` enumerates the vertices."""


def hull_radius(generators: ArrayLike) -> FloatArray:
    r"""Radius of the interval hull: the row sums :math:`\|R_i\|_1`.

    Parameters
    ----------
    generators : array_like, shape (..., n, m)

    Returns
    -------
    numpy.ndarray, shape (..., n)

    References
    ----------
    The integrated-observer paper (:mod:`intervalobs.references`), (A2) and (57).
    """
    return np.abs(np.asarray(generators, dtype=float)).sum(axis=-1)


def interval_matrix_image(
    a_lower: ArrayLike, a_upper: ArrayLike, center: ArrayLike, generators: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    r"""Zonotope enclosing :math:`\{Ax : \underline{A} \le A \le \overline{A},\ x \in \langle c, R\rangle\}`.

    With :math:`A_m = \mathrm{mid}(A)`, :math:`A_r = \mathrm{diam}(A)/2` and
    :math:`Ax = A_m x + (A - A_m)x`, the first term is the exact linear image
    :math:`\langle A_m c, A_m R\rangle` and :math:`|((A - A_m)x)_i| \le \sum_j (A_r)_{ij}|x_j|
    \le (A_r(|c| + \|R\|_1))_i`, an axis-aligned box. So

    .. math:: \langle A_m c,\ [A_m R,\ \mathrm{diag}(A_r(|c| + |R|\mathbf{1}))]\rangle

    encloses the image for every matrix in the interval matrix. This is Property 3 (the diagonal
    :math:`S_{ii} = \sum_j \mathrm{diam}((AR)_{ij})/2 = (A_r|R|\mathbf 1)_i`) and Property 4 of
    the integrated-observer paper, with the centre's term made a box: the paper's single generator ``diam(A)/2 · c``
    only covers the matrices whose deviation is proportional to ``diam(A)``.

    Parameters
    ----------
    a_lower, a_upper : array_like, shape (n, n_in)
        Interval matrix.
    center : array_like, shape (..., n_in)
        Centres (leading axes allowed).
    generators : array_like, shape (..., n_in, m)
        Generator matrices.

    Returns
    -------
    center, generators : numpy.ndarray, shapes (..., n) and (..., n, m + n)
    """
    al = np.asarray(a_lower, dtype=float)
    au = np.asarray(a_upper, dtype=float)
    c = np.asarray(center, dtype=float)
    g = np.asarray(generators, dtype=float)
    a_mid = 0.5 * (al + au)
    a_rad = 0.5 * (au - al)
    box = (np.abs(c) + hull_radius(g)) @ a_rad.T
    diag = box[..., :, None] * np.eye(al.shape[0])
    return c @ a_mid.T, np.concatenate([a_mid @ g, diag], axis=-1)


def reduce_order(generators: ArrayLike, order: int) -> FloatArray:
    r"""Combastel's reduction :math:`\downarrow_q` (the integrated-observer paper, Property 2): at most ``order``
    generators.

    The columns are sorted by decreasing Euclidean norm; the ``order - n`` largest are kept and the
    others are replaced by the box of their interval hull, ``diag(|R_small| 1)``, so that
    :math:`\langle c, R\rangle \subseteq \langle c, \downarrow_q R\rangle` and the interval hull is
    unchanged. When the matrix already has at most ``order`` columns it is returned unchanged.

    Parameters
    ----------
    generators : array_like, shape (..., n, m)
        Generator matrices (leading axes allowed; each is reduced on its own column norms).
    order : int
        Number of generators ``q`` kept; at least ``n``.

    Returns
    -------
    numpy.ndarray, shape (..., n, min(m, order))
    """
    g = np.asarray(generators, dtype=float)
    n, m = g.shape[-2], g.shape[-1]
    if order < n:
        raise DimensionError(f"order: expected at least the dimension n={n}, got {order}")
    if m <= order:
        return g
    keep = order - n
    norms = np.linalg.norm(g, axis=-2)  # (..., m)
    idx = np.argsort(-norms, axis=-1, kind="stable")
    ordered = np.take_along_axis(g, idx[..., None, :], axis=-1)
    box = np.abs(ordered[..., keep:]).sum(axis=-1)
    return np.concatenate([ordered[..., :keep], box[..., :, None] * np.eye(n)], axis=-1)


class Zonotope:
    r"""The zonotope :math:`\langle c, R\rangle = \{c + Rs : \|s\|_\infty \le 1\}` (the integrated-observer paper,
    (A1)).

    Parameters
    ----------
    center : array_like, shape (n,)
        Centre :math:`c`.
    generators : array_like, shape (n, m)
        Generator (shape) matrix :math:`R`; ``m`` may be 0.
    """

    def __init__(self, center: ArrayLike, generators: ArrayLike) -> None:
        self.center = as_vector("center", center)
        n = self.center.size
        g = np.asarray(generators, dtype=float)
        if g.size == 0:
            g = np.zeros((n, 0))
        self.generators = as_matrix("generators", g, (n, None))
        self.center.setflags(write=False)
        self.generators.setflags(write=False)

    @classmethod
    def from_box(cls, lower: ArrayLike, upper: ArrayLike) -> Zonotope:
        """The box ``[lower, upper]`` as the zonotope ``<(l+u)/2, diag((u-l)/2)>``.

        Parameters
        ----------
        lower, upper : array_like, shape (n,)

        Returns
        -------
        Zonotope
        """
        lo = as_vector("lower", lower)
        hi = as_vector("upper", upper, lo.size)
        if np.any(lo > hi):
            raise BoundsError("Zonotope.from_box: expected lower <= upper")
        return cls(0.5 * (lo + hi), np.diag(0.5 * (hi - lo)))

    @property
    def dim(self) -> int:
        """Dimension ``n``."""
        return int(self.center.size)

    @property
    def order(self) -> int:
        """Number of generators ``m``."""
        return int(self.generators.shape[1])

    def affine_map(self, matrix: ArrayLike, offset: ArrayLike | None = None) -> Zonotope:
        r"""Exact image :math:`\{Mx + b\} = \langle Mc + b, MR\rangle` (the integrated-observer paper, Property 1).

        Parameters
        ----------
        matrix : array_like, shape (k, n)
        offset : array_like, shape (k,), optional

        Returns
        -------
        Zonotope
        """
        m = as_matrix("matrix", matrix, (None, self.dim))
        b = np.zeros(m.shape[0]) if offset is None else as_vector("offset", offset, m.shape[0])
        return Zonotope(m @ self.center + b, m @ self.generators)

    def minkowski_sum(self, other: Zonotope) -> Zonotope:
        r"""Exact Minkowski sum :math:`\langle c_1 + c_2, [R_1, R_2]\rangle` (the integrated-observer paper, Definition
        A.2).

        Parameters
        ----------
        other : Zonotope

        Returns
        -------
        Zonotope
        """
        if other.dim != self.dim:
            raise DimensionError(f"other: expected a zonotope of dimension {self.dim}, got {other.dim}")
        return Zonotope(self.center + other.center, np.hstack([self.generators, other.generators]))

    def __add__(self, other: Zonotope) -> Zonotope:
        return self.minkowski_sum(other)

    def interval_matrix_map(self, a_lower: ArrayLike, a_upper: ArrayLike) -> Zonotope:
        """Enclosure of the image under an interval matrix (Properties 3–4); see :func:`interval_matrix_image`.

        Parameters
        ----------
        a_lower, a_upper : array_like, shape (k, n)

        Returns
        -------
        Zonotope
        """
        al = as_matrix("a_lower", a_lower, (None, self.dim))
        au = as_matrix("a_upper", a_upper, al.shape)
        if np.any(al > au):
            raise BoundsError("a_lower, a_upper: expected a_lower <= a_upper elementwise")
        c, g = interval_matrix_image(al, au, self.center, self.generators)
        return Zonotope(c, g)

    def reduce(self, order: int) -> Zonotope:
        """Combastel's order reduction to at most ``order`` generators (Property 2); contains ``self``.

        Parameters
        ----------
        order : int

        Returns
        -------
        Zonotope
        """
        return Zonotope(self.center, reduce_order(self.generators, int(order)))

    def interval_hull(self) -> tuple[FloatArray, FloatArray]:
        r"""Smallest box containing the zonotope, :math:`c \pm |R|\mathbf 1`.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (n,)

        References
        ----------
        The integrated-observer paper, (A2) and (57).
        """
        r = hull_radius(self.generators)
        return self.center - r, self.center + r

    @shared_docs
    def frobenius_radius(self, weight: ArrayLike | None = None) -> float:
        r"""Weighted Frobenius radius :math:`\|R\|_{F,W} = \sqrt{\mathrm{tr}(R^\top W R)}` (Definition A.3).

        %(weight)s
        """
        w = self._weight(weight)
        return float(np.sqrt(max(np.trace(self.generators.T @ w @ self.generators), 0.0)))

    @shared_docs
    def w_radius(self, weight: ArrayLike | None = None) -> float:
        r"""W-radius :math:`\max_{s \in [-1,1]^m} s^\top R^\top W R s`: the zonotope's size in the weight ``W``.

        The maximum of a convex quadratic over a box is attained at a vertex; the vertices are
        enumerated, so this is exact and limited to 20 generators (reduce first).

        %(weight)s

        References
        ----------
        The integrated-observer paper, Definition A.4 and (24).
        """
        w = self._weight(weight)
        m = self.order
        if m == 0:
            return 0.0
        if m > _MAX_EXACT_GENERATORS:
            raise DimensionError(
                f"Zonotope.w_radius: expected at most {_MAX_EXACT_GENERATORS} generators, got {m}; reduce first"
            )
        q = self.generators.T @ w @ self.generators
        best = 0.0
        total = 2 ** (m - 1)  # s and -s give the same value: fix s_0 = 1
        for start in range(0, total, 4096):
            codes = np.arange(start, min(start + 4096, total))
            s = np.where((codes[:, None] >> np.arange(m - 1)) & 1, 1.0, -1.0)
            s = np.hstack([np.ones((codes.size, 1)), s])
            best = max(best, float(np.einsum("ki,ij,kj->k", s, q, s).max()))
        return best

    def contains_points(self, points: ArrayLike, tol: float = 1e-9) -> NDArray[np.bool_]:
        """Whether each point lies in the zonotope (one small LP per point; for tests and checks).

        Parameters
        ----------
        points : array_like, shape (k, n)
        tol : float
            Absolute tolerance on the box constraint of the LP solution.

        Returns
        -------
        numpy.ndarray of bool, shape (k,)
        """
        from scipy.optimize import linprog

        pts = np.atleast_2d(np.asarray(points, dtype=float))
        if pts.shape[-1] != self.dim:
            raise DimensionError(f"points: expected shape (k, {self.dim}), got {pts.shape}")
        m = self.order
        out = np.zeros(pts.shape[0], dtype=bool)
        for i, p in enumerate(pts):
            if m == 0:
                out[i] = bool(np.allclose(p, self.center, atol=tol))
                continue
            # minimise t subject to R s = p - c, -t <= s <= t
            cost = np.r_[np.zeros(m), 1.0]
            a_ub = np.block([[np.eye(m), -np.ones((m, 1))], [-np.eye(m), -np.ones((m, 1))]])
            res = linprog(
                cost,
                A_ub=a_ub,
                b_ub=np.zeros(2 * m),
                A_eq=np.hstack([self.generators, np.zeros((self.dim, 1))]),
                b_eq=p - self.center,
                bounds=[(None, None)] * m + [(0, None)],
                method="highs",
            )
            out[i] = bool(res.status == 0 and res.x[-1] <= 1.0 + tol)
        return out

    def _weight(self, weight: ArrayLike | None) -> FloatArray:
        if weight is None:
            return np.eye(self.dim)
        w = as_matrix("weight", weight, (self.dim, self.dim))
        if not np.allclose(w, w.T) or np.linalg.eigvalsh(0.5 * (w + w.T)).min() <= 0:
            raise BoundsError("weight: expected a symmetric positive definite matrix")
        return w

    def __repr__(self) -> str:
        return f"Zonotope(dim={self.dim}, order={self.order})"
