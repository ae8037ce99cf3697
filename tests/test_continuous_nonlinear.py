"""The continuous-time nonlinear model and the parameter box of Bounds."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds, ContinuousNonlinearSystem, LTISystem
from intervalobs.errors import BoundsError, DimensionError
from intervalobs.interval import Interval


def _decay(**options: object) -> ContinuousNonlinearSystem:
    return ContinuousNonlinearSystem(
        lambda x, u, p: (-p[0] * x[0] + u[0], x[0] - x[1]), lambda x, u: (x[1],), n=2, m=1, n_params=1, **options
    )


def test_sizes_and_continuous_time() -> None:
    system = _decay(E=[[1.0], [0.0]])
    assert (system.n, system.m, system.p, system.nw, system.nv, system.n_params) == (2, 1, 1, 1, 1, 1)
    assert system.dt is None
    assert system.state_names == ("x1", "x2")


def test_point_and_box_evaluation_agree() -> None:
    system = _decay()
    x, u, p = np.array([[1.0, 2.0], [0.5, -1.0]]), np.array([[0.3], [0.0]]), np.array([[2.0], [1.0]])
    np.testing.assert_allclose(system.evaluate_f(x, u, p), [[-1.7, -1.0], [-0.5, 1.5]])
    np.testing.assert_allclose(system.evaluate_g(x, u), [[2.0], [-1.0]])
    field = system.augmented_field(np.array([0.3]))
    rates = field([Interval(1.0, 1.5), Interval(2.0), Interval(1.9, 2.1)])
    assert rates[0].lower <= -1.9 * 1.5 + 0.3 and rates[0].upper >= -2.1 * 1.0 + 0.3
    assert rates[2] == 0.0


def test_jacobians_are_automatic() -> None:
    field_jacobian, output_jacobian = _decay().jacobians(np.zeros(1))
    rows = field_jacobian([Interval(1.0), Interval(2.0), Interval(3.0)])
    np.testing.assert_allclose([[float(e.centre) for e in r] for r in rows], [[-3, 0, -1], [1, -1, 0], [0, 0, 0]])
    assert len(output_jacobian([Interval(1.0), Interval(2.0), Interval(3.0)])) == 1


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"n": 0}, DimensionError, "n: expected an integer >= 1"),
        ({"n_params": -1}, DimensionError, "n_params"),
        ({"E": [[1.0]]}, DimensionError, "E"),
        ({"domain": ([1.0, 0.0], [0.0, 1.0])}, BoundsError, "domain: expected lower <= upper"),
    ],
    ids=["n", "n_params", "E", "domain"],
)
def test_refused_arguments(options: dict[str, object], error: type[Exception], match: str) -> None:
    arguments: dict[str, object] = {"n": 2, "m": 1, "n_params": 1, **options}
    with pytest.raises(error, match=match):
        ContinuousNonlinearSystem(lambda x, u, p: (x[0], x[1]), lambda x, u: (x[1],), **arguments)  # type: ignore[arg-type]


def test_wrong_number_of_rates_is_refused() -> None:
    with pytest.raises(DimensionError, match="f: expected 2 components, got 1"):
        ContinuousNonlinearSystem(lambda x, u, p: (x[0],), lambda x, u: (x[1],), n=2)


def test_parameter_box_in_bounds() -> None:
    resolved = Bounds(x0=(0.0, 1.0), p=(0.9, 1.1)).resolve(_decay())
    np.testing.assert_allclose(resolved.p[0], [0.9])
    np.testing.assert_allclose(resolved.radius("p"), [0.1])
    np.testing.assert_allclose(resolved.centre("p"), [1.0])
    assert repr(Bounds(x0=(0.0, 1.0), p=(0.9, 1.1))).endswith("p=(0.9, 1.1))")


def test_parameter_box_refused_without_parameters() -> None:
    with pytest.raises(DimensionError, match="n_params is 0"):
        Bounds(x0=(0.0, 1.0), p=(0.9, 1.1)).resolve(LTISystem(-np.eye(2), [[1.0, 0.0]]))
    with pytest.raises(DimensionError, match=r"bounds\.p: expected length 1"):
        Bounds(x0=(0.0, 1.0), p=([0.9, 1.0], [1.1, 1.2])).resolve(_decay())
    assert Bounds(x0=(0.0, 1.0)).resolve(LTISystem(-np.eye(2), [[1.0, 0.0]])).p[0].size == 0
