"""observe(): the estimator chosen for each kind of model is sound, filtered and near the tightest the library has."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from intervalobs import (
    Bounds,
    HullEstimator,
    IntervalObserver,
    LTISystem,
    NullSpaceGSISIO,
    RobustHullEstimator,
    observe,
    simulate,
    simulate_nonlinear,
    suggest,
)
from intervalobs.errors import ArgumentError
from intervalobs.examples import aircraft as ac
from intervalobs.examples import gsisio as nonlinear_example
from intervalobs.examples import numerical3
from intervalobs.front_door import ESTIMATORS, filtered_rows, memory_horizon

BUDGET = 5.0
"""CPU ms a sample, the issue's budget: the pilot counts CPU time, so the load of the machine does not move the
choice (the hull costs about 1 ms a sample here, the ΔA window LP 4-5 ms)."""


def _mean_width(estimate, start: int = 10) -> float:
    return float(estimate.width()[..., start:, :].sum(axis=-1).mean())


def _random_lti(seed: int, uncertain: bool) -> LTISystem:
    rng = np.random.default_rng(seed)
    n = 3
    a = rng.uniform(-0.4, 0.4, (n, n))
    a *= 0.85 / max(np.abs(np.linalg.eigvals(a)).max(), 1e-9)
    c = rng.uniform(-1.0, 1.0, (1, n))
    d = 0.01 * np.abs(a) if uncertain else None
    return LTISystem(a, c, dt=1.0, dA=None if d is None else (-d, d))


BOUNDS = Bounds(x0=(-1, 1), w=(-0.02, 0.02), v=(-0.05, 0.05))


@pytest.mark.parametrize("seed", [0, 1])
def test_point_lti_is_sound_and_within_1_1_of_the_exact_hull(seed: int) -> None:
    system = _random_lti(seed, uncertain=False)
    t = np.arange(60.0)
    truth = simulate(system, BOUNDS, t, seed=seed)
    estimate = observe(system, BOUNDS, t, truth.y, budget=BUDGET)
    assert estimate.meta["estimator"] == "HullEstimator" and estimate.meta["rows"] == "filtered"
    assert "within" in estimate.meta["why"]
    assert estimate.enclosure(truth.x).fraction == 1.0
    exact = HullEstimator.design(system, BOUNDS, horizon=None, filtered=True).run(t, truth.y)
    assert _mean_width(estimate) <= 1.1 * _mean_width(exact)
    assert _mean_width(estimate) >= _mean_width(exact) * (1 - 1e-6)  # nothing beats the exact hull


@pytest.mark.parametrize("seed", [0, pytest.param(1, marks=pytest.mark.slow)])
def test_uncertain_lti_is_sound_and_within_1_1_of_the_best(seed: int) -> None:
    system = _random_lti(seed, uncertain=True)
    t = np.arange(40.0)
    truth = simulate(system, BOUNDS, t, seed=seed, runs=3)
    # the window LP costs 4.2-4.4 CPU ms a sample here, at the edge of 5 ms; on a slower machine the bank would
    # run (1.15-1.24x the best on these records), so the choice is tested with room
    estimate = observe(system, BOUNDS, t, truth.y, budget=10 * BUDGET)
    assert estimate.meta["estimator"] == "RobustHullEstimator" and estimate.meta["rows"] == "filtered"
    assert estimate.enclosure(truth.x).fraction == 1.0
    others = [
        IntervalObserver.design(system, BOUNDS).run(t, truth.y),
        RobustHullEstimator.design(system, BOUNDS, horizon=40).run(t, truth.y),
    ]
    best = min(_mean_width(filtered_rows(e, system, BOUNDS, truth.y)) for e in others)
    assert _mean_width(estimate) <= 1.1 * best


def test_unknown_input_picks_the_decoupling_observer_and_is_sound() -> None:
    t = np.arange(3001) * ac.TE
    record = ac.simulate_aircraft(t, seed=0, delta_kind="sine", omega_kind="vertex")
    options = {"noise_rate": np.full(4, ac.DELTA_DOT_BAR), "output_accel": np.full(4, ac.OUTPUT_ACCEL)}
    estimate = observe(
        ac.aircraft_system(), ac.aircraft_bounds(), t, record.y, unknown_input=ac.D, options=options, budget=BUDGET
    )
    assert estimate.meta["estimator"] == "UnknownInputIntervalObserver"
    assert estimate.enclosure(record.x, transient=0.0).fraction == 1.0
    assert estimate.input_enclosure(record.xi, transient=0.0).fraction == 1.0
    with pytest.raises(ArgumentError, match="noise_rate"):
        observe(ac.aircraft_system(), ac.aircraft_bounds(), t[:50], record.y[:50], unknown_input=ac.D)


def test_lpv_model_picks_the_lpv_observer_and_is_sound() -> None:
    lpv = pytest.importorskip("test_lpv_design")
    t = np.arange(0.0, 2.0 + lpv.H / 2, lpv.H)
    x, theta, u = lpv.simulate(t, runs=2, seed=3)
    estimate = observe(
        lpv.make_system(),
        lpv.BOUNDS,
        t,
        x[..., :2],
        u,
        theta=theta,
        options={"theta_rate": lpv.RHO},
        budget=BUDGET,
    )
    assert estimate.meta["estimator"] == "LPVIntervalObserver" and estimate.meta["rows"] == "filtered"
    assert estimate.enclosure(x).fraction == 1.0


def test_nonlinear_model_picks_the_null_space_observer_and_is_sound() -> None:
    system, bounds = nonlinear_example.fullrank_system(), nonlinear_example.fullrank_bounds()
    sim = simulate_nonlinear(system, bounds, nonlinear_example.fullrank_input(60), seed=4)
    t = np.arange(sim.y.shape[-2], dtype=float)
    estimate = observe(system, bounds, t, sim.y, budget=BUDGET)
    assert estimate.meta["estimator"] == "NullSpaceGSISIO"
    assert estimate.enclosure(sim.x).fraction == 1.0
    direct = NullSpaceGSISIO.design(system, bounds).run(t, sim.y)
    assert _mean_width(estimate) <= 1.1 * _mean_width(direct)


def test_suggest_lists_what_fits_tightest_first() -> None:
    names = [row["estimator"] for row in suggest(_random_lti(0, uncertain=False), BOUNDS)]
    assert names == ["HullEstimator", "FiniteMemoryObserver", "IntervalObserver"]
    first = suggest(_random_lti(0, uncertain=True), BOUNDS)[0]
    assert first["estimator"] == "RobustHullEstimator"
    assert any(row.kind == "nonlinear-continuous" for row in ESTIMATORS)  # the plug-in place


@pytest.mark.slow
def test_a_tight_budget_falls_back_and_says_why() -> None:
    """Learns the bank on the way (30 s on a loaded machine)."""
    system = _random_lti(2, uncertain=False)
    t = np.arange(30.0)
    truth = simulate(system, BOUNDS, t, seed=2)
    estimate = observe(system, BOUNDS, t, truth.y, budget=1e-6)
    assert estimate.meta["estimator"] == "IntervalObserver" and "over the budget" in estimate.meta["why"]
    assert [c.split(":")[0] for c in estimate.meta["considered"]] == ["HullEstimator", "FiniteMemoryObserver"]
    assert estimate.meta["rows"] == "filtered" and estimate.enclosure(truth.x).fraction == 1.0
    forced = observe(system, BOUNDS, t, truth.y, estimator="IntervalObserver", filtered=False)
    assert forced.meta["rows"] == "predicted"
    assert np.all(forced.width() >= estimate.width() - 1e-12)  # the contraction only narrows
    with pytest.raises(ArgumentError, match="RobustHullEstimator"):
        observe(system, BOUNDS, t, truth.y, estimator="RobustHullEstimator")


def test_memory_horizon_follows_the_decay() -> None:
    slow = LTISystem([[0.9]], [[1.0]], dt=1.0)
    fast = LTISystem([[0.5]], [[1.0]], dt=1.0)
    still = LTISystem([[1.0]], [[1.0]], dt=1.0)
    assert memory_horizon(fast) == 10 and memory_horizon(still) == 60
    assert 0.9 ** memory_horizon(slow) <= 0.01 < 0.9 ** (memory_horizon(slow) - 1)


@pytest.mark.slow
def test_seed002_68_within_1_05_of_the_exact_hull_under_5_ms() -> None:
    model = numerical3.system("68")
    system = LTISystem(model.A, model.C, B=model.B, E=model.E, F=model.F, dt=model.dt)  # θ = 0: the hull is exact
    bounds, t = numerical3.bounds(), numerical3.time_grid()
    u = numerical3.input_signal(t)
    truth = simulate(system, bounds, t, u, seed=0)
    estimate = observe(system, bounds, t, truth.y, u, budget=5.0)
    assert estimate.enclosure(truth.x).fraction == 1.0
    exact = HullEstimator.design(system, bounds, horizon=None, filtered=True).run(t, truth.y, u)
    assert _mean_width(estimate, 20) <= 1.05 * _mean_width(exact, 20)


def test_the_readme_table_is_the_estimators_table() -> None:
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    for row in ESTIMATORS:
        assert f"| `{row.name}` | {row.width} | {row.cost} |" in readme, f"README: rewrite the row of {row.name}"


def _damped_pendulum_record(t: np.ndarray) -> np.ndarray:
    """The test's own RK4 (200 steps a sample) of θ'' = -sin θ - 0.5 θ', from θ = 0.4, θ' = -0.2."""
    x = np.array([0.4, -0.2])
    out = [x]
    step = (t[1] - t[0]) / 200
    field = lambda s: np.array([s[1], -np.sin(s[0]) - 0.5 * s[1]])  # noqa: E731
    for _ in t[1:]:
        for _ in range(200):
            k1 = field(x)
            k2 = field(x + step / 2 * k1)
            k3 = field(x + step / 2 * k2)
            k4 = field(x + step * k3)
            x = x + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x)
    return np.array(out)


