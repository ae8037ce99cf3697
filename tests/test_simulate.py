"""simulate.py: the truth record."""

from __future__ import annotations

import numpy as np

from intervalobs import Bounds, LTISystem, simulate


def test_simulation_repr_is_short() -> None:
    system = LTISystem([[0.5, 0.1], [0.0, 0.4]], [[1.0, 0.0]], B=[[0.0], [1.0]], dt=1.0)
    bounds = Bounds((-np.ones(2), np.ones(2)), w=(-0.1 * np.ones(2), 0.1 * np.ones(2)), v=([-0.1], [0.1]))
    t = np.arange(5000.0)
    batch = simulate(system, bounds, t, u=np.zeros((t.size, 1)), runs=30)
    assert repr(batch) == "Simulation(runs=30, samples=5000, t=[0, 4999], n=2, p=1, m=1)"
    single = simulate(system, bounds, t[:3], u=np.zeros((3, 1)))
    assert repr(single) == "Simulation(samples=3, t=[0, 2], n=2, p=1, m=1)"
