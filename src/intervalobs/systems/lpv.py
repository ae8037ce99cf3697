r"""Uncertain continuous-time LPV systems (Rotondo et al., (1)–(2), Assumptions 2.1–2.3).

.. math::
    \dot x = (A(\vartheta) + \Delta A(\vartheta))x + (B(\vartheta) + \Delta B(\vartheta))u
             + (B_{un}(\vartheta) + \Delta B_{un}(\vartheta))u_{un} + c + d,\qquad y = Cx,

with a known scheduling vector :math:`\vartheta \in \Theta` (a box), elementwise bounds
:math:`\underline{\Delta A}(\vartheta) \le \Delta A(\vartheta) \le \overline{\Delta A}(\vartheta)`
(same for :math:`\Delta B, \Delta B_{un}`), a known term :math:`c` and a bounded disturbance
:math:`\underline d \le d \le \overline d` (10), given with the initial box as the ``w`` and ``x0`` of
a :class:`~intervalobs.systems.bounds.Bounds`.

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
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError, DimensionError, IntervalObserverError
from ..interval import Interval
from ..validation import as_box, as_matrix, as_vector
from .dimensions import ModelDimensions

__all__ = ["LPVSystem", "SampledLPVModel", "StepEnclosure"]

FloatArray = NDArray[np.float64]
MatrixFunction = Callable[..., Any]
BoundSpec = tuple[ArrayLike, ArrayLike] | Callable[..., Any]


class LPVSystem(ModelDimensions):
    r"""An uncertain continuous-time LPV system, validated on construction.

    Matrix functions follow the library's component convention (:mod:`intervalobs.inclusion`): they
    take the *sequence of the* :math:`n_\vartheta` *scheduling components* and return the rows of
    entries, e.g. ``A=lambda th: [[-1.0, th[0]], [0.0, -2.0]]``. Written with ``+ - * /`` and the
    NumPy functions of :data:`~intervalobs.interval.SUPPORTED_UFUNCS`, one definition is evaluated at
    points (arrays) and over boxes (:class:`~intervalobs.interval.Interval`), which is what the
    generic sampled observer needs between samples (:meth:`matrix_box`). A function may instead
    return an array of shape ``(N, rows, cols)`` at points (then it cannot be evaluated over boxes).
    Bounds of :math:`\Delta A, \Delta B, \Delta B_{un}` are either constant ``(lower, upper)`` arrays
    or functions of the same convention returning ``(lower rows, upper rows)``. Everything is
    evaluated at the centre and the vertices of ``theta_box`` (at most 64 points) to check shapes,
    finiteness, ``lower <= upper`` and :math:`\operatorname{rank}(CB_{un}) = n_{un}`.

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
    dA, dB, dB_un : tuple of array_like or callable, optional
        Elementwise bounds of :math:`\Delta A, \Delta B, \Delta B_{un}`.
    c : array_like, shape (n,), optional
        Known constant term.

    Attributes
    ----------
    n, m, p, q, n_theta : int
        States, known inputs, outputs, unknown inputs, scheduling variables.
    nw, nv : int
        Channels of the disturbance d (= n, the ``w`` of :class:`~intervalobs.systems.bounds.Bounds`)
        and of measurement noise (0: :math:`y = Cx`).
    continuous : bool
        Always True (the paper's systems are continuous time).

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): the uncertainty bounds (11), (12), (23).
    """

    continuous = True

    def __init__(
        self,
        A: MatrixFunction,
        B: MatrixFunction,
        C: ArrayLike,
        theta_box: tuple[ArrayLike, ArrayLike],
        B_un: MatrixFunction | None = None,
        dA: BoundSpec | None = None,
        dB: BoundSpec | None = None,
        dB_un: BoundSpec | None = None,
        c: ArrayLike | None = None,
    ) -> None:
        for name, f in (("A", A), ("B", B), ("B_un", B_un)):
            if f is not None and not callable(f):
                raise DimensionError(f"{name}: expected a callable of the scheduling vector, got {type(f).__name__}")
        self.theta_box = as_box("theta_box", theta_box)
        self.n_theta = self.theta_box[0].size
        self.A, self.B, self.B_un = A, B, B_un
        points = self.test_points()
        a0 = self._eval("A", A, points)
        if a0.shape[1] != a0.shape[2]:
            raise DimensionError(f"A: expected square matrices (n×n), got shape {a0.shape[1:]}")
        n = a0.shape[1]
        m = self._eval("B", B, points, rows=n).shape[2]
        self.C = as_matrix("C", C, (None, n))
        p = self.C.shape[0]
        if np.linalg.matrix_rank(self.C) != p:
            raise AssumptionError(f"C: expected full row rank {p}, got rank {np.linalg.matrix_rank(self.C)}")
        q = 0
        if B_un is not None:
            bu = self._eval("B_un", B_un, points, rows=n)
            q = bu.shape[2]
            for k, mat in enumerate(bu):
                r_b, r_cb = np.linalg.matrix_rank(mat), np.linalg.matrix_rank(self.C @ mat)
                if r_b != q or r_cb != q:
                    raise AssumptionError(
                        f"B_un: expected rank(B_un) = rank(C B_un) = {q} (problem statement, "
                        f"n_un <= n_y), got {r_b} and {r_cb} at theta = {points[k].tolist()}"
                    )
            if q > p:
                raise AssumptionError(f"B_un: expected n_un <= n_y = {p}, got n_un = {q}")
        self._set_dimensions(n=n, m=m, p=p, q=q, nw=n, nv=0)
        self.dA = self._bound_spec("dA", dA, self.n)
        self.dB = self._bound_spec("dB", dB, self.m)
        self.dB_un = self._bound_spec("dB_un", dB_un, self.q)
        for name, spec, cols in (("dA", self.dA, self.n), ("dB", self.dB, self.m), ("dB_un", self.dB_un, self.q)):
            if spec is not None:
                self._check_bounds(name, spec, points, cols)
        self.c = np.zeros(self.n) if c is None else as_vector("c", c, self.n)

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

    # --- evaluation ---------------------------------------------------------------------------------
    def matrix_at(self, name: str, theta: ArrayLike) -> FloatArray:
        """A matrix function (``"A"``, ``"B"`` or ``"B_un"``) at scheduling points.

        Parameters
        ----------
        name : str
            Which matrix.
        theta : array_like, shape (N, n_theta)
            Points.

        Returns
        -------
        numpy.ndarray, shape (N, rows, cols)
        """
        f = getattr(self, name)
        if f is None:
            raise DimensionError(f"{name}: the system has no {name}")
        return _matrix_at(f, np.atleast_2d(np.asarray(theta, dtype=float)))

    def matrix_box(self, name: str, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Natural interval extension of a matrix function over boxes of the scheduling vector.

        Parameters
        ----------
        name : str
            ``"A"``, ``"B"`` or ``"B_un"``.
        lower, upper : array_like, shape (N, n_theta)
            Boxes.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (N, rows, cols)
            Bounds containing the matrix for every scheduling value in the box.

        Raises
        ------
        DimensionError
            If the function cannot be evaluated on intervals (it returned an array).
        """
        f = getattr(self, name)
        if f is None:
            raise DimensionError(f"{name}: the system has no {name}")
        return _matrix_box(name, f, np.atleast_2d(lower), np.atleast_2d(upper))

    def bounds_box(self, name: str, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray] | None:
        r"""Bounds of ΔA, ΔB or ΔB_un valid on boxes of the scheduling vector (natural extension).

        Parameters
        ----------
        name : str
            ``"dA"``, ``"dB"`` or ``"dB_un"``.
        lower, upper : array_like, shape (N, n_theta)
            Boxes.

        Returns
        -------
        tuple of numpy.ndarray, shape (N, rows, cols), or None
            None when the system has no such uncertainty.
        """
        spec = getattr(self, name)
        if spec is None:
            return None
        lo_t, hi_t = np.atleast_2d(lower), np.atleast_2d(upper)
        if isinstance(spec, tuple):
            shape = (lo_t.shape[0], *spec[0].shape)
            return np.broadcast_to(spec[0], shape), np.broadcast_to(spec[1], shape)
        comps = [Interval._raw(lo_t[..., j], hi_t[..., j]) for j in range(lo_t.shape[-1])]
        low, high = spec(comps)
        return _rows_to_array(low, lo_t.shape[0], "lower")[0], _rows_to_array(high, lo_t.shape[0], "upper")[1]

    @staticmethod
    def _eval(name: str, f: MatrixFunction, points: FloatArray, rows: int | None = None) -> FloatArray:
        try:
            val = _matrix_at(f, points)
        except IntervalObserverError:
            raise
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

    def _bound_spec(self, name: str, spec: BoundSpec | None, cols: int) -> Any:
        if spec is None or callable(spec):
            return spec
        lo, hi = (np.asarray(v, dtype=float) for v in spec)
        if lo.shape != (self.n, cols) or hi.shape != (self.n, cols):
            raise DimensionError(f"{name}: expected bounds of shape {(self.n, cols)}, got {lo.shape} and {hi.shape}")
        return (lo, hi)

    def _check_bounds(self, name: str, spec: Any, points: FloatArray, cols: int) -> None:
        if isinstance(spec, tuple):
            lo, hi = spec
            lo, hi = lo[None], hi[None]
        else:
            try:
                lo, hi = _bounds_at(spec, points)
            except Exception as exc:  # as in _eval
                raise DimensionError(f"{name}: evaluating the bounds at theta failed: {exc}") from exc
        want = (points.shape[0], self.n, cols)
        if lo.shape[1:] != want[1:] or hi.shape[1:] != want[1:]:
            raise DimensionError(f"{name}: expected bounds of shape {want}, got {lo.shape} and {hi.shape}")
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise BoundsError(f"{name}: expected finite bounds, got NaN or inf")
        if np.any(lo > hi):
            k = np.argwhere(lo > hi)[0]
            raise BoundsError(f"{name}: expected lower <= upper, got lower > upper at {tuple(int(i) for i in k)}")

    def bounds_at(self, name: str, theta: ArrayLike) -> tuple[FloatArray, FloatArray] | None:
        r"""Bounds of :math:`\Delta A`, :math:`\Delta B` or :math:`\Delta B_{un}` at scheduling points.

        Parameters
        ----------
        name : str
            ``"dA"``, ``"dB"`` or ``"dB_un"``.
        theta : array_like, shape (N, n_theta)
            Points.

        Returns
        -------
        tuple of numpy.ndarray, shape (N, rows, cols), or None
        """
        spec = getattr(self, name)
        if spec is None:
            return None
        pts = np.atleast_2d(np.asarray(theta, dtype=float))
        if isinstance(spec, tuple):
            shape = (pts.shape[0], *spec[0].shape)
            return np.broadcast_to(spec[0], shape), np.broadcast_to(spec[1], shape)
        return _bounds_at(spec, pts)


