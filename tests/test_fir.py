"""FiniteMemoryObserver: soundness, evaluated radius, never wider than its fallback, errors."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import AssumptionError, Bounds, IntervalObserver, LTISystem, simulate
from intervalobs.errors import IntervalObserverError
from intervalobs.observers.fir import FiniteMemoryObserver

STEPS = 60
A68 = np.array([[0.8, 0.1, 0.3], [0.0, 0.8, 0.2], [0.01, 0.0, 0.8]])


def small_discrete() -> tuple[LTISystem, Bounds]:
    system = LTISystem(A68, [[0.0, 0.0, 1.0]], B=[[0.0], [0.0], [1.0]], E=0.08 * np.eye(3), F=[[0.2]], dt=1.0)
    bounds = Bounds((-np.ones(3), np.ones(3)), w=(-np.ones(3), np.ones(3)), v=(-np.ones(1), np.ones(1)))
    return system, bounds


def wide_fallback(system: LTISystem, bounds: Bounds) -> IntervalObserver:
    """An open-loop framer (L = 0): sound but wide, so the filter's own box is what is tested."""
    return IntervalObserver(system, bounds, np.zeros((3, 1)), method="framer")


@pytest.fixture(scope="module")
def observers() -> dict[str, FiniteMemoryObserver]:
    system, bounds = small_discrete()
    return {
        "default": FiniteMemoryObserver.design(system, bounds, window=30),
        "wide": FiniteMemoryObserver.design(system, bounds, window=30, fallback=wide_fallback(system, bounds)),
    }


def vertex_record(system: LTISystem, bounds: Bounds, t: np.ndarray, u: np.ndarray, seed: int, runs: int) -> object:
    rng = np.random.default_rng(seed)
    w = rng.choice([-1.0, 1.0], size=(runs, t.size, 3))
    v = rng.choice([-1.0, 1.0], size=(runs, t.size, 1))
    return simulate(system, bounds, t, u=u, noise={"w": w, "v": v}, seed=seed, runs=runs)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("noise", ["extreme", "vertex"])
def test_encloses_truth(observers: dict[str, FiniteMemoryObserver], seed: int, noise: str) -> None:
    system, bounds = small_discrete()
    t = np.arange(STEPS, dtype=float)
    u = np.sin(t)[:, None]
    if noise == "extreme":
        sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed, runs=20)
    else:
        sim = vertex_record(system, bounds, t, u, seed, 20)
    for name, obs in observers.items():
        est = obs.run(t, sim.y, u)  # type: ignore[attr-defined]
        report = est.enclosure(sim.x)  # type: ignore[attr-defined]
        assert report.max_violation == 0.0 and report.fraction == 1.0, name
        base = obs.fallback.run(t, sim.y, u)  # type: ignore[attr-defined]
        assert np.all(est.lower >= base.lower) and np.all(est.upper <= base.upper), name
    # With the open-loop fallback the filter's own box is active (strictly tighter after N steps).
    wide = observers["wide"]
    est = wide.run(t, sim.y, u)  # type: ignore[attr-defined]
    base = wide.fallback.run(t, sim.y, u)  # type: ignore[attr-defined]
    assert np.all((est.upper - est.lower)[:, 40:] < (base.upper - base.lower)[:, 40:])


def test_radius_is_the_evaluated_worst_case(observers: dict[str, FiniteMemoryObserver]) -> None:
    obs = observers["default"]
    K, N = obs.K, obs.window
    C, F = obs.system.C, obs.system.F
    r = 0.08 * np.ones(3)
    powers = [np.linalg.matrix_power(A68, j) for j in range(N + 1)]
    total = np.zeros(3)
    for i in range(3):
        for l_ in range(N):
            d = powers[N - 1 - l_][i] - sum(K[i, j] @ C @ powers[j - 1 - l_] for j in range(l_ + 1, N))
            total[i] += np.abs(d) @ r
        total[i] += np.sum(np.abs(K[i] @ F)) * 1.0
    # The model's noise radius is rounded up by 1e-12 and the evaluation by a few ulps: never below.
    assert np.allclose(obs.radius, total, rtol=1e-10, atol=0)
    assert np.all(obs.radius >= total)
    assert obs.meta()["residual"] < 1e-8
    # Window 80 reaches the worst-case hull of (68) (sup of observed hull widths ≈ [1.99, 1.20, 0.50]).
    system, bounds = small_discrete()
    long = FiniteMemoryObserver.design(system, bounds, window=80)
    assert np.all(2 * long.radius < np.array([2.01, 1.21, 0.51]))


def test_run_matches_repeated_step(observers: dict[str, FiniteMemoryObserver]) -> None:
    system, bounds = small_discrete()
    t = np.arange(45, dtype=float)
    u = np.sin(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=4, runs=3)
    for obs in observers.values():
        est = obs.run(t, sim.y, u)
        state = obs.init()
        lower, upper = [np.broadcast_to(state.lower, (3, 3))], [np.broadcast_to(state.upper, (3, 3))]
        for k in range(t.size - 1):
            state = obs.step(state, sim.y[:, k], np.broadcast_to(u[k], (3, 1)))
            lower.append(np.broadcast_to(state.lower, (3, 3)))
            upper.append(np.broadcast_to(state.upper, (3, 3)))
        assert np.max(np.abs(np.stack(lower, axis=1) - est.lower)) < 1e-12
        assert np.max(np.abs(np.stack(upper, axis=1) - est.upper)) < 1e-12


def test_errors() -> None:
    system, bounds = small_discrete()
    d = 0.01 * np.ones((3, 3))
    uncertain = LTISystem(A68, system.C, B=system.B, E=system.E, F=system.F, dt=1.0, dA=(-d, d))
    with pytest.raises(AssumptionError, match="point models only"):
        FiniteMemoryObserver.design(uncertain, bounds, window=10)
    for bad in (0, -3, 2.5, True):
        with pytest.raises(IntervalObserverError, match="window"):
            FiniteMemoryObserver.design(system, bounds, window=bad)  # type: ignore[arg-type]
    obs = FiniteMemoryObserver.design(system, bounds, window=5)
    with pytest.raises(IntervalObserverError):
        obs.run(np.arange(10.0), np.full((10, 1), np.nan))
    with pytest.raises(IntervalObserverError):
        obs.step(obs.init(), [1.0, 2.0])
    with pytest.raises(IntervalObserverError):
        FiniteMemoryObserver(system, bounds, np.zeros((3, 4, 2)), obs.fallback)
