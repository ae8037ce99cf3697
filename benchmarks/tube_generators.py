"""Error-tube widths with the noise propagated as generators against the box of each step's noise (issue 33).

The same observers (same gains, same coordinates) on the same records, run by two versions of the library:
``--label box`` with the tube that boxes ``E·w`` and ``L·F·v`` before propagating them (the library before
this change: ``PYTHONPATH=<old checkout>/src``), ``--label generators`` with the current one. Each run merges
its mean widths into benchmarks/tube_generators.json; once both labels are there the file also holds the
ratios generators / box and the ratio of each to the exact hull of the whole record (point models only).

Cases: random discrete-time systems with a dense ``E`` (``n + 1`` noise channels) and several outputs,
with and without an interval ``ΔA``; two continuous-time ones; system (68) with the paper's gain, with the
zonotopic observer's gain (and that observer itself) and with the designed gain; the pedestrian and vehicle
of ``scale_cases``; the two published examples of tests/test_published_filtered_observer.py; the tightness
notebook's system. Widths: mean over the samples ``START …`` of the summed box width, i.i.d. vertex noise,
two seeds; every estimate is checked to enclose its truth. ``python benchmarks/tube_generators.py --label …``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from intervalobs import Bounds, IntervalObserver, LTISystem, simulate
from intervalobs.design.hinf import zonotope_size_gain
from intervalobs.examples import numerical3
from intervalobs.examples.scale_cases import pedestrian, vehicle
from intervalobs.observers.hull import HullEstimator
from intervalobs.observers.zonotopic import ZonotopicObserver

START = 30
STEPS = 150
SEEDS = (0, 1)
OUT = Path(__file__).with_suffix(".json")


def random_case(seed: int, n: int, p: int, uncertain: bool, continuous: bool = False) -> tuple[LTISystem, Bounds]:
    """A random stable system with a dense ``E`` of ``n + 1`` columns (``ΔA`` of 2 % of ``|A|`` when uncertain)."""
    rng = np.random.default_rng(100 + seed)
    A = rng.normal(size=(n, n))
    if continuous:
        A = A - (np.max(np.linalg.eigvals(A).real) + rng.uniform(0.3, 1.0)) * np.eye(n)
    else:
        A = A / np.max(np.abs(np.linalg.eigvals(A))) * rng.uniform(0.6, 0.95)
    dA = (-0.02 * np.abs(A), 0.02 * np.abs(A)) if uncertain else None
    E = rng.normal(size=(n, n + 1))
    system = LTISystem(A, rng.normal(size=(p, n)), E=E, dt=None if continuous else 1.0, dA=dA)
    ones_w, ones_v = 0.1 * np.ones(n + 1), 0.05 * np.ones(p)
    return system, Bounds((-np.ones(n), np.ones(n)), w=(-ones_w, ones_w), v=(-ones_v, ones_v))


def vertex_record(system: LTISystem, bounds: Bounds, t: np.ndarray, u: np.ndarray | None, seed: int) -> Any:
    """A truth with every noise component at a bound, drawn anew at every sample (and sub-step)."""
    return simulate(system, bounds, t, u=u, noise="vertex", seed=seed)


def mean_width(estimate: Any) -> float:
    return float(np.mean(np.sum(estimate.upper - estimate.lower, axis=-1)[START:]))


def measure(
    name: str, system: LTISystem, bounds: Bounds, observers: dict[str, Any], h: float | None, u_of: Any = None
) -> dict[str, Any]:
    """Mean widths of every observer (and of the exact hull for a point model) over the seeds' records."""
    t = np.arange(STEPS) * (h or float(system.dt or 1.0))
    u = None if u_of is None else u_of(t)
    rows: dict[str, list[float]] = {}
    for seed in SEEDS:
        sim = vertex_record(system, bounds, t, u, seed)
        if system.dA is None:
            hull = HullEstimator.design(system, bounds, h=h, horizon=None).run(t, sim.y, u)
            rows.setdefault("exact hull", []).append(mean_width(hull))
        for label, observer in observers.items():
            estimate = observer.run(t, sim.y, u)
            assert estimate.enclosure(sim.x).max_violation == 0.0, (name, label)
            rows.setdefault(label, []).append(mean_width(estimate))
    return {label: float(np.mean(values)) for label, values in rows.items()}


