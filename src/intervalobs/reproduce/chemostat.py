r"""Reproduction ``chemostat``: guaranteed biomass bounds of a Monod chemostat from substrate samples.

.. math::

    \dot X = (\mu(S) - D)X,\qquad \dot S = D(S_{in} - S) - \mu(S)X/Y,\qquad
    \mu(S) = \mu_{max}S/(K_s + S),

with :math:`S` measured :math:`\pm 0.02` g/L every 0.1 h, :math:`\mu_{max}` and :math:`K_s` known to
:math:`\pm 5\,\%`, :math:`X_0 \in [1, 3]`, :math:`S_0 \in [0.3, 0.8]` (the case of issue 32).

Three runs of :class:`~intervalobs.observers.continuous_nonlinear.ContinuousNonlinearObserver`:

* **as written** (states :math:`X, S`, the prior split in 8 parts along :math:`X`): sound, but the
  first-order validated step loses the set within hours (``direct`` in the summary: when, and the
  warning). Its interval Jacobian cannot see that :math:`\mu X/Y` enters :math:`\dot X/Y` and
  :math:`\dot S` with opposite signs, so the error of each step is as wide as the kinetics are
  uncertain, and the biomass is seen only through that cancellation.
* **in reaction-invariant coordinates** (Bastin & Dochain 1990): :math:`Z = X/Y + S` obeys
  :math:`\dot Z = D(S_{in} - Z)` whatever the kinetics, so the model written in :math:`(Z, S)` —
  the same model, no approximation — has an exact linear row; the bounds of :math:`X = Y(Z - S)` are
  the recommended ones.
* the same as a **bundle** (``refine=BUNDLE_PARTS``, ``design.bundle`` in the summary): one zonotope
  keeps the whole box of :math:`\mu_{max}, K_s` (a sample's cut is too shallow to narrow it), so its
  :math:`S` is as wide as the steady substrate :math:`K_s D/(\mu_{max} - D)` over that box allows; the
  bundle drops the parts of the box the data contradict and bisects the rest.

With ``full``, the same invariant model through
:class:`~intervalobs.observers.set_inversion.SetInversionSmoother` (``design.smoother``): *smoothed* rows (each
given the whole record) from the starts and parameters no sample contradicts, with the biomass bounded as
:math:`X = Y(Z - S)` by its own linear programmes; the tightest here, offline.

And :class:`~intervalobs.observers.reaction_invariant.ReactionInvariantObserver`, the interval
asymptotic observer, which uses no kinetic model at all (the yield, the dilution and the inlet only):
its biomass width falls to :math:`2\,Y\,|v|` (the noise on :math:`S`, ``kinetics_free_biomass_noise_floor``)
at the dilution rate, the same as the validated run's over the 12 h record at a small fraction of the cost;
over 60 h (``benchmarks/chemostat_long.py``) the validated run, which knows the kinetics, ends tighter.

The reference is a lower bound of the consistent set: the inner hull of trajectories simulated
exactly (RK4, 10 steps per sample) from initial states and parameters of their boxes that stay within
the noise of every sample, pushed from the true ones towards the extreme biomass and substrate of the
record's second half by sequential linear programming (:func:`consistent_inner_hull`).

**References.**

* G. Bastin, D. Dochain, *On-line Estimation and Adaptive Control of Bioreactors*, Elsevier, 1990.
* J.-L. Gouzé, A. Rapaport, M. Z. Hadj-Sadok, "Interval observers for uncertain biological
  systems", *Ecological Modelling* 133(1-2):45-56, 2000.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from .._docstrings import shared_docs
from ..estimate import Estimate
from ..interval import Interval
from ..observers.continuous_nonlinear import ContinuousNonlinearObserver
from ..observers.reaction_invariant import ReactionInvariantObserver
from ..observers.set_inversion import SetInversionSmoother
from ..plotting import plot_estimate, plot_widths, save_figure
from ..systems.bounds import Bounds
from ..systems.continuous_nonlinear import ContinuousNonlinearSystem
from ..systems.reaction import ReactionSystem
from .contract import Example, base_summary, write_reproduction

FloatArray = NDArray[np.float64]

NAME = "chemostat"
DILUTION, INLET, YIELD = 0.2, 5.0, 0.5
"""Dilution rate (1/h), inlet substrate (g/L), yield (g biomass per g substrate)."""
TRUE_PARAMETERS = np.array([0.51, 0.29])
"""True μmax (1/h) and Ks (g/L), inside their ±5 % boxes around 0.5 and 0.3."""
PARAMETER_BOX = (np.array([0.475, 0.285]), np.array([0.525, 0.315]))
X0_BOX = (np.array([1.0, 0.3]), np.array([3.0, 0.8]))
NOISE = 0.02
STEP, T_FINAL = 0.1, 12.0
"""Sampling period and record length (hours); ``benchmarks/chemostat_long.py`` runs the 60 h record."""
DIRECT_HOURS = 2.0
"""Length of the run in the coordinates as written (it loses its set within it)."""
REFERENCE_ROUNDS, REFERENCE_TIMES = 8, 7
"""Linearisations per goal and times of the second half whose extreme X and S are sought (the consistent-set
lower bound)."""
STEP_FRACTIONS = (1.0, 0.8, 0.6, 0.45, 0.3, 0.2, 0.1, 0.05, 0.02, 0.01)
"""Fractions of the way to a linear programme's target tried by exact simulation (the farthest consistent is kept)."""
BUNDLE_PARTS = 256
"""Most parts of the bundle run (``ContinuousNonlinearObserver(refine=...)``)."""
DIFFERENCE = 1e-6
"""Forward-difference step of the sensitivities, per unit of each box width."""
SMOOTHER_OPTIONS: dict[str, Any] = {"splits": (23, 13, 4, 4), "max_parts": 128, "max_rounds": 10}
"""The smoother's prior grid (Z0, S0, μmax, Ks: parts small enough for an 8-substep validated step over the
record), most parts and rounds."""


