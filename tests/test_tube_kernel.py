"""The compiled recursion of IntervalObserver.run (observers/tube_kernel.py): the step loop's numbers, sound bounds."""

import numpy as np
import pytest

from conftest import random_system, simulate_truth, unit_bounds
from intervalobs import IntervalObserver, LTISystem, simulate
from intervalobs.observers import interval_observer
from intervalobs.systems import Bounds


def compiled_and_loop(monkeypatch, observer, t, y, u=None):
    """``run`` through the compiled kernel and through the step loop, on the same record."""
    estimates = []
    for threshold in (0, 10**15):
        with monkeypatch.context() as patch:
            patch.setattr(interval_observer, "COMPILED_MIN_SAMPLES", threshold)
            patch.setattr(interval_observer, "COMPILED_WARM_MIN_SAMPLES", threshold)
            estimates.append(observer.run(t, y, u))
    return estimates


def assert_same_boxes(compiled, loop):
    """Equal to 1e-12 of the magnitude; the compiled box is never narrower than the loop's beyond that.

    Both evaluate the same sums in round-to-nearest in another order and widen by the same margin (at least
    1e-12 of the same magnitude), so they differ by rounding only.
    """
    for got, want in ((compiled.lower, loop.lower), (compiled.upper, loop.upper)):
        assert np.array_equal(np.isnan(got), np.isnan(want))
    scale = np.nan_to_num(np.abs(loop.lower) + np.abs(loop.upper), nan=0.0) + 1e-300
    assert np.nanmax(np.abs(compiled.lower - loop.lower) / scale) <= 1e-12
    assert np.nanmax(np.abs(compiled.upper - loop.upper) / scale) <= 1e-12
    assert np.all(np.nan_to_num(compiled.lower - loop.lower) <= 1e-12 * scale)
    assert np.all(np.nan_to_num(loop.upper - compiled.upper) <= 1e-12 * scale)


def rotations(uncertain: bool, damping: float = 1.0) -> tuple[LTISystem, Bounds]:
    """Two damped rotations (discrete time): the tube's 2×2 blocks and modal coordinates have work to do."""
    blocks = []
    for radius, angle in ((0.9, 0.5), (0.7, 1.3)):
        blocks.append(damping * radius * np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]))
    A = np.block([[blocks[0], np.zeros((2, 2))], [np.zeros((2, 2)), blocks[1]]])
    dA = (-0.005 * np.ones((4, 4)), 0.005 * np.ones((4, 4))) if uncertain else None
    system = LTISystem(A, [[1.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]], B=[[0.0], [1.0], [0.0], [0.5]], dt=1.0, dA=dA)
    return system, Bounds((-np.ones(4), np.ones(4)), w=(-0.1 * np.ones(4), 0.1 * np.ones(4)), v=(-0.05, 0.05))


