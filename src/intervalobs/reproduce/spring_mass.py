"""Reproduction ``spring-mass-lti``: the general IntervalObserver on our own uncertain two-mass system."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from .._docstrings import shared_docs
from ..design.cooperative import FramerDesign
from ..design.tube import TubeDesign
from ..estimate import Estimate
from ..examples import spring_mass
from ..observers import IntervalObserver
from ..observers.intersection import IntersectionObserver
from ..plotting import plot_estimate, plot_widths, save_figure
from ..simulate import Simulation, simulate
from ..tightness import add_tightness
from .contract import Example, base_summary, write_reproduction

NAME = "spring-mass-lti"
ROBUST_HORIZON = 40
"""Window of the RobustHullEstimator in the tightness report (steps)."""
FIR_WINDOW = 60
"""Window of the learned RobustFiniteMemoryObserver in the tightness report (as benchmarks/robust_tightness.py)."""
BOUND_STRIDE = 50
"""The ΔA lower bound (full-history LPs) is computed every BOUND_STRIDE steps of the tightness report."""
TIGHTNESS_STEPS = 250
"""The tightness report (LP windows at every step) covers the first 2.5 s of the record."""
MCCORMICK_HORIZON = 40
"""Window of RobustHullEstimator(mccormick=True) in the tightness report (seed 0 of the benchmark, ΔA at a vertex:
H = 30 is no narrower than the split LP with H = 40, H = 40 is 16 % narrower)."""
MCCORMICK_STEPS = 151
"""It runs on the first MCCORMICK_STEPS samples only (the lower bound's steps 100 and 150): its continuous-time LP
(n_δ n products per step) costs about 30 times the split LP's per step."""


@shared_docs
def run(out_dir: Path, seed: int, plots: bool, full: bool = True) -> dict[str, Any]:
    """Design the observer automatically, simulate with bang-bang noise, write the contract files.

    %(tightness_run)s
    """
    system, bounds = spring_mass.system(), spring_mass.bounds()
    start = time.perf_counter()
    observer = IntervalObserver.design(system, bounds, h=spring_mass.SAMPLING_PERIOD)
    design_time = time.perf_counter() - start
    framer = IntervalObserver.design(system, bounds, h=spring_mass.SAMPLING_PERIOD, method="framer")
    t = np.arange(0.0, spring_mass.T_FINAL + 1e-9, spring_mass.SAMPLING_PERIOD)
    u = spring_mass.input_signal(t)
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed, substeps=10)
    start = time.perf_counter()
    estimate = observer.run(t, sim.y, u)
    run_time = time.perf_counter() - start
    framer_estimate = framer.run(t, sim.y, u)
    summary = base_summary(
        example=NAME,
        seed_file="-",
        observer="IntervalObserver/tube",
        t=t,
        x=sim.x,
        x_lower=estimate.lower,
        x_upper=estimate.upper,
        transient_s=0.0,
    )
    tube_design, framer_design = observer.design_result, framer.design_result
    assert isinstance(tube_design, TubeDesign) and isinstance(framer_design, FramerDesign)
    summary["design"] = {
        "tube": {
            "L": observer.L,
            "gain": tube_design.candidate,
            "horizon": observer.horizon,
            "stability_radius": observer.spectral_radius,
            "steady_width_noise_only": 2 * tube_design.steady_radius,
        },
        "framer": {
            "L": framer.L,
            "T": framer.T,
            "spectral_radius": framer.spectral_radius,
            "steady_width_noise_only": 2 * framer_design.steady_radius,
            "state_mean_width": framer_estimate.width().mean(axis=0),
        },
    }
    summary["paper"] = {"note": "our own example: no paper numbers"}
    summary["runtime_s"] = {"design": design_time, "run": run_time}
    if full:
        _tightness(summary, out_dir, plots, (t, sim, u), estimate, observer)
    trajectories = {
        "t": t,
        "x": sim.x,
        "x_lower": estimate.lower,
        "x_upper": estimate.upper,
        "tube_x_lower": estimate.lower,
        "tube_x_upper": estimate.upper,
        "framer_x_lower": framer_estimate.lower,
        "framer_x_upper": framer_estimate.upper,
    }
    write_reproduction(out_dir, summary, trajectories)
    if plots:
        labels = ["$q_1$", "$q_2$", r"$\dot q_1$", r"$\dot q_2$"]
        save_figure(plot_estimate(estimate, sim.x, labels, time_unit="s"), out_dir / "states.png")
        widths = {"tube (recommended)": estimate.width(), "framer": framer_estimate.width()}
        save_figure(plot_widths(t, widths), out_dir / "widths.png")
    return summary


def _tightness(
    summary: dict[str, Any],
    out_dir: Path,
    plots: bool,
    data: tuple[np.ndarray, Simulation, np.ndarray],
    estimate: Estimate,
    observer: IntervalObserver,
) -> None:
    """The tightness report of the recommended observer and of its intersection with the framer's."""
    system, bounds = spring_mass.system(), spring_mass.bounds()
    t, sim, u = data
    intersection = IntersectionObserver.design(system, bounds, h=spring_mass.SAMPLING_PERIOD, extra=[observer])
    compared = {"IntervalObserver": estimate, "IntersectionObserver": intersection.run(t, sim.y, u)}
    tightness = add_tightness(
        summary,
        system,
        bounds,
        t,
        sim.y,
        u,
        compared,
        h=spring_mass.SAMPLING_PERIOD,
        start=100,
        horizon=30,
        samples=0,
        truth=(sim.dA, sim.x),
        robust_horizon=ROBUST_HORIZON,
        stride=BOUND_STRIDE,
        fir_window=FIR_WINDOW,
        mccormick_horizon=MCCORMICK_HORIZON,
        mccormick_steps=MCCORMICK_STEPS,
        steps=TIGHTNESS_STEPS,
    )
    if plots:
        out_dir.mkdir(parents=True, exist_ok=True)
        save_figure(plot_widths(tightness.t, tightness.widths), out_dir / "tightness.png")


EXAMPLE = Example(
    NAME, "-", "our own 4-state uncertain spring-mass system: IntervalObserver, tube vs framer", run, weight=2.0
)
