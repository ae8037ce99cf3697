"""The field tape: its compiled replay gives the Python evaluation's boxes bit for bit, falls back where it cannot
record, and the observer that runs on it still encloses truths of the tests' own integrator."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from intervalobs import Bounds, ContinuousNonlinearObserver, ContinuousNonlinearSystem
from intervalobs.estimate import enclosure_report
from intervalobs.interval import Interval
from intervalobs.interval_dual import value_and_jacobian
from intervalobs.systems.field_tape import OPERATIONS, trace_field
from intervalobs.systems.flow_enclosure import StateZonotope, propagate
from nonlinear_cases import Case, chemostat_bundle, compartments, cstr, measure, pendulum, simulate_truth


def _monod(x: Any, u: Any, p: Any) -> tuple[Any, ...]:
    growth = p[0] * x[1] / (p[1] + x[1])
    return (growth - 0.2) * x[0], 0.2 * (5.0 - x[1]) - growth * x[0] / 0.5


def _arrhenius(x: Any, u: Any, p: Any) -> tuple[Any, ...]:
    rate = p[0] * (1.0 - x[0]) * np.exp(-8.0 / (x[1] + 3.0))
    return -x[0] + rate + u[0], -x[1] + 8.0 * rate - 0.3 * x[1]


def _pendulum(x: Any, u: Any, p: Any) -> tuple[Any, ...]:
    return x[1], -9.81 * np.sin(x[0]) - p[0] * x[1] + u[0] * np.cos(x[0])


def _division(x: Any, u: Any, p: Any) -> tuple[Any, ...]:
    return 1.0 / (x[0] + 4.0) - x[1] / (p[0] + 1.0), (x[0] * x[1]) / (x[1] + 4.5) - 2.0 / p[0] + u[0] / 3.0


def _everything(x: Any, u: Any, p: Any) -> tuple[Any, ...]:
    """Every recorded operation, on intervals and on points (the input), with constants on either side."""
    first = np.sqrt(x[0] + 5.0) + np.arctan(x[1]) + np.abs(x[1]) - (-x[0]) + x[0] ** 3 + np.square(x[1]) + x[0] ** 0
    second = np.log(x[0] + 4.0) * u[0] ** 2 + np.sin(u[0]) * p[0] - np.exp(u[0] / 2.0) + (u[0] - 1.0) * x[1] ** 4
    return first + 2 - x[1], second / (3.0 - u[0]) + np.cos(x[0] * p[0])


FIELDS = {
    "monod": _monod,
    "arrhenius": _arrhenius,
    "pendulum": _pendulum,
    "division": _division,
    "every-operation": _everything,
}


def _system(f: Callable[..., Any]) -> ContinuousNonlinearSystem:
    return ContinuousNonlinearSystem(f, lambda x, u: (x[0],), n=2, m=1, n_params=2)


def _random_boxes(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Boxes of (x0, x1, p0, p1): states from [0, 3] (some points, some 2 wide), parameters from [0.1, 1.5]."""
    lower = np.concatenate([rng.uniform(0.0, 3.0, (count, 2)), rng.uniform(0.1, 1.0, (count, 2))], axis=1)
    width = rng.uniform(0.0, 2.0, (count, 4)) * rng.integers(0, 2, (count, 4)) * np.array([1.0, 1.0, 0.25, 0.25])
    return lower, lower + width


def test_the_codes_are_the_kernels() -> None:
    from intervalobs.systems import tape_kernel

    assert OPERATIONS.index("absolute") == tape_kernel.ABS
    assert OPERATIONS.index("pow") == tape_kernel.POW


@pytest.mark.parametrize("name", list(FIELDS), ids=str)
def test_replay_is_the_python_evaluation_bit_for_bit(name: str) -> None:
    """600 random boxes (points and wide ones among them): the same value and Jacobian ends as value_and_jacobian."""
    system = _system(FIELDS[name])
    tape, reason = trace_field(system, np.array([-1.0, -1.0, 0.5, 0.5]), np.array([1.0, 1.0, 0.6, 0.6]))
    assert tape is not None, reason
    rng = np.random.default_rng(11)
    for _ in range(20):
        lower, upper = _random_boxes(rng, 30)
        u = rng.uniform(-1.0, 1.0, (30, 1))
        with np.errstate(all="ignore"):
            value, jacobian = value_and_jacobian(system.augmented_field(u), lower, upper, 4)
        replay = tape.evaluate(lower, upper, u, derivative=True)
        assert replay[1] is not None
        for mine, theirs in ((replay[0], value), (replay[1], jacobian)):
            np.testing.assert_array_equal(mine.lower, theirs.lower)
            np.testing.assert_array_equal(mine.upper, theirs.upper)
        np.testing.assert_array_equal(tape.evaluate(lower, upper, u)[0].upper, value.upper)


