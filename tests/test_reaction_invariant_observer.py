"""ReactionInvariantObserver and ReactionSystem: bounds that hold for kinetics the observer never sees.

The truth is simulated here by classical RK4 (40 steps per sample) with Monod and Haldane kinetics,
a dilution rate that switches between samples (the held input) or stays constant, the inlet at a
vertex of its box, the initial state at the vertices of its box and bang-bang measurement noise.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from intervalobs import Bounds, ReactionInvariantObserver, ReactionSystem
from intervalobs.errors import AssumptionError, DataError, DimensionError

H, STEPS = 0.1, 300
CHEMOSTAT_YIELDS = [[1.0], [-2.0]]  # X, S: Y = 0.5
PRODUCT_YIELDS = [[1.0, 0.0], [-2.0, -1.0], [0.3, 0.5]]  # X, S, P: growth and maintenance
Kinetics = Callable[[np.ndarray], np.ndarray]


def monod(x: np.ndarray) -> np.ndarray:
    return (0.5 * x[..., 1] / (0.3 + x[..., 1]) * x[..., 0])[..., None]


def haldane(x: np.ndarray) -> np.ndarray:
    s = np.maximum(x[..., 1], 0.0)
    return (0.6 * s / (0.2 + s + s**2 / 2.0) * x[..., 0])[..., None]


def growth_and_maintenance(x: np.ndarray) -> np.ndarray:
    s = np.maximum(x[..., 1], 0.0)
    return np.stack([0.5 * s / (0.3 + s) * x[..., 0], 0.05 * s / (1.0 + s) * x[..., 0]], -1)


def simulate(yields, kinetics: Kinetics, x0: np.ndarray, inlet: np.ndarray, dilution: np.ndarray) -> np.ndarray:
    """RK4 of dx/dt = K r(x) + D_k (x_in - x), D_k held on [t_k, t_{k+1}); returns (runs, STEPS, n)."""
    k = np.asarray(yields, dtype=float)
    x, out, dt = x0.copy(), [x0.copy()], H / 40

    def rates(state: np.ndarray, rate: np.ndarray) -> np.ndarray:
        return kinetics(state) @ k.T + rate[:, None] * (inlet - state)

    for step in range(STEPS - 1):
        rate = dilution[:, step]
        for _ in range(40):
            k1 = rates(x, rate)
            k2 = rates(x + 0.5 * dt * k1, rate)
            k3 = rates(x + 0.5 * dt * k2, rate)
            k4 = rates(x + dt * k3, rate)
            x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x.copy())
    return np.stack(out, 1)


def vertices(lower: list[float], upper: list[float]) -> np.ndarray:
    grid = np.stack(np.meshgrid(*zip(lower, upper), indexing="ij"), -1)
    return grid.reshape(-1, len(lower))


CASES = {
    "monod-constant-D": (CHEMOSTAT_YIELDS, monod, False),
    "haldane-switching-D": (CHEMOSTAT_YIELDS, haldane, True),
    "two-reactions-switching-D": (PRODUCT_YIELDS, growth_and_maintenance, True),
}


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("case", list(CASES), ids=list(CASES))
def test_encloses_unknown_kinetics(case: str, seed: int) -> None:
    yields, kinetics, switching = CASES[case]
    rng = np.random.default_rng(seed)
    n = len(yields)
    measured = [1] if n == 2 else [1, 2]
    x0_box = ([1.0, 0.3], [3.0, 0.8]) if n == 2 else ([1.0, 0.3, 0.0], [3.0, 0.8, 0.2])
    inlet_box = ([0.0, 4.9] + [0.0] * (n - 2), [0.0, 5.1] + [0.05] * (n - 2))
    x0 = vertices(*x0_box)
    runs = x0.shape[0]
    inlet = np.array(inlet_box[rng.integers(2)])  # one vertex of the inlet box for every run
    dilution = rng.choice([0.1, 0.35], size=(runs, STEPS)) if switching else np.full((runs, STEPS), 0.2)
    truth = simulate(yields, kinetics, x0, inlet, dilution)
    noise = 0.02 * rng.choice([-1.0, 1.0], size=(runs, STEPS, len(measured)))
    y = truth[..., measured] + noise
    system = ReactionSystem(yields, measured, (inlet_box[0], inlet_box[1]), None if switching else 0.2)
    observer = ReactionInvariantObserver(system, Bounds(x0=x0_box, v=(-0.02, 0.02)), H)
    t = H * np.arange(STEPS)
    estimate = observer.run(t, y, dilution[..., None] if switching else None)
    assert np.all((estimate.lower <= truth) & (truth <= estimate.upper))
    assert estimate.meta["consistent"] == [True] * runs
    unmeasured = next(i for i in range(n) if i not in measured)
    assert np.all(estimate.width()[:, -1, unmeasured] < 0.5)  # the prior (width 2) forgotten


def test_step_agrees_with_run() -> None:
    system = ReactionSystem(CHEMOSTAT_YIELDS, [1], [0.0, 5.0], dilution=None)
    observer = ReactionInvariantObserver(system, Bounds(x0=([1.0, 0.3], [3.0, 0.8]), v=(-0.02, 0.02)), H)
    t, y, u = H * np.arange(20), np.full((20, 1), 0.4), np.linspace(0.1, 0.3, 20)[:, None]
    estimate = observer.run(t, y, u)
    state = observer.init()
    for k in range(20):
        state = observer.step(state, y[k], u[k])
        np.testing.assert_allclose(state.lower, estimate.lower[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.upper, estimate.upper[k], rtol=0, atol=1e-12)


def test_contradicting_record_is_flagged() -> None:
    system = ReactionSystem(CHEMOSTAT_YIELDS, [1], [0.0, 5.0], dilution=0.2)
    observer = ReactionInvariantObserver(system, Bounds(x0=([1.0, 0.3], [3.0, 0.8]), v=(-0.02, 0.02)), H)
    y = np.full((30, 1), 0.4)
    y[10:] = 20.0  # more substrate than the invariant Z = X/Y + S allows
    with pytest.warns(RuntimeWarning, match="contradicts the model from t = 1"):
        estimate = observer.run(H * np.arange(30), y)
    assert estimate.meta["consistent"] is False and estimate.meta["inconsistent_from"] == pytest.approx(1.0)
    assert np.all(np.isfinite(estimate.upper[:10])) and np.all(np.isinf(estimate.upper[10:]))


def test_invariant_gain_is_exact() -> None:
    system = ReactionSystem(PRODUCT_YIELDS, [1, 2], [0.0, 5.0, 0.0], dilution=0.2)
    gain = system.invariant_gain
    exact = -np.array([[1.0, 0.0]]) @ np.linalg.inv(np.array(PRODUCT_YIELDS)[[1, 2]])
    assert np.all((gain.lower <= exact + 1e-15) & (exact - 1e-15 <= gain.upper))
    assert np.all(gain.upper - gain.lower <= 2 * np.spacing(np.abs(exact)))


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"yields": [[1.0], [-2.0]], "measured": [0, 1]}, AssumptionError, "as many measured components"),
        ({"yields": [[1.0, 2.0], [2.0, 4.0], [1.0, 0.0]], "measured": [0, 1]}, AssumptionError, "linearly dependent"),
        ({"yields": [[1.0], [-2.0]], "measured": [2]}, DimensionError, "distinct indices"),
        ({"yields": [1.0, -2.0], "measured": [1]}, DimensionError, "yields"),
    ],
    ids=["count", "singular", "index", "shape"],
)
def test_refuses_models_without_invariants(kwargs, error, match) -> None:
    n = np.shape(kwargs["yields"])[0]
    with pytest.raises(error, match=match):
        ReactionSystem(inlet=[0.0] * n, dilution=0.2, **kwargs)


def test_refuses_negative_dilution() -> None:
    system = ReactionSystem(CHEMOSTAT_YIELDS, [1], [0.0, 5.0])
    observer = ReactionInvariantObserver(system, Bounds(x0=([1.0, 0.3], [3.0, 0.8]), v=(-0.02, 0.02)), H)
    with pytest.raises(DataError, match="nonnegative dilution"):
        observer.run(H * np.arange(3), np.full((3, 1), 0.4), np.array([[0.2], [-0.1], [0.2]]))
