from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import random_system, simulate_truth, unit_bounds
from intervalobs import DesignError, IntervalObserver, LTISystem, simulate
from intervalobs.design.tube import abs_powers
from intervalobs.errors import DataError, DimensionError
from intervalobs.observers import interval_observer
from intervalobs.systems import Bounds

CASES = [
    (seed, n, p, cont, unc)
    for seed, (n, p, cont, unc) in enumerate(
        [
            (2, 1, True, False),
            (3, 2, True, True),
            (4, 1, True, False),
            (5, 2, True, True),
            (6, 1, True, False),
            (2, 1, False, True),
            (3, 1, False, False),
            (4, 2, False, True),
            (5, 1, False, False),
            (6, 2, False, True),
        ]
    )
]


@pytest.mark.parametrize("method", ["tube", "framer"])
@pytest.mark.parametrize(
    "seed,n,p,continuous,uncertain",
    CASES,
    ids=[f"n{c[1]}-p{c[2]}-{'ct' if c[3] else 'dt'}{'-dA' if c[4] else ''}" for c in CASES],
)
def test_random_systems_are_designed_and_enclosed_under_extreme_noise(seed, n, p, continuous, uncertain, method):
    system, bounds = random_system(seed, n, p, continuous, uncertain)
    h = 0.05 if continuous else None
    observer = IntervalObserver.design(system, bounds, h=h, method=method)
    assert observer.spectral_radius < 1
    t = np.arange(300) * (h or 1.0)
    for noise_seed in range(3):
        sim = simulate(system, bounds, t, noise="extreme", seed=noise_seed, runs=4)
        estimate = observer.run(t, sim.y)
        report = estimate.enclosure(sim.x)
        assert report.fraction == 1.0 and report.max_violation == 0.0
        width = estimate.width().max(axis=(0, 2))
        if uncertain:  # the width follows |x|: compare the last third with the second third
            assert width[200:].max() <= 2 * width[100:200].max() + 1e-9
        else:
            assert width[200:].max() <= width[100:200].max() * (1 + 1e-9) + 1e-12


