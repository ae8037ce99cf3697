"""Width ratios of the continuous-time nonlinear estimators to a consistent-set lower bound, every case (issue 32).

For each of the four soundness cases of ``tests/nonlinear_cases.py`` (the chemostat in reaction-invariant
coordinates, the exothermic CSTR, the damped pendulum and the six compartments), disturbance-free (the ``w`` box
zero, so the states are fixed by the start and the parameters), one record of ``CASES[name]`` samples from a truth
at a vertex or inside the boxes (the tests' ``simulate_truth``), with noise at a random sign and ``NOISE_DEPTH``
of the noise bound (see ``NOTES``):

* the **reference**, an *inner hull* of the consistent set: the hull of trajectories simulated exactly (classical
  RK4, ``REFERENCE_SUBSTEPS`` steps per sample, vectorised over trajectories from the case's own point field
  ``rates``; nothing of the library) from starts and parameters of their boxes that satisfy every sample, found by
  sequential linear programming from the truth towards the largest and smallest value of every state at
  ``REFERENCE_TIMES`` times of the record's second half (the chemostat reproduction's ``consistent_inner_hull``,
  generalised), then by an adaptive Gaussian random walk (``WALK_CHAINS`` chains, ``WALK_STEPS`` steps, the
  proposal shaped by the consistent points found so far). Only exactly simulated, checked trajectories are kept,
  so it is a lower bound of the hull of the consistent set and every sound estimator's width is at least its own;
* one zonotope (``ContinuousNonlinearObserver``), the bundle (``refine=BUNDLE_PARTS``) and the
  ``SetInversionSmoother`` (smoothed rows; options of ``CASES``): mean width of every state over the record's
  second half, its ratio to the reference's (asserted >= 1), enclosure of the truth (asserted 1.0) and CPU ms per
  sample (``time.process_time``, after a warm-up run that loads the compiled kernels).

Writes ``benchmarks/nonlinear_tightness.json``; about four minutes on one core (``OPENBLAS_NUM_THREADS=1``).

Run with ``python benchmarks/nonlinear_tightness.py [CASE ...]`` (a subset rewrites only those entries).
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import linprog

from intervalobs import Bounds, ContinuousNonlinearObserver
from intervalobs.observers.set_inversion import SetInversionSmoother
from intervalobs.reproduce.chemostat import SMOOTHER_OPTIONS

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from nonlinear_cases import Case, chemostat_bundle, compartments, cstr, pendulum, simulate_truth

OUT = Path(__file__).with_name("nonlinear_tightness.json")
BUNDLE_PARTS = 64
"""Most parts of the bundle run."""
NOISE_DEPTH = (0.5, 1.0)
"""The noise of a sample: a random sign times a uniform fraction in this range of the noise bound (see ``NOTES``)."""
REFERENCE_SUBSTEPS = 20
"""RK4 steps per sample of the reference's trajectories."""
REFERENCE_TIMES, REFERENCE_ROUNDS = 5, 8
"""Times of the second half whose extreme states are sought, and linearisations per goal."""
STEP_FRACTIONS = (1.0, 0.8, 0.6, 0.45, 0.3, 0.2, 0.1, 0.05, 0.02, 0.01)
"""Fractions of the way to a linear programme's target tried by exact simulation (the farthest consistent is kept)."""
DIFFERENCE = 1e-6
"""Forward-difference step of the sensitivities, per unit of each box width."""
WALK_CHAINS, WALK_STEPS = 64, 100
"""Chains and steps of the random walk."""
SEED = 0
WARM_SMOOTHER = 20
"""Samples of the smoother's warm-up run (the observers' is the whole record)."""

CASES: dict[str, dict[str, Any]] = {
    "chemostat": {
        "make": chemostat_bundle,
        "t_final": 12.0,
        "x0": [5.95, 0.35],
        "p": [0.51, 0.29],
        "input": None,
        "smoother": dict(SMOOTHER_OPTIONS),
    },
    "cstr": {"make": cstr, "t_final": 8.0, "x0": [0.15, 0.5], "p": [0.07], "input": None, "smoother": {}},
    "pendulum": {
        "make": pendulum,
        "t_final": 5.0,
        "x0": [0.6, -0.2],
        "p": [0.45],
        "input": 0.3,
        "smoother": {"substeps": 32, "order": 24, "reduction": "frame"},
    },
    "compartments": {
        "make": compartments,
        "t_final": 8.0,
        "x0": [0.5] * 6,
        "p": [1.05],
        "input": 0.3,
        "smoother": {},
    },
}
"""Record length, truth (start, parameters), held input and the smoother's options of every case."""

