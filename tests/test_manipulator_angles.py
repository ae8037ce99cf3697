"""The manipulator with only the joint angles measured (n_y = 2): velocity bounds and isolation (AnglesOnlyObserver)."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds
from intervalobs.errors import ArgumentError, BoundsError, DataError
from intervalobs.examples.manipulator import (
    FAULT_BOUND,
    X0,
    ManipulatorModel,
    controller,
    rk4_step,
)
from intervalobs.observers import AnglesOnlyObserver

H = 1e-3
SUBSTEPS = 8
VELOCITY_BOX = (np.array([-0.1, -0.1]), np.array([0.1, 0.1]))
BOTH = (-FAULT_BOUND * np.ones(2), FAULT_BOUND * np.ones(2))
FAULT_1_ABSENT = (np.array([0.0, -FAULT_BOUND]), np.array([0.0, FAULT_BOUND]))
FAULT_2_ABSENT = (np.array([-FAULT_BOUND, 0.0]), np.array([FAULT_BOUND, 0.0]))


@pytest.fixture(scope="module")
def model() -> ManipulatorModel:
    return ManipulatorModel(cells=32, splits=4, pieces=4)


def _truth(params: np.ndarray, t: np.ndarray, fault, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Fine RK4 (``SUBSTEPS`` per sample), torque held per sample, initial velocities at the prior box's
    vertices, and a fault ``fault(rng, t_sub, runs)`` re-drawn at every substep (switching inside steps)."""
    rng = np.random.default_rng(seed)
    runs = params.shape[0]
    x = np.tile(np.asarray(X0), (runs, 1))
    x[:, 2:] = np.where(rng.random((runs, 2)) < 0.5, VELOCITY_BOX[0], VELOCITY_BOX[1])
    xs, us = np.empty((runs, t.size, 4)), np.empty((runs, t.size, 2))
    for k in range(t.size):
        xs[:, k] = x
        us[:, k] = controller(x, float(t[k]))
        for i in range(SUBSTEPS):
            x = rk4_step(x, us[:, k] + fault(rng, t[k] + i * H / SUBSTEPS, runs), params, H / SUBSTEPS)
    return xs, us


def _bang_bang(rng: np.random.Generator, _: float, runs: int) -> np.ndarray:
    return FAULT_BOUND * np.where(rng.random((runs, 2)) < 0.5, -1.0, 1.0)


def test_velocity_bounds_enclose_a_fine_truth_at_parameter_vertices(model):
    """Every vertex of the parameter box, bang-bang faults of ±5 N·m switching inside the steps, initial
    velocities at the prior box's vertices: violation exactly 0, consistency signals never negative,
    velocity widths bounded (a few hundredths of rad/s after the first steps)."""
    t = np.arange(0, 1.5 + H / 2, H)
    params = model.bounds.vertices
    x, u = _truth(params, t, _bang_bang, seed=1)
    res, signal_lower, signal_upper = AnglesOnlyObserver(model, H, VELOCITY_BOX, BOTH).run_with_signals(
        t, x[..., :2], u
    )
    assert np.all(res.lower <= x) and np.all(x <= res.upper)
    np.testing.assert_array_equal(res.lower[..., :2], x[..., :2])
    assert signal_lower[:, 1:].min() >= 0.0 and signal_upper[:, 1:].min() >= 0.0
    width = (res.upper - res.lower)[:, t >= 0.1, 2:]
    assert np.all(np.isfinite(width)) and width.max() < 0.1


def test_hypothesis_bank_isolates_a_fault_switching_on_inside_a_step(model):
    """Fault 1 (+5 N·m) from inside the step after 0.5 s: the hypothesis 'fault 1 absent' becomes
    inconsistent right after the onset; 'fault 2 absent' (true) never does, nor does either one without a
    fault."""
    t = np.arange(0, 0.8 + H / 2, H)
    params = model.bounds.vertices[[0, 5]]
    onset = 0.5 + 0.4 * H

    def fault_1(_: np.random.Generator, ts: float, runs: int) -> np.ndarray:
        return np.tile([FAULT_BOUND if ts >= onset else 0.0, 0.0], (runs, 1))

    x, u = _truth(params, t, fault_1, seed=2)
    x0, u0 = _truth(params, t, lambda *_: 0.0, seed=2)
    q = np.concatenate([x[..., :2], x[..., :2], x0[..., :2], x0[..., :2]])
    boxes = [FAULT_1_ABSENT, FAULT_2_ABSENT, FAULT_1_ABSENT, FAULT_2_ABSENT]
    lo = np.repeat([b[0] for b in boxes], 2, axis=0)
    hi = np.repeat([b[1] for b in boxes], 2, axis=0)
    bank = AnglesOnlyObserver(model, H, VELOCITY_BOX, (lo, hi))
    res, signal_lower, signal_upper = bank.run_with_signals(t, q, np.concatenate([u, u, u0, u0]))
    signal = np.minimum(signal_lower, signal_upper).min(axis=-1)
    first = np.array([t[np.argmax(s < 0)] if np.any(s < 0) else np.inf for s in signal])
    assert np.all((first[:2] > onset) & (first[:2] <= onset + 0.01))
    assert np.all(np.isinf(first[2:]))
    assert np.all(np.isfinite(res.lower)) and np.all(np.isfinite(res.upper))  # refuted runs restart from C_k
    # a true hypothesis keeps its box sound
    for run, truth in ((2, x[0]), (3, x[1]), (4, x0[0]), (5, x0[1]), (6, x0[0]), (7, x0[1])):
        assert np.all(res.lower[run] <= truth) and np.all(truth <= res.upper[run])