def test_continuous_nonlinear_model_picks_the_validated_observer_and_is_sound() -> None:
    from intervalobs import ContinuousNonlinearSystem

    system = ContinuousNonlinearSystem(lambda x, u, p: (x[1], -np.sin(x[0]) - 0.5 * x[1]), lambda x, u: (x[0],), n=2)
    bounds = Bounds(x0=([0.3, -0.3], [0.5, -0.1]), v=(-0.01, 0.01))
    t = np.arange(0.0, 3.0 + 1e-9, 0.1)
    x = _damped_pendulum_record(t)
    y = x[:, :1] + 0.01 * np.where(np.arange(t.size) % 2 == 0, 1.0, -1.0)[:, None]
    estimate = observe(system, bounds, t, y, budget=1e4)
    assert estimate.meta["estimator"] == "ContinuousNonlinearObserver(refine=64)"  # the bundle first
    assert np.all((estimate.lower <= x) & (x <= estimate.upper))
    single = observe(system, bounds, t, y, estimator="ContinuousNonlinearObserver")
    assert np.all((single.lower <= x) & (x <= single.upper))
    assert np.mean(estimate.width()) <= np.mean(single.width()) * (1 + 1e-9)


def test_an_estimator_that_refuses_the_model_is_passed_over_with_its_reason() -> None:
    """A disconnected sensor: the learned bank's filter LP has no solution; the choice goes on, and sound."""
    system = LTISystem([[0.5, 0.1], [0.0, 0.5]], [[0.0, 0.0]], dt=1.0)
    bounds = Bounds(x0=([-1, -1], [1, 1]), w=(-0.01, 0.01), v=(-0.01, 0.01))
    t = np.arange(30.0)
    truth = simulate(system, bounds, t, noise="extreme", seed=0)
    estimate = observe(system, bounds, t, truth.y, budget=1e-9)  # every row over the budget: all are tried
    assert any("FiniteMemoryObserver: cannot be designed" in line for line in estimate.meta["considered"])
    assert estimate.enclosure(truth.x).max_violation == 0.0


