"""The validated flow enclosure over one sampling interval, against truths of the tests' own integrator."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from intervalobs import Bounds, ContinuousNonlinearSystem
from intervalobs.errors import AssumptionError, BoundsError
from intervalobs.interval import Interval
from intervalobs.systems import flow_enclosure
from intervalobs.systems.flow_enclosure import StateZonotope, propagate
from nonlinear_cases import Case, cstr, pendulum, simulate_truth


def _vertices(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    return np.array(list(itertools.product(*zip(lower, upper))))


@pytest.mark.parametrize("make", [pendulum, cstr], ids=["pendulum", "cstr"])
def test_encloses_trajectories_from_vertices_with_switching_disturbance(make) -> None:
    case: Case = make()
    b = case.bounds.resolve(case.system)
    h = case.h
    t = np.array([0.0, h])
    u = np.full((2, case.system.m), 0.3)
    box = flow_enclosure(case.system, case.bounds, h, u=u[0])
    points = _vertices(*b.x0)
    params = np.vstack([_vertices(*b.p), b.centre("p")])
    for seed, (x0, p) in enumerate(itertools.product(points, params)):
        end = simulate_truth(case, x0, p, t, u, seed=seed, substeps=40)[-1]
        assert np.all(box.lower <= end) and np.all(end <= box.upper), (x0, p, end, box.lower, box.upper)
        assert np.all(box.a_priori_lower <= end) and np.all(end <= box.a_priori_upper)


def test_tight_for_a_point_and_exact_linear_flow() -> None:
    decay = ContinuousNonlinearSystem(lambda x, u, p: (-p[0] * x[0],), lambda x, u: (x[0],), n=1, n_params=1)
    box = flow_enclosure(decay, Bounds(x0=(1.0, 1.0), p=(1.0, 1.0)), h=1.0, substeps=16)
    assert box.lower[0] <= np.exp(-1.0) <= box.upper[0]
    assert box.upper[0] - box.lower[0] < 2e-3
    wide = flow_enclosure(decay, Bounds(x0=(1.0, 2.0), p=(0.9, 1.1)), h=0.5, substeps=8)
    exact = (np.exp(-0.55), 2.0 * np.exp(-0.45))
    assert wide.lower[0] <= exact[0] and exact[1] <= wide.upper[0]
    assert (wide.upper[0] - wide.lower[0]) < 1.2 * (exact[1] - exact[0])


def test_batched_boxes_match_single_ones() -> None:
    """A batch shares its step length (halved for all when one box needs it), so it agrees to the order of the step."""
    case = pendulum()
    lower = np.array([[0.4, -0.2], [0.5, 0.0]])
    upper = np.array([[0.6, 0.2], [0.55, 0.1]])
    u = np.array([[0.3], [0.3]])
    both = flow_enclosure(case.system, case.bounds, case.h, lower, upper, u=u)
    for i in range(2):
        one = flow_enclosure(case.system, case.bounds, case.h, lower[i], upper[i], u=u[i])
        np.testing.assert_allclose(both.lower[i], one.lower, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(both.upper[i], one.upper, rtol=1e-5, atol=1e-5)


def test_blow_up_is_a_named_error() -> None:
    square = ContinuousNonlinearSystem(lambda x, u, p: (x[0] * x[0],), lambda x, u: (x[0],), n=1)
    with pytest.raises(AssumptionError, match="no validated enclosure of the flow"):
        flow_enclosure(square, Bounds(x0=(1.0, 2.0)), h=1.0)


def test_refused_arguments() -> None:
    case = pendulum()
    with pytest.raises(BoundsError, match="h: expected a positive step length"):
        flow_enclosure(case.system, case.bounds, h=0.0, u=[0.0])
    with pytest.raises(BoundsError, match="u: expected the held input"):
        flow_enclosure(case.system, case.bounds, h=0.1)


def test_zonotope_of_a_box_is_the_box() -> None:
    lower, upper = np.array([0.1, -2.0, 3.0]), np.array([0.3, 1.0, 3.0])
    hull = StateZonotope.from_box(lower, upper, order=5).box()
    assert hull.shape == (3,)
    assert np.all(hull.lower <= lower) and np.all(hull.upper >= upper)
    np.testing.assert_allclose(hull.lower, lower, rtol=1e-14)
    np.testing.assert_allclose(hull.upper, upper, rtol=1e-14)


@pytest.mark.parametrize("make", [pendulum, cstr], ids=["pendulum", "cstr"])
def test_the_compiled_step_gives_the_numpy_step_bounds(make) -> None:
    """flow_kernel.advance evaluates the NumPy step's formulas: the same sets up to the order of a few sums.

    Random start zonotopes (12 of them, 3 generators beyond the box's) so that the reduction runs too.
    """
    case: Case = make()
    b = case.bounds.resolve(case.system)
    rng = np.random.default_rng(7)
    size = case.system.n + case.system.n_params
    low = np.concatenate([b.x0[0], b.p[0]])
    high = np.concatenate([b.x0[1], b.p[1]])
    centre = low + (high - low) * rng.uniform(0.3, 0.7, (12, size))
    generators = 0.2 * (high - low)[:, None] * rng.uniform(-1.0, 1.0, (12, size, 4 * size))
    start = StateZonotope(centre, generators)
    u = np.full((12, case.system.m), 0.3)
    w = Interval._raw(*b.w)
    sets = [propagate(case.system, u, w, start, case.h, 2, 3 * size, compiled=c)[0] for c in (0, 1)]
    numpy_box, compiled_box = sets[0].box(), sets[1].box()
    scale = numpy_box.upper - numpy_box.lower
    assert np.all(np.abs(compiled_box.lower - numpy_box.lower) <= 1e-12 * scale)
    assert np.all(np.abs(compiled_box.upper - numpy_box.upper) <= 1e-12 * scale)
    np.testing.assert_allclose(sets[1].generators, sets[0].generators, rtol=1e-12, atol=1e-12 * scale.max())