def _rows_to_array(rows: Any, count: int, name: str) -> tuple[FloatArray, FloatArray]:
    """Rows of entries (floats, arrays or :class:`Interval`) to lower/upper arrays (count, r, c)."""
    if isinstance(rows, np.ndarray) and rows.ndim == 3:
        return rows, rows
    wrapped = [[Interval._wrap(e) for e in row] for row in rows]
    cols = {len(row) for row in wrapped}
    if len(cols) != 1:
        raise DimensionError(f"{name}: expected rows of equal length, got ragged rows")
    lo = np.empty((count, len(wrapped), cols.pop()))
    hi = np.empty_like(lo)
    for i, row in enumerate(wrapped):
        for j, e in enumerate(row):
            lo[:, i, j], hi[:, i, j] = e.lower, e.upper  # assignment broadcasts constant entries
    return lo, hi


def _matrix_at(f: Callable[..., Any], points: FloatArray) -> FloatArray:
    out = f([points[:, j] for j in range(points.shape[1])])
    if isinstance(out, np.ndarray):
        return np.asarray(out, dtype=float)
    return _rows_to_array(out, points.shape[0], "matrix")[0]


def _bounds_at(f: Callable[..., Any], points: FloatArray) -> tuple[FloatArray, FloatArray]:
    low, high = f([points[:, j] for j in range(points.shape[1])])
    return _rows_to_array(low, points.shape[0], "lower")[0], _rows_to_array(high, points.shape[0], "upper")[0]


