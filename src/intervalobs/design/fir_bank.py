r"""The design of a finite-memory observer's filter bank: the worst-case filter LP and the training's coverage.

:func:`_worst_case_gains` solves, per state component, the LP whose optimum is the FIR filter of least evaluated
worst-case error (the bank's first member, and the whole bank of :meth:`FiniteMemoryObserver.design
<intervalobs.observers.fir.FiniteMemoryObserver.design>`); :class:`_Coverage` decides which training LPs
:meth:`~intervalobs.observers.fir.FiniteMemoryObserver.learn` solves and which stored certificates it keeps. The
estimator (:mod:`intervalobs.observers.fir`) says what is estimated; how its filters are found is here.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from ..errors import AssumptionError, DataError, DesignError
from ..lp.certified import LP_OPTIONS
from ..systems.bounds import ResolvedBounds
from ..systems.lti import LTISystem, refuse_uncertain_input
from ..systems.sampling import SampledModel, sampled_model

FloatArray = NDArray[np.float64]


COVERAGE_PATIENCE = 10
"""Solves over which ``learn`` averages a bound's gap; a bound within its tolerance is solved once in this many
windows (so a bank that stops covering the data resumes training)."""


class _Coverage:
    r"""Which training LPs :meth:`FiniteMemoryObserver.learn` solves (the ``reuse`` hook of
    :meth:`~intervalobs.observers.hull.HullEstimator.certificates`).

    Per objective (window shape, component, sign) it keeps the certificates found so far as their multipliers
    ``y`` and reduced costs ``d = c - Aᵀy``, so that the bounds of all of them on a window are one matrix-vector
    product, :math:`y^+\cdot\underline r + y^-\cdot\overline r + d^+\cdot\underline z + d^-\cdot\overline z`
    (row and column bounds; used to rank them: the hull certifies the bound of the one it is given). After a
    solve, the gap is the LP's bound minus the best stored certificate's bound on that window, relative to the
    width of the component's box there: the stored bank's shortfall on a window it has not seen. An objective
    whose mean gap over its last ``COVERAGE_PATIENCE`` solves is at most ``tolerance`` is solved on one window in
    ``COVERAGE_PATIENCE`` only; on the others its bound is its best stored certificate's (any multipliers give a
    sound bound).
    """

    def __init__(self, tolerance: float) -> None:
        self.tolerance = tolerance
        self.found: dict[tuple[Any, int], list[Any]] = {}  # per key: [count, (y+, y-, d+, d-) rows, multipliers]
        self.gaps: dict[tuple[Any, int], list[float]] = {}
        self.windows: dict[Any, list[FloatArray]] = {}  # per window shape: the bounds of every training window
        self.model: tuple[FloatArray, Any] = (np.zeros((0, 0)), np.zeros((0, 0)))  # the 2n costs and Aᵀ
        self.skips: dict[tuple[Any, int], int] = {}
        self.log: list[Any] | None = None
        self.seen = 0
        self.pending: tuple[Any, ...] | None = None
        self.solved = self.reused = 0

    def __call__(self, lp: Any, costs: FloatArray) -> FloatArray:
        """Multipliers for the objectives not to solve on this window (NaN rows: solve)."""
        self.settle()
        if lp.dual_log is not self.log:  # a new record
            self.log, self.seen = lp.dual_log, 0
        measured = np.isfinite(lp.row_lo)
        shape = (lp.length, lp.full, int(np.count_nonzero(measured)))
        rows = [np.where(measured, lp.row_lo, 0.0), np.where(measured, lp.row_hi, 0.0)]
        window = np.concatenate([*rows, lp.col_lo, lp.col_hi])
        count = costs.shape[0]
        best, given = np.full(count, -np.inf), np.full((count, lp.nrow), np.nan)
        for r in range(count):
            key = (shape, r)
            if key not in self.found:
                continue
            stored, terms, duals = self.found[key]
            values = terms[:stored] @ window
            b = int(np.argmax(values))
            best[r] = values[b]
            gaps = self.gaps[key][-COVERAGE_PATIENCE:]
            covered = len(gaps) == COVERAGE_PATIENCE and float(np.mean(gaps)) <= self.tolerance
            if covered and self.skips.get(key, 0) < COVERAGE_PATIENCE - 1:
                given[r] = duals[b]
                self.skips[key] = self.skips.get(key, 0) + 1
            else:
                self.skips[key] = 0
        reused = int(np.count_nonzero(~np.isnan(given[:, 0])))
        self.reused, self.solved = self.reused + reused, self.solved + count - reused
        self.pending = (shape, window, measured, best, costs, lp.matrix_t)
        self.windows.setdefault(shape, []).append(window)
        self.model = (costs, lp.matrix_t)
        return given

    def select(self, base: FloatArray, size: int) -> FloatArray:
        """A bank (n, B, W, p) of the full windows: each component's ``base`` filter (W, p), then at most ``size - 1``
        stored certificates chosen greedily to cover the training windows.

        Every filter bounds both ends of its component (the box ``est ± radius``); its value on a window for the
        other end is that of its negated multipliers for the negated cost (reduced cost ``-d``). The greedy choice
        adds the filter that most raises the sum over the training windows of the best lower-end bound plus the
        best upper-end bound (minus the width), starting from ``base``; gains only fall as filters are added, so
        each step re-evaluates only the candidates whose earlier gain still leads (lazy greedy).
        """
        full = [shape for shape in self.windows if shape[1]]
        n, weights, p = base.shape[0], base.shape[1], base.shape[2]
        if not full:
            return base[:, None]
        windows = np.array(self.windows[max(full, key=lambda shape: shape[2])]).T  # scored on the most measured
        costs, matrix_t = self.model
        members = []
        for i in range(n):
            duals, signs = [], []
            for shape in full:
                for r, sign in ((2 * i, 1.0), (2 * i + 1, -1.0)):
                    if (shape, r) in self.found:
                        count, _, stored = self.found[(shape, r)]
                        duals.append(sign * stored[:count])  # as multipliers of the lower end's cost
                        signs.append(np.full(count, sign))
            base_y = np.zeros((1, matrix_t.shape[1]))
            base_y[0, : weights * p] = base[i].ravel()
            lower_y = np.concatenate([base_y, *duals])
            lower_y[:, weights * p :] = 0.0  # the rows a filter does not weigh (y_k of a predicted one)
            reduced = costs[2 * i] - lower_y @ matrix_t.T
            lower = _dual_terms(lower_y, reduced) @ windows  # (candidates, windows): bounds of the lower end
            upper = _dual_terms(-lower_y, -reduced) @ windows  # … and of the upper end (negated)
            chosen = [0]
            best_lo, best_hi = lower[0].copy(), upper[0].copy()
            bound = np.sum(np.maximum(lower - best_lo, 0) + np.maximum(upper - best_hi, 0), axis=1)
            bound[0] = -np.inf
            while len(chosen) < min(size, lower.shape[0]):
                c = int(np.argmax(bound))
                if bound[c] <= 0:
                    break
                gain = np.sum(np.maximum(lower[c] - best_lo, 0) + np.maximum(upper[c] - best_hi, 0))
                bound[c] = gain
                if gain < np.max(bound):  # another candidate may gain more: re-evaluate it first
                    continue
                chosen.append(c)
                bound[c] = -np.inf
                best_lo, best_hi = np.maximum(best_lo, lower[c]), np.maximum(best_hi, upper[c])
            filters = lower_y[chosen].reshape(len(chosen), -1, p)[:, :weights]
            filters[0] = base[i]
            members.append(filters)
        count = max(m.shape[0] for m in members)
        return np.stack([np.concatenate([m, np.repeat(m[:1], count - m.shape[0], 0)]) for m in members])

    def summary(self) -> dict[str, float]:
        """``solved`` and ``reused`` LPs, and the median over the full windows' bounds of their recent mean gap."""
        recent = [np.mean(gaps[-COVERAGE_PATIENCE:]) for key, gaps in self.gaps.items() if key[0][1]]
        gap = float(np.median(recent)) if recent else float("nan")
        return {"solved": self.solved, "reused": self.reused, "gap": gap}

    def settle(self) -> None:
        """Gaps and storage of the certificates solved on the pending window (logged since the last call)."""
        if self.pending is None or self.log is None:
            return
        shape, window, measured, best, costs, matrix_t = self.pending
        entries, self.seen, self.pending = self.log[self.seen :], len(self.log), None
        values = best.copy()
        new: dict[int, tuple[FloatArray, FloatArray]] = {}
        for i, sign, duals, *_ in entries:
            r = 2 * i + int(sign < 0)
            y = np.where(measured, duals, 0.0)
            reduced = costs[r] - matrix_t @ y
            new[r] = (_dual_terms(y, reduced), duals)
            values[r] = new[r][0] @ window
        width = -(values[0::2] + values[1::2])  # upper minus lower end of each component's box
        for r, (terms, duals) in new.items():
            key = (shape, r)
            gap = (values[r] - best[r]) / width[r // 2] if width[r // 2] > 0 else np.inf
            self.gaps.setdefault(key, []).append(float(max(gap, 0.0)))
            entry = self.found.setdefault(key, [0, np.empty((8, terms.size)), np.empty((8, duals.size))])
            if entry[0] == entry[1].shape[0]:  # capacity doubles
                entry[1], entry[2] = np.vstack([entry[1], entry[1]]), np.vstack([entry[2], entry[2]])
            entry[1][entry[0]], entry[2][entry[0]] = terms, duals
            entry[0] += 1


def _dual_terms(duals: FloatArray, reduced: FloatArray) -> FloatArray:
    """Rows ``(y+, y-, d+, d-)`` of multipliers ``y`` and reduced costs ``d``: their weak-duality value on a window is
    the product with ``(row_lo, row_hi, col_lo, col_hi)`` (free rows zeroed; rounding not counted)."""
    return np.concatenate(
        [np.maximum(duals, 0.0), np.minimum(duals, 0.0), np.maximum(reduced, 0.0), np.minimum(reduced, 0.0)], axis=-1
    )


def _noise_channels(
    system: LTISystem, full: ResolvedBounds, model: SampledModel
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The process noise as ``G η`` with ``η`` in a box: ``(G, centre, radius)``.

    Discrete time: ``G = E`` and the box of ``w`` (noise channels that drive several states keep their
    structure: a zonotope, tighter than the box of ``E w``); continuous time: ``G = I`` and the box of
    the sound sampled model.
    """
    if system.continuous:
        return np.eye(system.n), model.noise_center, model.noise_radius
    w_lo, w_hi = full.w
    return system.E, 0.5 * (w_lo + w_hi), 0.5 * (w_hi - w_lo)


_LP_ATTEMPTS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("highs", LP_OPTIONS),
    ("highs-ds", {"presolve": False, **LP_OPTIONS}),
    ("highs-ipm", {"presolve": False, **LP_OPTIONS}),
)
"""Solver settings tried in turn for a filter LP: HiGHS's default, then dual simplex and interior point
without presolve (HiGHS's presolve returns status "Not Set" on some large window LPs)."""

_LP_INFEASIBLE = 2
"""``scipy.optimize.linprog`` status of an infeasible problem."""


def _worst_case_gains(
    system: LTISystem, full: ResolvedBounds, window: int, h: float | None, extra: Any = 0.0
) -> tuple[FloatArray, float]:
    """Weights ``(n, N, p)`` minimising each component's evaluated worst-case error with ``R = 0``, and the LP time.

    The error's noise term is ``sum_l |D_l G| r`` (per noise channel, as the observer evaluates it), so a
    noise zonotope is weighed through its generators, not through the box of ``G η``.
    ``extra`` (n,) is charged like a further noise channel of radius ``extra`` on every state (a per-step
    error such as ``ΔA x``).
    """
    refuse_uncertain_input(system, "FiniteMemoryObserver")
    if system.dA is not None:
        raise AssumptionError("FiniteMemoryObserver: point models only (system.dA must be None)")
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)) or window < 1:
        raise DataError(f"window: expected a positive integer, got {window!r}")
    model = sampled_model(system, full, h)
    n, p, nv, big_n = system.n, system.p, system.F.shape[1], int(window)
    phi, c_mat, f_mat = model.Phi, system.C, system.F
    noise_map, _, r = _noise_channels(system, full, model)
    if np.any(extra):  # identity channels of radius extra
        noise_map, r = np.hstack([noise_map, np.eye(n)]), np.concatenate([r, np.broadcast_to(extra, (n,))])
    ng = noise_map.shape[1]
    vr = full.radius("v")
    powers = [np.eye(n)]
    for _ in range(big_n):
        powers.append(phi @ powers[-1])
    # H maps k (N p, block j = k_j) to the rows of D_l G (N nG, block l): -(sum_{j>l} (C Φ^{j-1-l} G)^T k_j).
    hmat = np.zeros((big_n * ng, big_n * p))
    for l_ in range(big_n):
        for j in range(l_ + 1, big_n):
            hmat[l_ * ng : (l_ + 1) * ng, j * p : (j + 1) * p] = (c_mat @ powers[j - 1 - l_] @ noise_map).T
    vmat = np.kron(np.eye(big_n), f_mat.T)  # (N nv, N p)
    gmat = np.hstack([(c_mat @ powers[j]).T for j in range(big_n)])  # (n, N p)
    nk, ne, nvv = big_n * p, big_n * ng, big_n * nv
    cost = np.concatenate([np.zeros(nk), np.tile(r, big_n), np.tile(vr, big_n)])
    eye_e, eye_v = np.eye(ne), np.eye(nvv)
    # t_e >= |(Φ^{N-1-l})_i G - H k|,  t_v >= |V k|
    a_ub = np.block(
        [
            [-hmat, -eye_e, np.zeros((ne, nvv))],
            [hmat, -eye_e, np.zeros((ne, nvv))],
            [vmat, np.zeros((nvv, ne)), -eye_v],
            [-vmat, np.zeros((nvv, ne)), -eye_v],
        ]
    )
    a_eq = np.hstack([gmat, np.zeros((n, ne + nvv))])
    var_bounds = [(None, None)] * nk + [(0, None)] * (ne + nvv)
    gains = np.zeros((n, big_n, p))
    start = time.perf_counter()
    for i in range(n):
        phi_row = np.concatenate([powers[big_n - 1 - l_][i] @ noise_map for l_ in range(big_n)])
        b_ub = np.concatenate([-phi_row, phi_row, np.zeros(2 * nvv)])
        outcomes = []
        for method, options in _LP_ATTEMPTS:
            res = linprog(
                cost,
                A_ub=a_ub,
                b_ub=b_ub,
                A_eq=a_eq,
                b_eq=powers[big_n][i],
                bounds=var_bounds,
                method=method,
                options=options,
            )
            if res.status in (0, _LP_INFEASIBLE):
                break
            outcomes.append(f"{method}: status {res.status} ({res.message})")
        if res.status == _LP_INFEASIBLE:
            raise DesignError(
                f"FiniteMemoryObserver: the filter LP of component {i} is infeasible ({res.message}): "
                f"Φ^N is not a combination of C, CΦ, …, CΦ^(N-1); observe more outputs or raise window={big_n}"
            )
        if res.status != 0:
            raise DesignError(
                f"FiniteMemoryObserver: the filter LP of component {i} was not solved by any method "
                f"({'; '.join(outcomes)}); scale the model or change window={big_n}"
            )
        gains[i] = res.x[:nk].reshape(big_n, p)
    elapsed = time.perf_counter() - start
    return gains, elapsed
