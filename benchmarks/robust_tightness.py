"""Tightness under interval ΔA (issue 19): the robust estimators against the certified lower bound.

The three reproductions with a tightness report, their own extreme (bang-bang) noise, seeds 0, 1, 2,
and the true ΔA at a vertex of its box (as the simulator draws it) and, separately, at a random point
of the box. For each run: the mean summed width of the RobustHullEstimator (window H), of the
LP-free RobustFiniteMemoryObserver (``learn``: window N = "fir window", 6 training records,
intersected with the IntervalObserver; learned once per example, on its own random records), of the
IntervalObserver (designed) and of the default IntersectionObserver, the lower bound of
``robust_hull_lower_bound`` (candidates: the true ΔA and the estimator's extremal ΔA values; computed
every ``stride`` steps, all means over those steps), the ratios, the enclosure of the truth and the
costs per step (the RobustFiniteMemoryObserver's includes its IntervalObserver). Settings (steps, first
step of the means, windows) are those of the reproductions. On numerical-3state also the McCormick window LP
(``RobustHullEstimator(mccormick=True)``, window "mccormick horizon", no identification; the lower bound's
candidates stay those of the split estimator) and a second learned bank of "fir size" filters per component
(``learn(size=..., selection="cover")``: the subset of the same training's certificates that covers its
windows best, for a cost below 1 ms/step).
Costs per step: CPU time of the online run only (``time.process_time``, the key "clock" of an example;
rows without it were timed by the wall clock), divided by the number of steps; the LP-free observers
take the fastest of three runs.

Run with ``make bench`` or ``python benchmarks/robust_tightness.py``; writes
benchmarks/robust_tightness.json.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from intervalobs import IntervalObserver, LTISystem, simulate
from intervalobs.examples import numerical3, spring_mass, two_tank
from intervalobs.observers.intersection import IntersectionObserver
from intervalobs.observers.robust_fir import RobustFiniteMemoryObserver
from intervalobs.observers.robust_hull import RobustHullEstimator
from intervalobs.tightness import robust_hull_lower_bound

SEEDS = (0, 1, 2)


def examples() -> dict[str, dict[str, Any]]:
    t3 = numerical3.time_grid()
    tt = two_tank.time_grid()[:400]
    ts = np.arange(250) * spring_mass.SAMPLING_PERIOD
    return {
        "numerical-3state (68)": {
            "system": numerical3.system("68"),
            "bounds": numerical3.bounds(),
            "t": t3,
            "u": numerical3.input_signal(t3),
            "h": None,
            "start": 20,
            "horizon": 40,
            "stride": 20,
            "fir window": 10,
            "fir size": 256,
            "fir selection": "cover",
            "mccormick horizon": 20,
        },
        "two-tank": {
            "system": two_tank.system(),
            "bounds": two_tank.bounds(),
            "t": tt,
            "u": two_tank.input_signal(tt),
            "h": None,
            "start": 20,
            "horizon": 120,
            "stride": 40,
            "fir window": 10,
        },
        "spring-mass-lti": {
            "system": spring_mass.system(),
            "bounds": spring_mass.bounds(),
            "t": ts,
            "u": spring_mass.input_signal(ts),
            "h": spring_mass.SAMPLING_PERIOD,
            "start": 100,
            "horizon": 80,
            "stride": 30,
            "fir window": 60,
        },
    }


SMALL = "RobustFiniteMemoryObserver small bank"


def learned_bank(case: dict[str, Any], size: int | None = None) -> tuple[RobustFiniteMemoryObserver, float]:
    """The example's RobustFiniteMemoryObserver (``size`` filters per component) and its learning time in s."""
    selection = case.get("fir selection", "random") if size is not None else "random"
    system, bounds, h = case["system"], case["bounds"], case["h"]
    clock = time.perf_counter()
    fallback = IntervalObserver.design(system, bounds, h=h)
    bank = RobustFiniteMemoryObserver.learn(
        system, bounds, window=case["fir window"], size=size, h=h, fallback=fallback, selection=selection
    )
    return bank, time.perf_counter() - clock


def timed(observer: Any, t: np.ndarray, y: np.ndarray, u: np.ndarray, repeats: int = 1) -> tuple[Any, float]:
    """The observer's estimate and the CPU time of its online run in ms per step (fastest of ``repeats``)."""
    costs = []
    for _ in range(repeats):
        clock = time.process_time()
        est = observer.run(t, y, u)
        costs.append(1e3 * (time.process_time() - clock) / t.size)
    return est, min(costs)


