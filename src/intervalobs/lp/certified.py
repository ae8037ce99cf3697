r"""Linear programmes with certified bounds: HiGHS finds multipliers, weak duality turns them into a proof.

A simplex optimum is only accurate to the solver's tolerances, which is not a guarantee. A bound of
:math:`\min c^\top x` over :math:`\underline b \le Ax \le \overline b`, :math:`\underline x \le x \le
\overline x` is instead taken from weak duality (Neumaier & Shcherbina 2004, "Safe bounds in linear
and mixed-integer programming"): for *any* row multipliers :math:`\lambda`, with :math:`r = c -
A^\top\lambda`,

.. math:: c^\top x \ge \sum_i \min(\lambda_i \underline b_i, \lambda_i \overline b_i)
                      + \sum_j \min(r_j \underline x_j, r_j \overline x_j)

for every feasible :math:`x`. The solver's duals are used as :math:`\lambda`; the bound is valid
whatever their accuracy, and the rounding of its own evaluation is bounded and subtracted
(:func:`dual_bounds`). The exact hull (:mod:`intervalobs.observers.hull`) and the robust hull
(:mod:`intervalobs.observers.robust_hull`) take every outer bound from here.

The other direction, an *inner* bound (a value that a consistent state attains), comes from the
solver's primal points, which are feasible only to its primal tolerance: :func:`shrink_inward` moves
such bounds inward by a relative :data:`INNER_SHRINK` to cover it.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from .chain import RecordsPath, SolverPath
from .compensated import RowProducts

__all__ = [
    "FEASIBILITY_TOLERANCE",
    "INNER_SHRINK",
    "LP_OPTIONS",
    "LP_TIME_LIMIT",
    "DenseLP",
    "basic_variables",
    "centred_bounds",
    "dual_bounds",
    "highs_model",
    "new_highs",
    "run_highs",
    "shrink_inward",
]

FloatArray = NDArray[np.float64]

_EPS = float(np.finfo(float).eps)

FEASIBILITY_TOLERANCE = 1e-9
"""Primal and dual feasibility tolerance of the LP solves (:func:`new_highs`; HiGHS's default is 1e-7): the
certified bounds are then within about this much, times the multipliers, of the optimum."""

LP_TIME_LIMIT = 30.0
"""Seconds one LP solve may take (HiGHS's ``time_limit``): a solve that reaches it ends without an optimum, which
every caller treats as a failed solve (a skipped candidate, a fallback box or a named error), never a wait.
The largest LPs of the test suite and the benchmarks take well under a second."""

LP_OPTIONS = {"time_limit": LP_TIME_LIMIT}
"""``options`` of every ``scipy.optimize.linprog`` call of the package."""

INNER_SHRINK = 1e-6
"""Relative inward margin of inner (lower-bound) hulls: covers the solver's primal tolerance (1e-7)."""


def new_highs() -> Any:
    """A silent HiGHS instance: dual simplex, no presolve, one thread, feasibility tolerances 1e-9.

    Returns
    -------
    highspy.Highs
        The low-level instance (the public wrapper prints a banner on construction).
    """
    try:
        from highspy._core import _Highs as highs_class
    except ImportError:  # pragma: no cover - older highspy
        from highspy import Highs as highs_class
    solver = highs_class()
    solver.setOptionValue("output_flag", False)
    solver.setOptionValue("presolve", "off")
    solver.setOptionValue("solver", "simplex")
    # One thread: the default (0) makes every run() count the physical cores from sysfs twice (a large share
    # of the run time of a warm-started window LP). See run_highs for the fallback.
    solver.setOptionValue("threads", 1)
    solver.setOptionValue("time_limit", LP_TIME_LIMIT)
    solver.setOptionValue("primal_feasibility_tolerance", FEASIBILITY_TOLERANCE)
    solver.setOptionValue("dual_feasibility_tolerance", FEASIBILITY_TOLERANCE)
    return solver


def run_highs(solver: Any) -> None:
    """``solver.run()``, falling back to HiGHS's default thread count if one thread is refused.

    HiGHS keeps one task scheduler per process: when another user of highspy has started it with more
    threads, a run with ``threads = 1`` returns an error, and the default (0: use that scheduler) works.
    An error can also come from a restored basis (an alien one that HiGHS completed badly): the run is
    first repeated from scratch, and only an error that persists is taken for the thread refusal.

    Each run may take :data:`LP_TIME_LIMIT` seconds: HiGHS's ``time_limit`` is read against the run time the
    instance has accumulated over all its runs (``getRunTime``), so it is moved on before every run. (Set once, it
    made every run of a long-lived instance end "time limit reached" once its runs had taken 30 s together: the
    McCormick LP of the two-tank reproduction lost 4.5 % of its mean width, by an amount that depended on the
    machine's load.)

    Parameters
    ----------
    solver : highspy.Highs
        An instance from :func:`new_highs` with a model passed.
    """
    from highspy import _core

    solver.setOptionValue("time_limit", solver.getRunTime() + LP_TIME_LIMIT)
    error = _core.HighsStatus.kError
    if solver.run() == error and solver.getOptionValue("threads")[1] == 1:
        solver.clearSolver()
        if solver.run() == error:
            solver.setOptionValue("threads", 0)
            solver.run()


def basic_variables(solver: Any) -> NDArray[np.int64]:
    """The basic variables of HiGHS's current basis: ``j ≥ 0`` column ``j``, ``-1 - r`` row ``r``.

    Read from the basis statuses, not from ``getBasicVariables``: that call reads HiGHS's factorisation, which a
    model with an empty matrix (an all-zero output row, no outputs) never builds, and it then ends the process
    with a segmentation fault (highspy 1.x).

    Parameters
    ----------
    solver : highspy.Highs
        An instance after a run that ended optimal.

    Returns
    -------
    numpy.ndarray of int
    """
    from highspy import _core

    basis = solver.getBasis()
    is_basic = _core.HighsBasisStatus.kBasic
    cols = [j for j, status in enumerate(basis.col_status) if status == is_basic]
    rows = [-1 - r for r, status in enumerate(basis.row_status) if status == is_basic]
    return np.asarray(cols + rows, dtype=np.int64)


def highs_model(
    matrix: FloatArray | sparse.csc_matrix,
    col_lo: FloatArray,
    col_hi: FloatArray,
    row_lo: FloatArray,
    row_hi: FloatArray,
    inf: float,
) -> Any:
    """The HiGHS model of ``row_lo ≤ A z ≤ row_hi``, ``col_lo ≤ z ≤ col_hi`` with zero costs.

    Parameters
    ----------
    matrix : numpy.ndarray or scipy.sparse.csc_matrix, shape (rows, cols)
        ``A``: a dense array is passed row by row with every entry, a CSC matrix column by column.
    col_lo, col_hi : numpy.ndarray, shape (cols,)
        Variable bounds.
    row_lo, row_hi : numpy.ndarray, shape (rows,)
        Row bounds; infinite ones become HiGHS's ``inf``.
    inf : float
        HiGHS's infinity (``solver.getInfinity()``).

    Returns
    -------
    highspy.HighsLp
    """
    from highspy import _core

    nrow, ncol = matrix.shape
    lp = _core.HighsLp()
    lp.num_col_, lp.num_row_ = ncol, nrow
    lp.col_cost_ = np.zeros(ncol)
    lp.col_lower_, lp.col_upper_ = col_lo, col_hi
    lp.row_lower_ = np.where(np.isfinite(row_lo), row_lo, -inf)
    lp.row_upper_ = np.where(np.isfinite(row_hi), row_hi, inf)
    if isinstance(matrix, sparse.csc_matrix):
        lp.a_matrix_.format_ = _core.MatrixFormat.kColwise
        lp.a_matrix_.start_ = np.asarray(matrix.indptr, dtype=np.int32)
        lp.a_matrix_.index_ = np.asarray(matrix.indices, dtype=np.int32)
        lp.a_matrix_.value_ = np.asarray(matrix.data, dtype=float)
    else:
        lp.a_matrix_.format_ = _core.MatrixFormat.kRowwise
        lp.a_matrix_.start_ = (np.arange(nrow + 1) * ncol).astype(np.int32)
        lp.a_matrix_.index_ = np.tile(np.arange(ncol, dtype=np.int32), nrow)
        lp.a_matrix_.value_ = np.asarray(matrix, dtype=float).ravel()
    return lp


class LinearProgram(Protocol):
    """What :func:`dual_bounds` reads from an LP: its bounds and its transposed matrix."""

    row_lo: FloatArray
    row_hi: FloatArray
    col_lo: FloatArray
    col_hi: FloatArray
    matrix_t: Any
    """``Aᵀ`` (dense or sparse), shape (cols, rows)."""
    abs_matrix_t: Any
    """``|A|ᵀ``."""
    col_nnz: int
    """Largest number of nonzeros of a column of ``A`` (terms of a reduced cost)."""


def dual_bounds(lp: LinearProgram, costs: FloatArray, duals: FloatArray) -> FloatArray:
    """Weak-duality bounds of ``min costs[r]·z`` for the multipliers ``duals[r]``, rounding subtracted.

    A multiplier on an infinite side of its row is dropped (any multipliers give a valid bound). The
    sums include zero terms, which only enlarges the term counts of the rounding bound. The rounding
    grows with the magnitude of the bounds: an LP of states far from the origin is better solved in
    coordinates centred near them (:func:`centred_bounds`).

    Parameters
    ----------
    lp : LinearProgram
        The LP's bounds and matrix.
    costs : numpy.ndarray, shape (R, cols)
        One objective per row.
    duals : numpy.ndarray, shape (R, rows)
        Row multipliers of each objective (e.g. the solver's duals).

    Returns
    -------
    numpy.ndarray, shape (R,)
        ``value[r] ≤ costs[r]·z`` for every feasible ``z`` (``-inf`` when an infinite variable bound
        meets a reduced cost that may be nonzero).
    """
    row_bound = np.where(duals > 0, lp.row_lo, lp.row_hi)
    used = np.isfinite(row_bound) & (duals != 0)
    y = np.where(used, duals, 0.0)
    row_terms = np.multiply(y, row_bound, out=np.zeros(y.shape), where=used)
    reduced = costs - (lp.matrix_t @ y.T).T
    col_bound = np.where(reduced > 0, lp.col_lo, lp.col_hi)
    active = reduced != 0
    reduced_error = (lp.col_nnz + 2) * _EPS * (np.abs(costs) + (lp.abs_matrix_t @ np.abs(y).T).T)
    magnitude = np.maximum(np.abs(lp.col_lo), np.abs(lp.col_hi))
    infinite = ~np.isfinite(magnitude)
    # An infinite column is harmless only if its reduced cost is zero even after rounding.
    unbounded = np.any(active & ~np.isfinite(col_bound), axis=1) | np.any((reduced_error > 0) & infinite, axis=1)
    col_terms = np.multiply(reduced, col_bound, out=np.zeros(reduced.shape), where=active & ~unbounded[:, None])
    magnitude[infinite] = 0.0
    terms = row_terms.shape[1] + col_terms.shape[1] + 2
    error = reduced_error @ magnitude + terms * _EPS * (np.abs(row_terms).sum(axis=1) + np.abs(col_terms).sum(axis=1))
    value = row_terms.sum(axis=1) + col_terms.sum(axis=1) - 2.0 * error
    return np.asarray(np.where(unbounded, -np.inf, value))


def _outward(value: FloatArray, error: FloatArray | float, side: float) -> FloatArray:
    """``value`` moved by ``error`` plus two roundings of itself toward ``side`` (±1), then one ulp more."""
    moved = value + side * (np.asarray(error) + 2.0 * _EPS * np.abs(value))
    return np.asarray(np.nextafter(moved, side * np.inf))


def centred_bounds(
    bounds: tuple[FloatArray, FloatArray, FloatArray, FloatArray], products: RowProducts, centre: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    r"""The bounds of an LP in ``d = z - centre``, rounded outward: the same feasible set, shifted.

    ``row_lo ≤ A z ≤ row_hi`` becomes ``row_lo - A·centre ≤ A d ≤ row_hi - A·centre`` with ``A·centre``
    from compensated products, so the shifted bounds lose about one rounding of the *residual*, not of
    ``A·centre``. With the centre near the feasible set, the solver and the weak-duality certificate work
    on small numbers: at states of :math:`3\cdot 10^6` with noise of :math:`10^{-9}`, the tolerance of
    the solver and the rounding of the certificate no longer scale with the states' magnitude.

    Parameters
    ----------
    bounds : (col_lo, col_hi, row_lo, row_hi)
        The LP's bounds (infinite entries stay infinite).
    products : RowProducts
        Of the LP's matrix.
    centre : numpy.ndarray, shape (cols,)
        Finite.

    Returns
    -------
    col_lo, col_hi, row_lo, row_hi : numpy.ndarray
    """
    col_lo, col_hi, row_lo, row_hi = bounds
    image, error = products.enclose(centre)
    return (
        _outward(col_lo - centre, 0.0, -1.0),
        _outward(col_hi - centre, 0.0, 1.0),
        _outward(row_lo - image, error, -1.0),
        _outward(row_hi - image, error, 1.0),
    )


class DenseLP(RecordsPath):
    """An LP ``row_lo ≤ A z ≤ row_hi``, ``col_lo ≤ z ≤ col_hi`` solved by HiGHS; bounds by weak duality.

    ``A`` is dense, or sparse (CSC) for a model with few nonzeros.

    A new model is passed with :meth:`load` (the last basis is kept when the sizes agree); :meth:`minima`
    solves several objectives in turn, each from the previous basis, again from scratch where that ends without an
    optimum.
    """

    def __init__(self) -> None:
        self.solver = new_highs()
        self.inf = float(self.solver.getInfinity())
        self.path = SolverPath()

    def load(
        self,
        matrix: FloatArray | sparse.csc_matrix,
        col_lo: FloatArray,
        col_hi: FloatArray,
        row_lo: FloatArray,
        row_hi: FloatArray,
    ) -> None:
        """Pass a new model.

        Parameters
        ----------
        matrix : numpy.ndarray or scipy.sparse.csc_matrix, shape (rows, cols)
            ``A``.
        col_lo, col_hi : numpy.ndarray, shape (cols,)
            Variable bounds (finite).
        row_lo, row_hi : numpy.ndarray, shape (rows,)
            Row bounds (may be infinite).
        """
        if isinstance(matrix, sparse.csc_matrix):
            self.matrix_t: Any = matrix.T.tocsr()
            self.abs_matrix_t: Any = abs(self.matrix_t)
            self.col_nnz = int(np.max(np.diff(matrix.indptr), initial=0))
        else:
            self.matrix_t = np.ascontiguousarray(matrix.T)
            self.abs_matrix_t = np.abs(self.matrix_t)
            self.col_nnz = matrix.shape[0]
        self.nrow, self.ncol = matrix.shape
        self.col_lo, self.col_hi, self.row_lo, self.row_hi = col_lo, col_hi, row_lo, row_hi
        self.solver.passModel(highs_model(matrix, col_lo, col_hi, row_lo, row_hi, self.inf))
        self._cols = np.arange(self.ncol, dtype=np.int32)

    def minima(self, costs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Certified lower bounds of ``costs[r] · z`` and the solver's optimal points.

        Parameters
        ----------
        costs : numpy.ndarray, shape (R, cols)
            One objective per row.

        Returns
        -------
        bounds : numpy.ndarray, shape (R,)
            Weak-duality bounds (``-inf`` where the solver returned no usable duals).
        points : numpy.ndarray, shape (R, cols)
            The solver's optimal points (NaN where it reported no optimum).
        """
        from highspy import _core

        duals = np.zeros((costs.shape[0], self.nrow))
        points = np.full((costs.shape[0], self.ncol), np.nan)
        usable = np.ones(costs.shape[0], dtype=bool)
        for r, cost in enumerate(costs):
            self.solver.changeColsCost(self.ncol, self._cols, cost)
            run_highs(self.solver)
            self.path.pivots += int(self.solver.getInfo().simplex_iteration_count)
            optimal = self.solver.getModelStatus() == _core.HighsModelStatus.kOptimal
            self.path.highs_warm += optimal
            if not optimal:  # a warm start that stalls (badly scaled objectives) is solved again from scratch
                self.solver.clearSolver()
                run_highs(self.solver)
                self.path.pivots += int(self.solver.getInfo().simplex_iteration_count)
                optimal = self.solver.getModelStatus() == _core.HighsModelStatus.kOptimal
                self.path.scratch += optimal
            self.path.failed += not optimal
            solution = self.solver.getSolution()
            dual = np.asarray(solution.row_dual)
            if dual.shape != (self.nrow,) or not np.all(np.isfinite(dual)):
                usable[r] = False
                continue
            duals[r] = dual
            if optimal:
                points[r] = np.asarray(solution.col_value)
        return np.where(usable, dual_bounds(self, costs, duals), -np.inf), points


def shrink_inward(lower: FloatArray, upper: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Move inner bounds (values attained by the solver's primal points) inward by :data:`INNER_SHRINK`.

    Parameters
    ----------
    lower, upper : numpy.ndarray
        Inner bounds (NaN where undefined, kept).

    Returns
    -------
    lower, upper : numpy.ndarray
        Shrunk by ``INNER_SHRINK (1 + max(|lower|, |upper|))``; where they cross, both become the midpoint.
    """
    shrink = INNER_SHRINK * (1.0 + np.maximum(np.abs(lower), np.abs(upper)))
    lower, upper = lower + shrink, upper - shrink
    middle = 0.5 * (lower + upper)
    crossed = lower > upper
    return np.where(crossed, middle, lower), np.where(crossed, middle, upper)
