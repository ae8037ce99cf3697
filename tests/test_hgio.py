"""The sound continuous-discrete HGIO (seed 004, Theorems 4.2 and 4.5)."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import DesignError
from intervalobs.design.regions import place_in_disks
from intervalobs.errors import AssumptionError, DataError
from intervalobs.estimate import enclosure_report
from intervalobs.examples import hgio as example
from intervalobs.interval import matvec_bounds
from intervalobs.observers.hgio import HighGainIntervalObserver, _Split
from intervalobs.simulate import simulate_sampled

HORIZON = 1.0


@pytest.fixture(scope="module")
def gains() -> dict[str, np.ndarray]:
    placed = place_in_disks(example.A, example.C, example.DISKS)
    return {
        "constructive": placed.L,
        "center": place_in_disks(example.A, example.C, example.DISKS, objective="center").L,
        "theta1000": np.array([[1000.0], [0.0], [0.0]]),
    }


def _observer(gain: np.ndarray, output_gain: np.ndarray | None = None, refine: bool = True) -> HighGainIntervalObserver:
    return HighGainIntervalObserver(
        example.system(),
        example.bounds(),
        gain,
        example.STEP,
        output_gain=output_gain,
        input_rate=example.INPUT_RATE,
        refine=refine,
    )


@pytest.mark.parametrize("design", ["constructive", "center", "theta1000"])
@pytest.mark.parametrize("seed", [0, 1])
def test_encloses_truth_under_bang_bang_disturbances(gains: dict[str, np.ndarray], design: str, seed: int) -> None:
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, HORIZON + 1e-12, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, noise="extreme", seed=seed, runs=3, substeps=4)
    observer = _observer(gains[design], output_gain=gains["constructive"])
    est = observer.run(t, sim.y, sim.u)
    for lo, hi in ((est.lower, est.upper), (est.meta["theorem45_lower"], est.meta["theorem45_upper"])):
        report = enclosure_report(t, lo, sim.x, hi)
        assert report.max_violation == 0.0
    out = enclosure_report(t, est.meta["output_lower"], sim.x[..., :1], est.meta["output_upper"])
    assert out.max_violation == 0.0
    assert np.all(np.isfinite(est.upper))


def test_encloses_with_held_input_and_sine_noise(gains: dict[str, np.ndarray]) -> None:
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, HORIZON + 1e-12, example.STEP)
    u = example.input_signal(t)
    sim = simulate_sampled(system, bounds, t, u=u, noise="sine", seed=4, runs=2)
    observer = HighGainIntervalObserver(system, bounds, gains["constructive"], example.STEP)  # input_rate 0: ZOH
    est = observer.run(t, sim.y, sim.u)
    assert est.enclosure(sim.x).max_violation == 0.0


def test_run_equals_repeated_step(gains: dict[str, np.ndarray]) -> None:
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, 0.1 + 1e-12, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, seed=5)
    observer = _observer(gains["center"], output_gain=gains["constructive"])
    est = observer.run(t, sim.y, sim.u)
    state = observer.init()
    for k in range(t.size - 1):
        np.testing.assert_allclose(state.lower, est.lower[k], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(state.upper, est.upper[k], rtol=1e-12, atol=1e-12)
        state = observer.step(state, sim.y[k], sim.u[k])


def test_refinement_only_tightens(gains: dict[str, np.ndarray]) -> None:
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, 0.3 + 1e-12, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, seed=6)
    est = _observer(gains["constructive"]).run(t, sim.y, sim.u)
    assert np.all(est.lower >= est.meta["theorem45_lower"] - 1e-12)
    assert np.all(est.upper <= est.meta["theorem45_upper"] + 1e-12)
    # the measured output pins x1 to a few noise bounds, Theorem 4.5 alone (L1 = 0) does not
    assert np.mean(est.width()[-50:, 0]) < 0.5 * np.mean(
        (est.meta["theorem45_upper"] - est.meta["theorem45_lower"])[-50:, 0]
    )


def test_split_matrix_equals_matvec_bounds() -> None:
    rng = np.random.default_rng(0)
    a = rng.normal(size=(3, 4))
    lo = rng.normal(size=(5, 4))
    hi = lo + rng.uniform(size=(5, 4))
    for got, want in zip(_Split(a).bounds(lo, hi), matvec_bounds(a, lo, hi)):
        np.testing.assert_allclose(got, want, rtol=1e-15)


def test_bad_inputs_raise(gains: dict[str, np.ndarray]) -> None:
    observer = _observer(gains["constructive"])
    t = np.arange(0.0, 0.01 + 1e-12, example.STEP)
    y = np.full((t.size, 1), np.nan)
    with pytest.raises(DataError, match="t: expected uniform spacing"):
        observer.run(t * 2, y)
    with pytest.raises(DataError, match="inf"):
        observer.run(t, np.where(np.arange(t.size)[:, None] == 0, np.inf, y))
    y[0] = 100.0
    with pytest.raises(AssumptionError, match="inconsistent"):
        observer.run(t, y, example.input_signal(t))
    with pytest.raises(DesignError, match="not Hurwitz"):
        _observer(np.array([[1000.0], [0.0], [0.0]]))  # the output observer cannot take a high gain


def test_paper_euler_step_with_large_theta_is_unsound(gains: dict[str, np.ndarray]) -> None:
    """θ cancels in exact arithmetic, but in the paper's Euler scheme it damps the radius artificially."""
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, 0.5 + 1e-12, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, seed=7, runs=2)
    widths = {}
    for scheme, theta in (("exact", 0.0), ("paper-euler", 100.0)):
        observer = HighGainIntervalObserver(
            system, bounds, gains["constructive"], example.STEP, theta=theta, input_rate=9.0, scheme=scheme
        )
        est = observer.run(t, sim.y, sim.u)
        lo, hi = est.meta["theorem45_lower"], est.meta["theorem45_upper"]
        widths[scheme] = (hi - lo)[:, -1].mean()
        violation = enclosure_report(t, lo, sim.x, hi).max_violation
        assert (violation == 0.0) == (scheme == "exact")
    assert widths["paper-euler"] < 0.5 * widths["exact"]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [11, 12, 13])
