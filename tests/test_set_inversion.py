"""The set-inversion smoother against truths of the tests' own integrator, and what it reports."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from intervalobs import Bounds, ContinuousNonlinearObserver, ContinuousNonlinearSystem
from intervalobs.errors import AssumptionError, BoundsError
from intervalobs.observers.set_inversion import SetInversionSmoother
from nonlinear_cases import Case, chemostat_bundle, compartments, cstr, measure, pendulum, simulate_truth, truths


def _still(case: Case) -> Case:
    """The case without its disturbance (the smoother inverts the start and the parameters only)."""
    b = case.bounds.resolve(case.system)
    bounds = Bounds(x0=b.x0, v=b.v, p=b.p, w=(np.zeros(case.system.nw), np.zeros(case.system.nw)))
    return dataclasses.replace(case, bounds=bounds)


CASES = {
    "chemostat": (chemostat_bundle, 2.0, {"splits": (8, 4, 2, 2), "max_parts": 128}),
    "pendulum": (pendulum, 1.0, {}),
    "cstr": (cstr, 2.0, {}),
    "compartments": (compartments, 1.5, {}),
}


@pytest.mark.parametrize("name", list(CASES))
def test_encloses_truths_from_vertices_and_interior_points(name: str) -> None:
    make, hours, options = CASES[name]
    case = _still(make())
    t = np.arange(0.0, hours + 1e-9, case.h)
    u = np.full((t.size, case.system.m), 0.3)
    options = {"max_parts": 8, "max_rounds": 3, **options}
    smoother = SetInversionSmoother(case.system, case.bounds, case.h, **options)
    for seed, (x0, p) in enumerate(truths(case, 2, seed=len(name))):
        x = simulate_truth(case, x0, p, t, u, seed=seed)
        estimate = smoother.run(t, measure(case, x, seed), u)
        assert estimate.meta["consistent"] and estimate.meta["rows"] == "smoothed"
        assert np.all(np.isfinite(estimate.lower)) and np.all(np.isfinite(estimate.upper))
        inside = (estimate.lower <= x) & (x <= estimate.upper)
        assert inside.all(), (name, seed, np.argwhere(~inside)[:3])


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_encloses_manytruths(name: str) -> None:
    """Six truths per case (vertices and interior points, bang-bang noise of other seeds), a longer record."""
    make, hours, options = CASES[name]
    case = _still(make())
    t = np.arange(0.0, 2 * hours + 1e-9, case.h)
    u = np.full((t.size, case.system.m), 0.3)
    options = {"max_parts": 16, "max_rounds": 4, **options}
    smoother = SetInversionSmoother(case.system, case.bounds, case.h, **options)
    for seed, (x0, p) in enumerate(truths(case, 6, seed=100 + len(name))):
        x = simulate_truth(case, x0, p, t, u, seed=seed + 10)
        estimate = smoother.run(t, measure(case, x, seed + 10), u)
        assert estimate.meta["consistent"]
        inside = (estimate.lower <= x) & (x <= estimate.upper)
        assert inside.all(), (name, seed, np.argwhere(~inside)[:3])


def test_compiled_and_numpy_paths_agree() -> None:
    case = _still(cstr())
    t = np.arange(0.0, 1.0 + 1e-9, case.h)
    x = simulate_truth(case, np.array([0.15, 0.5]), np.array([0.07]), t, np.zeros((t.size, 0)), seed=4)
    y = measure(case, x, 4)
    runs = [
        SetInversionSmoother(case.system, case.bounds, case.h, max_parts=4, max_rounds=3, compiled=flag).run(t, y)
        for flag in (False, True)
    ]
    np.testing.assert_allclose(runs[0].width(), runs[1].width(), rtol=1e-6, atol=1e-12)
    counts = [[(entry["parts"], entry["live"]) for entry in run.meta["rounds"]] for run in runs]
    assert counts[0] == counts[1]


def test_smoothed_rows_are_narrower_than_filtered_ones_early_in_the_record() -> None:
    """A row given the whole record cannot be wider than the filter's at the start, where the filter knows little."""
    case = _still(chemostat_bundle())
    t = np.arange(0.0, 3.0 + 1e-9, case.h)
    u = np.zeros((t.size, 0))
    x = simulate_truth(case, np.array([5.9, 0.35]), np.array([0.51, 0.29]), t, u, seed=1)
    y = measure(case, x, 1)
    options = {"splits": (8, 4, 2, 2), "max_parts": 128, "max_rounds": 3}
    smoothed = SetInversionSmoother(case.system, case.bounds, case.h, **options).run(t, y)
    filtered = ContinuousNonlinearObserver(case.system, case.bounds, case.h, refine=16).run(t, y)
    early = slice(0, 5)
    assert np.all(smoothed.width()[early, 0] < 0.5 * filtered.width()[early, 0])
    assert smoothed.enclosure(x).fraction == 1.0 and filtered.enclosure(x).fraction == 1.0
    assert len(smoothed.meta["rounds"]) >= 2 and smoothed.meta["rounds"][-1]["live"] >= 1