def _growth(s: Any, p: Any) -> Any:
    return p[0] * s / (p[1] + s)


def direct_model() -> ContinuousNonlinearSystem:
    """The chemostat as written: states (X, S), parameters (μmax, Ks), S measured.

    Returns
    -------
    ContinuousNonlinearSystem
    """

    def f(x: Any, u: Any, p: Any) -> tuple[Any, Any]:
        growth = _growth(x[1], p)
        return (growth - DILUTION) * x[0], DILUTION * (INLET - x[1]) - growth * x[0] / YIELD

    return ContinuousNonlinearSystem(
        f, lambda x, u: (x[1],), n=2, n_params=2, domain=(0.0, np.inf), state_names=["X", "S"]
    )


def invariant_model() -> ContinuousNonlinearSystem:
    """The same chemostat in reaction-invariant coordinates: states (Z = X/Y + S, S).

    Returns
    -------
    ContinuousNonlinearSystem
    """

    def f(z: Any, u: Any, p: Any) -> tuple[Any, Any]:
        return DILUTION * (INLET - z[0]), DILUTION * (INLET - z[1]) - _growth(z[1], p) * (z[0] - z[1])

    return ContinuousNonlinearSystem(
        f, lambda x, u: (x[1],), n=2, n_params=2, domain=(0.0, np.inf), state_names=["Z", "S"]
    )


def _rates(x: FloatArray, p: FloatArray) -> FloatArray:
    growth = p[..., 0] * x[..., 1] / (p[..., 1] + x[..., 1])
    return np.stack(
        [(growth - DILUTION) * x[..., 0], DILUTION * (INLET - x[..., 1]) - growth * x[..., 0] / YIELD], axis=-1
    )


def simulate_exact(x0: FloatArray, p: FloatArray, t: FloatArray, substeps: int = 10) -> FloatArray:
    """Classical RK4 of the chemostat (points; leading axes of starts and parameters carried).

    Parameters
    ----------
    x0 : numpy.ndarray, shape (..., 2)
        Initial states.
    p : numpy.ndarray, shape (..., 2)
        Parameters.
    t : numpy.ndarray, shape (T,)
        Uniform sample times.
    substeps : int
        RK4 steps per sample.

    Returns
    -------
    numpy.ndarray, shape (..., T, 2)
    """
    x = np.array(x0, dtype=float)
    out = [x.copy()]
    dt = (t[1] - t[0]) / substeps
    for _ in range(t.size - 1):
        for _ in range(substeps):
            k1 = _rates(x, p)
            k2 = _rates(x + 0.5 * dt * k1, p)
            k3 = _rates(x + 0.5 * dt * k2, p)
            k4 = _rates(x + dt * k3, p)
            x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x.copy())
    return np.stack(out, axis=-2)