def _matrix_box(
    name: str, f: Callable[..., Any], lower: FloatArray, upper: FloatArray
) -> tuple[FloatArray, FloatArray]:
    comps = [Interval._raw(lower[:, j], upper[:, j]) for j in range(lower.shape[1])]
    out = f(comps)
    if isinstance(out, np.ndarray):
        raise DimensionError(
            f"{name}: expected rows of entries (component convention) for interval evaluation, got an array"
        )
    return _rows_to_array(out, lower.shape[0], name)


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
        Bounds of :math:`\Delta A_R`, the uncertainty of ``A`` in the observer's coordinates.
    db_lower, db_upper : numpy.ndarray, shape (M, n, m)
        Bounds of :math:`\Delta B_R`, likewise for ``B``.
    dbun_lower, dbun_upper : numpy.ndarray, shape (M, n, q)
        Bounds of :math:`\Delta B_{un,R}`, likewise for the unknown-input matrix.

    References
    ----------
    Rotondo et al.: :math:`\Delta A_R` (14), :math:`\Delta B_R` (15), :math:`\Delta B_{un,R}` (24).
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
    matrix :math:`R(\vartheta)`. Subclasses set :attr:`system`.

    Attributes
    ----------
    system : LPVSystem
        The uncertain LPV model.

    References
    ----------
    Rotondo et al.: :math:`R(\vartheta)` of (14)–(16); the model (1)–(2).
    """

    system: LPVSystem
    box_free: bool = False
    """Whether :meth:`step_enclosure` ignores the observer's box (e.g. the whole state is measured): the
    enclosures of many samples can then be evaluated at once
    (:meth:`~intervalobs.observers.lpv.LPVIntervalObserver.advance_many`)."""

    @abstractmethod
    def r_matrix(self, y: FloatArray) -> FloatArray:
        r""":math:`R(\vartheta_k)` at measured samples.

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
