"""Affine abstraction LP (1), its sound sigma, and Corollary 1."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from intervalobs.design.abstraction import abstraction_sigma, affine_abstraction, corollary1_bounds
from intervalobs.design.mixed_monotone import decomposition_bounds, jacobian_bounds
from intervalobs.examples import gsisio
from intervalobs.inclusion import evaluate_function
from intervalobs.interval import Interval
from test_mixed_monotone import random_map


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.05, 3.0))
def test_affine_bounds_hold_on_the_whole_box(seed, scale):
    q, jac = random_map(seed, 2, 2)
    rng = np.random.default_rng(seed)
    lo = rng.normal(size=2)
    hi = lo + rng.uniform(0.01, scale, size=2)
    jb = jacobian_bounds(jac, lo, hi)
    ab = affine_abstraction(q, lo, hi, abstraction_sigma(lo, hi, *jb))
    pts = np.concatenate([Interval(lo, hi).vertices(), rng.uniform(lo, hi, size=(3000, 2))])
    vals = evaluate_function(q, pts)
    assert np.all(pts @ ab.A_lower.T + ab.e_lower <= vals)
    assert np.all(vals <= pts @ ab.A_upper.T + ab.e_upper)
    rlo, rhi = ab.range_bounds(lo, hi)
    assert np.all(rlo <= vals) and np.all(vals <= rhi)
    # Corollary 1 intersection is still an enclosure
    clo, chi = corollary1_bounds(decomposition_bounds(q, lo, hi, *jb), (rlo, rhi))
    assert np.all(clo <= vals) and np.all(vals <= chi)


def test_sigma_is_zero_for_affine_components_and_positive_otherwise():
    system = gsisio.paper_system()
    lo, hi = gsisio.X0_BOX
    sigma = abstraction_sigma(lo, hi, *jacobian_bounds(system.f_jacobian, lo, hi))
    assert sigma[0] > 0 and sigma[1] == 0.0
    ab = affine_abstraction(system.f, lo, hi, sigma)
    np.testing.assert_allclose(ab.A_lower[1], [-0.2, -0.14], atol=1e-7)
    assert "Optimal" in ab.status or "optimal" in ab.status


def test_range_bounds_give_no_information_outside_the_domain():
    system = gsisio.paper_system()
    lo, hi = gsisio.X0_BOX
    ab = affine_abstraction(system.f, lo, hi, abstraction_sigma(lo, hi, *jacobian_bounds(system.f_jacobian, lo, hi)))
    rlo, rhi = ab.range_bounds(lo - 1.0, hi)
    assert np.all(np.isneginf(rlo)) and np.all(np.isposinf(rhi))
