"""RobustFiniteMemoryObserver: sound under interval ΔA against an independent truth (vertices and random
points of the box, bang-bang noise switching inside the sampling steps), never wider than the
IntervalObserver it is intersected with, run == step, and the point-model bank when the box is a point."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds, IntervalObserver, LTISystem, simulate
from intervalobs.errors import AssumptionError, DataError
from intervalobs.observers.fir import FiniteMemoryObserver
from intervalobs.observers.robust_fir import RobustFiniteMemoryObserver
from intervalobs.observers.robust_hull import RobustHullEstimator
from test_robust_hull import H_CONTINUOUS, STEPS, random_system, record

CASES = [(seed, continuous, vertex) for seed in (1, 2, 3) for continuous in (False, True) for vertex in (True, False)]


@pytest.mark.parametrize(
    ("seed", "continuous", "vertex"),
    CASES,
    ids=[f"seed{s}-{'ct' if c else 'dt'}-{'vertex' if v else 'random'}" for s, c, v in CASES],
)
def test_sound_and_never_wider_than_the_interval_observer(seed: int, continuous: bool, vertex: bool) -> None:
    system, bounds = random_system(seed, continuous)
    t, u, sim, _ = record(system, bounds, seed, vertex)
    h = H_CONTINUOUS if continuous else None
    interval = IntervalObserver.design(system, bounds, h=h)
    base = interval.run(t, sim.y, u)
    robust = RobustFiniteMemoryObserver.learn(system, bounds, window=6, records=2, steps=30, h=h, fallback=interval)
    estimate = robust.run(t, sim.y, u)
    assert estimate.enclosure(sim.x).max_violation == 0.0
    assert np.all(estimate.lower >= base.lower) and np.all(estimate.upper <= base.upper)
    # The bank is what makes it narrow: strictly narrower than the interval observer after the window.
    assert np.mean(estimate.width()[6:]) < np.mean(base.width()[6:])
    # The window LP on the same data is sound as well (and is not wider than the interval observer either).
    hull = RobustHullEstimator.design(system, bounds, horizon=6, h=h, fallback=interval).run(t, sim.y, u)
    assert hull.enclosure(sim.x).max_violation == 0.0
    assert np.all(hull.lower >= base.lower) and np.all(hull.upper <= base.upper)


def test_several_runs_at_once_are_sound_and_equal_to_one_run_at_a_time() -> None:
    system, bounds = random_system(4, continuous=False)
    records = [record(system, bounds, seed, vertex=seed % 2 == 0) for seed in range(3)]
    t, u = records[0][0], records[0][1]
    robust = RobustFiniteMemoryObserver.design(system, bounds, window=5)
    batch = robust.run(t, np.stack([r[2].y for r in records]), u)
    for i, (_, _, sim, _) in enumerate(records):
        single = robust.run(t, sim.y, u)
        assert single.enclosure(sim.x).max_violation == 0.0
        np.testing.assert_allclose(batch.lower[i], single.lower, rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.upper[i], single.upper, rtol=0, atol=1e-12)


def test_step_and_run_agree() -> None:
    system, bounds = random_system(2, continuous=True)
    t, u, sim, _ = record(system, bounds, 2, vertex=False)
    robust = RobustFiniteMemoryObserver.learn(system, bounds, window=5, records=1, steps=20, h=H_CONTINUOUS)
    estimate = robust.run(t, sim.y, u)
    state = robust.init()
    for k in range(STEPS - 1):
        state = robust.step(state, sim.y[k], u[k])
        np.testing.assert_allclose(state.lower, estimate.lower[k + 1], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.upper, estimate.upper[k + 1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("continuous", [False, True], ids=["discrete", "continuous"])
def test_a_model_without_inputs(continuous: bool) -> None:
    """m = 0 (no known input): sound at a vertex of the ΔA box and never wider than the IntervalObserver."""
    system, bounds = random_system(2, continuous)
    free = LTISystem(system.A, system.C, E=system.E, dt=system.dt, dA=system.dA)
    assert free.dA is not None
    vertex = np.where(np.random.default_rng(5).integers(0, 2, size=system.A.shape) == 1, free.dA[1], free.dA[0])
    t = np.arange(STEPS) * (H_CONTINUOUS if continuous else 1.0)
    truth = LTISystem(system.A + vertex, system.C, E=system.E, dt=system.dt)
    sim = simulate(truth, bounds, t, noise="extreme", seed=5)
    h = H_CONTINUOUS if continuous else None
    interval = IntervalObserver.design(free, bounds, h=h)
    robust = RobustFiniteMemoryObserver.learn(free, bounds, window=5, records=1, steps=20, h=h, fallback=interval)
    estimate, base = robust.run(t, sim.y), interval.run(t, sim.y)
    assert estimate.enclosure(sim.x).max_violation == 0.0
    assert np.all(estimate.lower >= base.lower) and np.all(estimate.upper <= base.upper)


def test_a_point_box_gives_the_point_model_bank() -> None:
    """With ΔA = 0 (a degenerate box) the ΔA terms vanish: the numbers of FiniteMemoryObserver, same weights."""
    system, bounds = random_system(0, continuous=False)
    zero = np.zeros((system.n, system.n))
    point = LTISystem(system.A, system.C, B=system.B, E=system.E, dt=1.0)
    degenerate = LTISystem(system.A, system.C, B=system.B, E=system.E, dt=1.0, dA=(zero, zero))
    t, u, sim, _ = record(system, bounds, 0, vertex=True)
    fallback = IntervalObserver.design(point, bounds)
    gains = FiniteMemoryObserver.learn(point, bounds, window=5, records=1, steps=20, fallback=fallback).K
    learned = FiniteMemoryObserver(point, bounds, gains, fallback)  # the full windows' bank only, like robust
    robust = RobustFiniteMemoryObserver(degenerate, bounds, gains, fallback)
    np.testing.assert_allclose(robust.run(t, sim.y, u).lower, learned.run(t, sim.y, u).lower, rtol=0, atol=1e-12)
    np.testing.assert_allclose(robust.run(t, sim.y, u).upper, learned.run(t, sim.y, u).upper, rtol=0, atol=1e-12)


def test_errors_name_the_argument() -> None:
    system, bounds = random_system(0, continuous=False)
    point = LTISystem(system.A, system.C, B=system.B, E=system.E, dt=1.0)
    with pytest.raises(AssumptionError, match=r"^system.dA: expected an interval"):
        RobustFiniteMemoryObserver.design(point, bounds)
    with pytest.raises(DataError, match=r"^state_size: expected"):
        RobustFiniteMemoryObserver.design(system, bounds, state_size=[1.0])
    with pytest.raises(AssumptionError, match=r"point models only"):
        FiniteMemoryObserver.design(system, bounds)
    assert isinstance(bounds, Bounds)
