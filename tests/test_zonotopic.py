"""Seed 002 observers: enclosure under extreme noise and vertex θ, run == step, MC axis, Corollary 5.4."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds, LTISystem
from intervalobs.design.hinf import hinf_gain, zonotope_size_gain
from intervalobs.errors import AssumptionError, DesignError
from intervalobs.examples import numerical3, two_tank
from intervalobs.observers import IntervalObserver
from intervalobs.observers.zonotopic import IntegratedObserver, ZonotopicObserver
from intervalobs.simulate import simulate

CASES = {
    "68": (numerical3.system("68"), numerical3.bounds(), numerical3.time_grid()),
    "70": (numerical3.system("70"), numerical3.bounds(), numerical3.time_grid()),
    "tank": (two_tank.system(), two_tank.bounds(), two_tank.time_grid()[:400]),
}


def _input(name: str, t: np.ndarray) -> np.ndarray:
    return two_tank.input_signal(t) if name == "tank" else numerical3.input_signal(t)


def _gain(system: LTISystem) -> np.ndarray:
    return hinf_gain(system.A, system.C, system.E, system.F).gain


@pytest.mark.parametrize("case", list(CASES), ids=list(CASES))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_enclosure_under_extreme_noise(case: str, seed: int) -> None:
    system, bounds, t = CASES[case]
    u = _input(case, t)
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed, runs=8)
    size = zonotope_size_gain(system.A, system.C, system.E, system.F, rho=0.99 if case == "tank" else 0.9)
    observers = [
        ZonotopicObserver(system, bounds, size.gain),
        ZonotopicObserver(system, bounds, _gain(system), order=system.n),
        IntegratedObserver.design(system, bounds, fallback="hinf"),
    ]
    for observer in observers:
        report = observer.run(t, sim.y, u).enclosure(sim.x)
        assert report.max_violation == 0.0, type(observer).__name__
        assert report.fraction == 1.0


def test_run_equals_repeated_step_with_monte_carlo_axis() -> None:
    system, bounds, t = CASES["70"]
    u = _input("70", t)
    sim = simulate(system, bounds, t, u=u, noise="uniform", seed=4, runs=3)
    observer = ZonotopicObserver(system, bounds, _gain(system), order=6)
    est = observer.run(t, sim.y, u)
    assert est.lower.shape == (3, t.size, 3)
    for r in range(3):
        single = observer.run(t, sim.y[r], u)
        np.testing.assert_allclose(single.lower, est.lower[r], rtol=0, atol=1e-12)
        state = observer.init()
        for k in range(t.size - 1):
            np.testing.assert_allclose(state.lower, est.lower[r, k], rtol=0, atol=1e-12)
            np.testing.assert_allclose(state.upper, est.upper[r, k], rtol=0, atol=1e-12)
            state = observer.step(state, sim.y[r, k], u[k])


def test_integrated_equals_interval_framer_corollary_5_4() -> None:
    system, bounds, t = CASES["68"]
    u = _input("68", t)
    sim = simulate(system, bounds, t, u=u, seed=5)
    integrated = IntegratedObserver.design(system, bounds)
    framer = IntervalObserver(system, bounds, integrated.L, method="framer")
    a, b = integrated.run(t, sim.y, u), framer.run(t, sim.y, u)
    np.testing.assert_allclose(a.lower, b.lower, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.upper, b.upper, rtol=0, atol=1e-12)
    assert integrated.gain_design is not None and integrated.gain_design.monotone
    assert integrated.spectral_radius < 1  # ρ(|M| + D) certified, ΔA included


@pytest.mark.parametrize("case", ["68", "70"])
def test_zonotope_hull_never_wider_than_framer_with_same_gain(case: str) -> None:
    system, bounds, t = CASES[case]
    u = _input(case, t)
    sim = simulate(system, bounds, t, u=u, seed=6)
    gain = _gain(system)
    zono = ZonotopicObserver(system, bounds, gain).run(t, sim.y, u)
    framer = IntervalObserver(system, bounds, gain, method="framer").run(t, sim.y, u)
    slack = 1e-9 * (1 + np.abs(framer.upper))
    assert np.all(zono.upper <= framer.upper + slack) and np.all(zono.lower >= framer.lower - slack)


def test_certificates_include_delta_a() -> None:
    system, bounds, _ = CASES["tank"]
    printed = np.array([[0.6647], [0.6542]])  # Fig. 9 set-based gain: rho(|M|) = 1.000014
    observer = ZonotopicObserver(system, bounds, printed)
    assert observer.spectral_radius < 1 and not observer.certified
    with pytest.raises(DesignError, match="stable width system"):
        IntervalObserver(system, bounds, printed, method="framer")
    good = ZonotopicObserver(system, bounds, hinf_gain(system.A, system.C, system.E, system.F, monotone=True).gain)
    assert good.certified and good.width_spectral_radius < 1


def test_errors() -> None:
    system, bounds, _ = CASES["70"]
    printed = np.array([[-1.1376], [-1.9167], [-1.2604]])
    with pytest.raises(DesignError, match="diverge"):
        ZonotopicObserver(system, bounds, printed)
    assert ZonotopicObserver(system, bounds, printed, allow_unstable=True).spectral_radius > 2
    with pytest.raises(AssumptionError, match="column 1"):
        IntegratedObserver.design(system, bounds)
    fallback = IntegratedObserver.design(system, bounds, fallback="hinf")
    assert fallback.fallback is not None and "monotonicity dropped" in fallback.fallback
    assert fallback.meta()["fallback"] == fallback.fallback
    with pytest.raises(TypeError, match="unexpected keyword"):
        IntegratedObserver.design(system, bounds, gamma=1.0)
    continuous = LTISystem(-np.eye(2), [[1.0, 0.0]])
    box = Bounds((-np.ones(2), np.ones(2)))
    with pytest.raises(AssumptionError, match="discrete time"):
        ZonotopicObserver(continuous, box, np.ones((2, 1)))
    with pytest.raises(AssumptionError, match="discrete time"):
        IntegratedObserver(continuous, box, np.ones((2, 1)))
    with pytest.raises(DesignError, match="order"):
        ZonotopicObserver(system, bounds, _gain(system), order=2)


def test_without_parameter_uncertainty_zonotope_is_exact_linear_propagation() -> None:
    """With dA = None and no reduction the zonotope is the exact reachable set of the error system."""
    base = numerical3.system("70")
    system = LTISystem(base.A, base.C, B=base.B, E=base.E, F=base.F, dt=base.dt)
    bounds = numerical3.bounds()
    t = numerical3.time_grid()[:30]
    u = numerical3.input_signal(t)
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=7, runs=5)
    gain = _gain(system)
    observer = ZonotopicObserver(system, bounds, gain, order=10_000)
    est = observer.run(t, sim.y, u)
    assert est.enclosure(sim.x).max_violation == 0.0
    # the hull of the exact error set: sum over k of |M^k G| rows, plus the initial box
    m = base.A - gain @ base.C
    g = np.hstack([base.E, -gain @ base.F])
    radius = np.abs(np.linalg.matrix_power(m, 29)).sum(axis=1)
    for k in range(29):
        radius = radius + np.abs(np.linalg.matrix_power(m, k) @ g).sum(axis=1)
    np.testing.assert_allclose(0.5 * (est.upper[0, -1] - est.lower[0, -1]), radius, rtol=1e-9)


def test_zonotopic_design_classmethod() -> None:
    system, bounds, _ = CASES["68"]
    observer = ZonotopicObserver.design(system, bounds, rho=0.9)
    assert observer.gain_design is not None and observer.gain_design.lmi.startswith("(26)")
    assert observer.meta()["gain_design"]["gain"] == observer.L.ravel().tolist()
    hinf = ZonotopicObserver.design(system, bounds, lmi="(19)", order=4)
    assert hinf.order == 4 and hinf.certified
    with pytest.raises(DesignError, match="lmi"):
        ZonotopicObserver.design(system, bounds, lmi="(99)")
    with pytest.raises(TypeError, match="unexpected keyword"):
        ZonotopicObserver.design(system, bounds, gamma=2.0)
