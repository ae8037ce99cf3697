"""One front door: :func:`observe` picks the tightest estimator that fits the model and a cost budget.

The estimators are listed once, in :data:`ESTIMATORS`, tightest first for each kind of model; the
table of the README and the guide is this table. :func:`observe` takes the first entry that fits the
model and runs within the budget (CPU milliseconds per sample, measured on the first samples of the
record), runs it on the whole record, gives filtered rows (the box of ``x(t_k)`` given
``y_0 … y_k``) and records the choice and why in ``Estimate.meta``. :func:`suggest` lists the entries
that fit a model without running anything.

The window of the hull estimators is chosen from the model's memory: the number of samples after
which the influence of the window's prior box has decayed below 1 % (``ρ(Φ)^H ≤ 0.01`` for the
spectral radius ``ρ`` of the sampled state matrix ``Φ``), between 10 and 60 samples.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from ._docstrings import shared_docs
from .errors import ArgumentError, AssumptionError, DesignError
from .estimate import Estimate
from .interval import matvec_bounds
from .observers.base import Observer
from .observers.continuous_nonlinear import ContinuousNonlinearObserver
from .observers.fir import FiniteMemoryObserver
from .observers.hull import HullEstimator
from .observers.intersection import output_contraction
from .observers.interval_observer import IntervalObserver
from .observers.lpv import LPVIntervalObserver
from .observers.null_space_gsisio import NullSpaceGSISIO
from .observers.reaction_invariant import ReactionInvariantObserver
from .observers.robust_fir import RobustFiniteMemoryObserver
from .observers.robust_hull import RobustHullEstimator
from .observers.set_inversion import SetInversionSmoother
from .observers.unknown_input import UnknownInputIntervalObserver
from .systems.bounds import Bounds
from .systems.continuous_nonlinear import ContinuousNonlinearSystem
from .systems.lpv import LPVSystem
from .systems.lti import LTISystem
from .systems.nonlinear import NonlinearSystem
from .systems.reaction import ReactionSystem
from .validation import as_signal, as_time, labelled_parts

__all__ = ["ESTIMATORS", "Problem", "Suitable", "filtered_rows", "memory_horizon", "observe", "suggest"]

FloatArray = NDArray[np.float64]

PILOT_SAMPLES = 20
"""Samples of the record on which an estimator's cost per sample is measured (after one warm-up run)."""
BUNDLE_PARTS = 64
"""Most parts of the bundle row of a continuous-time nonlinear model (``ContinuousNonlinearObserver(refine=...)``):
on the 60 h chemostat, 64 parts are 4.5x narrower than one zonotope at 2.9 CPU ms a sample, compiled
(``benchmarks/chemostat_long.json``), within the default budget; 256 parts take 13.5."""

MEMORY_FRACTION = 0.01
"""The prior's influence (``ρ(Φ)^H``) below which a window of ``H`` samples is long enough."""

HORIZON_RANGE = (10, 60)
"""Shortest and longest window :func:`memory_horizon` chooses."""


@dataclass(frozen=True)
@shared_docs
class Problem:
    """What :func:`observe` was given, checked: the model, its bounds and the record.

    Parameters
    ----------
    %(model_bounds)s
    t : numpy.ndarray, shape (T,)
        Sample times.
    h : float or None
        Sampling period of a continuous-time model (the spacing of ``t``), None in discrete time.
    unknown_input : numpy.ndarray or None
        Matrix through which unknown (unbounded) inputs enter an LTI model.
    options : dict
        Further design arguments of the chosen estimator.
    smoothed : bool
        Whether rows given the whole record (offline estimators) are wanted.
    """

    system: Any
    bounds: Bounds
    t: FloatArray
    h: float | None
    unknown_input: FloatArray | None
    options: dict[str, Any]
    smoothed: bool = False

    @property
    def kind(self) -> str:
        """``"lti"``, ``"lti-dA"`` (interval ΔA), ``"lti-unknown-input"``, ``"lpv"``, ``"nonlinear"``,
        ``"nonlinear-continuous"`` or ``"reaction"`` (unknown kinetics)."""
        if isinstance(self.system, LPVSystem):
            return "lpv"
        if isinstance(self.system, NonlinearSystem):
            return "nonlinear"
        if isinstance(self.system, ContinuousNonlinearSystem):
            return "nonlinear-continuous"
        if isinstance(self.system, ReactionSystem):
            return "reaction"
        if self.unknown_input is not None:
            return "lti-unknown-input"
        return "lti" if self.system.dA is None else "lti-dA"


