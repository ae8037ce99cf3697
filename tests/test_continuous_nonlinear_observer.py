"""ContinuousNonlinearObserver: soundness against truths of the tests' own integrator, consistency, divergence."""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Callable

import numpy as np
import pytest

from intervalobs import Bounds, ContinuousNonlinearObserver, ContinuousNonlinearSystem
from intervalobs.errors import BoundsError, DivergenceWarning
from intervalobs.estimate import enclosure_report
from intervalobs.observers.continuous_nonlinear import _bisect_parts
from intervalobs.systems.flow_enclosure import StateZonotope
from nonlinear_cases import (
    Case,
    chemostat,
    chemostat_bundle,
    compartments,
    cstr,
    measure,
    pendulum,
    rotation,
    simulate_truth,
)

CASES = {
    "chemostat": (chemostat, 2.0, False),
    "chemostat-bundle": (chemostat_bundle, 6.0, True),
    "pendulum": (pendulum, 3.0, True),
    "cstr": (cstr, 4.0, True),
    "compartments": (compartments, 3.0, True),
    "rotation": (rotation, 4.0, True),
}
"""Case, record length (in the model's time unit: a few seconds of test each), and whether every run's bounds
stay finite (the chemostat's wide biomass prior loses them for the runs that start at high biomass: see
``test_chemostat_wide_prior_warns``)."""


def _starts(case: Case) -> list[tuple[np.ndarray, np.ndarray]]:
    """Initial states at vertices (and the centre) of x0, parameters at vertices and the centre of p."""
    b = case.bounds.resolve(case.system)
    corners = [b.x0[0], b.x0[1], np.where(np.arange(case.system.n) % 2 == 0, b.x0[0], b.x0[1]), b.centre("x0")]
    params = [b.p[0], b.p[1], b.centre("p")]
    return list(itertools.product(corners, params))


