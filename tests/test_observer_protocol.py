"""The protocol every observer shares (observers/base.py): what ``run`` and ``step`` refuse and accept."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from intervalobs import Bounds, LTISystem
from intervalobs.errors import ArgumentError, ArgumentTypeError, BoundsError, DataError
from intervalobs.examples import gsisio as gsisio_example
from intervalobs.examples import hgio as hgio_example
from intervalobs.examples import spring_mass
from intervalobs.examples.manipulator import X0, ManipulatorModel
from intervalobs.observers import (
    FiniteMemoryObserver,
    HighGainIntervalObserver,
    HullEstimator,
    IntegratedObserver,
    IntersectionObserver,
    IntervalObserver,
    LPVIntervalObserver,
    Observer,
    RobustFiniteMemoryObserver,
    ZonotopicObserver,
)
from intervalobs.observers.gsisio import GSISIO
from intervalobs.systems.nonlinear import NonlinearSystem

H = 0.1


def _discrete() -> tuple[LTISystem, Bounds]:
    A = np.array([[0.6, 0.2], [-0.1, 0.5]])
    system = LTISystem(A, [[1.0, 0.0]], B=[[0.0], [1.0]], dt=1.0)
    return system, Bounds((-np.ones(2), np.ones(2)), w=(-0.1 * np.ones(2), 0.1 * np.ones(2)), v=([-0.05], [0.05]))


def _with_dA(system: LTISystem) -> LTISystem:
    """The same model with every entry of ``A`` uncertain by ±0.02."""
    box = 0.02 * np.ones((system.n, system.n))
    return LTISystem(system.A, system.C, B=system.B, dt=system.dt, dA=(-box, box))


def _gsisio() -> Observer:
    paper = gsisio_example.fullrank_system()
    system = NonlinearSystem(
        paper.f,
        paper.g,
        paper.G,
        paper.H,
        B=[[0.0], [0.1]],
        f_jacobian=paper.f_jacobian,
        g_jacobian=paper.g_jacobian,
    )
    return GSISIO.design(system, gsisio_example.fullrank_bounds())


def _hgio() -> Observer:
    from intervalobs.design.regions import place_in_disks

    gain = place_in_disks(hgio_example.A, hgio_example.C, hgio_example.DISKS).L
    return HighGainIntervalObserver(
        hgio_example.system(), hgio_example.bounds(), gain, hgio_example.STEP, input_rate=hgio_example.INPUT_RATE
    )


def _lpv() -> Observer:
    box = (np.asarray(X0) - 0.1, np.asarray(X0) + 0.1)
    return LPVIntervalObserver(ManipulatorModel(cells=8, splits=2, pieces=2), 1e-3, -np.eye(4), bounds=Bounds(x0=box))


OBSERVERS: dict[str, Callable[[], Observer]] = {
    "interval-tube": lambda: IntervalObserver.design(spring_mass.system(), spring_mass.bounds(), h=H),
    "interval-framer": lambda: IntervalObserver.design(
        spring_mass.system(), spring_mass.bounds(), h=H, method="framer"
    ),
    "intersection": lambda: IntersectionObserver.design(spring_mass.system(), spring_mass.bounds(), h=H),
    "fir": lambda: FiniteMemoryObserver.design(*_discrete(), window=6),
    "robust-fir": lambda: RobustFiniteMemoryObserver.design(_with_dA(_discrete()[0]), _discrete()[1], window=6),
    "hull": lambda: HullEstimator.design(*_discrete(), horizon=4),
    "zonotopic": lambda: ZonotopicObserver.design(*_discrete()),
    "integrated": lambda: IntegratedObserver.design(*_discrete(), fallback="hinf"),
    "gsisio": _gsisio,
    "hgio": _hgio,
    "lpv": _lpv,
}


@pytest.fixture(scope="module", params=sorted(OBSERVERS), ids=sorted(OBSERVERS))
def observer(request: pytest.FixtureRequest) -> Observer:
    return OBSERVERS[request.param]()


def _record(observer: Observer, steps: int = 6) -> tuple[np.ndarray, np.ndarray]:
    h = float(getattr(observer, "h", None) or 1.0)
    t = np.arange(steps) * h
    return t, np.zeros((steps, observer.p))


def test_every_observer_has_a_known_input(observer: Observer) -> None:
    assert observer.m > 0


def test_run_without_u_names_u(observer: Observer) -> None:
    t, y = _record(observer)
    with pytest.raises(DataError, match=r"^u: .*got None"):
        observer.run(t, y)


def test_step_without_u_names_u(observer: Observer) -> None:
    with pytest.raises(DataError, match=r"^u: .*got None"):
        observer.step(observer.init(), np.zeros(observer.p))


def test_explicit_zero_input_is_accepted(observer: Observer) -> None:
    t, y = _record(observer)
    est = observer.run(t, y, np.zeros((t.size, observer.m)))
    assert est.lower.shape == (t.size, observer.n)
    state = observer.step(observer.init(), np.zeros(observer.p), np.zeros(observer.m))
    assert np.shape(state.lower)[-1] == observer.n


LTI_DESIGNS: dict[str, Callable[[LTISystem, Bounds, float], Observer]] = {
    "interval-tube": lambda s, b, h: IntervalObserver.design(s, b, h=h),
    "interval-framer": lambda s, b, h: IntervalObserver.design(s, b, h=h, method="framer"),
    "intersection": lambda s, b, h: IntersectionObserver.design(s, b, h=h),
    "fir": lambda s, b, h: FiniteMemoryObserver.design(s, b, window=6, h=h),
    "robust-fir": lambda s, b, h: RobustFiniteMemoryObserver.design(_with_dA(s), b, window=6, h=h),
    "hull": lambda s, b, h: HullEstimator.design(s, b, horizon=4, h=h),
    "integrated": lambda s, b, h: IntegratedObserver.design(s, b, h=h, fallback="hinf"),
}


@pytest.mark.parametrize("name", sorted(LTI_DESIGNS), ids=sorted(LTI_DESIGNS))
def test_discrete_design_refuses_a_step_other_than_dt(name: str) -> None:
    system, bounds = _discrete()
    with pytest.raises(BoundsError, match=r"^h: expected None or the system's dt = 1"):
        LTI_DESIGNS[name](system, bounds, 0.5)
    LTI_DESIGNS[name](system, bounds, 1.0)  # h = dt is the same design


@pytest.mark.parametrize("name", sorted(LTI_DESIGNS), ids=sorted(LTI_DESIGNS))
def test_discrete_run_refuses_a_record_not_sampled_every_dt(name: str) -> None:
    system, bounds = _discrete()
    A = system.A
    half = LTISystem(A, system.C, B=system.B, dt=0.5)
    observer = LTI_DESIGNS[name](half, bounds, 0.5)
    t = np.arange(6.0)  # spacing 1, not dt = 0.5
    y, u = np.zeros((t.size, 1)), np.zeros((t.size, 1))
    with pytest.raises(DataError, match=r"^t: expected uniform spacing h = 0.5"):
        observer.run(t, y, u)
    observer.run(0.5 * t, y, u)


# The HGIO accepts its a-priori (Picard) box for the whole batch at once, so a run's box depends on
# the others in its batch (sound either way): only shapes and finiteness are compared.
SHARED_ACROSS_RUNS = ("HighGainIntervalObserver",)


def test_batched_step_equals_steps_of_each_run(observer: Observer) -> None:
    """A leading Monte Carlo axis on ``y``/``u`` in ``step`` gives each run's own numbers."""
    if "(M, p)" not in (type(observer).step.__doc__ or ""):
        pytest.skip("step documents one run only")
    rng = np.random.default_rng(3)
    runs, steps = 3, 4
    y = 0.01 * rng.uniform(-1, 1, (runs, steps, observer.p))
    u = 0.1 * rng.uniform(-1, 1, (runs, steps, observer.m))
    batched = observer.init()
    single = [observer.init() for _ in range(runs)]
    for k in range(steps):
        batched = observer.step(batched, y[:, k], u[:, k])
        single = [observer.step(s, y[i, k], u[i, k]) for i, s in enumerate(single)]
        for i, s in enumerate(single):
            if type(observer).__name__ in SHARED_ACROSS_RUNS:
                assert batched.lower[i].shape == s.lower.shape and np.all(np.isfinite(batched.upper[i]))
            else:
                np.testing.assert_allclose(batched.lower[i], s.lower, rtol=1e-12, atol=1e-12)
                np.testing.assert_allclose(batched.upper[i], s.upper, rtol=1e-12, atol=1e-12)


