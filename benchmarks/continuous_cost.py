"""Cost and width of ContinuousNonlinearObserver per sample: the chemostat (12 h) and a damped pendulum (10 s).

Writes ``benchmarks/continuous_cost.json`` (or, with a label as first argument, the entry of that label in
it, so the same script measures the code of another checkout put first on ``PYTHONPATH``). For each case, one
run, ``substeps`` 2 (the default) and 1, with the NumPy path and, where the checkout has it, the compiled
kernels (``compiled=True``; the kernels are loaded by a warm-up run first, as in a long session): CPU
milliseconds per sample (``time.process_time``, the median of ``REPEATS``: the machine is shared), the mean
width of every state over the second half, and the enclosure of the truth.

Run with ``python benchmarks/continuous_cost.py [LABEL]``.
"""

from __future__ import annotations

import inspect
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from intervalobs import Bounds, ContinuousNonlinearObserver, ContinuousNonlinearSystem
from intervalobs.reproduce import chemostat

REPEATS = 5
Record = tuple[ContinuousNonlinearSystem, Bounds, float, np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]


def chemostat_record() -> Record:
    """The reproduction's chemostat (invariant coordinates Z, S), 12 h, seed 0 noise; truth in (Z, S)."""
    t = np.arange(0.0, 12.0 + 1e-9, chemostat.STEP)
    rng = np.random.default_rng(0)
    x = chemostat.simulate_exact(np.array([2.8, 0.35]), chemostat.TRUE_PARAMETERS, t, substeps=20)
    y = x[:, 1] + chemostat.NOISE * rng.choice([-1.0, 1.0], size=t.size) * rng.uniform(0.5, 1.0, size=t.size)
    low, high = chemostat.X0_BOX
    box = (np.array([low[0] / chemostat.YIELD + low[1], 0.3]), np.array([high[0] / chemostat.YIELD + 0.8, 0.8]))
    bounds = Bounds(x0=box, v=(-chemostat.NOISE, chemostat.NOISE), p=chemostat.PARAMETER_BOX)
    truth = np.stack([x[:, 0] / chemostat.YIELD + x[:, 1], x[:, 1]], axis=-1)
    return chemostat.invariant_model(), bounds, chemostat.STEP, t, y[:, None], None, truth


def pendulum_record() -> Record:
    """Damped pendulum (the tests' case): angle measured ±0.01 rad every 0.05 s, friction ±10 %, torque ±0.05."""

    def f(x: Any, u: Any, p: Any) -> tuple[Any, Any]:
        return x[1], -9.81 * np.sin(x[0]) - p[0] * x[1] + u[0]

    system = ContinuousNonlinearSystem(f, lambda x, u: (x[0],), n=2, m=1, n_params=1, E=[[0.0], [1.0]])
    bounds = Bounds(x0=([0.4, -0.2], [0.6, 0.2]), p=(0.45, 0.55), w=(-0.05, 0.05), v=(-0.01, 0.01))
    h, friction = 0.05, 0.5
    t = np.arange(0.0, 10.0 + 1e-9, h)
    u = 0.5 + 0.3 * np.sin(t)[:, None]
    rng = np.random.default_rng(0)
    x, fine = np.array([0.5, 0.0]), 20
    truth = [x]
    for k in range(t.size - 1):  # RK4 on steps 20 times finer, the torque switching sign every 5 of them
        for j in range(fine):
            w = 0.05 if (j // 5 + k) % 2 == 0 else -0.05

            def rates(z: np.ndarray, w: float = w, held: float = float(u[k, 0])) -> np.ndarray:
                return np.array([z[1], -9.81 * np.sin(z[0]) - friction * z[1] + held + w])

            dt = h / fine
            k1 = rates(x)
            k2 = rates(x + 0.5 * dt * k1)
            k3 = rates(x + 0.5 * dt * k2)
            x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + rates(x + dt * k3))
        truth.append(x)
    states = np.array(truth)
    y = states[:, :1] + 0.01 * rng.choice([-1.0, 1.0], size=(t.size, 1))
    return system, bounds, h, t, y, u, states


def measure(record: Record, substeps: int, compiled: bool | None) -> dict[str, float]:
    """Median CPU ms per sample over ``REPEATS`` runs, mean widths over the second half, enclosure."""
    system, bounds, h, t, y, u, truth = record
    options: dict[str, Any] = {"substeps": substeps}
    if compiled is not None:
        options["compiled"] = compiled
    observer = ContinuousNonlinearObserver(system, bounds, h, **options)
    observer.run(t, y, u)  # warm-up: loads the compiled kernels where asked
    costs = []
    for _ in range(REPEATS):
        clock = time.process_time()
        estimate = observer.run(t, y, u)
        costs.append(1000.0 * (time.process_time() - clock) / t.size)
    inside = (estimate.lower <= truth) & (truth <= estimate.upper)
    width = (estimate.upper - estimate.lower)[t >= 0.5 * t[-1]].mean(axis=0)
    return {
        "cpu_ms_per_sample": float(np.median(costs)),
        "mean_width_second_half": width.tolist(),
        "enclosure": float(inside.mean()),
    }


def main() -> None:
    label = sys.argv[1] if len(sys.argv) > 1 else "this_branch"
    has_kernels = "compiled" in inspect.signature(ContinuousNonlinearObserver.__init__).parameters
    paths = {"numpy": False, "compiled": True} if has_kernels else {"numpy": None}
    cases: dict[str, Callable[[], Record]] = {"chemostat_12h": chemostat_record, "pendulum_10s": pendulum_record}
    path = Path(__file__).parent / "continuous_cost.json"
    report = json.loads(path.read_text()) if path.exists() else {}
    report[label] = {
        name: {f"{how}/substeps={k}": measure(make(), k, flag) for how, flag in paths.items() for k in (2, 1)}
        for name, make in cases.items()
    }
    text = json.dumps(report, indent=1)
    path.write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
