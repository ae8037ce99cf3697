r"""The condensed window LP of the exact hull: the states eliminated, a chain of ``2n`` objectives a step.

:class:`CondensedWindowLP` solves the ``2n`` objectives of a window along a chain, by the dense simplex of
:mod:`~intervalobs.lp.dense_simplex` first and HiGHS for what it gives up on (or HiGHS alone, ``solver="highs"``),
records the route of every solve (:class:`~intervalobs.lp.chain.SolverPath`) and certifies every bound by weak
duality (:func:`~intervalobs.lp.certified.dual_bounds`).
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from ..interval import round_outward
from .certified import FEASIBILITY_TOLERANCE, basic_variables, dual_bounds, highs_model, new_highs, run_highs
from .chain import RecordsPath, Solver, SolverPath
from .window import WindowModel

__all__ = [
    "CERTIFICATE_GAP",
    "ITERATION_LIMIT",
    "MEASUREMENT_RELAX",
    "ROW_RELAX",
    "SMALL_MATRIX_VALUE",
    "CondensedWindowLP",
]

FloatArray = NDArray[np.float64]


CERTIFICATE_GAP = 1e-7
"""Relative gap between a solve's optimal value and its certified bound above which the condensed window
LP is solved again from scratch (a tolerance of the check, not a pad: either certificate is valid)."""

ROW_RELAX = 1e-9
"""Relative widening of the measurement rows, beyond ``MEASUREMENT_RELAX``, in the LP that HiGHS solves again
when a solve fails.

Vertex noise makes the window's feasible set thin (on the 6-tank cascade with i.i.d. vertex noise, a window
whose largest inscribed slack is -1e-11): the exact LP then ends "unknown", from a restored basis and from
scratch, and the multipliers of such a solve certify up to a few percent (of the width) less than the optimum.
The widened LP is well posed; its multipliers, evaluated on the exact rows by ``dual_bounds``, certify at least
its optimum, i.e. at most ``ROW_RELAX (1 + |b|) ‖λ‖₁`` below the exact one. (Too large for every solve: on the
first windows from the wide prior of ``x_0`` the multipliers are large and that loss shows; every solve is widened
by the ten times smaller ``MEASUREMENT_RELAX``.)"""

MEASUREMENT_RELAX = 1e-10
"""Relative widening of the measurement rows in every condensed window LP that HiGHS solves; the multipliers are
certified on the exact rows (``dual_bounds``), which loses at most ``MEASUREMENT_RELAX (1 + |b|) ‖λ‖₁``.

Under vertex noise the truth lies on many measurement faces at once and the exact feasible set is thin: on 30
steps of the 30-tank cascade, HiGHS ended 634 of 2 800 runs "infeasible", 182 "unknown" and 99 with a solve error,
and those failures took most of the time. The rows are residuals of about 0.1 once the prior's centre is
taken out, so the widening is about 1.1e-10 there. Measured with the primal simplex's bound perturbation off but
HiGHS's default ``small_matrix_value``: a factor of 1e-9 lost width (mean summed width 2.7279 against 2.7234
with 1e-10); with 2e-12 the failures came back (with the perturbation on)."""

SMALL_MATRIX_VALUE = 1e-12
"""Matrix entries HiGHS drops from the condensed window LP (its option ``small_matrix_value``, default 1e-9).

The powers of the sampled matrix give many small entries (on the 30-tank cascade, 14 743 of the 34 881 nonzeros
are below 1e-12 times the largest). Dropping those below 1e-9 moved the rows by up to 8.4e-10 at the truth, more
than a window thinned by vertex noise is wide: on the growing windows of a 30-step record (``k`` = 5 … 9) HiGHS
then found no feasible point at all (primal infeasibility 0.38 from scratch), about 80 failed runs a step. With
1e-12 (the smallest value HiGHS accepts) none failed on that record. The certificates use the full matrix either
way."""

ITERATION_LIMIT = 4
"""Simplex pivots allowed to one solve of the condensed window LP, per row and column. A solve that reaches
the limit is treated as failed (widened rows, then from scratch, see ``ROW_RELAX``): under switching bang-bang
noise some windows of the 30-tank cascade (231 rows, 330 columns) took 30 000–66 000 pivots and single solves
over a minute, against a median of 178 pivots and at most about a thousand on the other windows."""

_LOWER, _BASIC, _UPPER, _ZERO = 0, 1, 2, 3
"""Basis status codes of the bases kept by :class:`CondensedWindowLP` (``_ZERO``: a nonbasic free row)."""


_Solved = tuple[bool, "NDArray[np.int64] | None", "FloatArray | None", FloatArray]
"""One objective's outcome: optimal?, basic variables, primal values (columns, rows), row duals."""


