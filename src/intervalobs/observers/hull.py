r"""The exact interval hull of the consistent set: the tightest box any sound estimator can report.

For a linear model with box-bounded unknowns, the states :math:`x_k` consistent with the model, the
prior box of :math:`x_0`, the noise boxes and the measurements form a polytope :math:`S_k`; its interval
hull :math:`\square S_k` is the smallest box that contains every admissible state, so every sound
estimator's box contains it (seed 002, Section 3: the zonotopic and interval observers are outer
approximations of :math:`S_k`). Each bound of :math:`\square S_k` is a linear programme:

.. math::

    \min / \max \; e_i^\top x_k \quad \text{s.t.} \quad
    x_{j+1} - \Phi x_j - \Gamma u_j \in \mathcal W,\qquad y_j - C x_j \in \mathcal V,\qquad
    x_{k-H} \in [\underline{x}_{k-H}, \overline{x}_{k-H}],

over a window of :math:`H` steps (:math:`\mathcal W`, :math:`\mathcal V`: the noise sets — a box, or
:math:`E\,[\underline w, \overline w]` with noise variables when one noise channel drives several
states). With :math:`H \ge k` (full history) the prior is the box of :math:`x_0` and the hull is exact;
with a shorter window the prior is the estimator's own box :math:`H` steps back (sound by induction),
and every state of the window is also bounded by its earlier box (redundant for the full history,
so exactness is kept, and a useful tightening otherwise).

**Soundness of an LP bound.** A simplex optimum is only accurate to the solver's tolerances, which
is not a guarantee: every bound is taken from weak duality with the solver's duals as multipliers and
the rounding of its own evaluation subtracted (:mod:`intervalobs.lp.certified`), so it is valid
whatever their accuracy. The box is finally intersected with the interval propagation of the previous
box (sound without any LP) and inflated by ``ROUNDING_MARGIN`` like every observer's output.

**Continuous time** uses the sound sampled model of :mod:`intervalobs.systems.sampling`: the hull
is exact for that model (whose per-step noise set is a box around the true, non-box set), so it is
sound for the continuous system and slightly wider than its true hull. :func:`hull_lower_bound` gives
the matching inner value.

**Interval** :math:`\Delta A` makes :math:`S_k` non-convex. :class:`HullEstimator` refuses it;
:func:`hull_lower_bound` computes, for a few fixed samples of :math:`\Delta A`, inner hulls of the
consistent sets and reports the hull of their union: a **lower bound on the box of any sound
estimator**, never an estimate (it is not an :class:`~intervalobs.estimate.Estimate`).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import sparse
from scipy.linalg import expm

from ..errors import AssumptionError, DataError, DimensionError
from ..estimate import Estimate
from ..interval import ROUNDING_MARGIN, inflate, matvec_bounds, round_outward
from ..lp.certified import FEASIBILITY_TOLERANCE, dual_bounds, highs_model, new_highs, run_highs, shrink_inward
from ..systems.bounds import Bounds, ResolvedBounds
from ..systems.lti import LTISystem
from ..systems.sampling import sampled_model
from ..validation import as_positive, as_signal, as_time
from .base import Observer, ObserverState, _one_blas_thread

__all__ = ["HullEstimator", "HullLowerBound", "hull_lower_bound"]

FloatArray = NDArray[np.float64]


def _single_support(matrix: FloatArray) -> bool:
    """True when each column has at most one nonzero: then ``matrix @ box`` is itself a box."""
    return bool(np.all(np.count_nonzero(matrix, axis=0) <= 1))


@dataclass(frozen=True)
class _LinearModel:
    """``x+ = Φx + Γu + noise``, ``y = Cx + noise`` with box or variable noise (see :class:`_WindowLP`).

    ``G is None``: the process noise is the box ``x+ - Φx - Γu ∈ [w_lo, w_hi]``; otherwise
    ``x+ = Φx + Γu + G w`` with ``w ∈ [w_lo, w_hi]``. Likewise ``F is None``: ``y - Cx ∈ [v_lo, v_hi]``;
    otherwise ``y = Cx + F v``, ``v ∈ [v_lo, v_hi]``.
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

    def propagate(self, lower: FloatArray, upper: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Sound interval image of a box through one step (no measurement), inflated for rounding."""
        lo, hi = matvec_bounds(self.Phi, lower, upper)
        if self.G is None:
            lo, hi = lo + self.w_lo, hi + self.w_hi
        else:
            wl, wh = matvec_bounds(self.G, self.w_lo, self.w_hi)
            lo, hi = lo + wl, hi + wh
        drive = self.Gamma @ u
        return inflate(lo + drive, hi + drive, 8 * ROUNDING_MARGIN)


def _outer_model(system: LTISystem, full: ResolvedBounds, h: float | None) -> _LinearModel:
    """The exact (discrete) or sound sampled (continuous) model of a system without ``ΔA``."""
    model = sampled_model(system, full, h)
    if system.continuous or _single_support(system.E):
        G, w_lo, w_hi = None, model.noise_center - model.noise_radius, model.noise_center + model.noise_radius
    else:
        G, w_lo, w_hi = system.E, full.w[0], full.w[1]
    F, v_lo, v_hi = _measurement_noise(system, full)
    return _LinearModel(model.Phi, model.Gamma, G, w_lo, w_hi, system.C, F, v_lo, v_hi)


def inner_model(
    system: LTISystem, full: ResolvedBounds, h: float | None, delta_a: FloatArray, substeps: int = 1
) -> _LinearModel:
    """A model whose consistent set lies *inside* the true one: ``A + ΔA`` fixed, noise held per sub-step.

    In continuous time a process noise held constant over each of ``substeps`` equal parts of a sampling
    interval is admissible, so the exact sampled matrices with one noise vector per sub-step give a
    subset of the true consistent set (the simulator's noise is of that form, so its truth lies in it).
    """
    a = system.A + delta_a
    if system.continuous:
        h = as_positive("h", h, "a positive sampling period for a continuous-time system")
        n, m, nw = system.n, system.m, system.nw
        aug = np.zeros((n + m + nw, n + m + nw))
        aug[:n, :n], aug[:n, n : n + m], aug[:n, n + m :] = a, system.B, system.E
        exact = expm(aug * h)
        phi, gamma = exact[:n, :n], exact[:n, n : n + m]
        part = expm(aug * (h / substeps))
        phi_part, g_part = part[:n, :n], part[:n, n + m :]
        columns, carry = [], np.eye(n)
        for _ in range(substeps):  # noise of the last sub-step first: e^{A(h - iδ)} Γ_δ E
            columns.append(carry @ g_part)
            carry = carry @ phi_part
        g = np.hstack(columns[::-1])
        w_box = (np.tile(full.w[0], substeps), np.tile(full.w[1], substeps))
    else:
        phi, gamma, g = a, system.B, system.E
        w_box = (full.w[0], full.w[1])
    if _single_support(g):
        w_lo, w_hi = matvec_bounds(g, w_box[0], w_box[1])
        G: FloatArray | None = None
    else:
        G, w_lo, w_hi = g, w_box[0], w_box[1]
    F, v_lo, v_hi = _measurement_noise(system, full)
    return _LinearModel(phi, gamma, G, w_lo, w_hi, system.C, F, v_lo, v_hi)


def _measurement_noise(system: LTISystem, full: ResolvedBounds) -> tuple[FloatArray | None, FloatArray, FloatArray]:
    if _single_support(system.F):
        lo, hi = matvec_bounds(system.F, full.v[0], full.v[1])
        return None, lo, hi
    return system.F, full.v[0], full.v[1]


class _WindowLP:
    """The hull LP over a window of ``H`` steps, built once; each step changes only bounds and costs.

    Slot ``i = 0 … H`` holds time ``k - H + i``; the dynamics rows link slot ``i`` to ``i + 1`` (and,
    freed, the last to the first, so the matrix is a fixed cycle). Slots of times before 0 are fixed at
    0 with their rows freed, so one model serves every step. The optimal basis of each objective is
    kept and restored at the next step: the extremal trajectory seen from ``x_k`` changes little when
    the window moves, so the dual simplex restarts close to the optimum.
    """

    def __init__(self, model: _LinearModel, horizon: int, points: int = 0) -> None:
        self.model, self.horizon, self.points = model, horizon, points
        n, p = model.C.shape[1], model.C.shape[0]
        S = horizon + 1
        nq = 0 if model.G is None else model.G.shape[1]
        nv = 0 if model.F is None else model.F.shape[1]
        self.n, self.p, self.nq, self.nv, self.slots = n, p, nq, nv, S
        self.w0 = S * n
        self.v0 = self.w0 + S * nq
        self.l0 = self.v0 + S * nv
        self.ncol = self.l0 + points
        self.y0 = S * n
        self.p0 = self.y0 + S * p
        self.nrow = self.p0 + (n + 1 if points else 0)
        cycle = sparse.eye(S, S, k=1, format="lil")
        cycle[S - 1, 0] = 1.0
        dyn_x = sparse.kron(cycle.tocsr(), sparse.eye(n)) - sparse.kron(sparse.eye(S), sparse.csr_matrix(model.Phi))
        blocks: list[list[Any]] = [[dyn_x, None, None, None], [None, None, None, None], [None, None, None, None]]
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
        widths = [S * n, S * nq, S * nv, points]
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
        self.matrix = matrix
        self.matrix_t = matrix.T.tocsr()
        self.abs_matrix_t = abs(self.matrix_t)
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
        self._bases: dict[tuple[int, float], Any] = {}

    def forget_bases(self) -> None:
        """Drop the bases kept for warm starts and the solver's own (the next solves start from scratch)."""
        self._bases.clear()
        self.solver.clearSolver()

    def newest_column(self, i: int) -> int:
        """Column of component ``i`` of the newest state ``x_k`` (always the last slot)."""
        return (self.slots - 1) * self.n + i

    def set_points(self, pts: FloatArray) -> None:
        """Prior ``x_{k-H} = P λ`` (first slot) with ``λ`` in the simplex; ``pts`` has shape (points, n)."""
        for j in range(self.points):
            for i in range(self.n):
                self.solver.changeCoeff(self.p0 + i, self.l0 + j, -float(pts[j, i]))

    def set_bounds(self, col_lo: FloatArray, col_hi: FloatArray, row_lo: FloatArray, row_hi: FloatArray) -> None:
        """Replace all column and row bounds."""
        self.col_lo, self.col_hi, self.row_lo, self.row_hi = col_lo, col_hi, row_lo, row_hi
        self.solver.changeColsBounds(self.ncol, self._cols, col_lo, col_hi)
        self.solver.changeRowsBounds(self.nrow, self._rows, row_lo, row_hi)

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
        if ok:
            self._bases[(key, sign)] = self.solver.getBasis()
        solution = self.solver.getSolution()
        return ok, np.asarray(solution.col_value), np.asarray(solution.row_dual)

    def certified_min(self, col: int, sign: float, key: int) -> float:
        """A rigorous lower bound of ``sign * x[col]`` over the feasible set (weak duality)."""
        _, _, dual = self._minimise(col, sign, key)
        if dual.size != self.nrow or not np.all(np.isfinite(dual)):
            return -np.inf
        cost = np.zeros((1, self.ncol))
        cost[0, col] = sign
        return float(dual_bounds(self, cost, dual[None, :])[0])

    def primal_min(self, col: int, sign: float, key: int) -> tuple[bool, FloatArray]:
        """The solver's best point (for inner hulls) and whether it is feasible (to 1e-7).

        An inner hull needs feasible points only, not optimal ones: a point that is not optimal makes
        the bound less tight, never invalid.
        """
        ok, x, _ = self._minimise(col, sign, key)
        if not ok:
            info = self.solver.getInfo()
            ok = info.primal_solution_status == 2 and info.max_primal_infeasibility <= 1e-7
            ok = ok and x.size == self.ncol and bool(np.all(np.isfinite(x)))
        return ok, x


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
and those failures took two thirds of the time. The rows are residuals of about 0.1 once the prior's centre is
taken out, so the widening is about 1.1e-10 there. Measured with the primal simplex's bound perturbation off but
HiGHS's default ``small_matrix_value``: a factor of 1e-9 lost width (mean summed width 2.7279 against 2.7234
with 1e-10); with 2e-12 the failures came back (0.83 s a step, the perturbation on)."""

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
"""Basis status codes of the bases kept by :class:`_CondensedLP` (``_ZERO``: a nonbasic free row)."""


_Solved = tuple[bool, "NDArray[np.int64] | None", "FloatArray | None", FloatArray]
"""One objective's outcome: optimal?, basic variables, primal values (columns, rows), row duals."""


class _CondensedLP:
    r"""The window LP with the states eliminated (box measurement noise only).

    Variables :math:`z = (x_s, w_0, \dots, w_{H-1})` with :math:`x_s` the first state of the window
    (in its prior box) and :math:`e_i = x_{i+1} - \Phi x_i - \Gamma u_i = G w_i`, :math:`w_i` in its box
    (:math:`G = I` and :math:`w_i = e_i` when the process noise is a box), so
    :math:`x_j = \Phi^j x_s + \sum_{i<j}\Phi^{j-1-i}G w_i + q_j` with the known drive :math:`q_j`. Only the
    ``H + 1`` measurement rows remain (instead of ``(H + 1)(n + p)`` rows). A window shorter than ``H``
    (the first steps, ``s = 0``) uses the same LP with ``w_L … w_{H-1}`` fixed at 0 and the rows after
    its last state free.

    **Warm start.** The ``2n`` objectives of a window are solved as a chain: the lower bounds of
    components ``0 … n-1``, then the upper bounds of ``n-1 … 0`` (:attr:`chain`), by the dense simplex of
    :class:`~intervalobs.lp.dense_simplex.DenseSimplex`, which keeps the basis inverse from one objective to
    the next (HiGHS spends a fixed time on every ``run()``: about 0.7 ms on the 30-tank cascade, against about
    40 µs a pivot and 15 pivots a solve). The first objective of the chain starts from its own optimal basis of
    the previous step, shifted by one step (each variable and row keeps the status it had *at the same time*:
    the active measurements are a property of the data, not of the lag; the noise entering at the new end starts
    at the bound its cost prefers), made square and nonsingular, by the dual simplex. Every later objective
    starts from the optimum of the one before it, which is feasible for the same window, by the primal simplex.
    An objective the dense simplex gives up on (pivot limit, an inaccurate or singular basis) is solved by
    HiGHS's dual simplex, from the basis the dense simplex reached or from the shifted one, and the chain goes on
    from that optimum. Measured on a 30-tank record (30 and 40 steps of vertex noise, one core): 112 and 121 ms a
    step when HiGHS solved the whole chain (its primal simplex from one optimum to the next), 44–56 with the
    dense simplex (repeated runs), mean summed widths 2.72286796 → 2.72286703 and 2.70532032 → 2.70533071.

    **Scaling.** HiGHS solves the LP unscaled. Its default scaling is computed again after every restored
    basis: without it the 30-tank hull record is 2.0× faster (1457 ms a step scaled, 738 unscaled, same widths
    to 2e-8) and learning a bank on the 12-tank cascade 2.4× faster (25.8 s scaled, 10.6 s unscaled).
    Equilibrating the matrix once with power-of-2 factors was slower than either (5.3 s a step at 30 tanks:
    more pivots). The certificates do not depend on the scaling.

    **Thin windows.** Under vertex noise the truth sits on many measurement faces at once and the window's
    feasible set is thin. HiGHS solves every LP with its measurement rows widened by ``MEASUREMENT_RELAX``
    (relative), and its multipliers are certified on the exact rows; it keeps matrix entries down to
    ``SMALL_MATRIX_VALUE`` (its default drops entries below 1e-9, which moved the rows by more than such a set is
    wide); and the primal simplex runs without its random bound perturbation, which on such a set often made it
    end "infeasible". On the 30-tank cascade (records of 30 and 40 steps of vertex noise, one BLAS thread) the
    three took the hull from 1023 and 399 ms a step to 111 and 126, with no failed solve left, and its mean summed
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
    """

    def __init__(self, model: _LinearModel, horizon: int, workers: int = 1) -> None:
        from highspy import _core

        from ..lp.dense_simplex import DenseSimplex  # Numba: loaded (80 MB, 0.4 s) only where it is used

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
        self.ncol = n + H * nw
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
        """``objectives[L, i]``: the cost of ``(x_{s+L})_i`` for a window of ``L`` steps."""
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
        self.dense = [DenseSimplex(matrix, FEASIBILITY_TOLERANCE, FEASIBILITY_TOLERANCE, limit) for _ in range(workers)]
        self.solver = self.solvers[0]
        self._pool = ThreadPoolExecutor(max_workers=workers) if workers > 1 else None
        self.inf = float(self.solver.getInfinity())
        free_rows, unit = np.full(self.nrow, self.inf), np.ones(self.ncol)
        lp = highs_model(sparse.csc_matrix(matrix), -unit, unit, -free_rows, free_rows, self.inf)
        for solver in self.solvers:
            # Devex pricing: after each restored basis, steepest-edge weights would be recomputed (3-7 % slower).
            solver.setOptionValue("simplex_dual_edge_weight_strategy", 1)
            # No scaling (see "Scaling" above): HiGHS's own is set up again for every restored basis.
            solver.setOptionValue("simplex_scale_strategy", 0)
            # No random bound perturbation in HiGHS's primal simplex (now only its clean-up after the dual simplex),
            # and only entries below 1e-12 dropped from the matrix (HiGHS's smallest setting; default 1e-9): see
            # "Thin windows" above.
            solver.setOptionValue("primal_simplex_bound_perturbation_multiplier", 0.0)
            solver.setOptionValue("small_matrix_value", SMALL_MATRIX_VALUE)
            solver.setOptionValue("simplex_iteration_limit", ITERATION_LIMIT * (self.nrow + self.ncol))
            solver.passModel(lp)
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
        self.reuse: Callable[[_CondensedLP, FloatArray], FloatArray] | None = None
        """When set, called with this LP (bounds of the window set) and the ``2n`` costs before the solves;
        returns multipliers ``(2n, rows)`` to use instead of solving, a NaN row for each objective to solve
        (``HullEstimator.certificates``). Objectives not solved are not logged."""

    def set_window(
        self, k: int, y: FloatArray, u: FloatArray, prior_lo: FloatArray, prior_hi: FloatArray, use_current: bool
    ) -> tuple[FloatArray, FloatArray]:
        """Bounds for the window ``s = max(k - H, 0) … k``; returns the drive ``q_L`` and the objective's pad.

        Row ``i`` of ``y`` and ``u`` is time ``s + i``; ``prior_*`` bound the window's first state (the
        box of ``x_0`` while ``k ≤ H``).
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
        growth[:L] = self.e_max + np.abs(drives[:L]) + np.abs(q[1 : L + 1])
        # x_s = mid + z, z in the centred prior box: the LP works with deviations from the prior's centre
        mid = 0.5 * (prior_lo + prior_hi)
        q += self.objectives[:, :, :n] @ mid
        start_mag = np.maximum(np.abs(prior_lo), np.abs(prior_hi))
        mag = (self.abs_map @ np.concatenate([start_mag, growth.ravel()])).reshape(H + 1, n)
        width = n + m.Gamma.shape[1] + self.nw + 2  # terms per inner product of the powers, G and the drive
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
        self.col_lo = np.concatenate([z_lo, np.tile(m.w_lo, L), idle])
        self.col_hi = np.concatenate([z_hi, np.tile(m.w_hi, L), idle])
        self.row_lo, self.row_hi = lo.ravel(), hi.ravel()  # exact: what the certificates are evaluated on
        self.row_scale = 1.0 + np.maximum(np.abs(self.row_lo), np.abs(self.row_hi))  # of the relative widenings
        relax = MEASUREMENT_RELAX * self.row_scale
        self.solve_lo, self.solve_hi = self.row_lo - relax, self.row_hi + relax  # what HiGHS solves
        for solver in self.solvers:
            solver.changeColsBounds(self.ncol, self._cols, self.col_lo, self.col_hi)
            solver.changeRowsBounds(self.nrow, self._rows, self.solve_lo, self.solve_hi)
        return q[L], x_error[L] + rounding[L]

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

        def solve_part(w: int) -> list[tuple[int, _Solved]]:
            solver, dense = self.solvers[w], self.dense[w]
            out: list[tuple[int, _Solved]] = []
            dense.ready = False
            for r in parts[w].tolist():
                start = partial(self._start_basis, starts, r)
                if not dense.ready and starts is not None and starts[1][r]:
                    dense.start_from_statuses(self.col_lo, self.col_hi, self.solve_lo, self.solve_hi, starts[0][r])
                if dense.ready:
                    optimal, _ = dense.solve(costs[r])
                    if optimal:
                        out.append((r, (True, dense.basic_variables(), dense.values(), dense.row_duals())))
                        continue
                    start = partial(self._highs_basis, dense.statuses())
                solved = self._solve_one(solver, costs[r], start)
                if solved[0]:
                    assert solved[1] is not None and solved[2] is not None
                    dense.start(self.col_lo, self.col_hi, self.solve_lo, self.solve_hi, solved[1], solved[2])
                out.append((r, solved))
            return out

        run_parts = map if self._pool is None else self._pool.map
        outcomes = [item for part in run_parts(solve_part, range(len(parts))) for item in part]
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
            _, _, _, dual = self._solve_one(solver, costs[r], lambda: None)
            if dual.shape == (nrow,) and np.all(np.isfinite(dual)):
                again = dual_bounds(self, costs[r : r + 1], dual[None, :])[0]
                if again > bounds[r]:
                    bounds[r], duals[r], usable[r] = again, dual, True
        if self.dual_log is not None:
            for r in np.flatnonzero(usable & solve).tolist():
                self.dual_log.append((r // 2, float(signs[r]), duals[r].copy(), self.length, not self.full))
        return bounds[0::2], bounds[1::2]

    def _solve_one(self, solver: Any, cost: FloatArray, start: Callable[[], Any]) -> _Solved:
        """Solve one objective with HiGHS's dual simplex from the basis ``start()`` (None: from the instance's
        current basis, or from scratch after ``clearSolver``)."""
        solver.changeColsCost(self.ncol, self._cols, cost)
        basis = start()
        if basis is not None:
            solver.setBasis(basis)
        run_highs(solver)
        widened = solver.getModelStatus() != self._optimal
        if widened:
            # No optimum (a thin feasible set, see ROW_RELAX): solve the widened LP, from the basis reached and
            # then from scratch; its multipliers are certified on the exact rows like any others.
            relax = ROW_RELAX * self.row_scale
            solver.changeRowsBounds(self.nrow, self._rows, self.solve_lo - relax, self.solve_hi + relax)
            run_highs(solver)
            if solver.getModelStatus() != self._optimal:
                solver.clearSolver()
                run_highs(solver)
        return self._outcome(solver, widened)

    def _outcome(self, solver: Any, widened: bool) -> _Solved:
        """The solver's outcome; restores the rows of :meth:`set_window` after a ``ROW_RELAX``-widened solve."""
        solution = solver.getSolution()
        optimal = solver.getModelStatus() == self._optimal
        basic = np.asarray(solver.getBasicVariables()[1]) if optimal else None
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
        n, nw, p, ncol = self.n, self.nw, self.p, self.ncol
        if start + 1 == self.start:
            entering = np.where(costs[:, ncol - nw :] >= 0.0, _LOWER, _UPPER).astype(np.int8)
            fresh_rows = np.full((codes.shape[0], p), _BASIC, dtype=np.int8)
            codes = np.hstack([codes[:, :n], codes[:, n + nw : ncol], entering, codes[:, ncol + p :], fresh_rows])
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


