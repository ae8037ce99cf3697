r"""Guaranteed smoothing of a continuous-time nonlinear system by set inversion of its start and parameters.

Without a disturbance, the states of a record are fixed by the unknowns :math:`\theta = (x(t_0), p)`, so
the bounds of :math:`x(t_k)` given the *whole* record are the image of the set of :math:`\theta` that no
sample contradicts (Jaulin & Walter 1993; with validated integration, Raïssi, Ramdani & Candau 2004).
The prior box of :math:`\theta` is covered by *parts*, parallelotopes
:math:`\theta = c + G\xi + e`, :math:`\xi \in [-1, 1]^N`, :math:`e` in a small box. Each round:

1. **Prediction with persistent symbols.** Each part is carried over the record by the validated flow
   enclosure (:func:`~intervalobs.systems.flow_enclosure.propagate` with ``persistent=N``): its first
   :math:`N` generator columns are never reduced, so at every sample
   :math:`z(t_k) \in c_k + G_k\xi + [-r_k, r_k]` with the part's *own* :math:`\xi` (step 4 of that module
   maps the columns by the midpoint matrix and puts everything else in the other generators, whose hull is
   :math:`r_k`). No measurement enters the set, so the same :math:`\xi` holds at every sample. A part whose
   output hull misses a sample's strip is dropped there; a part whose validated step is lost is bisected.
2. **Rows.** The mean-value form of :math:`g` over the part's hull turns each sample into a row
   :math:`\underline s_k \le a_k^\top\xi \le \overline s_k` (the rest of the interval row and :math:`r_k` in
   the ends), so the part's consistent :math:`\xi` lie in a polytope :math:`\mathcal P`. Every bound over
   :math:`\mathcal P` is a linear programme certified by weak duality (:mod:`intervalobs.lp.certified`);
   a part is dropped only when an LP *proves* that no :math:`\xi` satisfies its rows.
3. **Refit.** :math:`\mathcal P` is enclosed in a new parallelotope: the bounds of :math:`W\xi` over it for
   the eigenvector basis :math:`W` of :math:`\sum_k a_k a_k^\top/s_k^2` (the directions the data pin, e.g.
   the thin slab of the kinetic parameters that one steady state leaves) or for the axes, whichever box is
   smaller. The round-off of :math:`W^{-1} \ne W^\top` is bounded and kept in :math:`e`.
   The parts shrink to the consistent set, so the first-order loss of the next prediction, which grows with
   the square of a part's size, shrinks with them.
4. **Bisection** along the generator that moves the states most, while the parts stay within ``max_parts``.

The rounds stop when the mean width of the parts' hull gains less than ``tolerance`` (and no part is lost),
or after ``max_rounds``. Row :math:`k` of the estimate is the union over the parts of the certified bounds
of :math:`x(t_k)` (or of ``report`` rows :math:`Mz(t_k)`) over :math:`\mathcal P`: a *smoothed* row, given
every sample of the record.

**References.**

* L. Jaulin, É. Walter, "Set inversion via interval analysis for nonlinear bounded-error estimation",
  *Automatica* 29(4):1053-1064, 1993. DOI: 10.1016/0005-1098(93)90106-4.
* T. Raïssi, N. Ramdani, Y. Candau, "Set membership state and parameter estimation for systems
  described by nonlinear differential equations", *Automatica* 40(10):1771-1777, 2004.
* A. Neumaier, O. Shcherbina, "Safe bounds in linear and mixed-integer linear programming",
  *Mathematical Programming* 99(2):283-296, 2004.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError
from ..estimate import Estimate
from ..inclusion import interval_function
from ..interval import Interval
from ..interval_dual import value_and_jacobian
from ..lp.certified import DenseLP
from ..systems.bounds import Bounds
from ..systems.continuous_nonlinear import ContinuousNonlinearSystem
from ..systems.field_tape import trace_field
from ..systems.flow_enclosure import REDUCTIONS, StateZonotope, interval_product, propagate
from .base import Observer, ObserverState, record_consistency
from .continuous_nonlinear import check_model, prior_parts, prior_splits

__all__ = ["SetInversionSmoother"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_EPS = float(np.finfo(float).eps)
_TINY = float(np.finfo(float).tiny)
_HALVINGS = 3
"""Halvings of a step tried before a part is declared lost (then it is bisected, not carried at tiny steps)."""


@dataclass
class _Parts:
    r"""Parallelotopes :math:`\theta = c + G\xi + e` of the unknowns, :math:`|\xi| \le 1`, :math:`|e| \le r`.

    Attributes
    ----------
    centre : numpy.ndarray, shape (P, N)
    generators : numpy.ndarray, shape (P, N, N)
        Persistent columns, one symbol each.
    radius : numpy.ndarray, shape (P, N)
        The box of :math:`e` (round-off of the refits), carried as ordinary generators.
    """

    centre: FloatArray
    generators: FloatArray
    radius: FloatArray

    def take(self, index: int | NDArray[np.int64] | BoolArray) -> _Parts:
        """The parts ``index``."""
        return _Parts(self.centre[index], self.generators[index], self.radius[index])

    def bisect(self, column: NDArray[np.int64]) -> _Parts:
        """Each part halved along its generator ``column[p]``: the two halves cover it (the rounding of their
        centres joins their boxes)."""
        rows = np.arange(self.centre.shape[0])
        half = 0.5 * self.generators[rows, :, column]  # halving is exact
        generators = self.generators.copy()
        generators[rows, :, column] = half
        centres = [Interval._wrap(self.centre) + Interval._wrap(side * half) for side in (-1.0, 1.0)]
        return _Parts(
            np.concatenate([centre.centre for centre in centres]),
            np.concatenate([generators, generators]),
            np.concatenate([np.nextafter(self.radius + _radius(centre), np.inf) for centre in centres]),
        )


@dataclass
class _Record:
    r"""The parts' states at the samples: :math:`z(t_k) \in c_k + G_k\xi \pm r_k` for :math:`k \le` ``last``.

    Attributes
    ----------
    active : list of numpy.ndarray of int
        Per sample, the parts reached (ascending).
    centre, generators, radius : list of numpy.ndarray
        Per sample, theirs: shapes (P_k, N), (P_k, N, N) (persistent columns) and (P_k, N) (the rest's hull).
    last : numpy.ndarray of int, shape (P,)
        Last sample each part reached (``T - 1``: the whole record).
    lost : numpy.ndarray of bool, shape (P,)
        The validated step was not found after ``last`` (else a part that stopped early was contradicted).
    """

    active: list[NDArray[np.int64]]
    centre: list[FloatArray]
    generators: list[FloatArray]
    radius: list[FloatArray]
    last: NDArray[np.int64]
    lost: BoolArray

    def series(self, part: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """One part's centres, persistent generators and rest radii at samples ``0 … last``.

        Returns
        -------
        numpy.ndarray, shapes (K, N), (K, N, N), (K, N)
        """
        where = [(k, int(np.searchsorted(self.active[k], part))) for k in range(int(self.last[part]) + 1)]
        return (
            np.stack([self.centre[k][i] for k, i in where]),
            np.stack([self.generators[k][i] for k, i in where]),
            np.stack([self.radius[k][i] for k, i in where]),
        )


class SetInversionSmoother(Observer):
    """Smoothed bounds of a disturbance-free :class:`ContinuousNonlinearSystem`: the consistent starts and parameters.

    For a record whose states are fixed by the initial state and the parameters (no ``w``), every row bounds
    ``x(t_k)`` given the whole record: the module's rounds shrink parallelotopes of ``(x0, p)`` to the set the
    samples leave, through a validated flow with persistent symbols and certified linear programmes. Far
    tighter than a filter where the data pin a combination of parameters slowly (a chemostat's steady
    substrate), at the cost of whole-record passes: offline, not online.

    Parameters
    ----------
    system : ContinuousNonlinearSystem
        The model (no disturbance: ``E`` without columns, or a ``w`` box of zero width).
    bounds : Bounds
        Boxes of ``x0``, ``v`` and the parameters ``p`` (finite).
    h : float
        Sampling period of the records.
    substeps : int
        Validated steps per sampling period. No measurement contracts a part between its rounds, so its
        first-order loss must contract by itself: more substeps than a filter needs (default 8).
    splits : int or sequence of int
        Parts of the prior box along each state (an int: along every state), or along each state and
        parameter, before the first round.
    max_parts : int
        Most parts carried (bisection stops there).
    max_rounds : int
        Most whole-record rounds.
    tolerance : float
        The rounds stop when the mean width of the parts' hull gains less than this fraction.
    report : array_like, shape (q, n) or (q, n + n_params), optional
        Rows of a matrix :math:`M`: the estimate bounds :math:`Mz(t_k)` (each row by its own linear programmes,
        so a combination of states is not the sum of their boxes; with the parameters' columns, parameters
        too). Default: the states.
    report_names : sequence of str, optional
        Names of the ``report`` rows (the estimate's columns).
    order : int, optional
        Non-persistent generators kept (default ``2 (n + n_params)``).
    compiled : bool
        Carry the parts in the compiled kernels (:mod:`intervalobs.systems.flow_kernel`, the field by its tape where
        it can be recorded: the same sets as the NumPy path up to the order of a few sums, about 7× faster); False
        keeps Numba unimported.
    reduction : {"box", "frame"}
        How the generators beyond the persistent ones and ``order`` are reduced after every step (as
        :class:`~intervalobs.observers.continuous_nonlinear.ContinuousNonlinearObserver`'s): in the axes (the
        default) or in the frame the flow carried, for a rotating flow such as a pendulum's, which then wraps far
        less (``benchmarks/nonlinear_tightness.json``; on the other cases the axes are tighter).

    Attributes
    ----------
    rows : str
        ``"smoothed"``.

    Raises
    ------
    BoundsError
        A box is infinite or an argument is out of range.
    AssumptionError
        The model has a disturbance (its states are then not fixed by ``x0`` and ``p``: use
        :class:`~intervalobs.observers.continuous_nonlinear.ContinuousNonlinearObserver`).

    Examples
    --------
    A decay whose rate is known to ±20 %, its state and its rate bounded by a noisy record (``report`` rows):

    >>> import numpy as np
    >>> from intervalobs import Bounds, ContinuousNonlinearSystem, SetInversionSmoother
    >>> decay = ContinuousNonlinearSystem(lambda x, u, p: (-p[0] * x[0],), lambda x, u: (x[0],), n=1, n_params=1)
    >>> bounds = Bounds(x0=(0.5, 1.5), v=(-0.05, 0.05), p=(0.8, 1.2))
    >>> smoother = SetInversionSmoother(decay, bounds, h=0.1, report=np.eye(2), report_names=["x", "rate"])
    >>> t = np.arange(0.0, 2.01, 0.1)
    >>> estimate = smoother.run(t, (1.1 * np.exp(-t) + 0.05 * np.cos(7 * t))[:, None])
    >>> bool(np.all((estimate.lower[:, 0] <= 1.1 * np.exp(-t)) & (1.1 * np.exp(-t) <= estimate.upper[:, 0])))
    True
    >>> bool(estimate.upper[0, 1] - estimate.lower[0, 1] < 0.4)  # the rate's box narrowed by the record
    True
    """

    rows = "smoothed"
    batched = False
    summary_fields = ("substeps", "max_parts", "max_rounds")

    def __init__(
        self,
        system: ContinuousNonlinearSystem,
        bounds: Bounds,
        h: float,
        *,
        substeps: int = 8,
        splits: int | tuple[int, ...] = 1,
        max_parts: int = 64,
        max_rounds: int = 12,
        tolerance: float = 0.02,
        report: ArrayLike | None = None,
        report_names: Sequence[str] | None = None,
        order: int | None = None,
        compiled: bool = True,
        reduction: str = "box",
    ) -> None:
        check_model(system, h)
        for name, value in (("substeps", substeps), ("max_parts", max_parts), ("max_rounds", max_rounds)):
            if not (isinstance(value, (int, np.integer)) and value >= 1):
                raise BoundsError(f"{name}: expected a positive integer, got {value!r}")
        if not (isinstance(tolerance, (int, float)) and 0 <= tolerance < 1):
            raise BoundsError(f"tolerance: expected a fraction in [0, 1), got {tolerance!r}")
        self.system, self.bounds = system, bounds.resolve(system)
        if system.nw and np.any(self.bounds.w[1] > self.bounds.w[0]):
            raise AssumptionError(
                "the model has a disturbance w(t): its states are not fixed by the initial state and the parameters, "
                "so there is no set of them to invert; use ContinuousNonlinearObserver (filtered rows)"
            )
        self.n, self.p, self.m, self.h = system.n, system.p, system.m, float(h)
        self._period = float(h)
        self.size = system.n + system.n_params
        self._low = np.concatenate([self.bounds.x0[0], self.bounds.p[0]])
        self._high = np.concatenate([self.bounds.x0[1], self.bounds.p[1]])
        if not (np.all(np.isfinite(self._low)) and np.all(np.isfinite(self._high))):
            raise BoundsError("bounds: the smoother needs finite boxes of x0 and of the parameters")
        self.splits = prior_splits(splits, system.n, self.size)
        self.substeps, self.max_parts, self.max_rounds = int(substeps), int(max_parts), int(max_rounds)
        self.tolerance = float(tolerance)
        self.order = 2 * self.size if order is None else int(order)
        if self.order < self.size:
            raise BoundsError(f"order: expected at least {self.size} generators, got {order!r}")
        self.report = _report_matrix(report, system.n, self.size)
        self._reporting = report is not None
        self._report_names = None if report_names is None else tuple(report_names)
        self._v = Interval._raw(*self.bounds.v)
        self._w = Interval._raw(*self.bounds.w)
        self._scale = np.maximum(self._high - self._low, np.finfo(float).tiny)
        self.compiled = bool(compiled)
        if reduction not in REDUCTIONS:
            raise BoundsError(f"reduction: expected one of {', '.join(map(repr, REDUCTIONS))}, got {reduction!r}")
        self.reduction = reduction
        self._tape = trace_field(system, self._low, self._high)[0] if self.compiled else None

    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """The prior box of the states (the smoother has no step: :meth:`run` takes the whole record).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional
            Prior box (default: the bounds' ``x0``).

        Returns
        -------
        ObserverState
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        return ObserverState(lo.copy(), hi.copy())

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Smoothed bounds over a whole record (each run of a leading axis on its own).

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times, spaced by ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Measurements.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs, held between samples.

        Returns
        -------
        Estimate
            Rows of ``report`` (default: the states). ``meta`` holds ``consistent`` and ``inconsistent_from``
            (a record no part of the prior fits: every row NaN, from the first sample), ``rounds`` (per round:
            parts, live parts, the mean hull width), ``parts`` (live at the end), ``lost_from`` (the first
            time a part's validated step was lost; rows from then are infinite, with a warning) and
            ``ms_per_sample`` (CPU).
        """
        times, ys, us = self._signals(t, y, u)
        clock = time.process_time()
        lead = ys.shape[:-2]
        count = int(np.prod(lead))
        runs = [
            self._one_run(times, yr, ur)
            for yr, ur in zip(ys.reshape(count, *ys.shape[-2:]), us.reshape(count, *us.shape[-2:]))
        ]
        lower = np.stack([r[0] for r in runs]).reshape(*lead, times.size, -1)
        upper = np.stack([r[1] for r in runs]).reshape(*lead, times.size, -1)
        flags = np.stack([r[2] for r in runs]).reshape(*lead, times.size)
        meta = {**self.meta(), "rows": self.rows, "inconsistent_from": None if flags.all() else float(times[0])}
        estimate = Estimate(times, lower, upper, meta=meta, state_names=self._channel_names("state") or ())
        record_consistency(estimate, flags)
        estimate.meta["rounds"] = [r[3]["rounds"] for r in runs] if lead else runs[0][3]["rounds"]
        estimate.meta["parts"] = [r[3]["parts"] for r in runs] if lead else runs[0][3]["parts"]
        lost = [r[3]["lost_from"] for r in runs if r[3]["lost_from"] is not None]
        estimate.meta["lost_from"] = min(lost) if lost else None
        estimate.meta["ms_per_sample"] = 1000.0 * (time.process_time() - clock) / (times.size * len(runs))
        if lost:
            warnings.warn(
                f"a part's validated flow enclosure was lost at t = {min(lost):.4g} even at {self.max_parts} parts: "
                "the rows from then are infinite; raise max_parts or substeps, or narrow the prior boxes",
                RuntimeWarning,
                stacklevel=2,
            )
        return estimate

    def meta(self) -> dict[str, Any]:
        """Design facts: method, sampling period, substeps, parts and rounds.

        Returns
        -------
        dict
        """
        return {
            "method": type(self).__name__,
            "h": self.h,
            "substeps": self.substeps,
            "max_parts": self.max_parts,
            "max_rounds": self.max_rounds,
        }

    def _one_run(
        self, t: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, BoolArray, dict[str, Any]]:
        """The rounds of the module on one record: bounds, consistency flags per row, and what happened."""
        parts = _grid(self._low, self._high, self.splits)
        history: list[dict[str, Any]] = []
        previous = np.inf
        for round_index in range(self.max_rounds):
            record = self._predict(parts, t, y, u)
            whole = record.last == t.size - 1
            width = _hull_width(record, whole, self.n)
            final = round_index == self.max_rounds - 1 or (
                not record.lost.any() and width > (1.0 - self.tolerance) * previous
            )
            kept, refits = [], []
            for part in np.flatnonzero(whole | record.lost).tolist():
                rows = self._rows(record, part, y, u)
                solver = _feasible(rows)
                if solver is None:
                    continue
                kept.append(part)
                if not final:
                    refits.append(_refit(parts.take(part), solver, rows))
            history.append({"parts": int(parts.centre.shape[0]), "live": len(kept), "mean_hull_width": width})
            if not kept:
                flags = np.zeros(t.size, dtype=bool)
                nothing = np.full((t.size, self.report.shape[0]), np.nan)
                return nothing, nothing, flags, {"rounds": history, "parts": 0, "lost_from": None}
            if final:
                lower, upper = self._bounds(record, np.asarray(kept), y, u)
                lost = record.lost[kept]
                lost_from = float(t[record.last[kept][lost].min() + 1]) if lost.any() else None
                facts = {"rounds": history, "parts": len(kept), "lost_from": lost_from}
                return lower, upper, np.ones(t.size, dtype=bool), facts
            parts = self._split(refits, record.lost[kept])
            previous = width
        raise AssertionError("unreachable: the last round returns")

    def _split(self, refits: list[_Parts], lost: BoolArray) -> _Parts:
        """The refit parts, bisected along their longest generator relative to the prior box: lost ones first, the
        others when all of them fit within ``max_parts``."""
        parts = _Parts(
            np.concatenate([r.centre for r in refits]),
            np.concatenate([r.generators for r in refits]),
            np.concatenate([r.radius for r in refits]),
        )
        column = np.argmax(np.linalg.norm(parts.generators / self._scale[:, None], axis=1), axis=1)
        count = parts.centre.shape[0]
        if 2 * count <= self.max_parts:
            chosen = np.ones(count, dtype=bool)
        else:  # the lost ones first, as many as fit
            chosen = lost & (np.cumsum(lost) <= self.max_parts - count)
        if not chosen.any():
            return parts
        halves = parts.take(chosen).bisect(column[chosen])
        rest = parts.take(~chosen)
        return _Parts(
            np.concatenate([rest.centre, halves.centre]),
            np.concatenate([rest.generators, halves.generators]),
            np.concatenate([rest.radius, halves.radius]),
        )

    def _predict(self, parts: _Parts, t: FloatArray, y: FloatArray, u: FloatArray) -> _Record:
        """Step 1 of the module: every part over the record, dropped at a contradicting sample, stopped when lost."""
        count, size = parts.centre.shape
        record = _Record([], [], [], [], np.full(count, -1, dtype=np.int64), np.zeros(count, dtype=bool))
        rest = np.zeros((count, size, self.order))
        rest[:, np.arange(size), np.arange(size)] = parts.radius
        zset = StateZonotope(parts.centre, np.concatenate([parts.generators, rest], axis=-1))
        active = np.arange(count)
        for k in range(t.size):
            if k > 0:
                zset, failed = self._advance(zset, u[k - 1])
                record.lost[active[failed]] = True
                zset = StateZonotope(zset.centre[~failed], zset.generators[~failed])
                active = active[~failed]
            agree = self._agree(zset, y[k], u[k])
            zset = StateZonotope(zset.centre[agree], zset.generators[agree])
            active = active[agree]
            record.active.append(active)
            record.centre.append(zset.centre)
            record.generators.append(zset.generators[..., :size])
            record.radius.append(_magnitude_sum(zset.generators[..., size:]))
            record.last[active] = k
            if active.size == 0:
                break
        return record

    def _advance(self, zset: StateZonotope, u: FloatArray) -> tuple[StateZonotope, BoolArray]:
        """One sampling period for all parts; where that fails, each part alone (the failing ones flagged)."""
        failed = np.zeros(zset.centre.shape[0], dtype=bool)
        size = zset.centre.shape[-1]

        def move(sets: StateZonotope) -> StateZonotope:
            held = np.broadcast_to(u, (*sets.centre.shape[:-1], self.m))
            order = size + self.order
            return propagate(
                self.system,
                held,
                self._w,
                sets,
                self._period,
                self.substeps,
                order,
                self.compiled,
                tape=self._tape,
                reduction=self.reduction,
                persistent=size,
                halvings=_HALVINGS,
            )[0]

        try:
            return move(zset), failed
        except AssumptionError:
            pass
        centre, generators = zset.centre.copy(), zset.generators.copy()
        for part in range(failed.size):
            try:
                moved = move(StateZonotope(zset.centre[part : part + 1], zset.generators[part : part + 1]))
            except AssumptionError:
                failed[part] = True
                continue
            centre[part], generators[part] = moved.centre[0], moved.generators[0]
        return StateZonotope(centre, generators), failed

    def _agree(self, zset: StateZonotope, y: FloatArray, u: FloatArray) -> BoolArray:
        """Whether each part's output hull meets the sample's strip (an interval test: cheap, sound)."""
        hull = zset.box()
        low, high = interval_function(self.system.output_map(u), hull.lower, hull.upper, self.p, "g")
        strip = Interval._wrap(y) - self._v
        return np.all((low <= strip.upper) & (high >= strip.lower), axis=-1)

    def _channel_names(self, kind: str) -> tuple[str, ...] | None:
        """The model's names; for ``report`` rows, ``report_names`` (None: generic names)."""
        if kind == "state" and self._reporting:
            return self._report_names
        return super()._channel_names(kind)

    def _rows(
        self, record: _Record, part: int, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        r"""Step 2 of the module for one part: rows :math:`a`, ends :math:`\underline s \le a\xi \le \overline s`."""
        last = int(record.last[part])
        centre, generators, radius = record.series(part)
        reach = _rest_box(radius)
        hull = Interval._wrap(centre) + reach + _unit_image(generators)
        output = self.system.output_map(u[: last + 1])
        ends = (np.stack([hull.lower, centre]), np.stack([hull.upper, centre]))
        values, slopes = value_and_jacobian(output, *ends, self.p)
        image = interval_product(slopes[0], Interval._wrap(generators))
        rows = image.centre
        remainder = _unit_image(_radius(image)) + interval_product(slopes[0], reach[..., None])[..., 0]
        strip = (Interval._wrap(y[: last + 1]) - self._v) - values[1] - remainder
        return rows.reshape(-1, rows.shape[-1]), strip.lower.reshape(-1), strip.upper.reshape(-1)

    def _bounds(
        self, record: _Record, kept: NDArray[np.int64], y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The union over the parts of the certified bounds of ``report`` rows at every sample (infinite after a
        part is lost)."""
        t_size, q = y.shape[0], self.report.shape[0]
        lower, upper = np.full((t_size, q), np.inf), np.full((t_size, q), -np.inf)
        matrix = Interval._wrap(self.report)
        for part in kept:
            solver = _feasible(self._rows(record, part, y, u))
            if solver is None:
                continue
            last = int(record.last[part])
            centres, generators, radius = record.series(part)
            objective = interval_product(matrix, Interval._wrap(generators))
            costs = objective.centre.reshape(-1, self.size)
            low = solver.minima(costs)[0].reshape(last + 1, q)
            high = -solver.minima(-costs)[0].reshape(last + 1, q)
            centre = Interval._wrap(centres[..., None])
            rest = _rest_box(radius)[..., None]
            level = interval_product(matrix, centre + rest)[..., 0] + _unit_image(_radius(objective))
            part_lo = (level + Interval._raw(low, low)).lower
            part_hi = (level + Interval._raw(high, high)).upper
            lower[: last + 1] = np.minimum(lower[: last + 1], part_lo)
            upper[: last + 1] = np.maximum(upper[: last + 1], part_hi)
            if record.lost[part]:
                lower[last + 1 :], upper[last + 1 :] = -np.inf, np.inf
        return lower, upper


def _grid(low: FloatArray, high: FloatArray, splits: tuple[int, ...]) -> _Parts:
    """The prior box split into ``splits`` boxes, each a part (centre, radii rounded up as generators)."""
    boxes = StateZonotope.from_box(*prior_parts(low, high, splits))
    return _Parts(boxes.centre, boxes.generators, np.zeros_like(boxes.centre))


def _report_matrix(report: ArrayLike | None, n: int, size: int) -> FloatArray:
    """``report`` as a (q, n + n_params) matrix (the states' identity by default; zero parameter columns added)."""
    if report is None:
        return np.eye(n, size)
    matrix = np.atleast_2d(np.asarray(report, dtype=float))
    if matrix.ndim != 2 or matrix.shape[1] not in (n, size) or not np.all(np.isfinite(matrix)):
        raise BoundsError(f"report: expected a finite matrix with {n} or {size} columns, got shape {matrix.shape}")
    return np.concatenate([matrix, np.zeros((matrix.shape[0], size - matrix.shape[1]))], axis=1)


def _magnitude_sum(generators: FloatArray) -> FloatArray:
    """Row sums of ``|G|`` rounded up: the radii of the hull of ``G η``, ``|η| ≤ 1``."""
    total = np.abs(generators).sum(axis=-1)
    return np.nextafter(total * (1.0 + 2 * generators.shape[-1] * _EPS), np.inf)


def _unit_image(generators: FloatArray) -> Interval:
    """The box of ``G ξ`` over ``|ξ| ≤ 1``, outward rounded."""
    reach = _magnitude_sum(generators)
    return Interval._raw(-reach, reach)


def _rest_box(radius: FloatArray) -> Interval:
    """The box ``[-r, r]``."""
    return Interval._raw(-radius, radius)


def _radius(interval: Interval) -> FloatArray:
    """Radii of an interval around its (floating-point) centre, rounded up."""
    centre = interval.centre
    return np.nextafter(np.maximum(interval.upper - centre, centre - interval.lower), np.inf)


def _hull_width(record: _Record, whole: BoolArray, n: int) -> float:
    """Mean over the samples and states of the width of the union of the whole parts' hulls (the rounds' gauge)."""
    if not whole.any():
        return float(np.inf)
    series = [record.series(part) for part in np.flatnonzero(whole).tolist()]
    spread = np.stack([_magnitude_sum(generators[:, :n]) + radius[:, :n] for _, generators, radius in series])
    centre = np.stack([centre[:, :n] for centre, _, _ in series])
    width = (centre + spread).max(axis=0) - (centre - spread).min(axis=0)
    return float(np.mean(width))


def _feasible(rows: tuple[FloatArray, FloatArray, FloatArray]) -> DenseLP | None:
    r"""The part's LP over its rows, or None when an LP proves that no :math:`\xi \in [-1, 1]^N` meets them.

    The proof: the least uniform widening :math:`s` of every row's ends that admits a :math:`\xi` has a
    certified lower bound above zero. Rows with a non-finite entry are left out (fewer rows: a larger set).
    """
    a, low, high = rows
    usable = np.all(np.isfinite(a), axis=1) & np.isfinite(low) & np.isfinite(high)
    a, low, high = a[usable], low[usable], high[usable]
    count, size = a.shape
    widen = np.concatenate([a, np.ones((count, 1))], axis=1), np.concatenate([a, -np.ones((count, 1))], axis=1)
    scale = float(
        np.max(np.abs(low), initial=0.0) + np.max(np.abs(high), initial=0.0) + np.abs(a).sum(1).max(initial=0.0)
    )
    probe = DenseLP()
    probe.load(
        np.concatenate(widen),
        np.concatenate([-np.ones(size), [0.0]]),
        np.concatenate([np.ones(size), [scale + 1.0]]),
        np.concatenate([low, np.full(count, -np.inf)]),
        np.concatenate([np.full(count, np.inf), high]),
    )
    least = probe.minima(np.eye(1, size + 1, size))[0][0]
    if least > 0.0:
        return None
    solver = DenseLP()
    solver.load(a, -np.ones(size), np.ones(size), low, high)
    return solver


def _extents(solver: DenseLP, basis: FloatArray) -> tuple[FloatArray, FloatArray]:
    r"""Certified bounds of :math:`W\xi` over the part's LP (each row of ``basis``), clipped to :math:`|\xi| \le 1`."""
    reach = _magnitude_sum(basis)
    low = np.maximum(solver.minima(basis)[0], -reach)
    high = np.minimum(-solver.minima(-basis)[0], reach)
    return low, high


def _refit(part: _Parts, solver: DenseLP, rows: tuple[FloatArray, FloatArray, FloatArray]) -> _Parts:
    r"""Step 3 of the module: a parallelotope containing the part's consistent :math:`\theta`.

    For an orthonormal :math:`V` (floating point) and :math:`\eta = V^\top\xi` bounded over the LP,
    :math:`\xi = V\eta + (I - VV^\top)\xi`, so :math:`\theta = c + GV\eta + G(I - VV^\top)\xi + e`; the
    products are enclosed in interval arithmetic and everything but :math:`\mathrm{mid}(GV)\eta` joins the box.
    Of the data's eigenvector basis and the axes, the one of smaller volume is kept.

    Returns
    -------
    _Parts
        One part.
    """
    a, low, high = rows
    usable = np.all(np.isfinite(a), axis=1) & np.isfinite(low) & np.isfinite(high) & (high > low)
    weighted = a[usable] / (0.5 * (high - low)[usable, None])
    size = part.centre.shape[-1]
    bases = [np.eye(size)]
    if weighted.shape[0]:
        bases.append(np.linalg.eigh(weighted.T @ weighted)[1])
    best: tuple[float, _Parts] | None = None
    for v in bases:
        low_eta, high_eta = _extents(solver, v.T)
        middle = Interval._raw(np.minimum(low_eta, high_eta), np.maximum(low_eta, high_eta))
        centre_eta, half = middle.centre, _radius(middle)
        turned = interval_product(Interval._wrap(part.generators), Interval._wrap(v))
        centre = Interval._wrap(part.centre) + interval_product(turned, Interval._wrap(centre_eta[:, None]))[:, 0]
        columns = turned * Interval._wrap(half)
        left = Interval._wrap(np.eye(size)) - interval_product(Interval._wrap(v), Interval._wrap(v.T))
        spill = np.maximum(-left.lower, left.upper)
        leak = _magnitude_sum(interval_product(Interval._wrap(np.abs(part.generators)), Interval._wrap(spill)).upper)
        radius = part.radius + _radius(centre) + _magnitude_sum(_radius(columns)) + leak
        radius = np.nextafter(radius * (1.0 + 8 * _EPS), np.inf)
        candidate = _Parts(centre.centre[None], columns.centre[None], radius[None])
        size_of = float(np.sum(np.log(np.maximum(half, _TINY))))
        if best is None or size_of < best[0]:
            best = (size_of, candidate)
    assert best is not None
    return best[1]
