import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from intervalobs import Interval
from intervalobs.errors import AssumptionError, BoundsError, DimensionError
from intervalobs.interval import (
    ROUNDING_MARGIN,
    inflate,
    interval_matvec_bounds,
    matvec_bounds,
    neg,
    pos,
    recursion_margin,
    round_outward,
    sandwich_bounds,
)

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


def box_strategy(n: int):
    return st.tuples(arrays(float, n, elements=finite), arrays(float, n, elements=st.floats(0, 5))).map(
        lambda cw: (cw[0] - cw[1], cw[0] + cw[1])
    )


@given(arrays(float, (3, 4), elements=finite))
def test_positive_and_negative_parts_split_the_matrix(a):
    assert np.all(pos(a) >= 0) and np.all(neg(a) >= 0)
    np.testing.assert_array_equal(pos(a) - neg(a), a)


@settings(max_examples=60)
@given(arrays(float, (3, 4), elements=finite), box_strategy(4), st.integers(0, 2**32 - 1))
def test_matvec_bounds_contain_samples_and_vertices_and_are_attained(a, box, seed):
    lo, hi = box
    out_lo, out_hi = matvec_bounds(a, lo, hi)
    vertices = Interval(lo, hi).vertices()
    rng = np.random.default_rng(seed)
    inside = lo + (hi - lo) * rng.uniform(size=(50, 4))
    for points in (vertices, inside):
        images = points @ a.T
        assert np.all(images >= out_lo - 1e-9) and np.all(images <= out_hi + 1e-9)
    # exactness (seed 003, Prop. 2): each bound is reached at a vertex
    images = vertices @ a.T
    np.testing.assert_allclose(images.min(axis=0), out_lo, atol=1e-9)
    np.testing.assert_allclose(images.max(axis=0), out_hi, atol=1e-9)


@settings(max_examples=60)
@given(box_strategy(6), box_strategy(3), st.integers(0, 2**32 - 1))
def test_interval_matvec_bounds_are_sound_and_exact(a_box, x_box, seed):
    a_lo, a_hi = a_box[0].reshape(2, 3), a_box[1].reshape(2, 3)
    lo, hi = x_box
    out_lo, out_hi = interval_matvec_bounds(a_lo, a_hi, lo, hi)
    rng = np.random.default_rng(seed)
    for _ in range(30):
        a = a_lo + (a_hi - a_lo) * rng.integers(0, 2, size=a_lo.shape)
        x = lo + (hi - lo) * rng.integers(0, 2, size=lo.shape)
        assert np.all(a @ x >= out_lo - 1e-9) and np.all(a @ x <= out_hi + 1e-9)
    # exactness: the lower bound of row 0 is reached by choosing each term's minimising corner
    corners = np.stack([a_lo * lo, a_lo * hi, a_hi * lo, a_hi * hi])
    np.testing.assert_allclose(corners.min(axis=0).sum(axis=1), out_lo)


def test_point_interval_matrix_reduces_to_matvec_bounds():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(3, 3))
    lo, hi = -rng.uniform(size=3), rng.uniform(size=3)
    np.testing.assert_allclose(interval_matvec_bounds(a, a, lo, hi), matvec_bounds(a, lo, hi))


def test_bounds_carry_leading_axes():
    a = np.array([[1.0, -2.0], [0.5, 3.0]])
    lo = np.zeros((5, 7, 2))
    lo_out, hi_out = matvec_bounds(a, lo, lo + 1)
    assert lo_out.shape == (5, 7, 2)
    np.testing.assert_allclose(hi_out[0, 0], [1.0, 3.5])


def test_inflate_widens_outward():
    lo, hi = inflate(np.array([-1.0, 0.0]), np.array([1.0, 0.0]))
    assert np.all(lo < [-1.0, 0.0]) and np.all(hi > [1.0, 0.0])


def test_interval_refuses_nan_empty_and_mismatched_ends_with_one_line_errors():
    with pytest.raises(
        BoundsError, match=r"^lower: expected lower <= upper, got lower 1.0 > upper 0.0 at index \(1,\)$"
    ):
        Interval([0.0, 1.0], [1.0, 0.0])
    with pytest.raises(BoundsError, match=r"^upper: expected no NaN, got NaN at index \(0,\)$"):
        Interval([0.0], [np.nan])
    with pytest.raises(BoundsError, match=r"^lower: expected no NaN"):
        Interval(np.nan)
    with pytest.raises(
        DimensionError, match=r"^upper: expected a shape that broadcasts with lower's \(2,\), got \(3,\)$"
    ):
        Interval([0.0, 1.0], [1.0, 2.0, 3.0])