def test_repr_is_short_and_names_dimensions_and_method_facts(observer: Observer) -> None:
    text = repr(observer)
    assert text.startswith(f"{type(observer).__name__}(n={observer.n}, p={observer.p}, m={observer.m}, ")
    assert " at 0x" not in text and "\n" not in text and len(text) < 160
    for name in observer.summary_fields:
        if getattr(observer, name, None) is not None:
            assert f"{name}=" in text


def _null_space_gsisio() -> Observer:
    from intervalobs.observers.null_space_gsisio import NullSpaceGSISIO

    return NullSpaceGSISIO.design(gsisio_example.paper_system(), gsisio_example.paper_bounds())


# HullEstimator steps one run at a time (LPs do not batch): its run == step is tested in test_hull.py.
RUN_LOOP = {
    **{name: make for name, make in OBSERVERS.items() if name != "hull"},
    "null-space-gsisio": _null_space_gsisio,
}


@pytest.mark.parametrize("name", sorted(RUN_LOOP), ids=sorted(RUN_LOOP))
def test_run_equals_init_and_steps_as_its_rows_say(name: str) -> None:
    """``run`` gives the numbers of ``init`` then ``step`` at every sample, rows as ``meta["rows"]`` states.

    ``"predicted"``: row 0 is the prior, row k + 1 the state after ``step`` with ``y_k``; ``"filtered"``:
    row k is the state after ``step`` with ``y_k``. Input rows without a bound are ``[-inf, inf]``. The
    runs are stepped as one batch (the HGIO's a-priori box is shared by a batch).
    """
    observer = RUN_LOOP[name]()
    rng = np.random.default_rng(11)
    runs, steps = 2, 5
    h = float(getattr(observer, "h", None) or 1.0)
    t = np.arange(steps) * h
    y = 0.01 * rng.uniform(-1, 1, (runs, steps, observer.p))
    u = 0.1 * rng.uniform(-1, 1, (runs, steps, observer.m))
    est = observer.run(t, y, u)
    assert est.meta["rows"] == observer.rows in ("predicted", "filtered")
    state = observer.init()
    rows = [] if observer.rows == "filtered" else [state]
    for k in range(steps - len(rows)):
        state = observer.step(state, y[:, k], u[:, k])
        rows.append(state)

    def stacked(key: str) -> np.ndarray:
        return np.stack([np.broadcast_to(getattr(s, key), (runs, np.shape(getattr(s, key))[-1])) for s in rows], 1)

    keys = ["lower", "upper"] + (["input_lower", "input_upper"] if est.input_lower is not None else [])
    for key in keys:
        np.testing.assert_allclose(getattr(est, key), stacked(key), rtol=1e-12, atol=1e-12, err_msg=key)