@dataclass(frozen=True)
class Suitable:
    """One row of :data:`ESTIMATORS`: an estimator, the models it fits, its width and its cost.

    Parameters
    ----------
    name : str
        The estimator (a class of :mod:`intervalobs.observers`, or a planned one).
    kind : str
        The :attr:`Problem.kind` it fits.
    width : str
        Expected width, in words (against the exact hull of the consistent set where it is known).
    cost : str
        Expected cost per sample and at design time, in words.
    build : callable
        ``build(problem) -> Observer``: the design.
    uncertain_input : bool
        Whether it bounds an uncertain input matrix (``dB``) soundly; a row without it does not fit a model
        with one.
    smoothed : bool
        Whether its rows are given the whole record (offline); such a row fits only a problem that asks for them.
    """

    name: str
    kind: str
    width: str
    cost: str
    build: Callable[[Problem], Observer]
    uncertain_input: bool = False
    smoothed: bool = False

    def fits(self, problem: Problem) -> bool:
        """Whether this estimator applies to the problem's model.

        Parameters
        ----------
        problem : Problem

        Returns
        -------
        bool
        """
        if self.kind != problem.kind or (self.smoothed and not problem.smoothed):
            return False
        if isinstance(problem.system, LTISystem) and problem.system.uncertain_input and not self.uncertain_input:
            return False
        continuous = problem.h is not None
        return not (self.name == "UnknownInputIntervalObserver" and not continuous)


def memory_horizon(system: LTISystem, h: float | None = None) -> int:
    """A window long enough that the prior box's influence has decayed: ``ρ(Φ)^H ≤ MEMORY_FRACTION``.

    Parameters
    ----------
    system : LTISystem
        The model (its nominal ``A``).
    h : float, optional
        Sampling period of a continuous-time model.

    Returns
    -------
    int
        ``H`` in :data:`HORIZON_RANGE`; the longest for a model without decay (``ρ(Φ) ≥ 1``).
    """
    phi = system.A if system.dt is not None or h is None else expm(system.A * h)
    rho = float(np.max(np.abs(np.linalg.eigvals(phi))))
    shortest, longest = HORIZON_RANGE
    if rho >= 1.0 or rho == 0.0:
        return longest if rho >= 1.0 else shortest
    return int(np.clip(np.ceil(np.log(MEMORY_FRACTION) / np.log(rho)), shortest, longest))


def _hull(problem: Problem) -> Observer:
    horizon = memory_horizon(problem.system, problem.h)
    return HullEstimator.design(problem.system, problem.bounds, h=problem.h, horizon=horizon, filtered=True)


def _bank(problem: Problem) -> Observer:
    horizon = min(memory_horizon(problem.system, problem.h), 20)
    return FiniteMemoryObserver.learn(problem.system, problem.bounds, window=horizon, h=problem.h, filtered=True)


def _robust_hull(problem: Problem) -> Observer:
    horizon = min(memory_horizon(problem.system, problem.h), 40)
    return RobustHullEstimator.design(problem.system, problem.bounds, h=problem.h, horizon=horizon)


def _robust_bank(problem: Problem) -> Observer:
    horizon = min(memory_horizon(problem.system, problem.h), 20)
    return RobustFiniteMemoryObserver.learn(problem.system, problem.bounds, window=horizon, h=problem.h, filtered=True)


def _tube(problem: Problem) -> Observer:
    return IntervalObserver.design(problem.system, problem.bounds, h=problem.h)


def _unknown_input(problem: Problem) -> Observer:
    needed = {"noise_rate", "output_accel"} - set(problem.options)
    if needed:
        raise ArgumentError(
            f"options: an observer of unknown inputs needs bounds of {', '.join(sorted(needed))} "
            "(|dv/dt| of the measurement noise, |d²y/dt²| of the outputs), got none"
        )
    assert problem.unknown_input is not None and problem.h is not None
    return UnknownInputIntervalObserver.design(
        problem.system, problem.bounds, D=problem.unknown_input, h=problem.h, **problem.options
    )


