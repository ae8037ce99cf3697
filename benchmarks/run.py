"""`make bench`: observer recursion cost against a plain per-step NumPy loop, and Monte Carlo batching.

(a) For n in {2, 5, 10, 20}: `IntervalObserver.run` against a straightforward loop that applies the
    same framer recursion one step at a time (centre and radius with NumPy, no Python objects).
(b) Per-run cost of `run` on a batch of M = 1, 100, 1000 Monte Carlo records.
(c) Issue 36: the observer `IntervalObserver.design` returns by default (the tube, with its companion gains)
    against a compiled loop of the same recursion without outward rounding (`unrounded_loop`: every gain's
    centre and tube, the disturbance radius of interval dA from the intersected box, no margin, no drive),
    at n = 2, 5, 10, 20, point A and interval dA, one record of `LONG_STEPS` samples and M = 1000 records of
    `BATCH_STEPS`, on extreme-noise simulations; `run` is timed whole (validation, compiled recursion, the
    Estimate), both warmed up first, best of 3 in this one process. Target: ratio <= 3.
Writes benchmarks/results.json and prints a table.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numba
import numpy as np

from intervalobs import Bounds, IntervalObserver, LTISystem, simulate

STEPS = 20_000
LONG_STEPS = 100_000
BATCH_RUNS, BATCH_STEPS = 1000, 100


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


@numba.njit(cache=True)
def unrounded_loop(y, ms, tl, offset, powers, lags, sums, k_phi, z_c0, z_r0, uncertain):
    """The default tube's recursion in identity coordinates, step by step, in round-to-nearest without margins."""
    runs, steps, p = y.shape
    gains, n = z_c0.shape
    lower, upper = np.empty((runs, steps, n)), np.empty((runs, steps, n))
    radii, disturbances = np.empty((steps, gains, n)), np.empty((steps, gains, n))
    for r in range(runs):
        z_c = z_c0.copy()
        new = np.empty(n)
        radii[0] = z_r0
        for k in range(steps):
            for i in range(n):
                lower[r, k, i], upper[r, k, i] = -np.inf, np.inf
                for g in range(gains):
                    lower[r, k, i] = max(lower[r, k, i], z_c[g, i] - radii[k, g, i])
                    upper[r, k, i] = min(upper[r, k, i], z_c[g, i] + radii[k, g, i])
            if k + 1 == steps:
                break
            if uncertain:  # the data-dependent disturbance; the noise's part is the constant sums[g, ℓ]
                for i in range(n):
                    extra = 0.0
                    for j in range(n):
                        extra += k_phi[i, j] * max(abs(lower[r, k, j]), abs(upper[r, k, j]))
                    for g in range(gains):
                        disturbances[k, g, i] = extra
            for g in range(gains):
                for i in range(n):
                    total = offset[g, i]
                    for j in range(n):
                        total += ms[g, i, j] * z_c[g, j]
                    for j in range(p):
                        total += tl[g, i, j] * y[r, k, j]
                    new[i] = total
                z_c[g] = new
                lag = min(k + 1, lags[g])
                for i in range(n):
                    total = sums[g, lag, i]
                    for j in range(n):
                        total += powers[g, lag, i, j] * radii[k + 1 - lag, g, j]
                    for h in range(lag if uncertain else 0):
                        for j in range(n):
                            total += powers[g, h, i, j] * disturbances[k - h, g, j]
                    radii[k + 1, g, i] = total
    return lower, upper


def compiled_row(n: int, uncertain: bool, runs: int, steps: int) -> dict:
    """`run` of the default design against `unrounded_loop` on one simulated batch."""
    system, bounds = system_of_size(n, uncertain)
    observer = IntervalObserver.design(system, bounds)
    assert observer._identity and observer.method == "tube"  # the reference loop is written for these
    t = np.arange(steps, dtype=float)
    y = simulate(system, bounds, t, noise="extreme", seed=n, runs=runs).y.reshape(runs, steps, 2)
    internal = observer.init().internal
    args = (
        y,
        observer._Ms,
        observer._TL,
        observer._offset,
        observer._abs_powers,
        observer._lags.astype(np.int64),
        np.ascontiguousarray(observer._noise_sums),
        observer._K_phi,
        internal["z_center"],
        internal["z_radius"],
        uncertain,
    )
    y_run = y[0] if runs == 1 else y
    reference, estimate = unrounded_loop(*args), observer.run(t, y_run)  # warm-up: compile or load both
    assert np.all(estimate.lower <= reference[0].reshape(estimate.lower.shape))  # same boxes, outward rounded
    loop_time = best_of(lambda: unrounded_loop(*args))
    run_time = best_of(lambda: observer.run(t, y_run))
    return {
        "n": n,
        "model": "interval dA" if uncertain else "point A",
        "runs": runs,
        "steps": steps,
        "gains": int(observer.gains.shape[0]),
        "horizons": list(observer.horizons),
        "unrounded loop us/step": 1e6 * loop_time / (runs * steps),
        "run us/step": 1e6 * run_time / (runs * steps),
        "ratio": run_time / loop_time,
    }


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
    print("(c) default design (tube, companion gains) against a compiled unrounded loop of its recursion")
    results["compiled"] = [
        compiled_row(n, uncertain, runs, steps)
        for uncertain in (False, True)
        for runs, steps in ((1, LONG_STEPS), (BATCH_RUNS, BATCH_STEPS))
        for n in (2, 5, 10, 20)
    ]
    for row in results["compiled"]:
        print("  " + ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()))
    results["largest ratio to the compiled unrounded loop (target 3)"] = max(r["ratio"] for r in results["compiled"])
    out = Path(__file__).with_name("results.json")
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
