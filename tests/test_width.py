"""HGIO designed for width (intervalobs.design.width) and the LMI regions beyond disks."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import DesignError
from intervalobs.design.regions import (
    Disk,
    HalfPlane,
    HorizontalStrip,
    Sector,
    VerticalStrip,
    in_region,
    modal_decomposition,
)
from intervalobs.design.width import design_for_width, modal_width_bound
from intervalobs.errors import BoundsError
from intervalobs.examples import hgio as example
from intervalobs.observers.hgio import HighGainIntervalObserver
from intervalobs.simulate import simulate_sampled
from intervalobs.systems import Bounds
from intervalobs.systems.sampled import SampledSystem

COARSE_STEP = 0.01  # the design at a coarse step: same code path, 10x fewer points
D_RADIUS = np.array([0.1, 1.0, 1.0])


@pytest.mark.parametrize(
    ("region", "inside"),
    [
        (HalfPlane(0.8), lambda s: s.real < -0.8),
        (VerticalStrip(-2.0, -0.5), lambda s: (s.real > -2.0) & (s.real < -0.5)),
        (HorizontalStrip(1.5), lambda s: np.abs(s.imag) < 1.5),
        (Sector(np.pi / 5), lambda s: (s.real < 0) & (np.abs(s.imag) < np.tan(np.pi / 5) * -s.real)),
        (Disk(-1 + 1j, 0.7), lambda s: np.abs(s - (-1 + 1j)) < 0.7),
    ],
    ids=["half-plane", "vertical-strip", "horizontal-strip", "sector", "disk"],
)
def test_region_characteristic_matches_its_geometry(region: object, inside: object) -> None:
    rng = np.random.default_rng(3)
    s = rng.uniform(-4, 2, 4000) + 1j * rng.uniform(-3, 3, 4000)
    np.testing.assert_array_equal(in_region(region, s), inside(s))  # type: ignore[arg-type, operator]


def test_region_validation() -> None:
    with pytest.raises(BoundsError, match=r"Sector\.angle"):
        Sector(2.0)
    with pytest.raises(BoundsError, match="VerticalStrip"):
        VerticalStrip(-1.0, -2.0)
    with pytest.raises(BoundsError, match=r"HalfPlane\.shift"):
        HalfPlane(-1.0)
    with pytest.raises(BoundsError, match=r"HorizontalStrip\.bound"):
        HorizontalStrip(0.0)


def test_bound_is_the_observers_radius_recursion() -> None:
    """With φ = 0 and L = 0 the input radius is exactly d^r: the bound is the observer's own radius."""
    system = SampledSystem(example.A, example.C, sample_period=COARSE_STEP)
    bounds = Bounds(x0=(np.zeros(3), np.zeros(3)), w=(-D_RADIUS, D_RADIUS), v=([-0.1], [0.1]))
    gain = np.zeros((3, 1))
    bound = modal_width_bound(modal_decomposition(example.A, example.C, gain), D_RADIUS, COARSE_STEP)
    t = np.arange(0.0, bound.settle_s + bound.window_s, COARSE_STEP)
    observer = HighGainIntervalObserver(
        system, bounds, gain, COARSE_STEP, refine=False, rewrap=False, predictor="box", output_gain=gain
    )
    y = np.full((t.size, 1), np.nan)
    est = observer.run(t, y)
    width = est.meta["theorem45_upper"] - est.meta["theorem45_lower"]
    steady = width[t >= bound.settle_s]
    # the observer adds rounding pads of 8 eps per step, relative: 1e-9 covers ~5000 steps with a margin
    np.testing.assert_allclose(steady.mean(axis=0), bound.mean, rtol=1e-9)
    np.testing.assert_allclose(steady.max(axis=0), bound.sup, rtol=1e-9)


@pytest.fixture(scope="module")
def sector_design() -> object:
    return design_for_width(
        example.A,
        example.C,
        COARSE_STEP,
        d_radius=D_RADIUS,
        phi_radius=example.PHI_RADIUS,
        output_radius=[0.1],
        weights=[0.0, 1.0, 1.0],
        regions=(Sector(np.pi / 4), HalfPlane(0.5)),
    )


