r"""Tightness report: how far each observer's box is from the tightest box any sound estimator can give.

The reference is the exact interval hull of the consistent set (:class:`~intervalobs.observers.hull.
HullEstimator`) for a model without :math:`\Delta A`, and otherwise the **lower bound** of
:func:`robust_hull_lower_bound` (consistent states of fixed
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
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._docstrings import shared_docs
from .errors import AssumptionError, BoundsError, DataError, DimensionError
from .estimate import Estimate
from .lp.certified import DenseLP, shrink_inward
from .lp.window import SparseWindow, window_state_maps
from .observers.hull import HullEstimator, inner_model
from .observers.interval_observer import IntervalObserver
from .observers.robust_fir import RobustFiniteMemoryObserver
from .observers.robust_hull import RobustHullEstimator
from .systems.bounds import Bounds, ResolvedBounds
from .systems.lti import LTISystem
from .systems.sampling import delta_linearisation
from .validation import as_signal, as_time

__all__ = [
    "HullLowerBound",
    "Tightness",
    "add_tightness",
    "format_tightness",
    "hull_lower_bound",
    "robust_hull_lower_bound",
    "tightness_reference",
    "tightness_report",
]

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


@shared_docs
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
    %(record)s
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
        :func:`hull_lower_bound`).
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
    t, y, u, truth, estimates = _first_steps(steps, t, y, u, truth, estimates)
    comparisons = _Comparisons()
    chosen = None
    if system.dA is not None:
        chosen = np.arange(start, t.size, max(int(stride), 1))
        comparisons = _run_comparisons(
            system, bounds, t, y, u, h, estimates, robust_horizon, mccormick_horizon, mccormick_steps, fir_window
        )
    clock_bound = time.perf_counter()
    reference = tightness_reference(
        system, bounds, t, y, u, h, horizon, samples, truth=truth, candidates=comparisons.candidates, steps=chosen
    )
    reference_s = time.perf_counter() - clock_bound
    report = tightness_report(t, estimates, reference, start=start, costs=comparisons.costs)
    report["reference"]["runtime_s"] = reference_s
    if comparisons.learn_s is not None:
        report["observers"]["RobustFiniteMemoryObserver"]["learn_s"] = comparisons.learn_s
    if MCCORMICK in report["observers"]:
        report["observers"][MCCORMICK]["horizon"] = mccormick_horizon
    oracle = None
    if truth is not None:
        for key, est in estimates.items():
            report["observers"][key]["enclosure"] = est.enclosure(truth[1][: est.t.size]).fraction
        if system.dA is not None:
            oracle = _oracle_hull(system, bounds, t, y, u, h, horizon, truth[0])
            report["oracle_hull"] = _oracle_report(t, estimates, oracle, start)
    report["runtime_s"] = time.perf_counter() - clock
    summary["tightness"] = report
    widths = _width_curves(t, estimates, reference, report["reference"]["kind"], oracle)
    return Tightness(t, reference, widths)


def _first_steps(
    steps: int | None,
    t: ArrayLike,
    y: ArrayLike,
    u: ArrayLike | None,
    truth: tuple[ArrayLike, ArrayLike] | None,
    estimates: Mapping[str, Estimate],
) -> tuple[FloatArray, FloatArray, FloatArray | None, tuple[ArrayLike, FloatArray] | None, dict[str, Estimate]]:
    """The record, the truth's states and the estimates cut to their first ``steps`` samples (all if None)."""
    cut = slice(None) if steps is None else slice(0, int(steps))
    t_cut = np.asarray(t, dtype=float)[cut]
    y_cut = np.asarray(y, dtype=float)[cut]
    u_cut = None if u is None else np.asarray(u, dtype=float)[cut]
    truth_cut = None if truth is None else (truth[0], np.asarray(truth[1], dtype=float)[cut])
    cut_estimates = {
        k: Estimate(e.t[cut], e.lower[..., cut, :], e.upper[..., cut, :], meta=e.meta) for k, e in estimates.items()
    }
    return t_cut, y_cut, u_cut, truth_cut, cut_estimates


