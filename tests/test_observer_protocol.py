"""The protocol every observer shares (observers/base.py): what ``run`` and ``step`` refuse and accept."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from intervalobs import Bounds, BoundsError, DataError, LTISystem
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
    ZonotopicObserver,
)
from intervalobs.observers.gsisio import GSISIO
from intervalobs.systems.nonlinear import NonlinearSystem

H = 0.1


def _discrete() -> tuple[LTISystem, Bounds]:
    A = np.array([[0.6, 0.2], [-0.1, 0.5]])
    system = LTISystem(A, [[1.0, 0.0]], B=[[0.0], [1.0]], dt=1.0)
    return system, Bounds((-np.ones(2), np.ones(2)), w=(-0.1 * np.ones(2), 0.1 * np.ones(2)), v=([-0.05], [0.05]))


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
        w=paper.w,
        v=paper.v,
    )
    return GSISIO.design(system, gsisio_example.FULLRANK_X0_BOX)


def _hgio() -> Observer:
    from intervalobs.design.regions import place_in_disks

    gain = place_in_disks(hgio_example.A, hgio_example.C, hgio_example.DISKS).L
    return HighGainIntervalObserver(
        hgio_example.system(), hgio_example.bounds(), gain, hgio_example.STEP, input_rate=hgio_example.INPUT_RATE
    )


def _lpv() -> Observer:
    box = (np.asarray(X0) - 0.1, np.asarray(X0) + 0.1)
    return LPVIntervalObserver(ManipulatorModel(cells=8, splits=2, pieces=2), 1e-3, -np.eye(4), x0=box)


OBSERVERS: dict[str, Callable[[], Observer]] = {
    "interval-tube": lambda: IntervalObserver.design(spring_mass.system(), spring_mass.bounds(), h=H),
    "interval-framer": lambda: IntervalObserver.design(
        spring_mass.system(), spring_mass.bounds(), h=H, method="framer"
    ),
    "intersection": lambda: IntersectionObserver.design(spring_mass.system(), spring_mass.bounds(), h=H),
    "fir": lambda: FiniteMemoryObserver.design(*_discrete(), window=6),
    "hull": lambda: HullEstimator(*_discrete(), horizon=4),
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
    "hull": lambda s, b, h: HullEstimator(s, b, horizon=4, h=h),
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