def consistent_inner_hull(
    t: FloatArray, y: FloatArray, truth: FloatArray, rounds: int = REFERENCE_ROUNDS
) -> FloatArray:
    """Lower bound of the consistent set: the hull of exact trajectories that stay within the noise of every sample.

    For each goal (the largest and the smallest X and S at ``REFERENCE_TIMES`` times of the record's
    second half) a point of the box of (X0, S0, μmax, Ks) is moved, from the true one (consistent by
    construction), by sequential linear programming: the samples' constraints
    :math:`|S_k(\\theta) - y_k| \\le` ``NOISE`` and the goal are linearised at the point (finite
    differences of the exact simulation), the linear programme gives a target, and the farthest of
    ``STEP_FRACTIONS`` of the way to it whose exact trajectory stays within the noise of every sample
    is the next point. Only exactly simulated trajectories checked against every sample are kept, so
    their hull lies inside the consistent set whatever the linearisation's error.

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        Sample times.
    y : numpy.ndarray, shape (T,)
        Measured substrate.
    truth : numpy.ndarray, shape (4,)
        True (X0, S0, μmax, Ks).
    rounds : int
        Linearisations per goal.

    Returns
    -------
    numpy.ndarray, shape (2, T, 2)
        Lower and upper ends of the inner hull of (X, S).
    """
    times = np.searchsorted(t, np.linspace(0.5 * t[-1], t[-1], REFERENCE_TIMES))
    goals = [(state, index, sign) for state in (0, 1) for index in times for sign in (1.0, -1.0)]
    points = np.repeat(truth[None, :], len(goals), axis=0)
    kept = [simulate_exact(truth[None, :2], truth[None, 2:], t)]
    for _ in range(rounds):
        targets = _linearised_extremes(t, y, points, goals)
        trials = points[:, None, :] + np.asarray(STEP_FRACTIONS)[:, None] * (targets - points)[:, None, :]
        paths = simulate_exact(trials[..., :2], trials[..., 2:], t)
        good = np.all(np.abs(paths[..., 1] - y) <= NOISE, axis=-1)
        kept.append(paths[good])
        farthest = np.argmax(good, axis=1)
        moved = good.any(axis=1)[:, None]
        points = np.where(moved, trials[np.arange(len(goals)), farthest], points)
    every = np.concatenate(kept)
    return np.stack([every.min(axis=0), every.max(axis=0)])


def _linearised_extremes(
    t: FloatArray, y: FloatArray, points: FloatArray, goals: list[tuple[int, int, float]]
) -> FloatArray:
    """For each goal, the maximiser of its linearisation at its point over the linearised consistent set and the box.

    Sensitivities are forward differences of the exact simulation, per unit of each box width.
    """
    low = np.concatenate([X0_BOX[0], PARAMETER_BOX[0]])
    high = np.concatenate([X0_BOX[1], PARAMETER_BOX[1]])
    scale = high - low
    probes = points[:, None, :] + np.concatenate([np.zeros((1, 4)), np.diag(scale * DIFFERENCE)])[None]
    paths = simulate_exact(probes[..., :2], probes[..., 2:], t)
    base, sensitivity = paths[:, 0], (paths[:, 1:] - paths[:, :1]) / DIFFERENCE
    targets = points.copy()
    for g, (state, index, sign) in enumerate(goals):
        rows = sensitivity[g, :, :, 1].T
        room = np.concatenate([y + NOISE - base[g, :, 1], base[g, :, 1] - y + NOISE])
        solution = linprog(
            -sign * sensitivity[g, :, index, state],
            A_ub=np.vstack([rows, -rows]),
            b_ub=np.maximum(room, 0.0),
            bounds=list(zip((low - points[g]) / scale, (high - points[g]) / scale)),
            method="highs",
        )
        if solution.status == 0:
            targets[g] = np.clip(points[g] + solution.x * scale, low, high)
    return targets


def _biomass_bounds(estimate: Estimate) -> tuple[FloatArray, FloatArray]:
    """(X, S) bounds from the invariant run: X = Y(Z - S) in outward-rounded interval arithmetic."""
    z = Interval._raw(estimate.lower[:, 0], estimate.upper[:, 0])
    s = Interval._raw(estimate.lower[:, 1], estimate.upper[:, 1])
    x = (z - s) * YIELD
    return np.stack([x.lower, s.lower], axis=-1), np.stack([x.upper, s.upper], axis=-1)


def _kinetics_free_run(t: FloatArray, y: FloatArray) -> tuple[Estimate, float]:
    """The interval asymptotic observer: the yields, the dilution and the inlet, no kinetic model."""
    system = ReactionSystem([[1.0], [-1.0 / YIELD]], [1], [0.0, INLET], DILUTION, state_names=["X", "S"])
    observer = ReactionInvariantObserver(system, Bounds(x0=X0_BOX, v=(-NOISE, NOISE)), STEP)
    clock = time.perf_counter()
    estimate = observer.run(t, y[:, None])
    return estimate, time.perf_counter() - clock


