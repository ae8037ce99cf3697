"""Cost and width of ContinuousNonlinearObserver on the chemostat (12 h record, one run), per substeps setting.

Writes ``benchmarks/continuous_cost.json`` (or, with a label as first argument, the entry of that label in
it, so the same script measures the code of another checkout put first on ``PYTHONPATH``). CPU
milliseconds per sample (``time.process_time``: the machine is shared), the mean biomass width over the
second half and the enclosure of the truth.

Run with ``python benchmarks/continuous_cost.py [LABEL]``.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from intervalobs import Bounds, ContinuousNonlinearObserver
from intervalobs.reproduce import chemostat


def measure(substeps: int) -> dict[str, float]:
    """One 12 h chemostat run (seed 0 noise) in invariant coordinates: CPU ms per sample, X width, enclosure."""
    t = np.arange(0.0, 12.0 + 1e-9, chemostat.STEP)
    rng = np.random.default_rng(0)
    x = chemostat.simulate_exact(np.array([2.8, 0.35]), chemostat.TRUE_PARAMETERS, t, substeps=20)
    y = x[:, 1] + chemostat.NOISE * rng.choice([-1.0, 1.0], size=t.size) * rng.uniform(0.5, 1.0, size=t.size)
    low, high = chemostat.X0_BOX
    box = (np.array([low[0] / chemostat.YIELD + low[1], 0.3]), np.array([high[0] / chemostat.YIELD + 0.8, 0.8]))
    bounds = Bounds(x0=box, v=(-chemostat.NOISE, chemostat.NOISE), p=chemostat.PARAMETER_BOX)
    observer = ContinuousNonlinearObserver(chemostat.invariant_model(), bounds, chemostat.STEP, substeps=substeps)
    clock = time.process_time()
    estimate = observer.run(t, y[:, None])
    seconds = time.process_time() - clock
    lower, upper = chemostat._biomass_bounds(estimate)
    inside = (lower <= x) & (x <= upper)
    return {
        "cpu_ms_per_sample": 1000.0 * seconds / t.size,
        "biomass_mean_width_second_half": float((upper - lower)[t >= 6.0, 0].mean()),
        "enclosure": float(inside.mean()),
    }


def main() -> None:
    label = sys.argv[1] if len(sys.argv) > 1 else "this_branch"
    path = Path(__file__).parent / "continuous_cost.json"
    report = json.loads(path.read_text()) if path.exists() else {}
    report[label] = {f"substeps={k}": measure(k) for k in (2, 1)}
    text = json.dumps(report, indent=1)
    path.write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