def test_design_keeps_every_constraint(sector_design: object) -> None:
    design = sector_design
    vals = design.placement.eigenvalues  # type: ignore[attr-defined]
    for region in design.regions:  # type: ignore[attr-defined]
        assert np.all(in_region(region, vals))
    disks = design.disks  # type: ignore[attr-defined]
    ring = np.exp(2j * np.pi * np.arange(64) / 64)
    for j, disk in enumerate(disks):
        assert disk.margin(vals[j]) > 0
        for region in design.regions:  # type: ignore[attr-defined]
            assert np.all(in_region(region, disk.center + disk.radius * ring))
        for other in disks[j + 1 :]:
            assert abs(disk.center - other.center) > disk.radius + other.radius  # disjoint: distinct eigenvalues
    assert design.placement.modal.condition <= 100.0  # type: ignore[attr-defined]
    # Algorithm 1 in the derived disks reproduces the optimiser's gain (single output: the spectrum fixes it)
    np.testing.assert_allclose(design.L, design.optimum_L, rtol=1e-4, atol=1e-4)  # type: ignore[attr-defined]


def test_a_binding_constraint_costs_width(sector_design: object) -> None:
    free = design_for_width(
        example.A,
        example.C,
        COARSE_STEP,
        d_radius=D_RADIUS,
        phi_radius=example.PHI_RADIUS,
        output_radius=[0.1],
        weights=[0.0, 1.0, 1.0],
    )
    angles = np.abs(np.angle(-free.placement.eigenvalues))
    assert np.max(angles) > np.pi / 4  # the free optimum lies outside the sector...
    assert free.objective < sector_design.objective  # type: ignore[attr-defined]  # ...so the sector costs width
    constructive = modal_width_bound(
        modal_decomposition(example.A, example.C, np.zeros((3, 1))), example.PHI_RADIUS + D_RADIUS, COARSE_STEP
    )
    assert free.objective < 0.7 * float(np.array([0.0, 1.0, 1.0]) @ constructive.mean)


def test_infeasible_constraints_raise() -> None:
    with pytest.raises(DesignError, match="relax them"):
        design_for_width(
            example.A,
            example.C,
            COARSE_STEP,
            d_radius=D_RADIUS,
            phi_radius=example.PHI_RADIUS,
            output_radius=[0.1],
            regions=(HalfPlane(50.0),),
        )


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_width_design_meets_the_goal_soundly(seed: int) -> None:
    """Issue 18: x1 <= 0.3, x2 <= 8, x3 <= 5.5 mean widths (t >= 5 s), enclosure 1.0 against RK4 truth."""
    system, bounds = example.system(), example.bounds()
    observer = HighGainIntervalObserver.design_for_width(
        system,
        bounds,
        h=example.STEP,
        phi_radius=example.PHI_RADIUS,
        input_rate=example.INPUT_RATE,
        weights=[0.0, 1.0, 1.0],
        regions=(HalfPlane(0.5), HorizontalStrip(5.0)),
    )
    t = np.arange(0.0, example.T_FINAL + example.STEP / 2, example.STEP)
    sim = simulate_sampled(system, bounds, t, u=example.input_signal, noise="extreme", seed=seed, runs=1, substeps=4)
    est = observer.run(t, sim.y, sim.u)
    assert est.enclosure(sim.x).max_violation == 0.0
    theorem45 = (est.meta["theorem45_lower"], est.meta["theorem45_upper"])
    assert np.all(theorem45[0] <= sim.x) and np.all(sim.x <= theorem45[1])
    assert np.all(est.meta["output_lower"] <= sim.x[..., :1]) and np.all(sim.x[..., :1] <= est.meta["output_upper"])
    widths = (est.upper - est.lower)[:, t >= 5.0].mean(axis=(0, 1))
    assert np.all(widths <= [0.3, 8.0, 5.5]), widths