def test_report_rows_bound_a_combination_tighter_than_the_sum_of_boxes() -> None:
    """The biomass X = Y(Z - S) of the invariant coordinates: its own LPs, inside the interval combination."""
    case = _still(chemostat_bundle())
    t = np.arange(0.0, 2.0 + 1e-9, case.h)
    x = simulate_truth(case, np.array([5.9, 0.35]), np.array([0.51, 0.29]), t, np.zeros((t.size, 0)), seed=2)
    y = measure(case, x, 2)
    options = {"splits": (8, 4, 4, 4), "max_parts": 512, "max_rounds": 2}
    states = SetInversionSmoother(case.system, case.bounds, case.h, **options).run(t, y)
    biomass = SetInversionSmoother(
        case.system, case.bounds, case.h, report=[[0.5, -0.5]], report_names=["X"], **options
    ).run(t, y)
    truth = 0.5 * (x[:, 0] - x[:, 1])
    assert biomass.state_names == ("X",)
    assert np.all((biomass.lower[:, 0] <= truth) & (truth <= biomass.upper[:, 0]))
    combined = 0.5 * (states.width()[:, 0] + states.width()[:, 1])
    assert np.all(biomass.width()[:, 0] <= combined * (1 + 1e-9))
    assert np.mean(biomass.width()[:, 0]) < 0.97 * np.mean(combined)


def test_data_that_contradict_the_model_are_a_result_not_an_error() -> None:
    case = _still(chemostat_bundle())
    t = np.arange(0.0, 1.0 + 1e-9, case.h)
    y = np.full((t.size, 1), 3.0)  # a substrate no start of the box reaches
    estimate = SetInversionSmoother(case.system, case.bounds, case.h, max_parts=4, max_rounds=2).run(t, y)
    assert estimate.meta["consistent"] is False and estimate.inconsistent_from == 0.0
    assert np.all(np.isnan(estimate.lower))


def test_monte_carlo_axis_runs_each_record() -> None:
    case = _still(cstr())
    t = np.arange(0.0, 1.0 + 1e-9, case.h)
    u = np.zeros((t.size, 0))
    runs = [simulate_truth(case, x0, p, t, u, seed=s) for s, (x0, p) in enumerate(truths(case, 2, seed=5))]
    ys = np.stack([measure(case, x, s) for s, x in enumerate(runs)])
    smoother = SetInversionSmoother(case.system, case.bounds, case.h, max_parts=4, max_rounds=2)
    batch = smoother.run(t, ys)
    assert batch.lower.shape == (2, t.size, 2)
    for r, x in enumerate(runs):
        single = smoother.run(t, ys[r])
        np.testing.assert_array_equal(batch.lower[r], single.lower)
        assert np.all((batch.lower[r] <= x) & (x <= batch.upper[r]))


def test_refuses_a_disturbance_and_infinite_boxes() -> None:
    case = pendulum()
    with pytest.raises(AssumptionError, match="disturbance"):
        SetInversionSmoother(case.system, case.bounds, case.h)
    decay = ContinuousNonlinearSystem(lambda x, u, p: (-p[0] * x[0],), lambda x, u: (x[0],), n=1, n_params=1)
    with pytest.raises(BoundsError, match="finite"):
        SetInversionSmoother(decay, Bounds(x0=(0.0, np.inf), v=(-0.1, 0.1), p=(0.9, 1.1)), 0.1)
    with pytest.raises(BoundsError, match="reduction"):
        SetInversionSmoother(decay, Bounds(x0=(0.0, 1.0), v=(-0.1, 0.1), p=(0.9, 1.1)), 0.1, reduction="axes")


def test_a_lost_flow_warns_and_leaves_the_rows_after_it_unbounded() -> None:
    """ẋ = x² from [0.9, 1.1] blows up at t = 1/x0: one part (one round) cannot be carried to t = 0.95."""
    blowup = ContinuousNonlinearSystem(lambda x, u, p: (x[0] * x[0],), lambda x, u: (x[0],), n=1)
    t = np.arange(0.0, 0.95 + 1e-9, 0.05)
    y = (1.0 / (1.0 - t))[:, None]  # the truth from x0 = 1
    smoother = SetInversionSmoother(blowup, Bounds(x0=(0.9, 1.1), v=(-0.05, 0.05)), 0.05, max_rounds=1)
    with pytest.warns(RuntimeWarning, match="lost"):
        estimate = smoother.run(t, y)
    lost_from = estimate.meta["lost_from"]
    assert lost_from is not None and lost_from < 0.95
    assert np.all(np.isinf(estimate.upper[t >= lost_from - 1e-9]))
    assert np.all(estimate.lower[t < lost_from - 1e-9, 0] <= y[t < lost_from - 1e-9, 0])


def test_the_halves_of_a_part_cover_it() -> None:
    """Vertices of a parallelotope (and its centre) lie in one of its two halves, up to the halves' boxes."""
    from intervalobs.observers.set_inversion import _Parts

    rng = np.random.default_rng(8)
    centre = rng.uniform(-1e3, 1e3, (5, 3))
    generators = rng.normal(size=(5, 3, 3)) * rng.uniform(1e-6, 1.0, (5, 1, 3))
    parts = _Parts(centre, generators, np.zeros((5, 3)))
    column = rng.integers(0, 3, 5)
    halves = parts.bisect(column)
    signs = np.array([*itertools.product((-1.0, 1.0), repeat=3), (0.0, 0.0, 0.0)])
    for p in range(5):
        for sign in signs:
            point = centre[p] + generators[p] @ sign
            covered = False
            for half in (p, p + 5):
                xi = np.linalg.solve(halves.generators[half], point - halves.centre[half])
                slack = np.abs(halves.generators[half]) @ np.full(3, 1e-9)
                residual = point - halves.centre[half] - halves.generators[half] @ np.clip(xi, -1, 1)
                covered |= bool(np.all(np.abs(residual) <= halves.radius[half] + slack))
            assert covered, (p, sign)
