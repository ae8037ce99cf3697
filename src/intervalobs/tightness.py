r"""Tightness report: how far each observer's box is from the tightest box any sound estimator can give.

The reference is the exact interval hull of the consistent set (:class:`~intervalobs.observers.hull.
HullEstimator`) for a model without :math:`\Delta A`, and otherwise the **lower bound** of
:func:`~intervalobs.observers.robust_hull.robust_hull_lower_bound` (consistent states of fixed
:math:`\Delta A` candidates over the full history, improved by sequential LP), which no sound
estimator can beat. For a model with :math:`\Delta A`, :func:`add_tightness` also runs the
data-dependent :class:`~intervalobs.observers.robust_hull.RobustHullEstimator` (window LP, split or
with McCormick envelopes) and its LP-free counterpart
:class:`~intervalobs.observers.robust_fir.RobustFiniteMemoryObserver` (learned filter bank) and reports
them next to the observers, with the cost per step of each estimator that was timed and, given the
truth, the enclosure of every estimator. For each observer the report gives the mean over the steps
:math:`k \ge` ``start`` of the summed widths :math:`\sum_i (\overline{x}_{k,i} - \underline{x}_{k,i})`
and its ratio to the reference's (≥ 1 for every sound observer: a ratio below 1 is a bug in one of the
two, and the report says so in ``reference_inside``).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .estimate import Estimate
from .observers.hull import HullEstimator, HullLowerBound, delta_samples
from .observers.interval_observer import IntervalObserver
from .observers.robust_fir import RobustFiniteMemoryObserver
from .observers.robust_hull import RobustHullEstimator, robust_hull_lower_bound
from .systems.bounds import Bounds
from .systems.lti import LTISystem

__all__ = ["Tightness", "add_tightness", "format_tightness", "tightness_reference", "tightness_report"]

FloatArray = NDArray[np.float64]

_INSIDE_TOL = 1e-9

MCCORMICK = "RobustHullEstimator McCormick"
"""Report key of ``RobustHullEstimator(mccormick=True)`` (:func:`add_tightness`'s ``mccormick_horizon``)."""


@dataclass(frozen=True)
class Tightness:
    """What :func:`add_tightness` computed besides the report: the data of the widths figure.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        The sample times used (the first ``steps`` of the record).
    reference : Estimate or HullLowerBound
        The hull (no ``ΔA``) or the lower bound (interval ``ΔA``).
    widths : dict of str to numpy.ndarray, shape (T, n)
        Widths of every estimator, of the reference and (with ``ΔA`` and the truth) of the hull if ``ΔA``
        were known: what :func:`~intervalobs.plotting.plot_widths` draws.
    """

    t: FloatArray
    reference: Estimate | HullLowerBound
    widths: dict[str, FloatArray]


def tightness_reference(
    system: LTISystem,
    bounds: Bounds,
    t: ArrayLike,
    y: ArrayLike,
    u: ArrayLike | None = None,
    h: float | None = None,
    horizon: int | None = 40,
    samples: int = 3,
    seed: int = 0,
    truth: tuple[ArrayLike, ArrayLike] | None = None,
    candidates: ArrayLike | None = None,
    steps: ArrayLike | None = None,
) -> Estimate | HullLowerBound:
    """The reference box sequence: the hull (no ``ΔA``) or the lower bound (interval ``ΔA``).

    Parameters
    ----------
    system : LTISystem
        The model.
    bounds : Bounds
        Its boxes.
    t : array_like, shape (T,)
        Sample times.
    y : array_like, shape (T, p)
        Measurements of one run.
    u : array_like, shape (T, m), optional
        Known inputs.
    h : float, optional
        Sampling period (continuous time).
    horizon : int or None
        Window of the hull LPs (None: full history); the lower bound always uses the full history.
    samples : int
        Number of ``ΔA`` candidates of the lower bound drawn at the centre and random vertices.
    seed : int
        Seed of the ``ΔA`` vertex draw.
    truth : tuple (ΔA, x), optional
        The simulation's true ``ΔA`` (a candidate of the lower bound) and states.
    candidates : array_like, shape (T, S, n, n), optional
        More ``ΔA`` candidates per step, e.g. :meth:`RobustHullEstimator.extremal_deltas`.
    steps : array_like of int, optional
        Steps at which the lower bound is computed (default all).

    Returns
    -------
    Estimate or HullLowerBound
    """
    if system.dA is None:
        return HullEstimator.design(system, bounds, horizon=horizon, h=h).run(t, y, u)
    size = np.asarray(t).size
    shared = [delta_samples(system, samples, seed)]
    if truth is not None:
        shared.insert(0, np.asarray(truth[0], dtype=float).reshape(1, system.n, system.n))
    pool = np.broadcast_to(np.concatenate(shared)[None], (size, sum(c.shape[0] for c in shared), system.n, system.n))
    if candidates is not None:
        pool = np.concatenate([pool, np.asarray(candidates, dtype=float)], axis=1)
    return robust_hull_lower_bound(system, bounds, t, y, u, h=h, candidates=pool, steps=steps)


def tightness_report(
    t: ArrayLike,
    estimates: Mapping[str, Estimate],
    reference: Estimate | HullLowerBound,
    start: int = 0,
    costs: Mapping[str, float] | None = None,
) -> dict[str, Any]:
    """Mean summed widths of each observer and of the reference, and their ratios.

    Parameters
    ----------
    t : array_like, shape (T,)
        Sample times.
    estimates : mapping of str to Estimate
        The observers' bounds (one run each). One that covers only the first rows of ``t`` is compared
        with the reference on those rows (its row then gives its ``steps``, ``steps_used`` and the
        reference's mean width there, ``reference_mean_width``).
    reference : Estimate or HullLowerBound
        From :func:`tightness_reference`.
    start : int
        First step of the average (skip the initial transient).
    costs : mapping of str to float, optional
        Run time per step (ms) of some of the estimators, reported next to their widths.

    Returns
    -------
    dict
        ``reference`` (kind, label, mean width), ``observers`` (mean width, ratio, whether the reference
        lies inside the observer's box at every step, ``ms_per_step`` when timed), ``best`` (smallest
        ratio), ``steps``. The means are over the steps ``≥ start`` where the reference is defined.
    """
    times = np.asarray(t, dtype=float)
    is_bound = isinstance(reference, HullLowerBound)
    ref_lo, ref_hi = np.asarray(reference.lower), np.asarray(reference.upper)
    ref_width = np.sum(ref_hi - ref_lo, axis=-1)[start:]
    defined = np.isfinite(ref_width)
    ref_mean = float(np.mean(ref_width[defined])) if defined.any() else float("nan")
    observers: dict[str, Any] = {}
    for name, est in estimates.items():
        rows = est.lower.shape[-2]  # an estimate of the first rows only is compared on those
        width = np.sum(est.upper - est.lower, axis=-1)[start:]
        used = defined[: width.shape[-1]]
        mean = float(np.mean(width[used])) if used.any() else float("nan")
        ref_here = float(np.mean(ref_width[: width.shape[-1]][used])) if used.any() else float("nan")
        finite = np.all(np.isfinite(ref_lo[:rows]), axis=-1) & np.all(np.isfinite(ref_hi[:rows]), axis=-1)
        scale = 1.0 + np.abs(ref_lo[:rows][finite]) + np.abs(ref_hi[:rows][finite])
        inside = bool(
            np.all(est.lower[finite] <= ref_lo[:rows][finite] + _INSIDE_TOL * scale)
            and np.all(est.upper[finite] >= ref_hi[:rows][finite] - _INSIDE_TOL * scale)
        )
        observers[name] = {
            "mean_width": mean,
            "ratio": mean / ref_here if ref_here > 0 else float("nan"),
            "reference_inside": inside,
        }
        if rows < times.size:
            observers[name]["steps"] = [int(start), rows - 1]
            observers[name]["steps_used"] = int(np.count_nonzero(used))
            observers[name]["reference_mean_width"] = ref_here
        if costs is not None and name in costs:
            observers[name]["ms_per_step"] = float(costs[name])
    best = min(observers, key=lambda k: observers[k]["ratio"]) if observers else None
    meta = reference.meta if isinstance(reference, (Estimate, HullLowerBound)) else {}
    return {
        "reference": {
            "kind": "lower_bound" if is_bound else "hull",
            "label": (
                reference.label
                if isinstance(reference, HullLowerBound)
                else "exact interval hull of the consistent set (predicted: uses y_0 … y_{k-1})"
            ),
            "mean_width": ref_mean,
            "horizon": meta.get("horizon"),
            "steps_used": int(np.count_nonzero(defined)),
        },
        "observers": observers,
        "best": best,
        "steps": [int(start), int(times.size - 1)],
        "width": "mean over steps of the sum over states of upper - lower",
    }


def format_tightness(report: Mapping[str, Any], title: str = "") -> str:
    """The report as a plain-text table (what ``intervalobs tightness NAME`` prints).

    Parameters
    ----------
    report : mapping
        From :func:`tightness_report` (or a ``summary.json``'s ``tightness`` object).
    title : str
        First line.

    Returns
    -------
    str
    """
    ref = report["reference"]
    lines = [title] if title else []
    kind = "hull" if ref["kind"] == "hull" else "LOWER BOUND"
    lines.append(f"reference: {ref['label']} (horizon {ref.get('horizon')})")
    lines.append(f"mean summed width over steps {report['steps'][0]}-{report['steps'][1]}")
    if ref.get("steps_used") is not None:
        lines.append(f"(the {ref['steps_used']} steps where the reference is computed)")
    lines.append(f"{'estimator':40s} {'mean width':>11s} {'ratio':>7s} {'ms/step':>8s}  reference inside")
    lines.append(f"{kind:40s} {ref['mean_width']:11.4g} {1.0:7.3f}")
    notes = []
    for name, row in report["observers"].items():
        inside = "yes" if row["reference_inside"] else "NO (bug in one of the two)"
        cost = f"{row['ms_per_step']:8.3g}" if "ms_per_step" in row else f"{'-':>8s}"
        label = name
        if "steps" in row:  # run on the first rows only
            label = f"{name} *"
            notes.append(
                f"* {name}: run on steps 0-{row['steps'][1]} only; mean over the {row['steps_used']} steps of "
                f"the reference among {row['steps'][0]}-{row['steps'][1]} (reference {row['reference_mean_width']:.4g})"
            )
        lines.append(f"{label:40s} {row['mean_width']:11.4g} {row['ratio']:7.3f} {cost}  {inside}")
    lines.extend(notes)
    oracle = report.get("oracle_hull")
    if oracle:
        lines.append(f"hull if ΔA were known: mean width {oracle['mean_width']:.4g}; ratios to it:")
        for name, ratio in oracle["ratios"].items():
            lines.append(f"  {name:38s} {ratio:7.3f}")
    return "\n".join(lines)


def add_tightness(
    summary: dict[str, Any],
    system: LTISystem,
    bounds: Bounds,
    t: ArrayLike,
    y: ArrayLike,
    u: ArrayLike | None,
    estimates: Mapping[str, Estimate],
    h: float | None = None,
    start: int = 0,
    horizon: int | None = 40,
    samples: int = 3,
    truth: tuple[ArrayLike, ArrayLike] | None = None,
    steps: int | None = None,
    robust_horizon: int | None = None,
    stride: int = 1,
    fir_window: int | None = None,
    mccormick_horizon: int | None = None,
    mccormick_steps: int | None = None,
) -> Tightness:
    """The hook a reproduction calls before writing its files: ``summary["tightness"]`` and the widths.

    It draws nothing: the caller plots :attr:`Tightness.widths` if it wants the figure.

    Parameters
    ----------
    summary : dict
        The reproduction's summary (gains the key ``tightness``; ``runtime_s`` gains ``tightness``).
    system : LTISystem
        The model.
    bounds : Bounds
        Its boxes.
    t : array_like, shape (T,)
        Sample times.
    y : array_like, shape (T, p)
        Measurements of one run.
    u : array_like, shape (T, m), or None
        Known inputs.
    estimates : mapping of str to Estimate
        The observers to compare.
    h : float, optional
        Sampling period (continuous time).
    start : int
        First step of the averages.
    horizon : int or None
        LP window.
    samples : int
        ``ΔA`` samples of the lower bound.
    truth : tuple (ΔA, x), optional
        The simulation's true ``ΔA`` and states (anchors the lower bound; see
        :func:`~intervalobs.observers.hull.hull_lower_bound`).
    steps : int, optional
        Use only the first ``steps`` samples (to keep a long record's LPs within the time budget).
    robust_horizon : int, optional
        With interval ``ΔA``: also run :class:`RobustHullEstimator` with this window (reported as
        ``"RobustHullEstimator"``, timed; its extremal ``ΔA`` values seed the lower bound).
    stride : int
        With interval ``ΔA``: the lower bound is computed every ``stride`` steps from ``start`` (its LPs
        span the whole history); the means are over those steps.
    fir_window : int, optional
        With interval ``ΔA``: also run :meth:`RobustFiniteMemoryObserver.learn
        <intervalobs.observers.robust_fir.RobustFiniteMemoryObserver.learn>` with this window, intersected
        with :meth:`IntervalObserver.design <intervalobs.observers.interval_observer.IntervalObserver.design>`
        of the model (reported as ``"RobustFiniteMemoryObserver"``, timed per step with its
        IntervalObserver; ``learn_s`` is its design time).
    mccormick_horizon : int, optional
        With interval ``ΔA``: also run ``RobustHullEstimator(mccormick=True)`` (the window LP with the
        products ``δ_l x_{j,b}`` bounded by McCormick envelopes, no identification, as
        benchmarks/robust_tightness.py) with this window, reported as ``"RobustHullEstimator McCormick"``
        (timed, with its ``horizon``).
    mccormick_steps : int, optional
        Run it on the first ``mccormick_steps`` samples only (a subsample, where its LPs would cost too
        much over the whole record): its mean width and ratio are then over the reference's steps among
        them (``steps`` and ``steps_used`` in its row).

    Returns
    -------
    Tightness
        The times used, the reference and the widths of every estimator and reference.
    """
    clock = time.perf_counter()
    cut = slice(None) if steps is None else slice(0, int(steps))
    t = np.asarray(t, dtype=float)[cut]
    y = np.asarray(y, dtype=float)[cut]
    u = None if u is None else np.asarray(u, dtype=float)[cut]
    if truth is not None:
        truth = (truth[0], np.asarray(truth[1], dtype=float)[cut])
    estimates = {
        k: Estimate(e.t[cut], e.lower[..., cut, :], e.upper[..., cut, :], meta=e.meta) for k, e in estimates.items()
    }
    costs: dict[str, float] = {}
    learn_s: float | None = None
    candidates = None
    chosen = None
    if system.dA is not None:
        chosen = np.arange(start, t.size, max(int(stride), 1))
        if robust_horizon is not None:
            robust = RobustHullEstimator.design(system, bounds, horizon=robust_horizon, h=h)
            clock_run = time.perf_counter()
            estimates["RobustHullEstimator"] = robust.run(t, y, u)
            costs["RobustHullEstimator"] = 1e3 * (time.perf_counter() - clock_run) / max(t.size, 1)
            candidates = robust.extremal_deltas(t.size)
        if mccormick_horizon is not None:
            tight = RobustHullEstimator.design(
                system, bounds, horizon=mccormick_horizon, h=h, identify=False, mccormick=True
            )
            part = t.size if mccormick_steps is None else min(int(mccormick_steps), t.size)
            clock_run = time.perf_counter()
            estimates[MCCORMICK] = tight.run(t[:part], y[:part], None if u is None else u[:part])
            costs[MCCORMICK] = 1e3 * (time.perf_counter() - clock_run) / max(part, 1)
        if fir_window is not None:
            clock_learn = time.perf_counter()
            fallback = IntervalObserver.design(system, bounds, h=h)
            bank = RobustFiniteMemoryObserver.learn(system, bounds, window=fir_window, h=h, fallback=fallback)
            learn_s = time.perf_counter() - clock_learn
            clock_run = time.perf_counter()
            estimates["RobustFiniteMemoryObserver"] = bank.run(t, y, u)
            costs["RobustFiniteMemoryObserver"] = 1e3 * (time.perf_counter() - clock_run) / max(t.size, 1)
    clock_bound = time.perf_counter()
    reference = tightness_reference(
        system, bounds, t, y, u, h=h, horizon=horizon, samples=samples, truth=truth, candidates=candidates, steps=chosen
    )
    reference_s = time.perf_counter() - clock_bound
    report = tightness_report(t, estimates, reference, start=start, costs=costs)
    report["reference"]["runtime_s"] = reference_s
    if learn_s is not None:
        report["observers"]["RobustFiniteMemoryObserver"]["learn_s"] = learn_s
    if MCCORMICK in report["observers"]:
        report["observers"][MCCORMICK]["horizon"] = mccormick_horizon
    if truth is not None:
        for key, est in estimates.items():
            report["observers"][key]["enclosure"] = est.enclosure(truth[1][: est.t.size]).fraction
    oracle = None
    if system.dA is not None and truth is not None:
        known = LTISystem(
            system.A + np.asarray(truth[0], dtype=float), system.C, B=system.B, E=system.E, F=system.F, dt=system.dt
        )
        oracle = HullEstimator.design(known, bounds, horizon=horizon, h=h).run(t, y, u)
        inner = tightness_report(t, estimates, oracle, start=start)
        report["oracle_hull"] = {
            "label": "hull if ΔA were known (= the true ΔA), sound sampled model, predicted: the true hull for "
            "unknown ΔA lies between the lower bound and this only when the window is long enough; an "
            "estimator below it is not a bug",
            "mean_width": inner["reference"]["mean_width"],
            "ratios": {k: v["ratio"] for k, v in inner["observers"].items()},
        }
    report["runtime_s"] = time.perf_counter() - clock
    summary["tightness"] = report
    name = "hull" if report["reference"]["kind"] == "hull" else "lower bound (no sound estimator below)"
    widths: dict[str, FloatArray] = {}
    for key, est in estimates.items():  # NaN (not drawn) after the rows of an estimate of the first rows only
        widths[key] = np.full((t.size, est.lower.shape[-1]), np.nan)
        widths[key][: est.t.size] = est.width()
    widths[name] = reference.upper - reference.lower
    if oracle is not None:
        widths["hull if ΔA were known"] = oracle.width()
    return Tightness(t, reference, widths)
