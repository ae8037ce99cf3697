r"""The window LP of the exact hull: the states of ``H + 1`` steps, their noises and measurements as variables.

:class:`SparseWindowLP` holds the LP of a window (built once, only bounds and costs change from one step to the
next), :class:`SparseWindow` fills its bounds from a record and the boxes found before, :class:`WindowModel` is the
linear model both read. The estimators (:class:`~intervalobs.observers.hull.HullEstimator`,
:func:`~intervalobs.tightness.hull_lower_bound`) say what is estimated; how the LP is solved and certified is here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from .._docstrings import shared_docs
from ..errors import AssumptionError
from ..interval import ROUNDING_MARGIN, inflate, matvec_bounds
from .certified import centred_bounds, dual_bounds, highs_model, new_highs, run_highs
from .chain import RecordsPath, SolverPath
from .compensated import RowProducts

__all__ = ["SharedDeltaB", "SparseWindow", "SparseWindowLP", "WindowModel", "window_state_maps"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SharedDeltaB:
    r"""An input-matrix error that is one unknown for the whole window: step ``j`` adds :math:`\Psi\beta u_j`.

    With :math:`B + \Delta B` and :math:`\Delta B = \Delta B_c + \beta` constant in time, the sampled model's
    :math:`\Gamma` holds :math:`\Delta B_c` and every step adds :math:`\Psi\beta u_j` with
    :math:`\Psi = \int_0^h e^{As}ds` (the identity in discrete time): linear in the entries of :math:`\beta`
    for known :math:`u_j`, so the window LP takes them as unknowns shared by all its steps
    (:class:`SparseWindowLP`).

    Parameters
    ----------
    map : numpy.ndarray, shape (n, n)
        :math:`\Psi` (the midpoint of its enclosure).
    radius : numpy.ndarray, shape (n, m)
        :math:`|\beta| \le` ``radius`` entry by entry (zero entries are not unknowns).
    residual : numpy.ndarray, shape (n, m)
        What the shared unknowns leave out (the radius of :math:`\Psi` times ``radius``, and the rounding of
        :math:`\Psi`): step ``j``'s noise box is widened by ``residual @ |u_j|``.
    """

    map: FloatArray
    radius: FloatArray
    residual: FloatArray

    def entries(self) -> NDArray[np.intp]:
        """The entries ``(a, b)`` of :math:`\beta` that are unknowns (nonzero radius), row-major.

        Returns
        -------
        numpy.ndarray, shape (count, 2)
        """
        return np.argwhere(self.radius > 0)


@dataclass(frozen=True)
class WindowModel:
    """``x+ = Φx + Γu + noise``, ``y = Cx + noise`` with box or variable noise (see :class:`SparseWindowLP`).

    ``G is None``: the process noise is the box ``x+ - Φx - Γu ∈ [w_lo, w_hi]``; otherwise
    ``x+ = Φx + Γu + G w`` with ``w ∈ [w_lo, w_hi]``. Likewise ``F is None``: ``y - Cx ∈ [v_lo, v_hi]``;
    otherwise ``y = Cx + F v``, ``v ∈ [v_lo, v_hi]``.

    Parameters
    ----------
    Phi, Gamma : numpy.ndarray
        Transition and input matrices.
    G : numpy.ndarray or None
        Map of the noise variables to the states (None: the noise is a box of the states).
    w_lo, w_hi : numpy.ndarray
        Box of the process noise.
    C : numpy.ndarray
        Output matrix.
    F : numpy.ndarray or None
        Map of the measurement-noise variables to the outputs (None: a box of the outputs).
    v_lo, v_hi : numpy.ndarray
        Box of the measurement noise.
    dGamma : numpy.ndarray, optional
        Elementwise radius of an interval input matrix ``Γ ± δΓ`` (an uncertain ``B``): step ``j``'s noise box
        is widened by ``δΓ|u_j|`` (:meth:`noise_box`), i.e. ``ΔΓ`` is free at every step. Box noise only
        (``G`` None).
    shared_dB : SharedDeltaB, optional
        With ``dGamma``: keep one input-matrix error for the whole window (:class:`SparseWindowLP` only); the
        window's noise rows are then widened by its ``residual`` only (:meth:`window_noise_box`), while
        :meth:`propagate` (one step, no memory) keeps ``dGamma``.
    """

    Phi: FloatArray
    Gamma: FloatArray
    G: FloatArray | None
    w_lo: FloatArray
    w_hi: FloatArray
    C: FloatArray
    F: FloatArray | None
    v_lo: FloatArray
    v_hi: FloatArray
    dGamma: FloatArray | None = None
    shared_dB: SharedDeltaB | None = None

    def __post_init__(self) -> None:
        if self.dGamma is not None and self.G is not None:
            raise AssumptionError("WindowModel: an interval input matrix (dGamma) needs box process noise (G None)")
        if self.shared_dB is not None and self.dGamma is None:
            raise AssumptionError("WindowModel: a shared input-matrix error (shared_dB) needs its dGamma")

    @shared_docs
    def window_noise_box(self, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Box of the process noise in a window LP: :meth:`noise_box`, or with ``shared_dB`` only its residual.

        %(step_inputs)s
        """
        if self.shared_dB is None:
            return self.noise_box(u)
        spread = np.abs(u) @ self.shared_dB.residual.T
        return inflate(self.w_lo - spread, self.w_hi + spread, scale=np.abs(self.w_lo) + np.abs(self.w_hi) + spread)

    @shared_docs
    def noise_box(self, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Box of ``x+ - Φx - Γu`` (``G`` None) or of ``w`` for the inputs ``u`` (shape (..., m)).

        %(step_inputs)s
            ``[w_lo - δΓ|u|, w_hi + δΓ|u|]`` rounded outward; ``[w_lo, w_hi]`` broadcast without ``dGamma``.
        """
        shape = (*np.shape(u)[:-1], self.w_lo.shape[0])
        if self.dGamma is None:
            return np.broadcast_to(self.w_lo, shape).copy(), np.broadcast_to(self.w_hi, shape).copy()
        spread = np.abs(u) @ self.dGamma.T
        return inflate(self.w_lo - spread, self.w_hi + spread, scale=np.abs(self.w_lo) + np.abs(self.w_hi) + spread)

    def propagate(self, lower: FloatArray, upper: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Sound interval image of a box through one step (no measurement), inflated for rounding.

        Parameters
        ----------
        lower, upper : numpy.ndarray, shape (n,)
            The box.
        u : numpy.ndarray, shape (m,)
            The known input.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (n,)
        """
        lo, hi = matvec_bounds(self.Phi, lower, upper)
        if self.G is None:
            w_lo, w_hi = self.noise_box(u)
            lo, hi = lo + w_lo, hi + w_hi
        else:
            wl, wh = matvec_bounds(self.G, self.w_lo, self.w_hi)
            lo, hi = lo + wl, hi + wh
        drive = self.Gamma @ u
        return inflate(lo + drive, hi + drive, 8 * ROUNDING_MARGIN)


@shared_docs
class SparseWindowLP(RecordsPath):
    """The hull LP over a window of ``H`` steps, built once; each step changes only bounds and costs.

    Slot ``i = 0 … H`` holds time ``k - H + i``; the dynamics rows link slot ``i`` to ``i + 1`` (and,
    freed, the last to the first, so the matrix is a fixed cycle). Slots of times before 0 are fixed at
    0 with their rows freed, so one model serves every step. The optimal basis of each objective is
    kept and restored at the next step: the extremal trajectory seen from ``x_k`` changes little when
    the window moves, so the dual simplex restarts close to the optimum.

    With ``model.shared_dB`` the entries of ``β`` (:class:`SharedDeltaB`) are the last columns, one set for the
    whole window, in their box; slot ``i``'s dynamics rows get ``-Ψ β u_i``, coefficients that move with the
    inputs and are set at every step (:meth:`set_inputs`). The true ``ΔB`` is constant over the record, hence
    over every window, so the LP's set still contains the truth.

    %(window)s
    """

    def __init__(self, model: WindowModel, horizon: int, points: int = 0) -> None:
        self.model, self.horizon, self.points = model, horizon, points
        n, p = model.C.shape[1], model.C.shape[0]
        S = horizon + 1
        nq = 0 if model.G is None else model.G.shape[1]
        nv = 0 if model.F is None else model.F.shape[1]
        self.n, self.p, self.nq, self.nv, self.slots = n, p, nq, nv, S
        self.w0 = S * n
        self.v0 = self.w0 + S * nq
        self.l0 = self.v0 + S * nv
        self.b0 = self.l0 + points
        self.dB_entries = np.zeros((0, 2), dtype=np.intp) if model.shared_dB is None else model.shared_dB.entries()
        nb = self.dB_entries.shape[0]
        self.ncol = self.b0 + nb
        self.y0 = S * n
        self.p0 = self.y0 + S * p
        self.nrow = self.p0 + (n + 1 if points else 0)
        cycle = sparse.eye(S, S, k=1, format="lil")
        cycle[S - 1, 0] = 1.0
        dyn_x = sparse.kron(cycle.tocsr(), sparse.eye(n)) - sparse.kron(sparse.eye(S), sparse.csr_matrix(model.Phi))
        blocks: list[list[Any]] = [[dyn_x, None, None, None, None], [None] * 5, [None] * 5]
        if nq:
            assert model.G is not None
            blocks[0][1] = -sparse.kron(sparse.eye(S), sparse.csr_matrix(model.G))
        blocks[1][0] = sparse.kron(sparse.eye(S), sparse.csr_matrix(model.C))
        if nv:
            assert model.F is not None
            blocks[1][2] = -sparse.kron(sparse.eye(S), sparse.csr_matrix(model.F))
        if points:
            prior = sparse.hstack([sparse.eye(n), sparse.csr_matrix((n, (S - 1) * n))])
            blocks[2][0] = sparse.vstack([prior, sparse.csr_matrix((1, S * n))])
            blocks[2][3] = sparse.csr_matrix(np.ones((n + 1, points)))
        if nb:
            assert model.shared_dB is not None  # the pattern of -Ψβu_i with u_i = 1 (values set by set_inputs)
            psi_columns = model.shared_dB.map[:, self.dB_entries[:, 0]]
            blocks[0][4] = -sparse.kron(np.ones((S, 1)), sparse.csr_matrix(psi_columns))
        widths = [S * n, S * nq, S * nv, points, nb]
        heights = [S * n, S * p, n + 1 if points else 0]
        rows = []
        for r, hgt in enumerate(heights):
            if hgt == 0:
                continue
            rows.append(
                [
                    blocks[r][c] if blocks[r][c] is not None else sparse.csr_matrix((hgt, wdt))
                    for c, wdt in enumerate(widths)
                    if wdt
                ]
            )
        matrix = sparse.csc_matrix(sparse.bmat(rows, format="csc"))
        matrix.eliminate_zeros()
        matrix.sort_indices()
        self.matrix = matrix
        self.matrix_t = matrix.T.tocsr()
        self.abs_matrix_t = abs(self.matrix_t)
        self._dB_pattern(model)
        self.col_nnz = int(np.max(np.diff(matrix.indptr))) if matrix.nnz else 0
        self.solver = new_highs()
        self.inf = float(self.solver.getInfinity())
        free_cols, free_rows = np.full(self.ncol, self.inf), np.full(self.nrow, self.inf)
        self.solver.passModel(highs_model(matrix, -free_cols, free_cols, -free_rows, free_rows, self.inf))
        from highspy import _core

        self._status_optimal = _core.HighsModelStatus.kOptimal
        self._cols = np.arange(self.ncol, dtype=np.int32)
        self._rows = np.arange(self.nrow, dtype=np.int32)
        self._cost_col = -1
        self._products: RowProducts | None = None  # of the matrix, for the centred bounds (built once)
        self.centre = np.zeros(self.ncol)
        self._bases: dict[tuple[int, float], Any] = {}
        self.path = SolverPath()

    def _dB_pattern(self, model: WindowModel) -> None:
        """Where the coefficients of the shared ``β`` sit: the last entries of the CSC data (and of the CSR data
        of the transpose, in the same order), with the ``-Ψ`` entry, the slot and the input each one takes."""
        first = int(self.matrix.indptr[self.b0])
        rows = self.matrix.indices[first:].astype(np.intp)
        columns = np.repeat(np.arange(self.dB_entries.shape[0]), np.diff(self.matrix.indptr[self.b0 :]))
        assert np.array_equal(self.matrix_t.indices[first:], rows)  # the transpose keeps the order
        self._dB_first, self._dB_rows = first, rows
        self._dB_cols = (self.b0 + columns).astype(np.int32)
        self._dB_slot = rows // self.n
        self._dB_input = self.dB_entries[columns, 1]
        self._dB_base = np.asarray(self.matrix.data[first:]).copy()

    def set_inputs(self, u: FloatArray) -> None:
        """Coefficients of the shared ``β`` for the inputs of the window's slots (no-op without ``shared_dB``).

        Parameters
        ----------
        u : numpy.ndarray, shape (slots, m)
            Row ``i``: the input of the step out of slot ``i`` (zero for a step outside the window).
        """
        if self._dB_rows.size == 0:
            return
        values = self._dB_base * u[self._dB_slot, self._dB_input]
        first = self._dB_first
        self.matrix.data[first:] = values
        self.matrix_t.data[first:] = values
        self.abs_matrix_t.data[first:] = np.abs(values)
        for row, col, value in zip(self._dB_rows.tolist(), self._dB_cols.tolist(), values.tolist()):
            self.solver.changeCoeff(row, col, value)

    def forget_bases(self) -> None:
        """Drop the bases kept for warm starts and the solver's own (the next solves start from scratch)."""
        self._bases.clear()
        self.solver.clearSolver()

    def newest_column(self, i: int) -> int:
        """Column of component ``i`` of the newest state ``x_k`` (always the last slot).

        Parameters
        ----------
        i : int

        Returns
        -------
        int
        """
        return (self.slots - 1) * self.n + i

    def set_points(self, pts: FloatArray) -> None:
        """Prior ``x_{k-H} = P λ`` (first slot) with ``λ`` in the simplex.

        Parameters
        ----------
        pts : numpy.ndarray, shape (points, n)
            The points ``P`` (rows).
        """
        for j in range(self.points):
            for i in range(self.n):
                self.solver.changeCoeff(self.p0 + i, self.l0 + j, -float(pts[j, i]))

    def set_bounds(self, col_lo: FloatArray, col_hi: FloatArray, row_lo: FloatArray, row_hi: FloatArray) -> None:
        """Replace all column and row bounds.

        The LP is solved in coordinates centred on the states' boxes (:func:`centred_bounds`): for states
        far from the origin the solver's tolerances and the certificate's rounding then act on the
        distances to the centres, not on the states themselves. :attr:`col_lo` … :attr:`row_hi` hold the
        centred bounds and :attr:`centre` the centre.

        Parameters
        ----------
        col_lo, col_hi : numpy.ndarray, shape (ncol,)
        row_lo, row_hi : numpy.ndarray, shape (nrow,)
        """
        states = slice(0, self.slots * self.n)  # only the states: the points prior's coefficients vary
        centre = np.zeros(self.ncol)
        lo, hi = col_lo[states], col_hi[states]
        box = np.isfinite(lo) & np.isfinite(hi)
        centre[states][box] = 0.5 * lo[box] + 0.5 * hi[box]
        if self._products is None:  # the β columns' coefficients change, but their centre is always 0
            self._products = RowProducts(self.matrix_t)
        self.centre = centre
        shifted = centred_bounds((col_lo, col_hi, row_lo, row_hi), self._products, centre)
        self.col_lo, self.col_hi, self.row_lo, self.row_hi = shifted
        self.solver.changeColsBounds(self.ncol, self._cols, self.col_lo, self.col_hi)
        self.solver.changeRowsBounds(self.nrow, self._rows, self.row_lo, self.row_hi)

    def _minimise(self, col: int, sign: float, key: int) -> tuple[bool, FloatArray, FloatArray]:
        if self._cost_col >= 0 and self._cost_col != col:
            self.solver.changeColCost(self._cost_col, 0.0)
        self.solver.changeColCost(col, sign)
        self._cost_col = col
        basis = self._bases.get((key, sign))
        if basis is not None:
            self.solver.setBasis(basis)
        run_highs(self.solver)
        ok = self.solver.getModelStatus() == self._status_optimal
        self.path.pivots += int(self.solver.getInfo().simplex_iteration_count)
        self.path.highs_warm += ok  # from the kept basis, or from the last optimum
        self.path.failed += not ok
        if ok:
            self._bases[(key, sign)] = self.solver.getBasis()
        solution = self.solver.getSolution()
        return ok, np.asarray(solution.col_value), np.asarray(solution.row_dual)

    def certified_min(self, col: int, sign: float, key: int) -> float:
        """A rigorous lower bound of ``sign * x[col]`` over the feasible set (weak duality).

        Parameters
        ----------
        col : int
            The variable.
        sign : float
            1 for its minimum, -1 for minus its maximum.
        key : int
            Which kept basis to start from (one per objective and family).

        Returns
        -------
        float
        """
        _, _, dual = self._minimise(col, sign, key)
        if dual.size != self.nrow or not np.all(np.isfinite(dual)):
            return -np.inf
        cost = np.zeros((1, self.ncol))
        cost[0, col] = sign
        shifted = float(dual_bounds(self, cost, dual[None, :])[0])  # of sign * (x[col] - centre[col])
        return float(np.nextafter(sign * self.centre[col] + shifted, -np.inf))

    def primal_min(self, col: int, sign: float, key: int) -> tuple[bool, FloatArray]:
        """The solver's best point (for inner hulls) and whether it is feasible (to 1e-7).

        An inner hull needs feasible points only, not optimal ones: a point that is not optimal makes
        the bound less tight, never invalid.

        Parameters
        ----------
        col : int
            The variable.
        sign : float
            1 for its minimum, -1 for its maximum.
        key : int
            Which kept basis to start from.

        Returns
        -------
        ok : bool
        point : numpy.ndarray, shape (ncol,)
        """
        ok, x, _ = self._minimise(col, sign, key)
        if not ok:
            info = self.solver.getInfo()
            ok = info.primal_solution_status == 2 and info.max_primal_infeasibility <= 1e-7
            ok = ok and x.size == self.ncol and bool(np.all(np.isfinite(x)))
        return ok, x + self.centre if x.size == self.ncol else x


@shared_docs
class SparseWindow:
    """Fills the bounds of a :class:`SparseWindowLP` for step ``k`` from the record and the stored boxes.

    %(window)s
    """

    def __init__(self, model: WindowModel, horizon: int, points: int = 0) -> None:
        self.model = model
        self.lp = SparseWindowLP(model, horizon, points)

    def bounds_at(
        self,
        k: int,
        y: FloatArray,
        u: FloatArray,
        boxes_lo: FloatArray | None,
        boxes_hi: FloatArray | None,
        last_lo: FloatArray,
        last_hi: FloatArray,
        use_current: bool,
        first_lo: FloatArray | None,
        first_hi: FloatArray | None,
        window_boxes: bool = False,
        offset: int = 0,
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Column and row bounds at step ``k``.

        Row ``τ - offset`` of ``y``, ``u`` and ``boxes_*`` is time ``τ``.
        ``boxes_*`` bound ``x_τ`` for ``τ < k`` (None: free, for inner hulls); ``last_*`` bounds
        ``x_k``; ``first_*`` is the prior of the window's first state when it is time 0 (the ``x_0``
        box) — for a later first state the caller sets the points prior or relies on ``boxes``.
        With a shared input-matrix error (``model.shared_dB``) it also sets that error's coefficients for the
        window's inputs (:meth:`SparseWindowLP.set_inputs`) and its box.
        With ``window_boxes`` False only the first state of the window gets its box (the prior); the
        others get a tenfold-widened copy (sound and finite, as the certificate needs, but inactive:
        fewer degenerate pivots).

        Parameters
        ----------
        k : int
            The step.
        y, u : numpy.ndarray
            Measurements and inputs.
        boxes_lo, boxes_hi : numpy.ndarray or None
            Boxes of the earlier states.
        last_lo, last_hi : numpy.ndarray, shape (n,)
            Box of ``x_k``.
        use_current : bool
            Whether ``y_k`` is used.
        first_lo, first_hi : numpy.ndarray or None
            The ``x_0`` box.
        window_boxes : bool
            Whether every state of the window keeps its box.
        offset : int
            The time of row 0 of the record.

        Returns
        -------
        col_lo, col_hi, row_lo, row_hi : numpy.ndarray
        """
        lp, m = self.lp, self.model
        S, n, p, nq, nv = lp.slots, lp.n, lp.p, lp.nq, lp.nv
        inf = lp.inf
        times = k - (S - 1) + np.arange(S)  # the time held by each slot
        valid = times >= 0
        col_lo = np.zeros(lp.ncol)
        col_hi = np.zeros(lp.ncol)
        xl = np.zeros((S, n))
        xh = np.zeros((S, n))
        past = valid & (times < k)
        if boxes_lo is not None and boxes_hi is not None:
            xl[past], xh[past] = boxes_lo[times[past] - offset], boxes_hi[times[past] - offset]
            if not window_boxes:
                loose = past.copy()
                loose[int(np.argmax(past))] = False  # the oldest state keeps its box: the prior
                mid, rad = 0.5 * (xl[loose] + xh[loose]), 0.5 * (xh[loose] - xl[loose])
                xl[loose], xh[loose] = mid - 10.0 * rad - 1.0, mid + 10.0 * rad + 1.0
        else:
            xl[past], xh[past] = -inf, inf
        xl[S - 1], xh[S - 1] = last_lo, last_hi
        if first_lo is not None and first_hi is not None and k < S:
            xl[S - 1 - k] = np.maximum(xl[S - 1 - k], first_lo)
            xh[S - 1 - k] = np.minimum(xh[S - 1 - k], first_hi)
        col_lo[: S * n], col_hi[: S * n] = xl.ravel(), xh.ravel()
        step_valid = past  # the transition out of each slot's time is in the window iff that time < k
        ut = np.zeros((S, u.shape[-1]))
        ut[step_valid] = u[times[step_valid] - offset]
        drive = ut @ m.Gamma.T
        if m.shared_dB is not None:
            lp.set_inputs(ut)
            radius = m.shared_dB.radius[lp.dB_entries[:, 0], lp.dB_entries[:, 1]]
            col_lo[lp.b0 :], col_hi[lp.b0 :] = -radius, radius
        if nq:
            wl = np.where(step_valid[:, None], m.w_lo, 0.0)
            wh = np.where(step_valid[:, None], m.w_hi, 0.0)
            col_lo[lp.w0 : lp.v0], col_hi[lp.w0 : lp.v0] = wl.ravel(), wh.ravel()
            d_lo, d_hi = drive, drive.copy()
        else:
            w_lo, w_hi = m.window_noise_box(ut)
            d_lo, d_hi = drive + w_lo, drive + w_hi
        d_lo = np.where(step_valid[:, None], d_lo, -inf)
        d_hi = np.where(step_valid[:, None], d_hi, inf)
        measured = valid & ((times < k) | use_current)
        yt = np.zeros((S, p))
        yt[measured] = y[times[measured] - offset]
        if nv:
            vl = np.where(measured[:, None], m.v_lo, 0.0)
            vh = np.where(measured[:, None], m.v_hi, 0.0)
            col_lo[lp.v0 : lp.l0], col_hi[lp.v0 : lp.l0] = vl.ravel(), vh.ravel()
            y_lo, y_hi = yt, yt.copy()
        else:
            y_lo, y_hi = yt - m.v_hi, yt - m.v_lo
        y_lo = np.where(measured[:, None], y_lo, -inf)
        y_hi = np.where(measured[:, None], y_hi, inf)
        row_lo = np.full(lp.nrow, -inf)
        row_hi = np.full(lp.nrow, inf)
        row_lo[: lp.y0], row_hi[: lp.y0] = d_lo.ravel(), d_hi.ravel()
        row_lo[lp.y0 : lp.p0], row_hi[lp.y0 : lp.p0] = y_lo.ravel(), y_hi.ravel()
        return col_lo, col_hi, row_lo, row_hi


def window_state_maps(
    phi: FloatArray, gamma: FloatArray, noise: FloatArray, sens: FloatArray, us: FloatArray
) -> tuple[FloatArray, FloatArray]:
    r"""States of a window as affine maps of ``z = (x_s, q_0 … q_{L-1}, δ)``: ``x_j = S_j z + d_j``.

    ``x_{j+1} = Φ x_j + Γ u_j + G q_j + W_j δ`` with ``noise`` = G (n, n_q) and ``sens[j]`` = W_j (n, n_δ);
    ``us`` has ``L`` rows.

    Parameters
    ----------
    phi, gamma : numpy.ndarray
        ``Φ`` and ``Γ``.
    noise : numpy.ndarray, shape (n, n_q)
        ``G``.
    sens : numpy.ndarray, shape (L, n, n_δ)
        ``W_j``.
    us : numpy.ndarray, shape (L, m)
        The inputs.

    Returns
    -------
    state : numpy.ndarray, shape (L + 1, n, ncol)
        ``S``.
    drive : numpy.ndarray, shape (L + 1, n)
        ``d``.
    """
    n, nq = noise.shape
    L, nd = us.shape[0], sens.shape[-1]
    ncol = n + L * nq + nd
    state = np.zeros((L + 1, n, ncol))
    drive = np.zeros((L + 1, n))
    state[0, :, :n] = np.eye(n)
    for j in range(L):
        state[j + 1] = phi @ state[j]
        state[j + 1, :, n + j * nq : n + (j + 1) * nq] += noise
        state[j + 1, :, n + L * nq :] += sens[j]
        drive[j + 1] = phi @ drive[j] + gamma @ us[j]
    return state, drive