def _record(case: Case, duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(0.0, duration + 1e-9, case.h)
    u = np.tile(0.5 + 0.3 * np.sin(t)[:, None], (1, case.system.m))
    truths, outputs = [], []
    for seed, (x0, p) in enumerate(_starts(case)):
        x = simulate_truth(case, x0, p, t, u, seed)
        truths.append(x)
        outputs.append(measure(case, x, seed))
    return t, u, np.array(truths), np.array(outputs)


@pytest.mark.parametrize("reduction", ["box", "frame"], ids=str)
@pytest.mark.parametrize("name", list(CASES), ids=str)
def test_encloses_every_truth(name: str, reduction: str) -> None:
    make, duration, bounded = CASES[name]
    case = make()
    t, u, x, y = _record(case, duration)
    observer = ContinuousNonlinearObserver(
        case.system, case.bounds, case.h, reduction=reduction, **case.observer_options
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        estimate = observer.run(t, y, np.broadcast_to(u, (*y.shape[:2], case.system.m)) if case.system.m else None)
    assert enclosure_report(t, estimate.lower, x, estimate.upper).fraction == 1.0
    assert estimate.meta["rows"] == "filtered"
    assert all(estimate.meta["consistent"])
    width = estimate.upper - estimate.lower
    assert np.all(np.isfinite(width[:, -1])) == bounded
    prior = np.subtract(*case.bounds.resolve(case.system).x0[::-1])
    finite = np.isfinite(width[:, -1, 0])
    assert np.all(width[finite, -1][:, case.outputs] < prior[case.outputs] + 1e-12)


def test_chemostat_wide_prior_warns() -> None:
    """Biomass in [1, 3] with μmax, Ks ±5 %: the validated step loses the set of the high-biomass parts (honest
    limitation of the first-order enclosure); the run says so instead of returning a useless width silently."""
    case = chemostat()
    t = np.arange(0.0, 2.0 + 1e-9, case.h)
    x = simulate_truth(case, np.array([3.0, 0.3]), np.array([0.525, 0.285]), t, np.zeros((t.size, 0)), seed=0)
    observer = ContinuousNonlinearObserver(case.system, case.bounds, case.h, splits=(8, 1))
    with pytest.warns(RuntimeWarning, match="validated flow enclosure was lost"):
        estimate = observer.run(t, measure(case, x, 0))
    assert estimate.meta["diverging"] is True
    assert enclosure_report(t, estimate.lower, x, estimate.upper).fraction == 1.0


def test_bisected_parts_hold_every_point_of_the_live_parts() -> None:
    """Two runs of four parts (one and three alive): the run with one live part bisects it into a dropped slot,
    every sampled point of it lies in one of the halves, and the run with three live parts is left alone."""
    rng = np.random.default_rng(3)
    centre, generators = rng.normal(size=(2, 4, 3)), rng.normal(size=(2, 4, 3, 5))
    zset = StateZonotope(centre, generators)
    alive = np.array([[False, True, False, False], [True, True, False, True]])
    split, now = _bisect_parts(zset, alive, np.ones(3), 5)
    assert now.tolist() == [[True, True, False, False], alive[1].tolist()]
    np.testing.assert_array_equal(split.centre[1], centre[1])
    xi = rng.uniform(-1.0, 1.0, size=(2000, 5))
    xi[:200] = np.sign(xi[:200])
    points = centre[0, 1] + xi @ generators[0, 1].T
    halves = split.box()
    inside = [(halves.lower[0, j] - 1e-12 <= points) & (points <= halves.upper[0, j] + 1e-12) for j in (0, 1)]
    assert np.all(np.all(inside[0], axis=1) | np.all(inside[1], axis=1))
    widths = halves.upper[0, :2] - halves.lower[0, :2]
    assert np.all(widths.max(axis=0) <= (zset.box().upper - zset.box().lower)[0, 1] + 1e-12)


def test_refine_is_checked() -> None:
    case = chemostat_bundle()
    with pytest.raises(BoundsError, match="refine: expected 0 or a number of parts of at least 2 and 4"):
        ContinuousNonlinearObserver(case.system, case.bounds, case.h, splits=2, refine=3)


@pytest.mark.parametrize("make", [pendulum, chemostat_bundle], ids=["pendulum", "chemostat-bundle"])
def test_step_and_run_agree(make: Callable[[], Case]) -> None:
    case = make()
    t, u, _, y = _record(case, 1.0)
    u = u if case.system.m else np.zeros((t.size, 0))
    observer = ContinuousNonlinearObserver(case.system, case.bounds, case.h, **case.observer_options)
    estimate = observer.run(t, y[0], u)
    state = observer.init()
    for k in range(t.size):
        state = observer.step(state, y[0, k], u[k])
        np.testing.assert_allclose(state.lower, estimate.lower[k], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(state.upper, estimate.upper[k], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("reduction", ["box", "frame"], ids=str)
@pytest.mark.parametrize(
    "make", [pendulum, chemostat_bundle, rotation], ids=["pendulum", "chemostat-bundle", "rotation"]
)
def test_the_compiled_kernels_give_the_numpy_bounds(make: Callable[[], Case], reduction: str) -> None:
    """compiled=True (flow step and strip updates in Numba) against compiled=False, every run, parts bisected."""
    case = make()
    t, u, x, y = _record(case, 1.5)
    held = np.broadcast_to(u, (*y.shape[:2], case.system.m)) if case.system.m else None
    options = {**case.observer_options, "reduction": reduction}
    estimates = [
        ContinuousNonlinearObserver(case.system, case.bounds, case.h, compiled=c, **options).run(t, y, held)
        for c in (False, True)
    ]
    scale = np.maximum(estimates[0].upper - estimates[0].lower, 1e-300)
    # the frame's entries are rounded to 26 bits, where a last-bit difference of two sums can flip one (2^-26)
    tolerance = 1e-12 if reduction == "box" else 1e-7
    for end in ("lower", "upper"):
        assert np.all(np.abs(getattr(estimates[1], end) - getattr(estimates[0], end)) <= tolerance * scale)
    assert enclosure_report(t, estimates[1].lower, x, estimates[1].upper).fraction == 1.0
    assert [e.meta["compiled"] for e in estimates] == [False, True]
    # by default, once this process has loaded the kernels (the run above), every run and step uses them
    observer = ContinuousNonlinearObserver(case.system, case.bounds, case.h, **options)
    assert observer.run(t[:3], y[:, :3], None if held is None else held[:, :3]).meta["compiled"]
    assert observer.init().internal["compiled"]


def test_contradicting_data_are_reported_not_raised() -> None:
    case = cstr()
    t, _, _, y = _record(case, 1.0)
    shifted = y[0].copy()
    shifted[5:] += 1.0
    estimate = ContinuousNonlinearObserver(case.system, case.bounds, case.h).run(t, shifted)
    assert estimate.meta["consistent"] is False
    assert estimate.meta["inconsistent_from"] == pytest.approx(t[5])
    assert np.all(np.isfinite(estimate.lower[:5])) and np.all(np.isinf(estimate.lower[5:]))


def test_a_batch_with_one_contradicting_run_reports_its_time() -> None:
    """Two runs, the second's record shifted from t_5 on: the batch's estimate says so through the same
    properties as a single run's (the earliest time over the runs), and warns of no divergence."""
    case = cstr()
    t, _, _, y = _record(case, 1.0)
    batch = y[:2].copy()
    batch[1, 5:] += 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("error", DivergenceWarning)
        estimate = ContinuousNonlinearObserver(case.system, case.bounds, case.h).run(t, batch)
    assert not estimate.consistent and estimate.inconsistent_from == pytest.approx(t[5])
    assert estimate.meta["consistent"] == [True, False]
    assert estimate.meta["inconsistent_from_runs"][0] is None


def test_unobserved_unstable_state_warns() -> None:
    system = ContinuousNonlinearSystem(lambda x, u, p: (0.8 * x[0], -x[1]), lambda x, u: (x[1],), n=2)
    observer = ContinuousNonlinearObserver(system, Bounds(x0=(-0.1, 0.1), v=(-0.01, 0.01)), h=0.2)
    t = np.arange(0.0, 4.0 + 1e-9, 0.2)
    with pytest.warns(RuntimeWarning, match="bounds of state 1 grew"):
        estimate = observer.run(t, 0.05 * np.exp(-t)[:, None])
    assert estimate.meta["diverging"] is True


def test_refused_options() -> None:
    case = pendulum()
    with pytest.raises(BoundsError, match="splits"):
        ContinuousNonlinearObserver(case.system, case.bounds, case.h, splits=(2, 2, 2, 2))
    with pytest.raises(BoundsError, match="h: expected a positive sampling period"):
        ContinuousNonlinearObserver(case.system, case.bounds, -1.0)
    with pytest.raises(BoundsError, match="order"):
        ContinuousNonlinearObserver(case.system, case.bounds, case.h, order=2)
    with pytest.raises(BoundsError, match="compiled"):
        ContinuousNonlinearObserver(case.system, case.bounds, case.h, compiled="yes")
    with pytest.raises(BoundsError, match="reduction: expected one of 'box', 'frame', got 'pca'"):
        ContinuousNonlinearObserver(case.system, case.bounds, case.h, reduction="pca")
