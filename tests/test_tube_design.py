"""Gain design at scale: the framer search's candidate pruning."""

import numpy as np
import pytest

from conftest import random_system
from intervalobs.design import cooperative
from intervalobs.examples.scale_cases import tank_cascade
from intervalobs.systems.sampling import sampled_model

# (seed, n, p, continuous, uncertain): gains of more than 16 entries (the gradient refinement's domain)
LARGE_GAIN_CASES = [(20, 6, 3, False, False), (21, 6, 4, True, True), (22, 8, 3, False, True), (23, 7, 4, True, False)]


def _model(system, bounds, continuous):
    full = bounds.resolve(system)
    return sampled_model(system, full, 0.05 if continuous else None), full.radius("v")


def _random(seed, n, p, continuous, uncertain):
    system, bounds = random_system(seed, n, p, continuous, uncertain)
    return system, bounds, continuous


def _tanks(n):
    case = tank_cascade(n)
    return case.system, case.bounds, False


@pytest.mark.parametrize(
    "make,args",
    [
        (_random, LARGE_GAIN_CASES[0]),
        (_random, LARGE_GAIN_CASES[1]),
        (_random, (1, 4, 2, False, False)),
        (_tanks, (12,)),
    ],
)
def test_skipping_candidates_that_cannot_win_leaves_the_framer_design_unchanged(monkeypatch, make, args):
    system, bounds, continuous = make(*args)
    model, v_radius = _model(system, bounds, continuous)
    pruned = cooperative.design_framer(model, system.C, system.F, v_radius)
    monkeypatch.setattr(cooperative, "_noise_floor", lambda model, T: -np.inf)
    full = cooperative.design_framer(model, system.C, system.F, v_radius)
    np.testing.assert_array_equal(pruned.L, full.L)
    np.testing.assert_array_equal(pruned.T, full.T)
    np.testing.assert_array_equal(pruned.steady_radius, full.steady_radius)
    assert pruned.coordinates == full.coordinates
    skipped = [name for name, score in pruned.tried.items() if score == np.inf and np.isfinite(full.tried[name])]
    if make is _tanks:  # the modal basis of the cascade spreads every tank's noise over all: its LPs are skipped
        assert "modal" in skipped


def test_noise_floor_is_below_every_gains_steady_radius_sum():
    """|T⁻¹||T|r_w bounds the steady x-radius of any gain with a stable width system in coordinates T."""
    rng = np.random.default_rng(0)
    for seed in range(6):
        system, bounds = random_system(seed, 4, 2, False, seed % 2 == 1)
        model, v_radius = _model(system, bounds, False)
        candidates = cooperative.coordinate_candidates(model, system.C, system.F, v_radius)
        design = cooperative.design_framer(model, system.C, system.F, v_radius, candidates)
        for T in candidates.values():
            floor = cooperative._noise_floor(model, T)
            for gain in [design.L] + [design.L + 0.05 * rng.normal(size=design.L.shape) for _ in range(20)]:
                rho, radius = cooperative._steady_radius(model, system.C, system.F, v_radius, gain, T)
                if rho < 1:
                    assert floor <= radius.sum() * (1 + 1e-12)