def _lpv(problem: Problem) -> Observer:
    if problem.h is None or "theta_rate" not in problem.options:
        raise ArgumentError("options: an LPV observer needs theta_rate (a bound of |dθ/dt|), got none")
    return LPVIntervalObserver.design(problem.system, problem.bounds, h=problem.h, **problem.options)


def _null_space(problem: Problem) -> Observer:
    return NullSpaceGSISIO.design(problem.system, problem.bounds, **problem.options)


def _continuous_nonlinear(problem: Problem, bundle: bool = False) -> Observer:
    """One zonotope, or (``bundle``) up to :data:`BUNDLE_PARTS` parts (at least twice the user's ``splits``),
    compiled, so that the pilot times what the whole record runs (its untimed warm-up loads the kernels); the
    user's ``options`` override both."""
    if problem.h is None:
        raise ArgumentError("t: a continuous-time model needs at least two sample times (their spacing is h)")
    options = dict(problem.options)
    if bundle:
        splits = options.get("splits", 1)
        start = splits**problem.system.n if isinstance(splits, int) else int(np.prod(splits))
        options = {"refine": max(BUNDLE_PARTS, 2 * start), "compiled": True, **options}
    return ContinuousNonlinearObserver(problem.system, problem.bounds, problem.h, **options)


def _set_inversion(problem: Problem) -> Observer:
    if problem.h is None:
        raise ArgumentError("t: a continuous-time model needs at least two sample times (their spacing is h)")
    return SetInversionSmoother(problem.system, problem.bounds, problem.h, **problem.options)


def _reaction_invariant(problem: Problem) -> Observer:
    if problem.h is None:
        raise ArgumentError("t: a continuous-time model needs at least two sample times (their spacing is h)")
    return ReactionInvariantObserver(problem.system, problem.bounds, problem.h)


ESTIMATORS: tuple[Suitable, ...] = (
    Suitable("HullEstimator", "lti", "the exact hull of a window as long as the model's memory", "LPs", _hull, True),
    Suitable("FiniteMemoryObserver", "lti", "near the hull (a learned bank of filters)", "filters; learning", _bank),
    Suitable("IntervalObserver", "lti", "the error tube of one fixed gain (widest)", "a few products", _tube, True),
    Suitable("RobustHullEstimator", "lti-dA", "the hull of a window over the ΔA box", "LPs", _robust_hull, True),
    Suitable(
        "RobustFiniteMemoryObserver",
        "lti-dA",
        "near that hull (learned bank)",
        "filters; learning",
        _robust_bank,
        True,
    ),
    Suitable("IntervalObserver", "lti-dA", "the error tube of one fixed gain (widest)", "a few products", _tube, True),
    Suitable(
        "UnknownInputIntervalObserver",
        "lti-unknown-input",
        "decoupled from the unknown inputs, which it bounds too",
        "a few products",
        _unknown_input,
    ),
    Suitable("LPVIntervalObserver", "lpv", "a gain designed by LMIs over the scheduling box", "a few products", _lpv),
    Suitable(
        "NullSpaceGSISIO",
        "nonlinear",
        "decoupled from the unknown inputs, which it bounds too",
        "interval maps",
        _null_space,
    ),
    Suitable(
        "SetInversionSmoother",
        "nonlinear-continuous",
        "smoothed rows (smoothed=True; no disturbance): the starts and parameters the whole record allows, 1.38x "
        "the consistent set on the 60 h chemostat",
        "whole-record validated passes and LPs, offline",
        _set_inversion,
        smoothed=True,
    ),
    Suitable(
        f"ContinuousNonlinearObserver(refine={BUNDLE_PARTS})",
        "nonlinear-continuous",
        "the validated observer as a bundle of parts: those the data contradict dropped, the rest bisected (4.5x "
        "narrower on the 60 h chemostat)",
        "validated integration of every part, compiled",
        partial(_continuous_nonlinear, bundle=True),
    ),
    Suitable(
        "ContinuousNonlinearObserver",
        "nonlinear-continuous",
        "validated flow enclosure cut by every sample (first order: wide where reaction terms cancel)",
        "validated integration",
        _continuous_nonlinear,
    ),
    Suitable(
        "ReactionInvariantObserver",
        "reaction",
        "no kinetic model: floored by the measurement noise",
        "a few products",
        _reaction_invariant,
    ),
)
"""Every estimator :func:`observe` can choose, tightest first within each kind of model; for a model with an
uncertain input matrix (``dB``) only the rows marked ``uncertain_input`` fit."""


