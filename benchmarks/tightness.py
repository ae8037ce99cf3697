"""Tightness benchmark (issue 9): width ratios to the exact hull on numerical-3state (68), and LP costs.

Settings of the issue's reference measurement: system (68) with θ = 0 (no ΔA, so the hull is exact),
paper gain L = [0.3 0.2 0.8], x0 ∈ [−1, 1]³, 200 steps, mean over steps 20–199 of the summed widths,
three seeds, two kinds of bang-bang noise: the simulator's ``"extreme"`` (each component at a bound,
switching with probability 0.1 per step) and i.i.d. vertices (a random bound every step).

Run with ``make bench`` (after the recursion benchmark) or ``python benchmarks/tightness.py``; writes
benchmarks/tightness.json.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import linprog

from intervalobs import Bounds, IntervalObserver, LTISystem, simulate
from intervalobs.design.hinf import zonotope_size_gain
from intervalobs.examples import numerical3
from intervalobs.observers.fir import FiniteMemoryObserver
from intervalobs.observers.hull import HullEstimator
from intervalobs.observers.intersection import IntersectionObserver
from intervalobs.observers.zonotopic import ZonotopicObserver

START = 20
FIR_WINDOWS = (20, 40, 80)
PAPER_GAIN = np.array([[0.3], [0.2], [0.8]])
BANK_WINDOW, BANK_RECORDS = 10, 6
BANK = f"FIR bank learned from hull certificates (N={BANK_WINDOW}, {BANK_RECORDS} records) ∩ tube"
BANK_FILTERED = f"FIR bank learned from filtered hull certificates (uses y_k; N={BANK_WINDOW}, {BANK_RECORDS} records)"


def nominal_68() -> tuple[LTISystem, Bounds, np.ndarray, np.ndarray]:
    s = numerical3.system("68")
    system = LTISystem(s.A, s.C, B=s.B, E=s.E, F=s.F, dt=s.dt)
    t = numerical3.time_grid()
    return system, numerical3.bounds(), t, numerical3.input_signal(t)


def record(system: LTISystem, bounds: Bounds, t: np.ndarray, u: np.ndarray, kind: str, seed: int) -> Any:
    if kind == "extreme":
        return simulate(system, bounds, t, u=u, noise="extreme", seed=seed)
    rng = np.random.default_rng(seed)
    w = rng.choice([-1.0, 1.0], size=(t.size, system.nw))
    v = rng.choice([-1.0, 1.0], size=(t.size, system.nv))
    return simulate(system, bounds, t, u=u, noise={"w": w, "v": v}, seed=seed)


def mean_width(lower: np.ndarray, upper: np.ndarray) -> float:
    return float(np.mean(np.sum(upper - lower, axis=-1)[START:]))


def ratios() -> dict[str, Any]:
    system, bounds, t, u = nominal_68()
    zono_gain = zonotope_size_gain(system.A, system.C, system.E, system.F, rho=0.9).gain
    plain = IntervalObserver(system, bounds, PAPER_GAIN, method="framer")
    tube = IntervalObserver.design(system, bounds)
    zonotopic = ZonotopicObserver(system, bounds, zono_gain)
    observers = {
        "interval (framer, paper gain)": plain,
        "tube (designed gain)": tube,
        "zonotopic ((26) gain)": zonotopic,
        "intersection: paper framer + output contraction": IntersectionObserver([plain], system, bounds),
        "intersection: 4 framers (coordinates), no contraction": IntersectionObserver.design(
            system, bounds, contract=False
        ),
        "intersection: 4 framers + paper framer + tube + zonotopic + contraction": IntersectionObserver.design(
            system, bounds, extra=[plain, tube, zonotopic]
        ),
    }
    fir = {N: FiniteMemoryObserver.design(system, bounds, window=N) for N in FIR_WINDOWS}
    for N, obs in fir.items():
        observers[f"FIR N={N} (worst-case-optimal LP weights) ∩ tube"] = obs
    observers[BANK] = FiniteMemoryObserver.learn(system, bounds, window=BANK_WINDOW, records=BANK_RECORDS)
    observers[BANK_FILTERED] = FiniteMemoryObserver.learn(
        system, bounds, window=BANK_WINDOW, records=BANK_RECORDS, filtered=True
    )
    sup = np.zeros(system.n)
    out: dict[str, Any] = {}
    for kind in ("extreme", "iid-vertex"):
        rows: dict[str, list[float]] = {}
        filtered: dict[str, list[float]] = {}
        for seed in (0, 1, 2):
            sim = record(system, bounds, t, u, kind, seed)
            hull = HullEstimator.design(system, bounds, horizon=50).run(t, sim.y, u)
            filt = HullEstimator.design(system, bounds, horizon=50, filtered=True).run(t, sim.y, u)
            ref = mean_width(hull.lower, hull.upper)
            rows.setdefault("hull (predicted, y_0..y_{k-1}): mean width", []).append(ref)
            rows.setdefault("hull (filtered, y_0..y_k): mean width", []).append(mean_width(filt.lower, filt.upper))
            rows.setdefault("filtered hull / predicted hull", []).append(mean_width(filt.lower, filt.upper) / ref)
            sup = np.maximum(sup, np.max((hull.upper - hull.lower)[START:], axis=0))
            for N, obs in fir.items():
                rows.setdefault(f"FIR N={N} alone (constant width 2·sum radius)", []).append(
                    2 * float(np.sum(obs.radius)) / ref
                )
            for name, obs in observers.items():
                est = obs.run(t, sim.y, u)
                assert est.enclosure(sim.x).max_violation == 0.0, name
                rows.setdefault(name, []).append(mean_width(est.lower, est.upper) / ref)
                filtered.setdefault(name, []).append(
                    mean_width(est.lower, est.upper) / mean_width(filt.lower, filt.upper)
                )
        out[kind] = {k: [round(v, 4) for v in vals] for k, vals in rows.items()}
        out[f"{kind}, ratio to the FILTERED hull"] = {k: [round(v, 4) for v in vals] for k, vals in filtered.items()}
    # Any sound observer whose width does not depend on the data is at least this wide (summed).
    out["sup over all runs of the hull width (summed per-component maxima)"] = round(float(np.sum(sup)), 4)
    return out


def bank_tradeoff() -> dict[str, Any]:
    """Learned FIR bank on (68), i.i.d. vertex noise: training size and bank size against tightness and cost."""
    system, bounds, t, u = nominal_68()
    sims = [record(system, bounds, t, u, "iid-vertex", seed) for seed in (0, 1, 2)]
    predicted = [HullEstimator.design(system, bounds, horizon=50).run(t, sim.y, u) for sim in sims]
    filtered = [HullEstimator.design(system, bounds, horizon=50, filtered=True).run(t, sim.y, u) for sim in sims]
    out: dict[str, Any] = {}
    for window in (10, 20):
        for records in (2, 6, 12):
            for size in (64, 256, None):
                start = time.perf_counter()
                obs = FiniteMemoryObserver.learn(system, bounds, window=window, records=records, size=size)
                learn_s = time.perf_counter() - start
                ratios_p, ratios_f, cost = [], [], 0.0
                for sim, hp, hf in zip(sims, predicted, filtered, strict=True):
                    start = time.perf_counter()
                    est = obs.run(t, sim.y, u)
                    cost += time.perf_counter() - start
                    assert est.enclosure(sim.x).max_violation == 0.0
                    ratios_p.append(round(mean_width(est.lower, est.upper) / mean_width(hp.lower, hp.upper), 4))
                    ratios_f.append(round(mean_width(est.lower, est.upper) / mean_width(hf.lower, hf.upper), 4))
                out[f"N={window} records={records} size={size or 'all'}"] = {
                    "filters per component": obs.meta()["bank"],
                    "learn s": round(learn_s, 2),
                    "run us/step": round(1e6 * cost / (3 * t.size), 1),
                    "/ predicted hull": ratios_p,
                    "/ filtered hull": ratios_f,
                }
    return out


def lp_costs() -> dict[str, Any]:
    system, bounds, t, u = nominal_68()
    sim = record(system, bounds, t, u, "extreme", 0)
    costs: dict[str, Any] = {}
    widths = {}
    for horizon in (10, 40, 50, None):
        est = HullEstimator.design(system, bounds, horizon=horizon)
        start = time.perf_counter()
        result = est.run(t, sim.y, u)
        elapsed = time.perf_counter() - start
        key = "full" if horizon is None else str(horizon)
        costs[f"hull H={key} ms/step"] = round(1e3 * elapsed / t.size, 3)
        widths[key] = mean_width(result.lower, result.upper)
    costs["width ratio H=10 / full"] = round(widths["10"] / widths["full"], 6)
    costs["width ratio H=40 / full"] = round(widths["40"] / widths["full"], 6)
    for N in FIR_WINDOWS:
        start = time.perf_counter()
        fir = FiniteMemoryObserver.design(system, bounds, window=N)
        costs[f"FIR N={N} design s (total / LPs)"] = [round(time.perf_counter() - start, 4), round(fir.lp_seconds, 4)]
        costs[f"FIR N={N} run us/step (incl. tube fallback)"] = round(1e3 * _timed(fir, t, sim, u), 3)
    est = HullEstimator.design(system, bounds, horizon=40, window_boxes=True)
    start = time.perf_counter()
    est.run(t, sim.y, u)
    costs["hull H=40 window_boxes ms/step"] = round(1e3 * (time.perf_counter() - start) / t.size, 3)
    for kind in ("extreme", "iid-vertex"):  # workers=2: two HiGHS instances in parallel threads (2 cores here)
        noisy = record(system, bounds, t, u, kind, 0)
        for workers in (1, 2):
            hull = HullEstimator.design(system, bounds, horizon=40, workers=workers)
            costs[f"hull H=40 workers={workers} ms/step ({kind})"] = _timed(hull, t, noisy, u)
    costs["hull H=40 filtered ms/step"] = _timed(
        HullEstimator.design(system, bounds, horizon=40, filtered=True), t, sim, u
    )
    costs["scipy linprog, H=40, 6 LPs ms/step"] = round(_linprog_window(system, sim.y, u, 40), 3)
    plain = IntervalObserver(system, bounds, PAPER_GAIN, method="framer")
    costs["interval framer run us/step"] = round(1e3 * _timed(plain, t, sim, u), 3)
    costs["intersection (paper framer + contraction) us/step"] = round(
        1e3 * _timed(IntersectionObserver([plain], system, bounds), t, sim, u), 3
    )
    costs["intersection (designed, 4 framers + contraction) us/step"] = round(
        1e3 * _timed(IntersectionObserver.design(system, bounds), t, sim, u), 3
    )
    return costs


def _timed(obs: Any, t: np.ndarray, sim: Any, u: np.ndarray) -> float:
    start = time.perf_counter()
    obs.run(t, sim.y, u)
    return round(1e3 * (time.perf_counter() - start) / t.size, 4)


def _linprog_window(system: LTISystem, y: np.ndarray, u: np.ndarray, horizon: int) -> float:
    """The same window LP (states as variables, box rows) solved from scratch by scipy's linprog."""
    n, steps = system.n, horizon
    nx = (steps + 1) * n
    rows, rhs_lo, rhs_hi = [], [], []
    for j in range(steps):
        block = np.zeros((n, nx))
        block[:, (j + 1) * n : (j + 2) * n] = np.eye(n)
        block[:, j * n : (j + 1) * n] = -system.A
        rows.append(block)
        meas = np.zeros((1, nx))
        meas[:, j * n : (j + 1) * n] = system.C
        rows.append(meas)
    a = np.vstack(rows)
    total, count = 0.0, 0
    for k in range(100, 110):
        lo, hi = [], []
        for j in range(steps):
            tau = k - steps + j
            drive = system.B @ u[tau]
            lo.append(drive - 0.08)
            hi.append(drive + 0.08)
            lo.append(y[tau] - 0.2)
            hi.append(y[tau] + 0.2)
        rhs_lo, rhs_hi = np.concatenate(lo), np.concatenate(hi)
        a_ub = np.vstack([a, -a])
        b_ub = np.concatenate([rhs_hi, -rhs_lo])
        box = [(-5.0, 5.0)] * nx
        start = time.perf_counter()
        for i in range(n):
            for sign in (1.0, -1.0):
                cost = np.zeros(nx)
                cost[steps * n + i] = sign
                linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=box, method="highs")
        total += time.perf_counter() - start
        count += 1
    return 1e3 * total / count


def main() -> None:
    results = {"ratios_to_predicted_hull": ratios(), "bank": bank_tradeoff(), "costs": lp_costs()}
    out = Path(__file__).with_name("tightness.json")
    out.write_text(json.dumps(results, indent=2) + "\n")
    for kind, rows in results["ratios_to_predicted_hull"].items():
        if not isinstance(rows, dict):
            print(f"{kind}: {rows}")
            continue
        print(f"(68), θ = 0, {kind} noise, seeds 0-2, mean summed width over steps {START}-199:")
        for name, values in rows.items():
            print(f"  {name:72s} {' '.join(f'{v:8.4f}' for v in values)}")
    print("learned FIR bank, i.i.d. vertex noise, seeds 0-2:")
    for name, row in results["bank"].items():
        print(f"  {name:32s} {row}")
    print("costs (n = 3, 200 steps):")
    for name, value in results["costs"].items():
        print(f"  {name:72s} {value}")
    print(f"written {out}")


if __name__ == "__main__":
    main()
