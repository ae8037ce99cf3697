"""`make bench`: observer recursion cost against a plain per-step NumPy loop, and Monte Carlo batching.

(a) For n in {2, 5, 10, 20}: `IntervalObserver.run` against a straightforward loop that applies the
    same framer recursion one step at a time (centre and radius with NumPy, no Python objects).
(b) Per-run cost of `run` on a batch of M = 1, 100, 1000 Monte Carlo records.
Writes benchmarks/results.json and prints a table.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from intervalobs import Bounds, IntervalObserver, LTISystem

STEPS = 5000


def system_of_size(n: int, uncertain: bool = False) -> tuple[LTISystem, Bounds]:
    rng = np.random.default_rng(n)
    A = rng.normal(size=(n, n)) / np.sqrt(n)
    A = A / np.max(np.abs(np.linalg.eigvals(A))) * 0.8
    dA = (-0.01 * np.abs(A), 0.01 * np.abs(A)) if uncertain else None
    system = LTISystem(A, rng.normal(size=(2, n)), dt=1.0, dA=dA)
    bounds = Bounds(
        (-np.ones(n), np.ones(n)), w=(-0.1 * np.ones(n), 0.1 * np.ones(n)), v=(-0.1 * np.ones(2), 0.1 * np.ones(2))
    )
    return system, bounds


def plain_loop(observer: IntervalObserver, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The framer recursion written step by step, as one would without the blocked evaluation."""
    M, abs_M, TL, T_inv = observer.M, np.abs(observer.M), observer.T @ observer.L, np.linalg.inv(observer.T)
    offset = observer.T @ observer.model.noise_center
    radius_in = np.abs(observer.T) @ (observer.model.noise_radius + np.abs(observer.L) @ (0.1 * np.ones(2)))
    lo0, hi0 = observer.bounds.x0
    z_c, z_r = observer.T @ (0.5 * (lo0 + hi0)), np.abs(observer.T) @ (0.5 * (hi0 - lo0))
    lower, upper = np.empty((y.shape[0], observer.n)), np.empty((y.shape[0], observer.n))
    for k in range(y.shape[0]):
        x_c, x_r = T_inv @ z_c, np.abs(T_inv) @ z_r
        lower[k], upper[k] = x_c - x_r, x_c + x_r
        z_c = M @ z_c + TL @ y[k] + offset
        z_r = abs_M @ z_r + radius_in
    lower[0], upper[0] = np.maximum(lower[0], lo0), np.minimum(upper[0], hi0)  # the first box is the prior's
    return lower, upper


def best_of(fn, repeat: int = 3) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    results: dict = {"steps": STEPS, "recursion": [], "batching": []}
    print(f"(a) per-step cost, {STEPS} steps, single run")
    print(f"{'n':>4} {'plain loop us/step':>20} {'run us/step':>14} {'speed-up':>9} {'max |diff|':>11}")
    t = np.arange(STEPS, dtype=float)
    for n in (2, 5, 10, 20):
        system, bounds = system_of_size(n)
        observer = IntervalObserver.design(system, bounds, method="framer")
        y = np.random.default_rng(0).normal(size=(STEPS, 2))
        loop_time = best_of(lambda o=observer, y=y: plain_loop(o, y))
        run_time = best_of(lambda o=observer, y=y: o.run(t, y))
        diff = np.max(np.abs(plain_loop(observer, y)[1] - observer.run(t, y).upper))
        row = {
            "n": n,
            "loop_us_per_step": 1e6 * loop_time / STEPS,
            "run_us_per_step": 1e6 * run_time / STEPS,
            "speedup": loop_time / run_time,
            "max_abs_difference": float(diff),
        }
        results["recursion"].append(row)
        print(
            f"{n:>4} {row['loop_us_per_step']:>20.2f} {row['run_us_per_step']:>14.3f} "
            f"{row['speedup']:>8.1f}x {diff:>11.2e}"
        )
    steps = STEPS // 5
    tb = np.arange(steps, dtype=float)
    for uncertain in (False, True):
        kind = "interval dA (per-step recursion)" if uncertain else "point A (modal recursion)"
        print(f"(b) Monte Carlo batching, n = 5, {steps} steps, {kind}")
        system, bounds = system_of_size(5, uncertain)
        observer = IntervalObserver.design(system, bounds, method="framer")
        base = None
        for runs in (1, 100, 1000):
            y = np.random.default_rng(1).normal(size=(runs, steps, 2))
            per_run = best_of(lambda o=observer, y=y: o.run(tb, y), repeat=2) / runs
            base = base or per_run
            row = {"model": kind, "runs": runs, "ms_per_run": 1e3 * per_run, "ratio_to_single": per_run / base}
            results["batching"].append(row)
            print(f"  M = {runs:>5}: {row['ms_per_run']:.4f} ms per run ({row['ratio_to_single']:.4f} of M = 1)")
    out = Path(__file__).with_name("results.json")
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