def _width_curves(
    t: FloatArray,
    estimates: Mapping[str, Estimate],
    reference: Estimate | HullLowerBound,
    kind: str,
    oracle: Estimate | None,
) -> dict[str, FloatArray]:
    """The width of every estimate and reference per step: NaN (not drawn) after an estimate's last row."""
    name = "hull" if kind == "hull" else "lower bound (no sound estimator below)"
    widths: dict[str, FloatArray] = {}
    for key, est in estimates.items():
        widths[key] = np.full((t.size, est.lower.shape[-1]), np.nan)
        widths[key][: est.t.size] = est.width()
    widths[name] = reference.upper - reference.lower
    if oracle is not None:
        widths["hull if ΔA were known"] = oracle.width()
    return widths


@dataclass
class _Comparisons:
    """What the optional estimators of a model with ΔA add to :func:`add_tightness`'s report."""

    costs: dict[str, float] = field(default_factory=dict)
    """Milliseconds per sample of each estimator run here."""
    learn_s: float | None = None
    """Design time of the robust finite-memory bank."""
    candidates: FloatArray | None = None
    """The robust hull's extremal ΔA values (they seed the lower bound)."""


def _run_comparisons(
    system: LTISystem,
    bounds: Bounds,
    t: FloatArray,
    y: FloatArray,
    u: FloatArray | None,
    h: float | None,
    estimates: dict[str, Estimate],
    robust_horizon: int | None,
    mccormick_horizon: int | None,
    mccormick_steps: int | None,
    fir_window: int | None,
) -> _Comparisons:
    """Run the robust hull, its McCormick form and the robust finite-memory bank where asked (into ``estimates``)."""
    out = _Comparisons()
    if robust_horizon is not None:
        robust = RobustHullEstimator.design(system, bounds, horizon=robust_horizon, h=h)
        clock_run = time.perf_counter()
        estimates["RobustHullEstimator"] = robust.run(t, y, u)
        out.costs["RobustHullEstimator"] = 1e3 * (time.perf_counter() - clock_run) / max(t.size, 1)
        out.candidates = robust.extremal_deltas(t.size)
    if mccormick_horizon is not None:
        tight = RobustHullEstimator.design(
            system, bounds, horizon=mccormick_horizon, h=h, identify=False, mccormick=True
        )
        part = t.size if mccormick_steps is None else min(int(mccormick_steps), t.size)
        clock_run = time.perf_counter()
        estimates[MCCORMICK] = tight.run(t[:part], y[:part], None if u is None else u[:part])
        out.costs[MCCORMICK] = 1e3 * (time.perf_counter() - clock_run) / max(part, 1)
    if fir_window is not None:
        clock_learn = time.perf_counter()
        fallback = IntervalObserver.design(system, bounds, h=h)
        bank = RobustFiniteMemoryObserver.learn(system, bounds, window=fir_window, h=h, fallback=fallback)
        out.learn_s = time.perf_counter() - clock_learn
        clock_run = time.perf_counter()
        estimates["RobustFiniteMemoryObserver"] = bank.run(t, y, u)
        out.costs["RobustFiniteMemoryObserver"] = 1e3 * (time.perf_counter() - clock_run) / max(t.size, 1)
    return out


def _oracle_hull(
    system: LTISystem,
    bounds: Bounds,
    t: FloatArray,
    y: FloatArray,
    u: FloatArray | None,
    h: float | None,
    horizon: int | None,
    true_delta: ArrayLike,
) -> Estimate:
    """The hull of the model with ΔA known (the simulation's true ΔA): an inner reference, not a bound."""
    known = LTISystem(
        system.A + np.asarray(true_delta, dtype=float), system.C, B=system.B, E=system.E, F=system.F, dt=system.dt
    )
    return HullEstimator.design(known, bounds, horizon=horizon, h=h).run(t, y, u)


def _oracle_report(t: FloatArray, estimates: Mapping[str, Estimate], oracle: Estimate, start: int) -> dict[str, Any]:
    """The report's ``oracle_hull`` entry: the known-ΔA hull's mean width and every estimator's ratio to it."""
    inner = tightness_report(t, estimates, oracle, start=start)
    return {
        "label": "hull if ΔA were known (= the true ΔA), sound sampled model, predicted: the true hull for "
        "unknown ΔA lies between the lower bound and this only when the window is long enough; an "
        "estimator below it is not a bug",
        "mean_width": inner["reference"]["mean_width"],
        "ratios": {k: v["ratio"] for k, v in inner["observers"].items()},
    }


