"""UnknownInputIntervalObserver with known inputs (held and interval-known) and complex closed-loop poles.

The truth is integrated independently by fine RK4 (8 sub-steps per sample; the true input switches
between the vertices of its box at every sub-step, i.e. inside sampling steps).
"""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.errors import DataError
from intervalobs.observers.unknown_input import UnknownInputIntervalObserver
from intervalobs.simulate import runge_kutta_step
from intervalobs.systems import Bounds, LTISystem

A = np.array([[-1.0, 2.0, 0.0], [-2.0, -1.0, 1.0], [0.0, 0.5, -2.0]])
B = np.array([[0.5, 0.0], [1.0, 0.3], [0.0, 1.0]])
C = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
D = np.array([[1.0], [0.0], [0.0]])
H = 1e-3
SUB = 4
U_RADIUS = 0.05
L_BOUND = 40.0
POLES = [-1.0, -2 + 0.5j, -2 - 0.5j]


def _command(t: np.ndarray) -> np.ndarray:
    return np.stack([0.5 * (t >= 1.0), 0.3 * np.sin(3 * t)], axis=-1)


def _simulate(seed: int, steps: int, interval: bool) -> dict[str, np.ndarray]:
    """Fine RK4 of ẋ = Ax + Bu + Dξ + ω with ξ = sin 2t, ω a vertex, δ = 0.01 sin(t + φ)."""
    rng = np.random.default_rng(seed)
    omega = 0.01 * rng.choice([-1.0, 1.0], 3)
    phase = rng.uniform(0, 2 * np.pi, 2)
    t = np.arange(steps) * H
    cmd = _command(t)
    x = rng.uniform(-1, 1, 3)
    xs, gdot = np.empty((steps, 3)), np.zeros(2)
    dt = H / SUB
    for k in range(steps):
        xs[k] = x
        for j in range(SUB):
            u = cmd[k] + (U_RADIUS * rng.choice([-1.0, 1.0], 2) if interval else 0.0)
            s = t[k] + j * dt

            def f(tau: float, z: np.ndarray, u: np.ndarray = u) -> np.ndarray:
                return A @ z + B @ u + D[:, 0] * np.sin(2 * tau) + omega

            # g = C(Ax + Dξ + ω): ġ = C(A ẋ + D 2cos 2t)
            gdot = np.maximum(gdot, np.abs(C @ (A @ f(s, x) + D[:, 0] * 2 * np.cos(2 * s))))
            x = runge_kutta_step(f, s, x, dt)
    y = xs @ C.T + 0.01 * np.sin(t[:, None] + phase)
    return {"t": t, "x": xs, "y": y, "xi": np.sin(2 * t)[:, None], "cmd": cmd, "gdot": gdot}


def _observer(known: bool = True) -> UnknownInputIntervalObserver:
    system = LTISystem(A, C, B=B if known else None)
    bounds = Bounds(
        x0=(-np.ones(3), np.ones(3)),
        w=(-0.01 * np.ones(3), 0.01 * np.ones(3)),
        v=(-0.01 * np.ones(2), 0.01 * np.ones(2)),
    )
    return UnknownInputIntervalObserver.design(
        system, bounds, D=D, h=H, noise_rate=np.full(2, 0.01), output_accel=np.full(2, L_BOUND), poles=POLES
    )


@pytest.fixture(scope="module")
def observer() -> UnknownInputIntervalObserver:
    return _observer()


def test_complex_poles_give_a_cyclic_metzler_block(observer) -> None:
    co = observer.coords
    np.testing.assert_allclose(np.sort_complex(co.poles), np.sort_complex(np.array(POLES)), atol=1e-8)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(co.N)), np.sort_complex(np.array(POLES)), atol=1e-8)
    off = co.M[~np.eye(3, dtype=bool)]
    assert off.min() >= 0 and np.count_nonzero(off > 0.1) >= 3  # a genuine cycle, not a diagonal
    assert co.form_residual < 1e-12 and co.metzler_check > -1e-12
    assert np.abs(observer.decoupling.P @ B).max() > 0.1  # the known input enters the w-dynamics


@pytest.mark.parametrize("interval", [False, True], ids=["held", "interval"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_encloses_with_known_inputs(observer, seed, interval) -> None:
    rec = _simulate(seed, 2001, interval)
    assert np.all(rec["gdot"] <= L_BOUND)  # the assumption behind the bounds holds on this truth
    u = (rec["cmd"] - U_RADIUS, rec["cmd"] + U_RADIUS) if interval else rec["cmd"]
    est = observer.run(rec["t"], rec["y"], u, x0_lower=-np.ones(3), x0_upper=np.ones(3))
    assert est.enclosure(rec["x"], transient=0.0).max_violation == 0.0
    assert est.input_enclosure(rec["xi"], transient=0.0).max_violation == 0.0
    assert est.meta["known_input"] == ("interval" if interval else "held point")


def test_held_input_widths_equal_the_no_input_widths(observer) -> None:
    rec = _simulate(3, 2001, False)
    est = observer.run(rec["t"], rec["y"], rec["cmd"])
    free = _observer(known=False).run(rec["t"], rec["y"] - 0.0)
    # the held input's response is known exactly: only rounding pads (relative 1e-9) differ
    np.testing.assert_allclose(est.width()[-1], free.width()[-1], rtol=1e-6)
    wide = observer.run(rec["t"], rec["y"], (rec["cmd"] - U_RADIUS, rec["cmd"] + U_RADIUS))
    assert np.all(wide.width()[-1] > est.width()[-1])


def test_run_equals_repeated_step_with_interval_input(observer) -> None:
    rec = _simulate(4, 300, True)
    box = (rec["cmd"] - U_RADIUS, rec["cmd"] + U_RADIUS)
    est = observer.run(rec["t"], rec["y"], box)
    state = observer.init()
    for k in range(rec["t"].size):
        state = observer.step(state, rec["y"][k], (box[0][k], box[1][k]))
        np.testing.assert_allclose(state.lower, est.lower[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.upper, est.upper[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.input_lower, est.input_lower[k], rtol=0, atol=1e-12)


def test_missing_or_bad_known_input_is_rejected(observer) -> None:
    rec = _simulate(5, 50, False)
    with pytest.raises(DataError, match="u: expected the known input"):
        observer.run(rec["t"], rec["y"])
    with pytest.raises(DataError, match="lower <= upper"):
        observer.run(rec["t"], rec["y"], (rec["cmd"] + 1, rec["cmd"]))
    with pytest.raises(DataError, match="u"):
        observer.run(rec["t"], rec["y"], rec["cmd"][:, :1])