NOTES = [
    "Disturbance-free cases (w box zero): the consistent set is a set of (x0, p); the reference is the hull of "
    "exactly simulated (RK4) trajectories from (x0, p) in their boxes that satisfy every sample, an inner hull "
    "(lower bound) of the consistent set's hull, so every sound estimator's ratio is >= 1.",
    "The filtered rows (one zonotope, bundle) are compared with a reference given the whole record: a filter's row "
    "k knows samples 0..k only and cannot reach it; the smoother's rows are given the whole record as the reference.",
    "Noise: random sign times a uniform fraction in NOISE_DEPTH of the bound, not the tests' bang-bang measure() at "
    "the bound's ends: with noise exactly at the ends the truth touches every sample's constraint from the side its "
    "noise sign gives, so the consistent set is (to first order) the truth alone and every ratio would be infinite.",
    "Widths are means over the record's second half; ms_per_sample is CPU time (time.process_time) of one run after "
    "a warm-up on the first samples; the smoother's includes its bisection rounds.",
]


def still(case: Case) -> Case:
    """The case without its disturbance (its box zero)."""
    b = case.bounds.resolve(case.system)
    zeros = np.zeros(case.system.nw)
    return dataclasses.replace(case, bounds=Bounds(x0=b.x0, v=b.v, p=b.p, w=(zeros, zeros)))