@pytest.mark.parametrize(
    ("field", "reason"),
    [
        (lambda x, u, p: (x[0] if x[0] > 0 else -x[0],), "not supported between"),
        (lambda x, u, p: (np.tanh(x[0]),), "numpy.tanh"),
        (lambda x, u, p: (x[0] ** 1.5,), "nonnegative integer"),
        (lambda x, u, p: (math.exp(x[0]),), "conversion of a value"),
        (lambda x, u, p: (np.maximum(x[0], 0.0),), "numpy.maximum"),
    ],
    ids=["branch", "tanh", "float-power", "math-function", "unsupported-function"],
)
def test_a_field_it_cannot_record_is_refused_with_the_reason(field: Callable[..., Any], reason: str) -> None:
    system = ContinuousNonlinearSystem(field, lambda x, u: (x[0],), n=1)
    tape, why = trace_field(system, np.array([0.5]), np.array([1.0]))
    assert tape is None
    assert why.startswith("not recorded") and reason in why


def test_a_replay_that_differs_from_the_python_evaluation_is_not_used() -> None:
    """A field whose constant changes between calls (state the recording cannot see): the probe catches it."""
    calls = itertools.count()

    def drifting(x: Any, u: Any, p: Any) -> tuple[Any]:
        return (x[0] * float(next(calls)),)

    system = ContinuousNonlinearSystem(drifting, lambda x, u: (x[0],), n=1)
    tape, why = trace_field(system, np.array([0.5]), np.array([1.0]))
    assert tape is None and why.startswith("not used") and "differs" in why