def test_infinite_ends_are_allowed_and_carried_soundly():
    x = Interval([-np.inf, 0.0], [1.0, np.inf])
    np.testing.assert_array_equal(x.width, [np.inf, np.inf])
    zero = x * 0.0
    np.testing.assert_array_equal(zero.lower, np.nextafter(0.0, -1.0))  # 0 * inf = 0, rounded outward
    total = x + Interval([1.0, 1.0], [2.0, 2.0])
    assert total.lower[0] == -np.inf and total.upper[1] == np.inf
    image = np.array([[1.0, 0.0], [0.0, -2.0]]) @ x
    assert image.lower[0] == -np.inf and image.upper[0] >= 1.0 and image.lower[1] == -np.inf and image.upper[1] >= 0.0


def test_centre_radius_width_and_vertices():
    x = Interval([[-1.0, 2.0], [0.0, 0.0]], [[3.0, 2.0], [1.0, 4.0]])
    np.testing.assert_array_equal(x.centre, [[1.0, 2.0], [0.5, 2.0]])
    np.testing.assert_array_equal(x.radius, [[2.0, 0.0], [0.5, 2.0]])
    np.testing.assert_array_equal(x.width, 2 * x.radius)
    np.testing.assert_array_equal(x[1].vertices(), [[0.0, 0.0], [1.0, 0.0], [0.0, 4.0], [1.0, 4.0]])
    np.testing.assert_array_equal(x.contains([[0.0, 2.0], [2.0, 2.0]]), [True, False])
    with pytest.raises(DimensionError, match="single box"):
        x.vertices()


def _samples(lo: np.ndarray, hi: np.ndarray, rng: np.random.Generator, count: int = 40) -> np.ndarray:
    """Both ends and random points of each element, stacked on a new leading axis."""
    return np.concatenate([lo[None], hi[None], lo + (hi - lo) * rng.uniform(size=(count, *lo.shape))])


def _encloses(out: Interval, values: np.ndarray) -> bool:
    return bool(np.all(out.lower <= values) and np.all(values <= out.upper))


@settings(max_examples=60, deadline=None)
@given(box_strategy(6), box_strategy(6), finite, arrays(float, 6, elements=finite), st.integers(0, 2**32 - 1))
def test_elementwise_operations_enclose_every_combination_of_ends_and_points(a_box, b_box, c, p, seed):
    rng = np.random.default_rng(seed)
    # leading (time) axis of 2: the last 6 numbers are two rows of three
    a = Interval(a_box[0].reshape(2, 3), a_box[1].reshape(2, 3))
    b = Interval(b_box[0].reshape(2, 3), b_box[1].reshape(2, 3))
    point = p.reshape(2, 3)
    xs = _samples(a.lower, a.upper, rng)[:, None]
    ys = _samples(b.lower, b.upper, rng)[None, :]
    cases = [
        (a + b, xs + ys),
        (a - b, xs - ys),
        (a * b, xs * ys),
        (a + c, xs + c),
        (c - a, c - xs),
        (c * a, c * xs),
        (a * point, xs * point),
        (point - a, point - xs),
        (-a, -xs),
        (a**2, xs**2),
        (a**3, xs**3),
    ]
    for out, values in cases:
        assert out.shape == (2, 3)
        assert _encloses(out, values)


@settings(max_examples=60, deadline=None)
@given(
    arrays(float, (3, 4), elements=finite),
    box_strategy(12),
    box_strategy(8),
    st.integers(0, 2**32 - 1),
)
def test_matrix_products_enclose_vertices_and_random_points(a, a_box, x_box, seed):
    rng = np.random.default_rng(seed)
    x = Interval(x_box[0].reshape(2, 4), x_box[1].reshape(2, 4))  # two vectors (a leading axis)
    big_a = Interval(a_box[0].reshape(3, 4), a_box[1].reshape(3, 4))
    corners = (np.arange(16)[:, None] >> np.arange(4)) & 1
    for row in range(2):
        lo, hi = x.lower[row], x.upper[row]
        points = np.concatenate([np.where(corners == 1, hi, lo), lo + (hi - lo) * rng.uniform(size=(50, 4))])
        assert _encloses((a @ x)[row], points @ a.T)
        matrices = np.concatenate(
            [
                np.where(rng.integers(0, 2, size=(30, 3, 4)) == 1, big_a.upper, big_a.lower),
                big_a.lower + big_a.width * rng.uniform(size=(30, 3, 4)),
            ]
        )
        assert _encloses((big_a @ x)[row], np.einsum("kij,pj->kpi", matrices, points))
    # the class's product contains the round-to-nearest hull the hot loops use, and is hardly wider
    hull = matvec_bounds(a, x.lower, x.upper)
    assert np.all((a @ x).lower <= hull[0]) and np.all(hull[1] <= (a @ x).upper)
    scale = np.abs(x.lower).max() + np.abs(x.upper).max() + 1.0
    np.testing.assert_allclose((a @ x).lower, hull[0], rtol=0, atol=1e-12 * scale * (np.abs(a).sum() + 1))
    i_hull = interval_matvec_bounds(big_a.lower, big_a.upper, x.lower, x.upper)
    assert np.all((big_a @ x).lower <= i_hull[0]) and np.all(i_hull[1] <= (big_a @ x).upper)