@shared_docs
def suggest(
    system: Any,
    bounds: Bounds,
    *,
    unknown_input: ArrayLike | None = None,
    h: float | None = None,
    smoothed: bool = False,
) -> list[dict[str, str]]:
    """The estimators that fit a model, tightest first, with their expected width and cost.

    Parameters
    ----------
    %(model_bounds)s
    unknown_input : array_like, shape (n, q), optional
        Matrix through which unknown inputs enter an LTI model.
    h : float, optional
        Sampling period of a continuous-time model.
    smoothed : bool
        Also list the estimators whose rows are given the whole record (offline), as :func:`observe` does.

    Returns
    -------
    list of dict
        ``{"estimator", "width", "cost"}`` per fitting row of :data:`ESTIMATORS`.
    """
    problem = replace(_problem(system, bounds, np.zeros(1), h, unknown_input, None), smoothed=bool(smoothed))
    return [{"estimator": s.name, "width": s.width, "cost": s.cost} for s in ESTIMATORS if s.fits(problem)]


def observe(
    system: Any,
    bounds: Bounds,
    t: ArrayLike,
    y: ArrayLike,
    u: ArrayLike | None = None,
    *,
    estimator: str = "auto",
    filtered: bool = True,
    budget: float = 5.0,
    theta: ArrayLike | None = None,
    unknown_input: ArrayLike | None = None,
    options: dict[str, Any] | None = None,
    smoothed: bool = False,
) -> Estimate:
    """Bounds of the state over a record, from the tightest estimator that fits the model and the budget.

    The rows of :data:`ESTIMATORS` that fit the model are tried tightest first: each is designed,
    its cost per sample measured on the first :data:`PILOT_SAMPLES` samples, and the first within
    ``budget`` runs on the whole record (the last that fits runs whatever its cost). A row whose design
    refuses the model (a :class:`DesignError` or :class:`AssumptionError`: e.g. a window too short to
    observe the state) is passed over with its reason.
    ``meta["estimator"]`` names it, ``meta["why"]`` says why, ``meta["considered"]`` lists the
    tighter ones passed over and ``meta["ms_per_sample"]`` the measured cost (process CPU time: the
    load of the machine does not change the choice).

    Parameters
    ----------
    system : LTISystem, LPVSystem or NonlinearSystem
        The model; continuous time when it has no ``dt`` (then ``t`` must be uniformly spaced).
    bounds : Bounds
        Boxes of the initial state and the noises.
    t : array_like, shape (T,)
        Sample times.
    y : array_like, shape (T, p) or (M, T, p)
        Measurements (a leading axis holds runs).
    u : array_like, shape (T, m) or (M, T, m), optional
        Known inputs.
    estimator : str
        ``"auto"``, or the name of a row of :data:`ESTIMATORS` to force it.
    filtered : bool
        Rows that use ``y_k`` (the box of ``x(t_k)`` given ``y_0 … y_k``); an estimator with predicted
        rows only gets them from :func:`filtered_rows`. False: the estimator's own rows.
    budget : float
        Milliseconds per sample (per run) an estimator may take.
    theta : array_like, shape (T, s), optional
        Scheduling signal of an LPV model.
    unknown_input : array_like, shape (n, q), optional
        Matrix through which unknown, unbounded inputs enter an LTI model.
    options : dict, optional
        Further design arguments of the estimator (``theta_rate`` for LPV; ``noise_rate`` and
        ``output_accel`` for unknown inputs).
    smoothed : bool
        Also consider estimators whose row ``k`` is given the whole record (offline: the set-inversion smoother
        of a continuous-time nonlinear model without disturbance), tightest first. Such an estimator is not held
        to ``budget``; ``meta["ms_per_sample"]`` is its whole run's cost.

    Returns
    -------
    Estimate

    Raises
    ------
    ArgumentError
        ``estimator`` is not a row that fits the model, or ``budget`` is not positive.
    """
    times = as_time("t", t)
    if not budget > 0:
        raise ArgumentError(f"budget: expected a positive number of milliseconds per sample, got {budget!r}")
    h = None if getattr(system, "dt", None) is not None or times.size < 2 else float(times[1] - times[0])
    problem = replace(_problem(system, bounds, times, h, unknown_input, options), smoothed=bool(smoothed))
    fitting = [s for s in ESTIMATORS if s.fits(problem)]
    if estimator != "auto":
        fitting = [s for s in fitting if s.name == estimator]
        if not fitting:
            names = [s.name for s in ESTIMATORS if s.fits(problem)]
            raise ArgumentError(f"estimator: expected 'auto' or one of {names} for this model, got {estimator!r}")
    extra = {} if theta is None else {"theta": theta}
    y, u = _unlabelled(system, times, y, u)
    row, observer, cost, considered = _choose(fitting, problem, times, y, u, extra, budget)
    estimate = observer.run(times, y, u, **extra)
    cost = float(estimate.meta["ms_per_sample"]) if row.smoothed else cost
    why = f"the tightest estimator for this model ({problem.kind}) within {budget:g} ms a sample: {row.width}"
    if row.smoothed:
        why = f"the tightest estimator for this model ({problem.kind}), offline (smoothed rows): {row.width}"
    elif cost > budget:
        why = f"the only or last estimator for this model ({problem.kind}), over the budget: {row.width}"
    if isinstance(system, LTISystem) and system.uncertain_input and row.name == "HullEstimator":
        why += "; the input matrix is uncertain (dB): one constant ΔB is kept for each window"
    elif isinstance(system, LTISystem) and system.uncertain_input:
        why += "; the input matrix is uncertain (dB): ΔB·u is bounded at every step as if ΔB could change between steps"
    meta = {"estimator": row.name, "why": why, "considered": considered, "ms_per_sample": cost, "budget_ms": budget}
    estimate.meta.update(meta)
    if filtered and estimate.meta.get("rows") == "predicted" and isinstance(system, LTISystem):
        return filtered_rows(estimate, system, bounds, y)
    return estimate