def cases() -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for seed, (n, p, uncertain) in enumerate([(3, 2, False), (4, 2, False), (5, 3, False), (3, 2, True), (4, 3, True)]):
        system, bounds = random_case(seed, n, p, uncertain)
        observer = IntervalObserver.design(system, bounds)
        key = f"random dt n={n} p={p}{' dA' if uncertain else ''}"
        out[key] = measure(key, system, bounds, {"tube (designed)": observer}, None)
    for seed, (n, p) in enumerate([(3, 2), (4, 2)]):
        system, bounds = random_case(10 + seed, n, p, False, continuous=True)
        observer = IntervalObserver.design(system, bounds, h=0.05)
        key = f"random ct n={n} p={p}"
        out[key] = measure(key, system, bounds, {"tube (designed)": observer}, 0.05)
    s = numerical3.system("68")
    system = LTISystem(s.A, s.C, B=s.B, E=s.E, F=s.F, dt=s.dt)
    bounds = numerical3.bounds()
    zono_gain = zonotope_size_gain(system.A, system.C, system.E, system.F, rho=0.9).gain
    out["(68)"] = measure(
        "(68)",
        system,
        bounds,
        {
            "tube (paper gain)": IntervalObserver(system, bounds, [[0.3], [0.2], [0.8]]),
            "tube (zonotopic observer's gain)": IntervalObserver(system, bounds, zono_gain),
            "zonotopic observer (its gain)": ZonotopicObserver(system, bounds, zono_gain),
            "tube (designed)": IntervalObserver.design(system, bounds),
        },
        None,
        numerical3.input_signal,
    )
    for case in (pedestrian(STEPS), vehicle(STEPS)):
        observers = {"tube (designed)": IntervalObserver.design(case.system, case.bounds)}
        out[case.name] = measure(case.name, case.system, case.bounds, observers, None, lambda t, c=case: c.u)
    out.update(published())
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -3.0, -3.0]])
    system = LTISystem(A, C=[[1.0, 0.0, 0.0]], B=[[0.0], [0.0], [1.0]])
    bounds = Bounds(x0=(-np.ones(3), np.ones(3)), w=(-0.05 * np.ones(3), 0.05 * np.ones(3)), v=([-0.02], [0.02]))
    observers = {"tube (designed)": IntervalObserver.design(system, bounds, h=0.02)}
    out["tightness notebook"] = measure("notebook", system, bounds, observers, 0.02, lambda t: np.sin(t)[:, None])
    return out


def published() -> dict[str, dict[str, Any]]:
    """The two examples of tests/test_published_filtered_observer.py with the designed tube."""
    sq = 0.25 * np.sqrt(2.0)
    examples = {
        "published two-state": ([[0.3, -0.7], [0.6, -0.5]], np.eye(2), [[1.0, 0.0]], 0.5, 0.1, 0.1),
        "published five-state": (
            [
                [-0.54, 0.45, 0.36, 0.0, 0.0],
                [0.63, 0.45, 0.18, 0.36, 0.0],
                [0.09, 0.45, 0.27, 0.09, 0.18],
                [0.0, 0.0, 0.25, sq, -sq],
                [0.0, 0.0, 0.0, sq, -sq],
            ],
            [[-1.0], [0.0], [0.0], [0.0], [1.0]],
            [[1.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0, 0.0]],
            1.0,
            0.1,
            1.0,
        ),
    }
    out = {}
    for key, (A, E, C, w, v, prior) in examples.items():
        system = LTISystem(A, C, E=E, dt=1.0)
        n, q = system.n, system.nw
        bounds = Bounds(x0=(-prior * np.ones(n), prior * np.ones(n)), w=(-w * np.ones(q), w * np.ones(q)), v=(-v, v))
        out[key] = measure(key, system, bounds, {"tube (designed)": IntervalObserver.design(system, bounds)}, None)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--label", choices=("box", "generators"), required=True)
    label = parser.parse_args().label
    stored = json.loads(OUT.read_text()) if OUT.exists() else {}
    stored[label] = cases()
    if "box" in stored and "generators" in stored:
        ratios: dict[str, dict[str, Any]] = {}
        for case, widths in stored["generators"].items():
            before = stored["box"][case]
            hull = widths.get("exact hull")
            ratios[case] = {
                observer: {
                    "generators / box": round(width / before[observer], 4),
                    **({} if hull is None else {"box / hull": round(before[observer] / hull, 4)}),
                    **({} if hull is None else {"generators / hull": round(width / hull, 4)}),
                }
                for observer, width in widths.items()
                if observer != "exact hull"
            }
        stored["ratios"] = ratios
    OUT.write_text(json.dumps(stored, indent=1) + "\n")
    print(json.dumps(stored.get("ratios", stored[label]), indent=1))


if __name__ == "__main__":
    main()