def test_when_the_cheapest_estimator_refuses_the_model_the_last_one_designed_runs() -> None:
    """Not detectable (a state that is neither seen nor stable): no observer gain, but the hull bounds it."""
    system = LTISystem(np.eye(2), [[1.0, 0.0]], dt=1.0)
    bounds = Bounds(x0=([-1, -1], [1, 1]), w=(-0.01, 0.01), v=(-0.01, 0.01))
    t = np.arange(20.0)
    truth = simulate(system, bounds, t, noise="extreme", seed=0)
    estimate = observe(system, bounds, t, truth.y, budget=1e-9)
    assert estimate.meta["estimator"] != "IntervalObserver"
    assert any("IntervalObserver: cannot be designed" in line for line in estimate.meta["considered"])
    assert estimate.enclosure(truth.x).max_violation == 0.0


def test_a_labelled_record_is_read_by_the_model_names() -> None:
    """A pandas record with the states beside the outputs and inputs (what ``Simulation.to_pandas`` gives): the
    front door reads the channels by name, as every estimator does, and the result is that of the bare arrays."""
    pytest.importorskip("pandas")
    motor = LTISystem(
        [[0.0, 1.0], [0.0, -8.0]], C=[[1.0, 0.0]], B=[[0.0], [40.0]],
        state_names=["angle", "speed"], output_names=["encoder"], input_names=["voltage"],
    )  # fmt: skip
    bounds = Bounds(x0=([-0.1, -1.0], [0.1, 1.0]), w=([0.0, -0.5], [0.0, 0.5]), v=([-0.002], [0.002]))
    t = np.arange(0.0, 0.5, 0.01)
    voltage = np.where(np.sin(8 * np.pi * t) >= 0, 1.0, -1.0)[:, None]
    truth = simulate(motor, bounds, t, u=voltage, noise="extreme", seed=7)
    record = truth.to_pandas()
    assert record.shape[1] > 2  # states, outputs and inputs side by side
    labelled = observe(motor, bounds, record.index, record, record, estimator="IntervalObserver")
    bare = observe(motor, bounds, t, truth.y, voltage, estimator="IntervalObserver")
    np.testing.assert_array_equal(labelled.lower, bare.lower)
    assert labelled.enclosure(truth).max_violation == 0.0


