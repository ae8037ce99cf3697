"""The HGIO on a chemostat: the state domain (no clipping in phi), divergence reported, unstable designs refused."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from intervalobs import DesignError, DivergenceWarning, Estimate
from intervalobs.errors import AssumptionError, BoundsError
from intervalobs.observers.base import GROWTH_LIMIT, check_growth
from intervalobs.observers.hgio import HighGainIntervalObserver
from intervalobs.simulate import simulate_sampled
from intervalobs.systems import Bounds
from intervalobs.systems.sampled import SampledSystem

MU_MAX, KS, DILUTION, S_IN, YIELD = 0.5, 0.3, 0.2, 2.0, 0.5
A = np.array([[-DILUTION, 0.0], [-1.0, -2 * DILUTION]])
"""Linear part of the chemostat (X, S); the rest of the Monod model is phi. The -1 makes (A, C) observable."""
STEP, SAMPLE = 0.05, 0.1
DISKS = ((-0.3, 0.05), (-0.6, 0.05))


def _phi(t: float, u: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Monod uptake; refuses a negative substrate instead of clipping it (it has no meaning there)."""
    if np.any(x[..., 1] < 0):
        raise ValueError("phi: negative substrate")
    rate = MU_MAX * x[..., 1] / (KS + x[..., 1]) * x[..., 0]
    return np.stack([rate, DILUTION * S_IN - rate / YIELD + x[..., 0] + DILUTION * x[..., 1]], axis=-1)