def _unlabelled(system: Any, times: FloatArray, y: ArrayLike, u: ArrayLike | None) -> tuple[Any, Any]:
    """``y`` and ``u`` with a labelled record (pandas, xarray) read into arrays by the model's channel names,
    once, as every estimator would read it (the pilot runs take the first samples of plain arrays)."""

    def read(kind: str, name: str, signal: Any, width: int | None) -> Any:
        if signal is None or width is None or labelled_parts(signal) is None:
            return signal  # a model without channel counts: its estimator reads the labels itself
        names = getattr(system, f"{kind}_names", None)
        return as_signal(name, signal, times.size, width, t=times, names=names, missing=True)

    return read("output", "y", y, getattr(system, "p", None)), read("input", "u", u, getattr(system, "m", None))


def _choose(
    fitting: list[Suitable],
    problem: Problem,
    times: FloatArray,
    y: ArrayLike,
    u: ArrayLike | None,
    extra: dict[str, ArrayLike],
    budget: float,
) -> tuple[Suitable, Observer, float, list[str]]:
    """The first row within ``budget`` (else the last one that could be designed), its observer, cost and
    the rows passed over with their reasons."""
    considered: list[str] = []
    found: tuple[Suitable, Observer, float] | None = None
    for row in fitting:
        try:
            observer = row.build(problem)
            if row.smoothed:  # offline: held to no budget, its cost is its whole run's
                return row, observer, 0.0, considered
            cost = _cost_per_sample(observer, times, y, u, extra)
        except (AssumptionError, DesignError) as error:  # this model is outside the estimator's conditions
            if found is None and row is fitting[-1]:
                raise
            considered.append(f"{row.name}: cannot be designed for this model ({error})")
            continue
        if found is not None:
            considered.append(f"{found[0].name}: {found[2]:.3g} ms a sample, over the budget")
        found = (row, observer, cost)
        if cost <= budget:
            break
    assert found is not None
    return (*found, considered)


