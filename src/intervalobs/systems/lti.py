r"""Linear time-invariant models with interval uncertainty.

.. math::

    \dot x = (A + \Delta A)x + (B + \Delta B)u + Ew,\qquad y = Cx + Fv \qquad (\text{continuous time, } dt = None)

    x_{k+1} = (A + \Delta A)x_k + (B + \Delta B)u_k + Ew_k,\qquad y_k = Cx_k + Fv_k \qquad (\text{discrete time})

with :math:`\underline{\Delta A} \le \Delta A \le \overline{\Delta A}` and
:math:`\underline{\Delta B} \le \Delta B \le \overline{\Delta B}` constant and unknown (e.g. a motor's
torque constant known to a few per cent),
:math:`w`, :math:`v` unknown signals in boxes and :math:`x(0)` in a box (the boxes are
:class:`~intervalobs.systems.bounds.Bounds`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ArgumentTypeError, AssumptionError, BoundsError, DimensionError
from ..validation import as_matrix, as_names, as_positive
from .dimensions import ModelDimensions

__all__ = ["LTISystem", "refuse_uncertain_input"]

FloatArray = NDArray[np.float64]
BoxPair = tuple[FloatArray, FloatArray]


class LTISystem(ModelDimensions):
    """A linear time-invariant system with optional elementwise interval uncertainty on ``A`` and ``B``.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Nominal state matrix.
    C : array_like, shape (p, n)
        Output matrix.
    B : array_like, shape (n, m), optional
        Known-input matrix (default: no input, m = 0).
    E : array_like, shape (n, nw), optional
        Process-noise matrix (default: the identity, nw = n).
    F : array_like, shape (p, nv), optional
        Measurement-noise matrix (default: the identity, nv = p).
    dt : float, optional
        Sampling period of a discrete-time system; ``None`` (default) for continuous time.
    dA : tuple of array_like, optional
        ``(lower, upper)`` elementwise bounds of the unknown constant ``ΔA``, each (n, n); must
        contain zero (``A`` is the nominal matrix).
    dB : tuple of array_like, optional
        ``(lower, upper)`` elementwise bounds of the unknown constant ``ΔB``, each (n, m); must contain
        zero (``B`` is the nominal matrix). A gain known to ±5 % is ``dB=(-0.05 * abs(B), 0.05 * abs(B))``.
    state_names, output_names, input_names : sequence of str, optional
        Names of the states, outputs and known inputs (default ``x1 …``, ``y1 …``, ``u1 …``): they
        label plots and exported tables, and a labelled record (a pandas ``DataFrame``, an xarray
        ``DataArray``) is matched to the outputs and inputs by them.

    Attributes
    ----------
    n, m, p, nw, nv : int
        Numbers of states, known inputs, outputs, process-noise and measurement-noise channels
        (:class:`~intervalobs.systems.dimensions.ModelDimensions`; ``q`` is 0: unknown inputs enter
        through the ``D`` of :class:`~intervalobs.observers.unknown_input.UnknownInputIntervalObserver`).
    continuous : bool
        True when ``dt`` is None.
    state_names, output_names, input_names : tuple of str
        The names (given or default).
    """

    def __init__(
        self,
        A: ArrayLike,
        C: ArrayLike,
        B: ArrayLike | None = None,
        E: ArrayLike | None = None,
        F: ArrayLike | None = None,
        dt: float | None = None,
        dA: tuple[ArrayLike, ArrayLike] | None = None,
        dB: tuple[ArrayLike, ArrayLike] | None = None,
        state_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        input_names: Sequence[str] | None = None,
    ) -> None:
        self.A = as_matrix("A", A)
        n = self.A.shape[0]
        if self.A.shape != (n, n):
            raise DimensionError(f"A: expected a square matrix, got shape {self.A.shape}")
        self.C = as_matrix("C", C, (None, n))
        if self.C.shape[0] == 0:
            raise DimensionError(
                f"C: expected at least one output row, got shape (0, {n}); to predict without measurements, "
                "give one all-zero row (C = [[0, ..., 0]]) and record zeros for it"
            )
        self.B = np.zeros((n, 0)) if B is None else as_matrix("B", B, (n, None))
        self.E = np.eye(n) if E is None else as_matrix("E", E, (n, None))
        self.F = np.eye(self.C.shape[0]) if F is None else as_matrix("F", F, (self.C.shape[0], None))
        self._set_dimensions(n=n, m=self.B.shape[1], p=self.C.shape[0], nw=self.E.shape[1], nv=self.F.shape[1])
        self.dt = None if dt is None else as_positive("dt", dt, "a positive sampling period or None")
        self.dA = _nominal_box("dA", "A", dA, (n, n))
        self.dB = _nominal_box("dB", "B", dB, self.B.shape)
        self.state_names = as_names("state_names", state_names, n, "x")
        self.output_names = as_names("output_names", output_names, self.C.shape[0], "y")
        self.input_names = as_names("input_names", input_names, self.B.shape[1], "u")

    @property
    def uncertain_input(self) -> bool:
        """True when ``dB`` is an interval of nonzero width (``B`` not known exactly)."""
        return self.dB is not None and bool(np.any(self.dB[1] > self.dB[0]))

    @property
    def continuous(self) -> bool:
        """True for a continuous-time system."""
        return self.dt is None

    def sampling_period(self, h: float | None) -> float:
        """The sampling period a design with step ``h`` assumes: ``dt`` in discrete time, ``h`` in continuous.

        A discrete-time system is sampled every ``dt``: an ``h`` that differs (by more than 1e-9
        relative) is refused rather than ignored, since the bounds would not hold for it.

        Parameters
        ----------
        h : float or None
            The step the caller asked for; required in continuous time.

        Returns
        -------
        float
        """
        if self.dt is not None:
            if h is not None and not abs(float(h) - self.dt) <= 1e-9 * self.dt:
                raise BoundsError(f"h: expected None or the system's dt = {self.dt:g} (discrete time), got {h!r}")
            return self.dt
        return as_positive("h", h, "a positive step for a continuous-time system")

    @classmethod
    def from_control(cls, sys: Any, **kwargs: Any) -> LTISystem:
        """Build from a python-control ``StateSpace`` (its A, B, C and signal labels; D must be zero).

        The names of states, outputs and inputs are python-control's labels (``sys.state_labels``, …:
        ``x[0]``, … unless the model was built with ``states=``, ``outputs=``, ``inputs=``).

        Parameters
        ----------
        sys : control.StateSpace
            The model; ``sys.dt`` of 0 or None means continuous time.
        **kwargs
            ``E``, ``F``, ``dA``, ``dB`` and names (``state_names``, …, replacing the labels) as in the constructor.

        Returns
        -------
        LTISystem
        """
        unknown = set(kwargs) - {"E", "F", "dA", "dB", "state_names", "output_names", "input_names"}
        if unknown:
            raise ArgumentTypeError(f"LTISystem.from_control: unexpected keyword argument {sorted(unknown)[0]!r}")
        for attr in ("A", "B", "C", "D"):
            if not hasattr(sys, attr):
                raise DimensionError(f"sys: expected a python-control StateSpace, got {type(sys).__name__}")
        if np.any(np.asarray(sys.D) != 0):
            raise DimensionError("sys: expected D = 0 (no direct feedthrough), got a nonzero D")
        dt = None if sys.dt in (0, None) else (None if sys.dt is True else float(sys.dt))
        if sys.dt is True:
            raise BoundsError("sys.dt: expected a numeric sampling period for a discrete-time system, got True")
        B = np.asarray(sys.B, dtype=float)
        for kind in ("state", "output", "input"):
            kwargs.setdefault(f"{kind}_names", getattr(sys, f"{kind}_labels", None))
        return cls(sys.A, sys.C, B=B if B.size else None, dt=dt, **kwargs)

    def __repr__(self) -> str:
        kind = "continuous" if self.continuous else f"discrete, dt={self.dt:g}"
        extra = (", interval dA" if self.dA is not None else "") + (", interval dB" if self.dB is not None else "")
        return f"LTISystem(n={self.n}, m={self.m}, p={self.p}, {kind}{extra})"


def _nominal_box(
    name: str, nominal: str, box: tuple[ArrayLike, ArrayLike] | None, shape: tuple[int, int]
) -> BoxPair | None:
    """The checked ``(lower, upper)`` of an uncertainty around a nominal matrix, or None."""
    if box is None:
        return None
    lo = as_matrix(f"{name} lower", box[0], shape)
    hi = as_matrix(f"{name} upper", box[1], shape)
    if np.any(lo > hi):
        raise BoundsError(f"{name}: expected lower <= upper elementwise, got lower > upper")
    if np.any(lo > 0) or np.any(hi < 0):
        raise BoundsError(f"{name}: expected bounds that contain 0 ({nominal} is the nominal matrix)")
    return (lo, hi)


def refuse_uncertain_input(system: LTISystem, estimator: str) -> None:
    """Refuse a model whose input matrix is uncertain, for an estimator that needs ``B`` exactly.

    Parameters
    ----------
    system : LTISystem
        The model.
    estimator : str
        The estimator that refuses, named in the message.

    Raises
    ------
    AssumptionError
        When ``system.dB`` has a nonzero width.
    """
    if system.uncertain_input:
        raise AssumptionError(
            f"system.dB: {estimator} needs the input matrix B known exactly, got an interval ΔB; "
            "HullEstimator, RobustHullEstimator (with dA), RobustFiniteMemoryObserver (with dA) and "
            "IntervalObserver bound an uncertain B"
        )
