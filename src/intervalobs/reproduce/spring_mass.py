"""Reproduction ``spring-mass-lti``: the general IntervalObserver on our own uncertain two-mass system."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from ..examples import spring_mass
from ..observers import IntervalObserver
from ..plotting import plot_estimate, plot_widths, save_figure
from ..simulate import simulate
from .contract import Example, base_summary, write_reproduction

NAME = "spring-mass-lti"


def run(out_dir: Path, seed: int, plots: bool) -> dict[str, Any]:
    """Design the observer automatically, simulate with bang-bang noise, write the contract files."""
    system, bounds = spring_mass.system(), spring_mass.bounds()
    start = time.perf_counter()
    observer = IntervalObserver.design(system, bounds, h=spring_mass.SAMPLING_PERIOD)
    design_time = time.perf_counter() - start
    t = np.arange(0.0, spring_mass.T_FINAL + 1e-9, spring_mass.SAMPLING_PERIOD)
    u = spring_mass.input_signal(t)
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed, substeps=10)
    start = time.perf_counter()
    estimate = observer.run(t, sim.y, u)
    run_time = time.perf_counter() - start
    summary = base_summary(
        example=NAME,
        seed_file="-",
        observer="IntervalObserver",
        t=t,
        x=sim.x,
        x_lower=estimate.lower,
        x_upper=estimate.upper,
        transient_s=0.0,
    )
    assert observer.design_result is not None
    summary["design"] = {
        "L": observer.L,
        "T": observer.T,
        "coordinates": observer.design_result.coordinates,
        "spectral_radius": observer.spectral_radius,
        "steady_width_noise_only": 2 * observer.design_result.steady_radius,
        "tried": observer.design_result.tried,
    }
    summary["paper"] = {"note": "our own example: no paper numbers"}
    summary["runtime_s"] = {"design": design_time, "run": run_time}
    write_reproduction(out_dir, summary, {"t": t, "x": sim.x, "x_lower": estimate.lower, "x_upper": estimate.upper})
    if plots:
        labels = ["$q_1$", "$q_2$", r"$\dot q_1$", r"$\dot q_2$"]
        save_figure(plot_estimate(estimate, sim.x, labels), out_dir / "states.png")
        save_figure(plot_widths(t, {"IntervalObserver": estimate.width()}), out_dir / "widths.png")
    return summary


EXAMPLE = Example(NAME, "-", "our own 4-state uncertain spring-mass system, general IntervalObserver", run)