def test_interval_refuses_a_matrix_of_the_wrong_width():
    with pytest.raises(DimensionError, match=r"matrix: expected shape \(\.\.\., m, 3\), got \(2, 2\)"):
        np.eye(2) @ Interval(np.zeros(3), np.ones(3))


def test_round_outward_covers_a_sum_whose_every_addition_rounds_the_same_way():
    # 1 + k terms of 0.75 ulp(1): each addition rounds up by 0.25 ulp, so the computed sum exceeds the exact
    # one by k/4 ulps; one ulp of outward rounding misses it, k ulps (the documented rule) cover it.
    k = 40
    term = 0.75 * 2.0**-52
    total = 1.0
    for _ in range(k):
        total += term
    exact_excess = total - 1.0 - k * term  # exact in binary: every number here is a multiple of 2^-54
    assert exact_excess == pytest.approx(0.25 * k * 2.0**-52)
    one, _ = round_outward(total, total)
    assert one > 1.0 + k * term  # one ulp does not cover the accumulation
    low, high = round_outward(total, total, ulps=k)
    assert low <= 1.0 + k * term <= high
    with pytest.raises(BoundsError, match="ulps: expected a positive integer, got 0"):
        round_outward(1.0, 1.0, ulps=0)


def test_recursion_margin_covers_the_worst_float_fixed_point_of_a_slow_recursion():
    # z_{k+1} = rho z_k + g with rho = 1 - 2^-14: the exact recursion converges to z* = g / (1 - rho) = c, while
    # every float z with fl(fl(rho z) + g) = z is a fixed point of the computed recursion: its rounding error
    # repeats identically at every step and accumulates the full 1/(1 - rho). The farthest such point is the
    # adversarial case of the margin's argument.
    rho, c = 1.0 - 2.0**-14, 1.0 + 1.0 / 3.0
    g = c * 2.0**-14
    z = c + np.arange(-(2**16), 2**16 + 1) * 2.0**-52
    fixed = z[(rho * z + g) == z]
    error = float(np.max(np.abs(fixed - c) / np.abs(fixed)))
    margin = recursion_margin(1, 1.0, rho)
    lower, upper = inflate(fixed, fixed, margin)
    assert np.all(lower <= c) and np.all(c <= upper)
    assert error > 2 * ROUNDING_MARGIN  # the flat margin alone would miss it
    assert error > margin / 32  # and the construction is within a small factor of the margin's bound


def test_recursion_margin_formula_and_refusals():
    assert recursion_margin(2) == ROUNDING_MARGIN
    assert recursion_margin(10, 4.0, 0.999) == pytest.approx(8 * 10 * np.finfo(float).eps * 4.0 / 0.001)
    with pytest.raises(AssumptionError, match=r"contraction: expected a rate in \[0, 1\), got 1.0"):
        recursion_margin(3, 1.0, 1.0)


def test_inflate_keeps_structural_zeros_only_when_asked():
    assert inflate(0.0, 0.0)[1] > 0.0
    assert inflate(-0.0, 0.0, floor=0.0)[1] == 0.0
    _, high = inflate(np.array([1.0]), np.array([2.0]), scale=np.array([10.0]))
    assert high[0] - 2.0 == pytest.approx(10.0 * ROUNDING_MARGIN, rel=1e-3)


@settings(max_examples=40, deadline=None)
@given(arrays(float, (2, 3), elements=finite), box_strategy(12), arrays(float, (4, 2), elements=finite))
def test_sandwich_bounds_enclose_vertex_products_and_batched_matvec_agrees(p, j_box, q):
    j_lo, j_hi = j_box[0].reshape(3, 4), j_box[1].reshape(3, 4)
    low, high = sandwich_bounds(p, j_lo, j_hi, q)
    rng = np.random.default_rng(0)
    for _ in range(40):
        j = np.where(rng.integers(0, 2, size=(3, 4)) == 1, j_hi, j_lo)
        value = p @ j @ q
        assert np.all(low <= value + 1e-9 * (1 + np.abs(value))) and np.all(value <= high + 1e-9 * (1 + np.abs(value)))
    # a matrix with a leading axis applies to the vectors of the same index
    stack = np.stack([p, -p])
    lo_b, _ = matvec_bounds(stack, j_lo[:, :2].T, j_hi[:, :2].T)
    for i in range(2):
        np.testing.assert_allclose(lo_b[i], matvec_bounds(stack[i], j_lo[:, i], j_hi[:, i])[0], atol=1e-12)
