r"""Reaction systems with unknown kinetics: the model of the asymptotic observer of bioprocesses.

.. math::

    \dot x = K\, r(x, t) + D(t)\,(x_{in} - x), \qquad y_k = x_M(t_k) + v_k,

with :math:`K` (``n`` × ``q``) the known yield (stoichiometric) matrix, :math:`r` the ``q`` reaction
rates — unknown functions, no model asked —, :math:`D(t) \ge 0` the dilution rate (a constant, or a
known input held between samples), :math:`x_{in}` the inlet concentrations (in a box) and :math:`M`
the measured components. When :math:`K_M` (the measured rows of :math:`K`) is square and invertible,
the reaction invariants of the unmeasured components

.. math::

    z = x_U + G\,x_M, \qquad G = -K_U K_M^{-1}, \qquad \text{so that } [G\;\, I]\,K = 0,

obey :math:`\dot z = D(t)\,(z_{in} - z)` with :math:`z_{in} = x_{in,U} + G\,x_{in,M}`, whatever the
kinetics. :math:`G` is computed exactly in rational arithmetic from the floating-point entries of
:math:`K` and kept as the enclosing interval matrix, so :math:`[G\;\, I]K = 0` holds exactly for the
invariant the bounds are about, not only up to rounding.

**References.**

* G. Bastin, D. Dochain, *On-line Estimation and Adaptive Control of Bioreactors*, Elsevier, 1990.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, DimensionError
from ..interval import Interval
from ..validation import as_box
from .dimensions import ModelDimensions

__all__ = ["ReactionSystem"]

FloatArray = NDArray[np.float64]


def _exact_solve(matrix: list[list[Fraction]], rhs: list[list[Fraction]]) -> list[list[Fraction]] | None:
    """``X`` with ``X @ matrix = rhs`` in exact arithmetic (Gauss–Jordan on the transpose); None if singular."""
    size = len(matrix)
    rows = [[matrix[j][i] for j in range(size)] + [rhs[k][i] for k in range(len(rhs))] for i in range(size)]
    for col in range(size):
        pivot = next((r for r in range(col, size) if rows[r][col] != 0), None)
        if pivot is None:
            return None
        rows[col], rows[pivot] = rows[pivot], rows[col]
        lead = rows[col][col]
        rows[col] = [entry / lead for entry in rows[col]]
        for r in range(size):
            if r != col and rows[r][col] != 0:
                factor = rows[r][col]
                rows[r] = [a - factor * b for a, b in zip(rows[r], rows[col])]
    return [[rows[i][size + k] for i in range(size)] for k in range(len(rhs))]


def _enclose(value: Fraction) -> tuple[float, float]:
    """The two floating-point numbers around an exact rational (equal when it is one)."""
    near = float(value)
    if Fraction(near) == value:
        return near, near
    if Fraction(near) < value:
        return near, float(np.nextafter(near, np.inf))
    return float(np.nextafter(near, -np.inf)), near


class ReactionSystem(ModelDimensions):
    r"""A reaction system :math:`\dot x = K r(x, t) + D(t)(x_{in} - x)` with unknown kinetics :math:`r`.

    Parameters
    ----------
    yields : array_like, shape (n, q)
        Yield matrix :math:`K`: column ``j`` is what reaction ``j`` produces (+) and consumes (−) of
        each component per unit of its rate.
    measured : sequence of int
        Indices of the measured components (``y_k = x_measured(t_k) + v_k``); exactly ``q`` of them,
        and :math:`K` restricted to them must be invertible.
    inlet : float, array_like or (lower, upper)
        Inlet concentrations :math:`x_{in}`: a list or array (known), or a tuple ``(lower, upper)``
        (a box, when they are uncertain).
    dilution : float, optional
        Constant dilution rate :math:`D \ge 0` (1/time). None: :math:`D` is the known input
        ``u_k`` (``m = 1``), held on :math:`[t_k, t_{k+1})`.
    nonnegative : bool
        Whether the concentrations are never negative (the observer then intersects with
        :math:`x \ge 0`).
    state_names : sequence of str, optional
        Names of the components.

    Attributes
    ----------
    n, m, p, q, nw, nv : int
        Components, known inputs (one when :math:`D` is the input ``u``, else none), measured components
        (as many as reactions), reactions (their unknown rates are the unknown inputs), disturbance channels
        (none: ``nw`` is zero) and measurement-noise channels (one per measured component).
    n_params : int
        Always 0: the kinetics are not parametrised.

    Raises
    ------
    DimensionError
        Shapes that do not fit.
    AssumptionError
        Measured components that do not determine the reaction rates (not ``q`` of them, or
        :math:`K_M` singular): then the invariants do not give the unmeasured components.

    Examples
    --------
    >>> from intervalobs import ReactionSystem
    >>> chemostat = ReactionSystem([[1.0], [-2.0]], measured=[1], inlet=[0.0, 5.0], dilution=0.2)
    >>> chemostat.invariant_gain.lower.tolist()  # Z = X + S/2
    [[0.5]]
    """

    def __init__(
        self,
        yields: ArrayLike,
        measured: Sequence[int],
        inlet: ArrayLike | tuple[ArrayLike, ArrayLike],
        dilution: float | None = None,
        *,
        nonnegative: bool = True,
        state_names: Sequence[str] | None = None,
    ) -> None:
        k = np.array(yields, dtype=float)
        if k.ndim != 2 or not np.all(np.isfinite(k)):
            raise DimensionError(f"yields: expected a finite (n, q) matrix, got shape {k.shape}")
        n, q = k.shape
        index = [int(i) for i in measured]
        if len(set(index)) != len(index) or not all(0 <= i < n for i in index):
            raise DimensionError(f"measured: expected distinct indices in [0, {n}), got {list(measured)!r}")
        if len(index) != q:
            raise AssumptionError(
                f"measured: expected as many measured components as reactions ({q}), got {len(index)}: the "
                "reaction invariants give the other components only when the measured ones fix the rates"
            )
        if dilution is not None and not (np.isfinite(dilution) and dilution >= 0):
            raise AssumptionError(f"dilution: expected a nonnegative rate, got {dilution!r}")
        self._set_dimensions(n=n, m=1 if dilution is None else 0, p=q, nw=0, nv=q, q=q)
        self.n_params = 0
        self.yields, self.measured = k, np.array(index, dtype=int)
        self.unmeasured = np.array([i for i in range(n) if i not in index], dtype=int)
        self.dilution = None if dilution is None else float(dilution)
        self.nonnegative = bool(nonnegative)
        low, high = inlet if isinstance(inlet, tuple) else (inlet, inlet)
        self.inlet = Interval(*as_box("inlet", (low, high), n))
        self.state_names = None if state_names is None else [str(name) for name in state_names]
        self.invariant_gain = self._gain()

    def _gain(self) -> Interval:
        """The enclosure of :math:`G = -K_U K_M^{-1}`, computed exactly in rationals."""
        exact = [[Fraction(float(v)) for v in row] for row in self.yields.tolist()]
        k_m = [exact[i] for i in self.measured]
        minus_k_u = [[-v for v in exact[i]] for i in self.unmeasured]
        gain = _exact_solve(k_m, minus_k_u) if self.q else []
        if gain is None:
            raise AssumptionError(
                f"yields: the rows of the measured components {self.measured.tolist()} are linearly dependent, "
                "so the measurements do not fix the reaction rates and the invariants miss the other components"
            )
        ends = np.array([[_enclose(v) for v in row] for row in gain], dtype=float).reshape(
            self.unmeasured.size, self.q, 2
        )
        return Interval(ends[..., 0], ends[..., 1])

    def __repr__(self) -> str:
        rate = "input u" if self.dilution is None else f"{self.dilution:g}"
        return f"ReactionSystem(n={self.n}, reactions={self.q}, measured={self.measured.tolist()}, dilution={rate})"