def test_long_horizon_enclosure_and_bounded_widths(gains: dict[str, np.ndarray], seed: int) -> None:
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, 15.0 + 1e-12, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, noise="extreme", seed=seed, runs=4, substeps=8)
    est = _observer(gains["constructive"]).run(t, sim.y, sim.u)
    assert est.enclosure(sim.x).max_violation == 0.0
    lo, hi = est.meta["theorem45_lower"], est.meta["theorem45_upper"]
    assert enclosure_report(t, lo, sim.x, hi).max_violation == 0.0
    width = (hi - lo).mean(axis=0)
    early = width[(t >= 5) & (t < 10)].max(axis=0)
    late = width[t >= 10].max(axis=0)
    assert np.all(late <= 1.2 * early)  # settled, not growing


def test_batched_init_and_step_match_run(gains: dict[str, np.ndarray]) -> None:
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, 0.02 + 1e-12, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, seed=8, runs=2)
    observer = _observer(gains["constructive"])
    est = observer.run(t, sim.y, sim.u)
    lo, hi = bounds.x0
    state = observer.init(np.stack([lo, lo]), np.stack([hi, hi]))
    for k in range(t.size - 1):
        state = observer.step(state, sim.y[:, k], sim.u[k])
    np.testing.assert_allclose(state.lower, est.lower[:, -1], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(state.upper, est.upper[:, -1], rtol=1e-12, atol=1e-12)


def test_design_runs_algorithm_1_and_theorem_44() -> None:
    observer = HighGainIntervalObserver.design(
        example.system(),
        example.bounds(),
        disks=example.DISKS,
        h=example.STEP,
        alpha_d=0.08,
        alpha_n=0.03,
        input_rate=9.0,
    )
    assert observer.placement is not None and observer.theta_design is not None
    np.testing.assert_allclose(observer.L, 0.0, atol=1e-12)
    assert observer.theta == pytest.approx(np.log(1.6 / 0.08), abs=1e-3)  # sound reading, recorded only
    with pytest.raises(TypeError):
        HighGainIntervalObserver.design(
            example.system(), example.bounds(), disks=example.DISKS, h=example.STEP, gain=1.0
        )  # type: ignore[call-arg]


def test_modal_predictor_and_rewrap_only_tighten(gains: dict[str, np.ndarray]) -> None:
    """Both only intersect sound enclosures, and every later map is inclusion-monotone."""
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, HORIZON + 1e-12, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, noise="extreme", seed=7, runs=2, substeps=4)
    widths = {}
    for options in ({"predictor": "box", "rewrap": False}, {"predictor": "modal", "rewrap": True}):
        observer = HighGainIntervalObserver(
            system,
            bounds,
            gains["center"],
            example.STEP,
            output_gain=gains["constructive"],  # the output-bound observer needs a gain whose radius system is Hurwitz
            input_rate=example.INPUT_RATE,
            **options,
        )
        est = observer.run(t, sim.y, sim.u)
        assert est.enclosure(sim.x).max_violation == 0.0
        widths[options["predictor"]] = est.upper - est.lower
    # rounding pads differ between the two paths: 1e-9 relative is far above them and far below any gain
    assert np.all(widths["modal"] <= widths["box"] * (1 + 1e-9) + 1e-12)
    # the modal predictor bounds Cẋ between samples: the measured state x₁ gains most
    assert widths["modal"][:, t >= 0.5, 0].mean() < 0.8 * widths["box"][:, t >= 0.5, 0].mean()


