"""Width against the exact hull on the other shapes of issue 21: vehicle, pedestrian, short record.

On ``intervalobs.examples.scale_cases``' ``vehicle()`` (6 states, 4 outputs, box noise, 200 steps),
``pedestrian()`` (4 states, 2 outputs, process noise a zonotope of 10 generators, 200 steps) and
``short_record()`` (2 states, 1 output, 20 steps), records with i.i.d. vertex noise (seeds 0 and 1), and on
each record:

- ``HullEstimator(horizon=None)``: the exact hull of the whole record (the reference; its CPU seconds for
  the record, which grow with its length);
- ``HullEstimator(horizon=H)``: the window hull, its cost per step and width / exact hull;
- ``FiniteMemoryObserver.learn(window=H, records=RECORDS, steps=TRAIN_STEPS, fallback=tube)``: learn time,
  number of filters per component, cost per step (the tube's included), width / exact hull;
- ``IntervalObserver.design()`` (error tube): design time, cost per step, width / exact hull.

The bank and the tube are designed once per case and run on both records. Widths: mean over the steps
``first … T - 1`` of the summed width of the box, ``first = H`` on the 200-step records and 0 on the short record
(its first rows are the point of the case). Every row is the box of ``x_k`` given ``y_0 … y_{k-1}``. Times are
CPU seconds of this process (the machine is shared; every solver runs on one thread; the hull's compiled
simplex is loaded before anything is timed). *Inside*: the largest amount by which a bound of any of the three
estimators lies inside the exact hull's box. Every bound is certified by weak duality, so a positive value is a
bound of the reference that falls short of its LP's optimum, not an estimator tighter than the hull: on the
vehicle, a full-history LP whose feasible set vertex noise makes thin (widening its measurement rows by 5e-10
moves a bound by 5e-3) solved to HiGHS's feasibility tolerance of 1e-9. Writes benchmarks/shapes.json;
``python benchmarks/shapes.py``."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from intervalobs import IntervalObserver
from intervalobs.estimate import Estimate
from intervalobs.examples.scale_cases import ScaleCase, pedestrian, short_record, vehicle
from intervalobs.lp.dense_simplex import load_kernels
from intervalobs.observers.fir import FiniteMemoryObserver
from intervalobs.observers.hull import HullEstimator

H = 10
SEEDS = (0, 1)
RECORDS = 6
TRAIN_STEPS = 200
CASES: tuple[tuple[Callable[[], ScaleCase], int], ...] = ((vehicle, H), (pedestrian, H), (short_record, 0))
"""Each case with the first step of its mean widths."""


def mean_width(estimate: Estimate, first: int) -> float:
    """Mean over steps ``first … T - 1`` of the summed width."""
    return float(np.mean(np.sum(estimate.upper[first:] - estimate.lower[first:], axis=1)))


def inside(estimate: Estimate, exact: Estimate) -> float:
    """Largest amount by which a bound of ``estimate`` lies inside the exact hull's box (negative: never)."""
    return float(max(np.max(estimate.lower - exact.lower), np.max(exact.upper - estimate.upper)))


def cpu(fn: Any) -> tuple[Any, float]:
    """``fn()`` and its CPU seconds."""
    start = time.process_time()
    out = fn()
    return out, time.process_time() - start


def case_rows(make: Callable[[], ScaleCase], first: int) -> list[dict[str, Any]]:
    """The rows of one case, a row per seed."""
    case = make()
    system, steps = case.system, case.t.size
    exact_hull = HullEstimator.design(system, case.bounds, horizon=None)
    window_hull = HullEstimator.design(system, case.bounds, horizon=H)
    tube, design_s = cpu(lambda: IntervalObserver.design(system, case.bounds))
    bank, learn_s = cpu(
        lambda: FiniteMemoryObserver.learn(
            system, case.bounds, window=H, records=RECORDS, steps=TRAIN_STEPS, fallback=tube
        )
    )
    shape = {"case": case.name, "n": system.n, "p": system.p, "m": system.m, "noise generators": system.nw}
    rows = []
    for seed in SEEDS:
        y = case.simulate(seed=seed, noise="vertex").y
        exact, exact_s = cpu(lambda y=y: exact_hull.run(case.t, y, case.u))
        reference = mean_width(exact, first)
        row: dict[str, Any] = {**shape, "seed": seed, "steps": steps, "widths from step": first}
        row["exact hull s"] = exact_s
        row["exact hull mean width"] = reference
        excursions = []
        for label, observer in (("hull", window_hull), ("bank", bank), ("tube", tube)):
            estimate, run_s = cpu(lambda observer=observer, y=y: observer.run(case.t, y, case.u))
            row[f"{label} ms/step"] = 1e3 * run_s / steps
            row[f"{label} / exact"] = mean_width(estimate, first) / reference
            excursions.append(inside(estimate, exact))
        row["bank learn s"] = learn_s
        row["bank filters"] = int(bank.K.shape[1])
        row["tube design s"] = design_s
        row["inside"] = max(excursions)
        rows.append(row)
    return rows


def main() -> None:
    settings = {"H": H, "seeds": list(SEEDS), "records": RECORDS, "train_steps": TRAIN_STEPS}
    results: dict[str, Any] = {"settings": settings, "rows": []}
    load_kernels()  # the hull's compiled simplex, loaded once before anything is timed
    out = Path(__file__).with_name("shapes.json")
    for make, first in CASES:
        for row in case_rows(make, first):
            results["rows"].append(row)
            print(json.dumps(row), flush=True)
        out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