def _bundle_run(
    t: FloatArray, y: FloatArray, x: FloatArray, bounds: Bounds, parts: int, compiled: bool | None = None
) -> tuple[FloatArray, FloatArray, dict[str, Any]]:
    """The invariant model as a bundle of up to ``parts`` parts (0: one zonotope): (X, S) bounds and their widths.

    The widths are means over the record's second half; ``ms_per_sample`` is CPU time. ``compiled`` as for
    :class:`~intervalobs.ContinuousNonlinearObserver`.
    """
    observer = ContinuousNonlinearObserver(invariant_model(), bounds, STEP, refine=parts, compiled=compiled)
    clock = time.process_time()
    estimate = observer.run(t, y[:, None])
    elapsed = time.process_time() - clock
    lower, upper = _biomass_bounds(estimate)
    half = t >= 0.5 * t[-1]
    width = (upper - lower)[half].mean(axis=0)
    return (
        lower,
        upper,
        {
            "parts": parts,
            "biomass_mean_width_second_half": width[0],
            "substrate_mean_width_second_half": width[1],
            "invariant_mean_width_second_half": float(estimate.width()[half, 0].mean()),
            "ms_per_sample": 1000.0 * elapsed / t.size,
            "enclosure": float(np.mean((lower <= x) & (x <= upper))),
        },
    )


def _smoother_run(t: FloatArray, y: FloatArray, x: FloatArray, bounds: Bounds) -> tuple[FloatArray, dict[str, Any]]:
    """The invariant model through the set-inversion smoother, X = Y(Z - S) and S reported: bounds and facts.

    The widths are means over the record's second half; ``ms_per_sample`` is CPU time.
    """
    report = [[YIELD, -YIELD], [0.0, 1.0]]
    smoother = SetInversionSmoother(
        invariant_model(), bounds, STEP, report=report, report_names=["X", "S"], **SMOOTHER_OPTIONS
    )
    estimate = smoother.run(t, y[:, None])
    half = t >= 0.5 * t[-1]
    width = estimate.width()[half].mean(axis=0)
    facts = {
        "options": SMOOTHER_OPTIONS,
        "biomass_mean_width_second_half": width[0],
        "substrate_mean_width_second_half": width[1],
        "ms_per_sample": estimate.meta["ms_per_sample"],
        "rounds": estimate.meta["rounds"],
        "enclosure": float(np.mean((estimate.lower <= x) & (x <= estimate.upper))),
    }
    return np.stack([estimate.lower, estimate.upper]), facts


def _direct_run(t: FloatArray, y: FloatArray, bounds: Bounds) -> dict[str, Any]:
    """The model as written, over the first ``DIRECT_HOURS``: when its bounds are lost, and the warning."""
    short = t <= DIRECT_HOURS + 1e-9
    observer = ContinuousNonlinearObserver(direct_model(), bounds, STEP, splits=(8, 1))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        estimate = observer.run(t[short], y[short, None])
    lost = ~np.all(np.isfinite(estimate.upper), axis=1)
    return {
        "splits": [8, 1],
        "bounds_lost_at_h": float(t[short][lost][0]) if lost.any() else None,
        "diverging": estimate.meta["diverging"],
        "warning": str(caught[0].message) if caught else None,
        "biomass_width_at_1h": float(estimate.width()[round(1.0 / STEP), 0]),
    }