def given_gain(uncertain: bool, coordinates: str) -> tuple[LTISystem, Bounds, IntervalObserver]:
    """A hand-given gain of :func:`rotations` in the identity, a dense ``T``, or ``T`` with 2×2 blocks."""
    framer = coordinates == "framer-T"  # |M| of a slow rotation is unstable: a faster one for the framer
    system, bounds = rotations(uncertain, 0.5 if framer else 1.0)
    gain = 0.2 * np.array([[1.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    T = np.eye(4) + (0.1 if framer else 0.3) * np.random.default_rng(4).normal(size=(4, 4))
    method = "framer" if framer else "tube"
    options = {"identity": {}, "T": {"T": T}, "framer-T": {"T": T}, "blocks": {"T": T, "blocks": (2, 2)}}[coordinates]
    return system, bounds, IntervalObserver(system, bounds, gain, method=method, **options)


@pytest.mark.parametrize("coordinates", ["identity", "T", "framer-T", "blocks"])
@pytest.mark.parametrize("uncertain", [False, True], ids=["point", "dA"])
def test_given_gains_in_every_coordinates_match_the_step_loop_and_enclose(monkeypatch, uncertain, coordinates):
    system, bounds, observer = given_gain(uncertain, coordinates)
    t = np.arange(300.0)
    u = np.sin(0.05 * t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=2, runs=3)
    for y in (sim.y, sim.y[1]):  # a Monte Carlo batch and one record
        compiled, loop = compiled_and_loop(monkeypatch, observer, t, y, u)
        assert_same_boxes(compiled, loop)
    report = compiled.enclosure(sim.x[1])
    assert report.fraction == 1.0 and report.max_violation == 0.0


CASES = [(0, 3, 2, False), (1, 4, 1, True), (5, 5, 2, False), (8, 6, 2, True)]


@pytest.mark.parametrize("method", ["tube", "framer"])
@pytest.mark.parametrize("seed,n,p,continuous", CASES, ids=[f"n{c[1]}-p{c[2]}-{'ct' if c[3] else 'dt'}" for c in CASES])
def test_default_designs_match_the_step_loop_under_extreme_noise(monkeypatch, seed, n, p, continuous, method):
    """What ``design`` returns (several gains for the tube), with interval ΔA at its vertices in the truth."""
    system, bounds = random_system(seed, n, p, continuous, True)
    h = 0.05 if continuous else None
    observer = IntervalObserver.design(system, bounds, h=h, method=method)
    t = np.arange(250) * (h or 1.0)
    sim = simulate(system, bounds, t, noise="extreme", seed=seed, runs=4)
    compiled, loop = compiled_and_loop(monkeypatch, observer, t, sim.y)
    assert_same_boxes(compiled, loop)
    report = compiled.enclosure(sim.x)
    assert report.fraction == 1.0 and report.max_violation == 0.0


@pytest.mark.parametrize("seed,n,p", [(0, 3, 2), (10, 4, 1)])
def test_several_gains_enclose_exact_exponentials_at_the_vertices_of_the_box(monkeypatch, seed, n, p):
    """Truth independent of the library: ΔA and x0 at vertices, the noise switching sign inside every step."""
    random, _ = random_system(seed, n, p, True, True)
    system = LTISystem(random.A, random.C, E=np.eye(n), dA=random.dA)
    observer = IntervalObserver.design(system, unit_bounds(n, n, p), h=0.05)
    assert observer.gains.shape[0] >= 2
    rng = np.random.default_rng(seed)
    steps, d = 200, system.dA[1]
    for _ in range(3):
        delta = d * rng.choice([-1.0, 1.0], d.shape)
        x, y = simulate_truth(system.A, system.E, system.C, delta, rng.choice([-1.0, 1.0], n), 0.05, steps, rng)
        compiled, loop = compiled_and_loop(monkeypatch, observer, 0.05 * np.arange(steps), y)
        assert_same_boxes(compiled, loop)
        assert np.all(compiled.lower <= x) and np.all(x <= compiled.upper)


def test_long_records_take_the_compiled_path_and_short_ones_the_loop(monkeypatch):
    _, _, observer = given_gain(True, "identity")
    calls = []
    original = IntervalObserver._compiled
    monkeypatch.setattr(IntervalObserver, "_compiled", lambda self, *a: calls.append(1) or original(self, *a))
    monkeypatch.setattr(interval_observer, "COMPILED_MIN_SAMPLES", 1000)
    monkeypatch.setattr(interval_observer, "_kernel_loaded", lambda: False)
    t = np.arange(400.0)
    u = np.zeros((400, 1))
    observer.run(t, np.zeros((400, 2)), u)
    assert calls == []
    observer.run(t, np.zeros((3, 400, 2)), u)
    assert calls == [1]


def test_once_loaded_the_compiled_loop_serves_short_records(monkeypatch):
    """A process that has loaded the kernel runs records from COMPILED_WARM_MIN_SAMPLES samples on with it (the
    same boxes as the step loop); shorter ones, and a process that has not loaded it, keep the step loop."""
    _, _, observer = given_gain(True, "identity")
    t, u = np.arange(40.0), np.zeros((40, 1))
    y = np.random.default_rng(5).normal(scale=0.1, size=(40, 2))
    monkeypatch.setattr(interval_observer, "COMPILED_MIN_SAMPLES", 0)
    observer.run(t, y, u)
    assert interval_observer._kernel_loaded()
    monkeypatch.setattr(interval_observer, "COMPILED_MIN_SAMPLES", 10**15)
    calls = []
    original = IntervalObserver._compiled
    monkeypatch.setattr(IntervalObserver, "_compiled", lambda self, *a: calls.append(1) or original(self, *a))
    warm = observer.run(t, y, u)
    observer.run(t[:8], y[:8], u[:8])
    assert calls == [1]
    monkeypatch.setattr(interval_observer, "COMPILED_WARM_MIN_SAMPLES", 10**15)
    assert_same_boxes(warm, observer.run(t, y, u))


@pytest.mark.parametrize("uncertain", [False, True], ids=["point", "dA"])
def test_dense_noise_generators_match_the_step_loop(monkeypatch, uncertain):
    """Process noise through a dense ``E`` (the tube's constant noise sums differ from the box's)."""
    random, bounds = random_system(3, 4, 2, False, uncertain)
    E = np.random.default_rng(3).normal(size=(4, 6))
    system = LTISystem(random.A, random.C, E=E, dt=1.0, dA=random.dA)
    bounds = Bounds(bounds.x0, w=(-0.1 * np.ones(6), 0.1 * np.ones(6)), v=bounds.v)
    observer = IntervalObserver.design(system, bounds)
    t = np.arange(200.0)
    sim = simulate(system, bounds, t, noise="vertex", seed=4, runs=3)
    compiled, loop = compiled_and_loop(monkeypatch, observer, t, sim.y)
    assert_same_boxes(compiled, loop)
    report = compiled.enclosure(sim.x)
    assert report.fraction == 1.0 and report.max_violation == 0.0
