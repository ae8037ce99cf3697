"""Per-step cost of `HullEstimator` on numerical-3state (68) under both kinds of bang-bang noise (issue 9).

Same system, record and width measure as benchmarks/tightness.py (seed 0, 200 steps), but both noise
kinds, the best of ``REPEATS`` runs per cell (the machine is shared), and the width ratio of every
window to the full history. To time another version of the library, put its ``src`` first on the path:
``PYTHONPATH=/path/to/checkout/src python benchmarks/hull_timing.py``. Prints a table, writes nothing.
"""

from __future__ import annotations

import time
from typing import Any

from tightness import mean_width, nominal_68, record

from intervalobs.observers.hull import HullEstimator

REPEATS = 3
CASES: list[tuple[str, int | None, dict[str, Any]]] = [
    ("H=10", 10, {}),
    ("H=40", 40, {}),
    ("H=40 workers=2", 40, {"workers": 2}),
    ("H=50", 50, {}),
    ("full", None, {}),
    ("H=40 window_boxes", 40, {"window_boxes": True}),
    ("H=40 filtered", 40, {"filtered": True}),
]


def main() -> None:
    system, bounds, t, u = nominal_68()
    for kind in ("extreme", "iid-vertex"):
        sim = record(system, bounds, t, u, kind, 0)
        widths: dict[str, float] = {}
        print(f"{kind} noise:")
        for name, horizon, options in CASES:
            best = float("inf")
            for _ in range(REPEATS if horizon is not None else 1):
                estimator = HullEstimator.design(system, bounds, horizon=horizon, **options)
                start = time.perf_counter()
                result = estimator.run(t, sim.y, u)
                best = min(best, time.perf_counter() - start)
            widths[name] = mean_width(result.lower, result.upper)
            print(f"  {name:20s} {1e3 * best / t.size:7.2f} ms/step   mean summed width {widths[name]:.9f}")
        for name in ("H=10", "H=40", "H=50"):
            print(f"  width {name} / full: {widths[name] / widths['full']:.7f}")


if __name__ == "__main__":
    main()