@shared_docs
def run(
    out_dir: Path, seed: int, plots: bool, full: bool = True, t_final: float = T_FINAL, sweep: tuple[int, ...] = ()
) -> dict[str, Any]:
    """Simulate the chemostat, bound it in both coordinates, write the contract files.

    %(reproduction_run)s
    full : bool
        Also compute the consistent-set reference (the inner hull) and the ``tightness`` ratios.
    t_final : float
        Length of the record (hours).
    sweep : tuple of int
        Bundle sizes (``refine``; 0: one zonotope) also run, their widths and cost in ``design.bundle_sweep``.

    %(reproduction_summary)s
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, t_final + 1e-9, STEP)
    start = np.array([2.8, 0.35])
    x = simulate_exact(start, TRUE_PARAMETERS, t, substeps=20)
    y = x[:, 1] + NOISE * rng.choice([-1.0, 1.0], size=t.size) * rng.uniform(0.5, 1.0, size=t.size)
    direct_bounds = Bounds(x0=X0_BOX, v=(-NOISE, NOISE), p=PARAMETER_BOX)
    invariant_box = (np.array([X0_BOX[0][0] / YIELD + X0_BOX[0][1], 0.3]), np.array([X0_BOX[1][0] / YIELD + 0.8, 0.8]))
    invariant_bounds = Bounds(x0=invariant_box, v=(-NOISE, NOISE), p=PARAMETER_BOX)
    observer = ContinuousNonlinearObserver(invariant_model(), invariant_bounds, STEP)
    clock = time.perf_counter()
    estimate = observer.run(t, y[:, None])
    run_time = time.perf_counter() - clock
    lower, upper = _biomass_bounds(estimate)
    summary = base_summary(
        example=NAME,
        seed_file="-",
        observer="ContinuousNonlinearObserver/invariant",
        t=t,
        x=x,
        x_lower=lower,
        x_upper=upper,
        transient_s=0.0,
    )
    half = t >= 0.5 * t_final
    width = (upper - lower)[half].mean(axis=0)
    free, free_time = _kinetics_free_run(t, y)
    free_width = free.width()[half].mean(axis=0)
    # the demo runs it in NumPy: on a fresh install the kernels' first compile (~13 CPU s) costs more than the run
    bundle_lower, bundle_upper, bundle = _bundle_run(
        t, y, x, invariant_bounds, BUNDLE_PARTS, compiled=None if full else False
    )
    bundle_width = (bundle_upper - bundle_lower)[half].mean(axis=0)
    summary["design"] = {
        "coordinates": "Z = X/Y + S, S",
        "substeps": observer.substeps,
        "zonotope_order": observer.order,
        "direct": _direct_run(t, y, direct_bounds),
        "biomass_mean_width_second_half": width[0],
        "kinetics_free_biomass_mean_width_second_half": free_width[0],
        "kinetics_free_biomass_noise_floor": 2.0 * NOISE * YIELD,
        "kinetics_free_ms_per_sample": 1000.0 * free_time / t.size,
        "bundle": bundle,
        "bundle_sweep": [_bundle_run(t, y, x, invariant_bounds, parts)[2] for parts in sweep],
    }
    trajectories = {"t": t, "x": x, "x_lower": lower, "x_upper": upper, "y": y}
    widths = {
        "invariant coordinates": upper - lower,
        f"bundle ({BUNDLE_PARTS} parts)": bundle_upper - bundle_lower,
        "no kinetics (asymptotic)": free.width(),
    }
    if full:  # the consistent-set reference: a comparison, behind --full like the other examples' tightness
        reference = consistent_inner_hull(t, y, np.concatenate([start, TRUE_PARAMETERS]))
        inner = (reference[1] - reference[0])[half].mean(axis=0)
        smoothed, summary["design"]["smoother"] = _smoother_run(t, y, x, invariant_bounds)
        smoother = summary["design"]["smoother"]
        summary["tightness"] = {
            "biomass_consistent_inner_width_second_half": inner[0],
            "biomass_ratio": width[0] / inner[0],
            "substrate_ratio": width[1] / inner[1],
            "reference": "inner hull of exact consistent trajectories (sequential linear programming from the truth)",
            "kinetics_free_biomass_ratio": free_width[0] / inner[0],
            "bundle_biomass_ratio": bundle_width[0] / inner[0],
            "bundle_substrate_ratio": bundle_width[1] / inner[1],
            "smoother_biomass_ratio": smoother["biomass_mean_width_second_half"] / inner[0],
            "smoother_substrate_ratio": smoother["substrate_mean_width_second_half"] / inner[1],
        }
        trajectories.update(reference_x_lower=reference[0], reference_x_upper=reference[1])
        widths["consistent set (inner)"] = reference[1] - reference[0]
        widths["smoother (whole record)"] = smoothed[1] - smoothed[0]
        trajectories.update(smoother_x_lower=smoothed[0], smoother_x_upper=smoothed[1])
    summary["paper"] = {"note": "the chemostat of issue 32: no paper numbers"}
    summary["runtime_s"] = {"design": 0.0, "run": run_time, "ms_per_sample": 1000.0 * run_time / t.size}
    trajectories.update(reaction_invariant_x_lower=free.lower, reaction_invariant_x_upper=free.upper)
    write_reproduction(out_dir, summary, trajectories)
    if plots:
        shown = Estimate(t, lower, upper, meta={"rows": "filtered"})
        save_figure(plot_estimate(shown, x, ["X (g/L)", "S (g/L)"], time_unit="h"), out_dir / "states.png")
        save_figure(plot_widths(t, widths), out_dir / "widths.png")
    return summary


EXAMPLE = Example(
    name=NAME,
    seed_file="-",
    description="Monod chemostat (issue 32): biomass bounds from substrate samples, validated flow, ±5 % kinetics",
    run=run,
)