def test_run_and_step_agree():
    system, bounds = random_system(1, 3, 2, True, True)
    observer = IntervalObserver.design(system, bounds, h=0.05)
    t = np.arange(120) * 0.05
    sim = simulate(system, bounds, t, noise="uniform", seed=5)
    estimate = observer.run(t, sim.y)
    state = observer.init()
    for k in range(t.size):
        np.testing.assert_allclose(state.lower, estimate.lower[k], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(state.upper, estimate.upper[k], rtol=1e-12, atol=1e-12)
        state = observer.step(state, sim.y[k])


def test_run_and_step_agree_without_uncertainty_and_with_inputs():
    rng = np.random.default_rng(2)
    system = LTISystem([[0.0, 1.0], [-2.0, -0.5]], [[1.0, 0.0]], B=[[0.0], [1.0]])
    bounds = Bounds(([-1, -1], [1, 1]), w=([-0.1, -0.1], [0.1, 0.1]), v=([-0.01], [0.01]))
    observer = IntervalObserver.design(system, bounds, h=0.02)
    t = np.arange(500) * 0.02
    u = rng.normal(size=(500, 1))
    sim = simulate(system, bounds, t, u=u, seed=1, runs=2)
    estimate = observer.run(t, sim.y, u)
    assert estimate.enclosure(sim.x).max_violation == 0.0
    state = observer.init()
    for k in range(t.size):
        upper = np.broadcast_to(state.upper, estimate.upper[:, k].shape)
        np.testing.assert_allclose(upper, estimate.upper[:, k], rtol=1e-12, atol=1e-12)
        state = observer.step(state, sim.y[:, k], u[k])


def test_undetectable_pair_is_refused():
    system = LTISystem([[1.2, 0.0], [0.0, 0.5]], [[0.0, 1.0]], dt=1.0)
    bounds = Bounds(([-1, -1], [1, 1]))
    with pytest.raises(DesignError, match="not detectable"):
        IntervalObserver.design(system, bounds)


def test_unstable_given_gain_is_refused():
    system = LTISystem([[1.2, 0.0], [0.0, 0.5]], [[1.0, 1.0]], dt=1.0)
    with pytest.raises(DesignError, match="spectral radius"):
        IntervalObserver(system, Bounds(([-1, -1], [1, 1])), L=[[0.0], [0.0]], method="framer")


def test_bad_records_are_refused_with_the_argument_name():
    system, bounds = random_system(0, 2, 1, True, False)
    observer = IntervalObserver.design(system, bounds, h=0.05)
    t = np.arange(10) * 0.05
    y = np.zeros((10, 1))
    with pytest.raises(DataError, match=r"y: expected shape \(10, 1\)"):
        observer.run(t, y[:9])
    bad = y.copy()
    bad[3, 0] = np.nan
    with pytest.raises(DataError, match="y: expected finite values, got NaN or inf at index"):
        observer.run(t, bad)
    with pytest.raises(DataError, match="t: expected uniform spacing"):
        observer.run(t * 2, y)
    with pytest.raises(DataError, match="t: expected strictly increasing"):
        observer.run(t[::-1], y)
    with pytest.raises(TypeError, match="unexpected keyword argument 'gain'"):
        IntervalObserver.design(system, bounds, h=0.05, gain=1)


@pytest.mark.parametrize("coordinates", [None, [[1.0, 0.5], [0.0, 1.0]]], ids=["identity", "T"])
@pytest.mark.parametrize("uncertain", [False, True], ids=["point", "dA"])
def test_tube_is_never_wider_than_the_framer_with_the_same_gain(uncertain, coordinates):
    # a damped rotation: |M|^i overestimates |M^i|, so the framer is strictly wider than the tube
    angle = 0.8
    A = 0.6 * np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    dA = (-0.01 * np.ones((2, 2)), 0.01 * np.ones((2, 2))) if uncertain else None
    system = LTISystem(A, [[1.0, 0.0]], dt=1.0, dA=dA)
    bounds = Bounds(([-1, -1], [1, 1]), w=([-0.1, -0.1], [0.1, 0.1]), v=([-0.05], [0.05]))
    gain = [[0.0], [0.0]]
    tube = IntervalObserver(system, bounds, gain, coordinates)
    framer = IntervalObserver(system, bounds, gain, coordinates, method="framer")
    t = np.arange(200.0)
    sim = simulate(system, bounds, t, seed=3, runs=3)
    tube_est, framer_est = tube.run(t, sim.y), framer.run(t, sim.y)
    assert tube_est.enclosure(sim.x).max_violation == 0.0
    assert np.all(tube_est.width() <= framer_est.width() * (1 + 1e-9))
    assert tube_est.width()[:, 100:].mean() < 0.9 * framer_est.width()[:, 100:].mean()


def test_tube_with_an_unstable_gain_is_refused():
    system = LTISystem([[1.2, 0.0], [0.0, 0.5]], [[1.0, 1.0]], dt=1.0)
    with pytest.raises(DesignError, match="Schur stable"):
        IntervalObserver(system, Bounds(([-1, -1], [1, 1])), L=[[0.0], [0.0]])


def test_step_refuses_bad_samples_with_the_argument_name():
    system, bounds = random_system(0, 2, 1, True, False)
    observer = IntervalObserver.design(system, bounds, h=0.05)
    state = observer.init()
    with pytest.raises(DataError, match=r"^y: expected finite values, got NaN or inf at index \(0,\)$"):
        observer.step(state, [np.inf])
    with pytest.raises(DataError, match="y: expected finite values with last dimension 1"):
        observer.step(state, [0.0, 1.0])
    with pytest.raises(DataError, match="u: expected finite values with last dimension 0"):
        observer.step(state, [0.0], [1.0])


def test_first_box_is_never_wider_than_the_prior_in_any_coordinates():
    # In coordinates T ≠ I the z-box of the prior maps back wider than the prior itself.
    A = np.array([[0.5, 0.4], [-0.3, 0.6]])
    system = LTISystem(A, [[1.0, 0.0]], dt=1.0)
    bounds = Bounds(([-1, -2], [1, 2]), w=([-0.1, -0.1], [0.1, 0.1]), v=([-0.05], [0.05]))
    T = np.array([[1.0, 1.0], [-1.0, 1.0]])
    obs = IntervalObserver(system, bounds, [[0.5], [0.0]], T=T, method="framer")
    t = np.arange(5.0)
    sim = simulate(system, bounds, t, seed=0, runs=2)
    est = obs.run(t, sim.y)
    np.testing.assert_array_equal(est.lower[:, 0], np.broadcast_to([-1.0, -2.0], (2, 2)))
    np.testing.assert_array_equal(est.upper[:, 0], np.broadcast_to([1.0, 2.0], (2, 2)))
    state = obs.init()
    np.testing.assert_array_equal(state.lower, [-1.0, -2.0])
    assert est.enclosure(sim.x).max_violation == 0.0
    state = obs.step(state, sim.y[0, 0])
    np.testing.assert_allclose(state.upper, est.upper[0, 1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("seed,n,p,continuous,uncertain", [c for c in CASES if c[2] * c[1] <= 16][:6])
def test_refined_gain_is_never_looser_than_the_winning_candidate(monkeypatch, seed, n, p, continuous, uncertain):
    """The local refinement of the tube gain: no state's verified steady radius above the unrefined winner's."""
    from intervalobs.design import tube
    from intervalobs.systems.sampling import sampled_model

    system, bounds = random_system(seed, n, p, continuous, uncertain)
    model = sampled_model(system, bounds.resolve(system), 0.05 if continuous else None)
    v_radius = bounds.resolve(system).radius("v")
    refined = tube.design_tube_gain(model, system.C, system.F, v_radius)
    monkeypatch.setattr(tube, "_SMALL_GAIN_ENTRIES", 0)
    monkeypatch.setattr(tube, "_descended", lambda *args: None)  # the larger gains' refinement (test_tube_design.py)
    plain = tube.design_tube_gain(model, system.C, system.F, v_radius)
    assert refined is not None and plain is not None
    assert np.all(refined.steady_radius <= plain.steady_radius)
    assert refined.candidate in (plain.candidate, f"{plain.candidate}+refined")


# (seed, n, p): designs with companion gains, with equal and unequal horizons
SEVERAL_GAIN_CASES = [(0, 3, 2), (1, 3, 1), (10, 4, 1), (9, 4, 2)]


def banked_observer(seed: int, n: int, p: int) -> tuple[LTISystem, Bounds, IntervalObserver]:
    """A random uncertain continuous system (E = I, unit boxes) and its designed tube, which has companions."""
    random, _ = random_system(seed, n, p, True, True)
    system = LTISystem(random.A, random.C, E=np.eye(n), dA=random.dA)
    bounds = unit_bounds(n, n, p)
    observer = IntervalObserver.design(system, bounds, h=0.05)
    assert observer.gains.shape[0] >= 2
    return system, bounds, observer


@pytest.mark.parametrize("seed,n,p", SEVERAL_GAIN_CASES)
def test_several_gains_enclose_an_independent_truth_and_are_never_wider_than_one_gain(seed, n, p):
    """Truth from exact exponentials with ΔA and x0 at box vertices and the noise switching sign inside the
    steps; the intersected box is never wider than either gain's own tube at any step.

    The per-gain sums are the ones a single-gain observer forms, in another order (over J_max ≤ 200 terms of
    4 entries padded with zeros), so they agree to a few hundred ulps: 1e-12 relative covers it.
    """
    system, bounds, observer = banked_observer(seed, n, p)
    alone = [IntervalObserver(system, bounds, gain, h=0.05) for gain in observer.gains]
    rng = np.random.default_rng(seed)
    steps, d = 200, system.dA[1]
    t = 0.05 * np.arange(steps)
    for _ in range(3):
        delta = d * rng.choice([-1.0, 1.0], d.shape)
        x, y = simulate_truth(system.A, system.E, system.C, delta, rng.choice([-1.0, 1.0], n), 0.05, steps, rng)
        estimate = observer.run(t, y)
        assert np.all(estimate.lower <= x) and np.all(x <= estimate.upper)
        for single in alone:
            own = single.run(t, y)
            assert np.all(own.lower <= x) and np.all(x <= own.upper)
            assert np.all(estimate.width() <= own.width() * (1 + 1e-12))
    assert np.any(estimate.width() < np.min([single.run(t, y).width() for single in alone], axis=0))


def test_several_gains_run_equals_step_with_and_without_runs_axis():
    system, bounds, observer = banked_observer(1, 3, 1)
    point = IntervalObserver(LTISystem(system.A, system.C, E=system.E), bounds, observer.gains, h=0.05)
    t = 0.05 * np.arange(150)
    for obs, model in ((observer, system), (point, point.system)):
        sim = simulate(model, bounds, t, noise="extreme", seed=3, runs=3)
        batched = obs.run(t, sim.y)
        assert batched.enclosure(sim.x).max_violation == 0.0
        single = obs.run(t, sim.y[1])
        np.testing.assert_allclose(single.upper, batched.upper[1], rtol=1e-12, atol=1e-12)
        state = obs.init()
        for k in range(t.size):
            np.testing.assert_allclose(np.broadcast_to(state.lower, (3, system.n)), batched.lower[:, k], atol=1e-12)
            np.testing.assert_allclose(np.broadcast_to(state.upper, (3, system.n)), batched.upper[:, k], atol=1e-12)
            state = obs.step(state, sim.y[:, k])
    meta = observer.run(t, sim.y[0]).meta
    assert meta["gains"] == observer.gains.tolist() and meta["horizons"] == list(observer.horizons)
    assert meta["L"] == observer.gains[0].tolist()


def test_several_gains_are_refused_for_the_framer_and_bad_shapes():
    system, bounds, observer = banked_observer(0, 3, 2)
    with pytest.raises(DimensionError, match=r"^L: expected shape \(3, 2\) \(framer\), got shape \(2, 3, 2\)"):
        IntervalObserver(system, bounds, observer.gains[:2], h=0.05, method="framer")
    with pytest.raises(
        DimensionError, match=r"^L: expected shape \(3, 2\) or \(G, 3, 2\) \(tube\), got shape \(0, 3, 2\)"
    ):
        IntervalObserver(system, bounds, np.zeros((0, 3, 2)), h=0.05)
    with pytest.raises(DimensionError, match=r"^L:"):
        IntervalObserver(system, bounds, np.zeros((2, 2, 2)), h=0.05)


def test_spring_mass_tube_is_never_wider_than_any_of_its_gains_alone():
    """The example the refinement was made for: before t = 6.5 s the refined gain alone is wider than the
    winner at some steps (the transient from the prior box); the designed observer runs both, and the
    other candidates bounded in the identity coordinates."""
    from intervalobs.examples import spring_mass

    system, bounds, h = spring_mass.system(), spring_mass.bounds(), spring_mass.SAMPLING_PERIOD
    observer = IntervalObserver.design(system, bounds, h=h)
    assert observer.gains.shape[0] >= 2 and observer.design_result.candidate.endswith("+refined")
    t = h * np.arange(700)
    u = spring_mass.input_signal(t)
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=0, substeps=10, runs=2)
    estimate = observer.run(t, sim.y, u)
    assert estimate.enclosure(sim.x).max_violation == 0.0
    widths = [IntervalObserver(system, bounds, gain, h=h).run(t, sim.y, u).width() for gain in observer.gains]
    for own in widths:  # the same sums in another order (J_max ≤ 600 terms of 4 entries): 1e-12 relative
        assert np.all(estimate.width() <= own * (1 + 1e-12))
    assert np.any(widths[0] > widths[1])  # the refined gain alone is wider somewhere in the transient


def _box_sums(m, generators, box, horizon, norms):
    """The tube's noise term before generators: ``Σ_{i<ℓ}|M^i| d`` with ``d`` the box of a step's noise."""
    return np.vstack([np.zeros((1, norms.count)), np.cumsum(abs_powers(m, horizon, norms) @ box, axis=0)])


def _dense_noise_system(seed, n, p, nw, continuous, uncertain):
    """A random system whose process noise enters through a dense ``E`` (the generators mix the states)."""
    random, bounds = random_system(seed, n, p, continuous, uncertain)
    E = np.random.default_rng(seed + 1000).normal(size=(n, nw))
    system = LTISystem(random.A, random.C, E=E, dt=random.dt, dA=random.dA)
    w = 0.1 * np.ones(nw)
    return system, Bounds(bounds.x0, w=(-w, w), v=bounds.v)


@settings(max_examples=12)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(2, 4),
    p=st.integers(1, 2),
    nw=st.integers(1, 5),
    continuous=st.booleans(),
    uncertain=st.booleans(),
)
def test_noise_generators_are_never_wider_than_their_box_and_enclose(seed, n, p, nw, continuous, uncertain):
    system, bounds = _dense_noise_system(seed, n, p, nw, continuous, uncertain)
    h = 0.05 if continuous else None
    try:
        generators = IntervalObserver.design(system, bounds, h=h)
    except DesignError:  # a random ΔA box may hold an unstable matrix: nothing to compare
        return
    with mock.patch.object(interval_observer, "noise_sums", _box_sums):
        box = IntervalObserver(system, bounds, generators.gains, generators.T, h, blocks=generators.norms.sizes)
    t = np.arange(80) * (h or 1.0)
    sim = simulate(system, bounds, t, noise="vertex", seed=seed, runs=3)
    narrow, wide = generators.run(t, sim.y), box.run(t, sim.y)
    assert narrow.enclosure(sim.x).max_violation == 0.0
    # equal in exact arithmetic where the generators are the box (continuous time): noise_sums rounds each sum up
    # by 1e-12 of its terms' magnitudes, which both ends of the width carry (seed 8, n 2, continuous: 1.7e-12)
    scale = np.abs(wide.lower) + np.abs(wide.upper)
    assert np.all(narrow.width() <= wide.width() + 1e-11 * scale.max(axis=-1, keepdims=True))


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("uncertain", [False, True], ids=["point", "dA"])
def test_noise_generators_enclose_an_own_loop_truth_at_vertices_and_narrow_the_tube(seed, uncertain):
    """Discrete time, dense ``E``, several outputs: ``ΔA`` and ``x0`` at vertices, bang-bang ``w`` and ``v``."""
    system, bounds = _dense_noise_system(seed, 4, 2, 5, False, uncertain)
    observer = IntervalObserver.design(system, bounds)
    with mock.patch.object(interval_observer, "noise_sums", _box_sums):
        box = IntervalObserver(system, bounds, observer.gains, observer.T, blocks=observer.norms.sizes)
    rng = np.random.default_rng(seed)
    steps = 150
    for _ in range(3):
        a = system.A + (0.0 if system.dA is None else system.dA[1] * rng.choice([-1.0, 1.0], (4, 4)))
        x = np.empty((steps, 4))
        x[0] = rng.choice([-1.0, 1.0], 4)
        for k in range(steps - 1):
            x[k + 1] = a @ x[k] + system.E @ (0.1 * rng.choice([-1.0, 1.0], 5))
        y = x @ system.C.T + 0.05 * rng.choice([-1.0, 1.0], (steps, 2))
        estimate = observer.run(np.arange(steps, dtype=float), y)
        assert np.all(estimate.lower <= x) and np.all(x <= estimate.upper)
    ratio = estimate.width()[30:].mean() / box.run(np.arange(steps, dtype=float), y).width()[30:].mean()
    assert ratio < 0.97, ratio
