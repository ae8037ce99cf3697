import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from intervalobs import BoundsError, Box, DimensionError, interval_matvec_bounds, matvec_bounds, neg, pos
from intervalobs.interval import inflate

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
    vertices = Box(lo, hi).vertices()
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


def test_box_rejects_empty_and_nonfinite():
    with pytest.raises(BoundsError, match="lower <= upper"):
        Box([1.0], [0.0])
    with pytest.raises(BoundsError, match="finite"):
        Box([np.nan], [0.0])
    with pytest.raises(DimensionError, match="shape"):
        Box([0.0, 1.0], [1.0])
