"""NonlinearSystem validation and its simulator."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.errors import AssumptionError, DataError, DimensionError
from intervalobs.examples import gsisio
from intervalobs.inclusion import interval_matrix
from intervalobs.simulate import simulate_nonlinear
from intervalobs.systems import NonlinearSystem


def f(x):
    return (0.5 * x[0], 0.5 * np.sin(x[1]))


def g(x):
    return (x[0] + x[1],)


def jf(x):
    return [[0.5, 0.0], [0.0, 0.5 * np.cos(x[1])]]


def jg(x):
    return [[1.0, 1.0]]


def test_dimensions_and_defaults():
    s = NonlinearSystem(f, g, G=[[1.0], [0.0]], H=[[0.5]], f_jacobian=jf, g_jacobian=jg)
    assert (s.n, s.m, s.p, s.q, s.nw, s.nv) == (2, 0, 1, 1, 2, 1)
    assert s.evaluate_f(np.zeros((4, 2))).shape == (4, 2)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"G": [[1.0], [0.0]], "H": [[0.5, 1.0]]}, DimensionError, "H"),
        ({"G": [[0.0], [0.0]], "H": [[0.0]]}, AssumptionError, "full column rank"),
        (
            {"G": [[1.0], [0.0]], "H": [[0.5]], "f_jacobian": lambda x: [[0.5, 0.0], [0.0, 0.5]]},
            DataError,
            r"f_jacobian: entry \(2,2\)",
        ),
        ({"G": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "H": [[0.5, 0, 0]]}, DimensionError, "f"),
    ],
    ids=["H-shape", "GH-rank", "wrong-jacobian", "f-size"],
)
def test_invalid_models_are_rejected(kwargs, error, match):
    with pytest.raises(error, match=match):
        NonlinearSystem(f, g, **kwargs)


def test_jacobians_default_to_the_automatic_ones_and_bound_the_user_ones():
    auto = NonlinearSystem(f, g, G=[[1.0], [0.0]], H=[[0.5]])
    user = NonlinearSystem(f, g, G=[[1.0], [0.0]], H=[[0.5]], f_jacobian=jf, g_jacobian=jg)
    assert auto.jacobian_source == {"f": "automatic", "g": "automatic"}
    assert user.jacobian_source == {"f": "user", "g": "user"}
    lo, hi = np.array([-1.0, -0.5]), np.array([2.0, 3.0])
    a_lo, a_hi = interval_matrix(auto.jacobians()[0], lo, hi)
    u_lo, u_hi = interval_matrix(user.jacobians()[0], lo, hi)
    # same formula as jf: the same range up to the outward rounding of a few operations (<= 4 ulp)
    ulp = 4 * np.finfo(float).eps
    assert a_lo[0, 1] == 0.0 and a_hi[0, 1] == 0.0 and a_lo[1, 0] == 0.0  # structural zeros stay exact
    assert a_lo[0, 0] <= 0.5 <= a_hi[0, 0] and a_hi[0, 0] - a_lo[0, 0] <= ulp
    np.testing.assert_allclose(a_lo, u_lo, rtol=ulp, atol=0)
    np.testing.assert_allclose(a_hi, u_hi, rtol=ulp, atol=0)
    np.testing.assert_allclose([a_lo[1, 1], a_hi[1, 1]], [0.5 * np.cos(3.0), 0.5], rtol=ulp)


def test_a_jacobian_wrong_only_away_from_the_origin_is_caught():
    def bad(x):
        return [[0.5, 0.0], [0.0, 0.5 * np.cos(x[1]) + 0.01 * x[0] ** 2]]

    with pytest.raises(DataError, match="derivative of f is in"):
        NonlinearSystem(f, g, G=[[1.0], [0.0]], H=[[0.5]], f_jacobian=bad)


def test_simulation_satisfies_the_model_equations_and_noise_bounds():
    s = gsisio.paper_system()
    d = gsisio.paper_input(50)
    sim = simulate_nonlinear(s, gsisio.paper_bounds(), d, seed=3, runs=4)
    assert sim.x.shape == (4, 50, 2) and sim.y.shape == (4, 50, 2)
    np.testing.assert_allclose(sim.x[:, 1:], s.evaluate_f(sim.x[:, :-1]) + d[:-1] @ s.G.T + sim.w[:, :-1], atol=1e-12)
    np.testing.assert_allclose(sim.y, s.evaluate_g(sim.x) + d @ s.H.T + sim.v, atol=1e-12)
    assert np.all(np.abs(sim.w) <= 0.2 + 1e-15) and np.all(np.isclose(np.abs(sim.v), 0.2))  # bang-bang
    with pytest.raises(DataError, match="d"):
        simulate_nonlinear(s, gsisio.paper_bounds(), np.zeros((10, 3)))


def test_a_matrix_product_is_a_component_map_on_batches_and_other_forms_get_one_line() -> None:
    """``lambda x: A @ x`` once passed design and crashed the simulation of Monte Carlo batches."""
    from intervalobs import Bounds

    A, C = np.array([[0.9, 0.1], [0.0, 0.8]]), np.array([[1.0, 0.0]])
    system = NonlinearSystem(lambda x: A @ x, lambda x: C @ x, [[1.0], [0.0]], [[1.0]])
    bounds = Bounds(x0=([-1, -1], [1, 1]), w=(-0.01, 0.01), v=(-0.01, 0.01))
    sim = simulate_nonlinear(system, bounds, np.zeros((3, 12, 1)), seed=0, runs=3)
    np.testing.assert_allclose(sim.x[:, 1:], sim.x[:, :-1] @ A.T + sim.w[:, :-1], rtol=1e-12, atol=1e-14)
    with pytest.raises(DimensionError, match="list of state components"):  # rows of points: said at once
        NonlinearSystem(lambda x: x @ A.T, lambda x: C @ x, [[1.0], [0.0]], [[1.0]])
