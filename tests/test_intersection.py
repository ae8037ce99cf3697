"""IntersectionObserver: sound, never wider than its members, run == step; the output contractor."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import random_system
from intervalobs import IntervalObserver, simulate
from intervalobs.errors import DataError
from intervalobs.observers.intersection import IntersectionObserver, output_contraction


@pytest.mark.parametrize(
    "seed, continuous, uncertain",
    [(0, False, False), (1, False, True), (2, True, False), (3, True, True)],
    ids=["discrete", "discrete-dA", "continuous", "continuous-dA"],
)
def test_intersection_is_sound_and_never_wider_than_members(seed: int, continuous: bool, uncertain: bool) -> None:
    system, bounds = random_system(seed, 3, 1, continuous, uncertain)
    h = 0.05 if continuous else None
    t = np.arange(60) * (h or 1.0)
    members = [
        IntervalObserver.design(system, bounds, h=h, method="framer"),
        IntervalObserver.design(system, bounds, h=h),
    ]
    obs = IntersectionObserver(members, system, bounds)
    sim = simulate(system, bounds, t, noise="extreme", seed=seed, runs=4)
    est = obs.run(t, sim.y)
    assert est.enclosure(sim.x).max_violation == 0.0
    for member in members:
        alone = member.run(t, sim.y)
        tol = 1e-9 * (1.0 + np.abs(alone.lower) + np.abs(alone.upper))  # rounding margin of a restart
        assert np.all(est.lower >= alone.lower - tol) and np.all(est.upper <= alone.upper + tol)


def test_designed_intersection_is_sound_and_tighter() -> None:
    system, bounds = random_system(4, 3, 1, continuous=False, uncertain=False)
    t = np.arange(80, dtype=float)
    obs = IntersectionObserver.design(system, bounds)
    sim = simulate(system, bounds, t, noise="extreme", seed=11, runs=3)
    est = obs.run(t, sim.y)
    assert est.enclosure(sim.x).max_violation == 0.0
    single = obs.members[0].run(t, sim.y)
    assert np.sum(est.width()) <= np.sum(single.width())


def test_run_matches_repeated_step() -> None:
    system, bounds = random_system(5, 3, 2, continuous=False, uncertain=True)
    t = np.arange(20, dtype=float)
    obs = IntersectionObserver([IntervalObserver.design(system, bounds, method="framer")], system, bounds, sweeps=2)
    sim = simulate(system, bounds, t, noise="extreme", seed=3)
    est = obs.run(t, sim.y)
    state = obs.init()
    for k in range(t.size):
        np.testing.assert_allclose(state.lower, est.lower[k], atol=1e-12)
        np.testing.assert_allclose(state.upper, est.upper[k], atol=1e-12)
        state = obs.step(state, sim.y[k])


def test_output_contraction_is_the_exact_hull_of_one_strip() -> None:
    rng = np.random.default_rng(0)
    c = np.array([[1.0, -2.0, 0.5]])
    lo, hi = -np.ones(3), np.ones(3)
    new_lo, new_hi = output_contraction(lo, hi, c, np.array([1.5]), np.array([2.0]))
    points = rng.uniform(lo, hi, size=(200_000, 3))
    inside = points[(points @ c[0] >= 1.5) & (points @ c[0] <= 2.0)]
    assert np.all(inside >= new_lo) and np.all(inside <= new_hi)
    from scipy.optimize import linprog

    a_ub = np.vstack([c, -c])
    b_ub = np.array([2.0, -1.5])
    for j in range(3):
        for sign, end in ((1.0, new_lo[j]), (-1.0, new_hi[j])):
            cost = np.zeros(3)
            cost[j] = sign
            res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(-1, 1)] * 3, method="highs")
            assert sign * end <= res.fun + 1e-12  # sound
            assert sign * end >= res.fun - 1e-9  # exact for one row
    with pytest.raises(DataError, match="inconsistent"):
        output_contraction(lo, hi, c, np.array([10.0]), np.array([11.0]))
