r"""Uncertain continuous-time LPV systems (seed 001, (1)–(2), Assumptions 2.1–2.3).

.. math::
    \dot x = (A(\vartheta) + \Delta A(\vartheta))x + (B(\vartheta) + \Delta B(\vartheta))u
             + (B_{un}(\vartheta) + \Delta B_{un}(\vartheta))u_{un} + c + d,\qquad y = Cx,

with a known scheduling vector :math:`\vartheta \in \Theta` (a box), elementwise bounds
:math:`\underline{\Delta A}(\vartheta) \le \Delta A(\vartheta) \le \overline{\Delta A}(\vartheta)`
(same for :math:`\Delta B, \Delta B_{un}`), a known term :math:`c` and a bounded disturbance
:math:`\underline d \le d \le \overline d`.

A sampled-data interval observer of a continuous-time LPV system must bound what happens *between*
samples (DESIGN.md). That needs interval extensions of the model over one step, which depend on the
model's formulas; :class:`SampledLPVModel` is the protocol a model implements to provide them
(see :class:`intervalobs.examples.manipulator.ManipulatorModel`).
"""

from __future__ import annotations

import itertools
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError, DimensionError
from ..validation import as_box, as_matrix, as_vector

__all__ = ["LPVSystem", "SampledLPVModel", "StepEnclosure"]

FloatArray = NDArray[np.float64]
MatrixFunction = Callable[[FloatArray], FloatArray]
BoundFunction = Callable[[FloatArray], tuple[FloatArray, FloatArray]]