class Reference:
    """Exact simulation of many (x0, p) at once and the consistency check against a record."""

    def __init__(self, case: Case, t: np.ndarray, u: np.ndarray, y: np.ndarray) -> None:
        b = case.bounds.resolve(case.system)
        self.case, self.t, self.u, self.y = case, t, u, y
        self.n = case.system.n
        self.low = np.concatenate([b.x0[0], b.p[0]])
        self.high = np.concatenate([b.x0[1], b.p[1]])
        self.scale = self.high - self.low
        self.size = self.low.size
        self.out_low, self.out_high = y - b.v[1], y - b.v[0]
        self.w = np.zeros((case.system.nw, 1))
        self.count = 0
        self.lower = np.full((t.size, self.n), np.inf)
        self.upper = np.full((t.size, self.n), -np.inf)

    def simulate(self, s: np.ndarray) -> np.ndarray:
        """Trajectories (N, T, n) from normalised points ``s`` (N, size) of the box (RK4, fixed step)."""
        theta = self.low + s * self.scale
        x, p = theta[:, : self.n].T.copy(), theta[:, self.n :].T.copy()
        dt = (self.t[1] - self.t[0]) / REFERENCE_SUBSTEPS
        out = [x.copy()]
        with np.errstate(all="ignore"):
            for k in range(self.t.size - 1):

                def rates(z: np.ndarray, held: np.ndarray = self.u[k]) -> np.ndarray:
                    field = self.case.rates(z, held, p, self.w)
                    return np.broadcast_to(field, z.shape)

                for _ in range(REFERENCE_SUBSTEPS):
                    k1 = rates(x)
                    k2 = rates(x + 0.5 * dt * k1)
                    k3 = rates(x + 0.5 * dt * k2)
                    k4 = rates(x + dt * k3)
                    x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
                out.append(x.copy())
        return np.stack(out).transpose(2, 0, 1)

    def consistent(self, paths: np.ndarray) -> np.ndarray:
        """Which trajectories satisfy every sample (finite, within the noise bounds)."""
        g = paths[..., self.case.outputs]
        inside = (g >= self.out_low) & (g <= self.out_high)
        return np.all(inside, axis=(-2, -1)) & np.all(np.isfinite(paths), axis=(-2, -1))

    def keep(self, s: np.ndarray) -> np.ndarray:
        """Simulate, check, widen the hull by the consistent ones; which were consistent."""
        inside = np.all((s >= 0.0) & (s <= 1.0), axis=-1)
        good = np.zeros(s.shape[0], dtype=bool)
        if inside.any():
            paths = self.simulate(s[inside])
            ok = self.consistent(paths)
            good[np.flatnonzero(inside)[ok]] = True
            if ok.any():
                self.count += int(ok.sum())
                self.lower = np.minimum(self.lower, paths[ok].min(axis=0))
                self.upper = np.maximum(self.upper, paths[ok].max(axis=0))
        return good

    def pushes(self, truth: np.ndarray) -> np.ndarray:
        """Sequential linear programming from the truth to every state's extremes: the consistent points reached."""
        t = self.t
        times = np.searchsorted(t, np.linspace(0.5 * t[-1], t[-1], REFERENCE_TIMES))
        goals = [(state, index, sign) for state in range(self.n) for index in times for sign in (1.0, -1.0)]
        points = np.repeat(truth[None, :], len(goals), axis=0)
        found = [truth[None, :]]
        fractions = np.asarray(STEP_FRACTIONS)[:, None]
        for _ in range(REFERENCE_ROUNDS):
            targets = self._linearised_extremes(points, goals)
            trials = points[:, None, :] + fractions * (targets - points)[:, None, :]
            good = self.keep(trials.reshape(-1, self.size)).reshape(len(goals), fractions.size)
            found.append(trials[good])
            farthest = np.argmax(good, axis=1)
            points = np.where(np.any(good, axis=1)[:, None], trials[np.arange(len(goals)), farthest], points)
        return np.concatenate(found)

    def _linearised_extremes(self, points: np.ndarray, goals: list[tuple[int, int, float]]) -> np.ndarray:
        """For each goal, the maximiser of its linearisation over the linearised consistent set and the box."""
        probes = points[:, None, :] + np.concatenate([np.zeros((1, self.size)), DIFFERENCE * np.eye(self.size)])[None]
        paths = self.simulate(probes.reshape(-1, self.size)).reshape(len(goals), self.size + 1, self.t.size, self.n)
        base, sensitivity = paths[:, 0], (paths[:, 1:] - paths[:, :1]) / DIFFERENCE
        outputs = self.case.outputs
        targets = points.copy()
        for g, (state, index, sign) in enumerate(goals):
            rows = sensitivity[g][..., outputs].transpose(1, 2, 0).reshape(-1, self.size)
            now = base[g][:, outputs].reshape(-1)
            room = np.concatenate([self.out_high.reshape(-1) - now, now - self.out_low.reshape(-1)])
            if not np.all(np.isfinite(rows)):
                continue
            solution = linprog(
                -sign * sensitivity[g, :, index, state],
                A_ub=np.vstack([rows, -rows]),
                b_ub=np.maximum(room, 0.0),
                bounds=list(zip(-points[g], 1.0 - points[g])),
                method="highs",
            )
            if solution.status == 0:
                targets[g] = np.clip(points[g] + solution.x, 0.0, 1.0)
        return targets

    def walk(self, starts: np.ndarray, rng: np.random.Generator) -> dict[str, Any]:
        """Adaptive Gaussian random walk inside the consistent set, chains started at consistent points."""
        spread = np.cov(starts.T) if starts.shape[0] > self.size else np.eye(self.size) * 1e-6
        factor = np.linalg.cholesky(np.atleast_2d(spread) + 1e-12 * np.eye(self.size))
        chains = starts[rng.integers(starts.shape[0], size=WALK_CHAINS)]
        step = np.full(WALK_CHAINS, 0.5)
        accepted = 0
        for _ in range(WALK_STEPS):
            trial = chains + step[:, None] * (rng.standard_normal((WALK_CHAINS, self.size)) @ factor.T)
            good = self.keep(trial)
            chains = np.where(good[:, None], trial, chains)
            step = np.where(good, step * 1.3, step * 0.85)
            accepted += int(good.sum())
        return {"steps": WALK_STEPS * WALK_CHAINS, "acceptance": accepted / (WALK_STEPS * WALK_CHAINS)}


def estimator_entry(
    estimate: Any, seconds: float, x: np.ndarray, half: np.ndarray, inner: np.ndarray, options: dict[str, Any]
) -> dict[str, Any]:
    """Widths over the second half, ratios to the reference, enclosure and cost of one estimator's run."""
    width = (estimate.upper - estimate.lower)[half].mean(axis=0)
    ratio = width / inner
    enclosure = float(np.mean((estimate.lower <= x) & (x <= estimate.upper)))
    assert enclosure == 1.0, (options, enclosure)
    assert np.all(ratio >= 1.0), (options, ratio)
    return {
        "options": options,
        "mean_width_second_half": width.tolist(),
        "ratio": ratio.tolist(),
        "enclosure": enclosure,
        "ms_per_sample": 1000.0 * seconds / x.shape[0],
    }


