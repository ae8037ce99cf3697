"""Reproduction ``numerical-3state``: the integrated-observer paper, Section 6.1, systems (68) and (70), Figs. 2–5.

Observers compared (all sound; the recommended bounds are the interval observer's on (68)):

* ``zonotopic`` — Prop. 3.1 with the gain of the zonotope-size LMI (26) (ρ = 0.9) on (68), of the H∞
  LMI (19) on (70);
* ``interval`` — the sound framer (39)–(40) (:class:`IntervalObserver`, ``method="framer"``) with the monotone H∞ gain
  (54)–(55) on (68); on (70) monotonicity is impossible, so the (19) gain;
* ``tube`` — for comparison, the project's general :class:`IntervalObserver` (exact error tube,
  ``method="tube"``) with the same gain as ``interval``;
* ``integrated`` — Theorem 5.3 (:class:`IntegratedObserver`), gain (19) + (65); on (70) with the
  explicit fallback to (19).

Failure modes of the paper, labelled ``naive`` (never shipped): the literal (39) with the printed
non-monotone gain of Fig. 4, and the zonotopic observer with the printed (19) gain of Fig. 3
(ρ(A0 − LC) ≈ 2.07: it diverges). The (70) trajectories are stored with the prefix ``sys70_`` and keys
``…_lower``/``…_upper`` (their truth is ``sys70_x``, not ``x``).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from .._docstrings import shared_docs
from ..design.hinf import GainDesign, hinf_gain, zonotope_size_gain
from ..errors import AssumptionError
from ..estimate import Estimate
from ..examples import numerical3
from ..observers import IntervalObserver
from ..observers.base import Observer
from ..observers.zonotopic import IntegratedObserver, ZonotopicObserver
from ..plotting import plot_widths, save_figure
from ..simulate import Simulation, simulate
from ..systems.bounds import Bounds
from ..systems.lti import LTISystem
from ._seed002 import (
    add_seed002_tightness,
    gain_entries,
    mean_width,
    monte_carlo_enclosure,
    naive_framer,
    plot_comparison,
    printed_gain_table,
    versus_paper,
)
from .contract import Example, base_summary, write_reproduction

NAME = "numerical-3state"
ROBUST_HORIZON = 40
"""Window of the RobustHullEstimator in the tightness report (steps)."""
FIR_WINDOW = 10
"""Window of the learned RobustFiniteMemoryObserver in the tightness report (as benchmarks/robust_tightness.py)."""
MCCORMICK_HORIZON = 20
"""Window of RobustHullEstimator(mccormick=True) in the tightness report (as benchmarks/robust_tightness.py)."""
BOUND_STRIDE = 45
"""The ΔA lower bound (full-history LPs) is computed every BOUND_STRIDE steps of the tightness report."""
SEED_FILE = "002_a6311576c67046f0.txt"
MONTE_CARLO_RUNS = 20
LABELS = ["$x_1$", "$x_2$", "$x_3$"]


@shared_docs
def run(out_dir: Path, seed: int, plots: bool, full: bool = True) -> dict[str, Any]:
    """Design, simulate (bang-bang noise, vertex θ), run every observer on (68) and (70), write files.

    %(tightness_run)s
    """
    t = numerical3.time_grid()
    u = numerical3.input_signal(t)
    bounds = numerical3.bounds()
    design: dict[str, Any] = {}
    trajectories: dict[str, Any] = {"t": t}
    timing = {"design": 0.0, "run": 0.0}
    figures: dict[str, Any] = {}

    # ---- (68): monotone system -------------------------------------------------------------------
    sys68 = numerical3.system("68")
    start = time.perf_counter()
    args68 = (sys68.A, sys68.C, sys68.E, sys68.F)
    gains68 = {
        **_hinf_and_size_gains(args68),
        "(54)-(55)": hinf_gain(*args68, monotone=True),
    }
    observers68: dict[str, Observer] = {
        "zonotopic": ZonotopicObserver(sys68, bounds, gains68["(26)"].gain),
        "interval": IntervalObserver(sys68, bounds, gains68["(54)-(55)"].gain, method="framer"),
        "integrated": IntegratedObserver.design(sys68, bounds),
        "zonotopic_same_gain": ZonotopicObserver(sys68, bounds, gains68["(54)-(55)"].gain),
        "tube": IntervalObserver(sys68, bounds, gains68["(54)-(55)"].gain),
    }
    timing["design"] += time.perf_counter() - start
    sim68, est68 = _simulate_and_run(sys68, bounds, observers68, (t, u, seed), timing)
    trajectories["x"] = sim68.x
    trajectories["x_lower"], trajectories["x_upper"] = est68["interval"].lower, est68["interval"].upper
    for name, est in est68.items():
        trajectories[f"{name}_x_lower"], trajectories[f"{name}_x_upper"] = est.lower, est.upper
    widths68 = {name: mean_width(est) for name, est in est68.items()}
    design["system_68"] = {
        "gains": gain_entries(sys68, gains68),
        "observers": _observer_facts(observers68),
        "mean_width": widths68,
        "width_ratio_interval_over_zonotopic": _ratio(widths68["interval"], widths68["zonotopic"]),
        "width_ratio_integrated_over_zonotopic": _ratio(widths68["integrated"], widths68["zonotopic"]),
        "width_ratio_zonotopic_same_gain_over_interval": _ratio(widths68["zonotopic_same_gain"], widths68["interval"]),
        "width_ratio_tube_over_interval": _ratio(widths68["tube"], widths68["interval"]),
        "enclosure_monte_carlo": monte_carlo_enclosure(observers68, sys68, bounds, t, u, seed + 1000, MONTE_CARLO_RUNS),
    }

    # ---- (70): non-monotone system -----------------------------------------------------------------
    sys70 = numerical3.system("70")
    start = time.perf_counter()
    args70 = (sys70.A, sys70.C, sys70.E, sys70.F)
    gains70 = {
        **_hinf_and_size_gains(args70),
        "(54) with full P (printed form)": hinf_gain(*args70, monotone=True, p_structure="full"),
    }
    try:
        hinf_gain(*args70, monotone=True)
        monotone_note = "unexpectedly feasible"
    except AssumptionError as exc:
        monotone_note = f"AssumptionError: {exc}"
    integrated70 = IntegratedObserver.design(sys70, bounds, fallback="hinf")
    observers70: dict[str, Observer] = {
        "zonotopic": ZonotopicObserver(sys70, bounds, gains70["(19)"].gain),
        "interval": IntervalObserver(sys70, bounds, gains70["(19)"].gain, method="framer"),
        "integrated": integrated70,
        "tube": IntervalObserver(sys70, bounds, gains70["(19)"].gain),
    }
    timing["design"] += time.perf_counter() - start
    sim70, est70 = _simulate_and_run(sys70, bounds, observers70, (t, u, seed), timing)
    printed70 = numerical3.PRINTED_GAINS["70"]
    naive70 = {
        "naive_interval_printed_(54a)": naive_framer(sys70, bounds, printed70["interval_(54a)-(55a)"], t, sim70.y, u),
    }
    divergent = ZonotopicObserver(sys70, bounds, np.reshape(printed70["set_based_(19)"], (3, 1)), allow_unstable=True)
    est_div = divergent.run(t, sim70.y, u)
    naive70["naive_zonotopic_printed_(19)"] = (est_div.lower, est_div.upper)
    trajectories["sys70_x"] = sim70.x
    for name, est in est70.items():
        trajectories[f"sys70_{name}_lower"], trajectories[f"sys70_{name}_upper"] = est.lower, est.upper
    for name, (lo, hi) in naive70.items():
        key = name.replace("(", "").replace(")", "")
        trajectories[f"sys70_{key}_lower"], trajectories[f"sys70_{key}_upper"] = lo, hi
    widths70 = {name: mean_width(est) for name, est in est70.items()}
    design["system_70"] = {
        "gains": gain_entries(sys70, gains70),
        "monotone_design": monotone_note,
        "integrated_fallback": integrated70.fallback,
        "observers": _observer_facts(observers70),
        "mean_width": widths70,
        "enclosure": {name: est.enclosure(sim70.x).as_dict() for name, est in est70.items()},
        "width_ratio_zonotopic_over_interval": _ratio(widths70["zonotopic"], widths70["interval"]),
        "width_ratio_tube_over_interval": _ratio(widths70["tube"], widths70["interval"]),
        "enclosure_monte_carlo": monte_carlo_enclosure(observers70, sys70, bounds, t, u, seed + 2000, MONTE_CARLO_RUNS),
        "naive": {name: _naive_facts(lo, hi, sim70.x) for name, (lo, hi) in naive70.items()},
    }
    design["choices"] = {
        "E_theta": "identity (not printed; reproduces the printed (68) interval gain)",
        "x0_box": [-numerical3.X0_RADIUS, numerical3.X0_RADIUS],
        "dt": float(t[1] - t[0]),
        "true_theta": "a vertex of the θ box per run (extreme noise), fixed over time",
        "reduction_order": observers68["zonotopic"].order,  # type: ignore[attr-defined]
        "rho_(26)": 0.9,
    }
    integrated70_design = integrated70.gain_design
    assert integrated70_design is not None
    design["versus_paper"] = {
        "system_68": versus_paper(
            numerical3.PRINTED_GAINS["68"],
            {
                "set_based_thm3.4+3.5": (
                    gains68["(26)"],
                    "(26) alone, normalised by W >= I, rho = 0.9; the paper does not say how (19) and (26), "
                    "with different P and W, give one gain, nor its rho",
                ),
                "interval_(54)-(55)": (gains68["(54)-(55)"], "reproduced: -γI blocks, E_θ = I, diagonal P"),
            },
        ),
        "system_70": versus_paper(
            printed70,
            {
                "set_based_(19)": (
                    gains70["(19)"],
                    "printed gain makes A0 - LC unstable (rho 2.07); ours: (19) with -γI, E_θ = I",
                ),
                "interval_(54a)-(55a)": (
                    gains70["(19)"],
                    "(54a) is the same LMI as (19); E_θ and γ not printed; the printed gain is not what (19) "
                    "gives with E_θ = I",
                ),
                "integrated_(19)+(65)": (
                    integrated70_design,
                    "(65) is infeasible for (70) (C = [0 0 1] cannot remove the -0.1), the printed gain keeps "
                    "-0.1; ours: explicit fallback to (19)",
                ),
            },
        ),
    }
    paper = {
        "system_68": printed_gain_table(sys68, numerical3.PRINTED_GAINS["68"]),
        "system_70": printed_gain_table(sys70, printed70),
        "gamma": "not printed",
    }

    summary = base_summary(
        example=NAME,
        seed_file=SEED_FILE,
        observer="IntervalObserver (sound (39)-(40)) with the monotone H∞ gain (54)-(55), system (68)",
        t=t,
        x=sim68.x,
        x_lower=trajectories["x_lower"],
        x_upper=trajectories["x_upper"],
        transient_s=0.0,
    )
    summary["design"] = design
    summary["paper"] = paper
    summary["runtime_s"] = timing
    # Tightness (issue 9) on (68): widths against the lower bound no sound estimator can beat.
    if full:
        add_seed002_tightness(
            summary,
            out_dir,
            plots,
            sys68,
            bounds,
            (t, sim68, u),
            est68,
            observers68,
            robust_horizon=ROBUST_HORIZON,
            stride=BOUND_STRIDE,
            fir_window=FIR_WINDOW,
            mccormick_horizon=MCCORMICK_HORIZON,
        )
    write_reproduction(out_dir, summary, trajectories)
    if plots:
        shown68 = {k: (e.lower, e.upper) for k, e in est68.items() if k in ("zonotopic", "interval", "integrated")}
        figures["fig2_system68.png"] = plot_comparison(
            t, sim68.x, shown68, LABELS, "(68), monotone: zonotopic (26) vs interval (54)-(55) vs integrated"
        )
        figures["fig5_system70.png"] = plot_comparison(
            t,
            sim70.x,
            {k: (e.lower, e.upper) for k, e in est70.items()},
            LABELS,
            "(70), non-monotone: sound observers, gain (19) (monotone gain impossible)",
        )
        figures["fig3_4_system70_naive.png"] = plot_comparison(
            t, sim70.x, naive70, LABELS, "(70): naive variants (printed gains, literal (39)) — NOT sound", clip=1.5
        )
        widths: dict[str, Any] = {f"(68) {k}": e.width() for k, e in est68.items()}
        widths.update({f"(70) {k}": e.width() for k, e in est70.items()})
        figures["widths.png"] = plot_widths(t, widths)
        for name, fig in figures.items():
            save_figure(fig, out_dir / name)
    return summary


def _hinf_and_size_gains(matrices: tuple[Any, Any, Any, Any]) -> dict[str, GainDesign]:
    """The gains both systems compare: the H∞ LMI (19) and the zonotope-size LMI (26) with ρ = 0.9."""
    return {"(19)": hinf_gain(*matrices), "(26)": zonotope_size_gain(*matrices, rho=0.9)}


def _simulate_and_run(
    system: LTISystem,
    bounds: Bounds,
    observers: dict[str, Observer],
    record: tuple[Any, Any, int],
    timing: dict[str, float],
) -> tuple[Simulation, dict[str, Estimate]]:
    """One bang-bang record of ``system`` (times, input, seed in ``record``), every observer run on it (timed)."""
    t, u, seed = record
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed)
    start = time.perf_counter()
    estimates = {name: obs.run(t, sim.y, u) for name, obs in observers.items()}
    timing["run"] += time.perf_counter() - start
    return sim, estimates


def _observer_facts(observers: dict[str, Observer]) -> dict[str, dict[str, Any]]:
    facts: dict[str, dict[str, Any]] = {}
    for name, obs in observers.items():
        info = obs.meta()
        facts[name] = {
            "method": info["method"],
            "L": np.ravel(info["L"]).tolist(),
            "certificate_spectral_radius": info.get("width_spectral_radius", info.get("spectral_radius")),
            "certified": bool(info.get("certified", info.get("spectral_radius", 2.0) < 1)),
        }
        if isinstance(obs, ZonotopicObserver):
            facts[name]["spectral_radius_centre"] = obs.spectral_radius
    return facts


def _naive_facts(lower: np.ndarray, upper: np.ndarray, x: np.ndarray) -> dict[str, Any]:
    amount = np.maximum(lower - x, x - upper)
    return {
        "max_violation": float(np.nan_to_num(amount.max(), nan=np.inf)),
        "fraction_enclosed": float(np.mean(amount <= 0)),
        "crossed_bounds": bool(np.any(lower > upper)),
        "final_width_max": float(np.max(upper[-1] - lower[-1])),
    }


def _ratio(a: list[float], b: list[float]) -> dict[str, Any]:
    per_state = [x / y for x, y in zip(a, b)]
    return {"per_state": per_state, "mean": float(np.sum(a) / np.sum(b))}


EXAMPLE = Example(
    NAME,
    SEED_FILE,
    "two 3-state examples: zonotopic, interval and integrated observers, H∞ LMI gains",
    run,
)