class LPVSystem:
    r"""An uncertain continuous-time LPV system, validated on construction.

    Matrix functions take the scheduling vector with any leading axes, ``theta`` of shape
    ``(..., n_theta)``, and return arrays of shape ``(..., rows, cols)``. They are evaluated at the
    centre and the vertices of ``theta_box`` (at most 64 points) to check shapes, finiteness,
    ``lower <= upper`` of every bound, and the rank condition :math:`\operatorname{rank}(CB_{un})
    = n_{un}` of the problem statement.

    Parameters
    ----------
    A, B : callable
        :math:`A(\vartheta)` (n×n) and :math:`B(\vartheta)` (n×m).
    C : array_like, shape (p, n)
        Output matrix, full row rank.
    theta_box : tuple of array_like
        ``(lower, upper)`` of :math:`\Theta`.
    B_un : callable, optional
        :math:`B_{un}(\vartheta)` (n×q), full column rank.
    dA, dB, dB_un : callable, optional
        Elementwise bounds ``theta -> (lower, upper)`` of :math:`\Delta A, \Delta B, \Delta B_{un}`
        ((11), (12), (23)).
    c : array_like, shape (n,), optional
        Known constant term.
    d : tuple of array_like, optional
        ``(lower, upper)`` bounds of the disturbance (10).

    Attributes
    ----------
    n, m, p, q, n_theta : int
        States, known inputs, outputs, unknown inputs, scheduling variables.
    continuous : bool
        Always True (the paper's systems are continuous time).
    """

    continuous = True

    def __init__(
        self,
        A: MatrixFunction,
        B: MatrixFunction,
        C: ArrayLike,
        theta_box: tuple[ArrayLike, ArrayLike],
        B_un: MatrixFunction | None = None,
        dA: BoundFunction | None = None,
        dB: BoundFunction | None = None,
        dB_un: BoundFunction | None = None,
        c: ArrayLike | None = None,
        d: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        for name, f in (("A", A), ("B", B), ("B_un", B_un), ("dA", dA), ("dB", dB), ("dB_un", dB_un)):
            if f is not None and not callable(f):
                raise DimensionError(f"{name}: expected a callable of the scheduling vector, got {type(f).__name__}")
        self.theta_box = as_box("theta_box", theta_box)
        self.n_theta = self.theta_box[0].size
        self.A, self.B, self.B_un = A, B, B_un
        self.dA, self.dB, self.dB_un = dA, dB, dB_un
        points = self.test_points()
        a0 = self._eval("A", A, points)
        if a0.ndim != 3 or a0.shape[1] != a0.shape[2]:
            raise DimensionError(f"A: expected square matrices (n×n), got shape {a0.shape[1:]}")
        self.n = a0.shape[1]
        b0 = self._eval("B", B, points, rows=self.n)
        self.m = b0.shape[2]
        self.C = as_matrix("C", C, (None, self.n))
        self.p = self.C.shape[0]
        if np.linalg.matrix_rank(self.C) != self.p:
            raise AssumptionError(f"C: expected full row rank {self.p}, got rank {np.linalg.matrix_rank(self.C)}")
        self.q = 0
        if B_un is not None:
            bu = self._eval("B_un", B_un, points, rows=self.n)
            self.q = bu.shape[2]
            for k, mat in enumerate(bu):
                r_b, r_cb = np.linalg.matrix_rank(mat), np.linalg.matrix_rank(self.C @ mat)
                if r_b != self.q or r_cb != self.q:
                    raise AssumptionError(
                        f"B_un: expected rank(B_un) = rank(C B_un) = {self.q} (problem statement, "
                        f"n_un <= n_y), got {r_b} and {r_cb} at theta = {points[k].tolist()}"
                    )
            if self.q > self.p:
                raise AssumptionError(f"B_un: expected n_un <= n_y = {self.p}, got n_un = {self.q}")
        for name, f, cols in (("dA", dA, self.n), ("dB", dB, self.m), ("dB_un", dB_un, self.q)):
            if f is not None:
                self._check_bounds(name, f, points, cols)
        self.c = np.zeros(self.n) if c is None else as_vector("c", c, self.n)
        self.d = None if d is None else as_box("d", d, self.n)

    def test_points(self) -> FloatArray:
        """The centre and up to 63 vertices of ``theta_box`` used for validation.

        Returns
        -------
        numpy.ndarray, shape (N, n_theta)
        """
        lo, hi = self.theta_box
        centre = 0.5 * (lo + hi)
        corners = itertools.islice(itertools.product(*zip(lo, hi)), 63)
        return np.array([centre, *[np.array(v) for v in corners]])

    @staticmethod
    def _eval(name: str, f: MatrixFunction, points: FloatArray, rows: int | None = None) -> FloatArray:
        try:
            val = np.asarray(f(points), dtype=float)
        except Exception as exc:  # a user callable may fail in any way; report it at the boundary
            raise DimensionError(f"{name}: evaluating at theta of shape {points.shape} failed: {exc}") from exc
        if val.ndim != 3 or val.shape[0] != points.shape[0] or (rows is not None and val.shape[1] != rows):
            want = f"({points.shape[0]}, {rows if rows is not None else 'rows'}, cols)"
            raise DimensionError(
                f"{name}: expected an array of shape {want} for theta of shape {points.shape}, got {val.shape}"
            )
        if not np.all(np.isfinite(val)):
            raise BoundsError(f"{name}: expected finite entries on theta_box, got NaN or inf")
        return val

    def _check_bounds(self, name: str, f: BoundFunction, points: FloatArray, cols: int) -> None:
        try:
            lo, hi = f(points)
        except Exception as exc:  # as in _eval
            raise DimensionError(f"{name}: evaluating the bounds at theta failed: {exc}") from exc
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        want = (points.shape[0], self.n, cols)
        if lo.shape != want or hi.shape != want:
            raise DimensionError(f"{name}: expected bounds of shape {want}, got {lo.shape} and {hi.shape}")
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise BoundsError(f"{name}: expected finite bounds, got NaN or inf")
        if np.any(lo > hi):
            k = np.argwhere(lo > hi)[0]
            raise BoundsError(f"{name}: expected lower <= upper, got lower > upper at {tuple(int(i) for i in k)}")


@dataclass(frozen=True)
class StepEnclosure:
    r"""Sound enclosures over one sampling step :math:`[t_k, t_k + h]` (all arrays (M, ·) or (M, ·, ·)).

    Attributes
    ----------
    flow_lower, flow_upper : numpy.ndarray, shape (M, n)
        A box containing :math:`x(t)` on the step.
    rate_lower, rate_upper : numpy.ndarray, shape (M, n)
        Bounds of the known part of :math:`\tfrac{d}{dt}(Rx)`: :math:`(\dot R + RA)x + RBu + Rc`.
    rx_lower, rx_upper : numpy.ndarray, shape (M, n)
        Bounds of :math:`R(\vartheta)x`.
    da_lower, da_upper : numpy.ndarray, shape (M, n, n)
        Bounds of :math:`\Delta A_R` (14).
    db_lower, db_upper : numpy.ndarray, shape (M, n, m)
        Bounds of :math:`\Delta B_R` (15).
    dbun_lower, dbun_upper : numpy.ndarray, shape (M, n, q)
        Bounds of :math:`\Delta B_{un,R}` (24).
    """

    flow_lower: FloatArray
    flow_upper: FloatArray
    rate_lower: FloatArray
    rate_upper: FloatArray
    rx_lower: FloatArray
    rx_upper: FloatArray
    da_lower: FloatArray
    da_upper: FloatArray
    db_lower: FloatArray
    db_upper: FloatArray
    dbun_lower: FloatArray
    dbun_upper: FloatArray


class SampledLPVModel(ABC):
    r"""What a sampled-data LPV interval observer needs from a model between two samples.

    Methods are vectorised over a leading run axis and return *sound* enclosures valid for every
    admissible parameter, unknown input and intersample behaviour. ``R`` is the observer's coordinate
    matrix :math:`R(\vartheta)` (seed 001, (14)–(16)). Subclasses set :attr:`system`.

    Attributes
    ----------
    system : LPVSystem
        The model in the form (1)–(2).
    """

    system: LPVSystem

    @abstractmethod
    def r_matrix(self, y: FloatArray) -> FloatArray:
        """:math:`R(\vartheta_k)` at measured samples.

        Parameters
        ----------
        y : numpy.ndarray, shape (M, p)
            Measured outputs (the scheduling vector is computed from them).

        Returns
        -------
        numpy.ndarray, shape (M, n, n)
        """

    @abstractmethod
    def rx_bounds(self, x_lower: FloatArray, x_upper: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Bounds of :math:`R(\vartheta)x` over a box of states.

        Parameters
        ----------
        x_lower, x_upper : numpy.ndarray, shape (M, n)
            Box of states.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (M, n)
        """

    @abstractmethod
    def step_enclosure(
        self, x_lower: FloatArray, x_upper: FloatArray, y: FloatArray, u: FloatArray, h: float
    ) -> StepEnclosure:
        """Enclosures over :math:`[t_k, t_k + h]`.

        Parameters
        ----------
        x_lower, x_upper : numpy.ndarray, shape (M, n)
            Observer box at :math:`t_k`.
        y : numpy.ndarray, shape (M, p)
            Output at :math:`t_k`.
        u : numpy.ndarray, shape (M, m)
            Known input, held over the step.
        h : float
            Step length (s).

        Returns
        -------
        StepEnclosure
        """
