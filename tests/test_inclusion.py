"""Interval arithmetic: enclosure of sampled values (ends included), domain errors, component convention."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from intervalobs.errors import BoundsError, DimensionError
from intervalobs.inclusion import evaluate_function, interval_function, interval_matrix
from intervalobs.interval import Interval

centre = st.floats(-20, 20, allow_nan=False)
radius = st.floats(0, 8, allow_nan=False)

UNARY = {
    "sin": np.sin,
    "cos": np.cos,
    "exp": np.exp,
    "tanh": np.tanh,
    "arctan": np.arctan,
    "abs": np.abs,
    "square": np.square,
}


@settings(max_examples=40, deadline=None)
@given(centre, radius, st.sampled_from(sorted(UNARY)))
def test_unary_functions_enclose_every_sample(c, r, name):
    fn = UNARY[name]
    if name == "exp":
        c = min(c, 5.0)
    box = Interval(c - r, c + r)
    out = fn(box)
    xs = np.concatenate([np.linspace(c - r, c + r, 2001), [c - r, c + r]])
    values = fn(xs)
    assert np.all(out.lower <= values) and np.all(values <= out.upper)


@settings(max_examples=40, deadline=None)
@given(centre, radius, centre, radius)
def test_arithmetic_encloses_all_vertex_and_sample_combinations(c1, r1, c2, r2):
    a, b = Interval(c1 - r1, c1 + r1), Interval(c2 - r2, c2 + r2)
    xs = np.linspace(c1 - r1, c1 + r1, 41)[:, None]
    ys = np.linspace(c2 - r2, c2 + r2, 41)[None, :]
    for out, vals in ((a + b, xs + ys), (a - b, xs - ys), (a * b, xs * ys), (3.0 * a - b * 0.5, 3 * xs - 0.5 * ys)):
        assert np.all(out.lower <= vals) and np.all(vals <= out.upper)
    if c2 - r2 > 0.1:
        q = a / b
        assert np.all(q.lower <= xs / ys) and np.all(xs / ys <= q.upper)


def test_sin_of_a_wide_or_infinite_interval_is_the_whole_range():
    assert (np.sin(Interval(-np.inf, np.inf)).lower, np.sin(Interval(0.0, 7.0)).upper) == (-1.0, 1.0)
    inner = np.sin(Interval(0.1, 0.2))
    assert 0.0998 < inner.lower < inner.upper < 0.1988


def test_division_by_interval_containing_zero_raises():
    with pytest.raises(BoundsError, match="contains 0"):
        Interval(1.0, 2.0) / Interval(-1.0, 1.0)
    with pytest.raises(BoundsError, match="lower <= upper"):
        Interval(1.0, 0.0)


def test_component_convention_for_points_boxes_and_matrices():
    def f(x):
        return (x[0] * x[1], np.sin(x[0]) + 1.0)

    def jac(x):
        return [[x[1], x[0]], [np.cos(x[0]), 0.0]]

    pts = np.array([[0.5, -1.0], [1.0, 2.0]])
    np.testing.assert_allclose(evaluate_function(f, pts), [[-0.5, np.sin(0.5) + 1], [2.0, np.sin(1.0) + 1]])
    lo, hi = interval_function(f, [0.0, -1.0], [1.0, 2.0])
    assert lo[0] <= -1.0 and hi[0] >= 2.0
    jl, _ = interval_matrix(jac, np.zeros((3, 2)), np.ones((3, 2)))
    assert jl.shape == (3, 2, 2) and np.all(jl[:, 1, 1] == 0.0)
    with pytest.raises(DimensionError, match="expected 3 components"):
        evaluate_function(f, pts, size=3)
