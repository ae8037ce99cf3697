r"""Nonlinear discrete-time systems with unknown inputs and bounded noise (Khajenejad & Yong, eq. (3)).

.. math::

    x_{k+1} = f(x_k) + Bu_k + Gd_k + w_k,\qquad y_k = g(x_k) + Du_k + Hd_k + v_k,

with :math:`\underline w \le w_k \le \overline w`, :math:`\underline v \le v_k \le \overline v` (the
boxes ``w``, ``v`` of a :class:`~intervalobs.systems.bounds.Bounds`, with the initial box ``x0``) and an
unknown input :math:`d_k` about which nothing is assumed (no bound, no model).

Dimensions use the library's names: ``n`` states, ``m`` known inputs, ``p`` outputs, ``q`` unknown
inputs (the paper calls them n, m, l, p). ``f`` and ``g`` follow the component convention of
:mod:`intervalobs.inclusion`: they take a sequence of the n state components and return a sequence of
components, written with NumPy functions, so that the same definition is evaluated at points, in
interval arithmetic over boxes, and — for the Jacobian bounds the observers need (Khajenejad & Yong,
Assumption 1) — in interval forward-mode differentiation (:mod:`intervalobs.interval_dual`). Jacobians
written by the user (rows of entries, same convention) are optional; they are checked against the
automatic ones.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..errors import AssumptionError, BoundsError, DataError, DimensionError
from ..inclusion import (
    MatrixFunction,
    VectorFunction,
    evaluate_function,
    evaluate_matrix,
    interval_function,
    interval_matrix,
)
from ..interval_dual import automatic_jacobian
from ..validation import as_matrix
from .dimensions import ModelDimensions

__all__ = ["NonlinearSystem"]

FloatArray = NDArray[np.float64]


class NonlinearSystem(ModelDimensions):
    """A nonlinear discrete-time system with unknown inputs that act on the state and the outputs.

    Parameters
    ----------
    f : callable
        State map :math:`f:\\mathbb{R}^n\\to\\mathbb{R}^n` (component convention).
    g : callable
        Output map :math:`g:\\mathbb{R}^n\\to\\mathbb{R}^p`.
    G : array_like, shape (n, q)
        Unknown-input matrix of the state equation.
    H : array_like, shape (p, q)
        Unknown-input (feedthrough) matrix of the output equation; may be rank-deficient.
    B : array_like, shape (n, m), optional
        Known-input matrix (default: no known input).
    D : array_like, shape (p, m), optional
        Known-input feedthrough (default zero).
    f_jacobian, g_jacobian : callable, optional
        Jacobians of ``f`` and ``g`` (rows of entries). Default: computed automatically from ``f`` and
        ``g`` (:func:`intervalobs.interval_dual.automatic_jacobian`). A Jacobian given here is used
        instead (it may be tighter over boxes) and is checked against the automatic one.
    check_jacobians : bool
        Compare user Jacobians with the automatic ones at sample points (default True): at each sample
        the interval value of the user's entry must meet the automatic derivative's enclosure.

    Attributes
    ----------
    n, m, p, q, nw, nv : int
        States, known inputs, outputs (the paper's l), unknown inputs (the paper's p), process-noise
        (= n) and measurement-noise (= p) channels
        (:class:`~intervalobs.systems.dimensions.ModelDimensions`).
    f_jacobian, g_jacobian : callable
        The Jacobians used for bounds (the user's, or the automatic ones).
    jacobian_source : dict
        ``{"f": "user" | "automatic", "g": ...}``.

    Raises
    ------
    DimensionError
        Shapes disagree, or ``f``/``g``/Jacobians return the wrong number of components.
    AssumptionError
        ``[G; H]`` does not have full column rank (Khajenejad & Yong, Section III).
    DataError
        A user Jacobian misses the automatic derivative at a sample point.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`), eq. (3).
    """

    def __init__(
        self,
        f: VectorFunction,
        g: VectorFunction,
        G: ArrayLike,
        H: ArrayLike,
        B: ArrayLike | None = None,
        D: ArrayLike | None = None,
        f_jacobian: MatrixFunction | None = None,
        g_jacobian: MatrixFunction | None = None,
        check_jacobians: bool = True,
    ) -> None:
        if not callable(f) or not callable(g):
            raise DimensionError("f, g: expected callables (component convention)")
        self.G = as_matrix("G", G)
        n, q = self.G.shape
        self.H = as_matrix("H", H, (None, q))
        p = self.H.shape[0]
        self.B = np.zeros((n, 0)) if B is None else as_matrix("B", B, (n, None))
        m = self.B.shape[1]
        self.D = np.zeros((p, m)) if D is None else as_matrix("D", D, (p, m))
        self._set_dimensions(n=n, m=m, p=p, q=q, nw=n, nv=p)
        self.f, self.g = f, g
        self.jacobian_source = {
            "f": "automatic" if f_jacobian is None else "user",
            "g": "automatic" if g_jacobian is None else "user",
        }
        self.f_jacobian: MatrixFunction = automatic_jacobian(f, n) if f_jacobian is None else f_jacobian
        self.g_jacobian: MatrixFunction = automatic_jacobian(g, n) if g_jacobian is None else g_jacobian
        rank = int(np.linalg.matrix_rank(np.vstack([self.G, self.H])))
        if rank < q:
            raise AssumptionError(
                f"[G; H]: expected full column rank {q} (unknown inputs that act independently), got rank {rank}"
            )
        zero = np.zeros(n)
        self.evaluate_f(zero)
        self.evaluate_g(zero)
        evaluate_matrix(self.f_jacobian, zero, (n, n), "f_jacobian")
        evaluate_matrix(self.g_jacobian, zero, (p, n), "g_jacobian")
        if check_jacobians:
            self._check_jacobians()

    @shared_docs
    def evaluate_f(self, x: ArrayLike) -> FloatArray:
        """:math:`f(x)` at points.

        %(points)s
        """
        return evaluate_function(self.f, x, self.n, "f")

    @shared_docs
    def evaluate_g(self, x: ArrayLike) -> FloatArray:
        """:math:`g(x)` at points.

        %(points)s
        """
        return evaluate_function(self.g, x, self.p, "g")

    @shared_docs
    def f_range(self, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Natural interval extension of ``f`` over boxes.

        %(natural_extension)s
        """
        return interval_function(self.f, lower, upper, self.n, "f")

    @shared_docs
    def g_range(self, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Natural interval extension of ``g`` over boxes.

        %(natural_extension)s
        """
        return interval_function(self.g, lower, upper, self.p, "g")

    def jacobians(self) -> tuple[MatrixFunction, MatrixFunction]:
        """The Jacobians of ``f`` and ``g`` used for bounds (user-given or automatic).

        Returns
        -------
        f_jacobian, g_jacobian : callable
            Component-convention matrix functions.
        """
        return self.f_jacobian, self.g_jacobian

    def _check_jacobians(self, points: int = 8) -> None:
        """User Jacobians against the automatic derivative at the origin and random points of [-2, 2]^n.

        Both are interval enclosures at the same (degenerate) box, so a correct Jacobian meets the
        automatic one exactly (no tolerance). Samples outside the functions' domain are skipped.
        """
        rng = np.random.default_rng(12345)
        xs = np.vstack([np.zeros(self.n), rng.uniform(-2.0, 2.0, size=(points, self.n))])
        for name, func, size in (("f_jacobian", self.f, self.n), ("g_jacobian", self.g, self.p)):
            if self.jacobian_source[name[0]] == "automatic":
                continue
            user = self.f_jacobian if name == "f_jacobian" else self.g_jacobian
            auto = automatic_jacobian(func, self.n)
            for x in xs:
                try:
                    a_lo, a_hi = interval_matrix(auto, x, x, (size, self.n), name)
                except BoundsError:
                    continue
                u_lo, u_hi = interval_matrix(user, x, x, (size, self.n), name)
                miss = (u_hi < a_lo) | (u_lo > a_hi)
                if np.any(miss):
                    i, j = (int(k) for k in np.argwhere(miss)[0])
                    raise DataError(
                        f"{name}: entry ({i + 1},{j + 1}) at x={x.round(3).tolist()} is "
                        f"[{u_lo[i, j]:.6g}, {u_hi[i, j]:.6g}], the derivative of "
                        f"{'f' if name == 'f_jacobian' else 'g'} is in [{a_lo[i, j]:.6g}, {a_hi[i, j]:.6g}]"
                    )

    def __repr__(self) -> str:
        return f"NonlinearSystem(n={self.n}, m={self.m}, p={self.p}, q={self.q})"
