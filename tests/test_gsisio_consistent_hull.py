"""The data-only lower bound of the seed-003 reproduction: every generated point is consistent with the data."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.examples import gsisio as ex
from intervalobs.observers.null_space_gsisio import NullSpaceGSISIO
from intervalobs.reproduce import nonlinear_gsisio as ng
from intervalobs.simulate import simulate_nonlinear

STEPS = 40


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_consistent_hull_is_consistent_and_inside_every_sound_box(seed: int) -> None:
    system = ex.paper_system()
    bounds = ex.paper_bounds().resolve(system)
    sim = simulate_nonlinear(system, bounds, ex.paper_input(STEPS), noise="extreme", seed=seed)
    hull = ng._consistent_set_inner_hull(system, bounds, sim)
    # witnesses, checked from f, g, G, H directly: x_0 in X0, w_k in W, v_k in V with d_k as generated
    xs, ds = hull.paths_x, hull.paths_d
    assert xs.shape[0] > 1 and np.all(np.isfinite(xs)) and np.all(np.isfinite(ds[:, 1:]))
    assert np.all((bounds.x0[0] <= xs[:, 0]) & (xs[:, 0] <= bounds.x0[1]))
    w = xs[:, 1:] - system.evaluate_f(xs[:, :-1]) - ds[:, 1:] @ system.G.T
    v = sim.y[:-1] - system.evaluate_g(xs[:, :-1]) - ds[:, 1:] @ system.H.T
    # the truth's path sits on the boxes' faces (bang-bang): allow the rounding of these O(10) sums, far
    # below the generator's margin (1e-8 of the radius) and its accepted Newton residual (1e-10)
    tol = 1e-13
    assert np.all((bounds.w[0] - tol <= w) & (w <= bounds.w[1] + tol))
    assert np.all((bounds.v[0] - tol <= v) & (v <= bounds.v[1] + tol))
    u2 = np.linalg.svd(system.H)[0][:, 1]  # the last output y_T-1 constrains x_T-1 through U2' only
    last = (sim.y[-1] - system.evaluate_g(xs[:, -1])) @ u2
    assert np.all(np.abs(last) <= np.abs(u2) @ (bounds.v[1] - bounds.v[0]) / 2 + tol)
    # the truth is one of the consistent points, so inside the hull
    assert np.all((hull.x_lower <= sim.x) & (sim.x <= hull.x_upper))
    assert np.all((hull.d_lower[1:] <= sim.d[:-1]) & (sim.d[:-1] <= hull.d_upper[1:]))
    # the truth's successors are in the population: the data-only hull contains the known-state hull
    known = ng._known_state_inner_hull(system, bounds, sim)
    assert np.all(hull.x_lower[1:] <= known[0][1:] + tol) and np.all(known[1][1:] <= hull.x_upper[1:] + tol)
    assert np.all(hull.d_lower[1:] <= known[2][1:] + tol) and np.all(known[3][1:] <= hull.d_upper[1:] + tol)
    # a sound estimator contains every consistent point
    est = NullSpaceGSISIO.design(system, bounds, splits=ng.SPLITS).run(np.arange(STEPS, dtype=float), sim.y)
    assert est.input_lower is not None and est.input_upper is not None
    assert np.all((est.lower <= hull.x_lower) & (hull.x_upper <= est.upper))
    assert np.all((est.input_lower[1:] <= hull.d_lower[1:]) & (hull.d_upper[1:] <= est.input_upper[1:]))
    tight = ng._tightness(est, known, (hull.x_lower, hull.x_upper, hull.d_lower, hull.d_upper))
    for part in ("state", "input"):
        assert tight[part]["consistent_hull_inside_ours"]
        assert 1.0 <= tight[part]["consistent_ratio_norm"] <= tight[part]["ratio_norm"]
