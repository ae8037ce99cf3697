"""The test systems at scale (examples/scale_cases.py): the issue's shapes, stable, observable, admissible truths."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.errors import DataError
from intervalobs.examples import scale_cases

CASES = scale_cases.cases()


def test_shapes_of_the_cases() -> None:
    tanks = CASES["tanks-30"].system
    assert (tanks.n, tanks.p, tanks.m, tanks.nw) == (30, 21, 15, 30)
    assert (CASES["vehicle"].system.n, CASES["vehicle"].system.p) == (6, 4)
    walker = CASES["pedestrian"].system
    assert (walker.n, walker.p, walker.E.shape) == (4, 2, (4, 10))
    assert CASES["short-record"].t.size == 20
    assert [CASES[f"tanks-{n}"].system.n for n in scale_cases.TANK_SIZES] == list(scale_cases.TANK_SIZES)


@pytest.mark.parametrize("name", list(CASES), ids=list(CASES))
def test_stable_slow_and_observable(name: str) -> None:
    system = CASES[name].system
    rho = np.max(np.abs(np.linalg.eigvals(system.A)))
    assert 0.95 < rho < 1.0
    powers = np.vstack([system.C @ np.linalg.matrix_power(system.A, k) for k in range(system.n)])
    singular = np.linalg.svd(powers, compute_uv=False)
    assert singular[0] / singular[-1] < 100.0  # observable, and not nearly unobservable


@pytest.mark.parametrize("name", list(CASES), ids=list(CASES))
def test_truth_is_admissible_and_at_the_vertices(name: str) -> None:
    case = CASES[name]
    system, full = case.system, case.bounds.resolve(case.system)
    sim = case.simulate(seed=3)
    assert np.all(np.isin(sim.w, [-1.0, 1.0])) and np.all(np.isin(sim.v, [-1.0, 1.0]))
    assert np.all((sim.x[0] == full.x0[0]) | (sim.x[0] == full.x0[1]))
    drive = sim.x[1:] - sim.x[:-1] @ system.A.T - case.u[:-1] @ system.B.T
    np.testing.assert_allclose(drive, sim.w[:-1] @ system.E.T, atol=1e-12)
    np.testing.assert_allclose(sim.y - sim.x @ system.C.T, sim.v @ system.F.T, atol=1e-12)


def test_too_few_tanks_refused() -> None:
    with pytest.raises(DataError, match="n: expected an integer of at least 3"):
        scale_cases.tank_cascade(2)
