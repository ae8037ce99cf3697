r"""Tightness report: how far each observer's box is from the tightest box any sound estimator can give.

The reference is the exact interval hull of the consistent set (:class:`~intervalobs.observers.hull.
HullEstimator`) for a model without :math:`\Delta A`, and otherwise the **lower bound** of
:func:`~intervalobs.observers.hull.hull_lower_bound` (inner hulls for fixed :math:`\Delta A` samples),
which no sound estimator can beat. For each observer the report gives the mean over the steps
:math:`k \ge` ``start`` of the summed widths :math:`\sum_i (\overline{x}_{k,i} - \underline{x}_{k,i})`
and its ratio to the reference's (≥ 1 for every sound observer: a ratio below 1 is a bug in one of the
two, and the report says so in ``reference_inside``).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .estimate import Estimate
from .observers.hull import HullEstimator, HullLowerBound, hull_lower_bound
from .systems.lti import Bounds, LTISystem

__all__ = ["add_tightness", "format_tightness", "tightness_reference", "tightness_report"]

FloatArray = NDArray[np.float64]

_INSIDE_TOL = 1e-9


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
        Window of the LPs (None: full history).
    samples : int
        Number of ``ΔA`` samples of the lower bound.
    seed : int
        Seed of the ``ΔA`` vertex draw.
    truth : tuple (ΔA, x), optional
        The simulation's true ``ΔA`` and states (see :func:`~intervalobs.observers.hull.hull_lower_bound`).

    Returns
    -------
    Estimate or HullLowerBound
    """
    if system.dA is None:
        return HullEstimator(system, bounds, horizon=horizon, h=h).run(t, y, u)
    return hull_lower_bound(system, bounds, t, y, u, h=h, samples=samples, horizon=horizon, seed=seed, truth=truth)


def tightness_report(
    t: ArrayLike,
    estimates: Mapping[str, Estimate],
    reference: Estimate | HullLowerBound,
    start: int = 0,
) -> dict[str, Any]:
    """Mean summed widths of each observer and of the reference, and their ratios.

    Parameters
    ----------
    t : array_like, shape (T,)
        Sample times.
    estimates : mapping of str to Estimate
        The observers' bounds (one run each).
    reference : Estimate or HullLowerBound
        From :func:`tightness_reference`.
    start : int
        First step of the average (skip the initial transient).

    Returns
    -------
    dict
        ``reference`` (kind, label, mean width), ``observers`` (mean width, ratio, whether the reference
        lies inside the observer's box at every step), ``best`` (smallest ratio), ``steps``.
    """
    times = np.asarray(t, dtype=float)
    is_bound = isinstance(reference, HullLowerBound)
    ref_lo, ref_hi = np.asarray(reference.lower), np.asarray(reference.upper)
    ref_width = np.sum(ref_hi - ref_lo, axis=-1)[start:]
    defined = np.isfinite(ref_width)
    ref_mean = float(np.mean(ref_width[defined])) if defined.any() else float("nan")
    observers: dict[str, Any] = {}
    for name, est in estimates.items():
        width = np.sum(est.upper - est.lower, axis=-1)[start:]
        mean = float(np.mean(width[defined])) if defined.any() else float("nan")
        finite = np.all(np.isfinite(ref_lo), axis=-1) & np.all(np.isfinite(ref_hi), axis=-1)
        scale = 1.0 + np.abs(ref_lo[finite]) + np.abs(ref_hi[finite])
        inside = bool(
            np.all(est.lower[finite] <= ref_lo[finite] + _INSIDE_TOL * scale)
            and np.all(est.upper[finite] >= ref_hi[finite] - _INSIDE_TOL * scale)
        )
        observers[name] = {
            "mean_width": mean,
            "ratio": mean / ref_mean if ref_mean > 0 else float("nan"),
            "reference_inside": inside,
        }
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
    lines.append(f"{'estimator':40s} {'mean width':>11s} {'ratio':>7s}  reference inside")
    lines.append(f"{kind:40s} {ref['mean_width']:11.4g} {1.0:7.3f}")
    for name, row in report["observers"].items():
        inside = "yes" if row["reference_inside"] else "NO (bug in one of the two)"
        lines.append(f"{name:40s} {row['mean_width']:11.4g} {row['ratio']:7.3f}  {inside}")
    oracle = report.get("oracle_hull")
    if oracle:
        lines.append(f"hull if ΔA were known: mean width {oracle['mean_width']:.4g}; ratios to it:")
        for name, ratio in oracle["ratios"].items():
            lines.append(f"  {name:38s} {ratio:7.3f}")
    return "\n".join(lines)


def add_tightness(
    summary: dict[str, Any],
    out_dir: Path,
    plots: bool,
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
) -> Estimate | HullLowerBound:
    """The hook a reproduction calls before writing its files: ``summary["tightness"]`` and a figure.

    Parameters
    ----------
    summary : dict
        The reproduction's summary (gains the key ``tightness``; ``runtime_s`` gains ``tightness``).
    out_dir : pathlib.Path
        Where ``tightness.png`` goes (when ``plots``).
    plots : bool
        Write the widths-over-time figure.
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

    Returns
    -------
    Estimate or HullLowerBound
        The reference (to store in the trajectories if wanted).
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
    reference = tightness_reference(system, bounds, t, y, u, h=h, horizon=horizon, samples=samples, truth=truth)
    report = tightness_report(t, estimates, reference, start=start)
    oracle = None
    if system.dA is not None and truth is not None:
        known = LTISystem(
            system.A + np.asarray(truth[0], dtype=float), system.C, B=system.B, E=system.E, F=system.F, dt=system.dt
        )
        oracle = HullEstimator(known, bounds, horizon=horizon, h=h).run(t, y, u)
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
    if plots:
        from .plotting import plot_widths, save_figure

        name = "hull" if report["reference"]["kind"] == "hull" else "lower bound (no sound estimator below)"
        widths: dict[str, Any] = {k: e.width() for k, e in estimates.items()}
        widths[name] = reference.upper - reference.lower
        if oracle is not None:
            widths["hull if ΔA were known"] = oracle.width()
        out_dir.mkdir(parents=True, exist_ok=True)
        save_figure(plot_widths(t, widths), out_dir / "tightness.png")
    return reference
