"""The truth simulators' shared helpers and their refusal of bad arguments."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds, LTISystem, simulate, simulate_nonlinear, simulate_sampled
from intervalobs.errors import DataError
from intervalobs.examples import gsisio
from intervalobs.examples import hgio as sampled_example
from intervalobs.simulate import NOISE_KINDS, draw_box, noise_signal, runge_kutta_step


@pytest.fixture
def lti() -> tuple[LTISystem, Bounds]:
    return LTISystem([[-1.0, 0.5], [0.0, -2.0]], [[1.0, 0.0]]), Bounds(x0=(-1, 1), w=(-0.1, 0.2), v=(-0.01, 0.01))


@pytest.mark.parametrize("kind", NOISE_KINDS)
def test_noise_stays_in_its_box(kind):
    lower, upper = np.array([-1.0, 0.0, 2.0]), np.array([1.0, 0.5, 2.0])
    signal = noise_signal(kind, lower, upper, 300, np.random.default_rng(1), runs=4)
    assert signal.shape == (4, 300, 3)
    assert np.all((signal >= lower) & (signal <= upper))


@pytest.mark.parametrize("kind", ["extreme", "vertex"])
def test_bang_bang_and_vertex_noise_sit_on_the_bounds_and_switch(kind):
    lower, upper = np.array([-1.0, 0.0]), np.array([1.0, 0.5])
    signal = noise_signal(kind, lower, upper, 400, np.random.default_rng(2))
    assert np.all((signal == lower) | (signal == upper))
    switches = np.count_nonzero(np.diff(signal, axis=0), axis=0)
    assert np.all(switches > 10)  # switches inside the record (0.1 per step for "extreme", 0.5 for "vertex")


def test_draw_box_gives_vertices_for_extreme_noise_and_interior_points_otherwise():
    lower, upper = np.zeros((2, 2)), np.ones((2, 2))
    vertices = draw_box("extreme", lower, upper, np.random.default_rng(0), 50)
    assert vertices.shape == (50, 2, 2) and set(np.unique(vertices)) == {0.0, 1.0}
    inside = draw_box("uniform", lower, upper, np.random.default_rng(0), 50)
    assert np.all((inside > 0) & (inside < 1))


def test_runge_kutta_step_is_exact_for_cubic_rates_and_fourth_order():
    # x' = 4t^3: RK4 reduces to Simpson's rule, exact for cubics.
    end = runge_kutta_step(lambda t, x: np.full_like(x, 4 * t**3), 0.0, np.zeros(1), 1.0)
    np.testing.assert_allclose(end, [1.0], rtol=0, atol=4 * np.finfo(float).eps)
    # x' = -x over [0, 1]: the global error shrinks by ~2^4 when the step halves.
    errors = []
    for steps in (10, 20):
        x = np.ones(1)
        for k in range(steps):
            x = runge_kutta_step(lambda t, xx: -xx, k / steps, x, 1.0 / steps)
        errors.append(abs(x[0] - np.exp(-1.0)))
    assert 14 < errors[0] / errors[1] < 18


def _call(name, system, bounds, **kwargs):
    if name == "lti":
        return simulate(system, bounds, np.arange(5) * 0.1, **kwargs)
    if name == "sampled":
        t = np.arange(0.0, 0.05, sampled_example.STEP)
        return simulate_sampled(sampled_example.system(), sampled_example.bounds(), t, **kwargs)
    model = gsisio.paper_system()
    return simulate_nonlinear(model, gsisio.paper_bounds(), np.zeros((5, model.q)), **kwargs)


@pytest.mark.parametrize("simulator", ["lti", "sampled", "nonlinear"])
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"runs": 0}, r"^runs: expected a positive integer, got 0$"),
        ({"runs": 2.5}, r"^runs: expected a positive integer, got 2\.5$"),
        ({"runs": True}, r"^runs: expected a positive integer, got True$"),
        ({"seed": -1}, r"^seed: expected a nonnegative integer, got -1$"),
        ({"noise": "gaussian"}, r"^noise: expected one of \('uniform', .*\), got 'gaussian'$"),
    ],
    ids=["runs-zero", "runs-float", "runs-bool", "seed", "noise"],
)
def test_bad_arguments_are_refused_in_one_line(lti, simulator, kwargs, message):
    with pytest.raises(DataError, match=message):
        _call(simulator, *lti, **kwargs)


@pytest.mark.parametrize("simulator", ["lti", "sampled"])
def test_bad_substeps_are_refused(lti, simulator):
    system = LTISystem(lti[0].A, lti[0].C)  # continuous time: substeps count
    with pytest.raises(DataError, match=r"^substeps: expected a positive integer, got 0$"):
        _call(simulator, system, lti[1], substeps=0)


def test_user_noise_needs_both_signals(lti):
    with pytest.raises(DataError, match=r"^noise: expected a dict with the keys 'w' and 'v', got keys \['w'\]$"):
        simulate(*lti, np.arange(5) * 0.1, noise={"w": np.zeros((50, 2))})
