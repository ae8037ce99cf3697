"""Interval dual numbers: the derivative boxes contain the exact derivatives over the whole box."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.errors import BoundsError, DimensionError
from intervalobs.inclusion import evaluate_matrix, interval_function, interval_matrix
from intervalobs.interval import SUPPORTED_UFUNCS, Interval
from intervalobs.interval_dual import IntervalDual, automatic_jacobian, value_and_jacobian

# The analytic derivative below is evaluated in floating point: a few operations, each with a relative
# error <= eps/2 and libm functions within 1 ulp, so it differs from the exact derivative by at most
# ~8 eps times the magnitude of its terms. Containment is checked with that slack and nothing more.
SLACK = 16 * np.finfo(float).eps

# (name, f(x) with x a sequence of 2 components, analytic Jacobian, box)
CASES = [
    (
        "arith",
        lambda x: (x[0] * x[1] - 3.0 * x[0] + x[1] / (2.0 + x[0] ** 2), -(x[1] ** 3) + 1.5),
        lambda x: [
            [x[1] - 3.0 - x[1] * 2 * x[0] / (2.0 + x[0] ** 2) ** 2, x[0] + 1.0 / (2.0 + x[0] ** 2)],
            [np.zeros_like(x[0]), -3 * x[1] ** 2],
        ],
        ([-1.5, -0.7], [0.8, 1.9]),
    ),
    (
        "trig",
        lambda x: (np.sin(0.3 * x[1] - 0.2 * x[0]) * np.cos(x[0]), np.cos(x[0] * x[1])),
        lambda x: [
            [
                -0.2 * np.cos(0.3 * x[1] - 0.2 * x[0]) * np.cos(x[0]) - np.sin(0.3 * x[1] - 0.2 * x[0]) * np.sin(x[0]),
                0.3 * np.cos(0.3 * x[1] - 0.2 * x[0]) * np.cos(x[0]),
            ],
            [-x[1] * np.sin(x[0] * x[1]), -x[0] * np.sin(x[0] * x[1])],
        ],
        ([-2.0, -3.0], [2.5, 1.0]),
    ),
    (
        "exp-log-sqrt",
        lambda x: (np.exp(-x[0]) * np.log(x[1]), np.sqrt(x[0] + x[1]) / x[1]),
        lambda x: [
            [-np.exp(-x[0]) * np.log(x[1]), np.exp(-x[0]) / x[1]],
            [0.5 / np.sqrt(x[0] + x[1]) / x[1], 0.5 / np.sqrt(x[0] + x[1]) / x[1] - np.sqrt(x[0] + x[1]) / x[1] ** 2],
        ],
        ([0.2, 0.5], [1.7, 2.5]),
    ),
    (
        "tanh-arctan-square-abs",
        lambda x: (np.tanh(x[0] - x[1]) + np.arctan(2.0 * x[1]), np.square(x[0]) + np.abs(x[1] - 0.3)),
        lambda x: [
            [1 - np.tanh(x[0] - x[1]) ** 2, -(1 - np.tanh(x[0] - x[1]) ** 2) + 2.0 / (1 + 4 * x[1] ** 2)],
            [2 * x[0], np.sign(x[1] - 0.3)],
        ],
        ([-1.0, -1.2], [1.3, 0.1]),
    ),
]


def _points(box, rng, count=400):
    lo, hi = np.asarray(box[0], float), np.asarray(box[1], float)
    corners = (np.arange(4)[:, None] >> np.arange(2)) & 1
    vertices = np.where(corners == 1, hi, lo)
    return np.vstack([vertices, lo + (hi - lo) * rng.uniform(size=(count, 2))])


def _contains(lo, hi, values):
    scale = 1.0 + np.abs(values)
    return np.all((lo - SLACK * scale <= values) & (values <= hi + SLACK * scale))


@pytest.mark.parametrize(("name", "func", "jac", "box"), CASES, ids=[c[0] for c in CASES])
def test_derivative_box_contains_the_analytic_derivative_at_vertices_and_random_points(name, func, jac, box):
    rng = np.random.default_rng(7)
    points = _points(box, rng)
    j_lo, j_hi = interval_matrix(automatic_jacobian(func, 2), *box)
    exact = evaluate_matrix(jac, points)
    assert _contains(j_lo, j_hi, exact)
    # the value box of the dual is the natural extension of f: contains f at the same points
    duals = func(IntervalDual.variables(*box))
    values = np.stack([[np.broadcast_to(c, ()) for c in func([p[0], p[1]])] for p in points])
    for i, d in enumerate(duals):
        if isinstance(d, IntervalDual):
            assert _contains(d.value.lower, d.value.upper, values[:, i])


@pytest.mark.parametrize(("name", "func", "jac", "box"), CASES, ids=[c[0] for c in CASES])
def test_sub_boxes_are_enclosed_and_shrink_to_the_point_derivative(name, func, jac, box):
    """Random sub-boxes (a leading axis) enclose the derivative; degenerate boxes are a few ulp wide."""
    rng = np.random.default_rng(11)
    lo, hi = np.asarray(box[0], float), np.asarray(box[1], float)
    a = lo + (hi - lo) * rng.uniform(size=(200, 2))
    b = lo + (hi - lo) * rng.uniform(size=(200, 2))
    s_lo, s_hi = np.minimum(a, b), np.maximum(a, b)
    j_lo, j_hi = interval_matrix(automatic_jacobian(func, 2), s_lo, s_hi)
    inner = s_lo + (s_hi - s_lo) * rng.uniform(size=(200, 2))
    assert _contains(j_lo, j_hi, evaluate_matrix(jac, inner))
    # at points (degenerate boxes) the enclosure is tight and agrees with central differences
    p_lo, p_hi = interval_matrix(automatic_jacobian(func, 2), inner, inner)
    exact = evaluate_matrix(jac, inner)
    smooth = np.isfinite(exact) & (np.abs(inner[:, None, None, 1] - 0.3) > 1e-3)  # abs has a kink at 0.3
    assert np.all(np.where(smooth, p_hi - p_lo, 0.0) <= 1e-12 * (1 + np.abs(exact)))
    h = 1e-6
    eye = np.eye(2) * h
    fd = np.stack(
        [
            (np.stack(func(list((inner + eye[j]).T)), -1) - np.stack(func(list((inner - eye[j]).T)), -1)) / (2 * h)
            for j in range(2)
        ],
        -1,
    )
    mid = 0.5 * (p_lo + p_hi)
    assert np.all(np.where(smooth, np.abs(mid - fd), 0.0) <= 1e-6 * (1 + np.abs(fd)))


@pytest.mark.parametrize(("name", "func", "jac", "box"), CASES, ids=[c[0] for c in CASES])
def test_seeding_one_direction_gives_that_column_of_the_full_seed_bit_for_bit(name, func, jac, box):
    """``variables(along=k)`` carries one derivative column; every rule works on each column alone."""
    rng = np.random.default_rng(5)
    lo, hi = np.asarray(box[0], float), np.asarray(box[1], float)
    a, b = lo + (hi - lo) * rng.uniform(size=(50, 2)), lo + (hi - lo) * rng.uniform(size=(50, 2))
    s_lo, s_hi = np.minimum(a, b), np.maximum(a, b)
    full = func(IntervalDual.variables(s_lo, s_hi))
    for k in range(2):
        for d_full, d_one in zip(full, func(IntervalDual.variables(s_lo, s_hi, along=k))):
            if not isinstance(d_full, IntervalDual):
                continue
            assert d_one.derivative.shape == (50, 1)
            assert np.array_equal(d_one.value.lower, d_full.value.lower)
            assert np.array_equal(d_one.derivative.lower[:, 0], d_full.derivative.lower[:, k])
            assert np.array_equal(d_one.derivative.upper[:, 0], d_full.derivative.upper[:, k])
    with pytest.raises(DimensionError, match="along"):
        IntervalDual.variables(s_lo, s_hi, along=2)


def test_abs_at_its_kink_gives_the_generalised_gradient():
    (d,) = [np.abs(IntervalDual.variables([-1.0], [2.0])[0])]
    np.testing.assert_allclose([d.derivative.lower[0], d.derivative.upper[0]], [-1.0, 1.0], rtol=SLACK)
    assert d.derivative.lower[0] <= -1.0 and d.derivative.upper[0] >= 1.0


def test_sqrt_and_log_at_zero_have_an_unbounded_derivative():
    x = IntervalDual.variables([0.0], [1.0])[0]
    assert np.sqrt(x).derivative.upper[0] == np.inf and np.sqrt(x).derivative.lower[0] == pytest.approx(0.5)
    y = IntervalDual.variables([0.0], [4.0])[0]
    assert np.log(y).derivative.upper[0] == np.inf and np.log(y).derivative.lower[0] == pytest.approx(0.25)


def test_every_supported_ufunc_has_a_rule():
    x = IntervalDual.variables([0.5], [0.7])[0]
    for name in SUPPORTED_UFUNCS:
        ufunc = getattr(np, name)
        out = ufunc(x, x) if ufunc.nin == 2 else ufunc(x)
        assert isinstance(out, IntervalDual), name


def test_constants_and_numpy_scalars_mix_with_duals():
    x, y = IntervalDual.variables([1.0, 2.0], [1.0, 2.0])
    out = np.float64(2.0) * x - y / np.float64(4.0) + 1
    assert isinstance(out, IntervalDual)
    assert out.derivative.lower[0] <= 2.0 <= out.derivative.upper[0]
    assert out.derivative.lower[1] <= -0.25 <= out.derivative.upper[1]
    assert isinstance(out.value, Interval)


def test_automatic_jacobian_checks_the_number_of_components():
    with pytest.raises(DimensionError, match="expected 2 components, got 3"):
        automatic_jacobian(lambda x: (x[0], x[1]), 2)([1.0, 2.0, 3.0])


@pytest.mark.parametrize(
    "divide", [lambda x: 1.0 / x, lambda x: x / x, lambda x: 2.0 * x / (x + 0.5)], ids=["rdiv", "div", "mixed"]
)
def test_a_divisor_that_may_vanish_on_the_box_is_refused(divide):
    x = IntervalDual.variables([-1.0], [1.0])[0]
    with pytest.raises(BoundsError, match="excluding 0"):
        divide(x)


def test_structural_zeros_stay_exact_through_products_and_quotients():
    """A variable an expression does not involve gets an exact zero derivative (no subnormal pad).

    The sign certificates of design.lpv count a derivative of one sign as monotone: a pad of ±5e-324 around
    an exact zero would cost them a line.
    """
    x, y = IntervalDual.variables([0.5, 1.0], [0.9, 1.5])
    out = (x**2 + 3.0) * (1.0 / (x + 2.0)) - 0.25 * x
    assert out.derivative.lower[1] == 0.0 and out.derivative.upper[1] == 0.0
    assert out.derivative.lower[0] < out.derivative.upper[0]
    assert isinstance(y * out, IntervalDual)


@pytest.mark.parametrize(("name", "func", "jac", "box"), CASES, ids=[c[0] for c in CASES])
def test_value_and_jacobian_give_the_two_separate_evaluations_bit_for_bit(name, func, jac, box):
    """One forward-mode pass: its value box is the natural extension, its Jacobian automatic_jacobian's."""
    rng = np.random.default_rng(3)
    lo, hi = (np.asarray(b, dtype=float) for b in box)
    corners = lo + (hi - lo) * np.sort(rng.uniform(0.0, 1.0, (2, 5, lo.size)), axis=0)
    value, slope = value_and_jacobian(func, corners[0], corners[1], 2)
    v_lo, v_hi = interval_function(func, corners[0], corners[1], 2)
    j_lo, j_hi = interval_matrix(automatic_jacobian(func, 2), corners[0], corners[1], (2, 2))
    for got, expected in ((value.lower, v_lo), (value.upper, v_hi), (slope.lower, j_lo), (slope.upper, j_hi)):
        np.testing.assert_array_equal(got, expected)
    with pytest.raises(DimensionError, match="expected 3 components"):
        value_and_jacobian(func, corners[0], corners[1], 3)