def one_run(
    case: dict[str, Any], seed: int, vertex: bool, banks: dict[str, RobustFiniteMemoryObserver]
) -> dict[str, Any]:
    system, bounds, t, u, h = case["system"], case["bounds"], case["t"], case["u"], case["h"]
    lo, hi = system.dA
    rng = np.random.default_rng(1000 + seed)
    delta = np.where(rng.integers(0, 2, size=lo.shape) == 1, hi, lo) if vertex else rng.uniform(lo, hi)
    truth = LTISystem(system.A + delta, system.C, B=system.B, E=system.E, F=system.F, dt=system.dt)
    sim = simulate(truth, bounds, t, u=u, noise="extreme", seed=seed, substeps=10)
    robust = RobustHullEstimator.design(system, bounds, horizon=case["horizon"], h=h)
    est, robust_ms = timed(robust, t, sim.y, u)
    others = {
        "IntervalObserver": IntervalObserver.design(system, bounds, h=h),
        "IntersectionObserver": IntersectionObserver.design(system, bounds, h=h),
    }
    steps = np.arange(case["start"], t.size, case["stride"])
    candidates = np.concatenate([np.broadcast_to(delta, (t.size, 1, *delta.shape)), robust.extremal_deltas(t.size)], 1)
    clock = time.perf_counter()
    bound = robust_hull_lower_bound(system, bounds, t, sim.y, u, h=h, candidates=candidates, steps=steps)
    bound_s = time.perf_counter() - clock
    ref = np.sum(bound.width(), axis=-1)[steps]
    defined = np.isfinite(ref)
    row: dict[str, Any] = {"lower bound": float(np.mean(ref[defined])), "bound steps": int(defined.sum())}

    def width(e: Any) -> float:
        return float(np.mean(np.sum(e.upper - e.lower, axis=-1)[steps][defined]))

    def inside(e: Any) -> bool:
        return bool(
            np.all(e.lower[steps][defined] <= bound.lower[steps][defined])
            and np.all(e.upper[steps][defined] >= bound.upper[steps][defined])
        )

    def estimator(name: str, e: Any, ms: float) -> None:
        """Width, ratio, enclosure of the truth, whether the lower bound lies inside, cost of estimate ``e``."""
        row[f"{name} ms/step"] = ms
        row[name] = width(e)
        row[f"{name} ratio"] = row[name] / row["lower bound"]
        row[f"{name} enclosure"] = e.enclosure(sim.x).fraction
        row[f"{name} max violation"] = e.enclosure(sim.x).max_violation
        row[f"{name} lower bound inside"] = inside(e)

    row["RobustHullEstimator"] = width(est)
    row["ratio"] = row["RobustHullEstimator"] / row["lower bound"]
    row["enclosure"] = est.enclosure(sim.x).fraction
    row["max violation"] = est.enclosure(sim.x).max_violation
    row["lower bound inside"] = inside(est)
    row["RobustHullEstimator ms/step"] = robust_ms
    for name, bank in banks.items():
        estimator(name, *timed(bank, t, sim.y, u, repeats=3))
    if "mccormick horizon" in case:
        mccormick = RobustHullEstimator.design(
            system, bounds, horizon=case["mccormick horizon"], h=h, identify=False, mccormick=True
        )
        estimator("RobustHullEstimator McCormick", *timed(mccormick, t, sim.y, u))
    for name, obs in others.items():
        other, row[f"{name} ms/step"] = timed(obs, t, sim.y, u, repeats=3)
        row[name] = width(other)
        row[f"{name} ratio"] = row[name] / row["lower bound"]
    row["lower bound s"] = bound_s
    return row


def main() -> None:
    chosen = sys.argv[1:]
    out = Path(__file__).with_name("robust_tightness.json")
    results: dict[str, Any] = json.loads(out.read_text()) if out.exists() else {}
    for name, case in examples().items():
        if chosen and not any(c in name for c in chosen):
            continue
        per: dict[str, Any] = {
            k: case[k]
            for k in ("horizon", "stride", "start", "fir window", "fir size", "fir selection", "mccormick horizon")
            if k in case
        }
        per["clock"] = "CPU time (process_time)"
        banks = {"RobustFiniteMemoryObserver": None, **({SMALL: case["fir size"]} if "fir size" in case else {})}
        learned = {}
        for label, size in banks.items():
            learned[label], per[f"{label} learn s"] = learned_bank(case, size)
            per[f"{label} filters per component"] = learned[label].meta()["bank"]
        for vertex in (True, False):
            key = "ΔA at a vertex" if vertex else "ΔA at a random point"
            per[key] = {f"seed {seed}": one_run(case, seed, vertex, learned) for seed in SEEDS}
            for seed, row in per[key].items():
                print(name, key, seed, {k: round(v, 4) if isinstance(v, float) else v for k, v in row.items()})
        results[name] = per
        out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