class _Window:
    """Fills the bounds of a :class:`_WindowLP` for step ``k`` from the record and the stored boxes."""

    def __init__(self, model: _LinearModel, horizon: int, points: int = 0) -> None:
        self.model = model
        self.lp = _WindowLP(model, horizon, points)

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
        With ``window_boxes`` False only the first state of the window gets its box (the prior); the
        others get a tenfold-widened copy (sound and finite, as the certificate needs, but inactive:
        fewer degenerate pivots).
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
        if nq:
            wl = np.where(step_valid[:, None], m.w_lo, 0.0)
            wh = np.where(step_valid[:, None], m.w_hi, 0.0)
            col_lo[lp.w0 : lp.v0], col_hi[lp.w0 : lp.v0] = wl.ravel(), wh.ravel()
            d_lo, d_hi = drive, drive.copy()
        else:
            d_lo, d_hi = drive + m.w_lo, drive + m.w_hi
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


class HullEstimator(Observer):
    r"""The interval hull of the consistent set of an LTI system, by linear programming at each step.

    Build it with :meth:`design` (the constructor takes the same arguments).

    Parameters
    ----------
    system : LTISystem
        Discrete- or continuous-time model without ``dA`` (for interval ``ΔA`` see
        :func:`hull_lower_bound`).
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v``.
    horizon : int or None
        Window length ``H`` (steps); ``None`` for the full history (exact, cost growing with time).
    h : float, optional
        Sampling period of a continuous-time system (the sound sampled model is used).
    filtered : bool
        If False (default), row ``k`` of :meth:`run` is the hull of ``x_k`` given ``y_0 … y_{k-1}``
        (:attr:`rows` ``"predicted"``), comparable with every other observer. If True it also uses
        ``y_k`` (the "filtered" hull, :attr:`rows` ``"filtered"``): :meth:`step` with ``y_k`` then
        returns the box of ``x_k`` given ``y_0 … y_k``.
    window_boxes : bool
        Also bound every state inside the window by its earlier box (not only the first one, the
        prior). Slightly tighter for short windows (0.4 % at H = 10 on seed 002's (68), nothing at
        H = 40) but about 1.5× more simplex pivots; redundant for the full history.
    workers : int
        HiGHS instances solving the ``2n`` LPs of a step in parallel threads (condensed LP only; HiGHS
        releases the GIL while it solves). The bounds do not depend on it; use at most the number of
        free cores.
    processes : int
        Worker processes for the Monte Carlo runs of :meth:`run` (a leading axis of ``y``): the runs are
        split into ``processes`` contiguous chunks, each run by a fresh estimator in its own process. A run's
        boxes depend on its data only (:meth:`init` forgets the warm starts), so they do not depend on it.

    Notes
    -----
    Each step solves ``2n`` LPs (the model is built once per window length and only bounds and costs
    change). With a finite horizon, a stable (ρ(Φ) ≤ 1) model with box measurement noise uses the
    condensed LP at every step (states eliminated, :class:`_CondensedLP`; the first ``H`` steps as shorter
    windows from ``x_0``): the same set with ``H + 1`` rows, and bases restored aligned by time (on seed
    002's (68) with ``H = 40``, 2.4 (switching noise) and 9.8 (i.i.d. vertex noise) pivots per LP instead
    of 16 and 63 with the sparse window LP). Its ``2n`` objectives are solved as a chain by a dense simplex of
    our own (:class:`~intervalobs.lp.dense_simplex.DenseSimplex`): the first by the dual simplex from its
    basis of the previous step, each next one by the primal simplex from the optimum of the one before; HiGHS
    solves what it gives up on, and the sparse window LP. Every bound is certified by weak duality (module
    docstring), so the box is sound whatever the solver's accuracy. A Monte
    Carlo axis of ``y`` is processed run by run (LPs do not vectorise), in ``processes`` worker processes.
    """

    summary_fields = ("horizon",)
    batched = False  # one LP per bound and run: a Monte Carlo axis is run after run

    h: float

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        horizon: int | None = 50,
        h: float | None = None,
        filtered: bool = False,
        window_boxes: bool = False,
        workers: int = 1,
        processes: int = 1,
    ) -> None:
        if not isinstance(system, LTISystem):
            raise TypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not isinstance(bounds, Bounds):
            raise TypeError(f"bounds: expected a Bounds, got {type(bounds).__name__}")
        if system.dA is not None:
            raise AssumptionError(
                "system.dA: the consistent set of an interval ΔA is not convex, so its hull is not an LP; "
                "use hull_lower_bound for a lower bound on the width of any sound estimator"
            )
        if horizon is not None and (int(horizon) != horizon or horizon < 1):
            raise DataError(f"horizon: expected a positive integer or None, got {horizon!r}")
        self.system, self.bounds = system, bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.horizon = None if horizon is None else int(horizon)
        self.filtered = bool(filtered)
        self.rows = "filtered" if self.filtered else "predicted"
        self.window_boxes = bool(window_boxes)
        if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
            raise DataError(f"workers: expected a positive integer, got {workers!r}")
        self.workers = int(workers)
        if isinstance(processes, bool) or not isinstance(processes, (int, np.integer)) or processes < 1:
            raise DataError(f"processes: expected a positive integer, got {processes!r}")
        self.processes = int(processes)
        self._given = (system, bounds, horizon, h, filtered, window_boxes, workers)
        self.model = _outer_model(system, self.bounds, h)
        self.h = float(h) if system.continuous and h is not None else float(system.dt or 1.0)
        self._windows: dict[int, _Window] = {}
        self._condensed: _CondensedLP | None = None
        if self.condensed_allowed():
            assert self.horizon is not None
            self._condensed = _CondensedLP(self.model, self.horizon, self.workers)

    @classmethod
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        h: float | None = None,
        *,
        horizon: int | None = 50,
        filtered: bool = False,
        window_boxes: bool = False,
        workers: int = 1,
        processes: int = 1,
    ) -> HullEstimator:
        """Build the estimator (there is no gain: the window LP of each step is the estimator).

        Parameters
        ----------
        system : LTISystem
            Discrete- or continuous-time model without ``dA``.
        bounds : Bounds
            Boxes of ``x0``, ``w``, ``v``.
        h : float, optional
            Sampling period of a continuous-time system.
        horizon : int or None
            Window length ``H`` in steps; ``None`` for the full history.
        filtered : bool
            Rows of :meth:`run` use ``y_k`` too (class docstring).
        window_boxes : bool
            Bound every state of the window by its earlier box.
        workers : int
            HiGHS instances solving a step's LPs in parallel threads.
        processes : int
            Worker processes for the Monte Carlo runs of :meth:`run`.

        Returns
        -------
        HullEstimator

        Raises
        ------
        AssumptionError
            If the system has an interval ``dA`` (the consistent set is not convex).
        """
        return cls(
            system,
            bounds,
            horizon=horizon,
            h=h,
            filtered=filtered,
            window_boxes=window_boxes,
            workers=workers,
            processes=processes,
        )

    def condensed_allowed(self) -> bool:
        """Whether the condensed LP is used (box measurement noise, finite horizon, prior-only boxes, stable Φ).

        Returns
        -------
        bool
        """
        return (
            self.horizon is not None
            and self.model.F is None
            and not self.window_boxes
            and bool(np.max(np.abs(np.linalg.eigvals(self.model.Phi))) <= 1.0)
        )

    def _window(self, k: int) -> _Window:
        if self.horizon is not None:
            size = self.horizon
        else:  # full history: capacity doubles, so rebuilds are rare
            size = max(16, 1 << int(np.ceil(np.log2(max(k, 1)))))
        if size not in self._windows:
            self._windows = {size: _Window(self.model, size)}
        return self._windows[size]

    # -- protocol ------------------------------------------------------------------------------
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at the first sample: the prior box of ``x_0`` and an empty record.

        Also drops the LP bases kept for warm starts, so that a record started here gives the same
        boxes whatever the estimator solved before.

        Parameters
        ----------
        x0_lower, x0_upper : array_like, optional
            Prior box of ``x(t_0)`` (default ``bounds.x0``).

        Returns
        -------
        ObserverState
            ``internal`` holds the step ``k``, the prior box ``x0`` and the record a window needs:
            ``y``, ``u`` and the boxes ``box_lo``/``box_hi`` of the last ``horizon`` samples (all of
            them for the full history), row ``i`` at time ``start + i``.
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        for window in self._windows.values():  # a record's boxes depend on its data only, not on earlier ones
            window.lp.forget_bases()
        if self._condensed is not None:
            self._condensed.forget_bases()
        internal: dict[str, Any] = {
            "k": 0,
            "x0": (lo.copy(), hi.copy()),
            "start": 0,
            "y": np.zeros((0, self.p)),
            "u": np.zeros((0, self.m)),
            "box_lo": np.zeros((0, self.n)),
            "box_hi": np.zeros((0, self.n)),
        }
        return ObserverState(lo.copy(), hi.copy(), internal=internal)

    @_one_blas_thread
    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume ``y_k``, ``u_k``: the hull of ``x_{k+1}`` given ``y_0 … y_k`` (of ``x_k`` when ``filtered``).

        With a finite horizon the state keeps the last ``horizon`` samples only, so a step costs the
        same time and memory at every ``k``; the given state is not modified. Like :meth:`run`, a step runs
        on one BLAS thread: on the 30-tank cascade OpenBLAS's default two threads took twice the CPU time
        (205 against 88 ms a step), spinning between the small products of the certificates.

        Parameters
        ----------
        state : ObserverState
            From :meth:`init` or a previous step.
        y : array_like, shape (p,)
            Measurement at ``t_k`` (one run: LPs do not batch).
        u : array_like, shape (m,), optional
            Known input at ``t_k``; required when the system has inputs (m > 0).

        Returns
        -------
        ObserverState
        """
        return super().step(state, y, u)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        if y.ndim != 1:
            raise DimensionError(f"y: expected one sample of shape ({self.p},) (LPs do not batch), got {y.shape}")
        old = state.internal
        k, start, x0 = int(old["k"]), int(old["start"]), old["x0"]
        lo, hi = state.lower, state.upper
        if self.filtered and k > 0:  # state: the filtered box of x_{k-1}; predict x_k from y_0 … y_{k-1}
            nlo, nhi = self.model.propagate(lo, hi, old["u"][-1])
            lo, hi = self._hull(k, start, old["y"], old["u"], old["box_lo"], old["box_hi"], nlo, nhi, False, x0)
        ys, us = np.concatenate([old["y"], y[None]]), np.concatenate([old["u"], u[None]])
        if self.filtered:
            lo, hi = self._hull(k, start, ys, us, old["box_lo"], old["box_hi"], lo, hi, True, x0)
        box_lo, box_hi = np.concatenate([old["box_lo"], lo[None]]), np.concatenate([old["box_hi"], hi[None]])
        if not self.filtered:
            nlo, nhi = self.model.propagate(lo, hi, u)
            lo, hi = self._hull(k + 1, start, ys, us, box_lo, box_hi, nlo, nhi, False, x0)
        drop = 0 if self.horizon is None else max(ys.shape[0] - self.horizon, 0)
        internal: dict[str, Any] = {
            "k": k + 1,
            "x0": x0,
            "start": start + drop,
            "y": ys[drop:],
            "u": us[drop:],
            "box_lo": box_lo[drop:],
            "box_hi": box_hi[drop:],
        }
        return ObserverState(lo, hi, internal=internal)

    def _hull(
        self,
        k: int,
        start: int,
        ys: FloatArray,
        us: FloatArray,
        box_lo: FloatArray,
        box_hi: FloatArray,
        last_lo: FloatArray,
        last_hi: FloatArray,
        use_current: bool,
        x0: tuple[FloatArray, FloatArray],
    ) -> tuple[FloatArray, FloatArray]:
        """Certified hull of ``x_k``.

        Row ``i`` of ``ys``, ``us``, ``box_*`` is time ``start + i`` (``box_*`` bound ``x_τ`` for
        ``τ < k``); ``last_*`` bound ``x_k``.
        """
        if k == 0:
            last_lo, last_hi = np.maximum(last_lo, x0[0]), np.minimum(last_hi, x0[1])
            if not use_current:
                return last_lo, last_hi
        if self._condensed is not None:
            assert self.horizon is not None
            s = max(k - self.horizon, 0)
            prior = (box_lo[s - start], box_hi[s - start]) if s < k else (last_lo, last_hi)
            lp = self._condensed
            drive, pad = lp.set_window(k, ys[s - start :], us[s - start :], prior[0], prior[1], use_current)
            low, high = lp.certified_bounds(int(use_current))
            lower, upper = np.maximum(last_lo, low + drive - pad), np.minimum(last_hi, -high + drive + pad)
            return self._consistent(k, lower, upper)
        window = self._window(k)
        sparse_lp = window.lp
        bounds = window.bounds_at(
            k, ys, us, box_lo, box_hi, last_lo, last_hi, use_current, x0[0], x0[1], self.window_boxes, start
        )
        sparse_lp.set_bounds(*bounds)
        lower = last_lo.copy()
        upper = last_hi.copy()
        key = 2 * self.n if use_current else 0
        for i in range(self.n):
            col = sparse_lp.newest_column(i)
            lower[i] = max(lower[i], sparse_lp.certified_min(col, 1.0, key + i))
            upper[i] = min(upper[i], -sparse_lp.certified_min(col, -1.0, key + i))
        return self._consistent(k, lower, upper)

    def _separate_runs(self, times: FloatArray, ys: FloatArray, us: FloatArray) -> list[Estimate]:
        """The Monte Carlo runs, in ``processes`` worker processes when there are several."""
        count = ys.shape[0]
        if self.processes == 1 or count == 1:
            return super()._separate_runs(times, ys, us)
        chunks = np.array_split(np.arange(count), min(self.processes, count))
        # fork where the platform has it: a spawned worker would import the package first (about a second).
        method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
        tasks = [(self._given, times, ys[chunk], us[chunk]) for chunk in chunks]
        with ProcessPoolExecutor(len(chunks), mp_context=multiprocessing.get_context(method)) as pool:
            return [estimate for part in pool.map(_hull_runs, tasks) for estimate in part]

    @staticmethod
    def _consistent(k: int, lower: FloatArray, upper: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Inflate the box, and refuse an empty one (the data contradict the bounds)."""
        lower, upper = inflate(lower, upper)
        if np.any(lower > upper):
            raise DataError(
                f"y: the measurements are inconsistent with the model and its bounds at step {k} "
                "(empty consistent set): check the noise bounds"
            )
        return lower, upper

    @_one_blas_thread
    def certificates(
        self,
        t: ArrayLike,
        y: ArrayLike,
        u: ArrayLike | None = None,
        first_rows: bool = False,
        reuse: Callable[[Any, FloatArray], FloatArray] | None = None,
    ) -> dict[tuple[int, float] | tuple[int, float, int], FloatArray]:
        r"""The duality certificates of the window LPs of a record: one FIR weight set per bound.

        For the bound ``sign * (x_k)_i`` the multipliers :math:`\lambda_j` of the window's measurement
        rows ``j = 0 … H`` give the linear combination :math:`\sum_j \text{sign}\,\lambda_j^\top y_{k-H+j}`
        that the certified bound uses (module docstring); any such weights give a sound bound on any
        record (:class:`~intervalobs.observers.fir.FiniteMemoryObserver` evaluates them rigorously).

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times.
        y : array_like, shape (T, p)
            Measurements of one record.
        u : array_like, shape (T, m), optional
            Known inputs.
        first_rows : bool
            Also return the certificates of the first rows' windows (``k ≤ H``: the ``L = k`` steps from
            the prior of ``x_0``; row ``j`` is the weight of ``y_j``).
        reuse : callable, optional
            Called before the solves of every window with the window LP (its ``row_lo``, ``row_hi``, ``col_lo``,
            ``col_hi``, ``length``, ``full`` and ``dual_log`` set) and the ``2n`` costs (rows ``2i``: lower bound of
            component ``i``, ``2i + 1``: upper); returns multipliers ``(2n, rows)`` to bound those objectives with
            instead of solving them (any multipliers give a sound bound), a NaN row for each objective to solve.
            Only solved objectives give certificates (:meth:`FiniteMemoryObserver.learn
            <intervalobs.observers.fir.FiniteMemoryObserver.learn>` skips bounds its bank already attains).

        Returns
        -------
        dict
            ``(i, sign)`` → array of shape ``(count, H + 1, p)``: the row multipliers of every solve of
            the condensed window LP (steps ``k > H``) for that bound; with ``filtered`` both the
            predicted and the filtered solves (row ``H``, the weight of :math:`y_k`, is zero in the first).
            With ``first_rows``, also ``(i, sign, L)`` → ``(count, H + 1, p)`` for the windows of ``L`` steps
            anchored at ``x_0`` (rows of measurements outside the window are zero).
        """
        if self._condensed is None:
            raise AssumptionError(
                "certificates: needs the condensed window LP (finite horizon, box measurement noise, stable Φ, "
                "window_boxes=False); see condensed_allowed()"
            )
        times, ys, us = self._signals(t, y, u)
        if ys.ndim != 2:
            raise DimensionError(f"y: expected one record of shape (T, {self.p}), got shape {ys.shape}")
        lp = self._condensed
        lp.dual_log, lp.reuse = [], reuse
        try:
            self._loop(times, ys, us)
            log = lp.dual_log
        finally:
            lp.dual_log, lp.reuse = None, None
        shape = (lp.horizon + 1, self.p)
        found: dict[tuple[int, float] | tuple[int, float, int], list[FloatArray]] = {
            (i, sign): [] for i in range(self.n) for sign in (1.0, -1.0)
        }
        for i, sign, duals, length, anchored in log:
            if anchored and first_rows:
                found.setdefault((i, sign, length), []).append(duals.reshape(shape))
            elif not anchored:
                found[(i, sign)].append(duals.reshape(shape))
        return {key: np.array(rows).reshape(len(rows), *shape) for key, rows in found.items()}

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
        """
        return {
            "method": "HullEstimator",
            "condensed": self._condensed is not None,
            "horizon": "full" if self.horizon is None else self.horizon,
            "filtered": self.filtered,
            "window_boxes": self.window_boxes,
            "workers": self.workers,
            "h": self.h,
            "transient_s": 0.0,
            "certificate": "weak duality (Neumaier-Shcherbina), rounding subtracted",
        }


def _hull_runs(task: tuple[tuple[Any, ...], FloatArray, FloatArray, FloatArray]) -> list[Estimate]:
    """Worker of :meth:`HullEstimator.run` with ``processes``: a chunk of runs on a fresh estimator."""
    given, times, ys, us = task
    return HullEstimator(*given)._separate_runs(times, ys, us)


@dataclass(frozen=True)
class HullLowerBound:
    """A LOWER BOUND on the box of any sound estimator — not an estimate; never use it as bounds.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
    lower, upper : numpy.ndarray, shape (T, n)
        Hull of the union of inner consistent sets of the fixed ``ΔA`` samples (NaN where no sample is
        consistent with the data). Every sound box of ``x_k`` contains ``[lower_k, upper_k]``, so
        ``upper - lower`` is a lower bound on any sound estimator's width.
    samples : numpy.ndarray, shape (S, n, n)
        The ``ΔA`` samples used.
    alive : numpy.ndarray, shape (S,)
        Whether each sample stayed consistent with the data to the end.
    label : str
        The reminder printed in every report.
    meta : dict
        Window length and whether ``y_k`` was used.
    """

    t: FloatArray
    lower: FloatArray
    upper: FloatArray
    samples: FloatArray
    alive: NDArray[np.bool_]
    label: str = "lower bound on the width of any sound estimator (not an estimate)"
    meta: dict[str, Any] = field(default_factory=dict)

    def width(self) -> FloatArray:
        """Widths ``upper - lower`` (NaN where undefined).

        Returns
        -------
        numpy.ndarray, shape (T, n)
        """
        return self.upper - self.lower


def delta_samples(system: LTISystem, count: int, seed: int) -> FloatArray:
    """``ΔA = 0`` (nominal), then random vertices of the ``ΔA`` box."""
    n = system.n
    if system.dA is None:
        return np.zeros((min(count, 1), n, n))
    lo, hi = system.dA
    rng = np.random.default_rng(seed)
    picks = [np.zeros((n, n))] if count > 0 else []
    for _ in range(max(count - 1, 0)):
        picks.append(np.where(rng.integers(0, 2, size=(n, n)) == 1, hi, lo))
    return np.array(picks).reshape(-1, n, n)


def hull_lower_bound(
    system: LTISystem,
    bounds: Bounds,
    t: ArrayLike,
    y: ArrayLike,
    u: ArrayLike | None = None,
    h: float | None = None,
    samples: int | ArrayLike = 3,
    horizon: int | None = 60,
    filtered: bool = False,
    seed: int = 0,
    truth: tuple[ArrayLike, ArrayLike] | None = None,
    substeps: int = 10,
) -> HullLowerBound:
    r"""Lower bound on the box any sound estimator can report: inner hulls for fixed ``ΔA`` samples.

    For a fixed :math:`\Delta A_s` the consistent set :math:`S^s_k` is a polytope contained in the true
    (non-convex) consistent set :math:`S_k`, so :math:`\square\bigcup_s S^s_k \subseteq \square S_k`,
    and a sound estimator's box contains :math:`\square S_k`. Each :math:`\square S^s_k` is computed
    from *inside*: in continuous time with a process noise held over each sampling interval (an
    admissible signal), and with a moving window whose prior is the convex hull of the optimal states
    found ``H`` steps back (points of :math:`S^s_{k-H}`), so every solution is a consistent state. The
    result is shrunk inward by a relative ``1e-6`` to cover the solver's primal tolerance.

    Parameters
    ----------
    system : LTISystem
        The model (``dA`` optional: without it one sample, ``ΔA = 0``, is used).
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v``.
    t : array_like, shape (T,)
        Sample times.
    y : array_like, shape (T, p)
        Measurements of one run.
    u : array_like, shape (T, m), optional
        Known inputs.
    h : float, optional
        Sampling period of a continuous-time system.
    samples : int or array_like, shape (S, n, n)
        Number of samples (the nominal ``ΔA = 0`` and random vertices of the box; 0 for none, e.g.
        when ``truth`` is given), or the samples.
    horizon : int or None
        Window length (None: the full history, exact and slow).
    filtered : bool
        Use ``y_k`` for the box of ``x_k`` (compare with filtered estimators) or not (default).
    seed : int
        Seed of the vertex draw.
    truth : tuple (ΔA, x), optional
        In a simulation: the true ``ΔA`` (added as a sample) and the true states (T, n). In discrete
        time the true state is a consistent point of that sample's set, so it is added to its window
        prior: the LPs of that sample then never become infeasible. (A sample inconsistent with the data
        has an empty set and contributes nothing; without the true ``ΔA`` all samples may be.)
        In continuous time the truth is such a point when it was simulated with process noise held
        over ``substeps`` equal parts of each sampling interval (the default of
        :func:`~intervalobs.simulate.simulate`).
    substeps : int
        Continuous time: noise vectors per sampling interval of the inner model.

    Returns
    -------
    HullLowerBound
        Not an :class:`~intervalobs.estimate.Estimate`: a width no sound estimator can beat.
    """
    times = as_time("t", t)
    ys = as_signal("y", y, times.size, system.p)
    if ys.ndim != 2:
        raise DimensionError(f"y: expected one run of shape (T, p), got shape {ys.shape}")
    if u is None and system.m > 0:
        raise DataError(f"u: expected the known input, shape ({times.size}, {system.m}), got None")
    us = np.zeros((times.size, system.m)) if u is None else as_signal("u", u, times.size, system.m)
    full = bounds.resolve(system)
    if np.ndim(samples) == 0:
        deltas = delta_samples(system, int(samples), seed)  # type: ignore[arg-type]
    else:
        deltas = np.asarray(samples, dtype=float).reshape(-1, system.n, system.n)
    anchors: list[FloatArray | None] = [None] * deltas.shape[0]
    if truth is not None:
        true_delta = np.asarray(truth[0], dtype=float).reshape(1, system.n, system.n)
        deltas = np.concatenate([true_delta, deltas])
        x_true = np.asarray(truth[1], dtype=float)
        if x_true.shape != (times.size, system.n):
            raise DimensionError(f"truth: expected states of shape {(times.size, system.n)}, got {x_true.shape}")
        anchors = [x_true, *anchors]
    steps, n = times.size, system.n
    size = steps - 1 if horizon is None else int(horizon)
    size = max(size, 1)
    lowers = np.full((deltas.shape[0], steps, n), np.nan)
    uppers = np.full((deltas.shape[0], steps, n), np.nan)
    alive = np.ones(deltas.shape[0], dtype=bool)
    x0 = full.x0
    for s, delta in enumerate(deltas):
        anchor = anchors[s]
        inner = inner_model(system, full, h, delta, substeps)
        window = _Window(inner, size, points=2 * n + (anchor is not None))
        lp = window.lp
        points: list[FloatArray] = []
        for k in range(steps):
            free_lo, free_hi = np.full(n, -lp.inf), np.full(n, lp.inf)
            col_lo, col_hi, row_lo, row_hi = window.bounds_at(
                k, ys, us, None, None, free_lo, free_hi, filtered, x0[0], x0[1]
            )
            first = k - size
            if first > 0:
                prior = points[first] if anchor is None else np.vstack([points[first], anchor[first]])
                lp.set_points(prior)
                row_lo[lp.p0 :] = 0.0
                row_hi[lp.p0 :] = 0.0
                row_lo[-1] = row_hi[-1] = 1.0
                col_lo[lp.l0 :], col_hi[lp.l0 :] = 0.0, 1.0
            lp.set_bounds(col_lo, col_hi, row_lo, row_hi)
            base = lp.newest_column(0)
            found = np.empty((2 * n, n))
            ok_all = True
            for i in range(n):
                for j, sign in enumerate((1.0, -1.0)):
                    ok, xs = lp.primal_min(base + i, sign, i)
                    ok_all &= ok
                    found[2 * i + j] = xs[base : base + n]
            if not ok_all:
                if anchor is None:
                    alive[s] = False
                    break
                points.append(np.repeat(anchor[k][None, :], 2 * n, axis=0))  # no hull at k: the truth only
                continue
            points.append(found)
            lowers[s, k] = found.min(axis=0)
            uppers[s, k] = found.max(axis=0)
    # A sample that became inconsistent with the data keeps its earlier (valid) hulls.
    lower = np.full((steps, n), np.nan)
    upper = np.full((steps, n), np.nan)
    seen = np.any(np.isfinite(lowers), axis=0)
    lower[seen] = np.nanmin(lowers[:, seen], axis=0)
    upper[seen] = np.nanmax(uppers[:, seen], axis=0)
    lower, upper = shrink_inward(lower, upper)
    return HullLowerBound(
        times, lower, upper, deltas, alive, meta={"horizon": "full" if horizon is None else size, "filtered": filtered}
    )
