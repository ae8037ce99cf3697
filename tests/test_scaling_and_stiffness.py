"""Badly scaled and stiff models: the same bounds in any units, designs in bounded time, no NaN.

The truths come from ``simulate`` (exact matrix exponentials, noise at the vertices of its boxes); the
rescaled model ``z = D x`` is built here from the original one, and its boxes are mapped back by ``1 / D``.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import intervalobs as io
from intervalobs.systems.balancing import balanced, state_scales


def _random_system(seed: int, n: int = 4, p: int = 2) -> io.LTISystem:
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    A *= 0.8 / max(abs(np.linalg.eigvals(A)))
    return io.LTISystem(A, rng.normal(size=(p, n)), dt=1.0)


def _rescaled(system: io.LTISystem, D: np.ndarray) -> io.LTISystem:
    return io.LTISystem(D[:, None] * system.A / D, system.C / D, E=np.diag(D), dt=system.dt)


BUILDERS = {
    "observer": lambda s, b: io.IntervalObserver.design(s, b),
    "hull": lambda s, b: io.HullEstimator.design(s, b, horizon=10),
}


@pytest.mark.parametrize("spread", [3, 6], ids=["1e3", "1e6"])
@pytest.mark.parametrize("name", sorted(BUILDERS))
def test_bounds_do_not_depend_on_the_units(name: str, spread: int) -> None:
    system = _random_system(3)
    n = system.n
    bounds = io.Bounds(x0=(-np.ones(n), np.ones(n)), w=(-0.05, 0.05), v=(-0.05, 0.05))
    t = np.arange(30.0)
    truth = io.simulate(system, bounds, t, seed=1)
    D = 10.0 ** np.linspace(-spread, spread, n)
    scaled_bounds = io.Bounds(x0=(-D, D), w=(-0.05, 0.05), v=(-0.05, 0.05))
    original = BUILDERS[name](system, bounds).run(t, truth.y)
    scaled = BUILDERS[name](_rescaled(system, D), scaled_bounds).run(t, truth.y)
    lower, upper = scaled.lower / D, scaled.upper / D
    assert np.all((lower <= truth.x) & (truth.x <= upper))
    np.testing.assert_allclose(upper - lower, original.upper - original.lower, rtol=1e-6)


def test_power_of_two_balancing_is_exact() -> None:
    system = _random_system(5)
    D = 10.0 ** np.linspace(-6, 6, system.n)
    model = _rescaled(system, D)
    bounds = io.Bounds(x0=(-D, D), w=(-0.05, 0.05), v=(-0.05, 0.05)).resolve(model)
    scales = state_scales(model, bounds)
    assert scales is not None
    np.testing.assert_array_equal(np.log2(scales), np.round(np.log2(scales)))
    twin, twin_bounds = balanced(model, bounds, scales)
    np.testing.assert_array_equal(twin.A / scales[:, None] * scales, model.A)  # exact both ways
    np.testing.assert_array_equal(twin_bounds.x0[1] / scales, bounds.x0[1])


def test_badly_scaled_design_returns_in_bounded_time() -> None:
    """An 11-state model in coordinates over 10^±6 did not return from the framer LP in 10 minutes."""
    rng = np.random.default_rng(1)
    n = 11
    A = rng.normal(size=(n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    D = 10.0 ** rng.uniform(-6, 6, n)
    system = io.LTISystem(D[:, None] * A / D, rng.normal(size=(3, n)) / D, E=np.diag(D), dt=1.0)
    bounds = io.Bounds(x0=(-D, D), w=(-0.01, 0.01), v=(-0.01, 0.01))
    start = time.process_time()
    observer = io.IntervalObserver.design(system, bounds)
    assert time.process_time() - start < 60.0
    assert observer.n == n


@pytest.mark.parametrize("h", [0.01, 0.71, 10.0])
def test_stiff_interval_model_gives_finite_sound_boxes(h: float) -> None:
    """e^{(|A| + D)h} overflowed for an eigenvalue of -1000 (NaN boxes from h = 0.71)."""
    A = np.array([[-1000.0, 0.0], [1.0, -1.0]])
    system = io.LTISystem(A, [[0.0, 1.0]], dA=(-0.01 * np.abs(A), 0.01 * np.abs(A)))
    bounds = io.Bounds(x0=([-1, -1], [1, 1]), w=(-0.1, 0.1), v=(-0.01, 0.01))
    t = np.arange(12) * h
    truth = io.simulate(system, bounds, t, seed=2)
    reference = io.IntervalObserver.design(system, bounds, h=h).run(t, truth.y)
    for estimator in (
        io.RobustHullEstimator.design(system, bounds, h=h, horizon=5),
        io.RobustFiniteMemoryObserver.design(system, bounds, window=5, h=h),
    ):
        estimate = estimator.run(t, truth.y)
        assert np.all(np.isfinite(estimate.lower)) and np.all(np.isfinite(estimate.upper))
        assert np.all((estimate.lower <= truth.x) & (truth.x <= estimate.upper))
        width = (estimate.upper - estimate.lower)[5:].sum()
        assert width <= 1.01 * (reference.upper - reference.lower)[5:].sum()


@pytest.mark.parametrize("seed", [0, 3])
def test_robust_hull_is_never_wider_than_the_default_observer(seed: int) -> None:
    """At ‖A‖h of a few units the window LP's linearisation in ΔA was up to 1.2x wider per sample."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(3, 3))
    A -= (max(np.linalg.eigvals(A).real) + 0.5) * np.eye(3)
    system = io.LTISystem(A, rng.normal(size=(1, 3)), dA=(-0.01 * np.abs(A), 0.01 * np.abs(A)))
    bounds = io.Bounds(x0=(-np.ones(3), np.ones(3)), w=(-0.1, 0.1), v=(-0.05, 0.05))
    h = 2.0
    t = np.arange(15) * h
    truth = io.simulate(system, bounds, t, seed=seed)
    reference = io.IntervalObserver.design(system, bounds, h=h).run(t, truth.y)
    estimate = io.RobustHullEstimator.design(system, bounds, h=h, horizon=5).run(t, truth.y)
    assert np.all((estimate.lower <= truth.x) & (truth.x <= estimate.upper))
    assert np.all(estimate.lower >= reference.lower) and np.all(estimate.upper <= reference.upper)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_full_history_hull_is_not_wider_than_a_window_far_from_the_origin(seed: int) -> None:
    """Levels of 3e6 with noise 1e-9: the full history once lost up to 6e-4 (60x the window's width) to
    the solver's tolerances and the certificate's rounding, both acting on the levels; its LPs are now
    solved in coordinates centred on the states' boxes. Both estimators still sit above the exact width
    (about 3e-9 at levels near 0): the record's own rounding (ulp(3e6) = 5e-10 against noise of 1e-9)."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(3, 3))
    A *= 0.95 / max(abs(np.linalg.eigvals(A)))
    system = io.LTISystem(A, rng.normal(size=(2, 3)), dt=1.0)
    level = 3e6 * np.ones(3)
    tiny = 1e-9 * np.ones(3)
    bounds = io.Bounds(x0=(level - 1.0, level + 1.0), w=(-tiny, tiny), v=(-tiny[:2], tiny[:2]))
    t = np.arange(30.0)
    truth = io.simulate(system, bounds, t, noise="extreme", seed=seed)
    full = io.HullEstimator.design(system, bounds, horizon=None).run(t, truth.y)
    window = io.HullEstimator.design(system, bounds, horizon=10).run(t, truth.y)
    for estimate in (full, window):
        assert np.all((estimate.lower <= truth.x) & (truth.x <= estimate.upper))
    floor = 1e-11 * np.abs(truth.x).max()  # seen: at most 3e-12 of the levels
    assert np.all(full.upper - full.lower <= window.upper - window.lower + floor)
