r"""Nonlinear discrete-time systems with unknown inputs and bounded noise (seed 003, eq. (3)).

.. math::

    x_{k+1} = f(x_k) + Bu_k + Gd_k + w_k,\qquad y_k = g(x_k) + Du_k + Hd_k + v_k,

with :math:`\underline w \le w_k \le \overline w`, :math:`\underline v \le v_k \le \overline v` and an
unknown input :math:`d_k` about which nothing is assumed (no bound, no model).

Dimensions use the library's names: ``n`` states, ``m`` known inputs, ``p`` outputs, ``q`` unknown
inputs (the seed calls them n, m, l, p). ``f``, ``g`` and their Jacobians follow the component
convention of :mod:`intervalobs.inclusion`: they take a sequence of the n state components and return a
sequence of components (the Jacobians: rows of entries), written with NumPy functions, so that the same
definition is evaluated at points and, in interval arithmetic, over boxes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, DataError, DimensionError
from ..inclusion import (
    MatrixFunction,
    VectorFunction,
    evaluate_function,
    evaluate_matrix,
    interval_function,
)
from ..validation import as_box, as_matrix, as_vector

__all__ = ["NonlinearSimulation", "NonlinearSystem", "simulate_nonlinear"]

FloatArray = NDArray[np.float64]
BoxPair = tuple[FloatArray, FloatArray]


class NonlinearSystem:
    """A nonlinear discrete-time system with unknown inputs, seed 003 eq. (3).

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
        Jacobians of ``f`` and ``g`` (rows of entries). Required by the observers (seed 003,
        Assumption 1 is used through Jacobian bounds); checked against finite differences here.
    w : tuple of array_like, optional
        ``(lower, upper)`` bounds of the process noise (default zero).
    v : tuple of array_like, optional
        ``(lower, upper)`` bounds of the measurement noise (default zero).
    check_jacobians : bool
        Compare the Jacobians with central differences at a few points (default True).

    Raises
    ------
    DimensionError
        Shapes disagree, or ``f``/``g``/Jacobians return the wrong number of components.
    AssumptionError
        ``[G; H]`` does not have full column rank (seed 003, Section III), or a Jacobian disagrees
        with finite differences.
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
        w: tuple[ArrayLike, ArrayLike] | None = None,
        v: tuple[ArrayLike, ArrayLike] | None = None,
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
        self.f, self.g = f, g
        self.f_jacobian, self.g_jacobian = f_jacobian, g_jacobian
        self.w: BoxPair = (np.zeros(n), np.zeros(n)) if w is None else as_box("w", w, n)
        self.v: BoxPair = (np.zeros(p), np.zeros(p)) if v is None else as_box("v", v, p)
        rank = int(np.linalg.matrix_rank(np.vstack([self.G, self.H])))
        if rank < q:
            raise AssumptionError(f"[G; H]: expected full column rank {q} (seed 003, Section III), got rank {rank}")
        zero = np.zeros(n)
        self.evaluate_f(zero)
        self.evaluate_g(zero)
        if f_jacobian is not None:
            evaluate_matrix(f_jacobian, zero, (n, n), "f_jacobian")
        if g_jacobian is not None:
            evaluate_matrix(g_jacobian, zero, (p, n), "g_jacobian")
        if check_jacobians:
            self._check_jacobians()

    @property
    def n(self) -> int:
        """Number of states."""
        return int(self.G.shape[0])

    @property
    def m(self) -> int:
        """Number of known inputs."""
        return int(self.B.shape[1])

    @property
    def p(self) -> int:
        """Number of outputs (the seed's l)."""
        return int(self.H.shape[0])

    @property
    def q(self) -> int:
        """Number of unknown inputs (the seed's p)."""
        return int(self.G.shape[1])

    def evaluate_f(self, x: ArrayLike) -> FloatArray:
        """:math:`f(x)` at points.

        Parameters
        ----------
        x : array_like, shape (..., n)
            Points.

        Returns
        -------
        numpy.ndarray
        """
        return evaluate_function(self.f, x, self.n, "f")

    def evaluate_g(self, x: ArrayLike) -> FloatArray:
        """:math:`g(x)` at points.

        Parameters
        ----------
        x : array_like, shape (..., n)
            Points.

        Returns
        -------
        numpy.ndarray
        """
        return evaluate_function(self.g, x, self.p, "g")

    def f_range(self, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Natural interval extension of ``f`` over boxes.

        Parameters
        ----------
        lower, upper : array_like, shape (..., n)
            Boxes.

        Returns
        -------
        lower, upper : numpy.ndarray
        """
        return interval_function(self.f, lower, upper, self.n, "f")

    def g_range(self, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Natural interval extension of ``g`` over boxes.

        Parameters
        ----------
        lower, upper : array_like, shape (..., n)
            Boxes.

        Returns
        -------
        lower, upper : numpy.ndarray
        """
        return interval_function(self.g, lower, upper, self.p, "g")

    def require_jacobians(self) -> tuple[MatrixFunction, MatrixFunction]:
        """Both Jacobians, or ``AssumptionError`` naming what is missing.

        Returns
        -------
        f_jacobian, g_jacobian : callable
        """
        if self.f_jacobian is None or self.g_jacobian is None:
            missing = "f_jacobian" if self.f_jacobian is None else "g_jacobian"
            raise AssumptionError(f"{missing}: required for Jacobian bounds (seed 003, Assumption 1), got None")
        return self.f_jacobian, self.g_jacobian

    def _check_jacobians(self, points: int = 4, tol: float = 1e-5) -> None:
        rng = np.random.default_rng(12345)
        xs = rng.uniform(-2.0, 2.0, size=(points, self.n))
        h = 1e-6
        for name, func, jac, size in (
            ("f_jacobian", self.f, self.f_jacobian, self.n),
            ("g_jacobian", self.g, self.g_jacobian, self.p),
        ):
            if jac is None:
                continue
            analytic = evaluate_matrix(jac, xs, (size, self.n), name)
            eye = np.eye(self.n) * h
            plus = evaluate_function(func, xs[:, None, :] + eye, size)
            minus = evaluate_function(func, xs[:, None, :] - eye, size)
            numeric = np.swapaxes((plus - minus) / (2 * h), -1, -2)
            err = np.abs(analytic - numeric) / (1.0 + np.abs(numeric))
            if err.max() > tol:
                k, i, j = (int(a) for a in np.unravel_index(np.argmax(err), err.shape))
                raise AssumptionError(
                    f"{name}: entry ({i + 1},{j + 1}) at x={xs[k].round(3).tolist()} is {analytic[k, i, j]:.6g}, "
                    f"finite differences give {numeric[k, i, j]:.6g}"
                )

    def __repr__(self) -> str:
        return f"NonlinearSystem(n={self.n}, m={self.m}, p={self.p}, q={self.q})"


@dataclass(frozen=True)
class NonlinearSimulation:
    """A simulated record of a :class:`NonlinearSystem`, time-first (leading run axis if ``runs``).

    Attributes
    ----------
    x : numpy.ndarray, shape (..., T, n)
    y : numpy.ndarray, shape (..., T, p)
    u : numpy.ndarray, shape (T, m)
    d : numpy.ndarray, shape (..., T, q)
    w : numpy.ndarray, shape (..., T, n)
    v : numpy.ndarray, shape (..., T, p)
    """

    x: FloatArray
    y: FloatArray
    u: FloatArray
    d: FloatArray
    w: FloatArray
    v: FloatArray


def simulate_nonlinear(
    system: NonlinearSystem,
    x0: ArrayLike | tuple[ArrayLike, ArrayLike],
    d: ArrayLike,
    u: ArrayLike | None = None,
    noise: str = "extreme",
    seed: int = 0,
    runs: int | None = None,
) -> NonlinearSimulation:
    """Iterate seed 003's eq. (3) with admissible noise.

    Parameters
    ----------
    system : NonlinearSystem
    x0 : array_like, shape (n,), or tuple (lower, upper)
        Initial state, or a box from which each run draws one (a random vertex for ``"extreme"`` noise,
        uniform otherwise).
    d : array_like, shape (T, q) or (runs, T, q)
        Unknown input; its length fixes the horizon T.
    u : array_like, shape (T, m), optional
        Known input (default zero).
    noise : str
        Kind of :func:`intervalobs.simulate.noise_signal` ("extreme" is bang-bang between the bounds).
    seed : int
        Random seed.
    runs : int, optional
        Number of Monte Carlo runs (leading axis).

    Returns
    -------
    NonlinearSimulation
    """
    from ..simulate import noise_signal

    dd = np.asarray(d, dtype=float)
    if dd.ndim not in (2, 3) or dd.shape[-1] != system.q:
        raise DataError(f"d: expected shape (T, {system.q}) or (runs, T, {system.q}), got {dd.shape}")
    if not np.all(np.isfinite(dd)):
        raise DataError("d: expected finite values, got NaN or inf")
    steps = dd.shape[-2]
    uu = np.zeros((steps, system.m)) if u is None else as_matrix("u", u, (steps, system.m))
    rng = np.random.default_rng(seed)
    count = 1 if runs is None else runs
    if isinstance(x0, tuple):
        lo, hi = as_box("x0", x0, system.n)
        unit = rng.integers(0, 2, size=(count, system.n)) if noise == "extreme" else rng.uniform(size=(count, system.n))
        x_init = lo + (hi - lo) * unit
    else:
        x_init = np.broadcast_to(as_vector("x0", x0, system.n), (count, system.n)).copy()
    w = noise_signal(noise, system.w[0], system.w[1], steps, rng, runs=count)
    v = noise_signal(noise, system.v[0], system.v[1], steps, rng, runs=count)
    dr = np.broadcast_to(dd, (count, steps, system.q))
    x = np.empty((count, steps, system.n))
    x[:, 0] = x_init
    for k in range(steps - 1):
        x[:, k + 1] = system.evaluate_f(x[:, k]) + uu[k] @ system.B.T + dr[:, k] @ system.G.T + w[:, k]
    y = system.evaluate_g(x) + uu @ system.D.T + dr @ system.H.T + v
    if runs is None:
        return NonlinearSimulation(x[0], y[0], uu, dr[0].copy(), w[0], v[0])
    return NonlinearSimulation(x, y, uu, np.array(dr), w, v)