def test_init_refuses_one_bound_of_the_prior_box(observer: Observer) -> None:
    """A single bound would be ignored (the design's prior box used instead): refused."""
    with pytest.raises(ArgumentError, match=r"^x0_lower, x0_upper: expected both or neither, got x0_lower without"):
        observer.init(np.ones(observer.n))
    with pytest.raises(ArgumentError, match=r"got x0_upper without x0_lower$"):
        observer.init(x0_upper=np.ones(observer.n))


def test_step_refuses_a_state_not_made_by_init(observer: Observer) -> None:
    with pytest.raises(
        ArgumentTypeError, match=r"^state: expected the ObserverState returned by init or step, got NoneType$"
    ):
        observer.step(None, np.zeros(observer.p), np.zeros(observer.m))  # type: ignore[arg-type]


def test_complex_measurements_are_refused_not_truncated(observer: Observer) -> None:
    t, y = _record(observer)
    u = np.zeros((t.size, observer.m))
    with pytest.raises(ArgumentTypeError, match=r"^y: expected real numbers, got complex values"):
        observer.run(t, y + 1e-3j, u)
    with pytest.raises(ArgumentTypeError, match=r"^y: expected real numbers, got complex values"):
        observer.step(observer.init(), y[0] + 1e-3j, u[0])
    with pytest.raises(ArgumentTypeError, match=r"^u: expected real numbers, got complex values"):
        observer.step(observer.init(), y[0], u[0] + 1e-3j)
