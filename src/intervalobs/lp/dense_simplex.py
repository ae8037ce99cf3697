r"""A bounded simplex method on a small dense LP, for a chain of objectives over the same feasible set.

The window hull (:class:`~intervalobs.observers.hull.HullEstimator`) solves ``2n`` LPs a step that differ only in
their objective: ``min c·z`` over ``row_lo ≤ A z ≤ row_hi``, ``col_lo ≤ z ≤ col_hi``. The optimum of one is a
feasible vertex of the next, so each is a few primal simplex pivots away from the one before. HiGHS spends a fixed
time on every ``run()`` that is large against those pivots on a dense matrix (on the 30-tank cascade of
:mod:`intervalobs.examples.scale_cases`, 231 × 330, about 15 pivots a solve): it checks and copies the matrix and
refactorises the basis. :class:`DenseSimplex` keeps the basis inverse from one objective to the next and pivots
on it in compiled code (Numba). The hull's cost a step is measured by ``benchmarks/scale.py``
(``benchmarks/scale.json``).

**Method.** The standard form has the row activities as variables, :math:`[A\;\; -I]\,(z, s) = 0` with the row
bounds on :math:`s`; a basis :math:`B` (``rows`` of the ``cols + rows`` columns) is held as its explicit inverse,
updated by one elimination step per pivot (the product form of the inverse, Dantzig & Orchard-Hays 1954) and
computed afresh from the square block of its structural columns (:meth:`DenseSimplex._refactor`). The primal
simplex prices by Devex (Harris 1973; reference weights reset at each objective) and uses Harris's two-pass ratio
test; the dual simplex (from a basis whose values violate their bounds) first makes the basis dual feasible by
putting every boxed nonbasic variable on the bound its reduced cost prefers, then removes the largest violation
first, with the same two-pass test on the reduced costs. Each pivot is checked by computing the pivot element
twice (from the column and from the row); a disagreement, or an optimum whose refined values violate a bound,
makes the inverse computed afresh.

**What is guaranteed.** Nothing here is trusted for soundness: the caller takes every bound from weak duality with
the row duals :meth:`DenseSimplex.row_duals` (:func:`~intervalobs.lp.certified.dual_bounds`), which is valid
for any multipliers. A solve that does not end optimal (pivot limit, degenerate cycling, a singular basis, an
infeasible LP) says so, and the caller solves that objective with HiGHS.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.linalg import qr

__all__ = ["DenseSimplex", "load_kernels"]

FloatArray = NDArray[np.float64]

_LOWER, _BASIC, _UPPER, _FREE = 0, 1, 2, 3
"""Status of a variable: nonbasic at its lower or upper bound, basic, nonbasic free (at 0)."""

OPTIMAL, PIVOT_LIMIT, UNBOUNDED, INACCURATE, INFEASIBLE = 0, 1, 2, 3, 4
"""Outcomes of :func:`_primal_simplex` and :func:`_dual_simplex` (``INACCURATE``: the pivot computed from the
column and from the row disagree, and the inverse has to be computed afresh)."""

EXITS = {
    OPTIMAL: "optimal",
    PIVOT_LIMIT: "pivot limit",
    UNBOUNDED: "unbounded",
    INACCURATE: "inaccurate",
    INFEASIBLE: "infeasible",
}
"""How :meth:`DenseSimplex.solve` ended (:attr:`DenseSimplex.exit`), by the outcome of its last pass; besides
these, ``"singular basis"`` (a basis whose inverse could not be computed), ``"no basis"`` (nothing loaded) and,
before any solve, ``"started"``."""

PIVOT_AGREEMENT = 1e-9
"""Relative disagreement of the two computations of a pivot (from the updated column and from the updated row)
above which the basis inverse is computed afresh (the same test as HiGHS's and most simplex codes', with their own
thresholds)."""

RANK_TOLERANCE = 1e-12
"""Relative size of the pivots of a QR factorisation below which a basis kept from another LP is taken as rank
deficient (:meth:`DenseSimplex.start_from_statuses`)."""

REFACTORISATIONS = 8
"""Fresh inverses allowed to one :meth:`DenseSimplex.solve` before it gives up."""


@numba.njit(cache=True, nogil=True)
def _basic_costs(cost: Any, basic: Any, cols: int) -> Any:  # pragma: no cover - compiled
    """``c_B``: the costs of the basic variables (those of the row activities are 0)."""
    cost_basic = np.empty(basic.shape[0])
    for i in range(basic.shape[0]):
        j = basic[i]
        cost_basic[i] = cost[j] if j < cols else 0.0
    return cost_basic


@numba.njit(cache=True, nogil=True)
def _reduced_costs(matrix_t: Any, cost: Any, basic: Any, inverse: Any) -> Any:  # pragma: no cover - compiled
    """Reduced costs of every variable (0 for the basic ones) for ``cost`` on ``z``."""
    cols, rows = matrix_t.shape
    duals = _basic_costs(cost, basic, cols) @ inverse
    reduced = np.empty(cols + rows)
    reduced[:cols] = cost - matrix_t @ duals
    reduced[cols:] = duals  # the column of row r's activity is -e_r, its cost 0
    for i in range(rows):
        reduced[basic[i]] = 0.0
    return reduced


@numba.njit(cache=True, nogil=True)
def _column(matrix_t: Any, inverse: Any, j: int) -> Any:  # pragma: no cover - compiled
    """``B⁻¹`` times the column of variable ``j`` in ``[A, -I]``."""
    cols = matrix_t.shape[0]
    if j < cols:
        return inverse @ matrix_t[j]
    return -inverse[:, j - cols]


@numba.njit(cache=True, nogil=True)
def _pivot(
    matrix_t: Any,
    reduced: Any,
    status: Any,
    basic: Any,
    inverse: Any,
    alpha: Any,
    row_inverse: Any,
    row_z: Any,
    leaving: int,
    entering: int,
) -> None:  # pragma: no cover - compiled
    """Exchange ``basic[leaving]`` for ``entering`` (values and the leaving variable's status set by the caller):
    the reduced costs along the pivot row (``row_inverse`` = row ``leaving`` of ``B⁻¹``, ``row_z`` its products
    with the columns of ``A``) and ``B⁻¹`` by one elimination step with the column ``alpha``."""
    cols, rows = matrix_t.shape
    pivot = alpha[leaving]
    theta = reduced[entering] / pivot
    out = basic[leaving]
    for j in range(cols):
        reduced[j] -= theta * row_z[j]
    for r in range(rows):
        reduced[cols + r] += theta * row_inverse[r]
    basic[leaving], status[entering] = entering, _BASIC
    for i in range(rows):
        reduced[basic[i]] = 0.0
    reduced[out] = -theta
    scaled = row_inverse / pivot
    inverse[leaving] = scaled
    for i in range(rows):
        factor = alpha[i]
        if i != leaving and factor != 0.0:
            for r in range(rows):
                inverse[i, r] -= factor * scaled[r]


@numba.njit(cache=True, nogil=True)
def _agree(row_pivot: float, pivot: float) -> bool:  # pragma: no cover - compiled
    """Whether the pivot computed from the row and from the column agree (``PIVOT_AGREEMENT``)."""
    return abs(row_pivot - pivot) <= PIVOT_AGREEMENT * min(abs(row_pivot), abs(pivot))


@numba.njit(cache=True, nogil=True)
def _primal_simplex(
    matrix_t: Any,
    cost: Any,
    lower: Any,
    upper: Any,
    x: Any,
    status: Any,
    basic: Any,
    inverse: Any,
    dual_tol: float,
    primal_tol: float,
    max_pivots: int,
) -> tuple[int, int]:  # pragma: no cover - compiled; covered through DenseSimplex
    """Minimise ``cost·z`` from the feasible basis ``basic`` (updates ``x``, ``status``, ``basic``, ``inverse``).

    Variables ``0 … cols-1`` are ``z``, ``cols + r`` the activity of row ``r``; ``cost`` covers ``z`` only.
    Returns ``(outcome, pivots)`` with ``outcome`` one of ``OPTIMAL``, ``PIVOT_LIMIT``, ``UNBOUNDED``,
    ``INACCURATE`` (nothing changed by the last pivot).
    """
    cols, rows = matrix_t.shape
    reduced = _reduced_costs(matrix_t, cost, basic, inverse)
    weight = np.ones(cols + rows)
    pivots = 0
    while pivots < max_pivots:
        # Devex pricing: the largest infeasibility squared over its reference weight
        entering, best = -1, 0.0
        for j in range(cols + rows):
            state = status[j]
            if state == _BASIC or lower[j] == upper[j]:
                continue
            d = reduced[j]
            if state == _LOWER:
                violation = -d
            elif state == _UPPER:
                violation = d
            else:
                violation = abs(d)
            if violation > dual_tol and violation * violation / weight[j] > best:
                best, entering = violation * violation / weight[j], j
        if entering < 0:
            return OPTIMAL, pivots
        direction = 1.0 if reduced[entering] < 0.0 else -1.0
        alpha = _column(matrix_t, inverse, entering)
        # Harris ratio test: the largest step within the bounds relaxed by the tolerance, then the largest pivot
        # among the basic variables that block before it
        relaxed = np.inf
        for i in range(rows):
            rate, j = direction * alpha[i], basic[i]
            if rate > primal_tol and lower[j] > -np.inf:
                relaxed = min(relaxed, (x[j] - lower[j] + primal_tol) / rate)
            elif rate < -primal_tol and upper[j] < np.inf:
                relaxed = min(relaxed, (upper[j] + primal_tol - x[j]) / -rate)
        leaving, largest, step = -1, 0.0, 0.0
        for i in range(rows):
            rate, j = direction * alpha[i], basic[i]
            if rate > primal_tol and lower[j] > -np.inf:
                ratio = (x[j] - lower[j]) / rate
            elif rate < -primal_tol and upper[j] < np.inf:
                ratio = (upper[j] - x[j]) / -rate
            else:
                continue
            if ratio <= relaxed and abs(rate) > largest:
                leaving, largest, step = i, abs(rate), ratio
        step = max(step, 0.0)
        span = upper[entering] - lower[entering]
        if leaving < 0 or span <= step:  # the entering variable reaches its other bound first
            if not span < np.inf:
                return UNBOUNDED, pivots
            pivots += 1
            for i in range(rows):
                x[basic[i]] -= direction * span * alpha[i]
            at_lower = status[entering] == _LOWER
            x[entering] = upper[entering] if at_lower else lower[entering]
            status[entering] = _UPPER if at_lower else _LOWER
            continue
        pivot = alpha[leaving]
        row_inverse = inverse[leaving].copy()  # row `leaving` of B⁻¹ [A, -I]: the pivot row
        row_z = matrix_t @ row_inverse
        if not _agree(row_z[entering] if entering < cols else -row_inverse[entering - cols], pivot):
            return INACCURATE, pivots
        pivots += 1
        for i in range(rows):
            x[basic[i]] -= direction * step * alpha[i]
        x[entering] += direction * step
        out = basic[leaving]
        if direction * pivot > 0.0:
            x[out], status[out] = lower[out], _LOWER
        else:
            x[out], status[out] = upper[out], _UPPER
        # Devex reference weights along the pivot row, then the exchange
        reference = weight[entering]
        for j in range(cols):
            weight[j] = max(weight[j], (row_z[j] / pivot) ** 2 * reference)
        for r in range(rows):
            weight[cols + r] = max(weight[cols + r], (row_inverse[r] / pivot) ** 2 * reference)
        weight[out] = max(reference / (pivot * pivot), 1.0)
        _pivot(matrix_t, reduced, status, basic, inverse, alpha, row_inverse, row_z, leaving, entering)
    return PIVOT_LIMIT, pivots


@numba.njit(cache=True, nogil=True)
def _dual_simplex(
    matrix_t: Any,
    cost: Any,
    lower: Any,
    upper: Any,
    x: Any,
    status: Any,
    basic: Any,
    inverse: Any,
    dual_tol: float,
    primal_tol: float,
    max_pivots: int,
) -> tuple[int, int]:  # pragma: no cover - compiled; covered through DenseSimplex
    """Minimise ``cost·z`` from any basis whose values may violate their bounds (same arguments as
    :func:`_primal_simplex`).

    Every nonbasic variable whose reduced cost has the wrong sign is first put on its other bound (all of them are
    boxed, or free and then priced at zero), which makes the basis dual feasible; the dual simplex then removes
    the bound violations of the basic variables, the largest first, with Harris's two-pass ratio test on the
    reduced costs. Returns ``OPTIMAL``, ``PIVOT_LIMIT``, ``INACCURATE`` or ``INFEASIBLE`` (a violated basic
    variable that no nonbasic one can move, or a free or one-sided variable priced the wrong way).
    """
    cols, rows = matrix_t.shape
    reduced = _reduced_costs(matrix_t, cost, basic, inverse)
    for j in range(cols + rows):
        state, d = status[j], reduced[j]
        if state == _BASIC or abs(d) <= dual_tol:
            continue
        if state == _FREE:
            return INFEASIBLE, 0
        if d < 0.0 and state == _LOWER:
            if not upper[j] < np.inf:
                return INFEASIBLE, 0
            x[j], status[j] = upper[j], _UPPER
        elif d > 0.0 and state == _UPPER:
            if not lower[j] > -np.inf:
                return INFEASIBLE, 0
            x[j], status[j] = lower[j], _LOWER
    for i in range(rows):
        x[basic[i]] = 0.0
    residual = np.empty(rows)
    activity = matrix_t.T @ x[:cols]
    for r in range(rows):
        residual[r] = activity[r] - x[cols + r]
    basic_values = inverse @ residual
    for i in range(rows):
        x[basic[i]] = -basic_values[i]
    pivots = 0
    while pivots < max_pivots:
        leaving, worst, to_lower = -1, primal_tol, True
        for i in range(rows):
            j = basic[i]
            if lower[j] - x[j] > worst:
                leaving, worst, to_lower = i, lower[j] - x[j], True
            elif x[j] - upper[j] > worst:
                leaving, worst, to_lower = i, x[j] - upper[j], False
        if leaving < 0:
            return OPTIMAL, pivots
        sign = 1.0 if to_lower else -1.0
        row_inverse = inverse[leaving].copy()
        row_z = matrix_t @ row_inverse
        # the row entries of the nonbasic variables that can move the leaving one towards its bound (0: cannot)
        movers = np.zeros(cols + rows)
        relaxed = np.inf
        for j in range(cols + rows):
            state = status[j]
            if state == _BASIC or lower[j] == upper[j]:
                continue
            a = row_z[j] if j < cols else -row_inverse[j - cols]
            if (
                (state == _LOWER and sign * a < -primal_tol)
                or (state == _UPPER and sign * a > primal_tol)
                or (state == _FREE and abs(a) > primal_tol)
            ):
                movers[j] = abs(a)
                relaxed = min(relaxed, (abs(reduced[j]) + dual_tol) / abs(a))
        entering, largest = -1, 0.0
        for j in range(cols + rows):
            if movers[j] > largest and abs(reduced[j]) / movers[j] <= relaxed:
                entering, largest = j, movers[j]
        if entering < 0:
            return INFEASIBLE, pivots
        alpha = _column(matrix_t, inverse, entering)
        pivot = alpha[leaving]
        if not _agree(row_z[entering] if entering < cols else -row_inverse[entering - cols], pivot):
            return INACCURATE, pivots
        pivots += 1
        out = basic[leaving]
        bound = lower[out] if to_lower else upper[out]
        change = (x[out] - bound) / pivot  # of the entering variable: the leaving one lands on its bound
        for i in range(rows):
            x[basic[i]] -= alpha[i] * change
        x[entering] += change
        x[out], status[out] = bound, _LOWER if to_lower else _UPPER
        _pivot(matrix_t, reduced, status, basic, inverse, alpha, row_inverse, row_z, leaving, entering)
    return PIVOT_LIMIT, pivots


@numba.njit(cache=True, nogil=True)
def _refined_feasible(
    matrix_t: Any, lower: Any, upper: Any, x: Any, basic: Any, inverse: Any, primal_tol: float
) -> bool:  # pragma: no cover - compiled; covered through DenseSimplex
    """Refine the basic values once against the residual of ``[A, -I] x = 0``; whether they are then within their
    bounds to ``primal_tol``."""
    cols, rows = matrix_t.shape
    residual = matrix_t.T @ x[:cols] - x[cols:]
    correction = inverse @ residual
    feasible = True
    for i in range(rows):
        j = basic[i]
        x[j] -= correction[i]
        if x[j] < lower[j] - primal_tol or x[j] > upper[j] + primal_tol:
            feasible = False
    return feasible


@numba.njit(cache=True, nogil=True)
def _row_duals(matrix_t: Any, cost: Any, basic: Any, inverse: Any) -> Any:  # pragma: no cover - compiled
    """``λ`` solving ``λ B = c_B``, refined once against its residual."""
    cols, rows = matrix_t.shape
    cost_basic = _basic_costs(cost, basic, cols)
    duals = cost_basic @ inverse
    column_terms = matrix_t @ duals
    residual = np.empty(rows)
    for i in range(rows):
        j = basic[i]
        residual[i] = cost_basic[i] - (column_terms[j] if j < cols else -duals[j - cols])
    return duals + residual @ inverse


@numba.njit(cache=True, nogil=True)
def _fresh_inverse(matrix_t: Any, basic: Any, x: Any) -> Any:  # pragma: no cover - compiled
    """``B⁻¹`` from the inverse of its square block ``K`` (:meth:`DenseSimplex._refactor`), and the basic values
    from the nonbasic ones (``x`` updated). Raises ``numpy.linalg.LinAlgError`` when ``K`` is singular."""
    cols, rows = matrix_t.shape
    spanned = np.ones(rows, dtype=np.bool_)  # rows whose activity is nonbasic
    structural = 0
    for i in range(rows):
        if basic[i] < cols:
            structural += 1
        else:
            spanned[basic[i] - cols] = False
    z_pos, s_pos = np.empty(structural, np.int64), np.empty(rows - structural, np.int64)
    a = b = 0
    for i in range(rows):
        if basic[i] < cols:
            z_pos[a] = i
            a += 1
        else:
            s_pos[b] = i
            b += 1
    r_rows = np.flatnonzero(spanned)
    block = np.empty((structural, structural))
    for a in range(structural):
        for b in range(structural):
            block[a, b] = matrix_t[basic[z_pos[b]], r_rows[a]]
    block_inverse = np.linalg.inv(block)
    other = np.empty((rows - structural, structural))
    for i in range(rows - structural):
        for b in range(structural):
            other[i, b] = matrix_t[basic[z_pos[b]], basic[s_pos[i]] - cols]
    lower_block = other @ block_inverse
    inverse = np.zeros((rows, rows))
    for a in range(structural):
        for b in range(structural):
            inverse[z_pos[a], r_rows[b]] = block_inverse[a, b]
    for i in range(rows - structural):
        for b in range(structural):
            inverse[s_pos[i], r_rows[b]] = lower_block[i, b]
        inverse[s_pos[i], basic[s_pos[i]] - cols] = -1.0
    for i in range(rows):
        x[basic[i]] = 0.0
    residual = matrix_t.T @ x[:cols] - x[cols:]
    values = inverse @ residual
    for i in range(rows):
        x[basic[i]] = -values[i]
    return inverse


@numba.njit(cache=True, nogil=True)
def _solve_once(
    primal: bool,
    matrix_t: Any,
    cost: Any,
    lower: Any,
    upper: Any,
    x: Any,
    status: Any,
    basic: Any,
    inverse: Any,
    dual_tol: float,
    primal_tol: float,
    max_pivots: int,
) -> tuple[int, int, bool, Any]:  # pragma: no cover - compiled; covered through DenseSimplex
    """One pass of :meth:`DenseSimplex.solve` in one call: the primal (or the dual) simplex, then at an optimum the
    refined values' feasibility and, if feasible, the row duals. Returns ``(outcome, pivots, feasible, duals)``."""
    kernel_arguments = (matrix_t, cost, lower, upper, x, status, basic, inverse, dual_tol, primal_tol, max_pivots)
    if primal:
        outcome, pivots = _primal_simplex(*kernel_arguments)
    else:
        outcome, pivots = _dual_simplex(*kernel_arguments)
    feasible = False
    duals = np.zeros(matrix_t.shape[1])
    if outcome == OPTIMAL:
        feasible = _refined_feasible(matrix_t, lower, upper, x, basic, inverse, primal_tol)
        if feasible:
            duals = _row_duals(matrix_t, cost, basic, inverse)
    return outcome, pivots, feasible, duals


class DenseSimplex:
    """The simplex method of the module docstring on ``row_lo ≤ A z ≤ row_hi``, ``col_lo ≤ z ≤ col_hi``.

    Parameters
    ----------
    matrix : numpy.ndarray, shape (rows, cols)
        ``A`` (dense).
    dual_tol, primal_tol : float
        Optimality and feasibility tolerances of the pivots (those of HiGHS in
        :func:`~intervalobs.lp.certified.new_highs`).
    pivot_limit : int
        Pivots allowed to one :meth:`solve`.
    """

    def __init__(self, matrix: FloatArray, dual_tol: float, primal_tol: float, pivot_limit: int) -> None:
        self.rows, self.cols = matrix.shape
        self.matrix_t = np.ascontiguousarray(matrix.T, dtype=float)
        self.dual_tol, self.primal_tol, self.pivot_limit = dual_tol, primal_tol, pivot_limit
        self.lower = np.zeros(self.cols + self.rows)
        self.upper = np.zeros(self.cols + self.rows)
        self.x = np.zeros(self.cols + self.rows)
        self.status = np.zeros(self.cols + self.rows, dtype=np.int64)
        self.basic = np.zeros(self.rows, dtype=np.int64)
        self.inverse = np.eye(self.rows)
        self.ready = False
        """Whether a basis is loaded (:meth:`start`) and usable by the next solve."""
        self.duals = np.zeros(self.rows)
        """The row multipliers of the last optimum (:meth:`row_duals`)."""
        self.feasible = False
        """Whether the current basic values are within their bounds (the primal simplex goes on from them; the
        dual simplex otherwise)."""
        self.exit = "no basis"
        """How the last :meth:`solve` ended (a value of :data:`EXITS`, ``"singular basis"`` or ``"no basis"``);
        after a :meth:`start`, ``"started"`` or ``"singular basis"`` (its basis could not be inverted)."""

    def start(
        self,
        col_lo: FloatArray,
        col_hi: FloatArray,
        row_lo: FloatArray,
        row_hi: FloatArray,
        basic: NDArray[np.int64],
        values: FloatArray,
    ) -> bool:
        """Load the bounds and a basis (a HiGHS optimum, say).

        The nonbasic variables are put on the bound nearest their value and the basic values are computed from
        them.

        Parameters
        ----------
        col_lo, col_hi : numpy.ndarray, shape (cols,)
            Bounds of ``z`` (finite).
        row_lo, row_hi : numpy.ndarray, shape (rows,)
            Bounds of ``A z`` (may be infinite).
        basic : numpy.ndarray of int, shape (rows,)
            The basic variables in HiGHS's convention: ``j ≥ 0`` column ``j``, ``-1 - r`` row ``r``.
        values : numpy.ndarray, shape (cols + rows,)
            The columns' then the rows' values at that basis.

        Returns
        -------
        bool
            Whether the basis is usable (:attr:`ready`): nonsingular. Values outside their bounds (a start from
            an optimum of slightly wider rows) are left to the dual simplex.
        """
        cols = self.cols
        self._set_bounds(col_lo, col_hi, row_lo, row_hi)
        at_upper = np.abs(values - self.upper) < np.abs(values - self.lower)  # False where both are infinite
        status = np.where(at_upper, _UPPER, _LOWER)
        status[np.where(basic >= 0, basic, cols - 1 - basic)] = _BASIC
        return self._load(status)

    def start_from_statuses(
        self,
        col_lo: FloatArray,
        col_hi: FloatArray,
        row_lo: FloatArray,
        row_hi: FloatArray,
        statuses: NDArray[np.integer],
    ) -> bool:
        """Load the bounds and a basis given by the status of every variable (a basis kept from another LP).

        The activity of a free row is made basic. The basis is then made square and nonsingular: of its structural
        columns, those that span the rows whose activity is nonbasic best are kept, as many as their numerical rank
        (QR with column pivoting, relative ``RANK_TOLERANCE``), the others go to a bound; of those rows, as many as
        the kept columns keep their activity nonbasic (QR with pivoting again), the others' becomes basic. The
        values then usually violate bounds, and :meth:`solve` starts with the dual simplex.

        Parameters
        ----------
        col_lo, col_hi : numpy.ndarray, shape (cols,)
            Bounds of ``z`` (finite).
        row_lo, row_hi : numpy.ndarray, shape (rows,)
            Bounds of ``A z`` (may be infinite).
        statuses : numpy.ndarray of int, shape (cols + rows,)
            As :meth:`statuses` returns them.

        Returns
        -------
        bool
            Whether the completed basis is nonsingular (:attr:`ready`).
        """
        self._set_bounds(col_lo, col_hi, row_lo, row_hi)
        return self._load(np.asarray(statuses, dtype=np.int64))

    def _set_bounds(self, col_lo: FloatArray, col_hi: FloatArray, row_lo: FloatArray, row_hi: FloatArray) -> None:
        """The bounds of every variable: the columns', then the rows' (of ``A z``)."""
        self.lower[: self.cols], self.upper[: self.cols] = col_lo, col_hi
        self.lower[self.cols :], self.upper[self.cols :] = row_lo, row_hi

    def _load(self, status: NDArray[np.int64]) -> bool:
        """Take ``status`` (bounds already set): complete the basis to ``rows`` variables, put every nonbasic one on
        a finite bound of its status (free when it has none) and compute the inverse and the basic values."""
        cols = self.cols
        status = status.copy()
        status[cols:][~np.isfinite(self.lower[cols:]) & ~np.isfinite(self.upper[cols:])] = _BASIC  # free rows
        basic = status == _BASIC
        structural = np.flatnonzero(basic[:cols])
        spanned = np.flatnonzero(~basic[cols:])  # rows whose activity is nonbasic
        if structural.size and spanned.size:
            # the structural columns that span those rows best, as many as their rank; then as many of the rows
            block = self.matrix_t[np.ix_(structural, spanned)].T  # A restricted
            diagonal, order = qr(block, mode="r", pivoting=True)
            size = min(block.shape)
            magnitude = np.abs(np.diag(diagonal[:size, :size]))
            rank = int(np.count_nonzero(magnitude > RANK_TOLERANCE * magnitude[0])) if size else 0
            status[structural[order[rank:]]] = _LOWER
            order = qr(block[:, order[:rank]].T, mode="r", pivoting=True)[1]
            status[cols + spanned[order[rank:]]] = _BASIC
        else:
            status[structural] = _LOWER
            status[cols + spanned] = _BASIC
        finite_lo, finite_hi = np.isfinite(self.lower), np.isfinite(self.upper)
        nonbasic = status != _BASIC
        status[nonbasic & (status == _LOWER) & ~finite_lo] = _UPPER
        status[nonbasic & (status == _UPPER) & ~finite_hi] = _LOWER
        status[nonbasic & ~finite_lo & ~finite_hi] = _FREE
        self.status = status
        self.basic = np.flatnonzero(status == _BASIC).astype(np.int64)
        self.x = np.where(status == _UPPER, self.upper, np.where(status == _LOWER, self.lower, 0.0))
        feasible = self._refactor()
        self.ready, self.feasible = feasible is not None, bool(feasible)
        self.exit = "started" if self.ready else "singular basis"
        return self.ready

    def _refactor(self) -> bool | None:
        r"""Compute the basis inverse afresh and the basic values from the nonbasic ones; returns whether those
        are within their bounds (to ``primal_tol``), None when the basis is singular.

        With the basic columns of ``z`` (``Z``) and the rows whose activity is basic (``S``), the other rows
        (``R``, as many as ``Z``) give the square block :math:`K = A_{RZ}`, and

        .. math:: B^{-1} = \begin{pmatrix} K^{-1} & 0 \\ A_{SZ} K^{-1} & -I \end{pmatrix}

        (rows: the basis positions of ``Z``, then of ``S``; columns: the rows ``R``, then ``S``), so only ``K`` is
        inverted.
        """
        try:
            inverse = _fresh_inverse(self.matrix_t, self.basic, self.x)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(inverse)):
            return None
        self.inverse = inverse
        return self._feasible()

    def _feasible(self) -> bool:
        """Whether the basic values are within their bounds to ``primal_tol``."""
        index, tol = self.basic, self.primal_tol
        basic = self.x[index]
        return bool(np.all(basic >= self.lower[index] - tol) and np.all(basic <= self.upper[index] + tol))

    def solve(self, cost: FloatArray) -> tuple[bool, int]:
        """Minimise ``cost·z`` from the current basis.

        An optimum is accepted when its basic values, refined once against the residual of ``[A, -I] x = 0``,
        are within their bounds: the updated inverse drifts on the ill-conditioned bases of thin feasible sets
        (condition numbers up to 1e9 on the 30-tank cascade under vertex noise), and values carried along the
        pivots can then hide a basis whose exact solution violates a bound (by up to 1e-3 there), whose
        multipliers certify correspondingly less. Otherwise, and when two computations of a pivot disagree, the
        inverse is computed afresh; from fresh values that violate a bound the dual simplex goes on (its optimum
        is then confirmed by the primal pricing). After a failed solve the basis is dropped (:attr:`ready`
        False) until the next :meth:`start`.

        Parameters
        ----------
        cost : numpy.ndarray, shape (cols,)
            The objective's coefficients of ``z``.

        Returns
        -------
        optimal : bool
            Whether it ended optimal (then :meth:`row_duals` and :meth:`values` are the optimum's).
        pivots : int
            Pivots and bound flips taken.

        Notes
        -----
        :attr:`exit` says how it ended: ``"optimal"``, ``"pivot limit"``, ``"unbounded"``, ``"infeasible"``,
        ``"inaccurate"`` (every fresh inverse used up), ``"singular basis"`` or ``"no basis"`` (none loaded).
        """
        if not self.ready:
            if self.exit != "singular basis":
                self.exit = "no basis"
            return False, 0
        cost = np.asarray(cost, dtype=float)
        total = 0
        for _ in range(REFACTORISATIONS):
            primal = self.feasible
            outcome, pivots, feasible, duals = _solve_once(
                primal,
                self.matrix_t,
                cost,
                self.lower,
                self.upper,
                self.x,
                self.status,
                self.basic,
                self.inverse,
                self.dual_tol,
                self.primal_tol,
                self.pivot_limit - total,
            )
            total += int(pivots)
            self.exit = EXITS[int(outcome)]
            if outcome == OPTIMAL:
                self.feasible = feasible
                if feasible and primal:
                    self.duals = duals
                    return True, total
                if feasible:
                    continue  # the dual simplex's optimum: confirmed by the primal pricing
            elif outcome != INACCURATE:
                break
            fresh = self._refactor()
            if fresh is None:
                self.exit = "singular basis"
                break
            self.feasible = fresh
        else:
            self.exit = "inaccurate"  # every fresh inverse used up
        self.ready = False
        return False, total

    def row_duals(self) -> FloatArray:
        """The row multipliers of the last optimum, refined once against the residual of ``λ B = c_B``.

        Returns
        -------
        numpy.ndarray, shape (rows,)
            ``λ`` with ``c - Aᵀλ`` the columns' reduced costs (HiGHS's sign convention of row duals).
        """
        return self.duals.copy()

    def statuses(self) -> NDArray[np.int64]:
        """The status of every variable.

        Returns
        -------
        numpy.ndarray of int, shape (cols + rows,)
            Columns, then rows: 0 nonbasic at its lower bound, 1 basic, 2 nonbasic at its upper bound, 3 nonbasic
            free.
        """
        return self.status.copy()

    def basic_variables(self) -> NDArray[np.int64]:
        """The basic variables.

        Returns
        -------
        numpy.ndarray of int, shape (rows,)
            In HiGHS's convention: ``j ≥ 0`` column ``j``, ``-1 - r`` row ``r``.
        """
        return np.where(self.basic < self.cols, self.basic, self.cols - 1 - self.basic)

    def values(self) -> FloatArray:
        """The values at the current basis.

        Returns
        -------
        numpy.ndarray, shape (cols + rows,)
            The columns' values, then the rows' (``A z``).
        """
        return self.x.copy()


def load_kernels() -> None:
    """Load the compiled kernels now, from Numba's cache (compiling them on a fresh install, 10–15 s).

    Otherwise the first :meth:`DenseSimplex.start` and :meth:`DenseSimplex.solve` of a process pay it; a benchmark
    calls this before it times anything.
    """
    simplex = DenseSimplex(np.ones((1, 1)), 1e-9, 1e-9, pivot_limit=10)
    one = np.ones(1)
    simplex.start(-one, one, -one, one, np.array([0]), np.zeros(2))
    simplex.solve(one)
