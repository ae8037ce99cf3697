import numpy as np
import pytest

from conftest import random_system
from intervalobs import DataError, DesignError, IntervalObserver, LTISystem, simulate
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
    monkeypatch.setattr(tube, "_REFINE_MAX_ENTRIES", 0)
    plain = tube.design_tube_gain(model, system.C, system.F, v_radius)
    assert refined is not None and plain is not None
    assert np.all(refined.steady_radius <= plain.steady_radius)
    assert refined.candidate in (plain.candidate, f"{plain.candidate}+refined")