# -- lower bounds on the box of any sound estimator (the references of a model with ΔA) ----------------

_CANDIDATE_TOLERANCE = 1e-12
"""Relative tolerance of the check that user ΔA candidates lie in the ΔA box (candidates only seed a
search for a lower bound; a check on the argument, not a rounding pad)."""

_BACKTRACK = (1.0, 0.5, 0.25)
"""Fractions of a sequential-LP step of the lower bound's ΔA search tried in turn."""
_TRUST_REGION = 0.2
"""Largest move of each ΔA entry in one sequential-LP step of the lower bound's search, as a fraction
of the box width: the linearisation holds near the current ΔA only, and a step across the whole box
lands where the data exclude ΔA (two-tank, seed 0, ΔA at a vertex: the bound rises from 0.12 / 0.92 /
0.64 to 0.56 / 1.44 / 1.30 at steps 60 / 180 / 300 with six steps)."""


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


@shared_docs
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
    %(record)s
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
    deltas, anchors = _lower_bound_samples(system, times.size, samples, seed, truth)
    steps, n = times.size, system.n
    size = max(steps - 1 if horizon is None else int(horizon), 1)
    lowers = np.full((deltas.shape[0], steps, n), np.nan)
    uppers = np.full((deltas.shape[0], steps, n), np.nan)
    alive = np.ones(deltas.shape[0], dtype=bool)
    for s, delta in enumerate(deltas):
        window = SparseWindow(
            inner_model(system, full, h, delta, substeps), size, points=2 * n + (anchors[s] is not None)
        )
        alive[s] = _inner_hulls(window, ys, us, full.x0, filtered, anchors[s], lowers[s], uppers[s])
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


def _lower_bound_samples(
    system: LTISystem, steps: int, samples: int | ArrayLike, seed: int, truth: tuple[ArrayLike, ArrayLike] | None
) -> tuple[FloatArray, list[FloatArray | None]]:
    """The ``ΔA`` samples of :func:`hull_lower_bound` (the true one first when ``truth`` is given) and, for each,
    the true trajectory that anchors its window prior (None but for the true ``ΔA``)."""
    if np.ndim(samples) == 0:
        deltas = delta_samples(system, int(samples), seed)  # type: ignore[arg-type]
    else:
        deltas = np.asarray(samples, dtype=float).reshape(-1, system.n, system.n)
    anchors: list[FloatArray | None] = [None] * deltas.shape[0]
    if truth is None:
        return deltas, anchors
    true_delta = np.asarray(truth[0], dtype=float).reshape(1, system.n, system.n)
    x_true = np.asarray(truth[1], dtype=float)
    if x_true.shape != (steps, system.n):
        raise DimensionError(f"truth: expected states of shape {(steps, system.n)}, got {x_true.shape}")
    return np.concatenate([true_delta, deltas]), [x_true, *anchors]


def _inner_hulls(
    window: SparseWindow,
    ys: FloatArray,
    us: FloatArray,
    x0: tuple[FloatArray, FloatArray],
    filtered: bool,
    anchor: FloatArray | None,
    lowers: FloatArray,
    uppers: FloatArray,
) -> bool:
    """Fill ``lowers``, ``uppers`` (steps, n) with the inner hulls of one fixed-``ΔA`` model's consistent sets.

    The prior of a window that starts after ``x_0`` is the convex hull of the optimal states found at its first
    step (and of ``anchor`` there, a consistent trajectory). Returns whether the model stayed consistent with the
    data to the end (a step without a feasible point ends the sample, unless ``anchor`` stands in for it).
    """
    lp, n = window.lp, lowers.shape[1]
    size = lp.slots - 1
    points: list[FloatArray] = []
    for k in range(lowers.shape[0]):
        free_lo, free_hi = np.full(n, -lp.inf), np.full(n, lp.inf)
        col_lo, col_hi, row_lo, row_hi = window.bounds_at(k, ys, us, None, None, free_lo, free_hi, filtered, *x0)
        first = k - size
        if first > 0:
            lp.set_points(points[first] if anchor is None else np.vstack([points[first], anchor[first]]))
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
                return False
            points.append(np.repeat(anchor[k][None, :], 2 * n, axis=0))  # no hull at k: the truth only
            continue
        points.append(found)
        lowers[k], uppers[k] = found.min(axis=0), found.max(axis=0)
    return True


