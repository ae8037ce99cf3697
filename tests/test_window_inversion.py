"""The moving-window validated observer against truths of the tests' own integrator, and what it reports."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds, ContinuousNonlinearObserver, ContinuousNonlinearSystem, ContinuousWindowObserver
from intervalobs.errors import BoundsError
from nonlinear_cases import Case, cstr, measure, pendulum, rotation, simulate_truth, truths

CASES = {"pendulum": (pendulum, 2.0), "cstr": (cstr, 4.0), "rotation": (rotation, 2.0)}


@pytest.mark.parametrize("name", list(CASES))
def test_encloses_truths_from_vertices_and_interior_points(name: str) -> None:
    make, seconds = CASES[name]
    case = make()
    t = np.arange(0.0, seconds + 1e-9, case.h)
    u = np.full((t.size, case.system.m), 0.3)
    observer = ContinuousWindowObserver(case.system, case.bounds, case.h, window=8)
    for seed, (x0, p) in enumerate(truths(case, 4, seed=len(name))):
        x = simulate_truth(case, x0, p, t, u, seed=seed)
        estimate = observer.run(t, measure(case, x, seed), u)
        assert estimate.meta["consistent"] and estimate.meta["rows"] == "filtered"
        assert estimate.meta["lost_from"] is None and not estimate.meta["diverging"]
        assert estimate.enclosure(x).fraction == 1.0
        assert np.all(np.isfinite(estimate.lower)) and np.all(np.isfinite(estimate.upper))


def test_runs_of_a_leading_axis_and_the_start_of_a_record() -> None:
    case = pendulum()
    t = np.arange(0.0, 0.6 + 1e-9, case.h)
    u = np.full((t.size, 1), 0.3)
    b = case.bounds.resolve(case.system)
    xs = np.stack([simulate_truth(case, x0, p, t, u, seed=s) for s, (x0, p) in enumerate(truths(case, 2, 3))])
    ys = np.stack([measure(case, x, s) for s, x in enumerate(xs)])
    observer = ContinuousWindowObserver(case.system, case.bounds, case.h, window=5)
    estimate = observer.run(t, ys, np.broadcast_to(u, (2, *u.shape)))
    assert estimate.lower.shape == (2, t.size, 2)
    assert estimate.enclosure(xs).fraction == 1.0
    # the first row is the prior box cut by the first sample, never wider than the prior
    assert np.all(estimate.lower[:, 0] >= b.x0[0] - 1e-12) and np.all(estimate.upper[:, 0] <= b.x0[1] + 1e-12)
    assert estimate.meta["window"] == 5 and estimate.meta["ms_per_sample"] > 0


def test_no_wider_than_the_continuous_observer_on_a_linear_case() -> None:
    """A damped rotation (linear, x1 measured, a disturbance on x2 and x3): the whole-window LP beats the strip cuts."""
    a = np.array([[-1.0, 1.0, 0.0], [0.0, -0.5, 1.9], [0.0, -1.9, -0.5]])

    def f(x: list[float], u: list[float], p: list[float]) -> tuple[float, ...]:
        return tuple(sum(a[i, j] * x[j] for j in range(3)) for i in range(3))

    system = ContinuousNonlinearSystem(f, lambda x, u: (x[0],), n=3, E=[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    bounds = Bounds(x0=([-0.5, -1.0, -1.0], [0.5, 1.0, 1.0]), w=(-0.2, 0.2), v=(-0.05, 0.05))
    case = Case("linear", system, bounds, lambda x, u, p, w: a @ x + np.array([0.0, *w]), [0], 0.05, {})
    t = np.arange(0.0, 4.0 + 1e-9, case.h)
    u = np.zeros((t.size, 0))
    x = simulate_truth(case, np.array([0.5, -1.0, 1.0]), np.zeros(0), t, u, seed=5)
    y = measure(case, x, 5)
    window = ContinuousWindowObserver(system, bounds, case.h, window=20).run(t, y)
    strips = ContinuousNonlinearObserver(system, bounds, case.h, order=24).run(t, y)
    assert window.enclosure(x).fraction == 1.0 and strips.enclosure(x).fraction == 1.0
    late = t >= 1.0
    ours = (window.upper - window.lower)[late].mean(0)
    theirs = (strips.upper - strips.lower)[late].mean(0)
    assert np.all(ours <= theirs)


def test_contradicting_data_are_flagged_not_raised() -> None:
    case = pendulum()
    t = np.arange(0.0, 0.5 + 1e-9, case.h)
    u = np.full((t.size, 1), 0.3)
    y = np.full((t.size, 1), 0.5)
    y[6:] = 3.0  # the angle cannot jump by 2.5 rad in one period
    estimate = ContinuousWindowObserver(case.system, case.bounds, case.h, window=4).run(t, y, u)
    assert not estimate.meta["consistent"]
    assert estimate.meta["inconsistent_from"] is not None and estimate.meta["inconsistent_from"] <= t[6] + 1e-9


@pytest.mark.parametrize("option", [{"window": 0}, {"substeps": 0}, {"window": 2.5}])
def test_rejects_bad_arguments(option: dict[str, object]) -> None:
    case = pendulum()
    with pytest.raises(BoundsError):
        ContinuousWindowObserver(case.system, case.bounds, case.h, **option)  # type: ignore[arg-type]


def test_rejects_an_unbounded_prior() -> None:
    case = pendulum()
    b = case.bounds.resolve(case.system)
    with pytest.raises(BoundsError):
        ContinuousWindowObserver(case.system, Bounds(x0=([-np.inf, -0.2], [0.6, 0.2]), p=b.p, w=b.w, v=b.v), case.h)