def _phi_bounds(t0: float, t1: float, ul: np.ndarray, uh: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple:
    """The range over a box of nonnegative states (the Monod factor is increasing, X >= 0)."""
    if np.any(lo < 0):
        raise ValueError("phi_bounds: a box outside the domain")
    rate_lo = MU_MAX * lo[..., 1] / (KS + lo[..., 1]) * lo[..., 0]
    rate_hi = MU_MAX * hi[..., 1] / (KS + hi[..., 1]) * hi[..., 0]
    rest_lo = DILUTION * S_IN + lo[..., 0] + DILUTION * lo[..., 1]
    rest_hi = DILUTION * S_IN + hi[..., 0] + DILUTION * hi[..., 1]
    return np.stack([rate_lo, rest_lo - rate_hi / YIELD], -1), np.stack([rate_hi, rest_hi - rate_lo / YIELD], -1)


def _chemostat() -> SampledSystem:
    return SampledSystem(A, [[0.0, 1.0]], _phi, _phi_bounds, sample_period=SAMPLE, domain=(0.0, np.inf))


BOUNDS = Bounds(x0=([1.0, 0.3], [3.0, 0.8]), w=([0.0, 0.0], [0.0, 0.0]), v=(-0.02, 0.02))


def _record(hours: float, seed: int, runs: int = 2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Truth by RK4 on a 4x finer grid, noise at the box vertices, S sampled every 0.1 h (NaN in between)."""
    t = np.arange(0.0, hours + 1e-9, STEP)
    sim = simulate_sampled(_chemostat(), BOUNDS, t, noise="extreme", seed=seed, runs=runs, substeps=4)
    y = sim.y.copy()
    y[:, np.round(t / STEP) % round(SAMPLE / STEP) != 0] = np.nan
    return t, y, sim.x


def test_the_spot_check_draws_inside_the_domain() -> None:
    with pytest.raises(ValueError, match="outside the domain"):
        SampledSystem(A, [[0.0, 1.0]], _phi, _phi_bounds, sample_period=SAMPLE)  # no domain: called at S < 0
    system = _chemostat()
    np.testing.assert_array_equal(system.domain[0], [0.0, 0.0])
    assert np.all(np.isinf(system.domain[1]))


@pytest.mark.parametrize(
    "domain, error",
    [((1.0, 0.0), BoundsError), ((np.nan, 1.0), BoundsError), (([0, 0, 0], 1.0), Exception), ((0.0,), BoundsError)],
    ids=["empty", "nan", "size", "not-a-pair"],
)
def test_bad_domains_raise(domain: tuple, error: type[Exception]) -> None:
    with pytest.raises(error, match="domain"):
        SampledSystem(A, [[0.0, 1.0]], domain=domain)


def test_a_box_outside_the_domain_is_reported_as_contradicting_data() -> None:
    with pytest.raises(AssumptionError, match="contradict"):
        _chemostat().in_domain(np.array([-2.0, 0.0]), np.array([-1.0, 1.0]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bounds_inside_the_domain_enclose_the_truth(seed: int) -> None:
    t, y, x = _record(6.0, seed)
    observer = HighGainIntervalObserver.design(_chemostat(), BOUNDS, disks=DISKS, h=STEP, output_gain=np.zeros((2, 1)))
    est = observer.run(t, y)
    assert est.enclosure(x).max_violation == 0.0
    assert np.all(est.lower >= 0.0)  # intersected with the domain: no negative concentration
    assert not est.meta["diverging"]


def test_a_diverging_run_warns_and_says_so_in_meta() -> None:
    """The issue's case: output gain zero, 60 h; the widths of X grow ~10^6 times, enclosure still 1.0."""
    t, y, x = _record(60.0, 3, runs=1)
    observer = HighGainIntervalObserver.design(_chemostat(), BOUNDS, disks=DISKS, h=STEP, output_gain=np.zeros((2, 1)))
    with pytest.warns(DivergenceWarning, match="grow without bound"):
        est = observer.run(t, y)
    assert est.enclosure(x).max_violation == 0.0
    assert est.meta["diverging"] and est.meta["width_growth"] > 1e4


def test_a_placed_gain_that_makes_the_output_observer_diverge_is_refused() -> None:
    with pytest.raises(DesignError, match="grow without bound on this system"):
        HighGainIntervalObserver.design(_chemostat(), BOUNDS, disks=DISKS, h=STEP)


def _estimate(width: np.ndarray) -> Estimate:
    """An estimate of these widths; NaN rows (no bound, as after data that contradict the model) set afterwards."""
    t = np.arange(width.shape[0], dtype=float)
    finite = np.where(np.isnan(width), 1.0, width)
    est = Estimate(t, -0.5 * finite, 0.5 * finite, meta={"method": "x"})
    est.lower[np.isnan(width)], est.upper[np.isnan(width)] = np.nan, np.nan
    return est


@pytest.mark.parametrize(
    "width, diverging",
    [
        (np.exp(0.1 * np.arange(100.0))[:, None], True),  # geometric growth
        (np.where(np.arange(100.0) < 10, 1e-3, np.arange(100.0))[:, None], True),  # linear, from a tight prior
        ((1.0 - np.exp(-0.2 * np.arange(100.0)))[:, None], False),  # from an exact x0 to a steady width
        (np.r_[np.ones(50), np.full(50, np.inf)][:, None], True),  # finite, then infinite
        (np.full((100, 2), np.inf), False),  # never bounded (no claim to lose)
        (np.r_[np.ones(50), np.full(50, np.nan)][:, None], False),  # no bound after a sample that contradicts
        (np.array([[1.0], [1e9], [1e9], [1e9], [1e9]]), False),  # too short to judge
        (np.r_[np.full(4, 1e-11), np.full(16, 0.2), np.full(16, 0.05), np.full(4, 0.2)][:, None], False),  # steady
    ],
    ids=["geometric", "linear", "settling", "lost", "unbounded", "ended", "short", "fluctuating"],
)
def test_growth_check(width: np.ndarray, diverging: bool) -> None:
    est = _estimate(width)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_growth(est)
    assert any(issubclass(w.category, DivergenceWarning) for w in caught) == diverging
    assert est.meta.get("diverging", False) == diverging
    if diverging and np.all(np.isfinite(width)):
        assert est.meta["width_growth"] > GROWTH_LIMIT


def test_growth_check_stops_where_the_data_contradict_the_model() -> None:
    """Rows without bound after an inconsistent sample (inf or NaN, as estimators write them) are no divergence."""
    est = _estimate(np.r_[np.ones(50), np.full(50, np.inf)][:, None])
    est.meta["inconsistent_from"] = 50.0
    with warnings.catch_warnings():
        warnings.simplefilter("error", DivergenceWarning)
        check_growth(est)
    assert not est.meta["diverging"]
