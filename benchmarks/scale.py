"""Cost against size on the tank cascades (issue 21): window hull, learned FIR bank and error tube, in one run.

For n = 3, 6, 12, 30, 60 tanks (``p = round(0.7 n)`` level sensors, ``n // 2`` pumps;
``intervalobs.examples.scale_cases.tank_cascade``), one record of ``STEPS`` samples with i.i.d. vertex
noise (seed 0), and on it:

- ``HullEstimator(horizon=H)``: the exact window hull (the reference of the other columns), its cost per
  step; the same with ``filtered=True`` (rows that also use ``y_k``), its cost per step against the
  predicted rows' (issue 36: at most 1.3) and its width against theirs;
- for n ≤ ``EXACT_MAX_N``, the exact hull of the record's first ``EXACT_STEPS`` steps (the condensed LP
  anchored at ``x_0``, ``HullEstimator(horizon=EXACT_STEPS)``): its CPU seconds for those steps and the window
  hull's width against it over the steps ``H … EXACT_STEPS - 1``. Both are certified outer bounds, so a ratio
  below 1 is an exact-hull certificate that falls short of its LP's optimum;
- ``FiniteMemoryObserver.learn(window=H, records=RECORDS, steps=TRAIN_STEPS)``: learn time (the hull's
  certificates on simulated records plus the worst-case filter LP), cost per step, width / hull;
- ``IntervalObserver.design()`` (error tube): design time, cost per step, width / hull.

Widths: mean over the steps ``H … `` of the summed width of the box. Times are CPU seconds of this
process (the machine is shared: the wall clock would measure the other jobs; every solver runs on one
thread; the hull's compiled simplex is loaded before anything is timed). A cell whose cost would exceed its
budget (``HULL_BUDGET_S`` for the hull record, projected from the steps already run; ``LEARN_BUDGET_S`` for
learning, projected from the hull's cost per step) is stopped or not run, and says so. Writes
benchmarks/scale.json; ``python benchmarks/scale.py``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from intervalobs import IntervalObserver
from intervalobs.examples.scale_cases import TANK_SIZES, tank_cascade
from intervalobs.lp.dense_simplex import load_kernels
from intervalobs.observers.fir import FiniteMemoryObserver
from intervalobs.observers.hull import HullEstimator

H = 10
STEPS = 60
RECORDS = 4
TRAIN_STEPS = 50
HULL_BUDGET_S = 300.0
EXACT_STEPS = 25
EXACT_MAX_N = 30
LEARN_BUDGET_S = 600.0


def mean_width(lower: np.ndarray, upper: np.ndarray, steps: int) -> float:
    """Mean over steps ``H … steps - 1`` of the summed width."""
    return float(np.mean(np.sum(upper[H:steps] - lower[H:steps], axis=1)))


def cpu(fn: Any) -> tuple[Any, float]:
    """``fn()`` and its CPU seconds."""
    start = time.process_time()
    out = fn()
    return out, time.process_time() - start


def hull_record(case: Any, y: np.ndarray, filtered: bool = False) -> tuple[np.ndarray, np.ndarray, int, float]:
    """The hull step by step until the record ends or the projected cost exceeds the budget."""
    hull = HullEstimator.design(case.system, case.bounds, horizon=H, filtered=filtered)
    state = hull.init()
    lower, upper = np.empty((STEPS, case.system.n)), np.empty((STEPS, case.system.n))
    spent, done = 0.0, 0
    for k in range(STEPS):
        lower[k], upper[k] = state.lower, state.upper
        state, seconds = cpu(lambda k=k, state=state: hull.step(state, y[k], case.u[k]))
        spent, done = spent + seconds, k + 1
        if k >= H + 2 and spent / done * STEPS > HULL_BUDGET_S:
            break
    return lower, upper, done, spent


def size_row(n: int) -> dict[str, Any]:
    """One row of the table: the three estimators on the ``n``-tank cascade."""
    case = tank_cascade(n, steps=STEPS)
    sim = case.simulate(seed=0, noise="vertex")
    row: dict[str, Any] = {"n": n, "p": case.system.p, "m": case.system.m}
    lower, upper, done, spent = hull_record(case, sim.y)
    reference = mean_width(lower, upper, done)
    hull_ms = 1e3 * spent / done
    row["hull ms/step"] = hull_ms
    row["hull steps"] = done if done == STEPS else f"{done} of {STEPS} (> {HULL_BUDGET_S:g} s projected)"
    row["hull mean width"] = reference
    f_lower, f_upper, f_done, f_spent = hull_record(case, sim.y, filtered=True)
    row["filtered hull ms/step"] = 1e3 * f_spent / f_done
    row["filtered / predicted cost"] = row["filtered hull ms/step"] / hull_ms
    row["filtered / predicted width"] = mean_width(f_lower, f_upper, min(done, f_done)) / mean_width(
        lower, upper, min(done, f_done)
    )
    if n <= EXACT_MAX_N:
        exact_hull = HullEstimator.design(case.system, case.bounds, horizon=EXACT_STEPS)
        exact, exact_s = cpu(lambda: exact_hull.run(case.t[:EXACT_STEPS], sim.y[:EXACT_STEPS], case.u[:EXACT_STEPS]))
        row["exact hull s"] = exact_s
        row["hull / exact"] = mean_width(lower, upper, EXACT_STEPS) / mean_width(exact.lower, exact.upper, EXACT_STEPS)
    tube, design_s = cpu(lambda: IntervalObserver.design(case.system, case.bounds))
    estimate, run_s = cpu(lambda: tube.run(case.t, sim.y, case.u))
    row["tube design s"] = design_s
    row["tube ms/step"] = 1e3 * run_s / STEPS
    row["tube / hull"] = mean_width(estimate.lower, estimate.upper, done) / reference
    projected = 1e-3 * hull_ms * RECORDS * TRAIN_STEPS
    if projected > LEARN_BUDGET_S:
        row["bank learn s"] = f"not run: > {projected:.0f} s projected"
        return row
    bank, learn_s = cpu(
        lambda: FiniteMemoryObserver.learn(
            case.system, case.bounds, window=H, records=RECORDS, steps=TRAIN_STEPS, fallback=tube
        )
    )
    estimate, run_s = cpu(lambda: bank.run(case.t, sim.y, case.u))
    row["bank learn s"] = learn_s
    row["bank ms/step"] = 1e3 * run_s / STEPS
    row["bank / hull"] = mean_width(estimate.lower, estimate.upper, done) / reference
    row["bank filters"] = int(bank.K.shape[1])
    return row


def main() -> None:
    settings = {"H": H, "steps": STEPS, "records": RECORDS, "train_steps": TRAIN_STEPS, "exact_steps": EXACT_STEPS}
    results: dict[str, Any] = {"settings": settings, "rows": []}
    load_kernels()  # the hull's compiled simplex, loaded once before anything is timed
    out = Path(__file__).with_name("scale.json")
    for n in TANK_SIZES:
        row = size_row(n)
        results["rows"].append(row)
        print(json.dumps(row), flush=True)
        out.write_text(json.dumps(results, indent=2) + "\n")  # rows so far, should a later size be stopped
    print(f"written {out}")


if __name__ == "__main__":
    main()