def test_an_untraceable_field_runs_in_python_and_says_so() -> None:
    """The pendulum with a tanh friction (not recorded): compiled=True falls back to the Python field, the same bounds
    as the NumPy path."""

    def saturated(x: Any, u: Any, p: Any) -> tuple[Any, Any]:
        return x[1], -9.81 * np.sin(x[0]) - p[0] * np.tanh(x[1]) + u[0]

    case = pendulum()
    system = ContinuousNonlinearSystem(saturated, lambda x, u: (x[0],), n=2, m=1, n_params=1, E=[[0.0], [1.0]])
    t, u, _, y = _record(case, 1.0)
    runs = [ContinuousNonlinearObserver(system, case.bounds, case.h, compiled=c).run(t, y[0], u) for c in (False, True)]
    assert runs[1].meta["field_tape"].startswith("not recorded") and runs[0].meta["field_tape"] is None
    np.testing.assert_allclose(runs[1].lower, runs[0].lower, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(runs[1].upper, runs[0].upper, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("make", [pendulum, cstr, chemostat_bundle], ids=["pendulum", "cstr", "chemostat"])
def test_the_recorded_step_gives_the_python_step(make: Callable[[], Case]) -> None:
    """flow_kernel.propagate (the tape, Picard, Jacobian and steps 3-4 in one call) against the Python step with the
    Python field: the a priori hull and the set agree to the order of a few sums (12 random zonotopes)."""
    case = make()
    b = case.bounds.resolve(case.system)
    size = case.system.n + case.system.n_params
    low, high = np.concatenate([b.x0[0], b.p[0]]), np.concatenate([b.x0[1], b.p[1]])
    rng = np.random.default_rng(5)
    centre = low + (high - low) * rng.uniform(0.3, 0.7, (12, size))
    start = StateZonotope(centre, 0.03 * (high - low)[:, None] * rng.uniform(-1.0, 1.0, (12, size, 4 * size)))
    tape, reason = trace_field(case.system, low, high)
    assert tape is not None, reason
    u, w = np.full((12, case.system.m), 0.3), Interval._raw(*b.w)
    reference = propagate(case.system, u, w, start, case.h, 2, 3 * size)
    recorded = propagate(case.system, u, w, start, case.h, 2, 3 * size, compiled=True, tape=tape)
    for mine, theirs in ((recorded[0].box(), reference[0].box()), (recorded[1], reference[1])):
        scale = theirs.upper - theirs.lower
        assert np.all(np.abs(mine.lower - theirs.lower) <= 1e-12 * scale + 1e-15)
        assert np.all(np.abs(mine.upper - theirs.upper) <= 1e-12 * scale + 1e-15)


def _record(case: Case, duration: float, starts: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Truths from starts at vertices of the x0 and p boxes, the tests' own RK4 with w switching inside steps."""
    b = case.bounds.resolve(case.system)
    t = np.arange(0.0, duration + 1e-9, case.h)
    u = np.tile(0.5 + 0.3 * np.sin(t)[:, None], (1, case.system.m))
    vertices = list(itertools.product((b.x0[0], b.x0[1], b.centre("x0")), (b.p[0], b.p[1])))[:starts]
    truths = [simulate_truth(case, x0, p, t, u, seed) for seed, (x0, p) in enumerate(vertices)]
    outputs = [measure(case, x, seed) for seed, x in enumerate(truths)]
    return t, u, np.array(truths), np.array(outputs)


@pytest.mark.parametrize(
    "make", [pendulum, cstr, compartments, chemostat_bundle], ids=["pendulum", "cstr", "compartments", "chemostat"]
)
def test_the_observer_on_the_tape_encloses_every_truth(make: Callable[[], Case]) -> None:
    case = make()
    t, u, x, y = _record(case, 3.0, starts=6)
    observer = ContinuousNonlinearObserver(case.system, case.bounds, case.h, compiled=True, **case.observer_options)
    held = np.broadcast_to(u, (*y.shape[:2], case.system.m)) if case.system.m else None
    estimate = observer.run(t, y, held)
    assert estimate.meta["field_tape"] == "recorded"
    assert enclosure_report(t, estimate.lower, x, estimate.upper).fraction == 1.0
    assert np.all(np.isfinite(estimate.upper[:, -1]))


def test_a_field_undefined_at_a_probe_input_is_recorded_when_both_paths_refuse() -> None:
    """``x / u`` is undefined at the probe's input 0 in Python and in the replay alike: recorded, and sound."""
    with np.errstate(all="ignore"):  # the model's own check evaluates f at u = 0
        system = ContinuousNonlinearSystem(lambda x, u, p: (x[0] / u[0],), lambda x, u: (x[0],), n=1, m=1)
    tape, why = trace_field(system, np.array([0.5]), np.array([1.0]))
    assert tape is not None, why
    bounds = Bounds(x0=(0.5, 1.0), v=(-0.01, 0.01))
    t = np.arange(0.0, 1.0 + 1e-9, 0.1)
    u = np.full((t.size, 1), 2.0)
    truth = 0.75 * np.exp(t / 2.0)
    estimate = ContinuousNonlinearObserver(system, bounds, 0.1, compiled=True).run(t, truth[:, None], u)
    assert estimate.meta["field_tape"] == "recorded"
    assert np.all((estimate.lower[:, 0] <= truth) & (truth <= estimate.upper[:, 0]))


@pytest.mark.parametrize("make", [chemostat_bundle, compartments, cstr], ids=["chemostat", "compartments", "cstr"])
def test_the_recorded_correction_gives_the_python_correction(make: Callable[[], Case]) -> None:
    """correction_kernel.correct (domain, parameter box, every output's strip) against the Python correction: 12
    random sets, some crossing the domain, three contradicted by the data: the same sets to the order of a few sums
    and the same empty ones."""
    case = make()
    b = case.bounds.resolve(case.system)
    size = case.system.n + case.system.n_params
    low, high = np.concatenate([b.x0[0], b.p[0]]), np.concatenate([b.x0[1], b.p[1]])
    rng = np.random.default_rng(9)
    centre = low + (high - low) * rng.uniform(-0.2, 1.2, (12, size))
    observer = ContinuousNonlinearObserver(case.system, case.bounds, case.h, compiled=True)
    generators = 0.1 * (high - low)[:, None] * rng.uniform(-1.0, 1.0, (12, size, observer.order))
    start = StateZonotope(centre, generators)
    truth = centre[:, : case.system.n] + 0.05 * (high - low)[: case.system.n] * rng.uniform(-1, 1, (12, case.system.n))
    y = truth[:, case.outputs] + b.v[1] * rng.uniform(-3.0, 3.0, (12, len(case.outputs)))
    y[-3:] += 100.0  # three sets the data contradict
    u = np.full((12, case.system.m), 0.4)
    recorded = observer._correct(start, y, u, True)
    reference = observer._correct(start, y, u, False)
    assert observer._recorded(output=True)[1] == "recorded"
    np.testing.assert_array_equal(recorded[1], reference[1])
    live = ~reference[1]
    mine, theirs = recorded[0].box(), reference[0].box()
    scale = (theirs.upper - theirs.lower)[live]
    assert 3 <= live.sum() < 12, live
    assert np.all(np.abs(mine.lower[live] - theirs.lower[live]) <= 1e-12 * scale + 1e-15)
    assert np.all(np.abs(mine.upper[live] - theirs.upper[live]) <= 1e-12 * scale + 1e-15)


@pytest.mark.parametrize("make", [pendulum, cstr, chemostat_bundle], ids=["pendulum", "cstr", "chemostat"])
def test_the_compiled_picard_search_is_the_python_one_bit_for_bit(make: Callable[[], Case]) -> None:
    """flow_kernel._picard against flow_enclosure._picard (the tape's rates both): the same a priori boxes, or both
    none, for 8 random sets and their centres at two step lengths (the longer one finds none)."""
    from intervalobs.systems import flow_kernel
    from intervalobs.systems.flow_enclosure import _Flow, _picard

    case = make()
    b = case.bounds.resolve(case.system)
    size = case.system.n + case.system.n_params
    low, high = np.concatenate([b.x0[0], b.p[0]]), np.concatenate([b.x0[1], b.p[1]])
    tape, _ = trace_field(case.system, low, high)
    assert tape is not None
    rng = np.random.default_rng(4)
    lower = low + (high - low) * rng.uniform(0.0, 0.6, (8, size))
    upper = lower + (high - low) * rng.uniform(0.0, 0.4, (8, size))
    middle = 0.5 * (lower + upper)
    u = np.full((8, case.system.m), 0.2)
    w = Interval._raw(*b.w)
    for tau in (case.h, 40 * case.h):
        flow = _Flow.build(case.system, u, w, 2, (True, tape))
        start = Interval._raw(np.stack([lower, middle]), np.stack([upper, middle]))
        expected = _picard(flow.rates, start, tau, flow.low, flow.high)
        box = (
            np.zeros((2, size))
            if flow.disturbance is None
            else np.stack([flow.disturbance.lower, flow.disturbance.upper])
        )
        domain = np.stack([flow.low.reshape(2, size), flow.high.reshape(2, size)])
        out = np.empty((2, 16, size))
        ends = np.stack([start.lower.reshape(16, size), start.upper.reshape(16, size)])
        field = ((box, flow.disturbance is not None), domain, float(tau))
        found = flow_kernel._picard(tuple(vars(tape).values()), ends, np.concatenate([u, u]), field, out)
        assert found == (expected is not None)
        if expected is not None:
            np.testing.assert_array_equal(out[0], expected.lower.reshape(16, size))
            np.testing.assert_array_equal(out[1], expected.upper.reshape(16, size))


def test_the_kernels_next_float_is_numpys_nextafter() -> None:
    """The bit-level ``_up``/``_down`` of the kernels against ``np.nextafter``: signed zeros, subnormals, the largest
    float, infinities, NaN and 200 000 numbers of every magnitude, bit for bit (the sign of a zero included)."""
    import numba

    from intervalobs.systems.tape_kernel import _down, _up

    @numba.njit
    def both(x: np.ndarray, out: np.ndarray) -> None:
        for i in range(x.size):
            out[0, i], out[1, i] = _up(x[i]), _down(x[i])

    big, tiny = np.finfo(float).max, np.finfo(float).tiny
    special = np.array([0.0, -0.0, 5e-324, -5e-324, 1e-323, tiny, -tiny, 1.0, -1.0, big, -big, np.inf, -np.inf, np.nan])
    rng = np.random.default_rng(2)
    x = np.concatenate([special, rng.standard_normal(200_000) * 10.0 ** rng.integers(-320, 300, 200_000)])
    out = np.empty((2, x.size))
    both(x, out)
    with np.errstate(over="ignore"):
        expected = np.nextafter(x, np.inf), np.nextafter(x, -np.inf)
    for mine, theirs in zip(out, expected, strict=True):
        np.testing.assert_array_equal(mine, theirs)
        np.testing.assert_array_equal(np.signbit(mine), np.signbit(theirs))


def test_an_output_map_it_cannot_record_is_evaluated_in_python() -> None:
    """The pendulum measured through tanh: f recorded, g not; the correction runs in Python, the same bounds as the
    NumPy path to the order of a few sums, every truth enclosed."""
    case = pendulum()
    system = ContinuousNonlinearSystem(
        case.system.f, lambda x, u: (np.tanh(x[0]),), n=2, m=1, n_params=1, E=[[0.0], [1.0]]
    )
    t, u, x, _ = _record(case, 1.0, starts=2)
    noise = np.where(np.random.default_rng(3).random((2, t.size)) < 0.5, -0.01, 0.01)
    y = (np.tanh(x[..., 0]) + noise)[..., None]
    held = np.broadcast_to(u, (2, t.size, 1))
    runs = [ContinuousNonlinearObserver(system, case.bounds, case.h, compiled=c).run(t, y, held) for c in (False, True)]
    assert runs[1].meta["field_tape"] == "recorded" and runs[1].meta["output_tape"].startswith("not recorded")
    np.testing.assert_allclose(runs[1].lower, runs[0].lower, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(runs[1].upper, runs[0].upper, rtol=1e-12, atol=1e-12)
    assert enclosure_report(t, runs[1].lower, x, runs[1].upper).fraction == 1.0