def timed(make: Callable[[], Any], t: np.ndarray, y: np.ndarray, u: np.ndarray, warm: int) -> tuple[Any, float]:
    """One run after a warm-up on the first ``warm`` samples: the estimate and its CPU seconds."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        make().run(t[:warm], y[:warm], u[:warm])  # the compiled kernels loaded (or compiled) first
        estimator = make()
        clock = time.process_time()
        estimate = estimator.run(t, y, u)
        return estimate, time.process_time() - clock


def run_case(name: str) -> dict[str, Any]:
    """The record, the reference and the three estimators of one case."""
    spec = CASES[name]
    case = still(spec["make"]())
    system, bounds, h = case.system, case.bounds, case.h
    rng = np.random.default_rng(SEED)
    t = np.arange(0.0, spec["t_final"] + 1e-9, h)
    u = np.full((t.size, system.m), spec["input"] or 0.0, dtype=float)
    x0, p = np.asarray(spec["x0"], dtype=float), np.asarray(spec["p"], dtype=float)
    x = simulate_truth(case, x0, p, t, u, seed=SEED)
    b = bounds.resolve(system)
    depth = rng.uniform(*NOISE_DEPTH, size=(t.size, len(case.outputs)))
    y = x[:, case.outputs] + np.where(rng.random(depth.shape) < 0.5, b.v[0], b.v[1]) * depth
    half = t >= 0.5 * t[-1]

    clock = time.process_time()
    reference = Reference(case, t, u, y)
    truth = (np.concatenate([x0, p]) - reference.low) / reference.scale
    assert reference.keep(truth[None, :])[0], "the truth is not consistent with its own record"
    pushed = reference.pushes(truth)
    slp_width = (reference.upper - reference.lower)[half].mean(axis=0)
    walk = reference.walk(pushed, rng)
    inner = (reference.upper - reference.lower)[half].mean(axis=0)
    reference_seconds = time.process_time() - clock
    assert np.all(reference.lower <= x + 1e-9) and np.all(x <= reference.upper + 1e-9)

    estimators: dict[str, Any] = {}
    estimate, seconds = timed(lambda: ContinuousNonlinearObserver(system, bounds, h), t, y, u, t.size)
    estimators["zonotope"] = estimator_entry(estimate, seconds, x, half, inner, {})
    estimate, seconds = timed(
        lambda: ContinuousNonlinearObserver(system, bounds, h, refine=BUNDLE_PARTS), t, y, u, t.size
    )
    estimators["bundle"] = estimator_entry(estimate, seconds, x, half, inner, {"refine": BUNDLE_PARTS})
    options = spec["smoother"]
    estimate, seconds = timed(lambda: SetInversionSmoother(system, bounds, h, **options), t, y, u, WARM_SMOOTHER)
    estimators["smoother"] = estimator_entry(estimate, seconds, x, half, inner, dict(options))
    estimators["smoother"]["rounds"] = len(estimate.meta["rounds"])
    estimators["smoother"]["parts"] = estimate.meta["parts"]
    return {
        "samples": int(t.size),
        "h": h,
        "states": list(system.state_names) if system.state_names else None,
        "truth": {"x0": x0.tolist(), "p": p.tolist(), "input": spec["input"]},
        "reference": {
            "mean_width_second_half": inner.tolist(),
            "slp_only_mean_width_second_half": slp_width.tolist(),
            "consistent_trajectories": reference.count,
            "walk": walk,
            "cpu_s": reference_seconds,
        },
        "estimators": estimators,
    }


def main() -> None:
    names = sys.argv[1:] or list(CASES)
    results = json.loads(OUT.read_text()) if OUT.exists() else {}
    results["notes"] = NOTES
    results.setdefault("cases", {})
    for name in names:
        clock = time.process_time()
        entry = run_case(name)
        entry["cpu_s"] = time.process_time() - clock
        results["cases"][name] = entry
        print(name, json.dumps(entry, default=float), flush=True)
        OUT.write_text(json.dumps(results, indent=1, default=float) + "\n")


if __name__ == "__main__":
    main()
