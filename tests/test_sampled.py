"""SampledSystem (seed 004, eq. (8)) validation and the fine truth simulation."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.errors import AssumptionError, BoundsError, DataError, DimensionError
from intervalobs.examples import hgio as example
from intervalobs.simulate import simulate_sampled
from intervalobs.systems.sampled import SampledSystem


def test_validation() -> None:
    with pytest.raises(AssumptionError, match="phi_bounds"):
        SampledSystem(example.A, example.C, phi=example.phi, m=1)
    with pytest.raises(AssumptionError, match="spot check"):
        SampledSystem(
            example.A, example.C, phi=example.phi, phi_bounds=lambda *a: (np.zeros_like(a[4]), np.zeros_like(a[4])), m=1
        )
    with pytest.raises(DimensionError, match="square"):
        SampledSystem(np.ones((2, 3)), [[1.0, 0.0, 0.0]])
    with pytest.raises(BoundsError, match="sample_period"):
        SampledSystem(example.A, example.C, sample_period=0.0)


def test_simulation_samples_and_accuracy() -> None:
    system, bounds = example.system(), example.bounds()
    t = np.arange(0.0, 0.2 + 1e-12, example.STEP)
    fine = simulate_sampled(system, bounds, t, u=example.input_signal, seed=3, substeps=4)
    again = simulate_sampled(system, bounds, t, u=example.input_signal, seed=3, substeps=4)
    np.testing.assert_array_equal(fine.x, again.x)  # deterministic
    assert np.all(np.isnan(fine.y[~fine.sampled]))
    assert np.flatnonzero(fine.sampled)[:3].tolist() == [0, 5, 10]
    lo, hi = bounds.x0
    assert np.all((fine.x[0] >= lo) & (fine.x[0] <= hi))
    with pytest.raises(DataError, match="multiple"):
        simulate_sampled(system, bounds, np.arange(0, 0.1, 0.003))


def test_rk4_truth_is_accurate() -> None:
    system = SampledSystem(example.A, example.C, sample_period=5e-3)
    bounds = example.bounds()
    t = np.arange(0.0, 0.5 + 1e-12, 1e-3)
    sim = simulate_sampled(system, bounds, t, noise="constant", seed=2)
    from scipy.linalg import expm

    d = sim.d[0]
    exact = expm(example.A * 0.5) @ sim.x[0] + np.linalg.solve(example.A, (expm(example.A * 0.5) - np.eye(3)) @ d)
    np.testing.assert_allclose(sim.x[-1], exact, atol=1e-10)
