r"""The McCormick envelope window LP of the robust hull (:class:`~intervalobs.observers.RobustHullEstimator`).

:class:`EnvelopeLP` holds the LP of a window with an interval :math:`\Delta A` (the products of the uncertain
entries and the states replaced by their McCormick envelopes) as one HiGHS model, solves its objectives from the
bases kept from the previous step, records the route of every solve (:class:`~intervalobs.lp.chain.SolverPath`) and
certifies every bound by weak duality (:func:`~intervalobs.lp.certified.dual_bounds`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import sparse

from ..interval import inflate, product_bounds
from .certified import dual_bounds, highs_model, new_highs, run_highs
from .chain import RecordsPath, SolverPath
from .condensed import CERTIFICATE_GAP

__all__ = ["EnvelopeLP"]

FloatArray = NDArray[np.float64]

_EPS = float(np.finfo(float).eps)

_PIVOT_MEMORY = 0.7
"""Weight of the previous average in the moving pivot count of a warm-start alignment."""
_EXPLORE = 16
"""Steps after which the McCormick LP's objective tries the warm-start alignment it has not used."""


class EnvelopeLP(RecordsPath):
    r"""The McCormick window LP (:meth:`RobustHullEstimator._box`) as one HiGHS model built once.

    Slot ``τ mod S`` (``S = H + 1``) holds the time ``τ`` of the window ``s … k``: its state
    :math:`x_\tau`, the noise :math:`e_\tau`, the products :math:`q_\tau = \delta_l x_{\tau,b}` of its
    transition to ``τ + 1`` (slot ``τ + 1 mod S``; the rows of ``k``, whose transition closes the cycle,
    are free), its measurement row and its envelope rows; :math:`\delta` comes last. Each step only the
    bounds change, and the coefficients that depend on the data: the envelopes' factors of
    :math:`\delta` (the box of :math:`x_\tau`) and, in continuous time, :math:`-N_l u_\tau` — those of
    the slot the window has just entered; the envelopes' factors of :math:`x` change with the identified
    :math:`\delta` box only. A slot outside the window (the first ``H`` steps) has its columns fixed at 0
    and its rows free. Every loaded value is kept, and only the entries that differ are passed on.

    **Warm starts.** The optimal basis of every objective is kept and restored at the next step, in one of two
    alignments: each variable and row with the status it had *at the same time* (the basis as it is: a variable
    keeps its slot), or with the status of the one *one step earlier*, i.e. at the same lag behind ``x_k`` (the
    basis rolled by one slot). Which one needs fewer pivots depends on the example: on the integrated-observer
    paper's three-state example, where the extremal trajectories of ``x_k`` are shaped by the shared :math:`\delta`,
    the lagged basis (several times fewer pivots); on the two-tank, where the measurements shape them, the timed one
    (a quarter fewer). So each objective uses the alignment whose recent pivot count (:data:`_PIVOT_MEMORY`) is
    lower and tries the other one every :data:`_EXPLORE` steps. An objective without a kept basis starts from the
    last solve's optimum. Dual simplex with Devex pricing (steepest-edge weights would be recomputed after every
    restored basis). A restored basis is passed as alien (HiGHS repairs a singular one); when it leads to no
    optimum, the LP is solved again from scratch.

    **Certificate.** A copy of the matrix with the same entries (as ``Aᵀ`` in CSR, updated in place)
    gives the weak-duality bounds (:func:`~intervalobs.lp.certified.dual_bounds`); an optimum
    whose multipliers certify more than ``CERTIFICATE_GAP`` below its value (an ill-conditioned basis
    reached from a restored one) is solved again from scratch and the better certificate kept.

    Parameters
    ----------
    model : intervalobs.systems.sampling.DeltaLinearisation
        The linearisation in the uncertain entries ``δ`` (read: ``Phi``, ``Gamma``, ``C``, ``M``, ``N``, ``R_x``,
        ``R_u``, the noise and measurement-noise boxes).
    pairs : tuple of numpy.ndarray
        The entries ``l`` of ``δ`` and the states ``b`` of the products ``δ_l x_b`` that the model has.
    horizon : int
        Window length ``H`` (steps).
    """

    def __init__(self, model: Any, pairs: tuple[NDArray[Any], NDArray[Any]], horizon: int) -> None:
        from highspy import _core

        self.model = model
        n, p = model.C.shape[1], model.C.shape[0]
        pl, pb = pairs
        nq, nd, S = pl.size, model.M.shape[0], horizon + 1
        self.n, self.p, self.nq, self.nd, self.slots, self.pairs = n, p, nq, nd, S, pairs
        e0 = S * n
        q0 = e0 + S * n
        self.d0 = q0 + S * nq
        self.ncol = self.d0 + nd
        self.x_col = np.arange(S * n).reshape(S, n)
        self.env0 = S * (n + p)
        self.nrow = self.env0 + 4 * S * nq
        e_col = e0 + np.arange(S * n).reshape(S, n)
        q_col = q0 + np.arange(S * nq).reshape(S, nq)
        dyn = np.arange(S * n).reshape(S, n)
        meas = S * n + np.arange(S * p).reshape(S, p)
        env = self.env0 + np.arange(4 * S * nq).reshape(4, S, nq)
        rows: list[NDArray[Any]] = []
        cols: list[NDArray[Any]] = []
        vals: list[NDArray[Any]] = []

        def put(r: ArrayLike, c: ArrayLike, v: ArrayLike) -> NDArray[np.int64]:
            """Entries ``v`` at rows ``r`` and columns ``c`` (broadcast); returns their positions."""
            r, c, v = np.broadcast_arrays(r, c, v)
            first = sum(a.size for a in rows)
            rows.append(r.ravel())
            cols.append(c.ravel())
            vals.append(np.asarray(v, dtype=float).ravel())
            return first + np.arange(r.size).reshape(r.shape)

        # dynamics of slot i: x_{i+1 mod S} - Φ x_i - e_i - Q q_i - Σ_l (N_l u_τ) δ_l
        put(dyn, self.x_col[(np.arange(S) + 1) % S], 1.0)
        put(dyn[:, :, None], self.x_col[:, None, :], -model.Phi[None])
        put(dyn, e_col, -1.0)
        Q = model.M[pl, :, pb].T  # (n, n_q): the column of product δ_l x_b
        put(dyn[:, :, None], q_col[:, None, :], -Q[None])
        drift = np.argwhere(np.any(model.N != 0, axis=2))  # (l, a): row a of N_l is nonzero
        self.drift_entries = (drift[:, 0], drift[:, 1])
        self.drift_at = put(dyn[:, drift[:, 1]], self.d0 + drift[:, 0][None], 1.0)  # (S, entries)
        put(meas[:, :, None], self.x_col[:, None, :], model.C[None])
        # envelopes: block b, slot i, product t: q - a x - c δ (a: an end of δ_l, c: an end of x_b)
        self.env_x_at, self.env_d_at = [], []
        for b in range(4):
            put(env[b], q_col, 1.0)
            self.env_x_at.append(put(env[b], self.x_col[:, pb], 1.0))
            self.env_d_at.append(put(env[b], self.d0 + pl[None, :], 1.0))
        r_all, c_all = np.concatenate(rows), np.concatenate(cols)
        order = np.lexsort((r_all, c_all))  # column-major: the CSC of A is the CSR of Aᵀ
        self.position = np.empty_like(order)
        self.position[order] = np.arange(order.size)
        indptr = np.searchsorted(c_all[order], np.arange(self.ncol + 1))
        data = np.concatenate(vals)[order]
        self.matrix_t = sparse.csr_matrix((data, r_all[order], indptr), shape=(self.ncol, self.nrow))
        self.abs_matrix_t = sparse.csr_matrix((np.abs(data), r_all[order], indptr), shape=(self.ncol, self.nrow))
        self.col_nnz = int(np.max(np.diff(indptr)))
        self.solver = new_highs()
        self.solver.setOptionValue("simplex_dual_edge_weight_strategy", 1)  # Devex (class docstring)
        self.inf = float(self.solver.getInfinity())
        free_rows = np.full(self.nrow, self.inf)
        matrix = sparse.csc_matrix((data, r_all[order], indptr), shape=(self.nrow, self.ncol))
        zero = np.zeros(self.ncol)
        self.solver.passModel(highs_model(matrix, zero, zero, -free_rows, free_rows, self.inf))
        self._r_all, self._c_all = r_all.astype(np.int32), c_all.astype(np.int32)
        self._cols = np.arange(self.ncol, dtype=np.int32)
        self._rows = np.arange(self.nrow, dtype=np.int32)
        self._optimal = _core.HighsModelStatus.kOptimal
        self._bases: dict[int, Any] = {}
        self._pivots: dict[tuple[int, bool], float] = {}
        """Per objective and alignment (lagged?): recent pivot count (a moving average)."""
        self._tried: dict[tuple[int, bool], int] = {}
        """Per objective and alignment: the step it was last used at."""
        self._step = 0
        self.path = SolverPath()

        # The lagged basis: slot i gets the statuses of slot i - 1 (δ keeps its own).
        def rolled(blocks: list[tuple[int, int]]) -> NDArray[np.int64]:
            return np.concatenate(
                [np.roll(first + np.arange(S * w).reshape(S, w), 1, axis=0).ravel() for first, w in blocks]
            )

        self._lagged_cols = np.concatenate([rolled([(0, n), (e0, n), (q0, nq)]), self.d0 + np.arange(nd)]).tolist()
        blocks = [(0, n), (S * n, p)] + [(self.env0 + b * S * nq, nq) for b in range(4)]
        self._lagged_rows = rolled(blocks).tolist()

    def _set(self, at: NDArray[np.int64], values: FloatArray) -> None:
        """Coefficients ``values`` at the entries ``at`` (only those that differ are passed to HiGHS)."""
        at, values = at.ravel(), values.ravel()
        where = self.position[at]
        changed = np.flatnonzero(self.matrix_t.data[where] != values)
        if changed.size == 0:
            return
        self.matrix_t.data[where[changed]] = values[changed]
        self.abs_matrix_t.data[where[changed]] = np.abs(values[changed])
        for e, v in zip(at[changed].tolist(), values[changed].tolist(), strict=True):
            self.solver.changeCoeff(int(self._r_all[e]), int(self._c_all[e]), v)

    def set_window(
        self,
        k: int,
        ys: FloatArray,
        us: FloatArray,
        box_lo: FloatArray,
        box_hi: FloatArray,
        predicted: tuple[FloatArray, FloatArray],
        delta_box: tuple[FloatArray, FloatArray],
        m: int,
    ) -> FloatArray:
        """Bounds and coefficients of the window ``s = k - L … k``; returns the objective rows of ``x_k``.

        Row ``i`` of ``ys``, ``us`` and ``box_*`` is time ``s + i`` (``box_*`` bound ``x_τ``, ``τ < k``);
        ``delta_box`` holds the ends of ``δ`` (one per uncertain entry), ``m`` the number of inputs.

        Parameters
        ----------
        k : int
            The step.
        ys, us : numpy.ndarray
            Measurements and inputs of the window.
        box_lo, box_hi : numpy.ndarray
            Boxes of the window's earlier states.
        predicted : tuple of numpy.ndarray
            A sound box of ``x_k``.
        delta_box : tuple of numpy.ndarray
            The ends of ``δ``.
        m : int
            Number of inputs.

        Returns
        -------
        numpy.ndarray, shape (n, ncol)
        """
        mod, n, p, nq, S, inf = self.model, self.n, self.p, self.nq, self.slots, self.inf
        pl, pb = self.pairs
        L = min(k, S - 1)
        slot = (k - L + np.arange(L)) % S  # the slots of s … k - 1 (with transitions and measurements)
        newest = k % S
        d_lo, d_hi = delta_box
        d_max = np.maximum(np.abs(d_lo), np.abs(d_hi))
        u_win, lo, hi = us[:L], box_lo[:L], box_hi[:L]
        # coefficients: the envelopes' factors of x (δ box), of δ (the boxes of the new slots), the drift
        for b, a in enumerate((d_lo[pl], d_hi[pl], d_lo[pl], d_hi[pl])):
            self._set(self.env_x_at[b], np.broadcast_to(-a, (S, nq)))
        for b, c in enumerate((lo, hi, hi, lo)):
            self._set(self.env_d_at[b][slot], -c[:, pb])
        drift = np.einsum("lab,jb->jal", mod.N, u_win)
        self._set(self.drift_at[slot], -drift[:, self.drift_entries[1], self.drift_entries[0]])
        # column bounds: states in their boxes (x_k in the prediction), e and q of s … k - 1, δ
        x_lo, x_hi = np.zeros((S, n)), np.zeros((S, n))
        x_lo[slot], x_hi[slot] = lo, hi
        x_lo[newest], x_hi[newest] = predicted
        rho = np.maximum(np.abs(lo), np.abs(hi)) @ mod.R_x.T + np.abs(u_win) @ mod.R_u.T
        e_lo, e_hi = np.zeros((S, n)), np.zeros((S, n))
        e_lo[slot], e_hi[slot] = mod.noise_lo - rho, mod.noise_hi + rho
        q_lo, q_hi = np.zeros((S, nq)), np.zeros((S, nq))
        q_lo[slot], q_hi[slot] = inflate(*product_bounds(d_lo[pl], d_hi[pl], lo[:, pb], hi[:, pb]))
        self.col_lo = np.concatenate([x_lo.ravel(), e_lo.ravel(), q_lo.ravel(), d_lo])
        self.col_hi = np.concatenate([x_hi.ravel(), e_hi.ravel(), q_hi.ravel(), d_hi])
        # row bounds: dynamics (padded for the rounding of Γ_c u_j and of N_l u_j times |δ_l|), measurements
        gamma_u = u_win @ mod.Gamma.T
        abs_drift = np.einsum("lab,jb->jal", np.abs(mod.N), np.abs(u_win))
        dyn_pad = 2.0 * (m + 2) * _EPS * (np.abs(u_win) @ np.abs(mod.Gamma).T + abs_drift @ d_max)
        dyn_lo, dyn_hi = np.full((S, n), -inf), np.full((S, n), inf)
        dyn_lo[slot], dyn_hi[slot] = gamma_u - dyn_pad, gamma_u + dyn_pad
        y_pad = 2.0 * _EPS * (np.abs(ys[:L]) + np.maximum(np.abs(mod.v_lo), np.abs(mod.v_hi)))
        y_lo, y_hi = np.full((S, p), -inf), np.full((S, p), inf)
        y_lo[slot], y_hi[slot] = ys[:L] - mod.v_hi - y_pad, ys[:L] - mod.v_lo + y_pad
        # envelopes: q - a x - c δ ≥ -a c (blocks 0, 1) or ≤ -a c (blocks 2, 3), constants padded
        env_lo, env_hi = np.full((4, S, nq), -inf), np.full((4, S, nq), inf)
        for b, (a, c) in enumerate(((d_lo[pl], lo), (d_hi[pl], hi), (d_lo[pl], hi), (d_hi[pl], lo))):
            rhs = -a * c[:, pb]
            pad = 2.0 * _EPS * np.abs(rhs)
            if b < 2:
                env_lo[b, slot] = rhs - pad
            else:
                env_hi[b, slot] = rhs + pad
        self.row_lo = np.concatenate([dyn_lo.ravel(), y_lo.ravel(), env_lo.ravel()])
        self.row_hi = np.concatenate([dyn_hi.ravel(), y_hi.ravel(), env_hi.ravel()])
        self.solver.changeColsBounds(self.ncol, self._cols, self.col_lo, self.col_hi)
        self.solver.changeRowsBounds(self.nrow, self._rows, self.row_lo, self.row_hi)
        objective = np.zeros((n, self.ncol))
        objective[np.arange(n), self.x_col[newest]] = 1.0
        return objective

    def forget_bases(self) -> None:
        """Drop the kept bases, their pivot counts and the solver's own (the next solves start from scratch)."""
        self._bases.clear()
        self._pivots.clear()
        self._tried.clear()
        self._step = 0
        self.solver.clearSolver()

    def _alignment(self, r: int) -> bool:
        """Whether objective ``r`` restores its kept basis lagged: the alignment of fewer recent pivots,
        or the other one when it was last tried :data:`_EXPLORE` steps ago (or never)."""
        for lagged in (True, False):
            if self._step - self._tried.get((r, lagged), -_EXPLORE) >= _EXPLORE:
                return lagged
        return self._pivots[(r, True)] < self._pivots[(r, False)]

    def _lag(self, basis: Any) -> Any:
        """The basis rolled by one slot (each variable and row gets the status of its predecessor in time)."""
        from highspy import _core

        col_status, row_status = basis.col_status, basis.row_status
        rolled = _core.HighsBasis()
        rolled.col_status = [col_status[i] for i in self._lagged_cols]
        rolled.row_status = [row_status[i] for i in self._lagged_rows]
        rolled.valid, rolled.alien = True, True
        return rolled

    def minima(self, costs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Certified lower bounds of ``costs[r] · z`` and the solver's optimal points (as ``DenseLP.minima``).

        Parameters
        ----------
        costs : numpy.ndarray, shape (R, cols)
            One objective per row; row ``r`` starts from the basis kept for row ``r``.

        Returns
        -------
        bounds : numpy.ndarray, shape (R,)
        points : numpy.ndarray, shape (R, cols)
        """
        solver = self.solver
        duals = np.zeros((costs.shape[0], self.nrow))
        points = np.full((costs.shape[0], self.ncol), np.nan)
        usable = np.zeros(costs.shape[0], dtype=bool)
        self._step += 1
        for r, cost in enumerate(costs):
            solver.changeColsCost(self.ncol, self._cols, cost)
            kept = self._bases.get(r)
            lagged = False
            if kept is not None:
                lagged = self._alignment(r)
                solver.setBasis(self._lag(kept) if lagged else kept)
            run_highs(solver)
            pivots = float(solver.getInfo().simplex_iteration_count)
            self.path.pivots += int(pivots)
            self.path.highs_warm += solver.getModelStatus() == self._optimal
            if kept is not None:
                old = self._pivots.get((r, lagged), pivots)
                self._pivots[(r, lagged)] = _PIVOT_MEMORY * old + (1.0 - _PIVOT_MEMORY) * pivots
                self._tried[(r, lagged)] = self._step
                if solver.getModelStatus() != self._optimal:
                    solver.clearSolver()  # the restored basis did not lead to an optimum: from scratch
                    run_highs(solver)
                    self.path.pivots += int(solver.getInfo().simplex_iteration_count)
                    self.path.scratch += 1
            usable[r], duals[r], points[r] = self._read()
            if solver.getModelStatus() == self._optimal:
                self._bases[r] = solver.getBasis()
            else:
                self.path.failed += 1
                self._bases.pop(r, None)
        bounds = np.where(usable, dual_bounds(self, costs, duals), -np.inf)
        solved = np.all(np.isfinite(points), axis=1)
        primal = np.where(solved, np.einsum("rc,rc->r", costs, np.nan_to_num(points)), np.nan)
        for loose in np.flatnonzero(solved & (primal - bounds > CERTIFICATE_GAP * (1.0 + np.abs(primal)))).tolist():
            solver.changeColsCost(self.ncol, self._cols, costs[loose])
            solver.clearSolver()
            run_highs(solver)
            self.path.pivots += int(solver.getInfo().simplex_iteration_count)
            self.path.scratch += 1
            ok, dual, _ = self._read()
            if ok:
                again = dual_bounds(self, costs[loose : loose + 1], dual[None, :])[0]
                bounds[loose] = max(bounds[loose], again)
        return bounds, points

    def _read(self) -> tuple[bool, FloatArray, FloatArray]:
        """Whether the last solve gave finite duals, the duals and the optimal point (NaN if none)."""
        solution = self.solver.getSolution()
        dual = np.asarray(solution.row_dual, dtype=float)
        point = np.full(self.ncol, np.nan)
        if self.solver.getModelStatus() == self._optimal:
            point = np.asarray(solution.col_value, dtype=float)
        ok = dual.shape == (self.nrow,) and bool(np.all(np.isfinite(dual)))
        return ok, (dual if ok else np.zeros(self.nrow)), point