def test_run_equals_init_and_steps_and_batched_steps_equal_each_run(model):
    """The run loop, the online step and a batch of runs give the same boxes and signals (to 1e-12)."""
    t = np.arange(0, 0.05 + H / 2, H)
    x, u = _truth(model.bounds.vertices[[1, 6]], t, _bang_bang, seed=3)
    observer = AnglesOnlyObserver.design(
        model,
        Bounds(x0=(np.r_[-1.0, -1.0, VELOCITY_BOX[0]], np.r_[1.0, 1.0, VELOCITY_BOX[1]])),
        h=H,
        unknown_input=BOTH,
    )
    batch, sig_lo, sig_hi = observer.run_with_signals(t, x[..., :2], u)
    assert batch.meta["rows"] == "filtered" and batch.meta["method"] == "angles-only"
    for run in range(2):
        state = observer.init()
        for k in range(t.size):
            state = observer.step(state, x[run, k, :2], u[run, k])
            np.testing.assert_allclose(state.lower, batch.lower[run, k], rtol=1e-12, atol=0)
            np.testing.assert_allclose(state.upper, batch.upper[run, k], rtol=1e-12, atol=0)
            np.testing.assert_allclose(state.internal["signal_lower"], sig_lo[run, k], rtol=1e-12, atol=0)
            np.testing.assert_allclose(state.internal["signal_upper"], sig_hi[run, k], rtol=1e-12, atol=0)
        single = observer.run(t, x[run, :, :2], u[run])
        np.testing.assert_allclose(single.lower, batch.lower[run], rtol=1e-12, atol=0)
        np.testing.assert_allclose(single.upper, batch.upper[run], rtol=1e-12, atol=0)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"unknown_input": (np.array([-6.0, -5.0]), np.array([5.0, 5.0]))}, BoundsError, "lower <= 0 <= upper"),
        ({"unknown_input": (np.array([0.5, -5.0]), np.array([5.0, 5.0]))}, BoundsError, "lower <= 0 <= upper"),
        ({"unknown_input": (np.zeros(3), np.zeros(3))}, BoundsError, r"shape \(2,\) or \(M, 2\)"),
        ({"decay": 0.0}, ArgumentError, "decay: expected a positive"),
        ({"t": np.array([0.0, 1e-3, 3e-3])}, DataError, "t: expected uniform spacing"),
        ({"q": np.zeros((1, 4, 2))}, DataError, "y: expected"),
        ({"unknown_input": (np.zeros((3, 2)), np.zeros((3, 2)))}, DataError, "expected 3 runs"),
    ],
    ids=[
        "fault-beyond-bound",
        "fault-box-without-zero",
        "fault-box-shape",
        "decay-zero",
        "t-spacing",
        "q-shape",
        "bank-size",
    ],
)
def test_bad_input_names_the_argument(model, kwargs, error, match):
    args = {"t": np.arange(3) * H, "q": np.zeros((1, 3, 2)), "u": np.zeros((1, 3, 2)), "unknown_input": BOTH}
    args.update(kwargs)
    with pytest.raises(error, match=match):
        observer = AnglesOnlyObserver(model, H, VELOCITY_BOX, args["unknown_input"], decay=args.get("decay", 1.0))
        observer.run(args["t"], args["q"], args["u"])


def test_design_refuses_a_disturbance_box(model):
    with pytest.raises(BoundsError, match=r"bounds\.w: expected none"):
        AnglesOnlyObserver.design(model, Bounds(x0=(-1.0, 1.0), w=(-0.1, 0.1)), h=H, unknown_input=BOTH)