class CondensedWindowLP(RecordsPath):
    r"""The window LP with the states eliminated (box measurement noise only).

    Variables :math:`z = (x_s, w_0, \dots, w_{H-1})` with :math:`x_s` the first state of the window
    (in its prior box) and :math:`e_i = x_{i+1} - \Phi x_i - \Gamma u_i = G w_i`, :math:`w_i` in its box
    (:math:`G = I` and :math:`w_i = e_i` when the process noise is a box), so
    :math:`x_j = \Phi^j x_s + \sum_{i<j}\Phi^{j-1-i}G w_i + q_j` with the known drive :math:`q_j`. Only the
    ``H + 1`` measurement rows remain (instead of ``(H + 1)(n + p)`` rows). A window shorter than ``H``
    (the first steps, ``s = 0``) uses the same LP with ``w_L … w_{H-1}`` fixed at 0 and the rows after
    its last state free.

    **A shared input-matrix error** (``model.shared_dB``, :class:`~intervalobs.lp.window.SharedDeltaB`): the entries
    of :math:`\beta` are the last columns, one set for the window, and :math:`e_i` gains :math:`\Psi\beta u_{s+i}`;
    their coefficients in the rows and the objectives move with the inputs and are set by :meth:`set_window` in
    both solvers (the dense simplex refactors its basis at the start of every window anyway).

    **Warm start.** The ``2n`` objectives of a window are solved as a chain: the lower bounds of
    components ``0 … n-1``, then the upper bounds of ``n-1 … 0`` (:attr:`chain`), by the dense simplex of
    :class:`~intervalobs.lp.dense_simplex.DenseSimplex`, which keeps the basis inverse from one objective to
    the next (HiGHS spends a fixed time on every ``run()``, large against the 15 or so pivots of a solve on the
    30-tank cascade). The first objective of the chain starts from its own optimal basis of
    the previous step, shifted by one step (each variable and row keeps the status it had *at the same time*:
    the active measurements are a property of the data, not of the lag; the noise entering at the new end starts
    at the bound its cost prefers), made square and nonsingular, by the dual simplex. Every later objective
    starts from the optimum of the one before it, which is feasible for the same window, by the primal simplex.
    An objective the dense simplex gives up on (pivot limit, an inaccurate or singular basis) is solved by
    HiGHS's dual simplex, from the basis the dense simplex reached or from the shifted one, and the chain goes on
    from that optimum. On a 30-tank record (30 and 40 steps of vertex noise, one core) the dense simplex took
    less time than HiGHS's primal simplex over the whole chain (the hull's cost a step is in
    ``benchmarks/scale.json``), mean summed widths 2.72286796 → 2.72286703 and 2.70532032 → 2.70533071.

    **Scaling.** HiGHS solves the LP unscaled. Its default scaling is computed again after every restored
    basis, which cost more time than it saved on the 30-tank hull record (same widths to 2e-8) and on learning a
    bank on the 12-tank cascade. Equilibrating the matrix once with power-of-2 factors was slower than either
    (more pivots). The certificates do not depend on the scaling.

    **Thin windows.** Under vertex noise the truth sits on many measurement faces at once and the window's
    feasible set is thin. HiGHS solves every LP with its measurement rows widened by ``MEASUREMENT_RELAX``
    (relative), and its multipliers are certified on the exact rows; it keeps matrix entries down to
    ``SMALL_MATRIX_VALUE`` (its default drops entries below 1e-9, which moved the rows by more than such a set is
    wide); and the primal simplex runs without its random bound perturbation, which on such a set often made it
    end "infeasible". On the 30-tank cascade (records of 30 and 40 steps of vertex noise, one BLAS thread) the
    three left no failed solve (those had taken most of the hull's time), and took its mean summed
    width from 2.72565 and 2.71030 to 2.72287 and 2.70532: the fallbacks of the failed solves had certified less.
    On the vehicle the widening costs 6e-5 of the width.

    **Failed solves.** When a solve still ends without an optimum, the LP with its measurement rows widened
    by ``ROW_RELAX`` more is solved (from the basis reached, then from scratch) and its multipliers are
    certified on the exact rows.

    **Centred prior.** The first state is written :math:`x_s = c + z` with :math:`c` the centre of its
    prior box and :math:`z` in the centred box (ends rounded outward), and :math:`\Phi^j c` joins the
    known drive. The LP then works with deviations instead of absolute values (levels around 5 with
    widths around 0.05 on the tank cascades of :mod:`intervalobs.examples.scale_cases`): with the 1e-9
    feasibility tolerances the uncentred LP often left a restored basis "infeasible" or unfinished, took
    thousands of pivots on single objectives, and returned certified bounds visibly wider than the exact
    optimum (the cost and the widths before and after are in CHANGELOG.md). The magnitude bound below
    uses ``|x_s| ≤ max(|lo|, |hi|)``, which also bounds ``|c| + |z|``, and the inputs' drive only in
    :math:`q`; the product :math:`\Phi^j c` (``n`` more terms) is covered by the same pad.
    An optimum whose multipliers certify much less than its value (relative gap above
    ``CERTIFICATE_GAP``: an ill-conditioned basis completed from an alien one) is solved again from scratch
    and the better certificate kept.

    **Rounding.** The powers :math:`\Phi^j` (repeated products), the drive (one product of the
    stacked inputs with the precomputed powers) and the magnitudes are computed in floating point: each
    row and the objective are padded outward by ``4 (H + 1)(n + m + 2) u`` times the magnitude bound
    :math:`m_j = |\Phi|^j m_0 + \sum_{i<j} |\Phi|^{j-1-i}(|e|_{max} + |\Gamma u_{s+i}| + |q_{i+1}|)`.
    This covers the error of the powers (``j n u |Φ|^j`` to first order), of the drive as an inner
    product of at most ``H n`` nonzero terms, and of the magnitudes' own evaluation (nonnegative terms).

    Parameters
    ----------
    model : WindowModel
        The model (box measurement noise: ``F`` None).
    horizon : int
        Window length ``H`` (steps).
    workers : int
        HiGHS instances (and dense simplices) solving parts of the chain in parallel threads.
    solver : {"auto", "highs"}
        ``"highs"``: no dense simplex, HiGHS solves every objective.
    """

    def __init__(self, model: WindowModel, horizon: int, workers: int = 1, solver: Solver = "auto") -> None:
        from highspy import _core

        from .dense_simplex import DenseSimplex  # Numba: loaded (80 MB, 0.4 s) only where it is used

        self.model, self.horizon = model, horizon
        n, p = model.C.shape[1], model.C.shape[0]
        H = horizon
        self.n, self.p = n, p
        powers = [np.eye(n)]
        abs_powers = [np.eye(n)]
        abs_phi = np.abs(model.Phi)
        for _ in range(H):
            powers.append(model.Phi @ powers[-1])
            abs_powers.append(abs_phi @ abs_powers[-1])
        noise_map = np.eye(n) if model.G is None else model.G  # e_i = G w_i (a box of e_i when G is None)
        self.nw = nw = noise_map.shape[1]
        self.dB_entries = np.zeros((0, 2), dtype=np.intp) if model.shared_dB is None else model.shared_dB.entries()
        self.nz = n + H * nw  # the columns before the shared β (fixed coefficients)
        self.ncol = self.nz + self.dB_entries.shape[0]
        self.nrow = (H + 1) * p
        # Block row j: x_j (without the drive) as a function of z. The drive and the magnitudes use the
        # same recursion in state space, (x_s, e_0 … e_{H-1}), with |Φ|^j in place of Φ^j for magnitudes.
        state_map = np.zeros((H + 1, n, self.ncol))
        step_map = np.zeros((H + 1, n, n + H * n))
        abs_map = np.zeros((H + 1, n, n + H * n))
        for j in range(H + 1):
            state_map[j, :, :n], step_map[j, :, :n], abs_map[j, :, :n] = powers[j], powers[j], abs_powers[j]
            for i in range(j):
                state_map[j, :, n + i * nw : n + (i + 1) * nw] = powers[j - 1 - i] @ noise_map
                step_map[j, :, n + i * n : n + (i + 1) * n] = powers[j - 1 - i]
                abs_map[j, :, n + i * n : n + (i + 1) * n] = abs_powers[j - 1 - i]
        self.objectives = state_map
        """``objectives[L, i]``: the cost of ``(x_{s+L})_i`` for a window of ``L`` steps (its β part set by
        :meth:`set_window`)."""
        self.transfer = step_map.reshape((H + 1) * n, n + H * n)[:, n:]
        self.abs_map = abs_map.reshape((H + 1) * n, n + H * n)
        matrix = np.einsum("pn,jnc->jpc", model.C, state_map).reshape(self.nrow, self.ncol)
        self.matrix_t = np.ascontiguousarray(matrix.T)
        self.abs_matrix_t = np.abs(self.matrix_t)
        self.col_nnz = self.nrow  # dense products: every row counts in the rounding of a reduced cost
        self.e_max = np.abs(noise_map) @ np.maximum(np.abs(model.w_lo), np.abs(model.w_hi))
        # One HiGHS instance and one dense simplex per worker, each solving a contiguous part of the chain.
        self.solvers = [new_highs() for _ in range(workers)]
        # A dense solve that needs more pivots than variables (degenerate cycling, mostly) goes to HiGHS instead.
        limit = self.nrow + self.ncol
        tol = FEASIBILITY_TOLERANCE
        self.dense = [DenseSimplex(matrix, tol, tol, limit) for _ in range(workers)] if solver == "auto" else []
        self.solver = self.solvers[0]
        self.path = SolverPath()
        """The routes of the solves since the last :meth:`take_path`."""
        self._pool = ThreadPoolExecutor(max_workers=workers) if workers > 1 else None
        self.inf = float(self.solver.getInfinity())
        free_rows, unit = np.full(self.nrow, self.inf), np.ones(self.ncol)
        lp = highs_model(sparse.csc_matrix(matrix), -unit, unit, -free_rows, free_rows, self.inf)
        for instance in self.solvers:
            # Devex pricing: after each restored basis, steepest-edge weights would be recomputed (3-7 % slower).
            instance.setOptionValue("simplex_dual_edge_weight_strategy", 1)
            # No scaling (see "Scaling" above): HiGHS's own is set up again for every restored basis.
            instance.setOptionValue("simplex_scale_strategy", 0)
            # No random bound perturbation in HiGHS's primal simplex (now only its clean-up after the dual simplex),
            # and only entries below 1e-12 dropped from the matrix (HiGHS's smallest setting; default 1e-9): see
            # "Thin windows" above.
            instance.setOptionValue("primal_simplex_bound_perturbation_multiplier", 0.0)
            instance.setOptionValue("small_matrix_value", SMALL_MATRIX_VALUE)
            instance.setOptionValue("simplex_iteration_limit", ITERATION_LIMIT * (self.nrow + self.ncol))
            instance.passModel(lp)
        self._cols = np.arange(self.ncol, dtype=np.int32)
        self._rows = np.arange(self.nrow, dtype=np.int32)
        self._optimal = _core.HighsModelStatus.kOptimal
        self._statuses = [
            _core.HighsBasisStatus.kLower,
            _core.HighsBasisStatus.kBasic,
            _core.HighsBasisStatus.kUpper,
            _core.HighsBasisStatus.kZero,
        ]
        self.chain = np.concatenate([np.arange(0, 2 * n, 2), np.arange(2 * n - 1, 0, -2)])
        """The order of the objectives (row ``2i``: lower bound of component ``i``, ``2i + 1``: upper)."""
        self._bases: dict[int, tuple[NDArray[np.int8], NDArray[np.bool_], int]] = {}
        """Per key: status codes of the last bases of the ``2n`` objectives, which are optimal (the others
        are not restored), and the window start."""
        self.length, self.start, self.full = H, 0, True
        self.dual_log: list[tuple[int, float, FloatArray, int, bool]] | None = None
        """When a list, every solve appends ``(component, sign, row duals, window length L, anchored)``,
        ``anchored`` when the window starts at ``x_0`` (``k ≤ H``; see ``HullEstimator.certificates``)."""
        self.reuse: Callable[[CondensedWindowLP, FloatArray], FloatArray] | None = None
        """When set, called with this LP (bounds of the window set) and the ``2n`` costs before the solves;
        returns multipliers ``(2n, rows)`` to use instead of solving, a NaN row for each objective to solve
        (``HullEstimator.certificates``). Objectives not solved are not logged."""

    def set_window(
        self, k: int, y: FloatArray, u: FloatArray, prior_lo: FloatArray, prior_hi: FloatArray, use_current: bool
    ) -> tuple[FloatArray, FloatArray]:
        """Bounds for the window ``s = max(k - H, 0) … k``; returns the drive ``q_L`` and the objective's pad.

        Row ``i`` of ``y`` and ``u`` is time ``s + i``; ``prior_*`` bound the window's first state (the
        box of ``x_0`` while ``k ≤ H``).

        Parameters
        ----------
        k : int
            The step.
        y, u : numpy.ndarray
            Measurements and inputs of the window.
        prior_lo, prior_hi : numpy.ndarray, shape (n,)
            Box of the window's first state.
        use_current : bool
            Whether ``y_k`` is used.

        Returns
        -------
        drive : numpy.ndarray, shape (n,)
            ``q_L``.
        pad : numpy.ndarray, shape (n,)
            The objective's rounding pad.
        """
        m, H, n, p = self.model, self.horizon, self.n, self.p
        L = min(k, H)
        s = k - L
        self.length, self.start, self.full = L, s, k > H
        eps = float(np.finfo(float).eps)
        drives = np.zeros((H, n))
        drives[:L] = u[:L] @ m.Gamma.T
        q = (self.transfer @ drives.ravel()).reshape(H + 1, n)
        growth = np.zeros((H, n))
        w_lo, w_hi = m.window_noise_box(u[:L])  # per step: wider by δΓ|u_j| for an interval input matrix
        e_max = self.e_max if m.dGamma is None else np.maximum(np.abs(w_lo), np.abs(w_hi))
        growth[:L] = e_max + np.abs(drives[:L]) + np.abs(q[1 : L + 1]) + self._set_shared_dB(u[:L])
        # x_s = mid + z, z in the centred prior box: the LP works with deviations from the prior's centre
        mid = 0.5 * (prior_lo + prior_hi)
        q += self.objectives[:, :, :n] @ mid
        start_mag = np.maximum(np.abs(prior_lo), np.abs(prior_hi))
        mag = (self.abs_map @ np.concatenate([start_mag, growth.ravel()])).reshape(H + 1, n)
        width = n + m.Gamma.shape[1] + self.nw + self.dB_entries.shape[0] + 2  # terms of the powers, G, drive, β
        rounding = width * eps * mag
        x_error = 4.0 * (H + 1) * rounding  # |computed x_j - exact x_j| for every z in the box
        row_pad = (x_error + rounding) @ np.abs(m.C).T
        rows = np.arange(H + 1)
        measured = (rows < L) | ((rows == L) & use_current)
        yt = np.zeros((H + 1, p))
        yt[measured] = y[rows[measured]]
        centre = q @ m.C.T
        lo = np.where(measured[:, None], yt - m.v_hi - centre - row_pad, -self.inf)
        hi = np.where(measured[:, None], yt - m.v_lo - centre + row_pad, self.inf)
        idle = np.zeros((H - L) * self.nw)
        z_lo, z_hi = round_outward(prior_lo - mid, prior_hi - mid)
        beta = np.zeros(0) if m.shared_dB is None else m.shared_dB.radius[tuple(self.dB_entries.T)]
        self.col_lo = np.concatenate([z_lo, w_lo.ravel(), idle, -beta])
        self.col_hi = np.concatenate([z_hi, w_hi.ravel(), idle, beta])
        self.row_lo, self.row_hi = lo.ravel(), hi.ravel()  # exact: what the certificates are evaluated on
        self.row_scale = 1.0 + np.maximum(np.abs(self.row_lo), np.abs(self.row_hi))  # of the relative widenings
        relax = MEASUREMENT_RELAX * self.row_scale
        self.solve_lo, self.solve_hi = self.row_lo - relax, self.row_hi + relax  # what HiGHS solves
        for solver in self.solvers:
            solver.changeColsBounds(self.ncol, self._cols, self.col_lo, self.col_hi)
            solver.changeRowsBounds(self.nrow, self._rows, self.solve_lo, self.solve_hi)
        return q[L], x_error[L] + rounding[L]

    def _set_shared_dB(self, u: FloatArray) -> FloatArray:
        """Set the β columns of the objectives, rows and both solvers for the window's inputs ``u`` (shape
        (L, m)); returns the bound ``|Ψ| r |u_i|`` of each step's ``Ψβu_i`` (zeros without a shared β)."""
        shared, n, nz = self.model.shared_dB, self.n, self.nz
        if shared is None:
            return np.zeros((u.shape[0], n))
        H, L = self.horizon, u.shape[0]
        rows, inputs = self.dB_entries[:, 0], self.dB_entries[:, 1]
        steps = np.zeros((H, n, rows.size))
        steps[:L] = shared.map[:, rows][None, :, :] * u[:, None, inputs]  # Ψ e_a u_b for each entry (a, b) of β
        state = (self.transfer @ steps.reshape(H * n, rows.size)).reshape(H + 1, n, rows.size)
        self.objectives[:, :, nz:] = state
        block = np.einsum("pn,jnq->jpq", self.model.C, state).reshape(self.nrow, rows.size)
        self.matrix_t[nz:] = block.T
        self.abs_matrix_t[nz:] = np.abs(block.T)
        for dense in self.dense:
            dense.matrix_t[nz:] = block.T
        for solver in self.solvers:
            for (r, q), value in np.ndenumerate(block):
                solver.changeCoeff(r, nz + q, float(value))
        return np.abs(u) @ (np.abs(shared.map) @ shared.radius).T

    def forget_bases(self) -> None:
        """Drop the bases kept for warm starts and the solvers' own (the next solves start from scratch)."""
        self._bases.clear()
        for solver in self.solvers:
            solver.clearSolver()

    def certified_bounds(self, key: int) -> tuple[FloatArray, FloatArray]:
        """Rigorous lower bounds of ``(x_k)_i - (q_L)_i`` and of ``(q_L)_i - (x_k)_i`` for every ``i``.

        Solves the ``2n`` LPs of the window along the chain (class docstring, "Warm start"), then evaluates
        every weak-duality bound at once (:func:`~intervalobs.lp.certified.dual_bounds`).

        Parameters
        ----------
        key : int
            Which family of kept bases to use (predicted or filtered hull).

        Returns
        -------
        lower, upper : numpy.ndarray, shape (n,)
            ``-upper`` bounds ``(q_L)_i - (x_k)_i`` from below, i.e. ``upper`` bounds ``(x_k)_i - (q_L)_i``.
        """
        n, ncol, nrow = self.n, self.ncol, self.nrow
        signs = np.tile([1.0, -1.0], n)
        costs = signs[:, None] * np.repeat(self.objectives[self.length], 2, axis=0)
        given = self.reuse(self, costs) if self.reuse is not None else np.full((2 * n, nrow), np.nan)
        solve = np.isnan(given[:, 0])
        starts = self._start_codes(key, costs)
        duals = np.where(solve[:, None], 0.0, given)
        values = np.zeros((2 * n, ncol + nrow))
        basics: list[NDArray[np.int64] | None] = [None] * (2 * n)
        usable = np.ones(2 * n, dtype=bool)
        parts = np.array_split(self.chain[solve[self.chain]], len(self.solvers))
        run_parts = map if self._pool is None else self._pool.map
        work = partial(self._solve_part, costs=costs, starts=starts)
        for outcomes, path in run_parts(work, range(len(parts)), parts):
            self.path.add(path)
            for r, (optimal, basic, value, dual) in outcomes:
                if optimal:
                    basics[r], values[r] = basic, value
                if dual.shape != (nrow,) or not np.all(np.isfinite(dual)):
                    usable[r] = False
                    continue
                duals[r] = dual
        self._keep_bases(key, values, basics)
        bounds = np.where(usable, dual_bounds(self, costs, duals), -np.inf)
        # An optimum can have an ill-conditioned basis whose multipliers certify much less than its value: those
        # objectives are solved again from scratch and the better certificate kept.
        solved = np.array([b is not None for b in basics])
        primal = np.einsum("rc,rc->r", costs, values[:, :ncol])
        loose = solved & (primal - bounds > CERTIFICATE_GAP * (1.0 + np.abs(primal)))
        solver = self.solvers[0]
        for r in np.flatnonzero(loose).tolist():
            solver.clearSolver()
            _, _, _, dual = self._solve_one(solver, costs[r], lambda: None, self.path, scratch=True)
            if dual.shape == (nrow,) and np.all(np.isfinite(dual)):
                again = dual_bounds(self, costs[r : r + 1], dual[None, :])[0]
                if again > bounds[r]:
                    bounds[r], duals[r], usable[r] = again, dual, True
        if self.dual_log is not None:
            for r in np.flatnonzero(usable & solve).tolist():
                self.dual_log.append((r // 2, float(signs[r]), duals[r].copy(), self.length, not self.full))
        return bounds[0::2], bounds[1::2]

    def _solve_part(
        self,
        w: int,
        part: NDArray[np.integer],
        costs: FloatArray,
        starts: tuple[NDArray[np.int8], NDArray[np.bool_]] | None,
    ) -> tuple[list[tuple[int, _Solved]], SolverPath]:
        """Solve the objectives ``part`` of the chain in turn on worker ``w``'s dense simplex and HiGHS instance.

        Each by the dense simplex (unless ``solver="highs"``) from the optimum before or from its kept basis
        ``starts``; what it gives up on by HiGHS from the basis it reached (or the kept one), and the dense simplex
        then goes on from HiGHS's optimum. Returns the outcomes and the route they took.
        """
        solver, dense = self.solvers[w], self.dense[w] if self.dense else None
        out: list[tuple[int, _Solved]] = []
        path = SolverPath()
        if dense is not None:
            dense.ready = False
        for r in part.tolist():
            start = partial(self._start_basis, starts, r)
            if dense is not None and not dense.ready and starts is not None and starts[1][r]:
                dense.start_from_statuses(self.col_lo, self.col_hi, self.solve_lo, self.solve_hi, starts[0][r])
            if dense is not None and dense.ready:
                optimal, pivots = dense.solve(costs[r])
                path.pivots += pivots
                if optimal:
                    path.dense += 1
                    out.append((r, (True, dense.basic_variables(), dense.values(), dense.row_duals())))
                    continue
                start = partial(self._highs_basis, dense.statuses())
            solved = self._solve_one(solver, costs[r], start, path)
            if solved[0] and dense is not None:
                assert solved[1] is not None and solved[2] is not None
                dense.start(self.col_lo, self.col_hi, self.solve_lo, self.solve_hi, solved[1], solved[2])
            out.append((r, solved))
        return out, path

    def _solve_one(
        self, solver: Any, cost: FloatArray, start: Callable[[], Any], path: SolverPath, scratch: bool = False
    ) -> _Solved:
        """Solve one objective with HiGHS's dual simplex from the basis ``start()`` (None: from the instance's
        current basis, or from scratch after ``clearSolver``: ``scratch``), counting the route in ``path``."""
        solver.changeColsCost(self.ncol, self._cols, cost)
        basis = start()
        if basis is not None:
            solver.setBasis(basis)
        run_highs(solver)
        path.pivots += int(solver.getInfo().simplex_iteration_count)
        widened = solver.getModelStatus() != self._optimal
        if not widened:
            path.scratch += scratch
            path.highs_warm += not scratch
        else:
            # No optimum (a thin feasible set, see ROW_RELAX): solve the widened LP, from the basis reached and
            # then from scratch; its multipliers are certified on the exact rows like any others.
            relax = ROW_RELAX * self.row_scale
            solver.changeRowsBounds(self.nrow, self._rows, self.solve_lo - relax, self.solve_hi + relax)
            run_highs(solver)
            path.pivots += int(solver.getInfo().simplex_iteration_count)
            path.widened += 1
            if solver.getModelStatus() != self._optimal:
                solver.clearSolver()
                run_highs(solver)
                path.pivots += int(solver.getInfo().simplex_iteration_count)
                path.scratch += 1
            path.failed += solver.getModelStatus() != self._optimal
        return self._outcome(solver, widened)

    def _outcome(self, solver: Any, widened: bool) -> _Solved:
        """The solver's outcome; restores the rows of :meth:`set_window` after a ``ROW_RELAX``-widened solve."""
        solution = solver.getSolution()
        optimal = solver.getModelStatus() == self._optimal
        basic = basic_variables(solver) if optimal else None
        value = np.concatenate([solution.col_value, solution.row_value]) if optimal else None
        if widened:
            solver.changeRowsBounds(self.nrow, self._rows, self.solve_lo, self.solve_hi)
        return optimal, basic, value, np.asarray(solution.row_dual, dtype=float)

    def _keep_bases(self, key: int, values: FloatArray, basics: list[NDArray[np.int64] | None]) -> None:
        """Store the optimal bases as status codes (the nonbasic side read from the solution values)."""
        lower = np.concatenate([self.col_lo, self.row_lo])
        upper = np.concatenate([self.col_hi, self.row_hi])
        finite_lo, finite_hi = np.isfinite(lower), np.isfinite(upper)
        middle = 0.5 * (np.where(finite_lo, lower, 0.0) + np.where(finite_hi, upper, 0.0))
        codes = np.where(values > middle, _UPPER, _LOWER).astype(np.int8)
        codes[:, ~finite_lo & ~finite_hi] = _ZERO
        kept = np.array([b is not None for b in basics])
        for r, basic in enumerate(basics):
            if basic is not None:
                codes[r, np.where(basic >= 0, basic, self.ncol - 1 - basic)] = _BASIC
        self._bases[key] = (codes, kept, self.start)

    def _start_codes(self, key: int, costs: FloatArray) -> tuple[NDArray[np.int8], NDArray[np.bool_]] | None:
        """Status codes of the kept bases of the ``2n`` objectives, shifted by one step if the window has moved
        by one, and which of them to use (None: no kept bases)."""
        kept = self._bases.get(key)
        if kept is None:
            return None
        codes, valid, start = kept
        n, nw, p, nz, ncol = self.n, self.nw, self.p, self.nz, self.ncol
        if start + 1 == self.start:  # the noise columns and the rows shift by one step; x_s and β stay
            entering = np.where(costs[:, nz - nw : nz] >= 0.0, _LOWER, _UPPER).astype(np.int8)
            fresh_rows = np.full((codes.shape[0], p), _BASIC, dtype=np.int8)
            parts = [codes[:, :n], codes[:, n + nw : nz], entering, codes[:, nz:ncol], codes[:, ncol + p :], fresh_rows]
            codes = np.hstack(parts)
        return codes, valid

    def _start_basis(self, starts: tuple[NDArray[np.int8], NDArray[np.bool_]] | None, r: int) -> Any:
        """The HiGHS basis of objective ``r`` from :meth:`_start_codes` (None: solve from scratch)."""
        if starts is None or not starts[1][r]:
            return None
        return self._highs_basis(starts[0][r])

    def _highs_basis(self, codes: NDArray[np.integer]) -> Any:
        """The HiGHS basis of the status codes ``codes`` (columns, then rows); alien when it has the wrong number
        of basic variables (HiGHS completes it)."""
        from highspy import _core

        row = codes.tolist()
        statuses = [self._statuses[c] for c in row]
        basis = _core.HighsBasis()
        basis.col_status, basis.row_status = statuses[: self.ncol], statuses[self.ncol :]
        basis.valid = True
        basis.alien = row.count(_BASIC) != self.nrow
        return basis
