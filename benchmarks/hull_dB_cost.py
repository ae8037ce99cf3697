"""Cost and width of `HullEstimator` with an uncertain input matrix: one ΔB shared by the window or free per step.

The two examples of ``tests/test_uncertain_input.py`` (imported from it, so that the models are defined once):
the discrete two-state system and the continuous DC motor, each with the test's own truth (ΔB at a vertex,
bang-bang noise), filtered rows and the window ``observe`` chooses (``memory_horizon``). For each of
``constant_dB=True`` (sparse window LP with the shared unknowns) and ``False`` (condensed window LP, the noise
box widened by ``δΓ|u_j|``): CPU milliseconds per step (``time.process_time``, best of ``REPEATS`` runs after one
warm-up: the machine is shared), the mean summed width after the first window, and the enclosure of the truth.

Writes ``benchmarks/hull_dB_cost.json`` (or, with a label as first argument, the entry of that label in it).
Run with ``python benchmarks/hull_dB_cost.py [LABEL]``.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from intervalobs import HullEstimator
from intervalobs.front_door import memory_horizon
from test_uncertain_input import MOTOR_BOUNDS, TWO_BOUNDS, H, _input, _motor, _own_truth, _two

REPEATS = 3
STEPS = 300


def measure(continuous: bool, constant_dB: bool) -> dict[str, Any]:
    """One example, one kind of ΔB: CPU ms per step, mean summed width after the first window, enclosure."""
    system, bounds, h = (_motor(), MOTOR_BOUNDS, H) if continuous else (_two(), TWO_BOUNDS, None)
    horizon = memory_horizon(system, h)
    u = _input(STEPS, continuous)
    t = np.arange(STEPS) * (H if continuous else 1.0)
    x, y = _own_truth(system, bounds, u, 2)
    hull = HullEstimator.design(system, bounds, h=h, horizon=horizon, filtered=True, constant_dB=constant_dB)
    estimate = hull.run(t, y, u)  # warm-up (the dense simplex is compiled on first use)
    best = np.inf
    for _ in range(REPEATS):
        clock = time.process_time()
        estimate = hull.run(t, y, u)
        best = min(best, time.process_time() - clock)
    return {
        "horizon": horizon,
        "window_lp": "condensed" if hull.condensed_allowed() else "sparse",
        "cpu_ms_per_step": round(1000.0 * best / STEPS, 3),
        "mean_summed_width": round(float(estimate.width()[horizon:].sum(axis=1).mean()), 5),
        "enclosure": estimate.enclosure(x).fraction,
    }


def main() -> None:
    label = sys.argv[1] if len(sys.argv) > 1 else "this_branch"
    path = Path(__file__).parent / "hull_dB_cost.json"
    report = json.loads(path.read_text()) if path.exists() else {}
    entry: dict[str, Any] = {}
    for name, continuous in (("two-state (discrete)", False), ("motor (continuous)", True)):
        cases = {kind: measure(continuous, kind == "constant ΔB") for kind in ("constant ΔB", "ΔB per step")}
        widths = [cases[kind]["mean_summed_width"] for kind in ("constant ΔB", "ΔB per step")]
        costs = [cases[kind]["cpu_ms_per_step"] for kind in ("constant ΔB", "ΔB per step")]
        entry[name] = {
            **cases,
            "width_ratio": round(widths[0] / widths[1], 4),
            "cost_ratio": round(costs[0] / costs[1], 2),
        }
    report[label] = entry
    text = json.dumps(report, indent=1, ensure_ascii=False)
    path.write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