def _problem(
    system: Any,
    bounds: Bounds,
    t: FloatArray,
    h: float | None,
    unknown_input: ArrayLike | None,
    options: dict[str, Any] | None,
) -> Problem:
    """The checked :class:`Problem` (the model's type and the unknown-input matrix)."""
    models = (LTISystem, LPVSystem, NonlinearSystem, ContinuousNonlinearSystem, ReactionSystem)
    if not isinstance(system, models):
        raise ArgumentError(
            "system: expected an LTISystem, LPVSystem, NonlinearSystem, ContinuousNonlinearSystem or ReactionSystem, "
            f"got {type(system).__name__}"
        )
    if unknown_input is not None and not isinstance(system, LTISystem):
        raise ArgumentError("unknown_input: expected None for this model (its unknown inputs are part of it)")
    matrix = None if unknown_input is None else np.atleast_2d(np.asarray(unknown_input, dtype=float))
    if isinstance(system, LTISystem) and system.dt is None and h is None and t.size > 1:
        h = float(t[1] - t[0])
    return Problem(system, bounds, t, h, matrix, dict(options or {}))


def _cost_per_sample(
    observer: Observer, t: FloatArray, y: ArrayLike, u: ArrayLike | None, extra: dict[str, ArrayLike]
) -> float:
    """CPU milliseconds per sample and run of ``observer.run`` on the first samples (after a warm-up on two).

    CPU time, not wall time: on a machine shared with other work the wall time of the pilot grows with the load,
    and the choice would depend on what else runs; the CPU time the estimator needs does not. The calling
    thread's CPU time, not the process's: the estimators built here compute in this thread (one BLAS thread,
    one LP solver), while BLAS worker threads left spinning by the design's multithreaded algebra would be
    charged to whichever estimator the pilot happens to time.
    """
    ys = np.asarray(y, dtype=float)
    runs = int(np.prod(ys.shape[:-2])) if ys.ndim > 2 else 1

    def head(signal: ArrayLike | None, count: int) -> Any:
        return None if signal is None else np.asarray(signal, dtype=float)[..., :count, :]

    count = min(PILOT_SAMPLES, t.size)
    observer.run(t[:2], head(ys, 2), head(u, 2), **{k: head(v, 2) for k, v in extra.items()})
    start = time.thread_time()
    observer.run(t[:count], head(ys, count), head(u, count), **{k: head(v, count) for k, v in extra.items()})
    return 1e3 * (time.thread_time() - start) / (count * runs)


def filtered_rows(estimate: Estimate, system: LTISystem, bounds: Bounds, y: ArrayLike) -> Estimate:
    r"""Filtered rows from predicted ones: each box contracted with the output set of its own sample.

    Row ``k`` of a predicted estimate bounds ``x(t_k)`` given ``y_0 … y_{k-1}``; intersecting it with
    :math:`\{x : Cx \in y_k - F[v]\}` (:func:`~intervalobs.observers.intersection.output_contraction`,
    exact for one output row, no LP) bounds ``x(t_k)`` given ``y_0 … y_k``. An empty intersection
    means ``y_k`` contradicts the model (``inconsistent_from``).

    Parameters
    ----------
    estimate : Estimate
        Predicted rows (``meta["rows"] == "predicted"``).
    system : LTISystem
        The model (``C``, ``F``).
    bounds : Bounds
        Its bounds (the measurement-noise box).
    y : array_like, shape (T, p) or (M, T, p)
        The measurements the estimate was computed from.

    Returns
    -------
    Estimate
        With ``meta["rows"] = "filtered"`` and ``meta["filtered_by"] = "output contraction"``.
    """
    resolved = bounds.resolve(system)
    fv_lo, fv_hi = matvec_bounds(system.F, *resolved.v)
    ys = np.asarray(y, dtype=float)
    lower, upper = output_contraction(
        estimate.lower, estimate.upper, system.C, ys - fv_hi, ys - fv_lo, allow_empty=True
    )
    meta = {k: v for k, v in estimate.meta.items() if k != "inconsistent_from"}
    meta.update(rows="filtered", filtered_by="output contraction")
    contracted = Estimate.from_boxes(estimate.t, lower, upper, estimate.input_lower, estimate.input_upper, meta)
    return replace(contracted, state_names=estimate.state_names, input_names=estimate.input_names)