def test_the_reproduction_reports_general_estimators_next_to_the_hgio(monkeypatch: pytest.MonkeyPatch) -> None:
    """The hook of hgio-sampled's summary: an estimator registered in GENERAL_ESTIMATORS is run on the record."""
    from types import SimpleNamespace

    from intervalobs.estimate import Estimate
    from intervalobs.reproduce import hgio_sampled

    t = np.arange(0.0, 10.0, 1.0)
    x = np.zeros((2, t.size, 3))
    sim = SimpleNamespace(x=x, y=np.zeros((2, t.size, 1)), u=np.zeros((t.size, 1)))
    hgio_half = np.broadcast_to([0.25, 1.0, 2.0], x.shape)
    hgio = Estimate(t, -hgio_half, hgio_half)
    monkeypatch.setattr(hgio_sampled, "GENERAL_ESTIMATORS", {})
    empty = hgio_sampled.general_path(t, sim, hgio, 1.0)
    assert empty["estimators"] == {} and "no general estimator" in empty["status"]

    def fixed_width(t: np.ndarray, y: np.ndarray, u: np.ndarray) -> Estimate:
        half = np.broadcast_to([0.25, 0.5, 1.0], (y.shape[0], t.size, 3))
        return Estimate(t, -half, half)

    monkeypatch.setitem(hgio_sampled.GENERAL_ESTIMATORS, "fixed", fixed_width)
    report = hgio_sampled.general_path(t, sim, hgio, 1.0)["estimators"]["fixed"]
    np.testing.assert_allclose(report["width_over_hgio"], [1.0, 0.5, 0.5])
    assert report["enclosure"]["fraction"] == 1.0 and not report["diverging"]
    np.testing.assert_allclose(report["intersected_over_hgio"], [1.0, 0.5, 0.5])

    def shifted_and_wide(t: np.ndarray, y: np.ndarray, u: np.ndarray) -> Estimate:
        centre = np.broadcast_to([0.1, 0.0, 0.0], (y.shape[0], t.size, 3))
        half = np.broadcast_to([0.25, 4.0, 8.0], centre.shape)
        return Estimate(t, centre - half, centre + half)

    monkeypatch.setitem(hgio_sampled.GENERAL_ESTIMATORS, "wide", shifted_and_wide)
    wide = hgio_sampled.general_path(t, sim, hgio, 1.0)["estimators"]["wide"]
    np.testing.assert_allclose(wide["width_over_hgio"], [1.0, 4.0, 4.0])
    # the intersection with the HGIO's boxes: never wider than them, narrower where the other estimator cuts
    np.testing.assert_allclose(wide["intersected_over_hgio"], [0.8, 1.0, 1.0])
    assert wide["intersected_enclosure"]["fraction"] == 1.0


@pytest.mark.parametrize(
    "name",
    ["continuous_nonlinear_observer", "continuous_nonlinear_observer_phi_as_disturbance", "continuous_window_observer"],
)
def test_general_estimators_enclose_the_example_under_bang_bang_disturbances(name: str) -> None:
    """Seed 004's example through the general path: sound at every sample against a truth integrated 4x finer.

    The truth's disturbance switches between the ends of its box inside the observer's sampling intervals,
    the noise sits at its ends, three runs; the estimator sees only the samples (NaN rows in between).
    """
    from intervalobs.reproduce import hgio_sampled

    system, bounds = example.system(), example.bounds().resolve(example.system())
    t = np.arange(0.0, 0.5 + example.STEP / 2, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, noise="extreme", seed=3, runs=3, substeps=4)
    est = hgio_sampled.GENERAL_ESTIMATORS[name](t, sim.y, sim.u)
    rows = np.searchsorted(t, est.t - 1e-9)
    assert est.t.size == 101 and np.allclose(t[rows], est.t)
    assert est.enclosure(sim.x[..., rows, :]).fraction == 1.0
    assert np.all(np.isfinite(est.upper))