def _inner_points(
    model: Any,
    x0: tuple[FloatArray, FloatArray],
    k: int,
    ys: FloatArray,
    us: FloatArray,
    lp: DenseLP,
    sens: FloatArray | None = None,
    delta_box: tuple[FloatArray, FloatArray] | None = None,
    objective: int | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Optimal points of ``± x_k`` over the full-history consistent set of a fixed-``ΔA`` model.

    Objective ``r < n`` minimises ``(x_k)_r``, ``r ≥ n`` maximises ``(x_k)_{r-n}``; ``objective`` solves
    that one only (the other rows of the results stay NaN).
    With ``sens`` (k, n, n_δ) and ``delta_box`` the model is the linearisation in a step ``δ`` of ``ΔA``
    (a search direction only). Returns the values (2n, n) of ``x_k`` at the points and the trajectories
    (2n, k + 1, n); NaN where the solver gave no point or (without ``sens``) the point fails the check
    against the measurement bounds (tolerance ``1e-8 (1 + |y|)``, the solver's primal accuracy).
    """
    n = model.C.shape[1]
    G = np.eye(n) if model.G is None else model.G
    nd = 0 if sens is None else sens.shape[-1]
    state, drive = window_state_maps(model.Phi, model.Gamma, G, np.zeros((k, n, nd)) if sens is None else sens, us[:k])
    ncol = state.shape[-1]
    matrix = np.einsum("pn,jnc->jpc", model.C, state[:k]).reshape(k * model.C.shape[0], ncol)
    centre = (drive[:k] @ model.C.T).ravel()
    y = ys[:k].ravel()
    v_lo, v_hi = np.tile(model.v_lo, k), np.tile(model.v_hi, k)
    extra_lo = np.zeros(0) if delta_box is None else delta_box[0]
    extra_hi = np.zeros(0) if delta_box is None else delta_box[1]
    col_lo = np.concatenate([x0[0], np.tile(model.w_lo, k), extra_lo])
    col_hi = np.concatenate([x0[1], np.tile(model.w_hi, k), extra_hi])
    if k == 0:
        matrix, centre, y, v_lo, v_hi = np.zeros((1, ncol)), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1)
    lp.load(matrix, col_lo, col_hi, y - v_hi - centre, y - v_lo - centre)
    chosen = list(range(2 * n)) if objective is None else [objective]
    _, points = lp.minima(np.concatenate([state[k], -state[k]])[chosen])
    values = np.full((2 * n, n), np.nan)
    paths = np.full((2 * n, k + 1, n), np.nan)
    steps = np.full((2 * n, nd), np.nan)
    for r, z in zip(chosen, points, strict=True):
        if not np.all(np.isfinite(z)):
            continue
        z = np.clip(z, col_lo, col_hi)
        slack = 1e-8 * (1.0 + np.abs(y))
        residual = y - (matrix @ z + centre)
        if sens is None and not (np.all(residual >= v_lo - slack) and np.all(residual <= v_hi + slack)):
            continue
        values[r] = state[k] @ z + drive[k]
        paths[r] = state @ z + drive
        steps[r] = z[ncol - nd :]
    return values, paths, steps


@shared_docs
def robust_hull_lower_bound(
    system: LTISystem,
    bounds: Bounds,
    t: ArrayLike,
    y: ArrayLike,
    u: ArrayLike | None = None,
    h: float | None = None,
    candidates: ArrayLike | None = None,
    steps: ArrayLike | None = None,
    search: int = 6,
    substeps: int = 2,
) -> HullLowerBound:
    r"""Lower bound on the box of any sound estimator under interval ``ΔA``: consistent states, full history.

    For any fixed admissible :math:`\Delta A` the states consistent with it and with the data (over the
    whole record, from the box of :math:`x_0`) are consistent states of the true problem, so the hull of
    any such states lies inside every sound box. For each step ``k`` and each bound of :math:`x_k`, the
    LP over the fixed-:math:`\Delta A` consistent set (full history, condensed from :math:`x_0`; in
    continuous time the process noise is held over ``substeps`` parts of each sampling interval, an
    admissible signal) is solved for each candidate :math:`\Delta A`, and improved by ``search``
    steps of sequential linear programming on the bilinear problem: the dynamics linearised in
    :math:`\Delta A` around the optimal trajectory give a new :math:`\Delta A` (each entry moved by at
    most a fifth of its interval, clipped to the box),
    kept when its exact LP value is better. Every point used is re-checked against the measurement
    bounds (tolerance ``1e-8 (1 + |y|)``, the solver's primal accuracy) and the result is shrunk inward
    by a relative 1e-6, as in :func:`hull_lower_bound`.

    Parameters
    ----------
    system : LTISystem
        Model with an interval ``dA``.
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v``.
    %(record)s
    h : float, optional
        Sampling period of a continuous-time system.
    candidates : array_like, shape (S, n, n) or (T, S, n, n), optional
        Starting ``ΔA`` values (shared by all steps, or per step; NaN entries are skipped), e.g. the
        simulation's true ``ΔA`` and :meth:`RobustHullEstimator.extremal_deltas`. Default: the centre.
    steps : array_like of int, optional
        Steps at which the bound is computed (default all; NaN elsewhere).
    search : int
        Sequential-LP improvement steps per candidate and bound.
    substeps : int
        Continuous time: noise values per sampling interval of the inner model (more: a larger inner
        set, slower LPs).

    Returns
    -------
    HullLowerBound
        Not an :class:`~intervalobs.estimate.Estimate`: a width no sound estimator can beat.
    """
    if system.dA is None:
        raise AssumptionError("system.dA: expected an interval ΔA (without it the hull is exact: HullEstimator)")
    times = as_time("t", t)
    ys = as_signal("y", y, times.size, system.p)
    if ys.ndim != 2:
        raise DimensionError(f"y: expected one run of shape (T, p), got shape {ys.shape}")
    us = np.zeros((times.size, system.m)) if u is None else as_signal("u", u, times.size, system.m)
    full = bounds.resolve(system)
    n = system.n
    if np.any(np.count_nonzero(system.F, axis=0) > 1):
        raise AssumptionError("system.F: the lower bound needs measurement noise channels that each drive one output")
    cands, finite = _checked_candidates(system, times.size, candidates)
    lower = np.full((times.size, n), np.nan)
    upper = np.full((times.size, n), np.nan)
    lp = DenseLP()
    fixed = _FixedDelta(system, full, h, substeps, ys, us, lp)
    chosen = range(times.size) if steps is None else [int(k) for k in np.atleast_1d(steps)]
    found = np.full((2 * n, n, n), np.nan)  # the best ΔA of each bound at the previous step: a candidate
    for k in chosen:
        best = np.full(2 * n, -np.inf)
        start: list[tuple[FloatArray, FloatArray] | None] = [None] * (2 * n)
        previous = found[np.all(np.isfinite(found), axis=(1, 2))]
        for delta in np.concatenate([cands[k][finite[k]], previous]):
            delta = np.clip(delta, system.dA[0], system.dA[1])
            values, paths, _ = fixed.points(delta, k)
            for r in range(2 * n):
                if np.all(np.isfinite(values[r])) and fixed.gain[r] * values[r, r % n] > best[r]:
                    best[r], start[r] = fixed.gain[r] * values[r, r % n], (delta, paths[r])
        for r in range(2 * n):  # sequential LP from the best candidate of each bound
            if start[r] is not None and k > 0 and fixed.rows_a.size:
                found[r], best[r] = fixed.improve(k, r, start[r], best[r], search)  # type: ignore[arg-type]
        lo, hi = -best[:n], best[n:]
        if np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)):
            lower[k], upper[k] = lo, hi
    lower, upper = shrink_inward(lower, upper)
    used = cands.reshape(-1, n, n)
    alive = np.ones(used.shape[0], dtype=bool)
    meta = {"horizon": "full", "filtered": False, "search": int(search), "steps": [int(k) for k in chosen]}
    label = (
        "lower bound on the width of any sound estimator (consistent states of fixed ΔA, full history; not an estimate)"
    )
    return HullLowerBound(times, lower, upper, used, alive, label=label, meta=meta)


def _checked_candidates(
    system: LTISystem, steps: int, candidates: ArrayLike | None
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The ``ΔA`` candidates of :func:`robust_hull_lower_bound` per step, shape (steps, S, n, n), and which are
    finite; refuses a wrong shape and a finite candidate outside the box ``system.dA``."""
    assert system.dA is not None
    n = system.n
    centre = 0.5 * (system.dA[0] + system.dA[1])
    cands = centre[None, None] if candidates is None else np.asarray(candidates, dtype=float)
    if cands.ndim == 3:
        cands = np.broadcast_to(cands, (steps, *cands.shape))
    if cands.ndim != 4 or cands.shape[0] != steps or cands.shape[2:] != (n, n):
        raise DimensionError(f"candidates: expected shape (S, {n}, {n}) or ({steps}, S, {n}, {n}), got {cands.shape}")
    finite = np.all(np.isfinite(cands), axis=(2, 3))
    tol = _CANDIDATE_TOLERANCE * (1.0 + np.abs(system.dA[0]) + np.abs(system.dA[1]))
    outside = (cands < system.dA[0] - tol) | (cands > system.dA[1] + tol)
    if np.any(np.any(outside, axis=(2, 3)) & finite):
        raise BoundsError("candidates: expected ΔA values inside the box system.dA, got one outside")
    return cands, finite


class _FixedDelta:
    """The consistent states of a fixed ``ΔA`` over a full-history record, and the sequential-LP search for the
    ``ΔA`` that pushes one bound furthest out (:func:`robust_hull_lower_bound`)."""

    def __init__(
        self,
        system: LTISystem,
        full: ResolvedBounds,
        h: float | None,
        substeps: int,
        ys: FloatArray,
        us: FloatArray,
        lp: DenseLP,
    ) -> None:
        assert system.dA is not None
        self.system, self.full, self.h, self.substeps, self.ys, self.us, self.lp = system, full, h, substeps, ys, us, lp
        self.linear = delta_linearisation(system, full, h)
        self.rows_a = np.array([a for a, _ in self.linear.entries], dtype=int)
        self.cols_b = np.array([b for _, b in self.linear.entries], dtype=int)
        self.da_lo = system.dA[0][self.rows_a, self.cols_b]
        self.da_hi = system.dA[1][self.rows_a, self.cols_b]
        self.reach = _TRUST_REGION * (self.da_hi - self.da_lo)
        self.gain = np.concatenate([-np.ones(system.n), np.ones(system.n)])
        """Row ``r < n`` minimises ``x_r``, the others maximise ``x_{r-n}``: ``gain[r] x`` is to maximise."""

    def points(
        self, delta: FloatArray, k: int, objective: int | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:func:`_inner_points` of the model with ``ΔA = delta`` at step ``k``."""
        model = inner_model(self.system, self.full, self.h, delta, self.substeps)
        return _inner_points(model, self.full.x0, k, self.ys, self.us, self.lp, objective=objective)

    def improve(
        self, k: int, r: int, start: tuple[FloatArray, FloatArray], best: float, search: int
    ) -> tuple[FloatArray, float]:
        """Up to ``search`` sequential-LP steps from the ``ΔA`` and trajectory ``start`` that push bound ``r`` of
        ``x_k`` out (each step backtracked by :data:`_BACKTRACK` until it improves ``best``); returns the last
        ``ΔA`` and its value."""
        current, path = start
        for _ in range(search):
            sens = np.einsum("lab,jb->jal", self.linear.M, path[:k])
            here = current[self.rows_a, self.cols_b]
            model = inner_model(self.system, self.full, self.h, current, self.substeps)
            box = (np.maximum(self.da_lo - here, -self.reach), np.minimum(self.da_hi - here, self.reach))
            _, _, step = _inner_points(model, self.full.x0, k, self.ys, self.us, self.lp, sens, box, objective=r)
            if not np.all(np.isfinite(step[r])):
                break
            for fraction in _BACKTRACK:
                trial = current.copy()
                trial[self.rows_a, self.cols_b] = np.clip(here + fraction * step[r], self.da_lo, self.da_hi)
                t_values, t_paths, _ = self.points(trial, k, objective=r)
                if np.all(np.isfinite(t_values[r])) and self.gain[r] * t_values[r, r % self.system.n] > best:
                    break
            else:
                break
            current, path, best = trial, t_paths[r], self.gain[r] * t_values[r, r % self.system.n]
        return current, best