def test_the_pilot_charges_computing_not_waiting() -> None:
    """The pilot's cost is CPU time: an estimator that waits (as on a loaded machine) is not charged for it."""
    from intervalobs.front_door import _cost_per_sample

    class Waiting:
        def run(self, t, y, u=None):
            time.sleep(0.002 * len(t))  # 2 ms of wall time a sample, no computing

    t = np.arange(30.0)
    cost = _cost_per_sample(Waiting(), t, np.zeros((30, 1)), None, {})  # type: ignore[arg-type]
    assert cost < 1.0  # wall time would say 2 ms a sample


def test_the_pilot_does_not_charge_other_threads() -> None:
    """A thread that spins beside the pilot (as BLAS workers do after a design) is not charged to the estimator."""
    import threading

    from intervalobs.front_door import _cost_per_sample

    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            pass

    class Waiting:
        def run(self, t, y, u=None):
            time.sleep(0.002 * len(t))

    spinner = threading.Thread(target=spin)
    spinner.start()
    try:
        cost = _cost_per_sample(Waiting(), np.arange(30.0), np.zeros((30, 1)), None, {})  # type: ignore[arg-type]
    finally:
        stop.set()
        spinner.join()
    assert cost < 1.0


def test_smoothed_rows_pick_the_set_inversion_smoother_and_are_sound() -> None:
    """``smoothed=True`` on a disturbance-free continuous-time model: the smoother, offline, enclosing the truth;
    with a disturbance it cannot be designed and the filter runs, with the reason."""
    from intervalobs import ContinuousNonlinearSystem

    system = ContinuousNonlinearSystem(
        lambda x, u, p: (x[1], -p[0] * np.sin(x[0]) - 0.5 * x[1]), lambda x, u: (x[0],), n=2, n_params=1
    )
    t = np.arange(0.0, 2.0 + 1e-9, 0.05)
    truth = _damped_pendulum_record(t)
    y = truth[:, :1] + 0.01 * np.where(np.arange(t.size) % 3 == 0, 1.0, -1.0)[:, None]
    bounds = Bounds(x0=([0.3, -0.3], [0.5, -0.1]), v=(-0.01, 0.01), p=(0.95, 1.05))
    estimate = observe(system, bounds, t, y, smoothed=True)
    assert estimate.meta["estimator"] == "SetInversionSmoother" and estimate.meta["rows"] == "smoothed"
    assert "offline" in estimate.meta["why"] and estimate.meta["ms_per_sample"] > 0
    assert estimate.enclosure(truth).fraction == 1.0
    assert "SetInversionSmoother" not in [row["estimator"] for row in suggest(system, bounds, h=0.05)]
    assert "SetInversionSmoother" in [row["estimator"] for row in suggest(system, bounds, h=0.05, smoothed=True)]
    noisy = ContinuousNonlinearSystem(
        lambda x, u, p: (x[1], -p[0] * np.sin(x[0]) - 0.5 * x[1]), lambda x, u: (x[0],), n=2, n_params=1, E=[[0], [1]]
    )
    filtered = observe(noisy, Bounds(x0=bounds.x0, v=bounds.v, p=bounds.p, w=(-0.01, 0.01)), t, y, smoothed=True)
    assert filtered.meta["estimator"].startswith("ContinuousNonlinearObserver")
    assert "disturbance" in filtered.meta["considered"][0]
